"""User text is never markup in a report: file names with ``$...$`` (matplotlib's mathtext),
HTML tags or a backslash come out as written, in the PDF, the HTML report and a plot file.

Today's hostile names: ``$\\foo$`` is an unknown mathtext command (ValueError while the PDF
is drawn), a deep ``^{^{...}}`` nest overflows the parser's recursion, ``$x$`` would come
out as an italic x (the name changed silently). The PDF's text is extracted and compared
with the names as uploaded.
"""

from __future__ import annotations

import dataclasses
import io
import re

import pytest
import report_snapshot
from pypdf import PdfReader

from app.report import DataFile, Provenance, build_html, build_pdf
from app.report.content import report_content
from app.report.figures import render, standalone

TIRE = r"tire $\foo{x}$ v1.h5"
CHASSIS = "chassis $" + "^{" * 40 + "x" + "}" * 40 + "$ <b>bold</b> \\$ end.uff"


@pytest.fixture(scope="module")
def snap():
    s = report_snapshot.snapshot(report_snapshot.results())
    prov = Provenance(
        tire=DataFile("tire", TIRE, "aa11bb22cc33"),
        chassis=DataFile("chassis", CHASSIS, "0123abcd4567"),
    )
    return dataclasses.replace(s, provenance=prov)


def _flat(text: str) -> str:
    return re.sub(r"\s+", " ", text)


def test_hostile_file_names_come_out_as_written_in_the_pdf(snap):
    name, data = build_pdf(snap)
    text = _flat("\n".join(p.extract_text() for p in PdfReader(io.BytesIO(data)).pages))
    for n in (TIRE, CHASSIS):
        assert _flat(n) in text, n
    assert "Eq. 4.1" in text  # the method's equations are still mathtext (drawn, no "$")
    assert r"\mathbf" not in text


def test_hostile_file_names_are_text_in_the_html_report(snap):
    name, text = build_html(snap)
    assert "<b>bold</b>" not in text
    assert "&lt;b&gt;bold&lt;/b&gt;" in text
    assert r"tire $\foo{x}$ v1.h5" in text


def test_a_plot_file_with_a_hostile_name_in_its_title_renders(snap):
    rep = report_content(snap)
    blocks = [s.figure for s in rep.sections if s.figure is not None]
    assert blocks
    for b in blocks:
        b = dataclasses.replace(b, title=dataclasses.replace(b.title, lines=(CHASSIS, TIRE)))
        for fmt in ("png", "svg", "pdf"):
            assert render(standalone(b), fmt)
