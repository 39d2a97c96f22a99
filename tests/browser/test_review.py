"""The review card in chromium, by clicking: two supplier tires beside the reference, a
target file, the verdict on the screen, its CSV, a pin of each candidate and the report.

Truth: the verdict the screen shows is compared with one built here from the core directly
(``fbs_core.bushing_response`` of each tire file's model, all modes, judged by
``fbs_core.verdict.verdict``); the target is made from those direct responses with a known
margin, so the soft tire's status and margin are known by construction.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import fbs_core
from fbs_core.candidates import Candidate, CandidateSet
from fbs_core.targets import read_targets, response_level
from fbs_core.tire import TireModel
from fbs_core.tire.storage import save_tire_model
from fbs_core.verdict import verdict

from .conftest import ARTIFACTS, open_dashboard, source, wait_loaded
from .layout_util import layout_problems, wait_stable

pytestmark = pytest.mark.browser

H = 2


def _tire(scale: float, tag: str) -> TireModel:
    t = fbs_core.reference_tire()
    return TireModel(
        t.speeds, t.poles * scale, t.psi, t.chi, t.wavelengths, t.participation,
        meta={"source": tag},
    )  # fmt: skip


def _wait_text(page, cls: str, pattern: str, timeout: float = 180_000) -> None:
    page.locator(f".{cls}").filter(has_text=re.compile(pattern)).first.wait_for(timeout=timeout)


def _open_compare(page) -> None:
    """Open the Analysis card (unless it is open) and its Compare tab."""
    collapsed = page.evaluate(
        """() => [...Bokeh.documents[0].all_models].filter(m => m.css_classes
             && m.css_classes.includes('analysis-card'))[0].collapsed"""
    )
    if collapsed:
        page.locator(".analysis-card .card-header").first.click()
    page.locator(".analysis-tabs .bk-tab", has_text="Compare").first.click(timeout=180_000)


def _pin(page, name: str) -> None:
    """Pin the current state under ``name`` (the Compare tab's name field and button)."""
    box = page.locator(".ctl-analysis-pin_name input").first
    box.click(timeout=20_000)
    box.fill(name)
    box.press("Enter")
    page.wait_for_function(
        """(n) => [...Bokeh.documents[0].all_models].some(m => m.css_classes
             && m.css_classes.includes('ctl-analysis-pin_name') && m.value === n)""",
        arg=name,
    )
    page.locator(".ctl-analysis-pin button").first.click()
    page.wait_for_function("(n) => window.location.search.includes(n + '~')", arg=name)


def _check_pins(page, pins: dict) -> None:
    """The Compare tab draws each pin as the core's response of its own tire (the page's
    case: harmonic 1, N = 50, bushing:z)."""
    names = list(pins)
    page.wait_for_function(
        """(names) => { const shown = [...Bokeh.documents[0].all_models].filter(
             m => m.type === 'Legend').flatMap(l => l.items).filter(i => i.visible)
             .map(i => i.label && i.label.value);
           return names.every(n => shown.includes(n)); }""",
        arg=names,
        timeout=180_000,
    )
    labels = page.evaluate(
        """() => [...Bokeh.documents[0].all_models].filter(m => m.type === 'Figure'
             && m.name === 'compare.levels').flatMap(f => [...f.center, ...f.below]
             .filter(r => r.type === 'Legend')).flatMap(l => l.items)
             .map(i => i.label.value)"""
    )
    for name in names:  # legend item i is curve i
        kw = {} if pins[name] is None else {"tire": pins[name]}
        want = fbs_core.bushing_response(1, n_modes=50, **kw).sel(outputs="bushing:z")
        got = source(page, f"compare.curve{labels.index(name)}")
        np.testing.assert_allclose(
            got["level"], 20 * np.log10(np.abs(want.data[:, 0, 0])), atol=1e-6, err_msg=name
        )


@pytest.mark.parametrize("size", [(1280, 720), (1920, 1080)], ids=["1280x720", "1920x1080"])
def test_two_suppliers_and_the_reference_judged_by_clicking(browser, dashboard, tmp_path, size):
    tires = {"supplier_x.h5": _tire(0.97, "x"), "supplier_y.h5": _tire(1.04, "y")}
    paths = {n: save_tire_model(m, tmp_path / n) for n, m in tires.items()}
    f = fbs_core.harmonic(H).frequencies()
    direct = {n: fbs_core.bushing_response(H, tire=m) for n, m in tires.items()}
    direct["reference"] = fbs_core.bushing_response(H)
    x_level = response_level(direct["supplier_x.h5"].sel(outputs="bushing:x"))[:, 0]
    level = float(20 * np.log10(x_level.max()) + 2.0)  # supplier X passes by 2 dB
    target = tmp_path / "bushing_targets.csv"
    target.write_text(
        "# tire-fbs target\n# quantity: mobility\n# scale: dB\n"
        f"# harmonic: {H}\nfreq [Hz],bushing:x\n{float(f[0])!r},{level!r}\n"
        f"{float(f[-1])!r},{level!r}\n"
    )

    ctx = browser.new_context(viewport={"width": size[0], "height": size[1]}, accept_downloads=True)
    page = ctx.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    open_dashboard(page, dashboard.url)
    page.locator(".review-card .card-header").first.click()  # open the card
    page.locator(".review-tire input[type=file]").first.wait_for(state="attached", timeout=60_000)
    for n, p in paths.items():
        page.locator(".review-tire input[type=file]").set_input_files(str(p))
        _wait_text(page, "review-candidates", re.escape(n))
    page.locator(".review-target-file input[type=file]").set_input_files(str(target))
    _wait_text(page, "review-targets", "bushing_targets.csv")
    _wait_text(page, "review-verdict", "Ranking", timeout=300_000)

    # the truth: the core's verdict of the direct responses
    cands = CandidateSet([Candidate.reference(), *(Candidate(n, n, m) for n, m in tires.items())])
    truth = verdict(
        {(c.name, H): direct[c.name] for c in cands},
        read_targets(target),
        candidates=cands,
    )
    row_x = truth.row("supplier_x.h5", H, "bushing:x")
    assert row_x.status == "pass" and abs(row_x.margin_db - 2.0) < 1e-6  # by construction
    shown = page.locator(".verdict-ranking tr").all_inner_texts()[1:]
    assert len(shown) == 3
    for s, line in zip(truth.ranking, shown, strict=True):
        cells = line.split("\t")
        assert cells[1].strip() == s.candidate and cells[2].strip() == s.status, (line, s)
        assert float(cells[3]) == pytest.approx(s.worst_db, abs=0.051), (line, s)

    # the CSV: the verdict's rows with the same numbers
    with page.expect_download() as info:
        page.locator(".review-csv button, .review-csv a").first.click()
    text = open(info.value.path()).read()
    block = text.split("# table: verdict\n")[1].split("\n\n")[0].splitlines()
    header = block[0].split(",")
    got = {}
    for line in block[1:]:
        cells = dict(zip(header, line.split(","), strict=True))
        got[(cells["candidate"], int(cells["harmonic"]), cells["dof"])] = float(cells["worst_db"])
    for r in truth.rows:
        assert got[(r.candidate, r.harmonic, r.dof)] == pytest.approx(r.worst_db, abs=1e-6)

    # the current candidate drives the detail views: choose supplier X, then the reference
    page.locator(".review-current select").select_option("supplier_x.h5")
    page.locator(".review-candidates-table tr").filter(has_text="supplier_x.h5").filter(
        has_text="yes"  # the "current" column (text content: no separators between cells)
    ).first.wait_for(timeout=120_000)

    # a pin of each candidate, by clicking: supplier X (current now), then the reference;
    # both keep their curves (each pin names its candidate's models)
    _open_compare(page)
    wait_loaded(page, ["compare.curve0"], timeout=180_000)
    _pin(page, "supx")
    page.locator(".review-current select").select_option("reference")
    page.locator(".review-candidates-table tr").filter(has_text="reference").filter(
        has_text="yes"
    ).first.wait_for(timeout=120_000)
    _pin(page, "ref")
    _check_pins(page, {"supx": tires["supplier_x.h5"], "ref": None})

    # the report opens with the verdict
    with page.expect_download(timeout=300_000) as info:  # drawn in a process of its own
        page.locator(".report-html button, .report-html a").first.click()
    report = open(info.value.path()).read()
    assert 0 < report.index('id="verdict"') < report.index('id="summary"')
    for c in cands:
        assert f"<td>{c.name}</td>" in report

    if size == (1920, 1080):  # the link, opened in a new page, restores the review
        page.wait_for_function("() => window.location.search.includes('review=')")
        url = page.evaluate("() => window.location.href")
        other = ctx.new_page()
        other.on("pageerror", lambda e: errors.append(str(e)))
        open_dashboard(other, url)
        other.locator(".review-card .card-header").first.click()
        _wait_text(other, "review-pending-text", "add their tire files")
        _wait_text(other, "review-targets", "from the link")
        for n, p in paths.items():
            other.locator(".review-tire input[type=file]").set_input_files(str(p))
            _wait_text(other, "review-candidates", re.escape(n))
        _wait_text(other, "review-verdict", "Ranking", timeout=300_000)
        again = other.locator(".verdict-ranking tr").all_inner_texts()[1:]
        assert [x.split("\t")[1:4] for x in again] == [x.split("\t")[1:4] for x in shown]
        other.locator(".review-candidates-table tr").filter(has_text="reference").filter(
            has_text="yes"
        ).first.wait_for(timeout=60_000)  # the link's current candidate
        # the pins of both candidates are back with their curves
        _open_compare(other)  # (the link opened the card on its Compare tab already)
        _check_pins(other, {"supx": tires["supplier_x.h5"], "ref": None})
        other.close()

    wait_stable(page)
    problems = layout_problems(page, size[0])
    page.screenshot(path=str(ARTIFACTS / f"review_{size[0]}x{size[1]}.png"), full_page=False)
    assert problems == [], problems
    assert errors == [] and dashboard.errors() == []
    ctx.close()


def test_a_bad_target_file_is_refused_on_the_page_and_changes_nothing(browser, dashboard, tmp_path):
    bad = tmp_path / "targets_in_newtons.csv"
    bad.write_text("# units: N/m\nfreq [Hz],bushing:z\n10,1e-3\n100,1e-3\n")
    ctx = browser.new_context(viewport={"width": 1280, "height": 720})
    page = ctx.new_page()
    open_dashboard(page, dashboard.url)
    page.locator(".review-card .card-header").first.click()
    page.locator(".review-target-file input[type=file]").first.wait_for(
        state="attached", timeout=60_000
    )
    page.locator(".review-target-file input[type=file]").set_input_files(str(bad))
    _wait_text(page, "review-error", r"targets_in_newtons\.csv.*N/m")  # the file and the unit
    _wait_text(page, "review-targets", "No targets yet", timeout=5_000)  # nothing changed
    ctx.close()
