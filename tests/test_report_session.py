"""The report snapshot of a dashboard session holds what the page shows."""

from __future__ import annotations

import numpy as np

import fbs_core
from app import compute
from app.datasource import Models
from app.report import build_html
from app.report.session import provenance_of, session_snapshot
from app.state import DashboardState


def test_session_snapshot_equals_the_core_results():
    state = DashboardState()
    state.case.param.update(harmonic=2, n_modes=40, dof="y")
    snap = session_snapshot(state, url="http://localhost:5006/main?h=2&N=40&dof=y")
    # second path: the core's bushing response computed directly
    ref = fbs_core.bushing_response(2)
    tr = fbs_core.bushing_response(2, n_modes=40)
    np.testing.assert_allclose(snap.reference.data, ref.data, rtol=1e-10, atol=0)
    np.testing.assert_allclose(snap.truncated.data, tr.data, rtol=1e-10, atol=0)
    tab = compute.suggested_table(20.0, 160.0, "6dof", "y")
    np.testing.assert_array_equal(snap.suggested.n_modes, tab["n_modes"])
    assert snap.band is None  # none given
    assert snap.settings["dof"] == "y" and snap.provenance.is_reference
    name, _ = build_html(snap)
    assert name.startswith("tire-fbs_h2_bushing-y_N40_6dof_")


def test_band_kept_only_for_its_settings():
    state = DashboardState()
    state.noise.param.update(rounds=50, noise=5.0)
    band = compute.band(1, 50, "6dof", 5.0, "both", False, 50, 0)
    assert session_snapshot(state, band=band, band_n_modes=50).band is band
    state.noise.seed = 1  # the band on the page is stale
    assert session_snapshot(state, band=band, band_n_modes=50).band is None


def test_provenance_names_uploads_with_digests():
    m = Models(
        tire=None, chassis=object(), key="tire=reference;chassis=abc123", chassis_name="c.uff"
    )
    p = provenance_of(m, ["note"])
    assert p.chassis.name == "c.uff" and p.chassis.digest == "abc123" and p.tire.is_reference
    assert p.notes == ("note",)
