"""Coupled mobility at the bushing: all-modes reference and truncated curve (figs. 4.8-4.9).

On request also the uncoupled subsystems: the tire's free hub velocity (figs. 4.6-4.7) and the
chassis' spindle-to-bushing mobility (figs. 4.2-4.3).
"""

from __future__ import annotations

import holoviews as hv
import panel as pn
import param
from panel.viewable import Viewer

from .. import compute
from ..state import CaseState
from .common import COLORS, CURVE_OPTS, FREQ, download_button, level_dim, name_source

CASE_KEYS = ["harmonic", "n_modes", "dof", "coupling", "models"]


class MobilityView(Viewer):
    """Coupled bushing response v_e* in dB versus frequency (thesis eq. 4.1)."""

    case = param.ClassSelector(class_=CaseState)

    def data(self) -> dict:
        """The columns behind the plot for the current state."""
        c = self.case
        return compute.mobility_data(c.harmonic, c.n_modes, c.dof, c.coupling, c.models)

    def meta(self) -> dict:
        c = self.case
        return {
            "view": "coupled bushing response v_e* (thesis eq. 4.1)",
            "harmonic": c.harmonic, "N (retained tire modes)": c.n_modes,
            "reference": "all tire modes", "response DOF": f"bushing:{c.dof}",
            "coupling": c.coupling, "unit": compute.level_unit(c.dof),
            "models": c.models.describe(),
        }

    # -- plot layers (each a DynamicMap watching only what it needs) -------------------
    # each layer is a DynamicMap fed by the parameters it depends on; styles are set once on
    # the DynamicMap (setting options inside a callback costs more than the data)
    def _reference(self, harmonic, dof, coupling, models):
        d = compute.mobility_data(harmonic, 400, dof, coupling, models)
        return hv.Curve((d["freq"], d["reference_db"]), FREQ, level_dim(dof),
                        label="all modes (reference)")

    def _truncated(self, harmonic, n_modes, dof, coupling, models):
        d = compute.mobility_data(harmonic, n_modes, dof, coupling, models)
        return hv.Curve((d["freq"], d["truncated_db"]), FREQ, level_dim(dof),
                        label="N retained modes")

    def plot(self) -> hv.DynamicMap:
        c = self.case
        tips = [("Frequency", "@freq{0.0} Hz"), ("Level", "@level{0.0} dB")]
        ref = hv.DynamicMap(
            self._reference,
            streams=[hv.streams.Params(c, ["harmonic", "dof", "coupling", "models"])],
        ).opts(color=COLORS["reference"], hooks=[name_source("mobility.reference")],
               hover_tooltips=[("", "all modes"), *tips], **CURVE_OPTS)
        tr = hv.DynamicMap(self._truncated, streams=[hv.streams.Params(c, CASE_KEYS)]).opts(
            color=COLORS["truncated"], line_dash="dashed",
            hooks=[name_source("mobility.truncated")],
            hover_tooltips=[("", "N retained modes"), *tips], **CURVE_OPTS)
        return (ref * tr).opts(hv.opts.Overlay(legend_position="bottom_left"))

    def __panel__(self):
        c = self.case
        dl = download_button(
            "mobility", self._csv_columns, self.meta,
            lambda: f"bushing_response_h{c.harmonic}_N{c.n_modes}_{c.dof}_{c.coupling}.csv",
        )
        caption = pn.pane.Markdown(pn.bind(
            lambda h, n, d, cp: f"**Harmonic {h}** &middot; bushing:{d} &middot; N = {n} "
            f"&middot; {cp} coupling", c.param.harmonic, c.param.n_modes, c.param.dof,
            c.param.coupling), margin=(0, 10))
        return pn.Column(
            pn.Row(caption, pn.layout.HSpacer(), dl),
            pn.pane.HoloViews(self.plot(), sizing_mode="stretch_both", min_height=340),
            sizing_mode="stretch_both",
        )

    def _csv_columns(self) -> dict:
        d = self.data()
        return {
            "freq_Hz": d["freq"], "reference_dB": d["reference_db"],
            "truncated_dB": d["truncated_db"], "reference": d["reference"],
            "truncated": d["truncated"],
        }


class UncoupledView(Viewer):
    """Uncoupled tire hub response and chassis spindle-to-bushing mobility."""

    case = param.ClassSelector(class_=CaseState)

    def data(self) -> dict:
        c = self.case
        return compute.uncoupled_data(c.harmonic, c.n_modes, c.dof, c.spindle_input,
                                      c.models)

    def _tire(self, harmonic, n_modes, dof, models):
        d = compute.uncoupled_data(harmonic, n_modes, dof, "z", models)
        lvl = level_dim(dof, "tire_level")
        ref = hv.Curve((d["freq"], d["tire_reference_db"]), FREQ, lvl, label="all modes").opts(
            color=COLORS["reference"], hooks=[name_source("uncoupled.tire_reference")])
        tr = hv.Curve((d["freq"], d["tire_truncated_db"]), FREQ, lvl,
                      label="N retained modes").opts(
            color=COLORS["tire"], line_dash="dashed",
            hooks=[name_source("uncoupled.tire_truncated")])
        return (ref * tr).opts(title=f"Tire: free hub velocity hub:{dof} (figs. 4.6-4.7)")

    def _chassis(self, harmonic, dof, spindle_input, models):
        d = compute.uncoupled_data(harmonic, 400, dof, spindle_input, models)
        unit = "dB re 1 (rad/s)/" if dof.startswith("r") else "dB re 1 (m/s)/"
        unit += "(N m)" if spindle_input.startswith("r") else "N"
        lvl = hv.Dimension("chassis_level", label="Mobility", unit=unit)
        return hv.Curve((d["freq"], d["chassis_db"]), FREQ, lvl).opts(
            color=COLORS["chassis"], hooks=[name_source("uncoupled.chassis")],
            title=f"Chassis: spindle:{spindle_input} -> bushing:{dof} (figs. 4.2-4.3)")

    def __panel__(self):
        c = self.case
        tire = hv.DynamicMap(self._tire, streams=[
            hv.streams.Params(c, ["harmonic", "n_modes", "dof", "models"])]).opts(
            hv.opts.Curve(**CURVE_OPTS), hv.opts.Overlay(legend_position="bottom_left"))
        chassis = hv.DynamicMap(self._chassis, streams=[
            hv.streams.Params(c, ["harmonic", "dof", "spindle_input", "models"])]).opts(
            hv.opts.Curve(**CURVE_OPTS))
        dl = download_button(
            "uncoupled", self._csv_columns, self._meta,
            lambda: f"uncoupled_h{c.harmonic}_N{c.n_modes}_{c.dof}_in{c.spindle_input}.csv",
        )
        inp = pn.widgets.Select.from_param(c.param.spindle_input, name="Chassis spindle input",
                                           width=160)
        return pn.Column(
            pn.Row(inp, pn.layout.HSpacer(), dl),
            pn.Row(pn.pane.HoloViews(tire, sizing_mode="stretch_both", min_height=300),
                   pn.pane.HoloViews(chassis, sizing_mode="stretch_both", min_height=300),
                   sizing_mode="stretch_both"),
            sizing_mode="stretch_both",
        )

    def _meta(self) -> dict:
        c = self.case
        return {"view": "uncoupled subsystems", "harmonic": c.harmonic,
                "N (retained tire modes)": c.n_modes, "tire output": f"hub:{c.dof}",
                "chassis": f"spindle:{c.spindle_input} -> bushing:{c.dof}"}

    def _csv_columns(self) -> dict:
        d = self.data()
        return {k: d[k] for k in ("freq", "tire_reference_db", "tire_truncated_db", "chassis_db",
                                  "tire_reference", "tire_truncated", "chassis")}
