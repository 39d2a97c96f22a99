"""Shared dimensions, plot options and helpers of the views."""

from __future__ import annotations

import io
from collections.abc import Callable

import holoviews as hv
import panel as pn

from .. import compute
from ..export import to_csv

#: Frequency axis shared by all spectra (same Dimension -> Panel links zoom and pan).
FREQ = hv.Dimension("freq", label="Frequency", unit="Hz")
#: Number of retained tire modes.
MODES = hv.Dimension("n_modes", label="Retained modes N")

#: Colours: reference (dark), truncated (accent), uncoupled subsystems.
COLORS = {
    "reference": "#1f2937",
    "truncated": "#d9480f",
    "tire": "#1971c2",
    "chassis": "#2b8a3e",
    "band": "#4dabf7",
    "percentile": "#1864ab",
    "round": "#e8590c",
}

CURVE_OPTS = dict(
    responsive=True, min_height=320, show_grid=True, tools=["hover"], line_width=2,
    active_tools=["wheel_zoom"], framewise=True,
)


def level_dim(dof: str, name: str = "level", label: str = "Level") -> hv.Dimension:
    """Level axis (dB) of a bushing/hub velocity per patch load for a DOF direction.

    Dimensions are matched by label too: give a second one on the same element (the upper
    edge of an area) its own label.
    """
    unit = compute.level_unit(dof).removeprefix("dB ")
    return hv.Dimension(name, label=label, unit=f"dB {unit}")


def level_tooltips(extra: str = "level") -> list[tuple[str, str]]:
    return [("Frequency", "@freq{0.0} Hz"), ("Level", "@{" + extra + "}{0.0} dB")]


def name_source(name: str) -> Callable:
    """HoloViews hook that names the plot's ColumnDataSource (found by the browser tests)."""

    def hook(plot, element):
        src = plot.handles.get("source")
        if src is not None and src.name != name:
            src.name = name

    return hook


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
