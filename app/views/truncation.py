"""Truncation error map (thesis figs. 5.3, 5.6, 5.7), suggested modes (table 5.1) and
eigenfrequency versus mode number (fig. 5.8)."""

from __future__ import annotations

import numpy as np
import panel as pn
import param
from panel.viewable import Viewer

from .. import compute
from ..state import CaseState, TruncationState
from .common import COLORS, MODES_LABEL, download_button, live_text
from .plots import (
    Pusher,
    add_image,
    add_line,
    add_span,
    fit_range,
    frequency_range,
    modes_range,
    new_figure,
)

#: Eigenfrequency curves of fig. 5.8: column -> (legend, colour).
EIGEN_STYLES = {
    "f_20": ("20 km/h", "#74c0fc"),
    "f_80": ("80 km/h", "#1c7ed6"),
    "f_120": ("120 km/h", "#0b3d91"),
}


def _same_columns(old: dict, new: dict) -> bool:
    """True when a source already holds ``new`` (skip a transfer that changes nothing)."""
    if old.keys() != new.keys():
        return False
    for k, v in new.items():
        a, b = old[k], v
        if k == "image":
            a, b = a[0], b[0]
        if np.shape(a) != np.shape(b) or not np.array_equal(a, b, equal_nan=True):
            return False
    return True


class TruncationView(Viewer):
    """Error over centre frequency and retained modes, colour capped at the threshold."""

    case = param.ClassSelector(class_=CaseState)
    truncation = param.ClassSelector(class_=TruncationState)
    x_range = param.Parameter(
        default=None,
        doc="Frequency range shared with other views (linked zoom and pan); a new one if None.",
    )
    n_range = param.Parameter(
        default=None,
        doc="Retained-modes range shared with the eigenfrequency plot; a new one if None.",
    )

    def __init__(self, **params):
        super().__init__(**params)
        self._layout = None
        self._push = Pusher()

    def data(self) -> dict:
        c, t = self.case, self.truncation
        dof = c.dof if t.map_mode == "selected DOF" else None
        return compute.error_map_data(c.harmonic, c.coupling, dof, c.models)

    def _suggested_n(self) -> int:
        c, t = self.case, self.truncation
        tab = compute.suggested_table(
            float(t.threshold),
            float(t.f_max),
            c.coupling,
            c.dof if t.map_mode == "selected DOF" else None,
            c.models,
        )
        return int(tab["n_modes"][list(tab["harmonic"]).index(c.harmonic)])

    def _build(self):
        if self.x_range is None:
            self.x_range = frequency_range()
        if self.n_range is None:
            self.n_range = modes_range()
        fig = new_figure(
            x_label="Centre frequency (Hz)",
            y_label=MODES_LABEL,
            x_range=self.x_range,
            y_range=self.n_range,
            name="truncation.figure",
        )
        fig.grid.visible = False
        self._fig = fig
        self._src, self._mapper, self._bar = add_image(
            fig,
            "truncation.map",
            colorbar_title="Error (%)",
            tooltips=[
                ("Centre frequency", "$x{0.0} Hz"),
                ("N", "$y{0}"),
                ("Error", "@image{0.0} %"),
            ],
        )
        self._suggested = add_span(
            fig,
            dimension="width",
            color=COLORS["suggested"],
            dash="dashed",
            name="truncation.suggested_n",
        )
        self._f_max = add_span(
            fig,
            dimension="height",
            color=COLORS["suggested"],
            dash="dotted",
            name="truncation.f_max",
        )
        self._chosen = add_span(
            fig, dimension="width", color=COLORS["round"], name="truncation.chosen_n"
        )
        self._apply(*self._state())()
        self.case.param.watch(self._changed, ["harmonic", "coupling", "dof", "models", "n_modes"])
        self.truncation.param.watch(self._changed, ["map_mode", "threshold", "f_max"])
        return fig

    def _state(self) -> tuple:
        c, t = self.case, self.truncation
        what = f"bushing:{c.dof}" if t.map_mode == "selected DOF" else "max over 6 DOFs"
        return (
            self.data(),
            self._suggested_n(),
            c.harmonic,
            c.n_modes,
            what,
            float(t.threshold),
            float(t.f_max),
            compute.frequencies(c.harmonic),
        )

    def _apply(self, d, n_suggested, harmonic, n_modes, what, threshold, f_max, freq):
        cf, nm = d["centre_freq"], d["n_modes"]
        dc = float(cf[1] - cf[0]) if cf.size > 1 else 1.0
        dn = float(nm[1] - nm[0]) if nm.size > 1 else 10.0
        cols = {
            "image": [d["error_pct"]],
            "x": [float(cf[0]) - dc / 2],
            "y": [float(nm[0]) - dn / 2],
            "dw": [dc * cf.size],
            "dh": [dn * nm.size],
        }

        def update():
            fit_range(self.x_range, freq)
            # up to the all-modes count too (the reference: no error, not in the map)
            fit_range(self.n_range, [cols["y"][0], cols["y"][0] + cols["dh"][0] + dn])
            if not _same_columns(self._src.data, cols):
                self._src.data = cols
            self._mapper.high = threshold
            self._bar.title = f"Error (%), capped at {threshold:g} %"
            self._fig.title.text = f"Harmonic {harmonic}, {what}"
            self._suggested.location = float(n_suggested)
            self._f_max.location = f_max
            self._chosen.location = float(n_modes)

        return update

    def _changed(self, *events):
        self._push(lambda: self._apply(*self._state()))

    def __panel__(self):
        if self._layout is not None:
            return self._layout
        c = self.case
        dl = download_button(
            "truncation",
            self._csv_columns,
            self._meta,
            lambda: f"truncation_map_h{c.harmonic}_{self._what()}.csv",
        )
        self._layout = pn.Column(
            pn.Row(
                pn.pane.Markdown(
                    "Error vs all modes, 12 Hz floating band; black: at or above the threshold. "
                    "Solid: chosen N; dashed: suggested N up to the dotted frequency.",
                    margin=(0, 10),
                    styles={"color": "#495057", "font-size": "0.9em"},
                ),
                pn.layout.HSpacer(),
                dl,
            ),
            pn.pane.Bokeh(self._build(), sizing_mode="stretch_both", min_height=340),
            sizing_mode="stretch_both",
        )
        return self._layout

    def _what(self) -> str:
        return self.case.dof if self.truncation.map_mode == "selected DOF" else "maxdof"

    def _meta(self) -> dict:
        c, t = self.case, self.truncation
        return {
            "view": "truncation error map (thesis eq. 5.1, figs. 5.3/5.6/5.7)",
            "harmonic": c.harmonic,
            "coupling": c.coupling,
            "response DOF": f"bushing:{c.dof}"
            if t.map_mode == "selected DOF"
            else "max over 6 DOFs",
            "reference": "all tire modes",
            "layout": "long: one row per (N, centre freq)",
        }

    def _csv_columns(self) -> dict:
        d = self.data()
        nn, ff = np.meshgrid(d["n_modes"], d["centre_freq"], indexing="ij")
        return {
            "n_modes": nn.ravel(),
            "centre_freq_Hz": ff.ravel(),
            "error_pct": d["error_pct"].ravel(),
        }


class SuggestedModesView(Viewer):
    """Suggested number of modes for all seven harmonics (thesis table 5.1)."""

    case = param.ClassSelector(class_=CaseState)
    truncation = param.ClassSelector(class_=TruncationState)

    def table(self) -> dict:
        c, t = self.case, self.truncation
        return compute.suggested_table(
            float(t.threshold),
            float(t.f_max),
            c.coupling,
            c.dof if t.map_mode == "selected DOF" else None,
            c.models,
        )

    def table_frame(self):
        """The suggested-modes table as a DataFrame (what the Tabulator shows)."""
        import pandas as pd

        tab = self.table()
        return pd.DataFrame(
            {
                "Harmonic": tab["harmonic"],
                "Band (Hz)": [
                    f"{a:.1f}-{b:.1f}" for a, b in zip(tab["f_low"], tab["f_high"], strict=True)
                ],
                "Suggested N": tab["n_modes"],
                "Highest eigenfreq. (Hz)": tab["eigenfrequency"].round(1),
            }
        )

    def __panel__(self):
        c, t = self.case, self.truncation
        table = pn.widgets.Tabulator(
            self.table_frame(),
            disabled=True,
            show_index=False,
            selectable=False,
            sizing_mode="stretch_width",
            css_classes=["suggested-table"],
            layout="fit_data_stretch",
            theme="bootstrap5",
        )

        def refresh(*events):
            if all(e.name == "dof" for e in events) and t.map_mode != "selected DOF":
                return  # the table judges the maximum over DOFs: nothing to do
            frame = self.table_frame()
            if not frame.equals(table.value):  # a re-sent table costs the browser a redraw
                table.value = frame

        t.param.watch(refresh, ["threshold", "f_max", "map_mode"])
        c.param.watch(refresh, ["coupling", "dof", "models"])
        dl = download_button(
            "suggested",
            self._csv_table,
            self._meta_table,
            lambda: f"suggested_modes_thr{t.threshold:g}_fmax{t.f_max:g}.csv",
        )

        def caption_text() -> str:
            where = "bushing:" + c.dof if t.map_mode == "selected DOF" else t.map_mode
            return (
                f"Smallest N from which the error stays below **{t.threshold:g} %** up "
                f"to **{t.f_max:g} Hz** ({where}), and the highest eigenfrequency among "
                "those modes at 80 km/h."
            )

        caption = live_text(
            caption_text,
            [(t, ["threshold", "f_max", "map_mode"]), (c, ["dof"])],
            styles={"color": "#495057"},
        )
        return pn.Column(pn.Row(caption, dl), table, sizing_mode="stretch_both")

    def _meta_table(self) -> dict:
        c, t = self.case, self.truncation
        return {
            "view": "suggested number of modes (thesis table 5.1)",
            "threshold_pct": t.threshold,
            "f_max_Hz": t.f_max,
            "coupling": c.coupling,
            "response DOF": f"bushing:{c.dof}"
            if t.map_mode == "selected DOF"
            else "max over 6 DOFs",
            "eigenfrequency": "highest retained eigenfrequency at 80 km/h",
        }

    def _csv_table(self) -> dict:
        tab = self.table()
        return {
            "harmonic": tab["harmonic"],
            "f_low_Hz": tab["f_low"],
            "f_high_Hz": tab["f_high"],
            "n_modes": tab["n_modes"],
            "eigenfrequency_Hz": tab["eigenfrequency"],
        }


class EigenView(Viewer):
    """Highest retained eigenfrequency versus number of modes at 20/80/120 km/h (fig. 5.8)."""

    case = param.ClassSelector(class_=CaseState)
    n_range = param.Parameter(
        default=None,
        doc="Retained-modes range shared with the "
        "truncation map's N axis (linked zoom); own if None.",
    )

    def __init__(self, **params):
        super().__init__(**params)
        self._layout = None
        self._push = Pusher()

    def data(self) -> dict:
        return compute.eigen_curves(self.case.models)

    def _build(self):
        fig = new_figure(
            x_label=MODES_LABEL,
            y_label="Highest retained eigenfrequency (Hz)",
            title="Eigenfrequency vs mode number",
            min_height=300,
            name="eigen.figure",
            x_range=self.n_range,
        )
        self._srcs = {
            k: add_line(
                fig,
                f"eigen.{k}",
                color=col,
                legend=lab,
                x="n_modes",
                y="eigenfrequency",
                legend_location="top_left",
                tooltips=[
                    ("Speed", lab),
                    ("N", "@n_modes"),
                    ("Eigenfrequency", "@eigenfrequency{0.0} Hz"),
                ],
            )
            for k, (lab, col) in EIGEN_STYLES.items()
        }
        self._marker = add_span(
            fig, dimension="height", color=COLORS["round"], name="eigen.chosen_n"
        )
        self._apply(self.data(), self.case.n_modes)()
        self.case.param.watch(self._changed, ["models", "n_modes"])
        return fig

    def _apply(self, d: dict, n_modes: int):
        def update():
            for k, src in self._srcs.items():
                if not _same_columns(src.data, {"n_modes": d["n_modes"], "eigenfrequency": d[k]}):
                    src.data = {"n_modes": d["n_modes"], "eigenfrequency": d[k]}
            self._marker.location = float(n_modes)

        return update

    def _changed(self, *events):
        self._push(lambda: self._apply(self.data(), self.case.n_modes))

    def __panel__(self):
        if self._layout is not None:
            return self._layout
        dl = download_button(
            "eigen",
            self._csv_columns,
            lambda: {
                "view": "highest retained eigenfrequency vs N (thesis fig. 5.8)",
                "models": self.case.models.describe(),
            },
            lambda: "eigenfrequency_vs_modes.csv",
        )
        self._layout = pn.Column(
            pn.Row(
                pn.pane.Markdown(
                    "Highest eigenfrequency among N retained modes (N/2 +/- pairs, lowest first).",
                    margin=(0, 10),
                    styles={"color": "#495057", "font-size": "0.9em"},
                ),
                pn.layout.HSpacer(),
                dl,
            ),
            pn.pane.Bokeh(self._build(), sizing_mode="stretch_both", min_height=300),
            sizing_mode="stretch_both",
        )
        return self._layout

    def _csv_columns(self) -> dict:
        d = self.data()
        return {
            "n_modes": d["n_modes"],
            "f_20kmh_Hz": d["f_20"],
            "f_80kmh_Hz": d["f_80"],
            "f_120kmh_Hz": d["f_120"],
        }
