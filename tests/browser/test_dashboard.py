"""The dashboard in a real browser (chromium via playwright).

Plot data are read from the Bokeh document (the named ColumnDataSources), not from
screenshots. One server for the whole module; most tests share one page.
"""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core
from app import compute
from app.export import read_csv

from .conftest import (
    SOURCES,
    color_high,
    fingerprint,
    model_value,
    open_dashboard,
    set_model_value,
    source,
    table_json,
    wait_band_idle,
    wait_changed,
    wait_loaded,
)

pytestmark = pytest.mark.browser

MOBILITY = ["mobility.reference", "mobility.truncated"]
MAP = ["truncation.map"]
BAND = ["scatter.minmax", "scatter.percentile", "scatter.reference", "scatter.round"]
EIGEN = ["eigen.f_20", "eigen.f_80", "eigen.f_120"]


def _radio(page, cls, label):
    page.locator(f".{cls}").get_by_role("button", name=label, exact=True).click()


def _type(page, cls, value):
    box = page.locator(f".{cls} input").first
    box.fill(str(value))
    box.press("Enter")


# control -> (action, sources that must change, sources that must not change)
STEPS = {
    "harmonic": (
        lambda p: set_model_value(p, "ctl-case-harmonic", 2, "Slider"),
        MOBILITY + MAP + BAND,
        EIGEN,
    ),
    "n_modes": (
        lambda p: set_model_value(p, "ctl-case-n_modes", 100, "Slider"),
        ["mobility.truncated"] + BAND,
        ["mobility.reference"] + MAP + EIGEN,
    ),
    "dof": (lambda p: _radio(p, "ctl-case-dof", "x"), MOBILITY + MAP + BAND, EIGEN),
    "coupling": (lambda p: _radio(p, "ctl-case-coupling", "5dof"), MOBILITY + MAP + BAND, EIGEN),
    "map_mode": (
        lambda p: _radio(p, "ctl-truncation-map_mode", "max over 6 DOFs"),
        MAP,
        MOBILITY + BAND + EIGEN,
    ),
    "noise": (
        lambda p: _type(p, "ctl-noise-noise", 4.5),
        ["scatter.minmax", "scatter.percentile", "scatter.round"],
        MOBILITY + MAP + ["scatter.reference"] + EIGEN,
    ),
    "target": (
        lambda p: _radio(p, "ctl-noise-target", "tire"),
        ["scatter.minmax", "scatter.percentile", "scatter.round"],
        MOBILITY + MAP + ["scatter.reference"] + EIGEN,
    ),
    "frequency_dependent": (
        lambda p: p.locator(".ctl-noise-frequency_dependent input").click(),
        ["scatter.minmax", "scatter.percentile", "scatter.round"],
        MOBILITY + MAP + ["scatter.reference"] + EIGEN,
    ),
    "seed": (
        lambda p: _type(p, "ctl-noise-seed", 11),
        ["scatter.minmax", "scatter.percentile", "scatter.round"],
        MOBILITY + MAP + ["scatter.reference"] + EIGEN,
    ),
    # the same round index is the same round whatever R: only the band edges move
    "rounds": (
        lambda p: _type(p, "ctl-noise-rounds", 2000),
        ["scatter.minmax", "scatter.percentile"],
        MOBILITY + MAP + ["scatter.reference", "scatter.round"] + EIGEN,
    ),
    "single_round": (
        lambda p: _type(p, "ctl-noise-single_round", 5),
        ["scatter.round"],
        MOBILITY + MAP + ["scatter.minmax", "scatter.percentile", "scatter.reference"] + EIGEN,
    ),
    "percentile": (
        lambda p: p.locator(".ctl-noise-percentile select").select_option("50"),
        ["scatter.percentile"],
        MOBILITY + MAP + ["scatter.minmax", "scatter.reference", "scatter.round"] + EIGEN,
    ),
}


def test_page_loads_without_console_errors(shared_page, dashboard):
    page = shared_page
    assert page.errors == []
    assert dashboard.errors() == []
    assert "Tire-chassis FBS" in page.title() or "tire-fbs" in page.title()
    for name in SOURCES:
        data = source(page, name)
        assert data is not None, name
        assert all(
            np.isfinite(np.asarray(v, float)).all() for k, v in data.items() if k != "image"
        ), name


@pytest.mark.parametrize("control", list(STEPS))
def test_control_updates_exactly_the_views_that_depend_on_it(shared_page, control):
    page = shared_page
    action, changed, unchanged = STEPS[control]
    before = {n: fingerprint(page, n) for n in SOURCES}
    action(page)
    for n in changed:
        wait_changed(page, n, before[n])
    wait_band_idle(page)
    for n in unchanged:
        assert fingerprint(page, n) == before[n], f"{control} changed {n}"
    assert page.errors == []


def test_threshold_caps_the_colour_and_f_max_changes_the_table(shared_page):
    page = shared_page
    table = table_json(page, "suggested-table")
    before = {n: fingerprint(page, n) for n in SOURCES}
    _type(page, "ctl-truncation-threshold", 7)
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].some("
        "m => m.type === 'LinearColorMapper' && m.high < 7 && m.high > 7 - 1e-9)"
    )
    # the colour scale ends just below the threshold: 7 % itself is "at or above" (red)
    assert 7 - 1e-9 < color_high(page) < 7
    page.wait_for_function(f"(t) => ({_js_table()})('suggested-table') !== t", arg=table)
    table2 = table_json(page, "suggested-table")
    _type(page, "ctl-truncation-f_max", 60)
    page.wait_for_function(f"(t) => ({_js_table()})('suggested-table') !== t", arg=table2)
    for n in SOURCES:  # threshold and f_max change colours and the table, not the data
        assert fingerprint(page, n) == before[n], n


def test_uncoupled_subsystems_on_request(shared_page):
    page = shared_page
    row = page.locator(".uncoupled-row")
    assert not row.is_visible()
    page.locator(".ctl-case-show_uncoupled input").click()
    row.wait_for(state="visible")
    wait_loaded(page, ["uncoupled.tire_reference", "uncoupled.tire_truncated", "uncoupled.chassis"])
    before = {n: fingerprint(page, n) for n in ["uncoupled.chassis", "uncoupled.tire_reference"]}
    page.locator(".uncoupled-row select").select_option("x")  # spindle input
    wait_changed(page, "uncoupled.chassis", before["uncoupled.chassis"])
    assert fingerprint(page, "uncoupled.tire_reference") == before["uncoupled.tire_reference"]


def _js_table():
    from .conftest import JS_TABLE

    return JS_TABLE


URL = (
    "?h=3&N=120&dof=rx&coupling=5dof&noise=5.5&target=tire&fdep=true&rounds=800&seed=3"
    "&round=7&pct=50&thr=10&fmax=130&map=max+over+6+DOFs"
)


def test_url_restores_the_state(browser, dashboard):
    page = browser.new_page()
    open_dashboard(page, dashboard.url + URL)
    assert model_value(page, "ctl-case-harmonic", "Slider") == 3
    assert model_value(page, "ctl-case-n_modes", "Slider") == 120
    # typed numbers are text fields (app/views/typed.py)
    assert model_value(page, "ctl-noise-seed") == "3"
    assert model_value(page, "ctl-noise-rounds") == "800"
    assert model_value(page, "ctl-noise-single_round") == "7"
    # the plotted data are those of the state in the URL
    mob = source(page, "mobility.truncated")
    want = fbs_core.bushing_response(3, n_modes=120, coupling="5dof")
    np.testing.assert_allclose(mob["freq"], want.freq)
    level = 20 * np.log10(np.abs(want.sel(outputs="bushing:rx").data[:, 0, 0]))
    np.testing.assert_allclose(mob["level"], level, rtol=1e-9)
    err = compute.error_map_data(3, "5dof", None)["error_pct"]
    np.testing.assert_allclose(source(page, "truncation.map")["image"], err.ravel(), rtol=1e-12)
    band = compute.band(3, 120, "5dof", 5.5, "tire", True, 800, 3)
    d = compute.band_data(band, "rx", 50)
    pct = source(page, "scatter.percentile")
    np.testing.assert_allclose(pct["freq"], d["freq"])
    np.testing.assert_allclose(pct["upper"], d["pct_high_db"], rtol=1e-12)
    np.testing.assert_allclose(pct["lower"], d["pct_low_db"], rtol=1e-12)
    assert 10 - 1e-9 < color_high(page) < 10  # below the threshold; 10 % is red
    # a control change goes back into the URL
    set_model_value(page, "ctl-case-n_modes", 130, "Slider")
    page.wait_for_function("() => window.location.search.includes('N=130')")
    page.close()


def test_csv_downloads_match_the_plotted_data(shared_page):
    page = shared_page
    with page.expect_download() as info:
        page.locator(".download-mobility").first.click()
    meta, cols = read_csv(open(info.value.path()).read())
    assert {
        "harmonic",
        "N (retained tire modes)",
        "response DOF",
        "coupling",
        "fbs_core version",
    } <= set(meta)
    ref, tr = source(page, "mobility.reference"), source(page, "mobility.truncated")
    np.testing.assert_allclose(cols["freq_Hz"], ref["freq"])
    np.testing.assert_allclose(cols["reference_dB"], ref["level"], rtol=1e-12)
    np.testing.assert_allclose(cols["truncated_dB"], tr["level"], rtol=1e-12)

    with page.expect_download() as info:
        page.locator(".download-scatter").first.click()
    meta, cols = read_csv(open(info.value.path()).read())
    assert {"noise_pct", "noise target", "frequency dependent", "rounds", "seed"} <= set(meta)
    mm = source(page, "scatter.minmax")
    np.testing.assert_allclose(cols["freq_Hz"], mm["freq"])
    np.testing.assert_allclose(cols["maximum_dB"], mm["upper"], rtol=1e-12)
    np.testing.assert_allclose(cols["minimum_dB"], mm["lower"], rtol=1e-12)
    rnd = [k for k in cols if k.startswith("round_")]
    np.testing.assert_allclose(cols[rnd[0]], source(page, "scatter.round")["level"], rtol=1e-12)

    with page.expect_download() as info:
        page.locator(".download-truncation").first.click()
    meta, cols = read_csv(open(info.value.path()).read())
    np.testing.assert_allclose(
        cols["error_pct"], source(page, "truncation.map")["image"], rtol=1e-12
    )


def test_long_computation_in_one_session_does_not_block_another(browser, dashboard):
    a, b = browser.new_page(), browser.new_page()
    open_dashboard(a, dashboard.url + "?rounds=500")
    open_dashboard(b, dashboard.url + "?rounds=500")
    # session A starts a long scatter band ...
    _type(a, "ctl-noise-rounds", 100_000)
    a.locator(".scatter-status p", has_text="Computing").wait_for()
    # ... session B changes N and sees its plot updated while A is still computing
    before = fingerprint(b, "mobility.truncated")
    set_model_value(b, "ctl-case-n_modes", 210, "Slider")
    wait_changed(b, "mobility.truncated", before, timeout=30_000)
    assert a.locator(".scatter-status p", has_text="Computing").count() == 1
    a.close()
    b.close()
