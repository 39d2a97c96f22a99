"""Review meetings in chromium at projector and desktop sizes: the presentation view, title
blocks on every plot and saved image, the readable error map, the report downloads and a
shared link that needs uploaded data. Screenshots go to tests/browser/artifacts/."""

from __future__ import annotations

import io
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest
from pypdf import PdfReader

from .conftest import open_dashboard, table_json

pytestmark = pytest.mark.browser

ARTIFACTS = Path(__file__).parent / "artifacts"
SIZES = [(1280, 720), (1920, 1080)]

JS_FIGURES = """
() => {
  const ms = [...Bokeh.documents[0].all_models];
  return ms.filter(m => m.type === 'Figure' && m.name && m.name.endsWith('.figure')).map(f => ({
    name: f.name,
    titles: f.above.filter(t => t.type === 'Title' && t.visible).map(t => t.text),
    tick: f.left.concat(f.below).filter(a => a.type.endsWith('Axis'))
                .map(a => a.major_label_text_font_size),
    legends_inside: f.center.filter(r => r.type === 'Legend').length,
    legend_sizes: f.below.concat(f.right).filter(r => r.type === 'Legend')
                   .map(l => l.label_text_font_size),
    save: f.toolbar.tools.filter(t => t.type === 'SaveTool').map(t => t.filename),
  }));
}
"""


def _figures(page) -> dict:
    return {f["name"]: f for f in page.evaluate(JS_FIGURES)}


def _px(size: str) -> float:
    return float(size[:-2]) * (4 / 3 if size.endswith("pt") else 1.0)


def _context(browser, size):
    return browser.new_context(
        viewport={"width": size[0], "height": size[1]}, accept_downloads=True
    )


@pytest.mark.parametrize("size", SIZES)
def test_presentation_view(browser, dashboard, size):
    ctx = _context(browser, size)
    page = ctx.new_page()
    errors = []
    page.on("console", lambda m: m.type == "error" and errors.append(m.text))
    open_dashboard(page, dashboard.url + "?view=present&rounds=1000")
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].some(m => m.type === 'Title' && "
        "m.text.startsWith('Harmonic 1: wavelength 0.646 m'))"
    )
    # the data card is collapsed and a plot is on the first screen
    collapsed = page.evaluate(
        "() => [...Bokeh.documents[0].all_models].filter(m => m.css_classes && "
        "m.css_classes.includes('upload-card')).map(m => m.collapsed)"
    )
    assert collapsed == [True]
    box = page.get_by_text("Coupled response at the bushing").first.bounding_box()
    assert box is not None and box["y"] + 250 < size[1]
    figs = _figures(page)
    assert {"truncation.figure", "scatter.figure", "eigen.figure"} <= set(figs)
    for name, f in figs.items():
        assert all(_px(s) >= 14 for s in f["tick"]), (name, f["tick"])
        assert f["legends_inside"] == 0, name
        assert all(_px(s) >= 16 for s in f["legend_sizes"]), (name, f["legend_sizes"])
        assert any(t.startswith("Data: reference models") for t in f["titles"]), name
        assert f["save"] and f["save"][0].startswith("tire-fbs_"), (name, f["save"])
    assert figs["scatter.figure"]["save"][0].startswith(
        "tire-fbs_scatter-band_h1_bushing-z_N50_6dof_p10-both_R1000_"
    )
    assert "view=present" in page.url
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / f"present_{size[0]}x{size[1]}.png"))
    assert not errors, errors
    ctx.close()


@pytest.mark.parametrize("size", SIZES)
def test_readable_error_map_and_layout_in_link(browser, dashboard, size):
    ctx = _context(browser, size)
    page = ctx.new_page()
    open_dashboard(page, dashboard.url + "?naxis=log&card=closed&thr=15&rounds=1000")
    info = page.evaluate(
        """() => {
          const ms = [...Bokeh.documents[0].all_models];
          const fig = ms.filter(m => m.name === 'truncation.figure')[0];
          const mapper = ms.filter(m => m.name === 'truncation.mapper')[0];
          const contour = ms.filter(m => m.name === 'truncation.contour')[0];
          const legend = ms.filter(m => m.name === 'truncation.legend')[0];
          return {scale: fig.y_scale.type, high: mapper.high, above: mapper.high_color,
                  lines: contour.data.xs.length,
                  labels: legend.items.map(i => i.label.value)};
        }"""
    )
    assert info["scale"] == "LogScale"
    assert info["high"] < 15 and info["high"] > 14.999999
    assert info["above"] == "#d62728"
    assert info["lines"] >= 1  # the 15 % contour crosses harmonic 1's map
    assert info["labels"][0] == "error >= 15 %"
    assert "threshold contour" in info["labels"] and "chosen N" in info["labels"]
    collapsed = page.evaluate(
        "() => [...Bokeh.documents[0].all_models].filter(m => m.css_classes && "
        "m.css_classes.includes('upload-card')).map(m => m.collapsed)"
    )
    assert collapsed == [True]
    page.screenshot(path=str(ARTIFACTS / f"errormap_log_{size[0]}x{size[1]}.png"))
    ctx.close()


class _Tables(HTMLParser):
    def __init__(self):
        super().__init__()
        self.urls, self.cells, self._in = [], [], False

    def handle_starttag(self, tag, attrs):
        self.urls += [v for k, v in attrs if k in ("src", "href", "xlink:href")]
        self._in = tag == "td"

    def handle_data(self, data):
        if self._in:
            self.cells.append(data.strip())


def test_report_downloads_hold_what_the_page_shows(browser, dashboard, tmp_path):
    ctx = _context(browser, (1920, 1080))
    page = ctx.new_page()
    open_dashboard(page, dashboard.url + "?h=3&N=60&rounds=1000")
    table = table_json(page, "suggested-table")
    shown = re.findall(r'"Suggested N":\["([^\]]*)"\]', table)[0].split('","')
    with page.expect_download(timeout=120_000) as dl:
        page.locator(".report-html button, .report-html a").first.click()
    path = tmp_path / dl.value.suggested_filename
    dl.value.save_as(path)
    assert dl.value.suggested_filename.startswith("tire-fbs_h3_bushing-z_N60_6dof_")
    parsed = _Tables()
    parsed.feed(path.read_text(encoding="utf-8"))
    for u in parsed.urls:
        assert u.startswith(("#", "data:image/png")) or u.startswith(dashboard.url), u
    # the suggested-modes table of the report: harmonic, band, suggested N, eigenfrequency
    rows = [parsed.cells[i : i + 4] for i in range(len(parsed.cells)) if parsed.cells[i] == "1"]
    sugg = next(r for r in rows if r[1].endswith(" Hz") and "-" in r[1])
    i = parsed.cells.index(sugg[0], parsed.cells.index(sugg[1]) - 1)
    col = [parsed.cells[i + 4 * k + 2] for k in range(7)]
    assert col == shown
    with page.expect_download(timeout=180_000) as dl:
        page.locator(".report-pdf button, .report-pdf a").first.click()
    pdf = dl.value.path().read_bytes()
    text = "".join(p.extract_text() for p in PdfReader(io.BytesIO(pdf)).pages)
    assert "Harmonic 3: road wavelength 0.339 m, 30-120 km/h" in text
    ARTIFACTS.mkdir(exist_ok=True)
    ctx.close()


def test_shared_link_that_needs_uploads_says_so(browser, dashboard):
    ctx = _context(browser, (1280, 720))
    page = ctx.new_page()
    open_dashboard(page, dashboard.url + "?data=chassis:0123456789ab&rounds=1000")
    # the alert's text is inside the pane's shadow root: match it there
    page.locator(".link-notice", has_text="made with uploaded data").wait_for(state="visible")
    page.locator(".link-notice", has_text="chassis: chassis:0123456789ab").wait_for()
    page.screenshot(path=str(ARTIFACTS / "link_notice_1280x720.png"))
    ctx.close()
