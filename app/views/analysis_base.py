"""Shared base of the Analysis card's views (issue 18) and the card itself.

An :class:`AnalysisView` is a :class:`~app.views.live.LiveView` that draws a result of the
session's :class:`~app.analysis_store.AnalysisResults` and shows the picked speed /
frequency (``AnalysisResults.pick``) as markers. :func:`analysis_card` builds the card with
one tab per view; the tab shown is ``state.analysis.tab`` (in the URL as ``atab``), and
only the shown tab's results are computed.
"""

from __future__ import annotations

import panel as pn
import param

from ..analysis_state import ANALYSIS_TABS
from ..analysis_store import AnalysisResults
from .common import FREQ_LABEL
from .live import LiveView
from .plots import frequency_range, new_figure

__all__ = ["AnalysisView", "analysis_card"]

#: Colours of the six interface DOFs' terms (and of pins).
TERM_COLORS = ("#1971c2", "#2b8a3e", "#e03131", "#f08c00", "#7048e8", "#0c8599")
PICK_COLOR = "#c2255c"
#: Height of the opened Analysis card (px).
CARD_HEIGHT = 760


class AnalysisView(LiveView):
    """A view of an analysis result; redrawn when its result or the pick changes."""

    analysis = param.ClassSelector(class_=AnalysisResults, doc="The card's results.")
    x_range = param.Parameter(default=None, doc="Shared frequency range (linked zoom).")
    #: Name of the result in AnalysisResults.
    result_name = ""

    def __init__(self, **params):
        super().__init__(**params)
        self.analysis.param.watch(lambda _e: self.redraw(), [self.result_name, "pick"])

    def result(self):
        return getattr(self.analysis, self.result_name)

    def _apply(self):
        super()._apply()
        if not self.store.closed and self.result() is not None:
            self._draw_pick(self.analysis.pick.draw)

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


def _tab_names() -> dict[str, str]:
    return {
        "compare": "Compare",
        "phase": "Phase and peaks",
        "speed": "Across speed",
        "contributions": "Contributions",
    }


def analysis_card(results, x_range=None, tabs: dict | None = None) -> pn.Card:
    """The "Analysis" card: one tab per analysis view, computed only while shown.

    ``tabs`` maps tab keys (:data:`~app.analysis_state.ANALYSIS_TABS`) to a function
    ``(analysis_results, x_range) -> viewable``; default all views of the card.
    """
    from .analysis_compare import CompareView
    from .analysis_contrib import ContributionsView
    from .analysis_phase import PhaseView
    from .analysis_speed import speed_tab

    analysis = AnalysisResults(store=results)
    results.analysis = analysis  # for the report, tests and benchmarks
    state = results.state.analysis
    if tabs is None:
        tabs = {
            "phase": lambda a, x: PhaseView(store=results, analysis=a, x_range=x),
            "speed": lambda a, x: speed_tab(results, a),
            "contributions": lambda a, x: ContributionsView(store=results, analysis=a, x_range=x),
        }
        tabs = {
            "compare": lambda a, x: CompareView(store=results, analysis=a, x_range=x),
            **tabs,
        }
    keys = [k for k in ANALYSIS_TABS if k in tabs]
    names = _tab_names()
    body = pn.Column(sizing_mode="stretch_both", css_classes=["analysis-body"])
    card = pn.Card(
        body,
        title="Analysis: compare states, phase and peaks, across speed, contributions",
        collapsible=True,
        collapsed=True,
        sizing_mode="stretch_width",
        header_background="#e9ecef",
        margin=(4, 4),
        css_classes=["analysis-card"],
    )
    panes: list[pn.Tabs] = []  # built when the card is first opened (a page load builds none)

    def build() -> pn.Tabs:
        if not panes:
            tabs_ = pn.Tabs(
                *[(names[k], tabs[k](analysis, x_range)) for k in keys],
                dynamic=True,
                sizing_mode="stretch_both",
                css_classes=["analysis-tabs"],
            )
            if state.tab in keys:
                tabs_.active = keys.index(state.tab)
            tabs_.param.watch(shown, "active")
            panes.append(tabs_)
            body.append(tabs_)
        return panes[0]

    def shown(*_):
        if not card.collapsed:
            tabs_ = build()
            card.height = CARD_HEIGHT
            tab = keys[tabs_.active]
        else:
            card.height = None
            tab = ""
        if state.tab != tab:
            state.tab = tab

    def from_state(*_):
        if state.tab in keys:
            tabs_ = build()
            if tabs_.active != keys.index(state.tab):
                tabs_.active = keys.index(state.tab)
            if card.collapsed:
                card.collapsed = False
        elif not card.collapsed:
            card.collapsed = True

    card.param.watch(shown, "collapsed")
    state.param.watch(from_state, "tab")
    from_state()
    return card
