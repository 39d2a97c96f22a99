"""The "Analysis" card: one tab per analysis view, built on first open.

The tab shown is ``state.analysis.tab`` (in the URL as ``atab``), and only the shown tab's
results are computed (:mod:`app.store`).
"""

from __future__ import annotations

import panel as pn

from ..state.analysis import ANALYSIS_TABS
from .analysis_compare import CompareView
from .analysis_contrib import ContributionsView
from .analysis_modes import modes_tab, selection_tab
from .analysis_phase import PhaseView
from .analysis_speed import speed_tab

__all__ = ["analysis_card"]


def _tab_names() -> dict[str, str]:
    return {
        "compare": "Compare",
        "phase": "Phase and peaks",
        "speed": "Across speed",
        "contributions": "Contributions",
        "modes": "Modes",
        "selection": "Selected modes",
    }


def _building() -> pn.Row:
    """What the opened card shows while its views are built the first time (several
    seconds): it is in the page from the start, so the browser shows it as soon as the card
    is opened, before the server has answered."""
    return pn.Row(
        pn.indicators.LoadingSpinner(value=True, size=36, margin=(10, 10)),
        pn.pane.HTML(
            "<p>Preparing the analysis views (the first time takes a few seconds) ...</p>",
            margin=(10, 0),
        ),
        css_classes=["analysis-building"],
        sizing_mode="stretch_width",
    )


#: Stylesheet of the card's tabs: a tab not shown takes no room. (Bokeh stacks the tabs'
#: contents in one grid cell and hides the others with ``visibility``: the card was as tall
#: as its tallest tab, with an empty space under a shorter one.)
TABS_CSS = 'div[style*="visibility: hidden"] { display: none !important; }'


def analysis_card(results, x_range=None, tabs: dict | None = None, page=None) -> pn.Card:
    """The "Analysis" card: one tab per analysis view, computed only while shown.

    ``tabs`` maps tab keys (:data:`~app.state.analysis.ANALYSIS_TABS`) to a function
    ``(results, x_range) -> viewable``; default all views of the card. ``page``
    (the page's layout state): the default views follow its view (type sizes of the normal
    or the presentation view).
    """
    state = results.state.analysis
    views: list = []  # the default views built so far: they follow the page's view

    def mode() -> str:
        return page.view if page is not None else "normal"

    def made(view):
        views.append(view)
        return view

    if tabs is None:
        tabs = {
            "compare": lambda r, x: made(CompareView(store=r, x_range=x, mode=mode())),
            "phase": lambda r, x: made(PhaseView(store=r, x_range=x, mode=mode())),
            "speed": lambda r, x: speed_tab(r, mode(), views),
            "contributions": lambda r, x: made(ContributionsView(store=r, x_range=x, mode=mode())),
            "modes": lambda r, x: modes_tab(r, mode(), views),
            "selection": lambda r, x: selection_tab(r, mode(), views),
        }
    if page is not None:

        def restyle(e):
            for v in views:
                v.mode = e.new

        page.param.watch(restyle, "view")
    keys = [k for k in ANALYSIS_TABS if k in tabs]
    names = _tab_names()
    # each view has the height of its plots (app/views/layout.py: the window's height within
    # limits); the card and its tabs state their sizing, so it is never inferred from their
    # content (a card of no height given a stretch_both sizing got no height at all in the
    # page column)
    body = pn.Column(_building(), sizing_mode="stretch_width", css_classes=["analysis-body"])
    card = pn.Card(
        body,
        title="Analysis: compare states, phase and peaks, across speed, contributions, modes",
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
                *[(names[k], tabs[k](results, x_range)) for k in keys],
                dynamic=True,
                sizing_mode="stretch_width",
                stylesheets=[TABS_CSS],
                css_classes=["analysis-tabs"],
            )
            if state.tab in keys:
                tabs_.active = keys.index(state.tab)
            tabs_.param.watch(shown, "active")
            panes.append(tabs_)
            body.objects = [tabs_]  # in place of the indicator
        return panes[0]

    def shown(*_):
        if not card.collapsed:
            tabs_ = build()
            tab = keys[tabs_.active]
        else:
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
