"""The Analysis card's views rendered in-process (no server): their plotted data against
independent computations (the interface forces solved here with numpy from the subsystem
FRFs, the coupled response of fbs_core.bushing_response, the tire's eigenfrequencies, the
closed-form order lines), lazy computation, picking, CSV provenance."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import fbs_core
from app.export import read_csv, to_csv
from app.store import Results
from app.views.analysis_contrib import ContributionsView
from app.views.analysis_phase import PhaseView
from app.views.analysis_speed import CampbellView, SpeedMapView
from fbs_core.vocabulary import magnitude_db

DIRS = ("x", "y", "z", "rx", "ry", "rz")


@pytest.fixture()
def store():
    r = Results()
    r.state.case.param.update(harmonic=2, n_modes=60)
    return r


def _terms_by_hand(harmonic, n_modes, coupling):
    """Eq. 4.1 term by term, solved here: g = (Y_jj^A + Y_jj^E)^-1 Y_ja^A F_a over the
    coupled DOFs, term k = Y_ej^E[:, k] g_k."""
    tire, chassis = fbs_core.reference_tire(), fbs_core.reference_chassis()
    h = fbs_core.harmonic(harmonic)
    f = h.frequencies()
    Yjj, vj = tire.truncations(f, h, [n_modes])
    Y = chassis.mobility(f)
    sp = [Y.outputs.index(f"spindle:{d}") for d in DIRS]
    bu = [Y.outputs.index(f"bushing:{d}") for d in DIRS]
    hub = [tire.hub_dofs.index(f"hub:{d}") for d in DIRS]
    keep = [k for k, d in enumerate(DIRS) if not (coupling == "5dof" and d == "ry")]
    A = Yjj[0][:, hub][:, :, hub] + Y.data[:, sp, :]
    A = A[:, keep][:, :, keep]
    g = np.linalg.solve(A, vj[0][:, hub][:, keep, None])[..., 0]
    Yej = Y.data[:, bu, :][:, :, keep]
    return f, Yej * g[:, None, :], [DIRS[k] for k in keep]


@pytest.mark.parametrize("coupling", ["6dof", "5dof"])
def test_contributions_view_equals_the_terms_solved_by_hand(store, coupling):
    r = store
    r.state.case.coupling = coupling
    r.state.analysis.tab = "contributions"
    view = ContributionsView(store=r)
    view.__panel__()
    f, terms, kept = _terms_by_hand(2, 60, coupling)
    z = DIRS.index("z")
    for k, d in enumerate(kept):
        plotted = view._lines.data[f"hub_{d}"]
        np.testing.assert_allclose(plotted, 20 * np.log10(np.abs(terms[:, z, k])), atol=1e-8)
    if coupling == "5dof":
        assert np.isnan(view._lines.data["hub_ry"]).all()  # released: no term
    # their sum is the coupled response
    want = fbs_core.bushing_response(2, n_modes=60, coupling=coupling)
    want = want.sel(outputs="bushing:z").data[:, 0, 0]
    np.testing.assert_allclose(terms[:, z].sum(-1), want, rtol=1e-9)
    np.testing.assert_allclose(view._lines.data["total"], 20 * np.log10(np.abs(want)), atol=1e-9)
    # stacked: shares of the total add up to 100 % at every line
    r.state.analysis.contrib_mode = "stacked"
    assert view._stack_fig.visible and not view._lines_fig.visible
    np.testing.assert_allclose(view._stack.data["c6"], 100.0, atol=1e-8)
    # CSV: the columns and the provenance of the same state
    res = r.contributions
    meta, cols = read_csv(to_csv(res.columns, res.meta, "contributions"))
    assert meta["coupling"] == coupling and meta["harmonic"] == "2"
    np.testing.assert_allclose(
        cols["hub_z_re"], terms[:, z, kept.index("z")].real, rtol=1e-9, atol=1e-14
    )


def test_phase_view_bode_real_imag_and_cursors(store):
    r = store
    # case 3: the loaded reference tire's case-2 bushing z has no peak to label (issue 14)
    r.state.case.harmonic = 3
    r.state.analysis.tab = "phase"
    view = PhaseView(store=r)
    view.__panel__()
    want = fbs_core.bushing_response(3, n_modes=60).sel(outputs="bushing:z").data[:, 0, 0]
    ref = fbs_core.bushing_response(3).sel(outputs="bushing:z").data[:, 0, 0]
    np.testing.assert_allclose(view._src["b"].data["top"], 20 * np.log10(abs(want)), atol=1e-9)
    np.testing.assert_allclose(view._src["a"].data["top"], 20 * np.log10(abs(ref)), atol=1e-9)
    # unwrapped: consecutive lines never jump by more than 180 degrees
    ph = view._src["b"].data["bottom"]
    assert np.all(np.abs(np.diff(ph)) < 180)
    np.testing.assert_allclose(np.exp(1j * np.radians(ph)), want / abs(want), atol=1e-9)
    # cursors on grid lines read the plotted level there
    f = view._src["b"].data["freq"]
    r.state.analysis.param.update(cursor1=float(f[3]), cursor2=float(f[10]))
    np.testing.assert_allclose(
        view._cursors.data["level"], 20 * np.log10(abs(want[[3, 10]])), atol=1e-9
    )
    assert "df = " in r.phase.caption and "cursors" in r.phase.meta
    # the coupled modes near each peak (computed after the labels): near the peak
    pm = r.peak_modes
    assert pm is not None and pm.draw["waiting"] == 0
    assert all("modes" in t for t in view._peaks.data["text"])
    # labels arriving later change the labels only: the curves are not sent again
    curves = view._src["b"].data
    new = tuple(f"label {k}" for k in range(len(pm.draw["labels"])))
    r.peak_modes = dataclasses.replace(pm, draw={**pm.draw, "labels": new})
    assert view._src["b"].data is curves and list(view._peaks.data["text"]) == list(new)
    # real / imaginary parts
    r.state.analysis.phase_mode = "real/imag"
    np.testing.assert_allclose(view._src["b"].data["top"], want.real, rtol=1e-9, atol=1e-13)
    np.testing.assert_allclose(view._src["b"].data["bottom"], want.imag, rtol=1e-9, atol=1e-13)
    # the uncoupled tire: its free hub velocity Y_ja F_a
    r.state.analysis.frf = "tire"
    hub = fbs_core.reference_tire().patch_response(
        fbs_core.harmonic(3).frequencies(), fbs_core.harmonic(3), 60
    )
    np.testing.assert_allclose(
        view._src["b"].data["top"], hub.sel(outputs="hub:z").data[:, 0, 0].real, rtol=1e-9
    )
    # a log frequency axis
    r.state.analysis.log_freq = True
    assert type(view._top.x_scale).__name__ == "LogScale"


def test_the_speed_tabs_campbell_claims_no_direction_of_travel(store):
    """The Speed tab's branches are the modal model's tracked modes, which pass between
    forward and backward waves at the veerings: labelled by their slope, most branches
    whose waves the belt-wave diagram follows got the wrong direction (docs/modes.md). The
    view shows them without a direction, in one colour, and points to the wave diagram;
    neither its legend, its CSV nor the report's plot says forward or backward."""
    r = store
    r.state.analysis.tab = "speed"
    cv = CampbellView(store=r)
    cv.__panel__()
    res = r.campbell
    words = ("forward", "backward")
    legend = [i.label.value for i in cv._fig.legend[0].items]
    assert not any(w in t for t in legend for w in words), legend
    assert not any(w in c for c in res.columns for w in words)
    groups = res.draw["report_plot"]["groups"]
    assert not any(w in g for g in groups for w in words), list(groups)
    assert "Modes" in res.caption and "wave" in res.caption
    # every tracked branch is still drawn (the same frequencies as the core's)
    cb = fbs_core.analysis.campbell(fbs_core.reference_tire(), fmax=450.0)
    assert len(cv._branches["modes"].data["ys"]) == cb.branch.size


def test_campbell_and_speed_map_views_and_picking(store):
    r = store
    r.state.analysis.tab = "speed"
    cv, sv = CampbellView(store=r), SpeedMapView(store=r)
    cv.__panel__(), sv.__panel__()
    tire = fbs_core.reference_tire()
    eig = tire.eigenfrequencies(80.0)
    n = 0
    src = cv._branches["modes"].data
    for xs, ys in zip(src["xs"], src["ys"], strict=True):
        k = int(np.argmin(np.abs(xs - 80.0)))
        assert abs(xs[k] - 80.0) < 1e-9 and np.min(np.abs(eig - ys[k])) < 1e-6
        n += 1
    assert n > 20
    o = cv._orders.data
    for h, xs, ys in zip(o["harmonic"], o["xs"], o["ys"], strict=True):
        np.testing.assert_allclose(ys, xs / 3.6 / fbs_core.harmonic(h).wavelength, rtol=1e-12)
    # the map: a row is the coupled response with the tire at that fixed speed
    img = sv._img.data["image"][0]  # (freq, speed)
    sm = fbs_core.analysis.speed_map(2, 60)
    row = list(sm.speeds).index(60.0)
    want = fbs_core.bushing_response(2, n_modes=60, freq=sm.freq, speed_kmh=60.0)
    np.testing.assert_allclose(
        img[:, row], 20 * np.log10(abs(want.sel(outputs="bushing:z").data[:, 0, 0])), atol=1e-8
    )
    # picking: a point in the map; on an order line in the Campbell: that harmonic
    r.pick_point(70.0, 45.0)
    assert [s.visible for s in sv._spans] == [True, True]
    assert [s.location for s in sv._spans] == [70.0, 45.0]
    assert r.state.case.harmonic == 2
    r.pick_campbell(50.0, 5.0)  # below every order line: the harmonic stays
    assert r.state.case.harmonic == 2
    lam5 = fbs_core.harmonic(5).wavelength
    r.pick_campbell(90.0, 90.0 / 3.6 / lam5 * 1.01)
    assert r.state.case.harmonic == 5
    assert r.state.analysis.picked_speed == 90.0


def test_nothing_is_computed_while_the_card_is_collapsed_or_another_tab_is_shown(store):
    r = store
    r.state.case.n_modes = 80
    assert r.contributions is None and r.phase is None and r.speed_map is None
    r.state.analysis.tab = "speed"
    first = r.speed_map
    assert first is not None and r.contributions is None
    r.state.analysis.tab = "phase"
    r.state.case.n_modes = 90  # not shown: the speed map stays as it was
    assert r.speed_map is first and r.phase.meta["N (retained tire modes)"] == 90


# -- compare: pinned baselines ----------------------------------------------------------------
def _db_direct(harmonic, n_modes, dof="z", coupling="6dof"):
    v = fbs_core.bushing_response(harmonic, n_modes=n_modes, coupling=coupling)
    return 20 * np.log10(np.abs(v.sel(outputs=f"bushing:{dof}").data[:, 0, 0]))


def test_compare_pins_overlay_difference_band_and_map(store):
    from app.views.analysis_compare import CompareView

    r = store
    r.state.noise.param.update(rounds=200, seed=4, noise=5.0)
    r.request_band(wait=True)
    r.pin("base")
    assert r.message == "" and [p.name for p in r.pins] == ["base"]
    assert r.pins[0].data.sources["models"] == "reference"
    r.state.case.n_modes = 100
    r.state.analysis.tab = "compare"
    view = CompareView(store=r)
    view.__panel__()
    # overlay and difference: current (N = 100) minus the pin (N = 60), from the core directly
    np.testing.assert_allclose(view._curves[0][0].data["level"], _db_direct(2, 100), atol=1e-9)
    np.testing.assert_allclose(view._curves[1][0].data["level"], _db_direct(2, 60), atol=1e-9)
    np.testing.assert_allclose(
        view._diffs[0][0].data["diff"], _db_direct(2, 100) - _db_direct(2, 60), atol=1e-9
    )
    # the pin's band edges: the band of its settings, computed here by the core
    sb = fbs_core.studies.scatter_band(
        2, noise=0.05, target="both", rounds=200, seed=4, n_modes=60, percentiles=(5, 95)
    )
    j = sb.dofs.index("bushing:z")
    np.testing.assert_allclose(
        view._bands[1][0].data["high"], 20 * np.log10(sb.percentiles[1, :, j]), atol=1e-9
    )
    # the error map as a difference map: the current map minus the pinned state's map
    r.state.case.coupling = "5dof"
    r.pin("five")
    r.state.case.coupling = "6dof"
    r.state.analysis.compare_to = "five"
    from app import compute

    want = (
        compute.error_map_data(2, "6dof", "z")["error_pct"]
        - compute.error_map_data(2, "5dof", "z")["error_pct"]
    )
    np.testing.assert_allclose(view._img.data["image"][0], want, atol=1e-9)
    # another harmonic: no difference on another grid, said so in the CSV header
    r.state.case.harmonic = 3
    assert np.isnan(view._diffs[0][0].data["diff"]).all()
    res = r.compare
    meta, cols = read_csv(to_csv(res.columns, res.meta, "compare"))
    assert "different frequency grids" in meta["curve 1 difference"]
    assert "pin 'base'" in meta["curve 1"] and "seed 4" in meta["curve 1"]
    assert set(np.unique(cols["curve"])) == {0.0, 1.0, 2.0}
    np.testing.assert_allclose(cols["level_dB"][cols["curve"] == 1], _db_direct(2, 60), atol=1e-9)


def test_pins_in_the_url_are_rebuilt_in_a_new_session_and_names_are_checked(store):
    r = store
    r.pin("base")
    r.state.case.n_modes = 120
    r.pin("n120")
    link = r.state.analysis.pins
    assert link.count("|") == 1
    # a new session restoring the link: the same pins, the same data
    r2 = Results()
    r2.state.analysis.pins = link
    assert [p.name for p in r2.pins] == ["base", "n120"]
    for p, q in zip(r.pins, r2.pins, strict=True):
        np.testing.assert_array_equal(p.data.frfs["response"].data, q.data.frfs["response"].data)
    # names: taken, malformed, too many
    r.pin("base")
    assert "already named" in r.message
    r.pin("bad|name")
    assert "pin name" in r.message
    r.pin("c")
    r.pin("d")
    r.pin("e")
    assert "at most 4" in r.message and len(r.pins) == 4
    r.unpin("c")
    assert [p.name for p in r.pins] == ["base", "n120", "d"]
    # a malformed link is refused with a message, the pins stay
    r.state.analysis.pins = "x~h9"
    assert "malformed pin" in r.message and len(r.pins) == 3
    # a pin of an upload that is not loaded here: listed, without data
    r3 = Results()
    r3.state.analysis.pins = link.replace("mreference", "mdeadbeef")
    assert all(p.data is None and "not loaded" in p.note for p in r3.pins)


def test_each_pin_is_published_in_the_store_against_the_current_state(store):
    r = store
    assert r.pinned == ()
    r.pin("base")  # N = 60
    r.state.case.n_modes = 90  # whatever tab is shown (here: none)
    (res,) = r.pinned
    np.testing.assert_allclose(res.columns["pin_base_dB"], _db_direct(2, 60), atol=1e-9)
    np.testing.assert_allclose(
        res.columns["current_minus_pin_dB"], _db_direct(2, 90) - _db_direct(2, 60), atol=1e-9
    )
    assert "seed" in res.meta["pin"] and "models=reference" in res.meta["pin sources"]
    r.state.case.harmonic = 4  # another grid: the pin alone, the reason in its header
    (res,) = r.pinned
    assert "current_dB" not in res.columns and "different frequency grids" in res.meta["difference"]
    r.unpin("base")
    assert r.pinned == ()


def test_peak_modes_are_the_nearest_coupled_modes_and_nearby_peaks_share_a_solve():
    """A peak's labels: the coupled system's modes nearest the peak (truth: a wider
    eigenvalue solve of the assembled tire + chassis at the snapped speed, sorted here by
    distance to the peak); a peak moved a little by a change of N reuses the solve."""
    from app.results import analysis_compute as ac
    from fbs_core.analysis.peaks import coupled_system, system_modes_near

    speed, f = 61.3, 117.37
    v_snap = round(speed / ac.PEAK_SNAP_KMH) * ac.PEAK_SNAP_KMH
    got = ac.peak_modes(f, speed, "6dof", n=2)
    wide = system_modes_near(coupled_system(v_snap, "6dof"), f, 12)
    want = sorted(wide, key=lambda m: abs(m.freq - f))[:2]
    assert [m.pole for m in got] == pytest.approx([m.pole for m in want], rel=1e-9)
    misses = ac._peak_modes.cache_info().misses
    ac.peak_modes(f + 0.1, speed + 0.2, "6dof", n=2)  # the same snapped point
    assert ac._peak_modes.cache_info().misses == misses


@pytest.mark.parametrize(
    ("tab", "name"),
    [
        ("speed", "speed_map"),
        ("contributions", "contributions"),
        ("phase", "phase"),
        ("compare", "compare"),
    ],
)
def test_the_shown_analysis_view_is_published_before_the_main_views(store, tab, name):
    """The view the user looks at is computed (and so drawn) first on a change of the case,
    and once: its own watcher, which comes later, finds it current."""
    r = store
    r.state.analysis.tab = tab
    order = []
    r.param.watch(lambda e: order.append(e.name), [name, "response", "error_map", "suggested"])
    r.state.case.dof = "x"
    assert order[0] == name and order.count(name) == 1, order
    assert "response" in order
    # the published result is that of the new state
    meta = getattr(r, name).meta
    if name == "compare":
        assert " bushing:x " in meta["curve 0"]
        cur = getattr(r, name).draw["curves"][0]["level"]
        ref = fbs_core.vocabulary.magnitude_db(
            fbs_core.bushing_response(2, n_modes=60).sel(outputs="bushing:x").data[:, 0, 0]
        )
        np.testing.assert_allclose(cur, ref, rtol=1e-9)
    else:
        assert meta["response DOF"] == "bushing:x"
    r.state.analysis.tab = ""  # a closed card: the main views' order as before
    order.clear()
    r.state.case.dof = "y"
    assert name not in order and order[0] == "response", order


def test_the_compare_result_shown_first_follows_its_pins_and_the_band(store):
    """Compare, published ahead of the main views, is published again when anything else
    it is made of changes (a new pin, the compared pin, the band arriving), and not again
    by its own watcher for the same state."""
    import time

    r = store
    r.state.noise.param.update(seed=90417, rounds=500)  # bands no other test computed
    r.request_band(wait=True)
    r.background = True  # as served: bands on a thread of their own
    r.state.analysis.tab = "compare"
    seen = []
    r.param.watch(lambda e: seen.append(e.new), ["compare"])
    r.pin("one")
    assert len(seen) == 1 and len(seen[-1].draw["curves"]) == 2  # current + the new pin
    # a new N: published for the new state ahead of the main views (no band of it yet),
    # then again when its band arrives
    r.state.case.n_modes = 80  # the band starts on its thread, waiting for the lock
    t0 = time.monotonic()
    while len(seen) < 3 and time.monotonic() - t0 < 300:
        time.sleep(0.01)
    assert len(seen) == 3
    assert seen[1].draw["curves"][0]["band"] is None
    assert seen[2].draw["curves"][0]["band"] is not None
    assert "N=80" in seen[1].meta["curve 0"] and "N=80" in seen[2].meta["curve 0"]
    r.pin("two")
    assert len(seen) == 4 and len(seen[-1].draw["curves"]) == 3
    r.state.analysis.compare_to = "two"
    assert len(seen) == 5 and "'two'" in seen[-1].meta["difference map"]
    r.state.analysis.cursor1 = 30.0  # not something the comparison is made of
    assert len(seen) == 5


def test_a_step_of_the_n_slider_on_the_speed_tab_computes_the_next_step_ahead(store, monkeypatch):
    """Served, a step of N on the speed tab computes the speed map of the next count in the
    same direction on the process' worker for work ahead: the next step is a cache hit. A
    change of harmonic computes nothing ahead."""
    from app.results import analysis_compute as ac
    from app.runtime.background import AHEAD

    r = store
    asked = []
    submit = AHEAD.submit
    monkeypatch.setattr(AHEAD, "submit", lambda key, work: (asked.append(key), submit(key, work)))
    r.background = True  # as in a served page
    models = r.state.case.models

    def hit(n):
        before = ac._speed_map.cache_info()
        m = ac.speed_map(2, n, "6dof", models)
        after = ac._speed_map.cache_info()
        return m.n_modes == n and (after.hits, after.misses) == (before.hits + 1, before.misses)

    ac._speed_map.cache_clear()  # a hit below is this test's own computation
    try:
        r.state.analysis.tab = "speed"  # N = 60
        assert asked == []  # the first map: no step yet
        r.state.case.n_modes = 70  # up: 80 ahead
        assert asked == [(r, "speed_map")] and AHEAD.idle(300) and hit(80)
        r.state.case.n_modes = 60  # down: 50 ahead
        assert AHEAD.idle(300) and hit(50)
        asked.clear()
        r.state.case.harmonic = 3
        assert asked == []
        # not served: nothing computed ahead
        r.background = False
        r.state.case.n_modes = 70
        assert asked == []
    finally:
        r.close()


def test_a_pin_keeps_its_residual_setting_and_compare_honours_the_current_one(store):
    """Issue 27: with residual compensation on, Compare showed a flat 0 dB difference to a
    pin taken with it off (its current curve ignored the setting). Truth: the core's
    plain and residual responses of this N computed directly."""
    r = store
    r.state.case.param.update(harmonic=5, n_modes=50)
    r.pin("plain")  # residual off
    r.state.case.residual = True
    r.pin("comp")  # residual on
    r.state.analysis.tab = "compare"
    try:
        curves = r.compare.draw["curves"]
        on = _db_direct_res(5, 50, True)
        off = _db_direct_res(5, 50, False)
        np.testing.assert_allclose(curves[0]["level"], on, atol=1e-9)  # current: compensated
        np.testing.assert_allclose(curves[1]["diff"], on - off, atol=1e-9)
        assert np.nanmax(np.abs(curves[1]["diff"])) > 1.0  # not flat
        np.testing.assert_allclose(curves[2]["diff"], 0.0, atol=1e-9)  # the same state
        assert "+ residual" in r.compare.meta["curve 0"]
        assert "+ residual" not in r.compare.meta["curve 1"]
        assert "+ residual" in r.compare.meta["curve 2"]
        # the link keeps it: a new session rebuilds both pins with their own setting
        r2 = Results()
        r2.state.analysis.pins = r.state.analysis.pins
        assert [p.settings.residual for p in r2.pins] == [False, True]
        np.testing.assert_allclose(
            magnitude_db(r2.pins[1].data.frfs["response"].data[:, 0, 0]), on, atol=1e-9
        )
        # a link made before pins kept the setting opens as plain truncation
        old = r.state.analysis.pins.split("|")[0].replace("~r0", "")
        r2.state.analysis.pins = old
        assert r2.message == "" and [p.settings.residual for p in r2.pins] == [False]
    finally:
        r.state.case.param.update(residual=False, harmonic=2, n_modes=60)
        r.state.analysis.tab = ""


def _db_direct_res(harmonic, n_modes, residual, dof="z"):
    v = fbs_core.bushing_response(harmonic, n_modes=n_modes, residual=residual)
    return magnitude_db(v.sel(outputs=f"bushing:{dof}").data[:, 0, 0])
