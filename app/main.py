"""The servable page: ``panel serve app/main.py``.

Every browser session gets its own :class:`~app.state.DashboardState`, synchronised with the
URL query (``?h=5&N=150&dof=z...``), so that a link reproduces the view.
"""

from __future__ import annotations

import panel as pn

from app.state import URL_KEYS, DashboardState
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


def sync_url(state: DashboardState) -> None:
    """Keep the state in the URL query (only when served)."""
    loc = pn.state.location
    if loc is None:
        return
    for group, keys in URL_KEYS.items():
        loc.sync(getattr(state, group), keys)


def create_app(state: DashboardState | None = None) -> pn.template.BootstrapTemplate:
    """Build one session's page around ``state`` (a new default state if omitted)."""
    state = state or DashboardState()
    case, noise, trunc = state.case, state.noise, state.truncation
    sync_url(state)
    # one frequency axis range for all spectra of the session: zoom and pan are linked
    freq = frequency_range()
    modes = modes_range()  # the error map's N axis and the eigenfrequency plot's
    scatter = ScatterBandView(case=case, noise=noise, x_range=freq)

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
        visible=case.param.show_uncoupled,
        css_classes=["uncoupled-row"],
        sizing_mode="stretch_width",
    )

    def show_uncoupled(*_):
        if case.show_uncoupled and not uncoupled.objects:
            uncoupled.append(
                card(
                    "Uncoupled subsystems: tire hub and chassis spindle-to-bushing",
                    UncoupledView(case=case, x_range=freq),
                    420,
                )
            )

    case.param.watch(show_uncoupled, "show_uncoupled")
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
                MobilityView(case=case, x_range=freq),
                500,
            ),
            card(
                "Truncation error map (thesis eq. 5.1, figs. 5.3, 5.6, 5.7)",
                TruncationView(case=case, truncation=trunc, x_range=freq, n_range=modes),
                500,
            ),
        ),
        uncoupled,
        pn.Row(
            card("Noise scatter band (thesis 5.2, figs. 5.9-5.11)", scatter, 500),
            card(
                "Eigenfrequency versus number of modes (fig. 5.8)",
                EigenView(case=case, n_range=modes),
                500,
            ),
        ),
        pn.Row(
            card(
                "Suggested number of modes (thesis table 5.1)",
                SuggestedModesView(case=case, truncation=trunc),
                360,
            )
        ),
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
    if pn.state.curdoc is not None and pn.state.curdoc.session_context is not None:
        pn.state.onload(scatter.start)
    else:
        scatter.compute_now()
    return template


if pn.state.served:
    # One recomputation of the document's model graph instead of one per added root
    # (Bokeh recomputes it on every change of the graph): about a fifth of the server's
    # CPU time for a new session (bench/load_test.py)
    with pn.state.curdoc.models.freeze():
        create_app().servable(title="tire-fbs dashboard")
