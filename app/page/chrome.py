"""The page's chrome: the report downloads, the help page, the busy indicator, the data
badge and the notice of a shared link that needs uploaded data (the reports themselves:
:mod:`app.report`)."""

from __future__ import annotations

import asyncio
import html
import io
from collections.abc import Callable
from pathlib import Path
from typing import Any

import panel as pn

from ..report import Provenance, ReportData
from ..runtime import reports
from ..runtime.activity import ACTIVITIES
from ..runtime.draw import on_document, served_document
from ..runtime.panel_private import html_model, html_text

__all__ = [
    "HELP_TEXT",
    "busy_indicator",
    "help_page",
    "report_buttons",
    "data_badge",
    "data_key",
    "link_notice",
    "link_notice_html",
]

#: Characters of a link's value a notice repeats at most (the rest: "...").
NOTICE_VALUE_CHARS = 120

#: The help page (method, equations, the thesis, how to read each view, units).
HELP_TEXT = (Path(__file__).with_name("help.md")).read_text(encoding="utf-8")


def help_page(**kw: Any) -> pn.pane.Markdown:
    """The help page as a Markdown pane."""
    kw.setdefault("sizing_mode", "stretch_width")
    kw.setdefault("css_classes", ["help-page"])
    return pn.pane.Markdown(HELP_TEXT, **kw)


#: The busy indicator's spinner (its own style: the pane's shadow root has no Bootstrap).
_SPINNER = (
    "<style>@keyframes fbs-spin{to{transform:rotate(360deg)}}</style>"
    '<span aria-hidden="true" style="display:inline-block;width:0.9em;height:0.9em;'
    "border:2px solid currentColor;border-right-color:transparent;border-radius:50%;"
    'animation:fbs-spin 0.8s linear infinite;vertical-align:-0.1em;margin-right:6px"></span>'
)


def busy_html(text: str) -> str:
    """The indicator's HTML for ``text`` (escaped: never markup)."""
    if not text:
        return ""
    return f'<div role="status" aria-live="polite">{_SPINNER}{html.escape(text)} ...</div>'


class BusyIndicator:
    """What the session is busy with while long work runs (``results.working``, written
    by :mod:`app.runtime.activity`): a spinner and e.g. "Computing the coupled response of
    the whole car (12 s)"; hidden otherwise.

    Its text changes every second while work runs, so it is set in place on Panel's HTML
    model (one small patch; a ``pn.pane.HTML`` given a new object re-sends its stylesheets
    as new models each time: :mod:`app.runtime.panel_private`).
    """

    def __init__(self, results: Any) -> None:
        self._doc = served_document()
        self._results = results
        self.object = busy_html(results.working)
        self.model = html_model(
            self.object,
            visible=bool(self.object),
            css_classes=["busy-indicator"],
            margin=(8, 10),
            styles={"color": "#664d03", "font-weight": "600"},
            sizing_mode="stretch_width",
        )
        self._pane = pn.pane.Bokeh(self.model, sizing_mode="stretch_width")
        results.param.watch(self._show, "working")

    @property
    def visible(self) -> bool:
        """Whether the indicator is shown."""
        return bool(self.model.visible)

    def _show(self, *_: Any) -> None:
        text = busy_html(self._results.working)

        def draw() -> None:
            self.object = text
            self.model.update(text=html_text(text), visible=bool(text))

        on_document(self._doc, draw)

    def __panel__(self) -> pn.pane.Bokeh:
        return self._pane


def busy_indicator(results: Any) -> BusyIndicator:
    """The session's busy indicator (:class:`BusyIndicator`)."""
    return BusyIndicator(results)


def report_buttons(report: Callable[[], ReportData], owner: Any = None) -> pn.Row:
    """Two downloads, the report as a self-contained HTML file and as PDF, each built from
    ``report()`` when clicked (the file name says what it shows).

    When served, a report is drawn on the report thread (:mod:`app.runtime.reports`) while the
    click waits on the session's event loop; a session has at most one report of each
    kind in the making (a second click gets the same file). While it is made, ``owner``'s
    busy indicator says so (:func:`busy_indicator`).
    """
    doc = pn.state.curdoc
    served = doc is not None and doc.session_context is not None

    def make(kind: str) -> pn.widgets.FileDownload:
        def build() -> tuple[str, str | bytes]:
            return reports.draw(kind, report())

        def deliver(name: str, content: str | bytes) -> io.StringIO | io.BytesIO:
            btn.filename = name
            if isinstance(content, str):
                return io.StringIO(content)
            return io.BytesIO(content)

        def callback() -> io.StringIO | io.BytesIO:
            btn.loading = True
            try:
                name, content = build()
            finally:
                btn.loading = False
            return deliver(name, content)

        making: list[
            asyncio.Future[tuple[str, str | bytes]]
        ] = []  # this session's report of this kind in the making

        async def served_callback() -> io.StringIO | io.BytesIO:
            if not making or making[0].done():
                doc = pn.state.curdoc

                def in_session() -> tuple[str, str | bytes]:
                    pn.state.curdoc = doc  # report() reads the session's page URL
                    try:
                        data = report()
                    finally:
                        pn.state.curdoc = None
                    return reports.draw_apart(kind, data)

                # cancelled when the tab closes before its turn: report() would then run
                # on a page whose names Bokeh has cleared (NameError)
                making[:] = [reports.submit_for_session(doc, in_session)]
            btn.loading = True
            token = ACTIVITIES.begin(owner, f"Making the {kind.upper()} report")
            try:
                name, content = await asyncio.shield(making[0])
            finally:
                ACTIVITIES.end(token)
                btn.loading = False
            return deliver(name, content)

        btn = pn.widgets.FileDownload(
            callback=served_callback if served else callback,
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
    if len(wanted) > NOTICE_VALUE_CHARS:
        wanted = wanted[:NOTICE_VALUE_CHARS] + "..."
    roles = ", ".join(part.split(":")[0] for part in wanted.split(",") if part)
    return (
        f"This link was made with uploaded data ({roles}: {wanted}). This page shows "
        f"{provenance.describe()}: upload the same file(s) to see what the link showed."
    )


def link_notice_html(text: str) -> str:
    """The notice's text as HTML: escaped, never markup (it repeats a value of the link, so
    a crafted link must not put an element or a link into the page)."""
    return f'<div class="alert alert-warning" role="alert">{html.escape(text)}</div>'
