"""The report's HTML file opened in chromium: nothing fetched, the numbers on screen.

Screenshots at 1280x720 and 1920x1080 are kept in tests/browser/artifacts/ (git-ignored).
"""

from __future__ import annotations

from pathlib import Path

import pytest
import report_snapshot
from playwright.sync_api import expect

from app.report import build_html

pytestmark = pytest.mark.browser

ARTIFACTS = Path(__file__).parent / "artifacts"


@pytest.fixture(scope="module")
def report_file(tmp_path_factory):
    snap = report_snapshot.snapshot(report_snapshot.results())
    name, text = build_html(snap)
    path = tmp_path_factory.mktemp("report") / name
    path.write_text(text, encoding="utf-8")
    return path, snap


@pytest.mark.parametrize("size", [(1280, 720), (1920, 1080)])
def test_report_opens_offline_and_shows_its_numbers(browser, report_file, size):
    path, snap = report_file
    context = browser.new_context(viewport={"width": size[0], "height": size[1]})
    page = context.new_page()
    requests, errors = [], []
    page.on("request", lambda r: requests.append(r.url))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(path.as_uri())
    expect(page.locator("h1")).to_contain_text("tire-fbs report: Harmonic 1, bushing:z, N = 20")
    # every plot is drawn (inline SVG with a size) with its title block
    figs = page.locator("figure")
    expect(figs).to_have_count(4)
    for i in range(4):
        box = figs.nth(i).locator("svg").bounding_box()
        assert box["width"] > 400 and box["height"] > 200
        expect(figs.nth(i).locator(".title-block")).to_contain_text("Data: ")
    table = page.locator("table", has=page.locator("caption", has_text="Suggested number of modes"))
    expect(table.locator("tbody td").nth(2)).to_have_text(str(int(snap.suggested.n_modes[0])))
    expect(page.locator("#reproduce")).to_have_attribute("href", report_snapshot.URL)
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / f"report_{size[0]}x{size[1]}.png"), full_page=False)
    assert all(u.startswith(("file:", "data:")) for u in requests), requests
    assert not errors, errors
    context.close()
