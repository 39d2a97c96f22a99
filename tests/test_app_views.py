"""Views without a browser: state -> published results -> plot data (Bokeh models, rendered
in-process), which views each control touches, and what the CSV exports hold.

Truth: ``fbs_core`` called directly (``bushing_response``, ``scatter_band``), closed forms
(a band without noise is the reference; a stricter threshold never needs fewer modes), and
the figures' own sources (an export must hold what is plotted).
"""

import threading

import numpy as np
import pytest
from bokeh.models import ColumnDataSource

import fbs_core
from app import compute
from app.export import read_csv, to_csv
from app.main import create_app
from app.state import DashboardState
from app.store import Results

NAMES = [
    "mobility.reference",
    "mobility.truncated",
    "truncation.map",
    "scatter.minmax",
    "scatter.percentile",
    "scatter.reference",
    "scatter.round",
    "eigen.f_80",
]


@pytest.fixture(scope="module")
def page():
    """One rendered page (no server) with a small scatter band."""
    state = DashboardState()
    state.noise.rounds = 200
    app = create_app(state)
    root = app.main[0].get_root()
    yield state, app, root


def _sources(root):
    out = {}
    for name in NAMES:
        found = [m for m in root.select({"name": name}) if isinstance(m, ColumnDataSource)]
        assert len(found) == 1, name
        out[name] = found[0]
    return out


def _snapshot(root):
    return {
        n: {k: np.array(v, copy=True) for k, v in s.data.items()} for n, s in _sources(root).items()
    }


def _same(a, b):
    return a.keys() == b.keys() and all(
        np.shape(a[k]) == np.shape(b[k]) and np.array_equal(a[k], b[k], equal_nan=True) for k in a
    )


def _db(x):
    return 20 * np.log10(np.abs(x))


def test_plotted_mobility_is_the_core_prediction(page):
    state, _, root = page
    c = state.case
    src = _sources(root)
    br = fbs_core.bushing_response(c.harmonic, n_modes=c.n_modes, coupling=c.coupling)
    ref = fbs_core.bushing_response(c.harmonic, coupling=c.coupling)
    np.testing.assert_allclose(src["mobility.truncated"].data["freq"], br.freq)
    want = _db(br.sel(outputs=f"bushing:{c.dof}").data[:, 0, 0])
    np.testing.assert_allclose(src["mobility.truncated"].data["level"], want, rtol=1e-9)
    want = _db(ref.sel(outputs=f"bushing:{c.dof}").data[:, 0, 0])
    np.testing.assert_allclose(src["mobility.reference"].data["level"], want, rtol=1e-9)


@pytest.mark.parametrize(
    ("group", "name", "value", "changed"),
    [
        (
            "case",
            "n_modes",
            120,
            {
                "mobility.truncated",
                "scatter.minmax",
                "scatter.percentile",
                "scatter.reference",
                "scatter.round",
            },
        ),
        (
            "case",
            "dof",
            "rx",
            {
                "mobility.reference",
                "mobility.truncated",
                "truncation.map",
                "scatter.minmax",
                "scatter.percentile",
                "scatter.reference",
                "scatter.round",
            },
        ),
        ("truncation", "map_mode", "max over 6 DOFs", {"truncation.map"}),
        ("truncation", "threshold", 5.0, set()),
        ("noise", "single_round", 17, {"scatter.round"}),
        ("noise", "percentile", 50, {"scatter.percentile"}),
        ("noise", "seed", 4, {"scatter.minmax", "scatter.percentile", "scatter.round"}),
        ("case", "harmonic", 2, set(NAMES) - {"eigen.f_80"}),
    ],
)
def test_each_control_changes_only_its_views(page, group, name, value, changed):
    state, _, root = page
    before = _snapshot(root)
    setattr(getattr(state, group), name, value)
    after = _snapshot(root)
    moved = {n for n in NAMES if not _same(before[n], after[n])}
    assert moved == changed


def test_threshold_caps_the_colour_scale(page):
    state, app, root = page
    state.truncation.threshold = 12.0
    from bokeh.models import LinearColorMapper

    from app.report import ErrorColorScale

    mappers = list(root.select({"type": LinearColorMapper}))
    # the largest value below the threshold: 12 % itself is "at or above" (red)
    assert [m.high for m in mappers] == [np.nextafter(12.0, 0.0)]
    assert mappers[0].high_color == ErrorColorScale(12.0).above


def _csv(result, key="x"):
    return read_csv(to_csv(result.columns, result.meta, key))


def test_exports_hold_the_plotted_data_and_the_core_truth(page):
    state, app, root = page
    res, src, c = app.results, _sources(root), state.case
    meta, cols = _csv(res.response)
    np.testing.assert_array_equal(cols["truncated_dB"], src["mobility.truncated"].data["level"])
    br = fbs_core.bushing_response(c.harmonic, n_modes=c.n_modes, coupling=c.coupling)
    v = br.sel(outputs=f"bushing:{c.dof}").data[:, 0, 0]
    np.testing.assert_allclose(cols["truncated_re"] + 1j * cols["truncated_im"], v, rtol=1e-9)
    assert meta["harmonic"] == str(c.harmonic) and meta["response DOF"] == f"bushing:{c.dof}"

    meta, cols = _csv(res.error_map)
    m = fbs_core.studies.truncation_map(c.harmonic, coupling=c.coupling)
    err = m.dof_error(f"bushing:{c.dof}") if state.truncation.map_mode == "selected DOF" else None
    if err is not None:
        np.testing.assert_allclose(cols["error_pct"][: err.shape[1]], 100 * err[0], rtol=1e-9)

    n = state.noise
    meta, cols = _csv(res.band_curves)
    band = fbs_core.scatter_band(
        c.harmonic,
        noise=n.noise / 100,
        target=n.target,
        rounds=n.rounds,
        frequency_dependent=n.frequency_dependent,
        seed=n.seed,
        n_modes=c.n_modes,
        coupling=c.coupling,
        percentiles=compute.Q_LEVELS,
    )
    j = band.dofs.index(f"bushing:{c.dof}")
    np.testing.assert_allclose(cols["maximum_dB"], _db(band.maximum[:, j]), rtol=1e-12)
    np.testing.assert_array_equal(cols["maximum_dB"], src["scatter.minmax"].data["upper"])
    np.testing.assert_allclose(
        cols[f"round_{n.single_round}_dB"], _db(band.round(n.single_round)[:, j]), rtol=1e-12
    )
    # independent of how the round is regenerated: one round lies inside the min-max band
    rnd = cols[f"round_{n.single_round}_dB"]
    assert np.all((cols["minimum_dB"] - 1e-9 <= rnd) & (rnd <= cols["maximum_dB"] + 1e-9))
    assert np.all(cols["minimum_dB"] <= cols["pct_low_dB"] + 1e-9)
    assert np.all(cols["pct_high_dB"] <= cols["maximum_dB"] + 1e-9)
    assert meta["rounds"] == str(n.rounds) and meta["seed"] == str(n.seed)


def test_zero_noise_band_collapses_on_the_reference():
    state = DashboardState()
    state.noise.param.update(noise=0.0, rounds=50)
    res = Results(state)
    res.request_band(wait=True)
    d = res.band_curves.draw["band"]
    ref = fbs_core.bushing_response(1, n_modes=state.case.n_modes)
    v = np.abs(ref.sel(outputs="bushing:z").data[:, 0, 0])
    np.testing.assert_allclose(d["minimum"], v, rtol=1e-9)
    np.testing.assert_allclose(d["maximum"], v, rtol=1e-9)


def test_suggested_table_follows_threshold_and_map_mode():
    res = Results(DashboardState())
    loose = res.suggested.columns["n_modes"]
    res.state.truncation.threshold = 5.0
    strict = res.suggested.columns["n_modes"]
    assert np.all(strict >= loose)  # a stricter threshold never needs fewer modes
    assert list(res.suggested.columns["harmonic"]) == list(range(1, 8))
    assert "5 %" in res.suggested.caption


def test_frequency_and_mode_axes_are_linked(page):
    """One range object per shared axis: zooming one plot zooms the others (in the browser
    the range is a single model), and it spans the harmonic's analysis grid."""
    from bokeh.plotting import figure

    state, _, root = page
    figs = {f.name: f for f in root.select({"type": figure}) if f.name}
    freq = figs["mobility.figure"].x_range
    assert figs["scatter.figure"].x_range is freq
    assert figs["truncation.figure"].x_range is freq
    assert figs["eigen.figure"].x_range is figs["truncation.figure"].y_range
    f = fbs_core.harmonic(state.case.harmonic).frequencies()
    assert (freq.start, freq.end) == (f[0], f[-1])
    state.case.harmonic = 6
    f = fbs_core.harmonic(6).frequencies()
    assert (freq.start, freq.end) == (f[0], f[-1])
    assert (freq.reset_start, freq.reset_end) == (f[0], f[-1])


def test_an_older_state_computed_slowly_never_lands_last(monkeypatch):
    """Two control changes of one session handled by two worker threads: the thread that
    read the older state computes slowly. The published response must be the newest
    state's (computed and published under the session's lock, the state read inside it)."""
    res = Results(DashboardState())
    res.state.noise.rounds = 20
    slow_started, go_on = threading.Event(), threading.Event()
    real = compute.mobility_data

    def mobility_data(harmonic, *args):
        if harmonic == 3:
            slow_started.set()
            assert go_on.wait(30)
        return real(harmonic, *args)

    monkeypatch.setattr(compute, "mobility_data", mobility_data)
    a = threading.Thread(target=setattr, args=(res.state.case, "harmonic", 3))
    a.start()
    assert slow_started.wait(30)
    b = threading.Thread(target=setattr, args=(res.state.case, "harmonic", 1))
    b.start()
    go_on.set()
    a.join(60)
    b.join(60)
    assert res.response.meta["harmonic"] == 1
    want = fbs_core.bushing_response(1, n_modes=res.state.case.n_modes)
    np.testing.assert_allclose(
        res.response.columns["truncated"],
        want.sel(outputs="bushing:z").data[:, 0, 0],
        rtol=1e-9,
    )


def test_caption_text_is_escaped_html_with_bold_and_middots():
    from app.views.live import inline_html

    # a DOF label from a user's file is text, never markup
    assert (
        inline_html("**Harmonic 2** &middot; bushing:<img src=x onerror=1> & co")
        == "<b>Harmonic 2</b> &middot; bushing:&lt;img src=x onerror=1&gt; &amp; co"
    )


def test_caption_follows_the_state(page):
    import html

    from app.views import MobilityView

    state, app, _ = page
    view = MobilityView(store=app.results)
    view.__panel__()
    state.case.n_modes = 70
    text = html.unescape(view._caption.text)
    assert f"<b>Harmonic {state.case.harmonic}</b>" in text and "N = 70" in text


def test_a_caption_change_sends_one_small_patch():
    """A changed caption is one change of one string property (no new models, nothing
    else re-sent); an unchanged one sends nothing."""
    import panel as pn
    from bokeh.document import Document

    from app.views.live import LiveText

    doc = Document()
    caption = LiveText("<p>a</p>")
    doc.add_root(pn.panel(caption).get_root(doc))  # the page holds it
    n_models = len(doc.models)
    events = []
    doc.on_change(events.append)
    caption.text = "<p>b</p>"
    caption.text = "<p>b</p>"
    assert [(e.model, e.attr) for e in events] == [(caption.model, "text")]
    assert len(doc.models) == n_models
    # sent as Panel's HTML pane sends the same HTML (the page decodes it once)
    for shown in ("<p>b</p>", "<p><b>N</b> &middot; bushing:&lt;img src=x&gt;</p>"):
        caption.text = shown
        pane_model = pn.pane.HTML(shown).get_root(Document())
        assert type(caption.model) is type(pane_model)
        assert caption.model.text == pane_model.text and caption.text == shown
