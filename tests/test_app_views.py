"""Views without a browser: state -> computed data -> plot data (Bokeh models, rendered
in-process), and which views each control touches."""

import numpy as np
import pytest
from bokeh.models import ColumnDataSource

import fbs_core
from app import compute
from app.main import create_app
from app.state import DashboardState

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


def test_plotted_mobility_is_the_core_prediction(page):
    state, _, root = page
    c = state.case
    src = _sources(root)
    br = fbs_core.bushing_response(c.harmonic, n_modes=c.n_modes, coupling=c.coupling)
    ref = fbs_core.bushing_response(c.harmonic, coupling=c.coupling)
    np.testing.assert_allclose(src["mobility.truncated"].data["freq"], br.freq)
    want = 20 * np.log10(np.abs(br.sel(outputs=f"bushing:{c.dof}").data[:, 0, 0]))
    np.testing.assert_allclose(src["mobility.truncated"].data["level"], want, rtol=1e-9)
    want = 20 * np.log10(np.abs(ref.sel(outputs=f"bushing:{c.dof}").data[:, 0, 0]))
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

    mappers = list(root.select({"type": LinearColorMapper}))
    assert [m.high for m in mappers] == [12.0]


def test_view_data_and_csv_columns_agree(page):
    state, app, root = page
    from app.views import MobilityView, ScatterBandView, TruncationView

    mob = MobilityView(case=state.case)
    d = mob.data()
    want = compute.mobility_data(
        state.case.harmonic, state.case.n_modes, state.case.dof, state.case.coupling
    )
    np.testing.assert_array_equal(d["truncated_db"], want["truncated_db"])
    cols = mob._csv_columns()
    np.testing.assert_array_equal(cols["truncated_dB"], d["truncated_db"])
    np.testing.assert_array_equal(cols["truncated"], d["truncated"])

    tv = TruncationView(case=state.case, truncation=state.truncation)
    m = tv.data()
    assert m["error_pct"].shape == (m["n_modes"].size, m["centre_freq"].size)
    long = tv._csv_columns()
    np.testing.assert_array_equal(long["error_pct"], m["error_pct"].ravel())

    sv = ScatterBandView(case=state.case, noise=state.noise)
    b = sv.data()
    assert np.all(b["minimum"] <= b["lower"] + 1e-12)
    assert np.all(b["upper"] <= b["maximum"] + 1e-12)
    r = sv.round_data()
    band = compute.band(*sv.key())
    np.testing.assert_array_equal(
        r["round"],
        band.round(state.noise.single_round)[:, band.dofs.index(f"bushing:{state.case.dof}")],
    )


def test_zero_noise_band_collapses_on_the_reference():
    state = DashboardState()
    state.noise.param.update(noise=0.0, rounds=50)
    from app.views import ScatterBandView

    sv = ScatterBandView(case=state.case, noise=state.noise)
    b = sv.data()
    np.testing.assert_allclose(b["minimum"], np.abs(b["reference"]), rtol=1e-12)
    np.testing.assert_allclose(b["maximum"], np.abs(b["reference"]), rtol=1e-12)


def test_suggested_table_follows_threshold_and_map_mode():
    state = DashboardState()
    from app.views import SuggestedModesView

    v = SuggestedModesView(case=state.case, truncation=state.truncation)
    loose = v.table()["n_modes"]
    state.truncation.threshold = 5.0
    strict = v.table()["n_modes"]
    assert np.all(strict >= loose)  # a stricter threshold never needs fewer modes
    assert list(v.table()["harmonic"]) == list(range(1, 8))


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
    f = compute.frequencies(state.case.harmonic)
    assert (freq.start, freq.end) == (f[0], f[-1])
    state.case.harmonic = 6
    f = compute.frequencies(6)
    assert (freq.start, freq.end) == (f[0], f[-1])
    assert (freq.reset_start, freq.reset_end) == (f[0], f[-1])


def test_a_slow_update_of_an_older_state_never_lands_last():
    """Two control changes of one session handled by two worker threads: the thread that
    read the older state finishes last. Its update must be dropped, so the plot shows the
    latest state (the ticket is drawn before the state is read)."""
    import threading

    from app.views.plots import Pusher

    state, shown = {"harmonic": 3}, []
    push = Pusher()
    a_has_read, b_is_done = threading.Event(), threading.Event()

    def make_a():  # reads harmonic 3, then computes slowly
        h = state["harmonic"]
        a_has_read.set()
        assert b_is_done.wait(5)
        return lambda: shown.append(h)

    def make_b():  # the next change: harmonic 1, computed quickly
        h = state["harmonic"]
        return lambda: shown.append(h)

    slow = threading.Thread(target=push, args=(make_a,))
    slow.start()
    assert a_has_read.wait(5)
    state["harmonic"] = 1
    push(make_b)
    b_is_done.set()
    slow.join(5)
    assert shown == [1]


def test_caption_text_is_escaped_html_with_bold_and_middots():
    from app.views.common import inline_html

    # a DOF label from a user's file is text, never markup
    assert (
        inline_html("**Harmonic 2** &middot; bushing:<img src=x onerror=1> & co")
        == "<b>Harmonic 2</b> &middot; bushing:&lt;img src=x onerror=1&gt; &amp; co"
    )


def test_live_text_follows_its_parameters():
    import html

    import param

    from app.views.common import live_text

    class P(param.Parameterized):
        h = param.Integer(1)

    p = P()
    pane = live_text(lambda: f"**Harmonic {p.h}**", [(p, ["h"])])
    model = pane.object
    assert html.unescape(model.text) == "<p><b>Harmonic 1</b></p>"
    p.h = 7  # no server: the update is applied at once
    assert html.unescape(model.text) == "<p><b>Harmonic 7</b></p>"
