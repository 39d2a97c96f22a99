"""Shared colours, axis labels, hover lines and the CSV download button of the views."""

from __future__ import annotations

import html
import io
import re
from collections.abc import Callable

import panel as pn
from panel.models.markup import HTML as PanelHTML

from .. import compute
from ..export import to_csv
from .plots import Pusher

#: Colours: reference (dark), truncated (accent), uncoupled subsystems.
COLORS = {
    "reference": "#1f2937",
    "truncated": "#d9480f",
    "tire": "#1971c2",
    "chassis": "#2b8a3e",
    "band": "#4dabf7",
    "percentile": "#1864ab",
    "round": "#e8590c",
    "suggested": "#0ca678",
}

FREQ_LABEL = "Frequency (Hz)"
MODES_LABEL = "Retained modes N"


def level_label(dof: str, label: str = "Level") -> str:
    """Axis label of a bushing/hub velocity level per road amplitude for a DOF direction."""
    return f"{label} ({compute.level_unit(dof)})"


def level_tooltips(what: str, column: str = "level") -> list[tuple[str, str]]:
    """Hover lines of a level curve: what it is, frequency and level."""
    return [("", what), ("Frequency", "@freq{0.0} Hz"), ("Level", "@" + column + "{0.0} dB")]


def inline_html(text: str) -> str:
    """A caption's text as HTML: escaped, then ``**bold**`` and ``&middot;`` restored.

    Values in captions may come from users' files (DOF labels), hence the escaping.
    """
    out = html.escape(text, quote=False).replace("&amp;middot;", "&middot;")
    return re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", out)


def _encoded(text: str) -> str:
    # Panel's HTML model takes its markup escaped once more (its view decodes it)
    return html.escape(f"<p>{inline_html(text)}</p>")


def live_text(
    text: Callable[[], str],
    watch: list[tuple],
    *,
    css_classes=(),
    styles=None,
    margin=(0, 10),
    height=None,
) -> pn.pane.Bokeh:
    """A line of text showing ``text()``, rewritten when a watched parameter changes.

    ``watch`` holds ``(parameterized, [parameter names])`` pairs; ``text`` may use
    ``**bold**`` and ``&middot;``. The line is Panel's HTML Bokeh model (its browser view
    swaps the text without laying out the page again, which Bokeh's ``Div`` does) whose
    ``text`` is assigned like the plots' data (``Pusher``: one property change, in order
    across threads): a Markdown pane rewritten in the watcher chain costs the server
    several times as much per rewrite (markdown rendering, Panel's per-property
    bookkeeping), three rewrites per control change.
    """
    div = PanelHTML(
        text=_encoded(text()),
        css_classes=list(css_classes),
        styles=dict(styles or {}),
        margin=margin,
        height=height,
        sizing_mode="stretch_width",
    )
    pusher = Pusher()

    def rewrite(*_):
        def make():
            new = _encoded(text())
            return lambda: None if div.text == new else setattr(div, "text", new)

        pusher(make)

    for obj, names in watch:
        obj.param.watch(rewrite, names)
    return pn.pane.Bokeh(div, sizing_mode="stretch_width", margin=0)


def download_button(
    view: str, columns: Callable[[], dict], meta: Callable[[], dict], filename: Callable[[], str]
) -> pn.widgets.FileDownload:
    """A CSV download of the data behind a view, built when clicked."""

    def callback():
        m = {**meta(), "fbs_core version": compute.version()}
        btn.filename = filename()
        return io.StringIO(to_csv(columns(), m, view))

    btn = pn.widgets.FileDownload(
        callback=callback,
        filename=filename(),
        label="CSV",
        button_type="light",
        width=90,
        embed=False,
        css_classes=[f"download-{view}"],
    )
    return btn
