"""Panel pieces of app.report: report downloads, help page, data badge, link notice."""

from __future__ import annotations

import io

import report_snapshot
from pypdf import PdfReader
from server_util import run_async

from app.page.chrome import data_badge, data_key, help_page, link_notice, report_buttons
from app.report import DataFile, Provenance


def test_report_buttons_download_html_and_pdf():
    snap = report_snapshot.snapshot({})
    row = report_buttons(lambda: snap)
    html_btn, pdf_btn = row.objects
    out = html_btn.callback()
    assert html_btn.filename == "tire-fbs_h1_bushing-z_N20_6dof_upload_2026-12-01.html"
    text = out.getvalue()
    assert text.startswith("<!DOCTYPE html>") and "rear corner &lt;v2&gt;.uff" in text
    out = pdf_btn.callback()
    assert pdf_btn.filename.endswith(".pdf") and not pdf_btn.loading
    pages = PdfReader(io.BytesIO(out.getvalue())).pages
    assert "Harmonic 1: road wavelength 0.646 m" in pages[0].extract_text()


def test_help_page_is_served_markdown():
    pane = help_page()
    assert "Chalmers University of Technology, 2018" in pane.object
    assert "## How to read each view" in pane.object


def test_badge_key_and_link_notice():
    ref = Provenance()
    up = Provenance(chassis=DataFile("chassis", "car.uff", "0123456789abcdef"))
    assert data_badge(ref) == "Data: reference models"
    assert data_badge(up) == "Data: uploaded chassis 'car.uff'"
    assert data_key(ref) == "" and data_key(up) == "chassis:0123456789ab"
    # a link made with the upload, opened where the upload is missing: a notice
    msg = link_notice("chassis:0123456789ab", ref)
    assert "made with uploaded data (chassis: chassis:0123456789ab)" in msg
    assert "reference tire and chassis" in msg
    # the same upload present, or a reference link: no notice
    assert link_notice("chassis:0123456789ab", up) == ""
    assert link_notice("", up) == ""
    other = Provenance(chassis=DataFile("chassis", "car.uff", "ffff"))
    assert link_notice("chassis:0123456789ab", other) != ""


def test_served_reports_wait_on_the_loop_one_per_session_and_kind(monkeypatch):
    """Served, a report is drawn on the report thread while the click waits on the event
    loop (no Panel worker thread held); clicks while a report of the same kind is in the
    making get that report; reports are drawn one at a time (issue 28, finding 7)."""
    import asyncio
    import threading
    import time
    from types import SimpleNamespace

    import panel as pn
    from bokeh.document import Document

    from app.runtime import reports as report_panel

    doc = Document()
    ctx = SimpleNamespace(
        request=SimpleNamespace(arguments={}, cookies={}, headers={}), server_context=None
    )
    monkeypatch.setattr(type(doc), "session_context", property(lambda d: ctx))
    monkeypatch.setattr(pn.state, "curdoc", doc)
    snap = report_snapshot.snapshot({})
    calls, active, most = [], [0], [0]
    lock = threading.Lock()

    def snapshot():
        with lock:
            calls.append(threading.current_thread().name)
            active[0] += 1
            most[0] = max(most[0], active[0])
        time.sleep(0.3)
        with lock:
            active[0] -= 1
        return snap

    html_btn, pdf_btn = report_buttons(snapshot).objects
    assert asyncio.iscoroutinefunction(html_btn.callback)

    async def clicks():
        return await asyncio.gather(
            html_btn.callback(), html_btn.callback(), html_btn.callback(), pdf_btn.callback()
        )

    outs = run_async(clicks())  # a loop of its own (an earlier test may leave one running)
    assert len(calls) == 2  # one HTML report for three clicks, one PDF report
    assert all(name.startswith("fbs-report") for name in calls) and most[0] == 1
    assert outs[0].getvalue() == outs[2].getvalue() and outs[3].getvalue()[:4] == b"%PDF"
    assert report_panel.REPORT_THREADS == 1
