"""Coupled mobility at the bushing: all-modes reference and truncated curve (figs. 4.8-4.9).

On request also the uncoupled subsystems: the tire's free hub velocity (figs. 4.6-4.7) and the
chassis' spindle-to-bushing mobility (figs. 4.2-4.3).
"""

from __future__ import annotations

import panel as pn
import param
from bokeh.core.property.vectorization import value

from .common import COLORS, FREQ_LABEL, level_label, level_tooltips
from .live import LiveView
from .plots import add_line, frequency_range, new_figure


class MobilityView(LiveView):
    """Coupled bushing response v_e* in dB versus frequency (thesis eq. 4.1)."""

    key = "mobility"
    x_range = param.Parameter(
        default=None,
        doc="Frequency range shared with other views (linked zoom and pan); a new one if None.",
    )

    def result(self):
        return self.store.response

    @param.depends("store.response", watch=True)
    def _changed(self):
        self.redraw()

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
        return [fig]

    def _draw(self, r):
        c = r.columns
        self._ref.data = {"freq": c["freq_Hz"], "level": c["reference_dB"]}
        self._tr.data = {"freq": c["freq_Hz"], "level": c["truncated_dB"]}
        self._fig.yaxis.axis_label = level_label(r.draw["dof"])
        label = r.draw.get("truncated_label")
        for item in self._fig.legend[0].items if label and self._fig.legend else ():
            if item.renderers and item.renderers[0].data_source is self._tr:
                item.label = value(label)  # "N retained modes" or "... + residual"
        self._fit(self.x_range, c["freq_Hz"])


class UncoupledView(LiveView):
    """Uncoupled tire hub response and chassis spindle-to-bushing mobility."""

    key = "uncoupled"
    x_range = param.Parameter(default=None, doc="Shared frequency range; a new one if None.")
    min_height = 300

    def result(self):
        return self.store.uncoupled

    @param.depends("store.uncoupled", watch=True)
    def _changed(self):
        self.redraw()

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
