"""The coupled-response plot as a test lab's FRF display (issue 29), driven as a user does:
two clicks in the plot place the labelled cursors and the readout appears, snap-to-peak
moves them onto peaks, a DOF button overlays its curve, the level axis turns linear; the
link reproduces it all. Screenshots go to ``tests/browser/artifacts/``.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy.signal import find_peaks

from .conftest import open_dashboard, source, wait_loaded
from .layout_util import layout_problems, shot, wait_stable

pytestmark = pytest.mark.browser

JS_SCREEN = """([name, x, y]) => {
  const m = [...Bokeh.documents[0].all_models].filter(m => m.name === name)[0];
  const v = Bokeh.index.find_one(m);
  const r = v.canvas_view.el.getBoundingClientRect();
  return [r.left + v.frame.x_scale.compute(x), r.top + v.frame.y_scale.compute(y)];
}"""

JS_CURSORS = """() => Object.fromEntries([...Bokeh.documents[0].all_models].filter(
     m => m.name && m.name.startsWith('mobility.cursor') && 'visible' in m && 'location' in m)
     .map(m => [m.name, m.visible ? m.location : null]))"""


JS_READOUT_AND_CANVAS = """() => {
  const walk = (root, out) => { for (const el of root.querySelectorAll('*')) {
      out.push(el); if (el.shadowRoot) walk(el.shadowRoot, out); } return out; };
  const t = walk(document, []).filter(el => el.tagName === 'TABLE'
      && el.classList.contains('cursor-readout'))[0];
  const f = [...Bokeh.documents[0].all_models].filter(m => m.name === 'mobility.figure')[0];
  const r = (e) => { const b = e.getBoundingClientRect(); return {top: b.top, bottom: b.bottom}; };
  return [r(t), r(Bokeh.index.find_one(f).el)];
}"""


def _query(page, key: str) -> str | None:
    return page.evaluate("(k) => new URLSearchParams(location.search).get(k)", key)


def _wait_query(page, key: str, pred: str) -> None:
    page.wait_for_function(
        f"(k) => {{ const v = new URLSearchParams(location.search).get(k); return {pred}; }}",
        arg=key,
        timeout=60_000,
    )


def test_cursors_readout_snap_overlay_and_linear_axis(browser, dashboard):
    ctx = browser.new_context(viewport={"width": 1366, "height": 768})
    page = ctx.new_page()
    open_dashboard(page, dashboard.url + "?rounds=1000&h=3")
    ref = source(page, "mobility.truncated")
    f, lv = np.asarray(ref["freq"], float), np.asarray(ref["level"], float)
    # two clicks in the plot: cursor 1, then cursor 2, at the frequencies clicked
    for k, i in ((1, 30), (2, 100)):
        # as a user: the plot is looked at where it stands now (the readout above it
        # appears with the first cursor)
        wait_stable(page)
        x, y = page.evaluate(JS_SCREEN, ["mobility.figure", float(f[i]), float(lv[i])])
        page.mouse.click(x, y)
        _wait_query(page, f"mc{k}", "v !== null && parseFloat(v) > 0")
        page.wait_for_function(
            "(n) => [...Bokeh.documents[0].all_models].filter(m => m.name === n && m.visible)"
            ".length === 1",
            arg=f"mobility.cursor{k}",
            timeout=60_000,
        )
    c1, c2 = float(_query(page, "mc1")), float(_query(page, "mc2"))
    step = f[1] - f[0]
    assert abs(c1 - f[30]) < 2 * step and abs(c2 - f[100]) < 2 * step, (c1, c2)
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].filter(m => m.name === "
        "'mobility.cursor2' && m.visible).length === 1"
    )
    readout = page.locator(".mobility-readout").filter(has_text="f2 - f1").last
    readout.wait_for(timeout=60_000)
    text = page.evaluate(  # the model's HTML (its text lies in a shadow root)
        """() => [...Bokeh.documents[0].all_models].filter(m => m.css_classes
             && m.css_classes.includes('mobility-readout')).map(m => m.text).join(' ')"""
    )
    assert f"f1 = {c1:.2f} Hz" in text and f"f2 - f1 = {c2 - c1:.2f} Hz" in text, text
    shot(page, "response_cursors")
    # snap to the nearest peak: the cursors stand on the curve's peaks
    page.locator(".ctl-plot-snap input").first.check()
    _wait_query(page, "snap", "v === 'true' || v === 'True'")
    peaks, _ = find_peaks(lv, prominence=3.0)
    want = [f[peaks[np.argmin(np.abs(f[peaks] - c))]] for c in (c1, c2)]
    page.wait_for_function(
        f"""(want) => {{ const c = ({JS_CURSORS})();
             return c['mobility.cursor1'] !== null && c['mobility.cursor2'] !== null
               && Math.abs(c['mobility.cursor1'] - want[0]) <= {step}
               && Math.abs(c['mobility.cursor2'] - want[1]) <= {step}; }}""",
        arg=want,
        timeout=60_000,
    )
    # a further DOF overlaid, and the linear level axis
    page.locator(".ctl-plot-overlay button").filter(has_text=re.compile(r"^\s*x\s*$")).first.click()
    wait_loaded(page, ["mobility.overlay_x"], timeout=60_000)
    page.locator(".ctl-plot-level_scale button", has_text="linear").first.click()
    page.wait_for_function(
        """() => [...Bokeh.documents[0].all_models].filter(m => m.type === 'Figure'
             && m.name === 'mobility.figure').every(f => f.left.every(
             a => a.axis_label && a.axis_label.startsWith('|v|')))""",
        timeout=60_000,
    )
    lin = source(page, "mobility.truncated")
    np.testing.assert_allclose(lin["level"], 10 ** (lv / 20), rtol=1e-9)
    # the link follows (written once the change is handled; the plot may come first)
    _wait_query(page, "lvl", "v === 'linear'")
    assert "x" in (_query(page, "over") or "")
    wait_stable(page)
    assert not layout_problems(page, 1366)
    # the readout's table lies above the plot's canvas, not over it
    table, canvas = page.evaluate(JS_READOUT_AND_CANVAS)
    assert table["bottom"] <= canvas["top"] + 0.5, (table, canvas)
    shot(page, "response_snap_overlay_linear")
    # the link reproduces it
    other = ctx.new_page()
    open_dashboard(other, page.url)
    wait_loaded(other, ["mobility.overlay_x"], timeout=60_000)
    other.locator(".mobility-readout").filter(has_text="f2 - f1").first.wait_for(timeout=60_000)
    assert other.evaluate(JS_CURSORS) == page.evaluate(JS_CURSORS)
    shot(other, "response_link")
    ctx.close()
