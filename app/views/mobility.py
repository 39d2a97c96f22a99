"""Coupled mobility at the bushing: all-modes reference and truncated curve (figs. 4.8-4.9).

With a review (app/review.py), the other tire candidates' responses (all modes, one colour
per candidate) and the target of the shown DOF and harmonic are drawn over them.

On request also the uncoupled subsystems: the tire's free hub velocity (figs. 4.6-4.7) and the
chassis' spindle-to-bushing mobility (figs. 4.2-4.3).
"""

from __future__ import annotations

import html

import numpy as np
import panel as pn
import param
from bokeh.core.property.vectorization import value
from bokeh.events import Tap
from bokeh.models import ColumnDataSource, HoverTool, Label, LegendItem, Span

from fbs_core.candidates import MAX_CANDIDATES
from fbs_core.vocabulary import DIRECTIONS

from ..results.base import made_of_same
from ..store import CASE
from .analysis_base import TERM_COLORS
from .common import (
    CANDIDATE_COLORS,
    COLORS,
    FREQ_LABEL,
    TARGET_COLOR,
    level_label,
    level_tooltips,
    tap_cursor,
)
from .layout import font
from .live import LiveText, LiveView
from .plots import add_line, frequency_range, new_figure

#: The cursors' colour (the phase view's) and line styles.
CURSOR_COLOR = "#5f3dc4"
CURSOR_DASH = ("solid", "dashed")
#: Height (px) of a line of the cursors' readout in the normal and the presentation view.
READOUT_LINE_PX = {"normal": 24, "present": 30}
#: Type of the cursors' labels in the normal and the presentation view.
CURSOR_LABEL_SIZES = {"normal": "12px", "present": "16px"}


class MobilityView(LiveView):
    """Coupled bushing response v_e* versus frequency (thesis eq. 4.1), as a test lab's FRF
    display: further DOFs overlaid, a dB or linear level axis and two labelled cursors
    with a readout (the published ``response_plot``, :mod:`app.results.response_plot`)."""

    key = "mobility"
    result_name = "response"
    also = ("response_plot", "review_curves")
    x_range = param.Parameter(
        default=None,
        doc="Frequency range shared with other views (linked zoom and pan); a new one if None.",
    )

    def __init__(self, **params):
        super().__init__(**params)
        self._next_cursor = 1
        self._readout = LiveText(css_classes=["mobility-readout"])

    def _extra(self):
        return [self._readout]

    def _build(self):
        if self.x_range is None:
            self.x_range = frequency_range()
        self._fig = fig = new_figure(
            x_label=FREQ_LABEL,
            y_label=level_label("z"),
            x_range=self.x_range,
            name="mobility.figure",
        )
        self._ref = add_line(
            fig,
            "mobility.reference",
            color=COLORS["reference"],
            legend="all tire modes",
            tooltips=level_tooltips("all modes"),
        )
        self._tr = add_line(
            fig,
            "mobility.truncated",
            color=COLORS["truncated"],
            legend="N retained modes",
            dash="dashed",
            tooltips=level_tooltips("N retained modes"),
        )
        # the lines of the DOFs overlaid are made when first overlaid (six lines made up
        # front were 66 of the first screen's ~400 models); their legend entries
        # and hover tools are here from the start, empty and hidden: a tool added later
        # lays the toolbar out again, and BokehJS then left the legend outside the canvas
        self._over: dict[str, ColumnDataSource] = {}
        self._over_items = {
            d: LegendItem(label=value(f"bushing:{d}"), renderers=[], visible=False)
            for d in DIRECTIONS
        }
        fig.legend[0].items = [*fig.legend[0].items, *self._over_items.values()]
        self._over_tools = {
            d: HoverTool(renderers=[], tooltips=level_tooltips(f"bushing:{d}"), mode="vline")
            for d in DIRECTIONS
        }
        fig.add_tools(*self._over_tools.values())
        # the review's candidates (a line per colour slot) and the target: lines made on
        # first use, their legend entries and one hover tool here from the start (as above)
        self._cand: dict[int, ColumnDataSource] = {}
        self._cand_items = [
            LegendItem(label=value(f"candidate {k + 1}"), renderers=[], visible=False)
            for k in range(MAX_CANDIDATES)
        ]
        self._target_item = LegendItem(label=value("target"), renderers=[], visible=False)
        fig.legend[0].items = [*fig.legend[0].items, *self._cand_items, self._target_item]
        self._cand_tool = HoverTool(
            renderers=[], tooltips=level_tooltips("@name", "level"), mode="vline"
        )
        fig.add_tools(self._cand_tool)
        self._cursor_spans = [
            Span(
                location=0,
                dimension="height",
                line_color=CURSOR_COLOR,
                line_width=1.5,
                line_dash=dash,
                visible=False,
                name=f"mobility.cursor{k + 1}",
            )
            for k, dash in enumerate(CURSOR_DASH)
        ]
        self._cursor_labels = [
            Label(
                x=0,
                y=4,
                y_units="screen",
                x_offset=4,
                text=f"f{k + 1}",
                text_color=CURSOR_COLOR,
                text_font_size=CURSOR_LABEL_SIZES["normal"],
                text_font_style="bold",
                background_fill_color="white",
                background_fill_alpha=0.8,
                visible=False,
                name=f"mobility.cursor_label{k + 1}",
            )
            for k in range(2)
        ]
        for m in (*self._cursor_spans, *self._cursor_labels):
            fig.add_layout(m)
        self._cursor_points = ColumnDataSource({"freq": [], "level": []}, name="mobility.cursors")
        fig.scatter("freq", "level", source=self._cursor_points, size=9, color=CURSOR_COLOR)
        fig.on_event(Tap, self._tapped)
        self._scale = "dB"
        return [fig]

    def _tapped(self, event):
        """A click on the plot places cursor 1, the next one cursor 2, and so on."""
        self._next_cursor = tap_cursor(self.store.state.plot, event.x, self._next_cursor)

    def _restyle_now(self) -> None:
        super()._restyle_now()
        for lb in self._cursor_labels:
            lb.text_font_size = CURSOR_LABEL_SIZES[self.mode]
        self._readout.model.styles = {"font-size": font("0.9em")}

    def _legend_items(self):
        return self._fig.legend[0].items if self._fig.legend else []

    def _overlay(self, dof: str) -> ColumnDataSource:
        """The source of ``dof``'s overlaid line, the line made on first use (Okabe-Ito
        colours) and given to its legend entry and hover tool."""
        src = self._over.get(dof)
        if src is not None:
            return src
        src = self._over[dof] = ColumnDataSource(
            {"freq": np.zeros(0), "level": np.zeros(0)}, name=f"mobility.overlay_{dof}"
        )
        line = self._fig.line(
            "freq",
            "level",
            source=src,
            line_color=TERM_COLORS[DIRECTIONS.index(dof)],
            line_width=2.0,
            visible=False,  # shown with its legend entry (_set_overlays)
        )
        self._over_items[dof].renderers = [line]
        self._over_tools[dof].renderers = [line]
        return src

    def _review_line(self, slot: int | None) -> ColumnDataSource:
        """The source of a candidate's line (``slot``) or of the target's (None), the line
        made on first use."""
        key = -1 if slot is None else slot
        src = self._cand.get(key)
        if src is not None:
            return src
        name = "mobility.target" if slot is None else f"mobility.candidate{slot}"
        src = self._cand[key] = ColumnDataSource(
            {"freq": np.zeros(0), "level": np.zeros(0), "name": []}, name=name
        )
        line = self._fig.line(
            "freq",
            "level",
            source=src,
            line_color=TARGET_COLOR if slot is None else CANDIDATE_COLORS[slot],
            line_width=2.6 if slot is None else 1.8,
            line_dash="dotdash" if slot is None else "solid",
            visible=False,
        )
        item = self._target_item if slot is None else self._cand_items[slot]
        item.renderers = [line]
        self._cand_tool.renderers = [*self._cand_tool.renderers, line]
        return src

    def _draw_review(self, r, scale: str) -> None:
        """The other candidates and the target, when they are of the case ``r`` shows and
        in the level scale drawn (``scale``)."""
        rc = self.store.review_curves
        fields: tuple[str, ...] = ("harmonic", "dof", "coupling", "models", "scope")
        if r.snapshot is not None and r.snapshot.vehicle:  # the car's road and point too
            fields += ("point", "wheels", "tracks", "coherence")
        ok = (
            rc is not None
            and made_of_same(rc, r, fields)
            and rc.snapshot is not None
            and (rc.snapshot.level_scale == "dB") == (scale == "dB")
        )
        d = rc.draw if ok and rc is not None else {"curves": [], "target": None}
        shown = set()
        for cv in d["curves"]:
            n = len(cv["y"])
            self._review_line(cv["slot"]).data = {
                "freq": cv["freq"],
                "level": cv["y"],
                "name": [cv["name"]] * n,
            }
            self._cand_items[cv["slot"]].label = value(f"{cv['name']} (all modes)")
            shown.add(cv["slot"])
        if d["target"] is not None:
            y = d["target"]
            self._review_line(None).data = {
                "freq": d["freq"],
                "level": y,
                "name": [d["target_label"]] * len(y),
            }
            self._target_item.label = value(d["target_label"])
            shown.add(-1)
        for key in self._cand:
            item = self._target_item if key == -1 else self._cand_items[key]
            on = key in shown
            if item.visible != on:
                item.visible = on
                for line in item.renderers:
                    line.visible = on

    def _set_overlays(self, shown) -> None:
        for dof, item in self._over_items.items():
            item.visible = dof in shown
            for r in item.renderers:
                r.visible = dof in shown

    def _set_scale(self, scale: str) -> None:
        """Hover lines in the level scale's unit (dB, or the magnitude's)."""
        if scale == self._scale:
            return
        self._scale = scale
        for tool in self._fig.select({"type": HoverTool}):
            self._format_tool(tool)

    def _format_tool(self, tool: HoverTool) -> None:
        """The hover tool's level in the current scale's unit."""
        fmt = "{0.0} dB" if self._scale == "dB" else "{0.000}"
        tool.tooltips = [(a, "@level" + fmt if a == "Level" else b) for a, b in tool.tooltips]

    def _draw(self, r):
        c = r.columns
        f = c["freq_Hz"]
        p = self.store.response_plot
        # the plot's extras (a corner's) only over the corner's response of the same case
        # (they are published just after it)
        corner = r.snapshot is not None and not r.snapshot.vehicle
        extras = p if corner and made_of_same(p, r, CASE) else None
        if extras is None:
            self._ref.data = {"freq": f, "level": c["reference_dB"]}
            self._tr.data = {"freq": f, "level": c["truncated_dB"]}
            self._fig.yaxis.axis_label = level_label(r.draw["dof"])
        else:
            self._draw_extras(extras.draw)
        label = r.draw.get("truncated_label")
        for item in self._legend_items() if label else ():
            if item.renderers and item.renderers[0].data_source is self._tr:
                item.label = value(label)  # "N retained modes" or "... + residual"
        self._draw_review(r, "dB" if extras is None else extras.draw["scale"])
        self._fit(self.x_range, f)

    def _draw_extras(self, d) -> None:
        f = d["freq"]
        curves = d["curves"]
        self._set_scale(d["scale"])
        self._ref.data = {"freq": f, "level": curves[0]["y"]}
        self._tr.data = {"freq": f, "level": curves[1]["y"]}
        shown = []
        for cv in curves[2:]:
            self._overlay(cv["dof"]).data = {"freq": f, "level": cv["y"]}
            shown.append(cv["dof"])
        for cv in curves[2:]:
            self._over_items[cv["dof"]].label = value(cv["label"])
        self._set_overlays(shown)
        self._fig.yaxis.axis_label = d["y_label"]
        on = {cur["k"]: cur for cur in d["cursors"]}
        for k, (span, lb) in enumerate(zip(self._cursor_spans, self._cursor_labels, strict=True)):
            cur = on.get(k + 1)
            span.visible = lb.visible = cur is not None
            if cur is not None:
                span.location = lb.x = cur["f"]
        pts = [cur for cur in d["cursors"] if cur["y"] is not None]
        self._cursor_points.data = {
            "freq": [cur["f"] for cur in pts],
            "level": [cur["y"] for cur in pts],
        }
        errors = [cur["error"] for cur in d["cursors"]]
        self._readout.text = readout_html(d["readout"], errors)
        # its height stated: a text set in place keeps the height of its first layout (the
        # table lay over the plot's title block)
        lines = len(d["readout"]["rows"]) + 1 + sum(1 for x in errors if x)
        line = READOUT_LINE_PX[self.mode]
        self._readout.model.height = lines * line + 6 if d["readout"]["rows"] else 0


def readout_html(readout: dict, errors: list[str]) -> str:
    """The cursors' readout as an HTML table (escaped: DOF labels may come from uploads)."""
    if not readout["rows"]:
        return ""
    e = html.escape
    head = "".join(f'<th style="padding:0 8px">{e(h)}</th>' for h in readout["header"])
    body = "".join(
        "<tr>" + "".join(f'<td style="padding:0 8px">{e(str(x))}</td>' for x in row) + "</tr>"
        for row in readout["rows"]
    )
    notes = "".join(f"<div>{e(x)}</div>" for x in errors if x)
    return (
        '<table class="cursor-readout" style="border-collapse:collapse;text-align:right">'
        f"<tr>{head}</tr>{body}</table>{notes}"
    )


class UncoupledView(LiveView):
    """Uncoupled tire hub response and chassis spindle-to-bushing mobility."""

    key = "uncoupled"
    result_name = "uncoupled"
    x_range = param.Parameter(default=None, doc="Shared frequency range; a new one if None.")

    def _controls(self):
        return [
            pn.widgets.Select.from_param(
                self.store.state.case.param.spindle_input, name="Chassis spindle input", width=160
            )
        ]

    def _build(self):
        if self.x_range is None:
            self.x_range = frequency_range()
        self._tire_fig = tire = new_figure(
            x_label=FREQ_LABEL, y_label=level_label("z"), x_range=self.x_range, min_height=300
        )
        self._tire_ref = add_line(
            tire,
            "uncoupled.tire_reference",
            color=COLORS["reference"],
            legend="all modes",
            tooltips=level_tooltips("all modes"),
        )
        self._tire_tr = add_line(
            tire,
            "uncoupled.tire_truncated",
            color=COLORS["tire"],
            legend="N retained modes",
            dash="dashed",
            tooltips=level_tooltips("N retained modes"),
        )
        self._chassis_fig = chassis = new_figure(
            x_label=FREQ_LABEL, y_label="Mobility", x_range=self.x_range, min_height=300
        )
        self._chassis = add_line(
            chassis,
            "uncoupled.chassis",
            color=COLORS["chassis"],
            legend=None,
            tooltips=level_tooltips("chassis mobility"),
        )
        return [tire, chassis]

    def _draw(self, r):
        c, d = r.columns, r.draw
        f = c["freq_Hz"]
        self._tire_ref.data = {"freq": f, "level": c["tire_reference_dB"]}
        self._tire_tr.data = {"freq": f, "level": c["tire_truncated_dB"]}
        self._chassis.data = {"freq": f, "level": c["chassis_dB"]}
        self._tire_fig.title.text = d["tire_title"]
        self._tire_fig.yaxis.axis_label = level_label(d["dof"])
        self._chassis_fig.title.text = d["chassis_title"]
        self._chassis_fig.yaxis.axis_label = d["chassis_label"]
        self._fit(self.x_range, f)
