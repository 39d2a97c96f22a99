"""The Modes and Selected-modes tabs on a projector: the presentation view at 1280 x 720.

What a meeting room needs to read: every plot of the two tabs in the presentation view's
type (tick labels, titles and title blocks at least 14-16 px, as the Speed tab's), the
bars' labels of the participation ranking apart from each other (measured: the label
extents from the page's own font metrics against the bar slots of the drawn plot), and
the tables whole: every column and header of the selected-modes table and of the
suggested-modes table inside its table's box and not cut (bounding boxes, scroll widths).
Screenshots go to tests/browser/artifacts/.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from .conftest import open_dashboard, wait_loaded

pytestmark = pytest.mark.browser

ARTIFACTS = Path(__file__).parent / "artifacts"
SIZE = (1280, 720)
MODES_FIGURES = ("participation.figure", "waves.figure", "modeshape.figure")
SELECTION_FIGURES = ("chassistrunc.figure",)

JS_FONTS = """(names) => {
  const ms = [...Bokeh.documents[0].all_models];
  const px = s => parseFloat(s) * (String(s).endsWith('pt') ? 4 / 3 : 1);
  return names.map(n => {
    const f = ms.filter(m => m.type === 'Figure' && m.name === n)[0];
    if (!f) return {name: n, missing: true};
    const axes = f.left.concat(f.below).filter(a => a.type.endsWith('Axis'));
    return {
      name: n,
      tick: Math.min(...axes.map(a => px(a.major_label_text_font_size))),
      axis: Math.min(...axes.map(a => px(a.axis_label_text_font_size))),
      titles: f.above.filter(t => t.type === 'Title' && t.visible && t.text)
                     .map(t => [t.text.slice(0, 40), px(t.text_font_size)]),
    };
  });
}"""

#: The participation plot's bar labels: the drawn plot's inner width, the labels, their font
#: and orientation, and each label's extent along the axis from the page's font metrics.
JS_BAR_LABELS = """() => {
  const ms = [...Bokeh.documents[0].all_models];
  const f = ms.filter(m => m.type === 'Figure' && m.name === 'participation.figure')[0];
  const ax = f.below.filter(a => a.type.endsWith('Axis'))[0];
  const src = ms.filter(m => m.name === 'participation.bars')[0];
  const labels = Array.from(src.data.label);
  const ctx = document.createElement('canvas').getContext('2d');
  const size = ax.major_label_text_font_size;
  ctx.font = `${ax.major_label_text_font_style || 'normal'} ${size} ${ax.major_label_text_font}`;
  const o = ax.major_label_orientation;
  const angle = typeof o === 'number' ? o : (o === 'horizontal' ? 0 : Math.PI / 2);
  const ext = labels.map(t => {
    const m = ctx.measureText(t);
    const h = m.actualBoundingBoxAscent + m.actualBoundingBoxDescent;
    return Math.abs(m.width * Math.cos(angle)) + Math.abs(h * Math.sin(angle));
  });
  return {inner: f.inner_width, n: labels.length, ext, angle, size,
          lo: f.x_range.start, hi: f.x_range.end};
}"""


def _open(browser, dashboard, query: str):
    ctx = browser.new_context(viewport={"width": SIZE[0], "height": SIZE[1]})
    page = ctx.new_page()
    page.errors = []
    page.on("pageerror", lambda e: page.errors.append(str(e)))
    open_dashboard(page, dashboard.url + query, timeout=400_000)
    return ctx, page


def _shot(page, name: str) -> None:
    ARTIFACTS.mkdir(exist_ok=True)
    path = ARTIFACTS / name
    page.screenshot(path=str(path), full_page=True)
    print(f"screenshot: {path}")


def _check_fonts(page, names) -> None:
    page.wait_for_function(
        """(names) => names.every(n => [...Bokeh.documents[0].all_models].some(
             m => m.type === 'Figure' && m.name === n))""",
        arg=list(names),
        timeout=240_000,
    )
    bad = []
    for f in page.evaluate(JS_FONTS, list(names)):
        if f.get("missing"):
            bad.append(f"{f['name']}: not in the page")
            continue
        if f["tick"] < 14 or f["axis"] < 14:
            bad.append(f"{f['name']}: tick {f['tick']} px, axis {f['axis']} px")
        small = [t for t in f["titles"] if t[1] < 16]
        if small or not f["titles"]:
            bad.append(f"{f['name']}: titles under 16 px {small or 'none shown'}")
    assert not bad, bad


def _boxes_inside(page, table_sel: str, cell_sel: str, text_sel: str) -> list[str]:
    """Problems of a table: a column (cell box) outside the table's box, or a header text
    wider than its cell (cut)."""
    table = page.locator(table_sel).first
    table.wait_for(state="visible", timeout=240_000)
    tb = table.bounding_box()
    assert tb is not None
    out = []
    cells = page.locator(f"{table_sel} {cell_sel}")
    assert cells.count() > 0, cell_sel
    for i in range(cells.count()):
        c = cells.nth(i)
        b = c.bounding_box()
        name = c.inner_text().strip().replace("\n", " ")
        if b is None or b["width"] < 1:
            if name:  # (an empty zero-width column is the grid's hidden index column)
                out.append(f"column {i} ({name!r}) not shown")
            continue
        if b["x"] < tb["x"] - 1 or b["x"] + b["width"] > tb["x"] + tb["width"] + 1:
            out.append(
                f"column {i} ({name!r}) at x {b['x']:.0f}-{b['x'] + b['width']:.0f}, the "
                f"table {tb['x']:.0f}-{tb['x'] + tb['width']:.0f}"
            )
        t = c.locator(text_sel).first
        if t.count():
            sw, cw = t.evaluate("e => [e.scrollWidth, e.clientWidth]")
            if sw > cw + 1:
                out.append(f"header {name!r} cut: {sw} px of text in {cw} px")
    return out


def test_the_modes_tab_in_the_presentation_view_at_1280(browser, dashboard):
    ctx, page = _open(browser, dashboard, "?view=present&rounds=200&h=1&atab=modes")
    try:
        wait_loaded(page, ["participation.bars", "modeshape.frames"], timeout=400_000)
        _check_fonts(page, MODES_FIGURES)
        # the bars' labels apart: each label's extent along the axis within its bar's slot
        g = page.evaluate(JS_BAR_LABELS)
        slot = g["inner"] / (g["hi"] - g["lo"])  # px per bar (bars one unit apart)
        wide = [(i, round(e, 1)) for i, e in enumerate(g["ext"]) if e > 0.9 * slot]
        assert g["n"] >= 10 and not wide, (round(slot, 1), g["angle"], g["size"], wide)
        _shot(page, "present_modes_1280x720.png")
        assert not page.errors, page.errors
    finally:
        ctx.close()


def test_the_selected_modes_and_suggested_tables_are_whole_at_1280(browser, dashboard):
    ctx, page = _open(browser, dashboard, "?view=present&rounds=200&h=1&atab=modes")
    try:
        wait_loaded(page, ["participation.bars"], timeout=400_000)
        page.locator(".analysis-tabs").get_by_text("Selected modes", exact=True).first.click()
        page.wait_for_function("() => window.location.search.includes('atab=selection')")
        # the table's columns and headers are there before its rows (the selections take
        # minutes on a busy machine): the layout is checked as built
        _check_fonts(page, SELECTION_FIGURES)
        page.wait_for_function(
            """() => [...Bokeh.documents[0].all_models].some(m => m.name === 'selected.table'
                 && m.data.name && m.data.name.length > 0)""",
            timeout=600_000,
        )  # the rows: the columns take their widths with the data in
        bad = _boxes_inside(page, ".bk-DataTable", ".slick-header-column", ".slick-column-name")
        bad += _boxes_inside(page, ".suggested-table .tabulator", ".tabulator-col",
                             ".tabulator-col-title")  # fmt: skip
        _shot(page, "present_selection_1280x720.png")
        assert not bad, bad
        assert not page.errors, page.errors
    finally:
        ctx.close()
