"""Truncation error map (thesis figs. 5.3, 5.6, 5.7), suggested modes (table 5.1) and
eigenfrequency versus mode number (fig. 5.8)."""

from __future__ import annotations

import numpy as np
import panel as pn
import param
from bokeh.core.properties import value
from bokeh.models import FixedTicker
from panel.viewable import Viewer

from ..page.bokeh import ErrorMapLayers
from ..report.colormap import LINE_STYLES, log_rows
from ..runtime.draw import on_document, served_document
from ..store import Results
from .common import COLORS, MODES_LABEL
from .live import LiveText, LiveView, download_button, inline_html
from .plots import (
    add_image,
    add_line,
    add_span,
    frequency_range,
    modes_range,
    new_figure,
    set_data,
)

#: Ticks of a logarithmic N axis (1-2-5, and the reference tire's 400).
LOG_N_TICKS = (10, 20, 50, 100, 200, 400, 1000, 2000)

#: Eigenfrequency curves of fig. 5.8: column -> (legend, colour).
EIGEN_STYLES = {
    "f_20": ("20 km/h", "#74c0fc"),
    "f_80": ("80 km/h", "#1c7ed6"),
    "f_120": ("120 km/h", "#0b3d91"),
}


def image_columns(d: dict) -> dict:
    """Image source columns of an error map: one image, cells centred on (centre, N)."""
    cf, nm = d["centre_freq"], d["n_modes"]
    dc = float(cf[1] - cf[0]) if cf.size > 1 else 1.0
    dn = float(nm[1] - nm[0]) if nm.size > 1 else 10.0
    return {
        "image": [d["error_pct"]],
        "x": [float(cf[0]) - dc / 2],
        "y": [float(nm[0]) - dn / 2],
        "dw": [dc * cf.size],
        "dh": [dn * nm.size],
    }


class TruncationView(LiveView):
    """Error over centre frequency and retained modes, colour capped at the threshold."""

    key = "truncation"
    result_name = "error_map"
    note = (
        "Error vs all modes, 12 Hz floating band; blue below the threshold (darker: larger), "
        "red at or above it, black line: the threshold contour."
    )
    x_range = param.Parameter(
        default=None,
        doc="Frequency range shared with other views (linked zoom and pan); a new one if None.",
    )
    n_range = param.Parameter(
        default=None,
        doc="Retained-modes range shared with the eigenfrequency plot; a new one if None.",
    )
    n_axis = param.Selector(
        default="linear",
        objects=["linear", "log"],
        doc="Scale of the N axis (log: the detail below N = 100 spreads out); set at build.",
    )

    def _build(self):
        if self.x_range is None:
            self.x_range = frequency_range()
        if self.n_range is None:
            self.n_range = modes_range()
        self._fig = fig = new_figure(
            x_label="Centre frequency (Hz)",
            y_label=MODES_LABEL,
            x_range=self.x_range,
            y_range=self.n_range,
            name="truncation.figure",
            y_axis_type=self.n_axis,
        )
        fig.grid.visible = False
        fig.title.visible = False  # the title block above says what the map shows
        if self.n_axis == "log":  # Bokeh's log ticks ran into each other from 150 to 400
            fig.yaxis.ticker = FixedTicker(ticks=list(LOG_N_TICKS))
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
        # colours split at the threshold, the threshold contour, lines with a halo
        self._layers = ErrorMapLayers(fig, 20.0)
        for rend in fig.renderers:
            for g in (rend.glyph, rend.nonselection_glyph, rend.selection_glyph, rend.hover_glyph,
                      rend.muted_glyph):  # fmt: skip
                if getattr(g, "color_mapper", None) is self._mapper:
                    g.color_mapper = self._layers.mapper
        self._bar.color_mapper = self._mapper = self._layers.mapper
        self._bar.title = "Error (%)"
        spans = {}
        for key, name, dim in (
            ("suggested N", "truncation.suggested_n", "width"),
            ("f_max", "truncation.f_max", "height"),
            ("chosen N", "truncation.chosen_n", "width"),
        ):
            color, dash, width, halo = LINE_STYLES[key]
            under = add_span(fig, dimension=dim, color=halo, width=width + 2.5)
            spans[key] = (
                add_span(fig, dimension=dim, color=color, dash=dash, width=width, name=name),
                under,
            )
        self._suggested, self._f_max, self._chosen = (
            spans["suggested N"],
            spans["f_max"],
            spans["chosen N"],
        )
        # legend entries (spans cannot be legend items): empty lines styled like them
        items = [("threshold contour", self._layers.contour_line)]
        for key, label in (
            ("chosen N", "chosen N"),
            ("suggested N", "suggested N"),
            ("f_max", "f_max of the suggestion"),
        ):
            color, dash, width, _ = LINE_STYLES[key]
            items.append(  # one NaN point: a legend draws no sample for an empty source
                (
                    label,
                    fig.line(
                        [np.nan], [np.nan], line_color=color, line_dash=dash, line_width=width
                    ),
                )
            )
        above = fig.scatter(
            [np.nan], [np.nan], marker="square", size=12, color=self._layers.scale.above
        )
        items.insert(0, ("at or above the threshold", above))
        self._legend = self._layers.legend(items, side="below")
        return [fig]

    def _draw(self, r):
        d = r.draw
        cols = image_columns(d["map"])
        nm = d["map"]["n_modes"]
        dn = float(nm[1] - nm[0]) if nm.size > 1 else 10.0
        top = cols["y"][0] + cols["dh"][0] + dn  # up to the all-modes count (no error)
        if self.n_axis == "log":  # rows uniform in log N: the image stretches linearly
            low, high, img = log_rows(nm, d["map"]["error_pct"], 512)
            cols = {**cols, "image": [img], "y": [low], "dh": [high - low]}
            self._fit(self.n_range, [low, top])
        else:
            self._fit(self.n_range, [cols["y"][0], top])
        set_data(self._src, cols)
        thr = float(d["threshold"])
        m = d["map"]
        self._layers.update(m["centre_freq"], m["n_modes"], m["error_pct"], thr)
        self._bar.title = f"Error (%), red: >= {thr:g} %"
        label = f"error >= {thr:g} %"
        if getattr(self._legend.items[0].label, "value", None) != label:
            self._legend.items[0].label = value(label)
        self._fig.title.text = d["title"]
        for (line, halo), loc in (
            (self._suggested, float(d["suggested_n"])),
            (self._f_max, float(d["f_max"])),
            (self._chosen, float(d["n_modes"])),
        ):
            line.location = halo.location = loc
        self._fit(self.x_range, d["freq"])


#: Headings of the suggested-modes table (its columns keep their full names in the data).
TABLE_TITLES = {
    "Harmonic": "Case",
    "Suggested N": "N",
    "N with residuals": "N, residual",
    "Highest eigenfreq. (Hz)": "Highest eig. (Hz)",
}


class SuggestedModesView(Viewer):
    """Suggested number of modes for all seven harmonics (thesis table 5.1)."""

    store = param.ClassSelector(class_=Results, doc="The session's results.")

    def __init__(self, **params):
        super().__init__(**params)
        self._layout = None
        self._doc = None
        self.store.param.watch(lambda _e: self._changed(), ["suggested"])

    @staticmethod
    def frame(r):
        """The table of a published result as a DataFrame (what the Tabulator shows)."""
        import pandas as pd

        tab = r.draw["table"]
        cols = {
            "Harmonic": tab["harmonic"],
            "Band (Hz)": [
                f"{a:.1f}-{b:.1f}" for a, b in zip(tab["f_low"], tab["f_high"], strict=True)
            ],
            "Suggested N": tab["n_modes"],
        }
        res = r.draw.get("table_residual")
        shown = tab
        if res is not None:  # both columns; the caption says which one the map shows
            cols["N with residuals"] = res["n_modes"]
            shown = res if r.draw.get("residual") else tab
        cols["Highest eigenfreq. (Hz)"] = shown["eigenfrequency"].round(1)
        return pd.DataFrame(cols)

    def _changed(self):
        if self._layout is None or self.store.closed:
            return
        on_document(self._doc, self._apply)

    def _apply(self) -> None:
        if self.store.closed:
            return
        r = self.store.suggested
        frame = self.frame(r)
        if not frame.equals(self._table.value):  # a re-sent table costs the browser a redraw
            self._table.value = frame
        self._caption.text = f"<p>{inline_html(r.caption)}</p>"

    def __panel__(self):
        if self._layout is None:
            self._doc = served_document()
            r = self.store.suggested
            self._table = pn.widgets.Tabulator(
                self.frame(r),
                disabled=True,
                show_index=False,
                selectable=False,
                sizing_mode="stretch_width",
                css_classes=["suggested-table"],
                layout="fit_data_stretch",
                # short headings: the table fits half the width of a 1280 px window
                titles=TABLE_TITLES,
                theme="bootstrap5",
            )
            self._caption = LiveText(
                f"<p>{inline_html(r.caption)}</p>", styles={"color": "#495057"}
            )
            dl = download_button("suggested", lambda: self.store.suggested)
            self._layout = pn.Column(
                pn.Row(self._caption, dl), self._table, sizing_mode="stretch_both"
            )
        return self._layout


class EigenView(LiveView):
    """Highest retained eigenfrequency versus number of modes at 20/80/120 km/h (fig. 5.8)."""

    key = "eigen"
    result_name = "eigen"
    note = "Highest eigenfrequency among N retained modes (N/2 +/- pairs, lowest first)."
    n_range = param.Parameter(
        default=None,
        doc="Retained-modes range shared with the "
        "truncation map's N axis (linked zoom); own if None.",
    )

    def _build(self):
        fig = new_figure(
            x_label=MODES_LABEL,
            y_label="Highest retained eigenfrequency (Hz)",
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
        return [fig]

    def _draw(self, r):
        d = r.draw["curves"]
        for k, src in self._srcs.items():
            new = {"n_modes": d["n_modes"], "eigenfrequency": d[k]}
            set_data(src, new)
        self._marker.location = float(r.draw["n_modes"])
