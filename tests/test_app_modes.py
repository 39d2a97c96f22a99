"""The Modes and Selected-modes tabs in process (issue 30): the published numbers are the
core's, the clicks pick the right mode, the CSV and the report hold what the page shows.

Truth: the core's functions called here directly with their own arguments (not through
the app's caches): ``mode_participation`` over the band the page names, ``tire_mode_shape``,
``wave_campbell``'s stored pairs, ``select_modes``, ``truncation_map(...).suggest`` (table
5.1) and ``chassis_truncation_map``.
"""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core
from app.datasource import Models
from app.export import read_csv, to_csv
from app.report import report_content
from app.report.session import report_data
from app.results.modes import nearest_bar
from app.state import URL_KEYS
from app.store import Results
from fbs_core.analysis import mode_participation, select_modes, tire_mode_shape
from fbs_core.studies import chassis_truncation_map, truncation_map


@pytest.fixture(scope="module")
def store():
    st = Results(background=False)
    st.state.case.param.update(harmonic=2, dof="x")
    st.state.truncation.f_max = 50.0  # the band up to 50 Hz: a part of harmonic 2's
    st.state.analysis.tab = "modes"
    return st


def test_the_ranking_is_the_cores_over_the_band_the_page_names(store):
    r = store.participation
    # harmonic 2's lines are 17 ... 66.5 Hz every 0.5 Hz: up to f_max = 50 Hz
    assert "17-50 Hz" in r.meta["band"] and "f_max = 50 Hz" in r.meta["band"]
    p = mode_participation(2, (17.0, 50.0))
    # the vibration modes ranked, then the tread's first-order states (no vibration) unranked
    order = np.argsort(-p.loo[:, 0], kind="stable")
    slip = np.asarray(p.first_order, bool)
    order = np.concatenate([order[~slip[order]], np.flatnonzero(slip)])
    np.testing.assert_array_equal(r.columns["mode"], p.modes[order])
    assert np.isnan(r.columns["rank"][-int(slip.sum()) :]).all()
    np.testing.assert_allclose(r.columns["loo_pct"], 100 * p.loo[order, 0], rtol=1e-12)
    np.testing.assert_allclose(r.columns["share_pct"], 100 * p.share[order, 0], rtol=1e-12)
    # the shares of all modes add up to the whole response (a second check of the core)
    assert abs(r.columns["share_pct"].sum() - 100.0) < 1e-6
    # ranked by another measure: the order of that measure
    store.state.analysis.mode_rank = "level"
    try:
        c = store.participation.columns
        lv = c["level_pct"][np.isfinite(c["rank"])]
        assert np.all(np.diff(lv) <= 0)
        assert "level" in store.participation.filename
    finally:
        store.state.analysis.mode_rank = "loo"


def test_a_click_on_a_bar_picks_its_mode_and_the_shape_is_the_cores(store):
    r = store.participation
    assert nearest_bar(r.draw, 2.4) == 2 and nearest_bar(r.draw, -0.7) is None
    store.pick_mode_bar(2.2)
    a = store.state.analysis
    want = int(r.draw["mode"][2])
    assert a.mode_pick == want and a.mode_speed == round(float(r.draw["speed"][2]), 1)
    s = store.mode_shape
    shape = tire_mode_shape(want, a.mode_speed)
    n_k, n_t = shape.shape.ring.shape[:2]
    np.testing.assert_allclose(
        s.columns["ring_x_m"].reshape(n_k, n_t), shape.shape.ring[..., 0], atol=1e-12
    )
    np.testing.assert_allclose(s.draw["frames_z"][3], shape.shape.ring[3, :, 2], atol=1e-12)
    assert f"Mode {want}" in s.caption and shape.direction in s.caption
    # the bar is in the URL state, and the link opens on the same shape
    assert {"mode_pick": "mode", "mode_speed": "mv"}.items() <= URL_KEYS["analysis"].items()
    other = Results(background=False)
    other.state.analysis.param.update(tab="modes", mode_pick=want, mode_speed=a.mode_speed)
    np.testing.assert_array_equal(other.mode_shape.columns["ring_z_m"], s.columns["ring_z_m"])
    other.close()


def test_the_shape_by_default_is_the_first_of_the_ranking_where_the_line_meets_it():
    st = Results(background=False)
    st.state.analysis.tab = "modes"
    p = mode_participation(1)
    i = int(np.argsort(-p.loo[:, 2], kind="stable")[0])
    shape = tire_mode_shape(int(p.modes[i]), round(float(p.mode_speed[i]), 1))
    assert st.mode_shape.draw["mode"] == int(p.modes[i])
    np.testing.assert_allclose(st.mode_shape.draw["frames_x"][0], shape.shape.ring[0, :, 0])
    st.close()


def test_a_click_on_a_wave_branch_picks_the_stored_pair_that_carries_it(store):
    r = store.waves
    cb = fbs_core.analysis.wave_campbell()
    sel = cb.selection(2)
    assert r.draw["label"] == [cb.labels()[b] for b in sel]  # the readable default
    i = int(np.argmin(np.abs(cb.speeds - 60.0)))
    b = int(sel[0])
    store.pick_wave(float(cb.speeds[i]), float(cb.freq[i, b]) * 1.01)
    a = store.state.analysis
    assert a.mode_pick == int(cb.stored[i, b]) and abs(a.mode_speed - cb.speeds[i]) < 0.051
    # far from every branch: nothing picked
    store.pick_wave(float(cb.speeds[i]), 1e4)
    assert a.mode_pick == int(cb.stored[i, b])
    store.state.analysis.waves_all = True
    try:
        assert len(store.waves.draw["label"]) == cb.order.size
        assert store.waves.filename.endswith("_all.csv")
    finally:
        store.state.analysis.waves_all = False


def test_csv_of_every_result_of_the_tabs_reads_back(store):
    for name in ("participation", "mode_shape", "waves"):
        r = getattr(store, name)
        meta, cols = read_csv(to_csv(r.columns, r.meta, name))
        assert set(cols) == set(r.columns)
        for k, v in r.columns.items():
            np.testing.assert_array_equal(cols[k], np.asarray(v, float))


def test_the_selection_tab_is_the_cores_selection_beside_table_5_1():
    st = Results(background=False)
    st.state.case.param.update(harmonic=3, dof="y")
    st.state.truncation.param.update(threshold=15.0, f_max=130.0)
    st.state.analysis.tab = "selection"
    r = st.selected_modes
    low = truncation_map(3).suggest(0.15, 130.0, "bushing:y")
    greedy = select_modes(3, 0.15, 130.0, by="greedy", dof="bushing:y")
    loo = select_modes(3, 0.15, 130.0, by="loo_floating", dof="bushing:y")
    np.testing.assert_array_equal(r.columns["n_modes"], [low, loo.n_modes, greedy.n_modes])
    c = st.chassis_truncation
    m = chassis_truncation_map(3)
    np.testing.assert_array_equal(c.columns["n_chassis_modes"], m.n_modes)
    worst = m.dof_error("bushing:y")[:, np.asarray(m.centres) <= 130.0].max(axis=1)
    np.testing.assert_allclose(c.columns["largest_error_pct"], 100 * worst, rtol=1e-12)
    n = m.suggest(0.15, 130.0, "bushing:y")
    assert c.draw["suggested"] == n and f"**{n}**" in c.caption
    # with residual compensation: both sides compensated, and the names say so
    st.state.case.residual = True
    mr = chassis_truncation_map(3, residual=True)
    assert st.chassis_truncation.draw["suggested"] == mr.suggest(0.15, 130.0, "bushing:y")
    assert "_res_" in st.selected_modes.filename and "_res_" in st.chassis_truncation.filename
    st.close()


def test_the_report_holds_the_tabs_results_and_the_shape_as_a_strip(store):
    snap = report_data(store, url="http://localhost:5006/main")
    keys = [e.key for e in snap.extra]
    assert {"participation", "mode_shape", "waves"} <= set(keys)
    ex = snap.extra[keys.index("mode_shape")]
    frames = store.mode_shape.draw["frames_x"]
    got = ex.strip["frames"]
    np.testing.assert_array_equal(got[1][0], frames[len(frames) // len(got)])
    rep = report_content(snap)
    sec = {s.key: s for s in rep.sections}
    assert sec["mode_shape"].figure is not None
    rows = dict(snap.extra[keys.index("participation")].rows)
    assert rows["rank 1"].startswith(f"mode {int(store.participation.columns['mode'][0])} ")


def test_an_uploaded_tire_without_matrices_says_why_there_is_no_shape():
    t = fbs_core.reference_tire()
    m = slice(0, 60)
    tire = fbs_core.tire.TireModel(
        t.speeds, t.poles[:, m], t.psi[:, m], t.chi[:, m], t.wavelengths,
        t.participation[:, :, m], meta={"source": "test"},
    )  # fmt: skip
    st = Results(background=False)
    st.state.case.models = Models(tire=tire, key="tire=modes60", tire_name="t60.h5")
    st.state.analysis.tab = "modes"
    assert st.participation.draw["ready"] and st.participation.filename.endswith("_upload.csv")
    assert len(st.participation.columns["mode"]) == 30
    for name in ("mode_shape", "waves"):
        r = getattr(st, name)
        assert not r.draw["ready"] and "Not available" in r.caption, r.caption
    st.close()
