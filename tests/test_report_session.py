"""The report of a dashboard session holds what the page shows: the store's published
results of the current state, residual compensation included, and the band only when it
is of the current settings.

Truth: the core called directly (``fbs_core.bushing_response``, with and without residual
compensation; ``fbs_core.studies.suggest_modes``).
"""

from __future__ import annotations

import threading

import numpy as np
import pytest

import fbs_core
from app import compute
from app.datasource import Models
from app.report import build_html
from app.report.session import provenance_of, report_data
from app.store import Results
from fbs_core import studies


@pytest.fixture(scope="module")
def store():
    r = Results()
    r.state.case.param.update(harmonic=2, n_modes=40, dof="y")
    r.state.noise.rounds = 50
    return r


def test_the_report_holds_the_published_results_equal_to_the_core(store):
    data = report_data(store, url="http://localhost:5006/main?h=2&N=40&dof=y")
    # second path: the core's bushing response computed directly
    ref = fbs_core.bushing_response(2).sel(outputs="bushing:y")
    tr = fbs_core.bushing_response(2, n_modes=40).sel(outputs="bushing:y")
    np.testing.assert_allclose(data.reference.data, ref.data, rtol=1e-10, atol=0)
    np.testing.assert_allclose(data.truncated.data, tr.data, rtol=1e-10, atol=0)
    tab = studies.suggest_modes(0.2, 160.0, dof="bushing:y", n_modes=np.arange(10, 400, 10))
    np.testing.assert_array_equal(data.suggested.n_modes, tab.n_modes)
    assert data.band is store.band.result  # the band of these settings (computed in place)
    assert data.settings["dof"] == "y" and not data.settings["residual"]
    assert data.provenance.is_reference
    name, _ = build_html(data)
    assert name.startswith("tire-fbs_h2_bushing-y_N40_6dof_")


def test_the_report_data_of_a_session_reach_the_report_process(store):
    """Served, a report is drawn in a process of its own (issue 28, finding 7): the data
    must cross whole. The core's immutable FRF did not unpickle there, so every report of
    a real session broke the report process twice and was drawn in the server."""
    import pickle

    from app.runtime import reports  # noqa: F401  (registers the settings' pickling)

    data = report_data(store)
    back = pickle.loads(pickle.dumps(data))
    assert back.settings == data.settings and back.provenance == data.provenance
    for name in ("reference", "truncated"):
        np.testing.assert_array_equal(getattr(back, name).data, getattr(data, name).data)
    np.testing.assert_array_equal(back.truncation.error, data.truncation.error)
    np.testing.assert_array_equal(back.band.minimum, data.band.minimum)
    # regenerated there from the pickled inputs: the same numbers to rounding (the order of
    # a compiled kernel's sums is not promised across processes and array copies)
    np.testing.assert_allclose(back.band.round(3), data.band.round(3), rtol=1e-12, atol=0)
    assert build_html(back)[0] == build_html(data)[0]


def test_with_residual_compensation_the_report_holds_the_compensated_numbers(store):
    """Issue 27: the report printed the plain numbers under the plain file name."""
    store.state.case.residual = True
    try:
        data = report_data(store)
        want = fbs_core.bushing_response(2, n_modes=40, residual=True).sel(outputs="bushing:y")
        np.testing.assert_allclose(data.truncated.data, want.data, rtol=1e-10, atol=0)
        np.testing.assert_array_equal(
            data.truncated.data[:, 0, 0], store.response.columns["truncated"]
        )
        assert data.settings["residual"] is True
        tab = studies.suggest_modes(
            0.2, 160.0, dof="bushing:y", n_modes=np.arange(10, 400, 10), residual=True
        )
        np.testing.assert_array_equal(data.suggested.n_modes, tab.n_modes)
        name, html = build_html(data)
        assert name.startswith("tire-fbs_h2_bushing-y_N40_res_6dof_")
        assert "residual compensation" in html
    finally:
        store.state.case.residual = False


def test_the_band_is_reported_only_for_its_settings(store, monkeypatch):
    store.request_band(wait=True)
    assert report_data(store).band is store.band.result
    gate = threading.Event()
    real = compute.band

    def held(*args, **kw):
        assert gate.wait(300)
        return real(*args, **kw)

    monkeypatch.setattr(compute, "band", held)
    store.background = True  # the band of the new seed on its own thread, held
    try:
        store.state.noise.seed = 1
        assert store.band_status.busy
        assert report_data(store).band is None  # the page's band is of the old seed
    finally:
        gate.set()
        store.background = False


def test_provenance_names_uploads_with_digests():
    m = Models(
        tire=None, chassis=object(), key="tire=reference;chassis=abc123", chassis_name="c.uff"
    )
    p = provenance_of(m, ["note"])
    assert p.chassis.name == "c.uff" and p.chassis.digest == "abc123" and p.tire.is_reference
    assert p.notes == ("note",)


def test_the_report_package_computes_nothing_and_builds_no_page():
    """No module of app/report imports the core's studies, the app's caches of them, the
    store's makers or Panel: the report reads what the store published."""
    import ast
    from pathlib import Path

    root = Path(__file__).resolve().parents[1] / "app" / "report"
    banned = ("fbs_core.studies", "compute", "analysis_compute", "results.main", "panel")
    found = []
    for path in sorted(root.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                names = [f"{node.module or ''}.{a.name}".strip(".") for a in node.names]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            for name in names:
                if any(b in name.split(".") or name.startswith(b) for b in banned):
                    found.append(f"{path.name}:{node.lineno} {name}")
    assert found == []
