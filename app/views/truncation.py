"""Truncation error map (thesis figs. 5.3, 5.6, 5.7), suggested modes (table 5.1) and
eigenfrequency versus mode number (fig. 5.8)."""

from __future__ import annotations

import holoviews as hv
import numpy as np
import panel as pn
import param
from panel.viewable import Viewer

from .. import compute
from ..state import CaseState, TruncationState
from .common import COLORS, CURVE_OPTS, FREQ, MODES, download_button, name_source

ERROR = hv.Dimension("error", label="Truncation error", unit="%")
EIGEN = hv.Dimension("eigenfrequency", label="Highest retained eigenfrequency", unit="Hz")


class TruncationView(Viewer):
    """Error over centre frequency and retained modes, colour capped at the threshold."""

    case = param.ClassSelector(class_=CaseState)
    truncation = param.ClassSelector(class_=TruncationState)

    def data(self) -> dict:
        c, t = self.case, self.truncation
        dof = c.dof if t.map_mode == "selected DOF" else None
        return compute.error_map_data(c.harmonic, c.coupling, dof, c.models)

    def _map(self, harmonic, coupling, dof, map_mode, threshold, models):
        d = compute.error_map_data(harmonic, coupling, dof if map_mode == "selected DOF" else None,
                                   models)
        what = f"bushing:{dof}" if map_mode == "selected DOF" else "max over 6 DOFs"
        img = hv.Image((d["centre_freq"], d["n_modes"], d["error_pct"]), [FREQ, MODES], ERROR)
        return img.opts(clim=(0.0, float(threshold)), title=f"Harmonic {harmonic}, {what}",
                        clabel=f"Error (%), capped at {threshold:g} %")

    def _chosen(self, n_modes):
        return hv.HLine(float(n_modes), label="chosen N")

    def _suggested(self, harmonic, coupling, dof, threshold, f_max, map_mode, models):
        tab = compute.suggested_table(float(threshold), float(f_max), coupling,
                                      dof if map_mode == "selected DOF" else None, models)
        n = float(tab["n_modes"][list(tab["harmonic"]).index(harmonic)])
        return hv.HLine(n).opts(color="#0ca678", line_dash="dashed", line_width=2) * hv.VLine(
            float(f_max)).opts(color="#0ca678", line_dash="dotted", line_width=2)

    def __panel__(self):
        c, t = self.case, self.truncation
        img = hv.DynamicMap(self._map, streams=[
            hv.streams.Params(c, ["harmonic", "coupling", "dof", "models"]),
            hv.streams.Params(t, ["map_mode", "threshold"])]).opts(
            cmap="inferno_r", colorbar=True, responsive=True, min_height=320, tools=["hover"],
            hover_tooltips=[("Centre frequency", "$x{0.0} Hz"), ("N", "$y{0}"),
                            ("Error", "@image{0.0} %")],
            hooks=[name_source("truncation.map")], framewise=True)
        chosen = hv.DynamicMap(self._chosen, streams=[hv.streams.Params(c, ["n_modes"])]).opts(
            color=COLORS["round"], line_width=2)
        sugg = hv.DynamicMap(self._suggested, streams=[
            hv.streams.Params(c, ["harmonic", "coupling", "dof", "models"]),
            hv.streams.Params(t, ["threshold", "f_max", "map_mode"])])
        dl = download_button("truncation", self._csv_columns, self._meta,
                             lambda: f"truncation_map_h{c.harmonic}_{self._what()}.csv")
        return pn.Column(
            pn.Row(pn.pane.Markdown(
                "Error vs all modes, 12 Hz floating band; black: at or above the threshold. "
                "Solid: chosen N; dashed: suggested N up to the dotted frequency.",
                margin=(0, 10), styles={"color": "#495057", "font-size": "0.9em"}),
                pn.layout.HSpacer(), dl),
            pn.pane.HoloViews(img * sugg * chosen, sizing_mode="stretch_both", min_height=340),
            sizing_mode="stretch_both",
        )

    def _what(self) -> str:
        return self.case.dof if self.truncation.map_mode == "selected DOF" else "maxdof"

    def _meta(self) -> dict:
        c, t = self.case, self.truncation
        return {"view": "truncation error map (thesis eq. 5.1, figs. 5.3/5.6/5.7)",
                "harmonic": c.harmonic, "coupling": c.coupling,
                "response DOF": f"bushing:{c.dof}" if t.map_mode == "selected DOF"
                else "max over 6 DOFs",
                "reference": "all tire modes", "layout": "long: one row per (N, centre freq)"}

    def _csv_columns(self) -> dict:
        d = self.data()
        nn, ff = np.meshgrid(d["n_modes"], d["centre_freq"], indexing="ij")
        return {"n_modes": nn.ravel(), "centre_freq_Hz": ff.ravel(),
                "error_pct": d["error_pct"].ravel()}

class SuggestedModesView(Viewer):
    """Suggested number of modes for all seven harmonics (thesis table 5.1)."""

    case = param.ClassSelector(class_=CaseState)
    truncation = param.ClassSelector(class_=TruncationState)

    def table(self) -> dict:
        c, t = self.case, self.truncation
        return compute.suggested_table(float(t.threshold), float(t.f_max), c.coupling,
                                       c.dof if t.map_mode == "selected DOF" else None,
                                       c.models)

    def table_frame(self):
        """The suggested-modes table as a DataFrame (what the Tabulator shows)."""
        import pandas as pd

        tab = self.table()
        return pd.DataFrame({
            "Harmonic": tab["harmonic"],
            "Band (Hz)": [f"{a:.1f}-{b:.1f}" for a, b in zip(tab["f_low"], tab["f_high"],
                                                              strict=True)],
            "Suggested N": tab["n_modes"],
            "Highest eigenfreq. (Hz)": tab["eigenfrequency"].round(1),
        })

    def __panel__(self):
        c, t = self.case, self.truncation
        table = pn.widgets.Tabulator(
            self.table_frame(), disabled=True, show_index=False, selectable=False,
            sizing_mode="stretch_width", css_classes=["suggested-table"],
            layout="fit_data_stretch", theme="bootstrap5")

        def refresh(*events):
            if all(e.name == "dof" for e in events) and t.map_mode != "selected DOF":
                return  # the table judges the maximum over DOFs: nothing to do
            table.value = self.table_frame()

        t.param.watch(refresh, ["threshold", "f_max", "map_mode"])
        c.param.watch(refresh, ["coupling", "dof", "models"])
        dl = download_button(
            "suggested", self._csv_table, self._meta_table,
            lambda: f"suggested_modes_thr{t.threshold:g}_fmax{t.f_max:g}.csv")
        caption = pn.pane.Markdown(pn.bind(
            lambda thr, fm, mode, dof: f"Smallest N from which the error stays below "
            f"**{thr:g} %** up to **{fm:g} Hz** "
            f"({'bushing:' + dof if mode == 'selected DOF' else mode}), and the highest "
            "eigenfrequency among those modes at 80 km/h.",
            t.param.threshold, t.param.f_max, t.param.map_mode, c.param.dof),
            margin=(0, 10), styles={"color": "#495057"})
        return pn.Column(pn.Row(caption, pn.layout.HSpacer(), dl), table,
                         sizing_mode="stretch_both")

    def _meta_table(self) -> dict:
        c, t = self.case, self.truncation
        return {"view": "suggested number of modes (thesis table 5.1)",
                "threshold_pct": t.threshold, "f_max_Hz": t.f_max, "coupling": c.coupling,
                "response DOF": f"bushing:{c.dof}" if t.map_mode == "selected DOF"
                else "max over 6 DOFs",
                "eigenfrequency": "highest retained eigenfrequency at 80 km/h"}

    def _csv_table(self) -> dict:
        tab = self.table()
        return {"harmonic": tab["harmonic"], "f_low_Hz": tab["f_low"],
                "f_high_Hz": tab["f_high"], "n_modes": tab["n_modes"],
                "eigenfrequency_Hz": tab["eigenfrequency"]}



class EigenView(Viewer):
    """Highest retained eigenfrequency versus number of modes at 20/80/120 km/h (fig. 5.8)."""

    case = param.ClassSelector(class_=CaseState)

    def data(self) -> dict:
        return compute.eigen_curves(self.case.models)

    def _curves(self, models):
        d = compute.eigen_curves(models)
        styles = {"f_20": ("20 km/h", "#74c0fc"), "f_80": ("80 km/h", "#1c7ed6"),
                  "f_120": ("120 km/h", "#0b3d91")}
        layers = [
            hv.Curve((d["n_modes"], d[k]), MODES, EIGEN, label=lab).opts(
                color=col, hooks=[name_source(f"eigen.{k}")],
                hover_tooltips=[("Speed", lab), ("N", "@n_modes"),
                                ("Eigenfrequency", "@eigenfrequency{0.0} Hz")])
            for k, (lab, col) in styles.items()
        ]
        return hv.Overlay(layers)

    def _marker(self, n_modes):
        return hv.VLine(float(n_modes))

    def __panel__(self):
        curves = hv.DynamicMap(self._curves, streams=[
            hv.streams.Params(self.case, ["models"])]).opts(
            hv.opts.Curve(**CURVE_OPTS),
            hv.opts.Overlay(legend_position="top_left", title="Eigenfrequency vs mode number",
                            logy=False))
        marker = hv.DynamicMap(self._marker, streams=[
            hv.streams.Params(self.case, ["n_modes"])]).opts(color=COLORS["round"], line_width=2)
        dl = download_button(
            "eigen", self._csv_columns,
            lambda: {"view": "highest retained eigenfrequency vs N (thesis fig. 5.8)",
                     "models": self.case.models.describe()},
            lambda: "eigenfrequency_vs_modes.csv")
        return pn.Column(
            pn.Row(pn.pane.Markdown("Highest eigenfrequency among N retained modes "
                                    "(N/2 +/- pairs, lowest first).", margin=(0, 10),
                                    styles={"color": "#495057", "font-size": "0.9em"}),
                   pn.layout.HSpacer(), dl),
            pn.pane.HoloViews(curves * marker, sizing_mode="stretch_both", min_height=300),
            sizing_mode="stretch_both",
        )

    def _csv_columns(self) -> dict:
        d = self.data()
        return {"n_modes": d["n_modes"], "f_20kmh_Hz": d["f_20"], "f_80kmh_Hz": d["f_80"],
                "f_120kmh_Hz": d["f_120"]}
