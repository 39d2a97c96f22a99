"""Phase and peaks: Bode (level and unwrapped phase) or real / imaginary parts of the coupled
response, the tire's free hub velocity or the chassis mobility, with automatic peak labels
(frequency, level, speed on the harmonic line and the coupled system's modes nearby, which
arrive a moment later), two delta cursors and a logarithmic frequency option.

A click in either plot places a cursor (1, then 2, then 1 ...); the cursors can also be
typed (0 = off). The readout (df, dL, f2/f1) is in the caption and the CSV header.
"""

from __future__ import annotations

import numpy as np
import panel as pn
from bokeh.events import Tap
from bokeh.layouts import column
from bokeh.models import (
    ColumnDataSource,
    DataRange1d,
    HoverTool,
    LabelSet,
    LinearAxis,
    LinearScale,
    LogAxis,
    LogScale,
    Span,
)

from .analysis_base import PICK_COLOR, AnalysisView
from .common import COLORS, FREQ_LABEL, tap_cursor
from .layout import plot_rows, weight
from .plots import frequency_range, new_figure, set_data
from .typed import NumberField

__all__ = ["PhaseView"]

CURSOR_COLOR = "#5f3dc4"
#: Type of the peak labels in the normal and the presentation view.
LABEL_SIZES = {"normal": "11px", "present": "16px"}


class PhaseView(AnalysisView):
    """Bode or real/imaginary view with peak labels and delta cursors."""

    key = "phase"
    result_name = "phase"
    css_height = plot_rows(1.45)

    def __init__(self, **params):
        super().__init__(**params)
        self._next_cursor = 1
        self._drawn = None  # the result whose curves were last drawn
        a = self.store.state.analysis
        # typed cursors (Hz; 0: off), read as a person means them (app/views/typed.py)
        self._cursor_fields = [
            NumberField(
                obj=a,
                parameter=f"cursor{k}",
                label=f"Cursor {k} (Hz, 0: off)",
                css_class=f"ctl-analysis-cursor{k}",
                width=80,
                compact=True,
            )
            for k in (1, 2)
        ]
        # the modes near the peaks arrive later: only the labels change (not the curves)
        self.store.param.watch(lambda _e: self._on_document(self._apply_labels), ["peak_modes"])

    def _controls(self):
        a = self.store.state.analysis
        W = pn.widgets
        return [
            W.Select.from_param(a.param.frf, name="", width=110, css_classes=["ctl-analysis-frf"]),
            W.RadioButtonGroup.from_param(
                a.param.phase_mode, name="", width=150, css_classes=["ctl-analysis-phase_mode"]
            ),
            W.Checkbox.from_param(
                a.param.log_freq, name="log f", width=70, css_classes=["ctl-analysis-log_freq"]
            ),
            *self._cursor_fields,
        ]

    def _messages(self):
        return [f.message for f in self._cursor_fields]

    def _build(self):
        if self.x_range is None:
            self.x_range = frequency_range()
        self._top = top = new_figure(
            x_label=FREQ_LABEL,
            y_label="Level (dB)",
            x_range=self.x_range,
            y_range=DataRange1d(range_padding=0.08, only_visible=True),
            name="phase.top",
            min_height=260,
        )
        self._bottom = bottom = new_figure(
            x_label=FREQ_LABEL,
            y_label="Phase (deg)",
            x_range=self.x_range,
            name="phase.bottom",
            min_height=200,
        )
        self._src = {}
        styles = {
            "a": (COLORS["reference"], "solid", "all modes"),
            "b": (COLORS["truncated"], "dashed", "N modes"),
        }
        for key, (color, dash, label) in styles.items():
            src = ColumnDataSource(
                {"freq": np.zeros(0), "top": np.zeros(0), "bottom": np.zeros(0)},
                name=f"phase.{key}",
            )
            self._src[key] = src
            for fig, col in ((top, "top"), (bottom, "bottom")):
                r = fig.line(
                    "freq",
                    col,
                    source=src,
                    line_color=color,
                    line_width=2,
                    line_dash=dash,
                    legend_label=label,
                )
                fig.add_tools(
                    HoverTool(
                        renderers=[r],
                        mode="vline",
                        tooltips=[
                            ("", label),
                            ("Frequency", "@freq{0.00} Hz"),
                            ("Value", f"@{col}{{0.00}}"),
                        ],
                    )
                )
        for fig in (top, bottom):
            fig.legend.location = "bottom_left"
            fig.legend.click_policy = "hide"
            fig.legend.label_text_font_size = "9pt"
        self._peaks = ColumnDataSource(
            {"freq": [], "level": [], "text": [], "align": [], "dx": []}, name="phase.peaks"
        )
        top.scatter(
            "freq",
            "level",
            source=self._peaks,
            size=8,
            marker="inverted_triangle",
            color=COLORS["truncated"],
        )
        self._labels = LabelSet(
            x="freq",
            y="level",
            text="text",
            source=self._peaks,
            # below the marker, towards the middle of the plot: a label above the highest
            # peak was cut at the top of the plot, one at the right end at its right edge
            x_offset="dx",
            y_offset=-10,
            text_align="align",
            text_baseline="top",
            text_font_size="8pt",
            background_fill_color="white",
            background_fill_alpha=0.7,
        )
        top.add_layout(self._labels)
        self._cursor_spans = []
        for fig in (top, bottom):
            spans = [
                Span(
                    location=0,
                    dimension="height",
                    line_color=CURSOR_COLOR,
                    line_width=1.5,
                    line_dash=dash,
                    visible=False,
                    name=f"phase.cursor{k + 1}",
                )
                for k, dash in enumerate(("solid", "dashed"))
            ]
            for s in spans:
                fig.add_layout(s)
            self._cursor_spans.append(spans)
        self._cursors = ColumnDataSource({"freq": [], "level": []}, name="phase.cursors")
        top.scatter("freq", "level", source=self._cursors, size=9, color=CURSOR_COLOR)
        self._pick_spans = []
        for fig in (top, bottom):
            s = Span(
                location=0,
                dimension="height",
                line_color=PICK_COLOR,
                line_dash="dotted",
                line_width=2,
                visible=False,
                name="phase.pick",
            )
            fig.add_layout(s)
            self._pick_spans.append(s)
        weight(top, 1.7)  # it carries the title block and the peak labels
        bottom.yaxis.ticker.desired_num_ticks = 4  # a short plot: ticks apart
        top.on_event(Tap, self._tapped)
        bottom.on_event(Tap, self._tapped)
        self._log = False
        return [column(top, bottom, sizing_mode="stretch_both")]

    def _tapped(self, event):
        """A click on the plot places cursor 1, the next one cursor 2, and so on."""
        self._next_cursor = tap_cursor(self.store.state.analysis, event.x, self._next_cursor)

    def _restyle_now(self) -> None:
        super()._restyle_now()
        self._labels.text_font_size = LABEL_SIZES[self.mode]

    def _set_log(self, log: bool) -> None:
        if log == self._log:
            return
        self._log = log
        for fig in (self._top, self._bottom):
            fig.x_scale = LogScale() if log else LinearScale()
            old = fig.below[0]
            new = (LogAxis if log else LinearAxis)(axis_label=old.axis_label)
            fig.below = [new]

    def _draw(self, r):
        d = r.draw
        f = d["freq"]
        bode = d["mode"] == "bode"
        curves = d["curves"]
        names = list(curves)
        slots = {"a": names[0], "b": names[1] if len(names) > 1 else None}
        for key, name in slots.items():
            if name is None:
                set_data(
                    self._src[key],
                    {"freq": np.zeros(0), "top": np.zeros(0), "bottom": np.zeros(0)},
                )
                continue
            c = curves[name]
            self._src[key].data = {
                "freq": f,
                "top": c["level"] if bode else c["re"],
                "bottom": c["phase"] if bode else c["im"],
            }
        unit = d["y_label"]
        self._top.yaxis.axis_label = unit if bode else "Real part"
        self._bottom.yaxis.axis_label = "Phase (deg)" if bode else "Imaginary part"
        self._peaks.data = self._peak_data(r)
        cur = d["cursors"]
        for spans in self._cursor_spans:
            for k, s in enumerate(spans):
                fk = d["c1"] if k == 0 else d["c2"]
                s.visible = fk > 0
                if fk > 0:
                    s.location = fk
        if cur is not None and bode:
            self._cursors.data = {"freq": [cur["f1"], cur["f2"]], "level": [cur["l1"], cur["l2"]]}
        else:
            self._cursors.data = {"freq": [], "level": []}
        self._set_log(bool(d["log"]))
        self._fit(self.x_range, f)
        self._drawn = r

    def _peak_data(self, r) -> dict:
        """The peak labels of result ``r``, with the modes nearby once they arrived."""
        d = r.draw
        bode = d["mode"] == "bode"
        labels = list(d["labels"])
        pm = self.store.peak_modes
        if pm is not None and np.array_equal(
            pm.columns["freq_Hz_of_peak"], [p["freq"] for p in d["peaks"]]
        ):  # the labels of these peaks, with the coupled modes known so far
            labels = list(pm.draw["labels"])
        peaks = d["peaks"] if bode else []
        f = d["freq"]
        lo, hi = (float(f[0]), float(f[-1])) if len(f) else (0.0, 0.0)
        mid = float(np.sqrt(lo * hi)) if d["log"] and lo > 0 else 0.5 * (lo + hi)
        right = [p["freq"] > mid for p in peaks]
        return {
            "freq": [p["freq"] for p in peaks],
            "level": [p["level"] for p in peaks],
            "text": labels if bode else [],
            "align": ["right" if r else "left" for r in right],
            "dx": [-8 if r else 8 for r in right],
        }

    def _apply_labels(self) -> None:
        r = self.result()
        if self._layout is None or self.store.closed or r is None:
            return
        if self._drawn is not r:
            # the curves of this result are not on the page yet (their draw was lost or is
            # still to come: the full suite once showed the labels over empty plots)
            self._apply()
            return
        self._peaks.data = self._peak_data(r)

    def _draw_pick(self, pick):
        f = pick.get("freq")
        for s in self._pick_spans:
            s.visible = f is not None
            if f is not None:
                s.location = f
