"""Vehicle scope in a real browser (issue 31): the scope switch and a wheel toggle clicked,
the plots and the link follow, the numbers are the library's; the report of the car opened.

Truth: :func:`fbs_core.vehicle.vehicle_response` called here (an independent call of the
library, not the app's caches), against the data in the page's Bokeh document.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from playwright.sync_api import expect

import fbs_core
from app.report import build_html
from app.store import Results
from fbs_core.vehicle import vehicle_response

from .conftest import fingerprint, model_value, open_dashboard, source, wait_changed

pytestmark = pytest.mark.browser


def _click(page, cls: str, label: str) -> None:
    page.locator(f".{cls}").get_by_role("button", name=label, exact=True).click()


def _level_db(harmonic: int, n_modes: int | None, dof: str, **kw) -> np.ndarray:
    r = vehicle_response(harmonic, n_modes, fbs_core.harmonic(harmonic).frequencies(), **kw)
    return 20 * np.log10(r.level[:, list(r.outputs).index(dof)])


def test_scope_switch_and_a_wheel_toggle_change_the_plots_and_the_link(browser, dashboard):
    page = browser.new_page()
    open_dashboard(page, dashboard.url)
    expect(page.locator(".wheels-card")).to_be_hidden()
    before = fingerprint(page, "mobility.truncated")
    corner = source(page, "mobility.truncated")["level"]
    _click(page, "ctl-case-scope", "Vehicle")
    wait_changed(page, "mobility.truncated", before, timeout=180_000)
    page.wait_for_function("() => window.location.search.includes('scope=vehicle')")
    expect(page.locator(".wheels-card")).to_be_visible()
    expect(page.locator(".ctl-vehicle")).to_be_visible()
    # the car's response at the thesis' bushing on the car (rear left), all four wheels
    mob = source(page, "mobility.truncated")
    want = _level_db(1, 50, "bushing_rl:z", outputs="bushing_rl")
    np.testing.assert_allclose(mob["level"], want, rtol=1e-9)
    assert not np.allclose(mob["level"], corner)
    ref = source(page, "mobility.reference")["level"]
    np.testing.assert_allclose(ref, _level_db(1, None, "bushing_rl:z", outputs="bushing_rl"))
    # the per-wheel view: four wheels whose sum is the response
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].some(m => m.name === 'wheels.lines' "
        "&& m.data.total && m.data.total.length > 0)",
        timeout=60_000,
    )
    np.testing.assert_allclose(source(page, "wheels.lines")["total"], want, rtol=1e-9)
    # the car's default rounds (a typed field since issue 29: its value is the text shown)
    assert int(model_value(page, "ctl-noise-rounds")) == 1000
    # the front-left wheel's road off: the response without it, the link says so
    before = fingerprint(page, "mobility.truncated")
    wheels_before = fingerprint(page, "wheels.lines")
    _click(page, "ctl-case-wheels", "FL")
    wait_changed(page, "mobility.truncated", before, timeout=60_000)
    wait_changed(page, "wheels.lines", wheels_before, timeout=60_000)
    page.wait_for_function(
        "() => { const w = new URLSearchParams(window.location.search).get('wheels');"
        " return w !== null && !w.includes('fl') && w.includes('rr'); }"
    )
    want = _level_db(1, 50, "bushing_rl:z", outputs="bushing_rl", wheels=("fr", "rl", "rr"))
    np.testing.assert_allclose(source(page, "mobility.truncated")["level"], want, rtol=1e-9)
    fl = np.asarray(source(page, "wheels.lines")["fl"], float)
    assert not np.any(np.isfinite(fl) & (fl > -200)), "the FL wheel's road is off"
    # anti-phase tracks, another response point: the plot follows
    before = fingerprint(page, "mobility.truncated")
    _click(page, "ctl-case-tracks", "anti-phase")
    wait_changed(page, "mobility.truncated", before, timeout=60_000)
    want = _level_db(
        1, 50, "bushing_rl:z", outputs="bushing_rl", wheels=("fr", "rl", "rr"), tracks="anti-phase"
    )
    np.testing.assert_allclose(source(page, "mobility.truncated")["level"], want, rtol=1e-9)
    page.wait_for_function("() => window.location.search.includes('tracks=anti-phase')")
    # back to the corner: the thesis' numbers again
    before = fingerprint(page, "mobility.truncated")
    _click(page, "ctl-case-scope", "Corner")
    wait_changed(page, "mobility.truncated", before, timeout=60_000)
    np.testing.assert_array_equal(source(page, "mobility.truncated")["level"], corner)
    expect(page.locator(".wheels-card")).to_be_hidden()
    assert not dashboard.errors(), "".join(dashboard.log[-40:])
    page.close()


def test_a_link_in_vehicle_scope_opens_the_car(browser, dashboard):
    page = browser.new_page()
    link = '?scope=vehicle&wheels=["rl","rr"]&point=seat_fl&dof=y&tracks=anti-phase'
    open_dashboard(page, dashboard.url + link)
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].some(m => m.name === 'wheels.lines' "
        "&& m.data.total && m.data.total.length > 0)",
        timeout=120_000,
    )
    want = _level_db(
        1, 50, "seat_fl:y", outputs="seat_fl", wheels=("rl", "rr"), tracks="anti-phase"
    )
    np.testing.assert_allclose(source(page, "mobility.truncated")["level"], want, rtol=1e-9)
    page.close()


def test_the_report_of_the_car_opens_with_its_sections(browser, tmp_path):
    store = Results(background=False)
    case = store.state.case
    case.param.update(scope="vehicle", point="seat_fl", wheels=["fl", "fr"], harmonic=2)
    store.state.noise.rounds = 40
    store.request_band(wait=True)
    from app.report.session import report_data

    snap = report_data(store, url="http://127.0.0.1:5006/main?scope=vehicle")
    name, text = build_html(snap)
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    assert "car-wFLFR-inphase" in name
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(path.as_uri())
    expect(page.locator("h1")).to_contain_text("seat_fl:z")
    expect(page.locator("body")).to_contain_text("wheels FL FR | tracks in phase | point seat_fl")
    expect(page.locator("body")).to_contain_text(re.compile("contribution of each wheel", re.I))
    figs = page.locator("figure")
    assert figs.count() >= 5  # response, map, band, eigenfrequencies, the wheels
    for i in range(figs.count()):
        box = figs.nth(i).locator("svg").bounding_box()
        assert box["width"] > 300 and box["height"] > 150
    assert not errors, errors
    page.close()
