"""The report as a PDF, drawn server-side with matplotlib's PDF backend (no browser).

The same content as the HTML file (:func:`app.report.content.report_content`) flowed onto A4
pages: headings, title blocks, plots, tables in a monospaced font, the method and its
equations (matplotlib mathtext). Fonts are embedded as TrueType, so the text extracts.
"""

from __future__ import annotations

import io
import textwrap
from typing import Any

from matplotlib.backends.backend_pdf import PdfPages
from matplotlib.figure import Figure

from . import figures
from .content import FigureBlock, Report, Table, report_content
from .data import ReportData
from .method import UNITS, Equation
from .titles import TitleBlock

__all__ = ["build_pdf", "render_pdf"]

PAGE = (8.27, 11.69)  # A4 portrait, inches
MARGIN = 0.6
_LINE = 1.4 / 72  # inches per pt of font size


class _Pages:
    """A cursor that writes blocks top-down and starts a new page when one is full."""

    def __init__(self, pdf: PdfPages, footer: str):
        self.pdf, self.footer = pdf, footer
        self.fig: Figure | None = None
        self.y = 0.0  # inches from the top
        self.page = 0

    @property
    def width(self) -> float:
        return PAGE[0] - 2 * MARGIN

    def _new(self) -> Figure:
        self.flush()
        self.fig = Figure(figsize=PAGE)
        self.page += 1
        self.y = MARGIN
        self.fig.text(
            MARGIN / PAGE[0], 0.35 / PAGE[1], f"{self.footer} | page {self.page}", fontsize=7,
            color="#868e96",
        )  # fmt: skip
        return self.fig

    def page_break(self) -> None:
        self._new()

    def flush(self) -> None:
        if self.fig is not None:
            self.pdf.savefig(figures.literal_text(self.fig), dpi=150)
            self.fig = None

    def need(self, h: float) -> Figure:
        """The current page, a new one when ``h`` inches do not fit on it."""
        if self.fig is None or self.y + h > PAGE[1] - MARGIN:
            return self._new()
        return self.fig

    def text(self, s: str, size: float = 9.0, **kw: Any) -> None:
        h = size * _LINE
        fig = self.need(h)
        self.y += h
        fig.text(MARGIN / PAGE[0], 1 - self.y / PAGE[1], s, fontsize=size, **kw)

    def para(self, s: str, size: float = 9.0, **kw: Any) -> None:
        width = int(self.width * 72 / (size * 0.55))
        for line in textwrap.wrap(s, width) or [""]:
            self.text(line, size, **kw)
        self.y += size * 0.4 / 72

    def heading(self, s: str, size: float = 13.0) -> None:
        self.need(size * _LINE * 4)  # keep a heading with what follows
        self.y += 0.12
        self.text(s, size, weight="bold")
        self.y += 0.04

    def table(self, t: Table, size: float = 8.0, wrap: bool = False) -> None:
        """A table in a monospaced font; ``wrap``: the last column wrapped to the page."""
        cols = len(t.header)
        widths = [max(len(r[i]) for r in (t.header, *t.rows)) for i in range(cols)]
        chars = int(self.width * 72 / (size * 0.6))  # DejaVu Sans Mono: 0.6 em a glyph
        last = max(12, chars - sum(widths[:-1]) - 2 * (cols - 1))
        if wrap:
            widths[-1] = min(widths[-1], last)
        fmt = "  ".join(f"{{:<{w}}}" for w in widths)
        self.need(size * _LINE * min(4, len(t.rows) + 2))
        self.text(t.caption, size + 0.5, weight="bold")
        self.text(fmt.format(*t.header), size, family="DejaVu Sans Mono", weight="bold")
        for r in t.rows:
            parts = textwrap.wrap(r[-1], widths[-1]) if wrap else [r[-1]]
            for k, part in enumerate(parts or [""]):
                cells = (*r[:-1], part) if k == 0 else ("",) * (cols - 1) + (part,)
                self.text(fmt.format(*cells).rstrip(), size, family="DejaVu Sans Mono")
        self.y += 0.12

    def title_block(self, tb: TitleBlock) -> None:
        self.text(tb.what, 10.0, weight="bold")
        for line in tb.lines:
            for part in textwrap.wrap(line, 118) or [""]:
                self.text(part, 8.0, color="#343a40")
        self.y += 0.05

    def figure(self, block: FigureBlock) -> None:
        w = self.width
        h = w * block.aspect
        self.need(h + 1.2)
        self.title_block(block.title)
        fig = self.need(h)
        rect = (MARGIN / PAGE[0], 1 - (self.y + h) / PAGE[1], w / PAGE[0], h / PAGE[1])
        block.draw(fig, rect)
        self.y += h + 0.1

    def equation(self, eq: Equation) -> None:
        self.need(0.9)
        self.text(f"Eq. {eq.number}: {eq.name}", 9.0, weight="bold")
        self.y += 0.05
        self.text(eq.mathtext, 10.5, gid=figures.MATH_GID)
        self.y += 0.06
        self.para(eq.meaning, 8.5)


def render_pdf(rep: Report) -> bytes:
    """PDF bytes of formatted report content."""
    buf = io.BytesIO()
    with (
        figures._RENDER_LOCK,
        figures.drawing_settings(),
        PdfPages(buf, metadata={"Title": rep.title, "Creator": "tire-fbs"}) as pdf,
    ):
        pages = _Pages(pdf, rep.stem)
        pages.text(rep.title, 15.0, weight="bold")
        pages.y += 0.05
        pages.title_block(rep.title_block)
        if rep.url:
            pages.para(f"Reproduce this page: {rep.url}", 8.5)
        pages.para(rep.reproduce_note, 8.5, color="#862e9c")
        if rep.verdict is not None:  # the review's question on the first page
            v = rep.verdict
            pages.heading(v.heading)
            for p in v.paragraphs:
                pages.para(p, 9.0)
            for t in (*v.tables, *v.long_tables):
                pages.table(t)
            pages.page_break()
        sm = rep.summary
        pages.heading("Summary")
        pages.table(Table("The case in numbers", ("quantity", "value"), sm.rows), wrap=True)
        if sm.peak_rows:
            pages.table(Table(sm.peak_caption, sm.peak_header, sm.peak_rows))
        for sec in rep.sections:
            if sec.figure is not None:
                pages.page_break()  # a plot's section starts on a new page
            pages.heading(sec.heading)
            for p in sec.paragraphs:
                pages.para(p, 9.0)
            if sec.title is not None:
                pages.title_block(sec.title)
            if sec.figure is not None:
                pages.figure(sec.figure)
            for t in sec.tables:
                pages.table(t)
        pages.page_break()  # the long tables last
        pages.heading("Tables")
        for sec in rep.sections:
            for t in sec.long_tables:
                pages.table(t)
        pages.heading("Data in use")
        pages.table(rep.provenance)
        pages.heading("Settings")
        pages.table(rep.settings)
        pages.heading("Method")
        for p in rep.method:
            pages.para(p)
        for eq in rep.equations:
            pages.equation(eq)
        for u in UNITS:
            pages.para(u)
        pages.para(f"Reference: {rep.thesis}.", 9.0, style="italic")
        pages.flush()
    return buf.getvalue()


def build_pdf(snap: ReportData) -> tuple[str, bytes]:
    """``(file name, PDF bytes)`` of the report of a snapshot."""
    rep = report_content(snap)
    return f"{rep.stem}.pdf", render_pdf(rep)
