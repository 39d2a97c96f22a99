"""Review meetings in chromium at projector and desktop sizes (issue 17): the presentation
view and the first screen, title blocks with the data in use on every plot and saved image,
the readable error map, validation messages, the band's progress and cancel, the report
downloads, help, exports with date and link, a shared link that needs uploaded data, and a
page closed during a band. Screenshots go to tests/browser/artifacts/ (git-ignored; the
path is printed)."""

from __future__ import annotations

import io
import json
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from playwright.sync_api import expect
from pypdf import PdfReader

from app.export import read_csv
from app.page.layout import BAR_WIDTHS

from .conftest import model_value, open_dashboard, set_model_value, table_json, wait_band_idle

pytestmark = pytest.mark.browser

ARTIFACTS = Path(__file__).parent / "artifacts"
SIZES = [(1280, 720), (1920, 1080)]
#: Where layout matters: the projector sizes too.
LAYOUT_SIZES = [(1280, 720), (1366, 768), (1920, 1080)]


def _shot(page, name: str) -> None:
    ARTIFACTS.mkdir(exist_ok=True)
    path = ARTIFACTS / name
    page.screenshot(path=str(path))
    print(f"screenshot: {path}")


def _first_screen(page, size, title: str) -> None:
    """The card ``title``'s plot starts on the first screen with room for a plot."""
    box = page.get_by_text(title).first.bounding_box()
    assert box is not None and box["y"] + 250 < size[1], (title, box)


def _collapse_control_visible(page) -> None:
    """The data card's collapse control is drawn (a framed button of at least 20 px)."""
    btn = page.locator(".upload-card .card-button").first
    btn.wait_for(state="visible")
    box = btn.bounding_box()
    assert box is not None and box["width"] >= 20 and box["height"] >= 20, box
    assert btn.evaluate("b => getComputedStyle(b).borderTopStyle") == "solid"


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


@pytest.mark.parametrize("size", LAYOUT_SIZES)
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
    _first_screen(page, size, "Coupled response at the bushing")
    _collapse_control_visible(page)
    figs = _figures(page)
    assert {"truncation.figure", "scatter.figure", "eigen.figure"} <= set(figs)
    # the per-wheel card is the vehicle scope's (hidden, empty in the corner scope this page
    # opens in; tests/browser/test_vehicle.py opens it)
    figs.pop("wheels.figure", None)
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
    _shot(page, f"present_{size[0]}x{size[1]}.png")
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
    _shot(page, f"errormap_log_{size[0]}x{size[1]}.png")
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


@pytest.mark.parametrize("size", SIZES)
def test_report_downloads_hold_what_the_page_shows(browser, dashboard, tmp_path, size):
    ctx = _context(browser, size)
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
    # the report opened in the browser shows the page's numbers
    view = ctx.new_page()
    view.goto(path.as_uri())
    view.locator("h1", has_text="Harmonic 3, bushing:z, N = 60").wait_for()
    _shot(view, f"report_from_page_{size[0]}x{size[1]}.png")
    ctx.close()


@pytest.mark.parametrize("size", SIZES)
def test_shared_link_that_needs_uploads_says_so(browser, dashboard, size):
    ctx = _context(browser, size)
    page = ctx.new_page()
    open_dashboard(page, dashboard.url + "?data=chassis:0123456789ab&rounds=1000")
    # the alert's text is inside the pane's shadow root: match it there
    page.locator(".link-notice", has_text="made with uploaded data").wait_for(state="visible")
    page.locator(".link-notice", has_text="chassis: chassis:0123456789ab").wait_for()
    _shot(page, f"link_notice_{size[0]}x{size[1]}.png")
    ctx.close()


@pytest.mark.parametrize("size", LAYOUT_SIZES)
def test_normal_view_first_screen_shows_a_plot(browser, dashboard, size):
    ctx = _context(browser, size)
    page = ctx.new_page()
    open_dashboard(page, dashboard.url + "?h=5&rounds=1000")
    _first_screen(page, size, "Coupled response at the bushing")
    _collapse_control_visible(page)
    # the harmonic's wavelength, speed range and band beside its control
    page.locator(
        ".ctl-harmonic-info", has_text="Harmonic 5: road wavelength 0.166 m, 30-120 km/h, band"
    ).wait_for()
    # the quantity is chosen in the data card (files that do not say it)
    page.locator(".upload-quantity select").wait_for(state="visible")
    _shot(page, f"normal_{size[0]}x{size[1]}.png")
    ctx.close()


def _type_sizes(page) -> tuple[float, float]:
    """Computed font sizes (px) of the body and of a card title."""
    card = page.get_by_text("Coupled response at the bushing").first
    body = page.evaluate("() => parseFloat(getComputedStyle(document.body).fontSize)")
    return body, card.evaluate("e => parseFloat(getComputedStyle(e).fontSize)")


@pytest.mark.parametrize("size", SIZES)
def test_presentation_switch_changes_the_type_without_a_reload(browser, dashboard, size):
    """The page's larger type follows the view switch at once, both ways (issue 17: it
    needed a reload with ?view=present)."""
    ctx = _context(browser, size)
    page = ctx.new_page()
    frames: list = []
    page.on("websocket", lambda ws: ws.on("framereceived", lambda f: frames.append(f)))
    open_dashboard(page, dashboard.url + "?rounds=1000")
    body0, card0 = _type_sizes(page)
    page.evaluate("() => { window.__fbs_not_reloaded = true; }")
    before = len(frames)
    page.locator(".ctl-page-view button", has_text="Presentation").click()
    page.wait_for_function("() => parseFloat(getComputedStyle(document.body).fontSize) >= 17")
    body1, card1 = _type_sizes(page)
    assert body1 > body0 and card1 > card0, (body0, body1, card0, card1)
    # the plots' type follows too (restyled on the server)
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].filter(m => m.name === 'mobility.figure')"
        ".every(f => f.left.every(a => parseFloat(a.major_label_text_font_size) >= 16))"
    )
    assert page.evaluate("() => window.__fbs_not_reloaded === true")  # same page
    # the whole restyle reached the page in one message: laid out once (a message per view
    # kept the page busy for 10-15 s, laying itself out again after each one)
    restyles = [
        events
        for kind, events in _bokeh_messages(frames[before:])
        if kind == "PATCH-DOC" and any(e.get("attr", "").endswith("font_size") for e in events)
    ]
    assert len(restyles) == 1, [len(e) for e in restyles]
    # the page bar's buttons follow the view by the page's CSS (a width set from the server
    # laid the whole page out again, one change at a time)
    widths = [e for e in restyles[0] if e.get("attr") in ("width", "min_width")]
    assert not widths, widths
    assert abs(_bar_width(page, ".ctl-page-view") - BAR_WIDTHS["present"]["view"]) <= 1
    page.locator(".ctl-page-view button", has_text="Normal view").click()
    page.wait_for_function(
        f"() => parseFloat(getComputedStyle(document.body).fontSize) === {body0}"
    )
    assert _type_sizes(page) == (body0, card0)
    assert abs(_bar_width(page, ".ctl-page-view") - BAR_WIDTHS["normal"]["view"]) <= 1
    ctx.close()


def _bar_width(page, selector: str) -> float:
    """The width (px) of a page-bar element as laid out (its host element)."""
    return page.locator(selector).first.evaluate("e => e.getBoundingClientRect().width")


def _bokeh_messages(frames: list) -> list[tuple[str, list]]:
    """The Bokeh messages in websocket text frames received by the page: (message type,
    events of its content) for each (a message is a header, metadata and content frame,
    then its binary buffers)."""
    out: list[tuple[str, list]] = []
    texts = [json.loads(f) for f in frames if isinstance(f, str)]
    i = 0
    while i < len(texts):
        head = texts[i]
        if isinstance(head, dict) and "msgtype" in head and i + 2 < len(texts):
            content = texts[i + 2]
            events = content.get("events", []) if isinstance(content, dict) else []
            out.append((head["msgtype"], [e for e in events if isinstance(e, dict)]))
            i += 3
        else:
            i += 1
    return out


def _status(page, words: str, timeout=120_000):
    page.locator(".scatter-status", has_text=words).first.wait_for(timeout=timeout)


@pytest.mark.parametrize("size", SIZES)
def test_out_of_range_input_gets_a_message(browser, dashboard, size):
    ctx = _context(browser, size)
    page = ctx.new_page()
    open_dashboard(page, dashboard.url + "?rounds=1000")
    for cls, typed, words in (
        ("ctl-noise-rounds", "300000", "Rounds R: 300,000 is outside the allowed range"),
        ("ctl-noise-rounds", "0", "Rounds R: 0 is outside the allowed range"),
        ("ctl-noise-noise", "150", "Noise level p (%): 150 is outside the allowed range"),
    ):
        box = page.locator(f".{cls} input").first
        box.fill(typed)
        box.press("Enter")
        msg = page.locator(f".ctl-message-{cls[4:]}", has_text=words)
        msg.wait_for(state="visible")
        # the field shows the value in force again
        expect(box).not_to_have_value(typed)
    assert model_value(page, "ctl-noise-rounds") == "1000"
    _shot(page, f"validation_{size[0]}x{size[1]}.png")
    ctx.close()


@pytest.mark.parametrize("size", SIZES)
def test_long_band_shows_progress_time_left_and_cancels(browser, dashboard, size):
    ctx = _context(browser, size)
    page = ctx.new_page()
    open_dashboard(page, dashboard.url + "?rounds=1000")
    wait_band_idle(page)
    # idle: no progress bar drawn (an empty bar looked like a text field), cancel disabled
    assert (
        page.locator(".scatter-progress progress").first.evaluate(
            "e => getComputedStyle(e).visibility"
        )
        == "hidden"
    )
    box = page.locator(".ctl-noise-rounds input").first
    box.fill("150000")
    box.press("Enter")
    set_model_value(page, "ctl-case-harmonic", 7)
    _status(page, "frequency lines")
    page.locator(".scatter-status", has_text=" left").first.wait_for(timeout=120_000)
    # (the status text is inside the pane's shadow root: matched there, not read)
    page.locator(
        ".scatter-status",
        has_text=re.compile(r"Computing 150,000 rounds: \d+ % \(\d+ of 633 frequency lines\)"),
    ).first.wait_for()
    assert (
        page.locator(".scatter-progress progress").first.evaluate(
            "e => getComputedStyle(e).visibility"
        )
        == "visible"
    )
    # the band on screen is marked as not of the current settings
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].some(m => m.type === 'Title' && "
        'm.text.includes("[shown: the previous settings\' band, the new one is computing]"))'
    )
    _shot(page, f"band_progress_{size[0]}x{size[1]}.png")
    page.locator(".scatter-cancel button").click()
    _status(page, "Cancelled after")
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].some(m => m.type === 'Title' && "
        'm.text.includes("[shown: the previous settings\' band]"))'
    )
    assert page.locator(".scatter-cancel button").is_disabled()
    _shot(page, f"band_cancelled_{size[0]}x{size[1]}.png")
    ctx.close()


@pytest.mark.parametrize("size", SIZES)
def test_help_page_and_exports_with_date_and_link(browser, dashboard, size, tmp_path):
    ctx = _context(browser, size)
    page = ctx.new_page()
    open_dashboard(page, dashboard.url + "?h=2&N=80&rounds=1000")
    page.locator(".help-button button").click()
    help_ = page.locator(".help-page")
    help_.get_by_text("Assembly of a tire and a vehicle model").first.wait_for(state="visible")
    for words in ("Chalmers University of Technology", "How to read each view", "eq. 4.1"):
        help_.get_by_text(words).first.wait_for(state="attached")
    _shot(page, f"help_{size[0]}x{size[1]}.png")
    page.locator(".help-close button").click()
    help_.first.wait_for(state="hidden")
    page.locator(".modal-backdrop").first.wait_for(state="detached")
    with page.expect_download() as dl:
        page.locator(".download-mobility").first.click()
    meta, cols = read_csv(dl.value.path().read_text())
    assert re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d UTC", meta["exported"])
    url = meta["page URL"]
    assert url.startswith(dashboard.url) and "h=2" in url and "N=80" in url
    # the export's link reproduces what it holds
    other = ctx.new_page()
    open_dashboard(other, url)
    shown = other.evaluate(
        "() => Array.from([...Bokeh.documents[0].all_models].filter(m => "
        "m.name === 'mobility.truncated')[0].data.level)"
    )
    np.testing.assert_allclose(shown, cols["truncated_dB"], rtol=1e-12, atol=1e-9)
    ctx.close()


def test_a_page_closed_during_a_band_logs_no_error(browser, dashboard):
    ctx = _context(browser, (1280, 720))
    page = ctx.new_page()
    open_dashboard(page, dashboard.url + "?rounds=1000")
    start = len(dashboard.log)
    box = page.locator(".ctl-noise-rounds input").first
    box.fill("120000")
    box.press("Enter")
    _status(page, "Computing 120,000 rounds")
    page.close()  # the session ends while its band computes
    # a new page loads and gets its band: the closed page's band has stopped or finished
    other = ctx.new_page()
    open_dashboard(other, dashboard.url + "?rounds=1000&seed=5")
    wait_band_idle(other)
    log = "".join(dashboard.log[start:])
    assert "IndexError" not in log, log
    assert "/app/" not in log, log  # no traceback through the app's code
    ctx.close()
