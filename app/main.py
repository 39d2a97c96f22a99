"""The servable page: ``panel serve app/main.py``.

Every browser session gets its own :class:`~app.state.DashboardState`, synchronised with the
URL query (``?h=5&N=150&dof=z...``), so that a link reproduces the view; the page layout
(presentation view, data card, N-axis scale, the uploads a link needs) is in the link too
(:class:`~app.page.layout.PageState`).

Layout, top to bottom: the page bar (report, help, layout switches), the notice of a link
that needs uploads, the first screen (:func:`first_screen`: coupled response and error map,
on the first screen also at 1280x720), then (:func:`below_first_screen`) the suggested modes
and eigenfrequencies, the "Your data" card, the noise band and one card per entry of
:data:`EXTRA_CARDS`, the place where further views (in their own modules under
``app/views/``) add themselves with one line. A served page sends its first screen first and
builds the rest once the browser shows it (the first plot of a page of ~1,000 Bokeh
models waited 2.5 s for all of them).
"""

from __future__ import annotations

import functools
import logging
import re
import sys
import urllib.parse
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import panel as pn
import param

from app.page import scripts as page_scripts
from app.page.chrome import (
    busy_indicator,
    data_key,
    help_page,
    link_notice,
    link_notice_html,
    report_buttons,
)
from app.page.layout import (
    BAR_WIDTHS,
    CARD_CSS,
    PAGE_CSS,
    PAGE_URL_KEYS,
    VIEW_SWITCH_JS,
    PageState,
    bar_stylesheet,
    present_css,
)
from app.page.titles import PAGES, PageLink, page_url, read_link, resolve_view_id
from app.public_url import public_base
from app.report.session import provenance_of, report_data
from app.review import review_link
from app.runtime import background, closed_pages, libraries  # noqa: F401 (libraries: preloaded)
from app.runtime.collector import count_alive, session_ended, session_started
from app.runtime.collector import start as start_quiet_collections
from app.runtime.draw import DrawQueue, on_document, served, served_document
from app.runtime.pace import step_aside
from app.runtime.panel_private import lock_held_only_by_its_thread
from app.state import URL_KEYS, DashboardState
from app.store import LIVE, Results
from app.views import (
    Controls,
    EigenView,
    MobilityView,
    ScatterBandView,
    SuggestedModesView,
    TruncationView,
    UncoupledView,
    UploadView,
)
from app.views.analysis_card import analysis_card
from app.views.bind import control
from app.views.campaign import campaign_card
from app.views.landmarks import landmarks_card
from app.views.layout import (
    HIDE_TEMPLATE_TOGGLE_CSS,
    PANEL_CONFIG,
    VIEW_SIDEBAR_JS,
    font,
    layout_css,
    sidebar_toggle,
    sized,
)
from app.views.plots import frequency_range, modes_range
from app.views.quality import TireQualityView
from app.views.review import review_card
from app.views.wheels import wheels_card

# bokeh-tables: the Selected modes tab's DataTable is built when the tab is first shown,
# after the page loaded; Panel bundles only the scripts of the models a page starts with
pn.extension("tabulator", "bokeh-tables", notifications=True, sizing_mode="stretch_width")
lock_held_only_by_its_thread()  # Panel's worker threads change a page only under its lock
public_base()  # a wrong FBS_PUBLIC_URL stops the server at start, naming the variable
pn.config.param.update(**PANEL_CONFIG)  # stated sizing modes hold (app/views/layout.py)

log = logging.getLogger("app.main")  # (run as a script by panel serve: no module name)

ACCENT = "#1c7ed6"

INTRO = """
Prediction of the vibration at a rear-chassis bushing from a rolling-tire modal model
coupled to a chassis FRF model at the hub (receptance coupling, thesis eq. 4.1), with the
two sensitivity studies of the thesis: **modal truncation** of the tire (5.1) and **random
noise** in the subsystem FRFs (5.2). Zoom and pan are linked across the frequency axes;
every view downloads its data as CSV; the URL holds the page state. **Help** explains the
method and how to read each view.
"""

#: The link notice's colours (Bootstrap's warning alert; the page's CSS does not reach a pane).
NOTICE_STYLE = {
    "background": "#fff3cd",
    "color": "#664d03",
    "border": "1px solid #ffecb5",
    "border-radius": "6px",
    "padding": "2px 12px",
}

#: Class of the page's main column until what is below the first screen is added.
BUILDING = "page-building"

#: Height of a plot card's content: the window's height within limits (app/views/layout.py).
PLOT_ROW = "plot"


def apply_valid(obj: param.Parameterized, values: dict) -> list[str]:
    """Set every value its parameter accepts, one by one; return the names refused.

    Panel applies a URL's values to a parameterized object in one update, which stops at
    the first bad value (a shared link with ``h=9`` would lose the valid ``N=150`` after
    it); this is its ``on_error`` fallback.
    """
    refused = []
    for name, value in values.items():
        try:
            obj.param.update(**{name: value})
        except Exception:  # param's ValueError/TypeError: out of range, wrong type
            refused.append(name)
    return refused


def drop_unreadable_numbers(loc) -> list[str]:
    """Remove from ``loc.search`` the keys whose value Panel cannot read; return them.

    Panel reads a value of digits with ``int()``, which refuses more than
    ``sys.get_int_max_str_digits()`` digits (4,300) with a ``ValueError`` that would stop the
    page build: a 5 KB link would break the page. No setting of the page takes such a number,
    so the key is dropped and the setting keeps its default.
    """
    limit = sys.get_int_max_str_digits()
    pairs = urllib.parse.parse_qsl((loc.search or "").lstrip("?"), keep_blank_values=True)
    # a whole number as Panel's parse_query tells one (a sign too)
    whole = re.compile(r"-?[0-9]+")
    bad = [k for k, v in pairs if limit and whole.fullmatch(v) and len(v.lstrip("-")) > limit]
    if bad:
        kept = [(k, v) for k, v in pairs if k not in bad]
        loc.search = "?" + urllib.parse.urlencode(kept) if kept else ""
    return bad


def sync_url(state: DashboardState, location=None, page: PageState | None = None):
    """Open the page on its link's settings, then keep the state (and the layout ``page``)
    in the URL query (only when served, or with a given ``location``); returns the
    :class:`~app.page.titles.PageLink` writing the URL (None: no location)."""
    loc = pn.state.location if location is None else location
    if loc is None:
        return None
    unknown = resolve_view_id(loc)
    if unknown:
        log.info("a link's view id %r is unknown to this server (made before a restart)", unknown)
    drop_unreadable_numbers(loc)
    for group, keys in URL_KEYS.items():
        obj = getattr(state, group)
        read_link(loc, obj, keys, on_error=functools.partial(apply_valid, obj))
    if page is not None:
        read_link(loc, page, PAGE_URL_KEYS, on_error=functools.partial(apply_valid, page))
    link = PageLink(loc, state, page)
    link.watch()
    link.write()
    return link


@dataclass
class PageParts:
    """What a card of the page is built from: one session's store, state and layout.

    Attributes
    ----------
    results : Results
        The session's results store (``results.state`` is its ``DashboardState``).
    page : PageState
        The layout state (``page.view`` is ``"normal"`` or ``"present"``).
    freq, modes : bokeh Range1d
        The shared frequency axis and N axis (zoom and pan linked across views).
    """

    results: Results
    page: PageState
    freq: Any
    modes: Any

    @property
    def state(self) -> DashboardState:
        state = self.results.state
        assert state is not None  # a Results always owns a state
        return state

    def card(self, title: str, view, height: int | str | None = PLOT_ROW, **kw) -> pn.Card:
        """A collapsible card of the page's style.

        ``height``: of its content, "plot" (the plot rows' height, which follows the window,
        :mod:`app.views.layout`), a number of px, or None (as tall as its content).
        """
        kw.setdefault("css_classes", [])
        kw["css_classes"] = [*kw["css_classes"], "fbs-card"]
        if isinstance(height, str):
            view = sized(view, row=height)
        elif height is not None:
            view = pn.Column(view, height=height, sizing_mode="stretch_width", margin=0)
        return pn.Card(
            view,
            title=title,
            collapsible=True,
            sizing_mode="stretch_width",
            header_background="#dee2e6",
            margin=(4, 4),
            stylesheets=[CARD_CSS],
            **kw,
        )


#: Further cards, below the built-in plots, in this order: ``builder(parts) -> panel object``
#: (None: nothing). A view in its own module under ``app/views/`` adds its builder here.
EXTRA_CARDS: list[Callable[[PageParts], Any]] = []
EXTRA_CARDS.append(review_card)  # candidates against targets: the verdict (built on opening)
EXTRA_CARDS.append(wheels_card)  # per-wheel contributions (vehicle scope)
EXTRA_CARDS.append(  # compare, phase and peaks, across speed, contributions
    lambda parts: analysis_card(parts.results, parts.freq, page=parts.page)
)
EXTRA_CARDS.append(campaign_card)  # campaign result files of FBS_CAMPAIGN_DIR (unset: how to)
EXTRA_CARDS.append(landmarks_card)  # the thesis' landmarks next to this tire's


def extra_cards(parts: PageParts) -> list:
    """The cards of :data:`EXTRA_CARDS` for this session."""
    cards = []
    for build in EXTRA_CARDS:
        step_aside()
        card = build(parts)
        if card is not None:
            cards.append(card)
    return cards


class PlotViews:
    """The built-in plot views of one page, and the page-layout switches they follow."""

    def __init__(self, parts: PageParts):
        r, p, mode = parts.results, parts.page, parts.page.view
        self.parts = parts
        self.mobility = MobilityView(store=r, x_range=parts.freq, mode=mode)
        # the views themselves are kept: a layout holds what a view's __panel__ returned, so
        # the error map in its column never heard of the Presentation button
        self.map_view = self._map(p.n_axis)
        self.uncoupled_view: UncoupledView | None = None
        self.truncation = pn.Column(self.map_view, sizing_mode="stretch_both")
        # the views below the first screen: built by build_below (a served page: once the
        # browser shows the first screen, so the first plot does not wait for them)
        self.scatter: ScatterBandView | None = None
        self.eigen: EigenView | None = None
        self.suggested: SuggestedModesView | None = None
        # the uncoupled subsystems are built on first request (two plots less per page load)
        self.uncoupled = pn.Row(
            visible=r.state.case.param.show_uncoupled,
            css_classes=["uncoupled-row"],
            sizing_mode="stretch_width",
        )
        r.state.case.param.watch(lambda e: self._show_uncoupled(e.new), "show_uncoupled")
        self._show_uncoupled(r.state.case.show_uncoupled)
        p.param.watch(lambda e: self._rebuild_map(e.new), "n_axis")
        p.param.watch(lambda e: self._restyle(e.new), "view")

    def build_below(self) -> None:
        """The plot views below the first screen (noise band, suggested modes,
        eigenfrequencies), in the page's view as it is now."""
        pa = self.parts
        r, mode = pa.results, pa.page.view
        self.scatter = ScatterBandView(store=r, x_range=pa.freq, mode=mode)
        self.eigen = EigenView(store=r, n_range=pa.modes, mode=mode)
        self.suggested = SuggestedModesView(store=r)

    def _map(self, n_axis: str) -> TruncationView:
        pa = self.parts
        return TruncationView(
            store=pa.results,
            x_range=pa.freq,
            n_range=pa.modes,
            mode=pa.page.view,
            n_axis=n_axis,
        )

    def _rebuild_map(self, n_axis: str) -> None:  # the axis scale is fixed at build
        self.map_view = self._map(n_axis)
        self.truncation.objects = [self.map_view]

    def _show_uncoupled(self, show: bool) -> None:
        if show and self.uncoupled_view is None:
            pa = self.parts
            self.uncoupled_view = view = UncoupledView(
                store=pa.results, x_range=pa.freq, mode=pa.page.view
            )
            self.uncoupled.append(
                pa.card("Uncoupled subsystems: tire hub and chassis spindle-to-bushing", view)
            )

    def live(self) -> list:
        """The plot views now on the page."""
        built = (self.scatter, self.eigen, self.uncoupled_view)
        return [self.mobility, self.map_view, *(v for v in built if v is not None)]

    def _restyle(self, view: str) -> None:
        for v in self.live():
            v.mode = view


def first_screen(parts: PageParts, views: PlotViews) -> list:
    """The plots of the first screen: the coupled response and the error map (also at
    1280x720), and the uncoupled subsystems below them when asked for."""
    card = parts.card
    return [
        pn.Row(
            card("Coupled response at the bushing (thesis eq. 4.1)", views.mobility),
            card("Truncation error map (eq. 5.1, figs. 5.3, 5.6, 5.7)", views.truncation),
        ),
        views.uncoupled,
    ]


def below_first_screen(parts: PageParts, views: PlotViews) -> list:
    """Everything below the first screen, top to bottom: the rest of the truncation study
    (suggested modes, eigenfrequencies), the "Your data" card, the noise study, then the
    cards of :data:`EXTRA_CARDS`. Builds the views it shows (:meth:`PlotViews.build_below`).
    """
    step_aside()  # (safe points: nothing held that another page may wait for)
    views.build_below()
    step_aside()
    card = parts.card
    truncation = pn.Row(
        card("Suggested number of modes (thesis table 5.1)", views.suggested),
        card("Eigenfrequency versus number of modes (fig. 5.8)", views.eigen),
    )
    step_aside()
    data = data_card(parts)
    step_aside()
    noise = pn.Row(card("Noise scatter band (thesis 5.2, figs. 5.9-5.11)", views.scatter))
    return [truncation, data, noise, *extra_cards(parts)]


def data_card(parts: PageParts) -> pn.Card:
    """The "Your data" card; collapsed in the presentation view or with ``card=closed``, and
    its state kept in the link."""
    page = parts.page
    upload = parts.card(
        "Your data: chassis FRF and tire model for this session",
        pn.Column(UploadView(data=parts.state.data), TireQualityView(store=parts.results)),
        None,
        collapsed=page.view == "present" or page.data_card == "closed",
        css_classes=["upload-card"],
    )
    upload.param.watch(
        lambda e: setattr(page, "data_card", "closed" if e.new else "open"), "collapsed"
    )

    def follow_view(e):
        if e.new == "present":
            upload.collapsed = True

    page.param.watch(follow_view, "view")
    return upload


def link_notice_pane(parts: PageParts) -> pn.pane.HTML:
    """The notice of a link made with uploads this session lacks; the link names the
    uploads in use. An HTML pane of escaped text, not Markdown: the notice repeats the
    link's value, which must stay text."""
    state, page = parts.state, parts.page
    notice = pn.pane.HTML(
        "",
        visible=False,
        css_classes=["link-notice"],
        margin=(4, 8),
        styles=NOTICE_STYLE,
        sizing_mode="stretch_width",
    )

    def check(*_):  # the link's uploads (from the URL) vs the session's
        text = link_notice(page.data, provenance_of(state.data.models))
        notice.param.update(object=link_notice_html(text) if text else "", visible=bool(text))

    def data_in_use(*_):  # the link names the uploads now in use
        page.data = data_key(provenance_of(state.data.models))

    page.param.watch(check, "data")
    state.data.param.watch(data_in_use, "models")
    check()
    review_in_link(parts)
    return notice


def review_in_link(parts: PageParts) -> None:
    """The review the link names, restored once (its targets and incumbent at once, its
    candidates as their files are uploaded); from then on the link names the session's."""
    state, page = parts.state, parts.page
    data = state.data
    if page.review:
        data.apply_link(page.review)

    def write(*_):
        page.review = review_link(data.review, data.pending)

    data.param.watch(write, ["review", "pending"])


def page_bar(parts: PageParts, report: Callable, open_help: Callable) -> pn.Row:
    """Report downloads, help and the layout switches (presentation view, N axis)."""
    page = parts.page
    help_button = pn.widgets.Button(
        label="Help", button_type="light", css_classes=["help-button"], width=70
    )
    help_button.on_click(lambda _e: open_help())
    view_switch = control(
        pn.widgets.RadioButtonGroup,
        page.param.view,
        name="Page",
        options={"Normal view": "normal", "Presentation": "present"},
        css_classes=["ctl-page-view"],
        width=220,
        in_draw=True,  # the whole page restyled in one message: laid out once
    )
    # the page's type (page.py) and the sidebar at once
    view_switch.jscallback(value=VIEW_SWITCH_JS + VIEW_SIDEBAR_JS)
    reports = report_buttons(report, parts.results)
    n_axis = control(
        pn.widgets.RadioButtonGroup,
        page.param.n_axis,
        name="N axis",
        options={"N linear": "linear", "N log": "log"},
        css_classes=["ctl-page-naxis"],
        width=150,
    )
    sidebar = sidebar_toggle(page)

    # the buttons as wide as their labels in the view's type (the page's CSS variables)
    normal = BAR_WIDTHS["normal"]
    for widget, part in (
        (sidebar, "sidebar"),
        (help_button, "help"),
        (view_switch, "view"),
        (n_axis, "naxis"),
    ):
        widget.param.update(width=normal[part], stylesheets=[bar_stylesheet(part)])
    for b in reports.objects:
        b.param.update(width=normal["report"], stylesheets=[bar_stylesheet("report")])
    reports.param.update(
        sizing_mode=None,
        width=2 * normal["report"] + 20,
        stylesheets=[bar_stylesheet("report", times=2, plus=20)],
    )
    return pn.Row(
        sidebar,
        reports,
        help_button,
        view_switch,
        n_axis,
        busy_indicator(parts.results),  # what long work runs (hidden otherwise)
        css_classes=["page-bar"],
        sizing_mode="stretch_width",
        margin=(2, 4),
    )


def create_app(
    state: DashboardState | None = None, results: Results | None = None
) -> pn.template.BootstrapTemplate:
    """Build one session's page around ``state`` (a new default state if omitted).

    The page's :class:`~app.store.Results` computes everything it shows; when served, it
    is closed with the session (its running band is cancelled).
    """
    step_aside()  # (safe points: nothing held that another page may wait for)
    results = results if results is not None else Results(state)
    step_aside()
    state = results.state
    page = PageState()
    link = sync_url(state, page=page)  # the layout is kept in the link too
    if served_document() is not None:
        PAGES[served_document()] = page  # (title blocks' links name the page's N axis)
    # one frequency axis range for all spectra of the session: zoom and pan are linked;
    # one N range for the error map and the eigenfrequency plot
    parts = PageParts(results=results, page=page, freq=frequency_range(), modes=modes_range())
    views = PlotViews(parts)
    step_aside()

    def report():  # the page's published results, as they are when the button is clicked
        from app.views.vpt_consistency import report_notes

        return report_data(
            results, url=page_url(), n_axis=page.n_axis, notes=report_notes(state.data)
        )

    # the modal's own close control (Panel's public close_modal); a button in the page is
    # reachable by keyboard and by tests, unlike the template's icon or the Escape key
    help_close = pn.widgets.Button(
        label="Close help", button_type="primary", css_classes=["help-close"], width=110
    )
    template = pn.template.BootstrapTemplate(
        title="Tire-chassis FBS: bushing vibration dashboard",
        sidebar=[
            pn.pane.Markdown(INTRO, styles={"font-size": font("0.85em")}),
            Controls(state=state),
        ],
        modal=[help_close, help_page()],
        header_background=ACCENT,
        sidebar_width=340,
        collapsed_sidebar=page.sidebar_collapsed,
        # no header spinner: Panel's busy flag is one for the process, and every browser
        # change of a widget in any session set every open page's spinner twice (resolving
        # the spinner's design files each time: an eighth of the server's CPU with 20
        # sessions changing, bench/load_test.py profiled); the page has its own progress
        busy_indicator=None,
    )
    step_aside()
    main = pn.Column(
        page_bar(parts, report, template.open_modal),
        link_notice_pane(parts),
        *first_screen(parts, views),  # a plot on the first screen, also at 1280x720
        sizing_mode="stretch_width",
        css_classes=[BUILDING],  # until the rest is added (tests and benchmarks wait for it)
    )

    def complete() -> None:  # the rest of the page, below the first screen
        # made as the first screen was, before the template set the page's design: with no
        # design of their own, the template's reaches them as it reaches the first screen
        # (with one of their own, Panel skips them: no margins inside the cards)
        with pn.config.set(design=None):
            below = below_first_screen(parts, views)
        # added on the page's draw queue, in order with its draws and sent as one message
        # as they are (added from Panel's worker thread, Panel sent it through its held
        # events, and with 10 sessions opening at once a later draw of a session never
        # reached its page: bench/load_test.py)
        on_document(
            served_document(),
            lambda: main.param.update(
                objects=[*main.objects, *below],
                css_classes=[c for c in main.css_classes if c != BUILDING],
            ),
        )

    help_close.on_click(lambda _e: template.close_modal())
    step_aside()
    template.main.append(main)
    template.config.raw_css.append(PAGE_CSS)
    # the presentation view's larger type follows the view switch without a reload
    template.config.raw_css.append(present_css(page.view == "present"))
    template.config.raw_css.append(layout_css(page.view == "present"))
    template.config.raw_css.append(HIDE_TEMPLATE_TOGGLE_CSS)
    template.page = page
    template.state = state  # for tests and benchmarks
    template.results = results
    template.views = views
    doc = pn.state.curdoc
    page_scripts.install(doc)  # checkbox labels toggle, tooltips stay inside the window
    if doc is not None:  # a served session, or a document built without one
        # bound now: Bokeh may clear the session's module namespace before its
        # session-destroyed callbacks run ("name 'close_page' is not defined", seen under load)
        # (the document by weak reference: held strongly by its own session-destroyed
        # callback it kept the page alive, tests/test_server_pages.py)
        doc_ref = weakref.ref(doc)
        log.info("a page's session started")  # (bench/load_test.py counts them)
        session_started()  # (the quiet collector weighs ended sessions against open ones)
        doc.on_session_destroyed(
            lambda _ctx, close=close_page, drop=DrawQueue.discard, ended=session_ended: (
                drop(doc_ref()),
                close(template),
                ended(),  # the quiet collection thaws what was frozen with the page
            )
        )
    if served():
        closed_pages.quiet_closed_page_writes()  # once per process: the server's loop
        # the first screen is sent and shown first (a page of ~1,000 Bokeh models
        # took 2.5 s to its first plot); the rest follows once the browser shows it
        pn.state.onload(complete)
        if link is not None:
            # the browser reports its own URL when the page loads (a view id's, or one the
            # page read differently): the page's URL is the state's from then on
            pn.state.onload(link.write_again)
        pn.state.onload(results.request_band)
        # once per process, after the first page: the other harmonics' reference studies
        pn.state.onload(background.warm_reference_studies)
        pn.state.onload(start_quiet_collections)  # once per process (runtime/collector.py)
        count_alive("pages", LIVE.__len__)  # logged after thawed collections (a bound method:
        # Bokeh may clear this script's namespace before the collection runs)
    else:
        complete()
        results.request_band(wait=True)
    return template


def close_page(page: pn.template.BootstrapTemplate, log: logging.Logger = log) -> None:
    """End a page of :func:`create_app`: its band is cancelled, nothing more is published,
    and the watchers of its components are dropped (the draws still waiting for its
    document are dropped beside it, ``DrawQueue.discard``).

    Called with the document's session-destroyed callbacks. Panel drops the watchers of a
    served session's components itself; a page built in a document without a browser
    session (Panel's ``--liveness`` check, a warm-up, a test) is not among them, and
    Panel's registry of JavaScript callbacks (``panel.links.Callback.registry``, used by
    the editable sliders of the controls) would then keep the whole page, its results and
    its data alive for the life of the process.
    """
    page.results.close()
    # (``log`` is bound as a default: Bokeh may clear the module's namespace before the
    # session-destroyed callbacks run, and a global name then raised here)
    log.info("a page's session ended")  # (bench/load_test.py counts them)
    # the template's areas, not ``page.select()``: in a served page the template renders
    # Panel's BrowserInfo too, which has no ``select`` (the callback failed there, and the
    # watchers stayed)
    for area in (page.header, page.sidebar, page.main, page.modal):
        for item in area.objects:
            for obj in item.select():
                obj.param.watchers = {}


def unreadable_link() -> pn.viewable.Viewable | None:
    """The page of a served link whose query cannot be read (:mod:`app.page.query`), or
    None for a link the dashboard can open.

    Checked on the request's raw query before anything asks for the page's location: Panel
    reads every value when it makes the location, and a value it cannot read would stop the
    page build with a traceback and leave the page blank.
    """
    from app.page.query import kept_query, shown_key, unreadable_keys, unreadable_link_page

    args = pn.state.session_args
    bad = unreadable_keys(args)
    if not bad:
        return None
    request = pn.state.curdoc.session_context.request
    path = str(getattr(request, "path", "") or "")
    log.info(
        "a link with unreadable query values opened a message page: %s",
        "; ".join(f"{shown_key(k)} {why}" for k, why in bad.items()),
    )
    return unreadable_link_page(bad, kept_query(args, list(bad)), path)


if pn.state.served:
    _message = unreadable_link()
    if _message is not None:  # no location: Panel would read the unreadable values
        _message.servable(title="tire-fbs dashboard", location=False)
    else:
        # One recomputation of the document's model graph instead of one per added root
        # (Bokeh recomputes it on every change of the graph): about a fifth of the server's
        # CPU time for a new session (bench/load_test.py)
        with pn.state.curdoc.models.freeze():
            _page = create_app()
            step_aside()
            _page.servable(title="tire-fbs dashboard")
