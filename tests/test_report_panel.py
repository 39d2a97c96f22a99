"""Panel pieces of app.report: report downloads, help page, data badge, link notice."""

from __future__ import annotations

import io

import report_snapshot
from pypdf import PdfReader

from app.report import DataFile, Provenance
from app.report.panel import data_badge, data_key, help_page, link_notice, report_buttons


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
