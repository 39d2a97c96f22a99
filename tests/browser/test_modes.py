"""The Modes and Selected-modes tabs in a real browser (issue 30): clicks, not links.

A click on a bar of the participation ranking and a click on a branch of the Campbell
diagram of the waves pick a mode: the URL says which, and the page draws its shape and
animates it (the frames shown one after the other by the page's own script). Truth: the
core called here directly (the ranking of ``mode_participation``, the shape of
``tire_mode_shape``, the stored pair of the wave branch at the operating point).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import fbs_core
from fbs_core.analysis import mode_participation, tire_mode_shape

from .conftest import fingerprint, open_dashboard, source, wait_changed, wait_loaded
from .layout_util import layout_problems, wait_stable
from .test_analysis import _screen

pytestmark = pytest.mark.browser

JS_LISTS = """(name) => {
  const m = [...Bokeh.documents[0].all_models].filter(x => x.name === name)[0];
  const out = {};
  for (const [k, v] of Object.entries(m.data))
    out[k] = Array.from(v, a => (typeof a === 'object' ? Array.from(a) : a));
  return out;
}"""


@pytest.fixture(scope="module")
def page(browser, dashboard):
    context = browser.new_context(viewport={"width": 1600, "height": 1400}, accept_downloads=True)
    pg = context.new_page()
    pg.errors = []
    pg.on("console", lambda m: m.type == "error" and pg.errors.append(m.text))
    pg.on("pageerror", lambda e: pg.errors.append(str(e)))
    open_dashboard(pg, dashboard.url + "?rounds=500&h=1&fmax=160&atab=modes", timeout=400_000)
    yield pg
    context.close()


def _mode_in_url(page) -> int | None:
    m = re.search(r"[?&]mode=(\d+)", page.evaluate("() => window.location.search"))
    return int(m.group(1)) if m else None


def test_a_click_on_a_bar_draws_that_modes_shape_and_animates_it(page, dashboard):
    wait_loaded(page, ["participation.bars", "modeshape.frames"], timeout=180_000)
    bars = page.evaluate(JS_LISTS, "participation.bars")
    # the bars are the core's ranking (an independent call): harmonic 1, bushing:z, the band
    # up to 160 Hz (its whole band), by the leave-one-out error
    p = mode_participation(1)
    order = p.ranking("loo", "bushing:z", vibration=True)  # the slip states: not bars
    n = len(bars["mode"])
    assert [int(m) for m in bars["mode"]] == [int(m) for m in p.modes[order[:n]]]
    np.testing.assert_allclose(bars["value"], 100 * p.loo[order[:n], 2], rtol=1e-9)
    # the tab's views stand one below the other: no control over a plot takes its clicks
    wait_stable(page)
    assert not layout_problems(page, 1600)
    # a real click on the third bar
    target = int(bars["mode"][2])
    before = fingerprint(page, "modeshape.frames")
    x, y = _screen(page, "participation.figure", 2.0, 0.5 * bars["value"][2])
    page.mouse.click(x, y)
    page.wait_for_function(f"() => /[?&]mode={target}(&|$)/.test(window.location.search)")
    wait_changed(page, "modeshape.frames", before)
    # the frames drawn are the core's shape of that mode where the harmonic line meets it
    speed = float(p.mode_speed[order[2]])
    want = tire_mode_shape(target, round(speed, 1))
    frames = page.evaluate(JS_LISTS, "modeshape.frames")
    np.testing.assert_allclose(frames["x"][5], want.shape.ring[5, :, 0], atol=1e-9)
    np.testing.assert_allclose(frames["z"][5], want.shape.ring[5, :, 2], atol=1e-9)
    # the bar of the picked mode is highlighted
    page.wait_for_function(
        """(m) => { const s = [...Bokeh.documents[0].all_models].filter(
             x => x.name === 'participation.bars')[0];
           const i = Array.from(s.data.mode).indexOf(m);
           return s.data.color[i] !== s.data.color[(i + 1) % s.data.mode.length]; }""",
        arg=target,
    )
    # animated in the page: the shown frame changes by itself, through the frames sent
    shown = []
    for _ in range(3):
        page.wait_for_function(
            """(prev) => { const s = [...Bokeh.documents[0].all_models].filter(
                 x => x.name === 'modeshape.ring')[0];
               return s.data.x.length > 0 && s.data.x[3] !== prev; }""",
            arg=shown[-1][3] if shown else None,
        )
        shown.append(source(page, "modeshape.ring")["x"])
    sent = np.asarray(frames["x"])
    for ring in shown:
        assert np.min(np.abs(sent - np.asarray(ring)).max(axis=1)) < 1e-12
    assert len({tuple(np.round(r, 12)) for r in shown}) == 3
    assert page.errors == [] and dashboard.errors() == []


def test_a_click_on_a_wave_branch_draws_the_mode_that_carries_it(page, dashboard):
    # the waves are solved in the background the first time (about 20 s on an idle core)
    wait_loaded(page, ["waves.branches"], timeout=300_000)
    cb = fbs_core.analysis.wave_campbell()
    sel = cb.selection(1)
    br = page.evaluate(JS_LISTS, "waves.branches")
    assert br["label"] == [cb.labels()[b] for b in sel]
    # click the most excited branch at an operating point inside the harmonic's speeds
    b = int(sel[0])
    i = int(np.argmin(np.abs(cb.speeds - 50.0)))
    v, f = float(cb.speeds[i]), float(cb.freq[i, b])
    want = int(cb.stored[i, b])
    assert want >= 0
    x, y = _screen(page, "waves.figure", v, f)
    page.mouse.click(x, y)
    page.wait_for_function(f"() => /[?&]mode={want}(&|$)/.test(window.location.search)")
    page.wait_for_function(
        """(v) => { const s = [...Bokeh.documents[0].all_models].filter(
             x => x.name === 'waves.picked')[0];
           return s.data.x.length === 1 && Math.abs(s.data.x[0] - v) < 0.06; }""",
        arg=v,
    )
    assert _mode_in_url(page) == want
    shape = tire_mode_shape(want, round(v, 1))
    frames = page.evaluate(JS_LISTS, "modeshape.frames")
    np.testing.assert_allclose(frames["x"][0], shape.shape.ring[0, :, 0], atol=1e-9)
    star = source(page, "waves.picked")
    assert abs(star["x"][0] - v) < 0.06 and abs(star["y"][0] - shape.freq) < 1e-6
    assert page.errors == [] and dashboard.errors() == []


def test_selected_modes_tab_shows_the_selections_and_the_chassis_side(page, dashboard):
    page.locator(".analysis-tabs").get_by_text("Selected modes", exact=True).first.click()
    page.wait_for_function("() => window.location.search.includes('atab=selection')")
    wait_loaded(page, ["selected.table", "chassistrunc.curve"], timeout=180_000)
    table = page.evaluate(JS_LISTS, "selected.table")
    low = fbs_core.studies.truncation_map(1).suggest(0.2, 160.0, "bushing:z")
    sel = fbs_core.analysis.select_modes(1, 0.2, 160.0, by="greedy", dof="bushing:z")
    assert table["n_modes"][0] == low and table["n_modes"][2] == sel.n_modes
    curve = source(page, "chassistrunc.curve")
    m = fbs_core.studies.chassis_truncation_map(1)
    np.testing.assert_array_equal(curve["n"], m.n_modes)
    assert page.errors == [] and dashboard.errors() == []
