"""A measured chassis in a real browser: the knuckle geometry and the measured set uploaded,
transformed to the virtual point, coupled (the views change) and its consistency shown."""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.io.geometry import geometry_csv
from fbs_core.vpt import validation as val

from .conftest import fingerprint, open_dashboard, source, wait_band_idle, wait_changed

pytestmark = pytest.mark.browser

#: Every harmonic's analysis grid (multiples of 0.5 Hz in 13-422 Hz).
GRID = np.arange(13.0, 422.01, 0.5)


def _shows(page, cls: str, words: str, timeout=30_000):
    page.locator(f".{cls}").filter(has_text=words).first.wait_for(timeout=timeout)


def test_measured_set_and_geometry_become_the_sessions_chassis(browser, dashboard, tmp_path):
    m = val.knuckle_measurement(GRID, quantity="accelerance")
    frf_path = fc.save_frf(m.measured, tmp_path / "knuckle.h5")
    geo_path = tmp_path / "knuckle_geometry.csv"
    geo_path.write_bytes(geometry_csv(m.layout, "mm"))
    ctx = browser.new_context(viewport={"width": 1600, "height": 1400})
    page = ctx.new_page()
    page.errors = []
    page.on("pageerror", lambda e: page.errors.append(str(e)))
    open_dashboard(page, dashboard.url)
    wait_band_idle(page)
    before = fingerprint(page, "mobility.truncated")

    page.locator(".upload-geometry input[type=file]").set_input_files(str(geo_path))
    _shows(page, "upload-summary", "knuckle_geometry.csv", timeout=60_000)
    assert fingerprint(page, "mobility.truncated") == before  # a geometry alone: no change
    page.locator(".upload-chassis input[type=file]").set_input_files(str(frf_path))
    try:
        wait_changed(page, "mobility.truncated", before, timeout=180_000)
    except Exception as exc:
        raise AssertionError(
            "the views did not change after the measured set; server log:\n"
            + "".join(dashboard.log[-60:])
        ) from exc
    _shows(page, "upload-summary", "virtual point 'spindle' from 9 sensor channels")
    _shows(page, "vpt-consistency", "lowest channel", timeout=60_000)
    # the consistency plots hold one line per channel, values in [0, 1]
    for name in ("vpt.sensors.sa:x", "vpt.impacts.tc:z"):
        data = source(page, name)
        assert data is not None and len(data["c"]) == GRID.size
        assert 0.9 < min(data["c"]) <= max(data["c"]) <= 1.0 + 1e-9
    assert page.errors == []
    ctx.close()
