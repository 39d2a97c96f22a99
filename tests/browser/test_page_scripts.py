"""The page's small browser behaviours (app/page/scripts.py) at 1280x720, as a person uses
them: a click on a checkbox's words toggles it (every checkbox of the dashboard), and a
widget's description tooltip stays inside the window (the dashboard's icons, and a widget at
the window's right edge, where Bokeh put the tooltip off screen)."""

from __future__ import annotations

import panel as pn
import pytest
from panel.tests.util import serve_component

from app.page import scripts

from .conftest import open_dashboard

pytestmark = pytest.mark.browser

SIZE = {"width": 1280, "height": 720}

#: Rectangles of the shown tooltips (the DOM's public API; Bokeh's class name).
JS_TOOLTIPS = """() => { const out = [];
  const walk = (root) => { for (const el of root.querySelectorAll('*')) {
    if (el.classList.contains('bk-Tooltip')) { const r = el.getBoundingClientRect();
      if (r.width > 0 && r.height > 0) out.push([r.left, r.top, r.right, r.bottom]); }
    if (el.shadowRoot) walk(el.shadowRoot); } };
  walk(document); return out; }"""


def _inside(page, rects) -> list:
    w, h = SIZE["width"], SIZE["height"]
    return [r for r in rects if r[0] < 0 or r[1] < 0 or r[2] > w or r[3] > h]


def _hover_tooltip(page, icon) -> list:
    """Hover ``icon`` as a person does (onto it, then a small move) and the shown tooltips."""
    box = icon.bounding_box()
    icon.hover()
    page.mouse.move(box["x"] + box["width"] / 2 + 1, box["y"] + box["height"] / 2 + 1)
    page.wait_for_function(f"() => ({JS_TOOLTIPS})().length > 0", timeout=10_000)
    page.wait_for_timeout(150)  # a frame or two: where it settles is what the user sees
    return page.evaluate(JS_TOOLTIPS)


def test_every_checkbox_label_toggles_and_tooltips_stay_inside(browser, dashboard):
    ctx = browser.new_context(viewport=SIZE)
    page = ctx.new_page()
    try:
        open_dashboard(page, dashboard.url)
        labels = page.locator("input[type=checkbox] + .bk-label")
        n = labels.count()
        assert n >= 3, f"only {n} checkboxes found"
        toggled = 0
        for i in range(n):
            label = labels.nth(i)
            if not label.is_visible():
                continue
            box = label.locator("xpath=preceding-sibling::input[1]")
            if box.is_disabled():
                continue
            before = box.is_checked()
            label.click()
            page.wait_for_function(
                "([el, b]) => el.checked !== b", arg=[box.element_handle(), before], timeout=10_000
            )
            label.click()  # and back
            page.wait_for_function(
                "([el, b]) => el.checked === b", arg=[box.element_handle(), before], timeout=10_000
            )
            toggled += 1
        assert toggled >= 2, f"only {toggled} visible checkboxes toggled"
        # every description icon on the first screen: its tooltip inside the window
        icons = page.locator(".bk-description")
        outside = []
        for i in range(icons.count()):
            icon = icons.nth(i)
            if not icon.is_visible():
                continue
            icon.scroll_into_view_if_needed()
            outside += _inside(page, _hover_tooltip(page, icon))
            page.mouse.move(640, 5)
        assert not outside, outside
    finally:
        ctx.close()


def test_a_tooltip_at_the_right_edge_is_moved_inside_the_window(browser):
    """A widget with a long description at the window's right edge (Bokeh put its tooltip
    258 px beyond the edge at 1280x720)."""

    def app():
        scripts.install(pn.state.curdoc)
        w = pn.widgets.Select(
            name="Response point",
            options=["seat_fl", "seat_fr"],
            description="The response point of the whole car, six DOFs; " * 4,
            width=150,
        )
        return pn.Row(pn.Spacer(width=1110), w)

    page = browser.new_context(viewport=SIZE).new_page()
    try:
        serve_component(page, app)
        rects = _hover_tooltip(page, page.locator(".bk-description").first)
        assert rects and not _inside(page, rects), rects
    finally:
        page.context.close()
