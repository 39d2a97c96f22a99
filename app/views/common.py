"""Shared colours, axis labels, hover lines and the CSV download button of the views."""

from __future__ import annotations

import io
from collections.abc import Callable

import panel as pn

from .. import compute
from ..export import to_csv

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


def live_text(text: Callable[[], str], watch: list[tuple], **pane_kw) -> pn.pane.Markdown:
    """A Markdown pane showing ``text()``, rewritten when a watched parameter changes.

    ``watch`` holds ``(parameterized, [parameter names])`` pairs. Only the pane's text
    changes (a bound function would re-render the pane and make the browser lay out the
    page again); an unchanged text sends nothing.
    """
    pane = pn.pane.Markdown(text(), **pane_kw)

    def rewrite(*_):
        pane.object = text()  # param sends no event for an equal value

    for obj, names in watch:
        obj.param.watch(rewrite, names)
    return pane


def download_button(view: str, columns: Callable[[], dict], meta: Callable[[], dict],
                    filename: Callable[[], str]) -> pn.widgets.FileDownload:
    """A CSV download of the data behind a view, built when clicked."""

    def callback():
        m = {**meta(), "fbs_core version": compute.version()}
        btn.filename = filename()
        return io.StringIO(to_csv(columns(), m, view))

    btn = pn.widgets.FileDownload(
        callback=callback, filename=filename(), label="CSV", button_type="light",
        width=90, embed=False,
        css_classes=[f"download-{view}"],
    )
    return btn
