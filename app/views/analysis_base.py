"""Shared base of the Analysis card's views.

An :class:`AnalysisView` is a :class:`~app.views.live.LiveView` that draws a result of the
session's store (:mod:`app.store`: the rows computed while their tab is shown) and shows
the picked speed / frequency (the ``pick`` result) as markers. The card with one tab per
view is :func:`app.views.analysis_card.analysis_card`.
"""

from __future__ import annotations

import param

from .common import FREQ_LABEL
from .live import LiveView
from .plots import frequency_range, new_figure

__all__ = ["PICK_COLOR", "TERM_COLORS", "AnalysisView"]

#: Colours of the six interface DOFs' terms hub:x ... hub:rz (and of pins): the Okabe-Ito
#: palette without its yellow, distinct also for colour-blind readers (the earlier
#: palette's hub:x and hub:rz were two blues; tests/test_app_palette.py measures it).
TERM_COLORS = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00")
PICK_COLOR = "#c2255c"


class AnalysisView(LiveView):
    """A view of an analysis result; redrawn when its result or the pick changes."""

    x_range = param.Parameter(default=None, doc="Shared frequency range (linked zoom).")
    also = ("pick",)

    def _apply(self):
        super()._apply()
        if not self.store.closed and self.result() is not None:
            self._draw_pick(self.store.pick.draw)

    def _draw_pick(self, pick: dict) -> None:
        """Show the picked speed / frequency (``None``: not picked)."""

    def _frequency_figure(self, name: str, y_label: str, min_height: int, **kw):
        """A figure over frequency on the views' shared (linked-zoom) frequency range,
        created with the first such figure (review D1/D7: the views' common set-up)."""
        if self.x_range is None:
            self.x_range = frequency_range()
        return new_figure(
            x_label=FREQ_LABEL,
            y_label=y_label,
            x_range=self.x_range,
            name=name,
            min_height=min_height,
            **kw,
        )
