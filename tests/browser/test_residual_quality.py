"""Residual toggle (issue 15) and the tire's interpolation quality (issue 13) in a real
browser: the toggle goes into the URL, the plotted data become the residual-compensated
ones (truth: the core's own residual synthesis of that N), the table shows both columns,
and the quality badge sits next to the data source.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import fbs_core
from app import compute

from .conftest import JS_FINGERPRINT, fingerprint, open_dashboard, source, table_json, wait_changed

pytestmark = pytest.mark.browser


def test_residual_toggle_changes_url_plots_and_table(browser, dashboard):
    page = browser.new_page()
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    # the first page of a fresh server builds every truncation map: generous on a busy machine
    open_dashboard(page, dashboard.url + "?h=4&N=60&dof=x&rounds=200", timeout=900_000)
    assert "res=" not in page.evaluate("() => window.location.search")
    # the quality badge next to the data source, from the shipped tire's data
    badge = page.locator(".tire-quality-badge")
    badge.wait_for()
    assert "interpolation" in badge.inner_text()
    table = json.loads(table_json(page, "suggested-table"))
    assert "N with residuals" in table and "Suggested N" in table
    before = {n: fingerprint(page, n) for n in ("mobility.truncated", "truncation.map")}
    ref_before = fingerprint(page, "mobility.reference")

    page.locator(".ctl-case-residual input").click()
    page.wait_for_function("() => window.location.search.includes('res=true')", timeout=600_000)
    for n, fp in before.items():
        wait_changed(page, n, fp, timeout=900_000)
    f = compute.frequencies(4)
    want = fbs_core.bushing_response(4, n_modes=60, freq=f, residual=True)
    level = 20 * np.log10(np.abs(want.sel(outputs="bushing:x").data[:, 0, 0]))
    mob = source(page, "mobility.truncated")
    np.testing.assert_allclose(mob["freq"], f)
    np.testing.assert_allclose(mob["level"], level, rtol=1e-9)
    err = compute.error_map_data(4, "6dof", "x", residual=True)["error_pct"]
    np.testing.assert_allclose(source(page, "truncation.map")["image"], err.ravel(), rtol=1e-12)
    assert fingerprint(page, "mobility.reference") == ref_before  # the reference stays

    # and back: the URL drops the toggle, the plain truncation returns
    page.locator(".ctl-case-residual input").click()
    page.wait_for_function("() => !window.location.search.includes('res=true')", timeout=600_000)
    page.wait_for_function(
        f"([name, fp]) => ({JS_FINGERPRINT})(name) === fp",
        arg=["mobility.truncated", before["mobility.truncated"]],
        timeout=600_000,
    )
    assert errors == []
    page.close()
