"""Bokeh figures of the views, built once per session and then updated in place.

A view builds its figure(s) once; a control change only assigns new columns to the view's
named :class:`~bokeh.models.ColumnDataSource` objects (and moves a span, a colour limit, a
label): far cheaper than re-rendering plot layers (``bench/bench_dashboard.py`` measures
the browser-side latency).

Every source carries a stable ``name`` (``"mobility.truncated"``, ``"scatter.minmax"`` ...):
the browser tests and the benchmark find the plotted data by it.

When the figures are redrawn is the business of :class:`app.views.live.LiveView`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from bokeh.models import (
    ColorBar,
    ColumnDataSource,
    DataRange1d,
    HoverTool,
    LinearColorMapper,
    Range1d,
    Span,
)
from bokeh.palettes import Inferno256
from bokeh.plotting import figure

__all__ = [
    "TOOLS",
    "add_band",
    "add_image",
    "add_line",
    "add_span",
    "fit_range",
    "frequency_range",
    "modes_range",
    "new_figure",
    "same_columns",
    "set_data",
]

TOOLS = "pan,wheel_zoom,box_zoom,reset,save"
#: Reversed inferno: small errors light, errors at or above the threshold black.
ERROR_PALETTE = tuple(reversed(Inferno256))


def frequency_range() -> Range1d:
    """A frequency axis range to share between the spectra of one session (linked zoom)."""
    return Range1d(start=0.0, end=1.0, name="frequency_range")


def modes_range() -> Range1d:
    """A retained-modes axis range to share (the error map's N axis and the eigen plot's)."""
    return Range1d(start=0.0, end=400.0, name="modes_range")


def fit_range(rng, values: np.ndarray) -> None:
    """Set a :class:`Range1d` to the extent of ``values`` (also what *reset* returns to).

    A :class:`DataRange1d` follows its data in the browser and is left alone.
    """
    if not isinstance(rng, Range1d) or np.size(values) == 0:
        return
    lo, hi = float(np.min(values)), float(np.max(values))
    if hi <= lo:
        hi = lo + 1.0
    if (rng.start, rng.end, rng.reset_start, rng.reset_end) != (lo, hi, lo, hi):
        rng.update(start=lo, end=hi, reset_start=lo, reset_end=hi)


def same_columns(old, new: dict) -> bool:
    """True when a source's data ``old`` already hold ``new`` (column ``image``: its first
    image compared)."""
    if old.keys() != new.keys():
        return False
    for k, v in new.items():
        a, b = old[k], v
        if k == "image":
            a, b = a[0], b[0]
        if np.shape(a) != np.shape(b) or not np.array_equal(a, b, equal_nan=True):
            return False
    return True


def set_data(src, data: dict) -> bool:
    """Assign ``data`` to the source ``src`` unless it holds them already (no patch sent to
    the page for a transfer that changes nothing). Whether it was assigned."""
    if same_columns(src.data, data):
        return False
    src.data = data
    return True


def new_figure(
    *,
    x_label: str,
    y_label: str,
    x_range=None,
    y_range=None,
    title: str | None = None,
    min_height: int = 320,
    name: str | None = None,
    y_axis_type: str = "linear",
):
    """A responsive figure with pan/zoom/box-zoom/reset/save, wheel zoom active."""
    fig = figure(
        y_axis_type=y_axis_type,
        x_range=x_range if x_range is not None else DataRange1d(range_padding=0.0),
        y_range=y_range
        if y_range is not None
        else DataRange1d(range_padding=0.05, only_visible=True),
        tools=TOOLS,
        active_scroll="wheel_zoom",
        toolbar_location="above",
        sizing_mode="stretch_both",
        min_height=min_height,
        title=title or "",
        name=name,
    )
    fig.xaxis.axis_label = x_label
    fig.yaxis.axis_label = y_label
    fig.grid.grid_line_alpha = 0.5
    return fig


def _legend(fig, location: str) -> None:
    if fig.legend:
        fig.legend.location = location
        fig.legend.click_policy = "hide"
        fig.legend.background_fill_alpha = 0.7
        fig.legend.label_text_font_size = "9pt"


def add_line(
    fig,
    name: str,
    *,
    color: str,
    legend: str | None,
    tooltips: Sequence[tuple[str, str]],
    x: str = "freq",
    y: str = "level",
    dash: str = "solid",
    width: float = 2.0,
    legend_location: str = "bottom_left",
    source: ColumnDataSource | None = None,
) -> ColumnDataSource:
    """A line fed by a new named source with columns ``x``, ``y`` (or by column ``y`` of
    ``source``, shared by several lines: one patch for all of them); hover along x."""
    src = (
        ColumnDataSource({x: np.zeros(0), y: np.zeros(0)}, name=name) if source is None else source
    )
    kw = {"legend_label": legend} if legend else {}
    r = fig.line(x, y, source=src, line_color=color, line_width=width, line_dash=dash, **kw)
    fig.add_tools(HoverTool(renderers=[r], tooltips=list(tooltips), mode="vline"))
    _legend(fig, legend_location)
    return src


def add_band(
    fig, name: str, *, color: str, alpha: float, legend: str, legend_location: str = "bottom_left"
) -> ColumnDataSource:
    """A filled band between ``lower`` and ``upper`` over ``freq`` (a named source)."""
    src = ColumnDataSource(
        {"freq": np.zeros(0), "lower": np.zeros(0), "upper": np.zeros(0)}, name=name
    )
    fig.varea(
        "freq",
        "lower",
        "upper",
        source=src,
        fill_color=color,
        fill_alpha=alpha,
        legend_label=legend,
    )
    _legend(fig, legend_location)
    return src


def add_image(fig, name: str, *, tooltips: Sequence[tuple[str, str]], colorbar_title: str):
    """An image glyph over a named source and a linear colour mapper with a colour bar.

    Returns ``(source, mapper, colorbar)``; the source's columns are ``image`` (a list with
    one 2-D array, row 0 at the bottom), ``x``, ``y``, ``dw``, ``dh``.
    """
    src = ColumnDataSource(
        {"image": [np.zeros((1, 1))], "x": [0.0], "y": [0.0], "dw": [1.0], "dh": [1.0]}, name=name
    )
    mapper = LinearColorMapper(palette=ERROR_PALETTE, low=0.0, high=1.0)
    r = fig.image(image="image", x="x", y="y", dw="dw", dh="dh", source=src, color_mapper=mapper)
    fig.add_tools(HoverTool(renderers=[r], tooltips=list(tooltips)))
    bar = ColorBar(color_mapper=mapper, title=colorbar_title, width=12)
    fig.add_layout(bar, "right")
    return src, mapper, bar


def add_span(
    fig,
    *,
    dimension: str,
    color: str,
    dash: str = "solid",
    width: float = 2.0,
    name: str | None = None,
) -> Span:
    """A horizontal (``dimension="width"``) or vertical (``"height"``) line at a location."""
    span = Span(
        location=0.0,
        dimension=dimension,
        line_color=color,
        line_dash=dash,
        line_width=width,
        name=name,
    )
    fig.add_layout(span)
    return span
