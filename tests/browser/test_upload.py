"""Uploading a chassis FRF in a real browser: the file input, the error and summary alerts,
the views of this session only (read from the Bokeh document)."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

from fbs_core.io import load_frf, save_frf

from .conftest import (
    JS_FINGERPRINT,
    fingerprint,
    open_dashboard,
    wait_band_idle,
    wait_changed,
)

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parents[2]
VIEWS = ["mobility.reference", "mobility.truncated", "truncation.map", "scatter.reference"]


def _shows(page, cls: str, words: str, timeout=30_000):
    """Wait until the element with class ``cls`` shows ``words`` (shadow DOM pierced)."""
    page.locator(f".{cls}").filter(has_text=words).first.wait_for(timeout=timeout)


def test_upload_changes_the_views_of_this_session_only(browser, dashboard, tmp_path):
    shipped = ROOT / "data" / "reference_chassis.h5"
    digest = hashlib.sha256(shipped.read_bytes()).hexdigest()
    Y = load_frf(shipped).frf  # the shipped chassis FRF, 1 Hz lines
    path = save_frf(Y.replace(data=2.0 * Y.data), tmp_path / "reference_chassis.mat")
    pages = []
    for _ in range(2):
        ctx = browser.new_context(viewport={"width": 1600, "height": 1400})
        page = ctx.new_page()
        page.errors = []
        page.on("pageerror", lambda e, p=page: p.errors.append(str(e)))
        open_dashboard(page, dashboard.url)
        wait_band_idle(page)
        pages.append(page)
    a, b = pages
    before = {n: fingerprint(a, n) for n in VIEWS}
    other = {n: fingerprint(b, n) for n in VIEWS}

    a.locator(".upload-chassis input[type=file]").set_input_files(str(path))
    # 1 Hz lines, the analysis grids have 0.5 Hz lines: refused until interpolation is chosen
    _shows(a, "upload-error", "interpolate", timeout=60_000)
    assert {n: fingerprint(a, n) for n in VIEWS} == before
    a.locator(".upload-interpolate input").check()
    a.locator(".upload-reread button").click()
    for n in VIEWS:
        try:
            wait_changed(a, n, before[n], timeout=120_000)
        except Exception as exc:  # say which view, with the server's side of the story
            raise AssertionError(
                f"{n} did not change after the upload; server log:\n" + "".join(dashboard.log[-60:])
            ) from exc
    for words in (
        "uploaded chassis 'reference_chassis.mat'",
        "bushing:rz",
        "1 to 600 Hz",
        "interpolated onto the analysis grids",
    ):
        _shows(a, "upload-summary", words)
    wait_band_idle(b)
    assert {n: fingerprint(b, n) for n in VIEWS} == other  # the other session: unchanged

    a.locator(".upload-reset button").click()
    # back to the reference data (a replaced source may list its columns in another order)
    for n in VIEWS:
        a.wait_for_function(
            f"""([n, fp]) => {{
                  const now = ({JS_FINGERPRINT})(n);
                  const cols = s => s.split(';').filter(x => x).sort().join(';');
                  return now !== null && cols(now) === cols(fp);
                }}""",
            arg=[n, before[n]],
            timeout=60_000,
        )
    assert a.errors == [] and b.errors == []
    assert hashlib.sha256(shipped.read_bytes()).hexdigest() == digest
    for p in pages:
        p.context.close()


def test_a_file_above_bokehs_default_message_limit_gets_a_clear_answer(
    browser, dashboard, tmp_path
):
    """22 MB of bytes that are no MAT-file: base64-encoded, the upload is a 29 MB websocket
    message, above Bokeh's default limit (20 MB), which would close the connection and
    leave the page without an answer. With the served limit it reaches the server and is
    refused with the reason; the page keeps working."""
    path = tmp_path / "huge.mat"
    path.write_bytes(np.random.default_rng(0).bytes(22 * 1024 * 1024))
    ctx = browser.new_context(viewport={"width": 1600, "height": 1400})
    page = ctx.new_page()
    page.errors = []
    page.on("pageerror", lambda e: page.errors.append(str(e)))
    open_dashboard(page, dashboard.url)
    before = fingerprint(page, "mobility.reference")
    page.locator(".upload-chassis input[type=file]").set_input_files(str(path))
    _shows(page, "upload-error", "huge.mat", timeout=120_000)
    assert fingerprint(page, "mobility.reference") == before  # nothing changed
    assert page.errors == []
    ctx.close()
