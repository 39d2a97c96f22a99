"""The servable page: ``panel serve app/main.py``.

Every browser session gets its own :class:`~app.state.DashboardState`, synchronised with the
URL query (``?h=5&N=150&dof=z...``), so that a link reproduces the view.
"""

from __future__ import annotations

import functools

import panel as pn
import param

from app.bands import served
from app.state import URL_KEYS, DashboardState
from app.store import Results
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
from app.views.analysis_base import analysis_card
from app.views.plots import frequency_range, modes_range

pn.extension("tabulator", notifications=True, sizing_mode="stretch_width")

ACCENT = "#1c7ed6"

INTRO = """
Prediction of the vibration at a rear-chassis bushing from a rolling-tire modal model
coupled to a chassis FRF model at the hub (receptance coupling, thesis eq. 4.1), with the
two sensitivity studies of the thesis: **modal truncation** of the tire (5.1) and **random
noise** in the subsystem FRFs (5.2). Zoom and pan are linked across the frequency axes;
every view downloads its data as CSV; the URL holds the page state.
"""


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


def sync_url(state: DashboardState, location=None) -> None:
    """Keep the state in the URL query (only when served, or with a given ``location``)."""
    loc = pn.state.location if location is None else location
    if loc is None:
        return
    for group, keys in URL_KEYS.items():
        obj = getattr(state, group)
        loc.sync(obj, keys, on_error=functools.partial(apply_valid, obj))


def create_app(
    state: DashboardState | None = None, results: Results | None = None
) -> pn.template.BootstrapTemplate:
    """Build one session's page around ``state`` (a new default state if omitted).

    The page's :class:`~app.store.Results` computes everything it shows; when served, it
    is closed with the session (its running band is cancelled).
    """
    results = results if results is not None else Results(state)
    state = results.state
    sync_url(state)
    # one frequency axis range for all spectra of the session: zoom and pan are linked
    freq = frequency_range()
    modes = modes_range()  # the error map's N axis and the eigenfrequency plot's

    def card(title, view, height, **kw):
        return pn.Card(
            view,
            title=title,
            collapsible=True,
            height=height,
            sizing_mode="stretch_width",
            header_background="#e9ecef",
            margin=(4, 4),
            **kw,
        )

    # the uncoupled subsystems are built on first request (two plots less per page load)
    uncoupled = pn.Row(
        visible=state.case.param.show_uncoupled,
        css_classes=["uncoupled-row"],
        sizing_mode="stretch_width",
    )

    @param.depends(state.case.param.show_uncoupled, watch=True)
    def show_uncoupled(show=state.case.show_uncoupled):
        if show and not uncoupled.objects:
            uncoupled.append(
                card(
                    "Uncoupled subsystems: tire hub and chassis spindle-to-bushing",
                    UncoupledView(store=results, x_range=freq),
                    420,
                )
            )

    show_uncoupled()

    upload = card(
        "Your data: chassis FRF and tire model for this session",
        UploadView(data=state.data),
        None,
        collapsed=False,
        css_classes=["upload-card"],
    )
    main = pn.Column(
        pn.Row(upload),
        pn.Row(
            card(
                "Coupled response at the bushing (thesis eq. 4.1)",
                MobilityView(store=results, x_range=freq),
                500,
            ),
            card(
                "Truncation error map (thesis eq. 5.1, figs. 5.3, 5.6, 5.7)",
                TruncationView(store=results, x_range=freq, n_range=modes),
                500,
            ),
        ),
        uncoupled,
        pn.Row(
            card(
                "Noise scatter band (thesis 5.2, figs. 5.9-5.11)",
                ScatterBandView(store=results, x_range=freq),
                500,
            ),
            card(
                "Eigenfrequency versus number of modes (fig. 5.8)",
                EigenView(store=results, n_range=modes),
                500,
            ),
        ),
        pn.Row(
            card(
                "Suggested number of modes (thesis table 5.1)",
                SuggestedModesView(store=results),
                360,
            )
        ),
        pn.Row(analysis_card(results, freq)),  # issue 18: compare, phase, speed, contributions
        sizing_mode="stretch_width",
    )
    template = pn.template.BootstrapTemplate(
        title="Tire-chassis FBS: bushing vibration dashboard",
        sidebar=[pn.pane.Markdown(INTRO, styles={"font-size": "0.85em"}), Controls(state=state)],
        main=[main],
        header_background=ACCENT,
        sidebar_width=340,
    )
    template.state = state  # for tests and benchmarks
    template.results = results
    if served():
        pn.state.onload(results.request_band)
        pn.state.on_session_destroyed(lambda _ctx: results.close())
    else:
        results.request_band(wait=True)
    return template


if pn.state.served:
    # One recomputation of the document's model graph instead of one per added root
    # (Bokeh recomputes it on every change of the graph): about a fifth of the server's
    # CPU time for a new session (bench/load_test.py)
    with pn.state.curdoc.models.freeze():
        create_app().servable(title="tire-fbs dashboard")
