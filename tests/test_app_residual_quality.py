"""The residual toggle (issue 15) and the tire's interpolation quality (issue 13) in the
dashboard's results store and its CSV exports.

Truth: the core called directly (``fbs_core.bushing_response(..., residual=True)``: one
mode count synthesised on its own, not a row of the app's truncation map), the all-modes
response (what residual compensation converges to), the leave-one-out estimate recomputed
from physics (the tire's matrices solved at the left-out speed), and a tire whose
operating points do not cover the harmonic bands.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import fbs_core
from app import compute
from app.datasource import Models
from app.export import read_csv, to_csv
from app.results import Snapshot
from app.results.main import tire_meta
from app.state import URL_KEYS, DashboardState
from app.store import Results
from fbs_core import studies
from fbs_core.tire import TireModel
from fbs_core.tire.quality import interpolation_quality


def _level(frf, dof):
    return 20 * np.log10(np.abs(frf.sel(outputs=f"bushing:{dof}").data[:, 0, 0]))


@pytest.fixture(scope="module")
def results():
    state = DashboardState()
    state.case.param.update(harmonic=5, n_modes=50, dof="z")
    return Results(state)


def test_residual_toggle_acts_on_the_response_and_is_in_the_url(results):
    r = results
    assert URL_KEYS["case"]["residual"] == "res"
    plain = r.response
    assert "off" in plain.meta["residual compensation"]
    want = fbs_core.bushing_response(5, n_modes=50, freq=compute.frequencies(5))
    np.testing.assert_allclose(plain.columns["truncated_dB"], _level(want, "z"), atol=1e-9)

    r.state.case.residual = True
    try:
        on = r.response
        # truth: the core's residual synthesis of this one N (not the app's map row)
        want = fbs_core.bushing_response(5, n_modes=50, freq=compute.frequencies(5), residual=True)
        np.testing.assert_allclose(on.columns["truncated_dB"], _level(want, "z"), atol=1e-9)
        # and below the retained modes (50 modes: up to 146 Hz at 80 km/h) it is much
        # nearer the all-modes response than the plain truncation
        low = on.columns["freq_Hz"] < 120.0
        ref = on.columns["reference"][low]
        e_on = np.linalg.norm(on.columns["truncated"][low] - ref)
        e_off = np.linalg.norm(plain.columns["truncated"][low] - ref)
        assert e_on < 0.5 * e_off, (e_on, e_off)
        assert "on:" in on.meta["residual compensation"]
        assert "residual" in on.caption and "_res" in on.filename
        assert on.draw["truncated_label"].endswith("+ residual")
        meta, cols = read_csv(to_csv(on.columns, on.meta, "mobility"))
        assert meta["residual compensation"].startswith("on:")
        np.testing.assert_allclose(cols["truncated_dB"], on.columns["truncated_dB"])
    finally:
        r.state.case.residual = False
    assert r.response.filename == plain.filename


def test_residual_with_all_modes_is_the_reference():
    state = DashboardState()
    state.case.param.update(harmonic=2, n_modes=400, residual=True)
    r = Results(state)
    c = r.response.columns
    np.testing.assert_allclose(c["truncated"], c["reference"], rtol=1e-12)


def test_residual_toggle_acts_on_the_error_map_and_the_suggestion(results):
    r = results
    off = r.error_map
    r.state.case.residual = True
    try:
        on = r.error_map
        m = studies.truncation_map(5, n_modes=np.arange(10, 400, 10), residual=True)
        np.testing.assert_allclose(
            on.columns["error_pct"], 100 * np.asarray(m.dof_error("bushing:z")).ravel()
        )
        assert not np.allclose(on.columns["error_pct"], off.columns["error_pct"])
        assert "with residuals" in on.draw["title"] and "_res" in on.filename
        # the dashed line marks the residual-compensated suggestion; the table has both
        sug = r.suggested
        thr, f_max = r.state.truncation.threshold / 100, r.state.truncation.f_max
        kw = {"dof": "bushing:z", "n_modes": np.arange(10, 400, 10)}  # the map's DOF and Ns
        s_on = studies.suggest_modes(thr, f_max, residual=True, **kw)
        s_off = studies.suggest_modes(thr, f_max, **kw)
        np.testing.assert_array_equal(sug.columns["n_modes_residual"], s_on.n_modes)
        np.testing.assert_array_equal(sug.columns["n_modes"], s_off.n_modes)
        assert on.draw["suggested_n"] == s_on.n_modes[4]
        assert sug.meta["shown in the error map"] == "with residuals"
        assert "with residuals" in sug.caption
        from app.views.truncation import SuggestedModesView

        frame = SuggestedModesView.frame(sug)
        assert list(frame["N with residuals"]) == list(s_on.n_modes)
        assert list(frame["Suggested N"]) == list(s_off.n_modes)
    finally:
        r.state.case.residual = False
    assert r.suggested.meta["shown in the error map"] == "plain"
    assert r.error_map.draw["suggested_n"] == off.draw["suggested_n"]


def _sub(tire, idx, key):
    sub = TireModel(
        tire.speeds[idx],
        tire.poles[idx],
        tire.psi[idx],
        tire.chi[idx],
        tire.wavelengths,
        tire.participation[idx],
    )
    return sub, Models(sub, None, key, f"{key}.h5")


def test_interpolation_quality_is_shown_and_exported(results):
    r = results
    q = r.tire_quality
    tire = fbs_core.reference_tire()
    want = interpolation_quality(tire)
    # the shipped tire shows the estimate its build script stored (rounded to 0.001 dB)
    np.testing.assert_allclose(q.columns["loo_error_dB"], want.worst_db, atol=5.1e-4)
    assert q.draw["warnings"] == [""] * 7 and q.meta["speed range warnings"] == "none"
    # every export of the case carries the estimate of its harmonic and the coverage
    for res in (r.response, r.error_map):
        assert res.meta["tire interpolation error (leave-one-out, worst)"] == (
            f"h5: {q.columns['loo_error_dB'][4]:.2f} dB"
        )
        assert res.meta["tire speed range"].startswith("covered: 20-120 km/h")
    sug = r.suggested.meta["tire interpolation error (leave-one-out, worst)"]
    assert sug.count("dB") == 7
    from app.views.quality import quality_html

    page = quality_html(q)
    assert f"{np.nanmax(q.columns['loo_error_dB']):.2f} dB" in page
    assert "tire-speed-warning" not in page


def test_quality_of_a_coarse_tire_against_the_physics():
    """Every 10 km/h: the estimate at 30 km/h is the physics' error of the model
    interpolated from 20, 40, 50 km/h (matrices solved directly at 30 km/h)."""
    tire = fbs_core.reference_tire()
    idx = np.flatnonzero(np.isin(tire.speeds, np.arange(20.0, 121.0, 10.0)))
    coarse, models = _sub(tire, idx, "coarse")
    q = compute.tire_quality(models)
    assert np.nanmax(q["loo_db"]) > np.nanmax(compute.tire_quality()["loo_db"])
    k = 2
    h = fbs_core.harmonic(k)
    v = 30.0
    f = v / 3.6 / h.wavelength
    nb = np.flatnonzero(np.isin(tire.speeds, [20.0, 40.0, 50.0]))
    part = _sub(tire, nb, "part")[0]
    Yp, _ = part.synthesis([f], [v])
    ts = tire.system(v)
    w = 2 * np.pi * f
    X = 1j * w * np.linalg.solve(ts.K - w**2 * ts.M + 1j * w * ts.C, np.eye(ts.n)[:, :6])
    err = np.linalg.norm(Yp[0] - X[:6]) / np.linalg.norm(X[:6])
    mob = interpolation_quality(coarse, (k,)).mobility_db[0, 0]  # 30 km/h: first interior
    np.testing.assert_allclose(mob, 20 * np.log10(1 + err), rtol=1e-3)


def test_speed_range_warning_for_a_tire_that_does_not_cover_the_bands():
    tire = fbs_core.reference_tire()
    idx = np.flatnonzero((tire.speeds >= 40.0) & (tire.speeds <= 100.0))
    _, models = _sub(tire, idx, "narrow")
    q = compute.tire_quality(models)
    assert not q["covered"].any() and len(q["warnings"]) == 7
    assert "30-120 km/h" in q["warnings"][0] and "40-100 km/h" in q["warnings"][0]
    s = dataclasses.replace(Snapshot.of(DashboardState()), models=models, harmonic=3)
    meta = tire_meta(s)
    assert "harmonic 3" in meta["tire speed range"].lower() or "40-100" in meta["tire speed range"]
    assert "no extrapolation" in meta["tire speed range"]


def test_on_a_served_page_the_residual_column_follows_without_delaying_the_table():
    import time

    state = DashboardState()
    state.truncation.param.update(threshold=17.0, f_max=140.0)  # a table nobody computed
    r = Results(state, background=True)
    first = r.suggested
    assert np.isnan(first.columns["n_modes_residual"]).all()
    assert first.meta["with residuals"].startswith("being computed")
    t0 = time.monotonic()
    while np.isnan(r.suggested.columns["n_modes_residual"]).any():
        assert time.monotonic() - t0 < 900, "the residual column never arrived"
        time.sleep(0.05)
    s_on = studies.suggest_modes(
        0.17, 140.0, residual=True, dof="bushing:z", n_modes=np.arange(10, 400, 10)
    )
    np.testing.assert_array_equal(r.suggested.columns["n_modes_residual"], s_on.n_modes)
    assert r.suggested.meta["with residuals"] == "computed"
    np.testing.assert_array_equal(r.suggested.columns["n_modes"], first.columns["n_modes"])
