"""The Analysis card in a real browser: contributions, phase and peaks, across speed.

Plot data are read from the Bokeh document's named sources. Truth: the core called here
directly (the coupled response, the tire's eigenfrequencies, the closed-form order lines),
and, inside the page, the main view's coupled response (the contributions add up to it).
"""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core
from app.export import read_csv

from .conftest import fingerprint, open_dashboard, source, wait_changed, wait_loaded

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def page(browser, dashboard):
    context = browser.new_context(viewport={"width": 1600, "height": 1400}, accept_downloads=True)
    pg = context.new_page()
    pg.errors = []
    pg.on("console", lambda m: m.type == "error" and pg.errors.append(m.text))
    pg.on("pageerror", lambda e: pg.errors.append(str(e)))
    open_dashboard(pg, dashboard.url + "?rounds=500&h=2&N=60&atab=contributions")
    yield pg
    context.close()


def _tab(page, name):
    page.locator(".analysis-tabs").get_by_text(name, exact=True).first.click()


def _db(v):
    return 20 * np.log10(np.abs(v))


def test_contributions_add_up_to_the_coupled_response(page, dashboard):
    wait_loaded(page, ["contributions.lines", "mobility.truncated"])
    lines = source(page, "contributions.lines")
    # inside the page: the total of the terms is the main view's coupled response
    np.testing.assert_allclose(
        lines["total"], source(page, "mobility.truncated")["level"], atol=1e-9
    )
    want = fbs_core.bushing_response(2, n_modes=60).sel(outputs="bushing:z").data[:, 0, 0]
    np.testing.assert_allclose(lines["total"], _db(want), atol=1e-9)
    # the CSV holds the plotted terms and its provenance
    with page.expect_download() as info:
        page.locator(".download-contributions").first.click()
    meta, cols = read_csv(open(info.value.path()).read())
    assert meta["harmonic"] == "2" and meta["response DOF"] == "bushing:z"
    assert "fbs_core version" in meta and "models" in meta
    np.testing.assert_allclose(cols["hub_x_dB"], lines["hub_x"], rtol=1e-12)
    terms = sum(
        cols[f"hub_{d}_re"] + 1j * cols[f"hub_{d}_im"] for d in ("x", "y", "z", "rx", "ry", "rz")
    )
    np.testing.assert_allclose(terms, want, rtol=1e-9, atol=1e-12)
    # stacked (its data are sent when it is shown): the shares add up to 100 % at every line
    modes = page.locator(".ctl-analysis-contrib_mode")
    modes.get_by_text("stacked", exact=True).click()
    wait_loaded(page, ["contributions.stacked"])
    st = source(page, "contributions.stacked")
    np.testing.assert_allclose(st["c6"], 100.0, atol=1e-6)
    modes.get_by_text("lines", exact=True).click()
    assert page.errors == [] and dashboard.errors() == []


def test_phase_view_bode_peaks_cursors_and_log_axis(browser, dashboard):
    # harmonic 3: its bushing:z response has peaks to label (harmonic 2's has none of 3 dB
    # prominence on the statically loaded reference tire). A page of its own, closed once
    # loaded: navigating the module's page away while its session starts up makes Bokeh
    # log a traceback of its own
    context = browser.new_context(viewport={"width": 1600, "height": 1400})
    page = context.new_page()
    page.errors = []
    page.on("console", lambda m: m.type == "error" and page.errors.append(m.text))
    page.on("pageerror", lambda e: page.errors.append(str(e)))
    try:
        open_dashboard(page, dashboard.url + "?rounds=500&h=3&N=60&atab=contributions")
        _phase_view_checks(page, dashboard)
    finally:
        context.close()


def _phase_view_checks(page, dashboard):
    _tab(page, "Phase and peaks")
    page.wait_for_function("() => window.location.search.includes('atab=phase')")
    wait_loaded(page, ["phase.a", "phase.b", "phase.peaks"])
    want = fbs_core.bushing_response(3, n_modes=60).sel(outputs="bushing:z").data[:, 0, 0]
    b = source(page, "phase.b")
    np.testing.assert_allclose(b["top"], _db(want), atol=1e-9)
    np.testing.assert_allclose(b["bottom"], np.degrees(np.unwrap(np.angle(want))), atol=1e-7)
    # automatic peak labels: each at a local maximum of the plotted level (within a line)
    peaks = source(page, "phase.peaks")
    lv, f = np.asarray(b["top"]), np.asarray(b["freq"])
    assert len(peaks["freq"]) >= 1
    for fp in peaks["freq"]:
        j = int(np.argmin(np.abs(f - fp)))
        assert abs(f[j] - fp) <= 0.5 * (f[1] - f[0]) + 1e-9
        top = max(lv[max(j - 1, 0) : j + 2])
        assert lv[j] == top or max(lv[j - 1], lv[j + 1]) == top
    # the coupled modes nearby arrive a moment later
    page.wait_for_function(
        """() => [...Bokeh.documents[0].all_models].filter(m => m.name === 'phase.peaks')[0]
                 .data.text.some(t => t.includes('modes'))""",
        timeout=120_000,
    )
    # delta cursors: two clicks in the plot -> two cursors on grid lines
    before = fingerprint(page, "phase.cursors")
    for cls, value in (
        ("ctl-analysis-cursor1", b["freq"][4]),
        ("ctl-analysis-cursor2", b["freq"][20]),
    ):
        inp = page.locator(f".{cls} input").first
        inp.fill(str(value))
        inp.press("Enter")
    wait_changed(page, "phase.cursors", before)
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].filter(m => m.name === 'phase.cursors')[0]"
        ".data.freq.length === 2"
    )
    cur = source(page, "phase.cursors")
    np.testing.assert_allclose(cur["level"], [_db(want)[4], _db(want)[20]], atol=1e-9)
    # real / imaginary parts
    before = fingerprint(page, "phase.b")
    page.locator(".ctl-analysis-phase_mode").get_by_role("button", name="real/imag").click()
    wait_changed(page, "phase.b", before)
    b = source(page, "phase.b")
    np.testing.assert_allclose(b["top"], want.real, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(b["bottom"], want.imag, rtol=1e-9, atol=1e-12)
    # log-frequency axis
    page.locator(".ctl-analysis-log_freq input").click()
    page.wait_for_function(
        """() => [...Bokeh.documents[0].all_models].some(
                 m => m.name === 'phase.top' && m.x_scale.type === 'LogScale')"""
    )
    assert page.errors == [] and dashboard.errors() == []


def test_across_speed_campbell_speed_map_and_picking(page, dashboard):
    _tab(page, "Across speed")
    wait_loaded(page, ["campbell.modes", "campbell.orders"], timeout=180_000)
    page.wait_for_function(
        """() => [...Bokeh.documents[0].all_models].filter(m => m.name === 'speedmap.image')[0]
                 .data.image[0].length > 100""",
        timeout=180_000,
    )
    tire = fbs_core.reference_tire()
    # every branch passes through the tire's eigenfrequencies at its operating points
    eig = tire.eigenfrequencies(80.0)
    for d in ("modes",):  # one set of branches: no direction of travel is claimed
        data = page.evaluate(
            """(n) => { const m = [...Bokeh.documents[0].all_models].filter(
                 x => x.name === n)[0];
               return {xs: m.data.xs.map(a => Array.from(a)),
                       ys: m.data.ys.map(a => Array.from(a))}; }""",
            f"campbell.{d}",
        )
        for xs, ys in zip(data["xs"], data["ys"], strict=True):
            k = int(np.argmin(np.abs(np.asarray(xs) - 80.0)))
            assert abs(xs[k] - 80.0) < 1e-9
            assert np.min(np.abs(eig - ys[k])) < 1e-6
    # order lines: f = v / 3.6 / lambda (closed form) of the seven cases
    orders = page.evaluate(
        """() => { const m = [...Bokeh.documents[0].all_models].filter(
             x => x.name === 'campbell.orders')[0];
           return {xs: m.data.xs.map(a => Array.from(a)), ys: m.data.ys.map(a => Array.from(a)),
                   h: Array.from(m.data.harmonic)}; }"""
    )
    assert orders["h"] == [1, 2, 3, 4, 5, 6, 7]
    for h, xs, ys in zip(orders["h"], orders["xs"], orders["ys"], strict=True):
        lam = fbs_core.harmonic(h).wavelength
        np.testing.assert_allclose(ys, np.asarray(xs) / 3.6 / lam, rtol=1e-12)
    # the speed map's row at 60 km/h is the fixed-speed coupled response
    img = source(page, "speedmap.image")["image"]
    sm_rows = 21
    lv = np.asarray(img, float).reshape(-1, sm_rows).T  # (speed, freq)
    f = fbs_core.analysis.speed_map(2, 60).freq
    want = fbs_core.bushing_response(2, n_modes=60, freq=f, speed_kmh=60.0)
    np.testing.assert_allclose(lv[8], _db(want.sel(outputs="bushing:z").data[:, 0, 0]), atol=1e-8)
    # a click in the speed map picks a speed and a frequency: markers and the URL
    x, y = _screen(page, "speedmap.figure", 70.0, 45.0)
    page.mouse.click(x, y)
    page.wait_for_function("() => window.location.search.includes('pv=')")
    page.wait_for_function(
        """() => [...Bokeh.documents[0].all_models].filter(
             m => m.name === 'speedmap.pick_width' && m.visible).length === 1"""
    )
    spans = _spans(page, "speedmap.pick")
    assert spans["speedmap.pick_height"][0] and abs(spans["speedmap.pick_height"][1] - 70) < 1.5
    assert spans["speedmap.pick_width"][0] and abs(spans["speedmap.pick_width"][1] - 45) < 1.5
    # a click on harmonic 5's order line in the Campbell diagram chooses harmonic 5
    lam = fbs_core.harmonic(5).wavelength
    x, y = _screen(page, "campbell.figure", 90.0, 90.0 / 3.6 / lam)
    page.mouse.click(x, y)
    page.wait_for_function("() => window.location.search.includes('h=5')", timeout=180_000)
    assert page.errors == [] and dashboard.errors() == []


JS_SCREEN = """([name, x, y]) => {
  const m = [...Bokeh.documents[0].all_models].filter(m => m.name === name)[0];
  const v = Bokeh.index.find_one(m);
  v.el.scrollIntoView({block: 'center'});
  const r = v.canvas_view.el.getBoundingClientRect();
  return [r.left + v.frame.x_scale.compute(x), r.top + v.frame.y_scale.compute(y)];
}"""


def _screen(page, figure, x, y):
    """Page coordinates of the data point (x, y) in the named figure."""
    return page.evaluate(JS_SCREEN, [figure, x, y])


def _spans(page, prefix):
    return page.evaluate(
        """(p) => Object.fromEntries([...Bokeh.documents[0].all_models].filter(
             m => m.name && m.name.startsWith(p) && m.type === 'Span').map(
             m => [m.name, [m.visible, m.location]]))""",
        prefix,
    )


def test_compare_pin_change_and_difference(page, dashboard):
    _tab(page, "Compare")
    page.wait_for_function("() => window.location.search.includes('atab=compare')", timeout=180_000)
    # (the previous test's harmonic 5 starts a new band: on a loaded machine it takes long)
    wait_loaded(page, ["compare.curve0", "mobility.truncated"], timeout=180_000)
    before = source(page, "mobility.truncated")
    box = page.locator(".ctl-analysis-pin_name input").first
    box.fill("base")
    box.press("Enter")
    page.locator(".ctl-analysis-pin button").first.click()
    page.wait_for_function("() => window.location.search.includes('pins=base')")
    wait_loaded(page, ["compare.curve1"])
    # change N: the difference is the current main-view curve minus the pinned one
    fp = fingerprint(page, "compare.diff1")
    fp_main = fingerprint(page, "mobility.truncated")
    from .conftest import set_model_value

    set_model_value(page, "ctl-case-n_modes", 150, "Slider")
    page.wait_for_function("() => window.location.search.includes('N=150')")
    wait_changed(page, "compare.diff1", fp)
    # the shown analysis view is drawn before the main views: wait for the main curve too
    wait_changed(page, "mobility.truncated", fp_main)
    page.wait_for_function(
        """() => { const d = [...Bokeh.documents[0].all_models].filter(
             m => m.name === 'compare.diff1')[0].data.diff;
           return Array.from(d).some(x => Math.abs(x) > 0); }"""
    )
    now = source(page, "mobility.truncated")
    diff = source(page, "compare.diff1")
    np.testing.assert_allclose(diff["freq"], before["freq"])
    np.testing.assert_allclose(
        diff["diff"], np.asarray(now["level"]) - np.asarray(before["level"]), atol=1e-9
    )
    with page.expect_download() as info:
        page.locator(".download-compare").first.click()
    meta, cols = read_csv(open(info.value.path()).read())
    assert "pin 'base'" in meta["curve 1"] and "fbs_core version" in meta
    np.testing.assert_allclose(cols["diff_dB"][cols["curve"] == 1], diff["diff"], atol=1e-12)
    assert page.errors == [] and dashboard.errors() == []
