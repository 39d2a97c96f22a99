"""Across speed: the Campbell diagram of the tire and the bushing level over speed and
frequency for the chosen harmonic.

Campbell: every tracked tire mode pair's eigenfrequency over 20-120 km/h
(:func:`fbs_core.analysis.campbell`) in one colour, and the order lines ``f = v / lambda``
of the seven harmonic cases (solid inside the case's speed range, dotted outside; the
chosen case thicker). The branches carry no direction of travel: the modal model tracks
its modes for the interpolation, and they pass between forward and backward waves at the
veerings (docs/modes.md), so a label by slope would claim what is not known; the Modes
tab's Campbell diagram of the belt waves follows the waves.

Speed map: ``20 log10 |v_e*|`` at the chosen bushing DOF for the tire at fixed speeds under
the chosen case's road wavelength (:func:`fbs_core.analysis.speed_map`), with the harmonic
line ``f = v / lambda`` (where the coupled-response view lives).

Picking: a click in either plot picks that speed and frequency (``pv`` / ``pf`` in the
URL): a cross-hair here, a dotted frequency marker in the phase, contributions and compare
views. A click on an order line of a case inside its speed range (within 3 % in frequency)
in the Campbell diagram also chooses that harmonic case.
"""

from __future__ import annotations

import numpy as np
import panel as pn
from bokeh.events import Tap
from bokeh.models import ColumnDataSource, HoverTool, Span
from bokeh.palettes import Viridis256

from .analysis_base import PICK_COLOR, AnalysisView
from .layout import plot_rows
from .plots import add_image, new_figure, set_data

__all__ = ["CampbellView", "SpeedMapView", "speed_tab"]

#: The tracked branches' one colour (no direction of travel is known for them).
BRANCH_COLOR = "#1971c2"
ORDER_COLOR = "#2b2b2b"
SPEED_LABEL = "Speed (km/h)"
FREQ_LABEL = "Frequency (Hz)"


def _pick_spans(fig, name):
    spans = []
    for dim in ("height", "width"):
        s = Span(
            location=0,
            dimension=dim,
            line_color=PICK_COLOR,
            line_dash="dotted",
            line_width=2,
            visible=False,
            name=f"{name}.pick_{dim}",
        )
        fig.add_layout(s)
        spans.append(s)
    return spans


def _show_pick(spans, pick):
    for s, value in zip(spans, (pick.get("speed"), pick.get("freq")), strict=True):
        s.visible = value is not None
        if value is not None:
            s.location = value


class CampbellView(AnalysisView):
    """Tire eigenfrequencies vs speed (the tracked branches) and order lines."""

    key = "campbell"
    result_name = "campbell"
    css_height = plot_rows(1)

    def _build(self):
        self._fig = fig = new_figure(
            x_label=SPEED_LABEL, y_label=FREQ_LABEL, name="campbell.figure", min_height=440
        )
        src = ColumnDataSource({"xs": [], "ys": [], "branch": []}, name="campbell.modes")
        r = fig.multi_line(
            "xs", "ys", source=src, line_color=BRANCH_COLOR, line_width=1.4,
            legend_label="tire modes (no direction of travel: see Modes, waves)",
        )  # fmt: skip
        fig.add_tools(HoverTool(renderers=[r], tooltips=[("mode pair", "@branch")]))
        self._branches = {"modes": src}
        self._orders = ColumnDataSource(
            {"xs": [], "ys": [], "harmonic": [], "width": []}, name="campbell.orders"
        )
        r = fig.multi_line(
            "xs",
            "ys",
            source=self._orders,
            line_color=ORDER_COLOR,
            line_width="width",
            line_alpha=0.8,
        )
        fig.add_tools(HoverTool(renderers=[r], tooltips=[("order line of harmonic", "@harmonic")]))
        self._order_out = ColumnDataSource({"xs": [], "ys": []}, name="campbell.orders_out")
        fig.multi_line(
            "xs",
            "ys",
            source=self._order_out,
            line_color=ORDER_COLOR,
            line_dash="dotted",
            line_width=1,
            line_alpha=0.5,
        )
        fig.legend.location = "top_left"
        fig.legend.click_policy = "hide"
        fig.on_event(Tap, self._tapped)
        self._spans = _pick_spans(fig, "campbell")
        return [fig]

    def _tapped(self, event):
        if event.x is not None and event.y is not None:
            self.store.pick_campbell(float(event.x), float(event.y))

    def _draw(self, r):
        d = r.draw
        for k, src in self._branches.items():  # the same tire: nothing sent again
            b = d["branches"][k]
            set_data(src, {"xs": b["xs"], "ys": b["ys"], "branch": b["branch"]})
        v = d["speeds"]
        xs, ys, hs, ws, out_x, out_y = [], [], [], [], [], []
        for j, h in enumerate(d["harmonic"]):
            inb = d["in_band"][:, j]
            xs.append(v[inb])
            ys.append(d["lines"][inb, j])
            hs.append(h)
            ws.append(3.0 if h == d["current"] else 1.3)
            out_x.append(v)
            out_y.append(d["lines"][:, j])
        self._orders.data = {"xs": xs, "ys": ys, "harmonic": hs, "width": ws}
        set_data(self._order_out, {"xs": out_x, "ys": out_y})
        # the axes span the speeds and the seven lines' band (branches up to 450 Hz), set
        # here: the branches' gaps (NaN) are no data a range should be computed from
        self._fig.x_range.start, self._fig.x_range.end = float(v.min()), float(v.max())
        self._fig.y_range.start, self._fig.y_range.end = 0.0, 460.0

    def _draw_pick(self, pick):
        _show_pick(self._spans, pick)


class SpeedMapView(AnalysisView):
    """Bushing level over speed (x) and frequency (y) for the chosen harmonic."""

    key = "speedmap"
    result_name = "speed_map"
    css_height = plot_rows(1)

    def _build(self):
        self._fig = fig = new_figure(
            x_label=SPEED_LABEL, y_label=FREQ_LABEL, name="speedmap.figure", min_height=440
        )
        self._img, self._mapper, self._bar = add_image(
            fig,
            "speedmap.image",
            tooltips=[
                ("Speed", "$x{0.0} km/h"),
                ("Frequency", "$y{0.0} Hz"),
                ("Level", "@image{0.0} dB"),
            ],
            colorbar_title="dB",
        )
        self._mapper.palette = Viridis256
        self._line = ColumnDataSource({"speed": [], "freq": []}, name="speedmap.line")
        fig.line(
            "speed", "freq", source=self._line, line_color="white", line_dash="dashed", line_width=2
        )
        fig.on_event(Tap, self._tapped)
        self._spans = _pick_spans(fig, "speedmap")
        return [fig]

    def _tapped(self, event):
        if event.x is not None and event.y is not None:
            self.store.pick_point(float(event.x), float(event.y))

    def _draw(self, r):
        d = r.draw
        v, f, lv = d["speeds"], d["freq"], d["level"]
        dv = float(v[-1] - v[0]) if v.size > 1 else 1.0
        df = float(f[-1] - f[0]) if f.size > 1 else 1.0
        # cells centred on the grid: half a step beyond the first and last values
        sv = dv / max(v.size - 1, 1)
        sf = df / max(f.size - 1, 1)
        self._img.data = {
            "image": [np.ascontiguousarray(lv.T)],
            "x": [float(v[0] - sv / 2)],
            "y": [float(f[0] - sf / 2)],
            "dw": [dv + sv],
            "dh": [df + sf],
        }
        finite = lv[np.isfinite(lv)]
        hi = float(finite.max()) if finite.size else 0.0
        self._mapper.update(low=hi - 60.0, high=hi)
        self._bar.title = r.meta["unit"]
        self._line.data = {"speed": v, "freq": d["line_freq"]}

    def _draw_pick(self, pick):
        _show_pick(self._spans, pick)


def speed_tab(results, mode: str = "normal", views: list | None = None) -> pn.Row:
    """The "Across speed" tab: the Campbell diagram beside the speed map (in the type sizes
    of ``mode``; both views are appended to ``views``)."""
    pair = [
        CampbellView(store=results, mode=mode),
        SpeedMapView(store=results, mode=mode),
    ]
    if views is not None:
        views.extend(pair)
    return pn.Row(*pair, sizing_mode="stretch_width")
