"""Panel pieces of the report: the report downloads, the help page, the data badge and the
notice of a shared link that needs uploaded data."""

from __future__ import annotations

import io
from collections.abc import Callable
from pathlib import Path
from typing import Any

import panel as pn

from .html import build_html
from .pdf import build_pdf
from .snapshot import Provenance, Snapshot

__all__ = [
    "HELP_TEXT",
    "help_page",
    "report_buttons",
    "data_badge",
    "data_key",
    "link_notice",
]

#: The help page (method, equations, the thesis, how to read each view, units).
HELP_TEXT = (Path(__file__).with_name("help.md")).read_text(encoding="utf-8")


def help_page(**kw: Any) -> pn.pane.Markdown:
    """The help page as a Markdown pane."""
    kw.setdefault("sizing_mode", "stretch_width")
    kw.setdefault("css_classes", ["help-page"])
    return pn.pane.Markdown(HELP_TEXT, **kw)


def report_buttons(snapshot: Callable[[], Snapshot]) -> pn.Row:
    """Two downloads, the report as a self-contained HTML file and as PDF, each built from
    ``snapshot()`` when clicked (the file name says what it shows)."""

    def make(kind: str) -> pn.widgets.FileDownload:
        def callback() -> io.StringIO | io.BytesIO:
            btn.loading = True
            try:
                name, content = (build_html if kind == "html" else build_pdf)(snapshot())
            finally:
                btn.loading = False
            btn.filename = name
            if isinstance(content, str):
                return io.StringIO(content)
            return io.BytesIO(content)

        btn = pn.widgets.FileDownload(
            callback=callback,
            filename=f"tire-fbs_report.{kind}",
            label=f"Report ({kind.upper()})",
            embed=False,
            css_classes=[f"report-{kind}"],
            width=140,
        )
        return btn

    return pn.Row(make("html"), make("pdf"), css_classes=["report-buttons"])


def data_badge(provenance: Provenance) -> str:
    """Short text of the data in use for a badge on every plot."""
    if provenance.is_reference:
        return "Data: reference models"
    return "Data: " + ", ".join(f"uploaded {d.role} '{d.name}'" for d in provenance.uploads)


def data_key(provenance: Provenance) -> str:
    """The URL value naming the uploads a link needs (``""`` for the reference models):
    ``tire:<digest>`` and/or ``chassis:<digest>`` (12 characters of each), joined by ``,``."""
    return ",".join(f"{d.role}:{(d.digest or 'upload')[:12]}" for d in provenance.uploads)


def link_notice(wanted: str, provenance: Provenance) -> str:
    """The notice a page shows when its link was made with uploads this session lacks
    (``""`` when the data in use are the ones the link names)."""
    wanted = (wanted or "").strip()
    if wanted == data_key(provenance):
        return ""
    if not wanted:
        return ""  # a link of the reference models opened in a session with uploads
    roles = ", ".join(part.split(":")[0] for part in wanted.split(",") if part)
    return (
        f"This link was made with uploaded data ({roles}: {wanted}). This page shows "
        f"{provenance.describe()}: upload the same file(s) to see what the link showed."
    )
