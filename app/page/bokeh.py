"""Bokeh side of the title blocks, the presentation style and the readable error map.

Helpers the live views call on their figures (built once, then only properties assigned):

- :class:`TitleBlockModels`: the title block as Bokeh ``Title`` models above the plot, so the
  toolbar's saved PNG carries it too, and the save tool's file name;
- :func:`style_figure`: type sizes of the normal and the presentation view and legends
  outside the data;
- :class:`ErrorMapLayers`: the threshold colour scale, the threshold contour and legend
  entries for the lines of the truncation error map.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from bokeh.models import ColorBar, ColumnDataSource, Legend, LegendItem, SaveTool, Title
from numpy.typing import ArrayLike

from ..report.colormap import LINE_STYLES, ErrorColorScale, contour_columns, threshold_contour
from ..report.titles import TitleBlock

__all__ = ["STYLES", "TitleBlockModels", "style_figure", "wrap_line", "ErrorMapLayers"]

#: Type sizes of the normal and the presentation view (the projector needs tick labels of
#: at least 14 px and legends of at least 12 pt).
STYLES: dict[str, dict[str, str]] = {
    "normal": {
        "tick": "12px",
        "axis": "13px",
        "title": "13px",
        "detail": "10px",
        "legend": "10pt",
    },
    "present": {
        "tick": "16px",
        "axis": "17px",
        "title": "18px",
        "detail": "16px",
        "legend": "13pt",
    },
}
#: Lines of a live plot's title block (heading + case, noise, data and date, link; long
#: lines wrapped at their separators, :func:`wrap_line`).
TITLE_LINES = 9
#: Characters per title-block line before it wraps: 10 px type in a half-width plot of a
#: 1280 px window, 16 px type in a half-width plot without the sidebar (the
#: presentation view's lines were cut at the plot's right edge).
WRAP = {"normal": 72, "present": 62}
#: Columns of a legend below a plot (the same widths).
LEGEND_COLUMNS = {"normal": 3, "present": 2}


def wrap_line(text: str, width: int, seps: tuple[str, ...] = (" | ", "&", " ", "~")) -> list[str]:
    """``text`` as lines of at most ``width`` characters, broken after its ``" | "``
    separators, then after the ``&`` of a link's query, then between words, then after
    the ``~`` between a pin's fields (a piece longer than ``width`` is cut).

    A piece still too long is broken at the next separators only (``seps``), so every
    step shortens the list of separators tried and the wrap ends for any text."""
    if len(text) <= width:
        return [text]
    found = [k for k, sep in enumerate(seps) if sep in text]
    if not found:
        return [text[i : i + width] for i in range(0, len(text), width)]
    sep, rest = seps[found[0]], seps[found[0] + 1 :]
    parts = text.split(sep)
    keep = sep.rstrip()  # the separator stays at the line's end
    lines: list[str] = []
    cur = parts[0]
    for part in parts[1:]:
        if len(cur) + len(sep) + len(part) <= width:
            cur = cur + sep + part
        else:
            lines.append(cur + keep)
            cur = part
    lines.append(cur)
    out: list[str] = []
    for line in lines:
        out.extend(wrap_line(line, width, rest) if len(line) > width else [line])
    return out


class TitleBlockModels:
    """A title block drawn as Bokeh ``Title`` models above a figure (saved with it).

    Built once per figure; :meth:`update` only assigns the titles' text (and the save
    tool's file name), so a change costs a few property patches.
    """

    def __init__(self, fig: Any, lines: int = TITLE_LINES) -> None:
        self.fig = fig
        # Bokeh stacks the "above" panels from the plot outwards: add the last line first
        self.titles = [
            Title(
                text="",
                text_font_size="11px",
                text_font_style="normal",
                text_color="#343a40",
                standoff=0,  # tight lines: the plot keeps its height
            )
            for _ in range(lines - 1)
        ]
        for t in reversed(self.titles):
            fig.add_layout(t, "above")
        self.heading = Title(text="", text_font_size="13px", text_font_style="bold", standoff=2)
        fig.add_layout(self.heading, "above")
        self.mode = "normal"
        self._shown: tuple[TitleBlock | None, str | None] = (None, None)
        # the figure's save tools, found once (figure.select walks the whole model graph:
        # it was the largest cost of a control change)
        self.save_tools = [t for t in fig.toolbar.tools if isinstance(t, SaveTool)]

    def update(self, tb: TitleBlock, stem: str | None = None) -> None:
        """Show ``tb``: its lines wrapped for the view's type size (:data:`WRAP`); lines
        beyond the models' count are joined into the last one."""
        self._shown = (tb, stem)
        lines = [w for line in tb.lines for w in wrap_line(line, WRAP[self.mode])]
        n = len(self.titles)
        if len(lines) > n:
            lines = lines[: n - 1] + [" | ".join(lines[n - 1 :])]
        lines += [""] * (n - len(lines))
        if self.heading.text != tb.what:
            self.heading.text = tb.what
        for t, text in zip(self.titles, lines, strict=True):
            if t.text != text:
                t.text = text
            visible = bool(text)
            if t.visible != visible:
                t.visible = visible
        if stem is not None:
            for tool in self.save_tools:
                if tool.filename != stem:
                    tool.filename = stem

    def style(self, mode: str) -> None:
        s = STYLES[mode]
        self.heading.text_font_size = s["title"]
        for t in self.titles:
            t.text_font_size = s["detail"]
        if mode != self.mode:
            self.mode = mode
            tb, stem = self._shown
            if tb is not None:  # wrapped again for the new type size
                self.update(tb, stem)


def style_figure(fig: Any, mode: str = "normal", legend_side: str = "right") -> None:
    """Type sizes of ``mode`` (``"normal"`` or ``"present"``) and legends outside the data.

    Raises
    ------
    ValueError
        For an unknown mode or side.
    """
    if mode not in STYLES:
        raise ValueError(f"unknown style {mode!r}; allowed: {', '.join(STYLES)}")
    if legend_side not in ("right", "below", "left", "above"):
        raise ValueError(f"unknown legend side {legend_side!r}; allowed: right, below")
    s = STYLES[mode]
    # on the projector the toolbar goes beside the plot: the height is the scarce direction
    toolbar = "right" if mode == "present" else "above"
    if fig.toolbar_location is not None and fig.toolbar_location != toolbar:
        fig.toolbar_location = toolbar
    for ax in (*fig.xaxis, *fig.yaxis):
        ax.major_label_text_font_size = s["tick"]
        ax.axis_label_text_font_size = s["axis"]
    fig.title.text_font_size = s["title"]
    for bar in (r for r in (*fig.right, *fig.left, *fig.below) if isinstance(r, ColorBar)):
        bar.major_label_text_font_size = s["tick"]
        bar.title_text_font_size = s["axis"]
    for leg in list(fig.legend):
        leg.label_text_font_size = s["legend"]
        if leg in fig.center:
            fig.center = [r for r in fig.center if r is not leg]
            leg.location = "top_left" if legend_side in ("right", "left") else "center"
            if legend_side in ("below", "above"):
                leg.orientation = "horizontal"
            fig.add_layout(leg, legend_side)
        if leg.orientation == "horizontal" and (leg in fig.below or leg in fig.above):
            # as many columns as fit a half-width plot in the view's type
            cols = max(1, min(len(leg.items), LEGEND_COLUMNS[mode]))
            if (leg.ncols, leg.nrows) != (cols, "auto"):
                leg.update(ncols=cols, nrows="auto")


class ErrorMapLayers:
    """Colour scale split at the threshold, threshold contour and the lines' legend.

    Parameters
    ----------
    fig : bokeh figure
        The error map's figure (its image glyph takes :attr:`mapper`).
    threshold : float
        Initial threshold in percent.
    """

    def __init__(self, fig: Any, threshold: float) -> None:
        self.scale = ErrorColorScale(float(threshold))
        self.mapper = self.scale.bokeh_mapper(name="truncation.mapper")
        self.contour = ColumnDataSource({"xs": [], "ys": []}, name="truncation.contour")
        color, dash, width, halo = LINE_STYLES["threshold contour"]
        fig.multi_line(
            "xs", "ys", source=self.contour, line_color=halo, line_width=width + 2.5
        )  # the halo under the line
        self.contour_line = fig.multi_line(
            "xs", "ys", source=self.contour, line_color=color, line_width=width, line_dash=dash
        )
        self.fig = fig

    def update(
        self, centres: ArrayLike, n_modes: ArrayLike, error_pct: ArrayLike, threshold: float
    ) -> None:
        """New threshold and map: the mapper's cap and the contour polylines."""
        thr = float(threshold)
        if thr != self.scale.threshold:
            self.scale = ErrorColorScale(thr)
        if self.mapper.high != self.scale.cap:
            self.mapper.high = self.scale.cap
        lines = threshold_contour(centres, n_modes, np.asarray(error_pct, float), thr)
        self.contour.data = contour_columns(lines)

    def legend(self, items: list[tuple[str, object]], side: str = "below") -> Legend:
        """A legend outside the map: ``(label, renderer)`` pairs, the contour first."""
        leg = Legend(
            items=[LegendItem(label=lab, renderers=[r]) for lab, r in items],
            orientation="horizontal",
            ncols=3,
            location="center",
            name="truncation.legend",
        )
        self.fig.add_layout(leg, side)
        return leg
