"""Coupled mobility at the bushing: all-modes reference and truncated curve (figs. 4.8-4.9).

On request also the uncoupled subsystems: the tire's free hub velocity (figs. 4.6-4.7) and the
chassis' spindle-to-bushing mobility (figs. 4.2-4.3).
"""

from __future__ import annotations

import panel as pn
import param
from panel.viewable import Viewer

from .. import compute
from ..state import CaseState
from .common import (
    COLORS,
    FREQ_LABEL,
    download_button,
    level_label,
    level_tooltips,
    live_text,
)
from .plots import Pusher, add_line, fit_range, frequency_range, new_figure

CASE_KEYS = ["harmonic", "n_modes", "dof", "coupling", "models"]


class MobilityView(Viewer):
    """Coupled bushing response v_e* in dB versus frequency (thesis eq. 4.1)."""

    case = param.ClassSelector(class_=CaseState)
    x_range = param.Parameter(
        default=None,
        doc="Frequency range shared with other views (linked zoom and pan); a new one if None.",
    )

    def __init__(self, **params):
        super().__init__(**params)
        self._layout = None
        self._push = Pusher()

    def data(self) -> dict:
        """The columns behind the plot for the current state."""
        c = self.case
        return compute.mobility_data(c.harmonic, c.n_modes, c.dof, c.coupling, c.models)

    def meta(self) -> dict:
        c = self.case
        return {
            "view": "coupled bushing response v_e* (thesis eq. 4.1)",
            "harmonic": c.harmonic,
            "N (retained tire modes)": c.n_modes,
            "reference": "all tire modes",
            "response DOF": f"bushing:{c.dof}",
            "coupling": c.coupling,
            "unit": compute.level_unit(c.dof),
            "models": c.models.describe(),
        }

    # -- plot ----------------------------------------------------------------------------
    def _build(self):
        if self.x_range is None:
            self.x_range = frequency_range()
        fig = new_figure(
            x_label=FREQ_LABEL,
            y_label=level_label(self.case.dof),
            x_range=self.x_range,
            name="mobility.figure",
        )
        self._fig = fig
        self._ref = add_line(
            fig,
            "mobility.reference",
            color=COLORS["reference"],
            legend="all modes (reference)",
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
        self._apply(self.data(), self.case.dof)()
        self.case.param.watch(self._changed, CASE_KEYS)
        return fig

    def _apply(self, d: dict, dof: str):
        """The model changes that show data ``d`` of response DOF ``dof``."""

        def update():
            fit_range(self.x_range, d["freq"])
            self._ref.data = {"freq": d["freq"], "level": d["reference_db"]}
            self._tr.data = {"freq": d["freq"], "level": d["truncated_db"]}
            self._fig.yaxis[0].axis_label = level_label(dof)

        return update

    def _changed(self, *events):
        self._push(lambda: self._apply(self.data(), self.case.dof))

    def __panel__(self):
        if self._layout is not None:
            return self._layout
        c = self.case
        dl = download_button(
            "mobility",
            self._csv_columns,
            self.meta,
            lambda: f"bushing_response_h{c.harmonic}_N{c.n_modes}_{c.dof}_{c.coupling}.csv",
        )
        caption = live_text(self._caption, [(c, ["harmonic", "n_modes", "dof", "coupling"])])
        self._layout = pn.Column(
            pn.Row(caption, dl),
            pn.pane.Bokeh(self._build(), sizing_mode="stretch_both", min_height=340),
            sizing_mode="stretch_both",
        )
        return self._layout

    def _caption(self) -> str:
        c = self.case
        return (
            f"**Harmonic {c.harmonic}** &middot; bushing:{c.dof} &middot; N = {c.n_modes} "
            f"&middot; {c.coupling} coupling"
        )

    def _csv_columns(self) -> dict:
        d = self.data()
        return {
            "freq_Hz": d["freq"],
            "reference_dB": d["reference_db"],
            "truncated_dB": d["truncated_db"],
            "reference": d["reference"],
            "truncated": d["truncated"],
        }


class UncoupledView(Viewer):
    """Uncoupled tire hub response and chassis spindle-to-bushing mobility."""

    case = param.ClassSelector(class_=CaseState)
    x_range = param.Parameter(default=None, doc="Shared frequency range; a new one if None.")

    def __init__(self, **params):
        super().__init__(**params)
        self._layout = None
        self._push = Pusher()

    def data(self) -> dict:
        c = self.case
        return compute.uncoupled_data(c.harmonic, c.n_modes, c.dof, c.spindle_input, c.models)

    @staticmethod
    def _chassis_label(dof: str, spindle_input: str) -> str:
        unit = "dB re 1 (rad/s)/" if dof.startswith("r") else "dB re 1 (m/s)/"
        unit += "(N m)" if spindle_input.startswith("r") else "N"
        return f"Mobility ({unit})"

    def _build(self):
        if self.x_range is None:
            self.x_range = frequency_range()
        c = self.case
        self._tire_fig = tire = new_figure(
            x_label=FREQ_LABEL, y_label=level_label(c.dof), x_range=self.x_range, min_height=300
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
            x_label=FREQ_LABEL,
            y_label=self._chassis_label(c.dof, c.spindle_input),
            x_range=self.x_range,
            min_height=300,
        )
        self._chassis = add_line(
            chassis,
            "uncoupled.chassis",
            color=COLORS["chassis"],
            legend=None,
            tooltips=level_tooltips("chassis mobility"),
        )
        self._apply(self.data())()
        c.param.watch(self._changed, ["harmonic", "n_modes", "dof", "spindle_input", "models"])
        return tire, chassis

    def _apply(self, d: dict):
        c = self.case
        dof, inp = c.dof, c.spindle_input

        def update():
            fit_range(self.x_range, d["freq"])
            self._tire_ref.data = {"freq": d["freq"], "level": d["tire_reference_db"]}
            self._tire_tr.data = {"freq": d["freq"], "level": d["tire_truncated_db"]}
            self._chassis.data = {"freq": d["freq"], "level": d["chassis_db"]}
            self._tire_fig.title.text = f"Tire: free hub velocity hub:{dof} (figs. 4.6-4.7)"
            self._tire_fig.yaxis[0].axis_label = level_label(dof)
            self._chassis_fig.title.text = (
                f"Chassis: spindle:{inp} -> bushing:{dof} (figs. 4.2-4.3)"
            )
            self._chassis_fig.yaxis[0].axis_label = self._chassis_label(dof, inp)

        return update

    def _changed(self, *events):
        self._push(lambda: self._apply(self.data()))

    def __panel__(self):
        if self._layout is not None:
            return self._layout
        c = self.case
        tire, chassis = self._build()
        dl = download_button(
            "uncoupled",
            self._csv_columns,
            self._meta,
            lambda: f"uncoupled_h{c.harmonic}_N{c.n_modes}_{c.dof}_in{c.spindle_input}.csv",
        )
        inp = pn.widgets.Select.from_param(
            c.param.spindle_input, name="Chassis spindle input", width=160
        )
        self._layout = pn.Column(
            pn.Row(inp, pn.layout.HSpacer(), dl),
            pn.Row(
                pn.pane.Bokeh(tire, sizing_mode="stretch_both", min_height=300),
                pn.pane.Bokeh(chassis, sizing_mode="stretch_both", min_height=300),
                sizing_mode="stretch_both",
            ),
            sizing_mode="stretch_both",
        )
        return self._layout

    def _meta(self) -> dict:
        c = self.case
        return {
            "view": "uncoupled subsystems",
            "harmonic": c.harmonic,
            "N (retained tire modes)": c.n_modes,
            "tire output": f"hub:{c.dof}",
            "chassis": f"spindle:{c.spindle_input} -> bushing:{c.dof}",
        }

    def _csv_columns(self) -> dict:
        d = self.data()
        return {
            k: d[k]
            for k in (
                "freq",
                "tire_reference_db",
                "tire_truncated_db",
                "chassis_db",
                "tire_reference",
                "tire_truncated",
                "chassis",
            )
        }
