"""The review in vehicle scope in chromium, by clicking: the car chosen, a supplier tire
added, a target typed at a seat of the car, the verdict on the screen and the target line
on the car's plot.

Truth: the car's response computed here by the core directly
(:func:`fbs_core.vehicle.vehicle_response` with each tire on the four wheels, all modes,
every harmonic) and judged by :func:`fbs_core.verdict.verdict` against the same typed
target; the target sits 1 dB above the reference's highest level, so the reference passes
by 1 dB by construction.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import fbs_core
from fbs_core.candidates import Candidate, CandidateSet
from fbs_core.targets import Target
from fbs_core.tire import TireModel
from fbs_core.tire.storage import save_tire_model
from fbs_core.vehicle import vehicle_response
from fbs_core.verdict import verdict
from fbs_core.vocabulary import HARMONIC_CASES

from .conftest import fingerprint, open_dashboard, source, wait_changed

pytestmark = pytest.mark.browser

DOF = "seat_fl:z"


def _tire(scale: float, tag: str) -> TireModel:
    t = fbs_core.reference_tire()
    return TireModel(
        t.speeds, t.poles * scale, t.psi, t.chi, t.wavelengths, t.participation,
        meta={"source": tag},
    )  # fmt: skip


def _wait_text(page, cls: str, pattern: str, timeout: float = 300_000) -> None:
    page.locator(f".{cls}").filter(has_text=re.compile(pattern)).first.wait_for(timeout=timeout)


def test_a_target_at_a_seat_of_the_car_judged_by_clicking(browser, dashboard, tmp_path):
    tire = _tire(0.97, "x")
    path = save_tire_model(tire, tmp_path / "supplier_x.h5")
    cars = {
        (name, k): vehicle_response(
            k, None, fbs_core.harmonic(k).frequencies(), outputs="seat_fl", **kw
        )
        for name, kw in (("reference", {}), ("supplier_x.h5", {"tire": tire}))
        for k in HARMONIC_CASES
    }
    peak = max(
        20 * np.log10(r.level[:, list(r.outputs).index(DOF)].max())
        for (name, _k), r in cars.items()
        if name == "reference"
    )
    level = round(float(peak) + 1.0, 6)  # typed with six decimals: the margin is 1 dB to 1e-6
    lo = min(fbs_core.harmonic(k).frequencies()[0] for k in HARMONIC_CASES)
    hi = max(fbs_core.harmonic(k).frequencies()[-1] for k in HARMONIC_CASES)
    points = f"{lo:g}:{level:.6f}, {hi:g}:{level:.6f}"

    ctx = browser.new_context(viewport={"width": 1280, "height": 720})
    page = ctx.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    open_dashboard(page, dashboard.url)
    before = fingerprint(page, "mobility.truncated")
    page.locator(".ctl-case-scope").get_by_role("button", name="Vehicle", exact=True).click()
    wait_changed(page, "mobility.truncated", before, timeout=180_000)

    page.locator(".review-card .card-header").first.click()  # open the card
    page.locator(".review-tire input[type=file]").first.wait_for(state="attached", timeout=60_000)
    page.locator(".review-tire input[type=file]").set_input_files(str(path))
    _wait_text(page, "review-candidates", re.escape("supplier_x.h5"))
    page.locator(".review-seg-dof select").select_option(DOF)
    box = page.locator(".review-seg-points input").first
    box.click()
    box.fill(points)
    box.press("Enter")
    page.locator(".review-seg-add button").first.click()
    _wait_text(page, "review-targets", re.escape(DOF))
    _wait_text(page, "review-verdict", "Ranking")

    # the truth: the core's verdict of the car's direct responses against the typed target
    cands = CandidateSet([Candidate.reference(), Candidate("supplier_x.h5", "supplier_x.h5", tire)])
    target = Target.segments(DOF, [(lo, level), (hi, level)], axis="log")
    truth = verdict({key: r.response for key, r in cars.items()}, [target], candidates=cands)
    ref = [x for x in truth.rows if x.candidate == "reference"]
    assert len(ref) == 7 and min(x.margin_db for x in ref) == pytest.approx(1.0, abs=1e-5)
    shown = page.locator(".verdict-ranking tr").all_inner_texts()[1:]
    assert len(shown) == 2
    for s, line in zip(truth.ranking, shown, strict=True):
        cells = line.split("\t")
        assert cells[1].strip() == s.candidate and cells[2].strip() == s.status, (line, s)
        assert float(cells[3]) == pytest.approx(s.worst_db, abs=0.051), (line, s)
        assert cells[5].strip() == DOF
    page.locator(".review-verdict").filter(has_text="at the car's seat_fl").first.wait_for()

    # the car's plot at the seat draws the target line (flat at the typed level)
    page.locator(".ctl-case-point select").select_option("seat_fl")
    page.wait_for_function("() => window.location.search.includes('point=seat_fl')")
    page.wait_for_function(
        """(lv) => [...Bokeh.documents[0].all_models].some(m => m.name === 'mobility.target'
             && m.data.level && m.data.level.length > 0
             && m.data.level.some(v => Math.abs(v - lv) < 1e-6))""",
        arg=level,
        timeout=180_000,
    )
    got = np.asarray(source(page, "mobility.target")["level"], float)
    assert np.allclose(got[np.isfinite(got)], level, atol=1e-6)
    assert errors == [] and dashboard.errors() == []
    ctx.close()
