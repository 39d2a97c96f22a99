"""Compare: pin the current state as a named baseline (up to four), change anything, and see
the pinned coupled responses overlaid on the current one with the difference in dB, the
scatter bands' percentile edges, and the truncation error map as a difference map (current
minus a chosen pin, percentage points; its colours clipped at the 95th percentile of the
cells that differ, the clipping said in its title and colour bar). Pins are in the URL
(``pins=``), the CSV (one row per curve and line, each curve's settings and provenance in the
header) and the report.
"""

from __future__ import annotations

import numpy as np
import panel as pn
from bokeh.layouts import column, row
from bokeh.models import ColumnDataSource, FixedTicker, HoverTool
from bokeh.palettes import RdBu11

from fbs_core.analysis import MAX_PINS
from fbs_core.vocabulary import magnitude_db

from ..page.bokeh import wrap_line
from .analysis_base import PICK_COLOR, TERM_COLORS, AnalysisView
from .analysis_speed import _pick_spans
from .common import COLORS, level_label
from .layout import plot_rows, weight
from .plots import add_image, set_data

#: Characters per line of the error map's title (its type in a half-width plot at 1280 px).
TITLE_CHARS = 56

__all__ = ["CompareView"]

#: The current state, then the pins (not the orange next to the current state's colour).
CURVE_COLORS = (COLORS["truncated"],) + tuple(
    c for i, c in enumerate(TERM_COLORS) if i not in (1, 5)
)[:MAX_PINS]
#: A difference map whose largest value is below this (percentage points) is zero: the two
#: maps are the same (eq. 5.1 does not depend on N, the pinned state may differ in N only).
SAME_MAP_PP = 1e-9


class CompareView(AnalysisView):
    """Pinned baselines against the current state."""

    key = "compare"
    result_name = "compare"
    css_height = plot_rows(1.8)

    def __init__(self, **params):
        super().__init__(**params)
        self._unpin: pn.widgets.Select | None = None  # the header's widgets, once built
        self.store.param.watch(lambda _e: self._sync_widgets(), ["pins", "message"])

    def _controls(self):
        a = self.store.state.analysis
        self._name = pn.widgets.TextInput(
            label="Name of the pin",
            placeholder="e.g. baseline",
            width=160,
            css_classes=["ctl-analysis-pin_name"],
        )
        self._pin_btn = pn.widgets.Button(
            label="Pin current state", width=150, css_classes=["ctl-analysis-pin"], align="end"
        )
        self._unpin = pn.widgets.Select(
            label="Pinned", options=[], width=130, css_classes=["ctl-analysis-unpin"]
        )
        self._unpin_btn = pn.widgets.Button(
            label="Unpin", width=80, css_classes=["ctl-analysis-unpin_btn"], align="end"
        )
        self._against = pn.widgets.Select(
            label="Error map against",
            options=[],
            width=150,
            css_classes=["ctl-analysis-compare_to"],
        )
        self._msg = pn.pane.HTML(
            "",
            styles={"color": "#c92a2a"},
            sizing_mode="stretch_width",
            min_width=200,
            css_classes=["analysis-pin-message"],
        )
        # the name as typed so far: the field's value arrives with its blur, which the click
        # on the button causes, and the two may be handled on two threads in either order
        self._pin_btn.on_click(
            lambda _e: self.store.pin(self._name.value_input or self._name.value or "")
        )
        self._unpin_btn.on_click(
            lambda _e: self._unpin.value and self.store.unpin(self._unpin.value)
        )

        def chosen(e):
            if e.new is not None and a.compare_to != e.new:
                a.compare_to = e.new

        self._against.param.watch(chosen, "value")
        self._sync_widgets()
        return [self._name, self._pin_btn, self._unpin, self._unpin_btn, self._against, self._msg]

    def _sync_widgets(self):
        if self._unpin is None:
            return
        names = [p.name for p in self.store.pins]

        def update():
            self._unpin.options = names
            self._against.options = names
            want = self.store.state.analysis.compare_to
            if names:
                self._against.value = want if want in names else names[0]
            self._msg.object = self.store.message

        doc = self._doc
        if doc is None:
            update()
        else:
            pn.state.execute(update, schedule=True)

    def _build(self):
        spectrum = self._frequency_figure
        self._lv = lv = spectrum("compare.levels", level_label("z"), 250)
        self._df = df = spectrum(
            "compare.diff",
            "Current minus pin (dB)",
            200,
            title="Difference of the levels: current minus each pin (dB)",
        )
        self._bd = bd = spectrum(
            "compare.band",
            level_label("z", "Band level"),
            250,
            title="Scatter band: current band and the pins' percentile edges",
        )
        self._mp = mp = spectrum(
            "compare.map_figure", "Retained modes N", 200, title="Error map: current minus pin"
        )
        self._curves, self._diffs, self._bands = [], [], []
        for i, color in enumerate(CURVE_COLORS):
            label = "current" if i == 0 else f"pin {i}"
            src = ColumnDataSource({"freq": [], "level": []}, name=f"compare.curve{i}")
            r = lv.line(
                "freq",
                "level",
                source=src,
                line_color=color,
                line_width=2.4 if i == 0 else 1.8,
                line_dash="solid" if i == 0 else "dashed",
                legend_label=label,
            )
            lv.add_tools(
                HoverTool(
                    renderers=[r],
                    mode="vline",
                    tooltips=[
                        ("", label),
                        ("Frequency", "@freq{0.0} Hz"),
                        ("Level", "@level{0.0} dB"),
                    ],
                )
            )
            self._curves.append((src, lv.legend.items[-1]))
            b = ColumnDataSource({"freq": [], "low": [], "high": []}, name=f"compare.band{i}")
            if i == 0:
                bd.varea(
                    "freq",
                    "low",
                    "high",
                    source=b,
                    fill_color=COLORS["band"],
                    fill_alpha=0.4,
                    legend_label="current",
                )
            else:
                bd.line(
                    "freq",
                    "low",
                    source=b,
                    line_color=color,
                    line_dash="dashed",
                    legend_label=label,
                )
                bd.line(
                    "freq",
                    "high",
                    source=b,
                    line_color=color,
                    line_dash="dashed",
                    legend_label=label,
                )
            self._bands.append((b, bd.legend.items[-1]))
            if i:
                d = ColumnDataSource({"freq": [], "diff": []}, name=f"compare.diff{i}")
                r = df.line(
                    "freq", "diff", source=d, line_color=color, line_width=1.8, legend_label=label
                )
                df.add_tools(
                    HoverTool(
                        renderers=[r],
                        mode="vline",
                        tooltips=[
                            ("", label),
                            ("Frequency", "@freq{0.0} Hz"),
                            ("Difference", "@diff{0.00} dB"),
                        ],
                    )
                )
                self._diffs.append((d, df.legend.items[-1]))
        for fig in (lv, df, bd):
            fig.legend.location = "bottom_left"
            fig.legend.click_policy = "hide"
            fig.legend.label_text_font_size = "8pt"
        self._img, self._mapper, self._bar = add_image(
            mp,
            "compare.map",
            tooltips=[("Centre", "$x{0.0} Hz"), ("N", "$y{0}"), ("Difference", "@image{0.0} pp")],
            colorbar_title="pp",
        )
        self._mapper.palette = tuple(reversed(RdBu11))
        self._map_glyph = mp.renderers[-1]
        self._spans = [
            _pick_spans(f, f"compare.{k}")[0]
            for k, f in (("levels", lv), ("diff", df), ("band", bd))
        ]
        for s in self._spans:
            s.line_color = PICK_COLOR
        weight(lv, 1.6)  # it carries the title block
        return [
            row(
                column(lv, df, sizing_mode="stretch_both"),
                column(bd, mp, sizing_mode="stretch_both"),
                sizing_mode="stretch_both",
            )
        ]

    def _draw(self, r):
        d = r.draw
        curves = d["curves"]
        empty = {"freq": np.zeros(0), "level": np.zeros(0)}
        # the curves and their differences first (what the tab is read for), then the bands
        for i, (src, item) in enumerate(self._curves):
            c = curves[i] if i < len(curves) else None
            set_data(src, {"freq": c["freq"], "level": c["level"]} if c else empty)
            item.label = {"value": c["name"] if c else ("current" if i == 0 else f"pin {i}")}
            item.visible = c is not None
        for i, (src, item) in enumerate(self._diffs, start=1):
            c = curves[i] if i < len(curves) else None
            set_data(
                src,
                {"freq": c["freq"], "diff": c["diff"]}
                if c is not None
                else {"freq": np.zeros(0), "diff": np.zeros(0)},
            )
            item.visible = c is not None
            if c is not None:
                item.label = {"value": c["name"]}
        for i, (src, item) in enumerate(self._bands):
            c = curves[i] if i < len(curves) else None
            if c is not None and c["band"] is not None:
                src.data = {
                    "freq": c["freq"],
                    "low": magnitude_db(c["band"][0]),
                    "high": magnitude_db(c["band"][1]),
                }
            else:
                set_data(src, {"freq": np.zeros(0), "low": np.zeros(0), "high": np.zeros(0)})
            item.visible = c is not None and c["band"] is not None
            if c is not None:
                item.label = {"value": c["name"]}
        m = d["map"]
        if m is not None:
            e = m["diff_pct"]
            c, n = m["centres"], m["n_modes"]
            dc = float(c[1] - c[0]) if c.size > 1 else 1.0
            dn = float(n[1] - n[0]) if n.size > 1 else 10.0
            self._img.data = {
                "image": [np.ascontiguousarray(e)],
                "x": [float(c[0] - dc / 2)],
                "y": [float(n[0] - dn / 2)],
                "dw": [float(c[-1] - c[0] + dc)],
                "dh": [float(n[-1] - n[0] + dn)],
            }
            lim, beyond = float(m["scale_pp"]), int(m["beyond"])
            title = f"Error map: current minus pin {m['pin']!r} ({m['what']})"
            if lim < SAME_MAP_PP:  # a colour scale of +-1e-6 pp drew a grey box: say it
                lim, beyond = 1.0, 0
                title = f"Error map: no difference to pin {m['pin']!r} (identical maps)"
            elif beyond:
                title += (
                    f"; colours clipped at \u00b1{lim:.3g} pp: {beyond} cells beyond, "
                    f"up to \u00b1{m['largest_pp']:.4g} pp"
                )
            self._mapper.update(low=-lim, high=lim)
            ticks = [float(t) for t in np.linspace(-lim, lim, 5)]
            self._bar.ticker = FixedTicker(ticks=ticks)
            self._bar.major_label_overrides = (
                {ticks[0]: f"\u2264 {-lim:.3g}", ticks[-1]: f"\u2265 {lim:.3g}"} if beyond else {}
            )
            # on lines that fit a half-width plot (one long line widened the page)
            self._mp.title.text = "\n".join(wrap_line(title, TITLE_CHARS))
            self._map_glyph.visible = self._bar.visible = True
        else:
            self._img.data = {
                "image": [np.zeros((1, 1))],
                "x": [0.0],
                "y": [0.0],
                "dw": [1.0],
                "dh": [1.0],
            }
            self._mp.title.text = "Error map: no difference map (pin a state of this harmonic)"
            self._map_glyph.visible = self._bar.visible = False
        self._lv.yaxis.axis_label = level_label(d["dof"])
        self._fit(self.x_range, curves[0]["freq"])

    def _draw_pick(self, pick):
        f = pick.get("freq")
        for s in self._spans:
            s.visible = f is not None
            if f is not None:
                s.location = f
