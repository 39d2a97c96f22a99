"""Contributions of the six interface forces to the bushing response (eq. 4.1 term by term).

Lines: the level of each term ``Y_ej^E[bushing, spindle:d] g_d`` and of their sum (the
coupled response). Stacked: each term's share of the total, ``Re(t conj(T)) / |T|^2`` in
percent (the shares add up to 100 % at every line; a term in anti-phase with the total
counts negative), answering "is it the vertical force or the wind-up moment?".
"""

from __future__ import annotations

import numpy as np
import panel as pn
from bokeh.models import ColumnDataSource, HoverTool, Range1d, Span

from fbs_core.vocabulary import DIRECTIONS, percent

from .analysis_base import PICK_COLOR, TERM_COLORS, AnalysisView
from .common import COLORS, level_label, level_tooltips
from .layout import plot_rows
from .plots import add_line

__all__ = ["ContributionsView"]

#: Near an antiresonance the total is small and the terms' shares of it reach +-1000 % and
#: more over a few lines, which flattened the rest: the axis then spans the central part of
#: the stacked edges (these percentiles over the lines) and 0-100 %.
CLIP_PERCENTILES = (2.0, 98.0)
#: ... when the values reach beyond that central part by more than this share of its span.
CLIP_BEYOND = 0.5


def share_range(edges: np.ndarray) -> tuple[float, float, bool]:
    """The y range of the stacked shares ``edges`` (%, any shape): ``(low, high, cut)``.

    All values and 0-100 %, padded by 8 %, unless they reach beyond the central
    :data:`CLIP_PERCENTILES` (and 0-100 %) by more than :data:`CLIP_BEYOND` of its span:
    then that central part, padded, and ``cut`` is True.
    """
    finite = edges[np.isfinite(edges)]
    if finite.size == 0:
        return -10.0, 110.0, False
    lo, hi = np.percentile(finite, CLIP_PERCENTILES)
    lo, hi = min(float(lo), 0.0), max(float(hi), 100.0)
    reach = CLIP_BEYOND * (hi - lo)
    cut = bool(finite.min() < lo - reach or finite.max() > hi + reach)
    if not cut:
        lo, hi = min(lo, float(finite.min())), max(hi, float(finite.max()))
    pad = 0.08 * (hi - lo)
    return lo - pad, hi + pad, cut


class ContributionsView(AnalysisView):
    """Bushing response split into the contributions of the hub forces and moments."""

    key = "contributions"
    result_name = "contributions"
    css_height = plot_rows(1)

    def _controls(self):
        return [
            pn.widgets.RadioButtonGroup.from_param(
                self.store.state.analysis.param.contrib_mode,
                name="",
                width=160,
                css_classes=["ctl-analysis-contrib_mode"],
            )
        ]

    def _build(self):
        self._lines_fig = fig = self._frequency_figure(
            "contributions.figure", level_label("z"), 300
        )
        # one source for the six terms and the total: one patch per change
        self._lines = ColumnDataSource(
            {
                "freq": np.zeros(0),
                **{f"hub_{d}": np.zeros(0) for d in DIRECTIONS},
                "total": np.zeros(0),
            },
            name="contributions.lines",
        )
        for d, color in zip(DIRECTIONS, TERM_COLORS, strict=True):
            add_line(
                fig,
                "",
                y=f"hub_{d}",
                source=self._lines,
                color=color,
                legend=f"hub:{d}",
                width=1.6,
                tooltips=level_tooltips(f"force at hub:{d}", f"hub_{d}"),
                legend_location="bottom_right",
            )
        add_line(
            fig,
            "",
            y="total",
            source=self._lines,
            color=COLORS["reference"],
            legend="total (eq. 4.1)",
            width=2.6,
            tooltips=level_tooltips("total", "total"),
            legend_location="bottom_right",
        )
        # stacked shares: one source, a varea per term between cumulative columns
        self._stack = ColumnDataSource(
            {"freq": np.zeros(0), **{f"c{k}": np.zeros(0) for k in range(len(DIRECTIONS) + 1)}},
            name="contributions.stacked",
        )
        self._stack_range = Range1d(-10.0, 110.0, name="contributions.share_range")
        self._stack_fig = sf = self._frequency_figure(
            "contributions.stacked_figure",
            "Share of the total (%)",
            300,
            y_range=self._stack_range,
        )
        for k, (d, color) in enumerate(zip(DIRECTIONS, TERM_COLORS, strict=True)):
            sf.varea(
                "freq",
                f"c{k}",
                f"c{k + 1}",
                source=self._stack,
                fill_color=color,
                fill_alpha=0.7,
                legend_label=f"hub:{d}",
            )
        sf.add_tools(
            HoverTool(
                tooltips=[("Frequency", "@freq{0.0} Hz")]
                + [(f"hub:{d}", f"@s{k}{{0.0}} %") for k, d in enumerate(DIRECTIONS)],
                mode="vline",
            )
        )
        sf.legend.location = "bottom_right"
        sf.legend.click_policy = "hide"
        self._picks = [
            Span(
                location=0,
                dimension="height",
                line_color=PICK_COLOR,
                line_dash="dotted",
                line_width=2,
                visible=False,
                name="contributions.pick",
            )
            for _ in range(2)
        ]
        fig.add_layout(self._picks[0])
        sf.add_layout(self._picks[1])
        sf.visible = False
        # two figures, one shown at a time, each with its own title block
        return [fig, sf]

    def _draw(self, r):
        c, d = r.columns, r.draw
        f = c["freq_Hz"]
        interface = [j.split(":")[1] for j in d["interface"]]
        stacked = d["mode"] == "stacked"
        # only the shown figure's data travel (a change of mode is a new result: redrawn)
        if not stacked:
            empty = np.full(f.size, np.nan)
            self._lines.data = {
                "freq": f,
                **{f"hub_{d}": c[f"hub_{d}_dB"] if d in interface else empty for d in DIRECTIONS},
                "total": c["total_dB"],
            }
        else:
            cum = np.zeros(f.size)
            stack = {"freq": f, "c0": cum.copy()}
            for k, dof in enumerate(DIRECTIONS):
                share = percent(c[f"hub_{dof}_share"]) if dof in interface else np.zeros(f.size)
                stack[f"s{k}"] = share
                cum = cum + share
                stack[f"c{k + 1}"] = cum.copy()
            self._stack.data = stack
            edges = np.stack([stack[f"c{k + 1}"] for k in range(len(DIRECTIONS))])
            lo, hi, cut = share_range(edges)
            self._stack_range.update(start=lo, end=hi, reset_start=lo, reset_end=hi)
            self._stack_fig.title.text = (
                f"Axis cut at {lo:.0f}..{hi:.0f} %: shares reach {np.nanmin(edges):.0f}.."
                f"{np.nanmax(edges):.0f} % near antiresonances"
                if cut
                else ""
            )
        self._stack_fig.visible = stacked
        self._lines_fig.visible = not stacked
        self._lines_fig.yaxis.axis_label = level_label(d["dof"])
        self._fit(self.x_range, f)

    def _draw_pick(self, pick):
        f = pick.get("freq")
        for s in self._picks:
            s.visible = f is not None
            if f is not None:
                s.location = f
