"""Vehicle scope: the contribution of each wheel's road to the car's response.

The four lines are the levels of ``VehicleResponse.by_wheel`` at the response point (the
road under each wheel, a wheelbase apart front to rear, the right track in phase, in
anti-phase or partially coherent with the left), the thick line their sum: the coupled
response view's truncated curve (N modes). Where two wheels' contributions are of equal
level and opposite phase the total drops below both (wheelbase filtering). A wheel whose
road input is off contributes exact zeros, which have no level: its line and legend entry
are hidden, so the axis spans the driven wheels' levels only.
"""

from __future__ import annotations

import numpy as np
import panel as pn
import param
from bokeh.models import ColumnDataSource

from fbs_core.vehicle import WHEELS

from .analysis_base import TERM_COLORS
from .common import COLORS, FREQ_LABEL, level_label, level_tooltips
from .live import LiveView
from .plots import add_line, frequency_range, new_figure

__all__ = ["WheelContributionsView", "wheels_card"]


class WheelContributionsView(LiveView):
    """The level of each wheel's contribution and of their sum versus frequency."""

    key = "wheels"
    result_name = "wheel_contributions"
    x_range = param.Parameter(default=None, doc="Shared frequency range; a new one if None.")

    def _build(self):
        if self.x_range is None:
            self.x_range = frequency_range()
        self._fig = fig = new_figure(
            x_label=FREQ_LABEL, y_label=level_label("z"), x_range=self.x_range, name="wheels.figure"
        )
        # one source for the four wheels and the total: one patch per change
        self._src = ColumnDataSource(
            {"freq": np.zeros(0), **{w: np.zeros(0) for w in WHEELS}, "total": np.zeros(0)},
            name="wheels.lines",
        )
        for w, color in zip(WHEELS, TERM_COLORS, strict=False):
            add_line(
                fig,
                "",
                y=w,
                source=self._src,
                color=color,
                legend=f"road under {w.upper()}",
                width=1.6,
                tooltips=level_tooltips(f"wheel {w.upper()}", w),
                legend_location="bottom_right",
            )
        add_line(
            fig,
            "",
            y="total",
            source=self._src,
            color=COLORS["reference"],
            legend="total (N modes)",
            width=2.6,
            tooltips=level_tooltips("total", "total"),
            legend_location="bottom_right",
        )
        # a wheel whose road input is off has no level: its line and legend entry are hidden
        self._lines = {r.glyph.y: r for r in fig.renderers if r.glyph.y in WHEELS}
        return [fig]

    def _draw(self, r):
        c = r.columns
        f = c["freq_Hz"]
        gap = np.full(np.shape(f), np.nan)  # an off wheel: no level, nothing for the axis
        self._src.data = {
            "freq": f,
            **{w: c.get(f"{w}_dB", gap) for w in WHEELS},
            "total": c["total_dB"],
        }
        on = set(r.draw["wheels"])
        for w, line in self._lines.items():
            if line.visible != (w in on):
                line.visible = w in on
        for item in self._fig.legend[0].items:
            w = next((x for x, ln in self._lines.items() if ln in item.renderers), None)
            if w is not None and item.visible != (w in on):
                item.visible = w in on
        self._fig.yaxis.axis_label = level_label(r.draw["dof"])
        self._fit(self.x_range, f)


def wheels_card(parts) -> pn.Card:
    """The card of the per-wheel contributions, shown in vehicle scope only."""
    case = parts.state.case
    view = WheelContributionsView(store=parts.results, x_range=parts.freq, mode=parts.page.view)
    card = parts.card(
        "Vehicle: contribution of each wheel's road to the response (eq. 4.1)",
        view,
        css_classes=["wheels-card"],
    )
    card.visible = case.scope == "vehicle"
    case.param.watch(lambda e: setattr(card, "visible", e.new == "vehicle"), "scope")
    return card
