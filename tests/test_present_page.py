"""Issue 17 without a browser: input validation messages, the harmonic's description, the
band's progress and cancel, exports with date and page URL, the short reproducing link, and
sections other views contribute to the report.

Truth: the parameters' own bounds (param), the harmonic definitions of fbs_core, the core's
scatter band computed directly, and the CSV read back.
"""

from __future__ import annotations

import datetime as dt
import html
import threading
import time

import numpy as np
import pytest

import fbs_core
from app.export import read_csv, to_csv
from app.main import EXTRA_CARDS, PageParts, create_app
from app.page.titles import short_query
from app.report import build_html, build_pdf
from app.report.data import ExtraSection
from app.report.session import report_data
from app.results import progress_status
from app.runtime import bands
from app.state import DashboardState
from app.store import Results
from app.views.controls import Controls, harmonic_text
from app.views.live import export_meta


# -- validation feedback ------------------------------------------------------------------
@pytest.mark.parametrize(
    "key, typed, words",
    [
        ("noise.rounds", 0, "Rounds R: 0 is outside the allowed range 1 to 200,000"),
        ("noise.rounds", 300_000, "Rounds R: 300,000 is outside the allowed range 1 to 200,000"),
        ("noise.noise", 150.0, "Noise level p (%): 150 is outside the allowed range 0 to 99.99"),
        ("truncation.threshold", 0.0, "Error threshold (%): 0 is outside"),
        ("noise.seed", -1, "Seed: -1 is outside"),
    ],
)
def test_an_out_of_range_value_gets_a_message_and_the_field_shows_the_value_in_force(
    key, typed, words
):
    state = DashboardState()
    controls = Controls(state=state)
    w = controls.widgets()[key]
    group, name = key.split(".")
    before = getattr(getattr(state, group), name)
    w.value = f"{typed:g}"
    msg = controls.messages[key]
    assert msg.visible and words in msg.object
    assert f"still {before:,}" in msg.object or f"still {before:g}" in msg.object
    assert getattr(getattr(state, group), name) == before  # nothing changed
    assert w.value == f"{before:g}"  # the field no longer shows the refused value
    # a valid value is taken and clears the message
    good = 2 * before if before else 3
    w.value = str(good)
    assert getattr(getattr(state, group), name) == good and not msg.visible


def test_the_bounds_of_the_messages_are_the_parameters_own():
    state = DashboardState()
    controls = Controls(state=state)
    for key in ("noise.rounds", "noise.noise", "truncation.f_max"):
        group, name = key.split(".")
        obj = getattr(state, group)
        lo, hi = obj.param[name].bounds
        w = controls.widgets()[key]
        w.value = str(hi)  # the largest allowed value is taken
        assert getattr(obj, name) == hi and not controls.messages[key].visible
        with pytest.raises(ValueError):  # and param itself refuses one step above
            obj.param.update(**{name: hi + 1})
        w.value = str(hi + 1)
        assert controls.messages[key].visible and getattr(obj, name) == hi


def test_a_link_or_another_control_moves_the_field():
    state = DashboardState()
    controls = Controls(state=state)
    w = controls.widgets()["noise.rounds"]
    state.noise.rounds = 5000
    assert w.value == "5000"
    # a typed value beyond the slider's end moves the field and the slider alike
    state.truncation.threshold = 75.5
    field = controls.fields["truncation.threshold"]
    assert field.text.value == "75.5" and field.bar.value == 75.5


@pytest.mark.parametrize("k", range(1, 8))
def test_harmonic_text_has_wavelength_speeds_and_band(k):
    h = fbs_core.harmonic(k)
    text = harmonic_text(k)
    lo, hi = h.freq_range
    assert f"wavelength {h.wavelength:g} m" in text and "30-120 km/h" in text
    assert f"band {lo:.1f}-{hi:.1f} Hz" in text
    # the band is the speed range over the wavelength (f = v / lambda)
    assert abs(lo - 30 / 3.6 / h.wavelength) < 0.05 and abs(hi - 120 / 3.6 / h.wavelength) < 0.05


def test_the_line_under_the_harmonic_slider_follows_the_harmonic():
    # the wavelength/speeds/band line changes in place with the harmonic (its model is kept:
    # one text property changes, no new models are sent)
    state = DashboardState()
    controls = Controls(state=state)
    controls.__panel__()
    info = controls.harmonic_info
    model = info.model
    assert info.text == html.escape(harmonic_text(state.case.harmonic))
    for k in (3, 7, 1):
        state.case.harmonic = k
        assert info.text == html.escape(harmonic_text(k))
        assert f"Harmonic {k}: road wavelength" in model.text and info.model is model


# -- progress and cancel ----------------------------------------------------------------
def test_progress_status_says_done_total_and_time_left():
    st = progress_status(200_000, 221, 633, 70.4)
    assert st.busy and st.percent == 34
    assert "34 % (221 of 633 frequency lines)" in st.text and "about 1 min 10 s left" in st.text
    assert progress_status(10, 0, 0, None).text == "Computing 10 rounds ..."


def test_a_band_reports_its_progress_and_the_cancel_button_stops_it():
    """The band's progress reaches the page's status (lines done of the harmonic's lines,
    from the kernel) and a cancel stops it; the old band stays, marked by the status."""
    res = Results()  # not served: the first band is computed here
    res.state.noise.rounds = 50
    old = res.band
    assert old is not None and old.result.rounds == 50
    res.background = True  # then on a thread of its own, as when served
    seen = []
    res.PROGRESS_INTERVAL = 0.0
    res.param.watch(lambda e: seen.append(e.new), "band_status")
    gate = threading.Event()
    turns = bands.Turnstile()
    orig = turns.next_turn

    def slow_turn(job):  # each chunk waits for the test: progress is observed mid-way
        gate.wait(timeout=60)
        gate.clear()
        return orig(job)

    turns.next_turn = slow_turn
    saved = bands.TURNSTILE
    bands.TURNSTILE = turns
    try:
        # 8 * 6 * R bytes per line: with max_chunk_bytes 64e6, R = 100,000 gives 13 lines
        res.state.case.harmonic = 7
        res.state.noise.rounds = 100_000
        total = fbs_core.harmonic(7).frequencies().size
        deadline = time.monotonic() + 120
        while not any(s.done > 0 for s in seen) and time.monotonic() < deadline:
            gate.set()  # one more chunk
            time.sleep(0.02)
        busy = [s for s in seen if s.busy and s.total]
        assert busy and busy[-1].total == total and 0 < busy[-1].done < total
        assert f"of {total} frequency lines" in busy[-1].text
        res.cancel_band()
        gate.set()
        st = res.band_status
        assert not st.busy and st.text.startswith("Cancelled after")
        assert "earlier settings" in st.text
        assert res.band is old  # the band on the page stays (marked stale by the view)
    finally:
        bands.TURNSTILE = saved
        gate.set()
        res.close()


# -- exports ---------------------------------------------------------------------------
def test_every_export_carries_date_and_the_page_url():
    now = dt.datetime(2026, 12, 1, 22, 5, tzinfo=dt.UTC)
    url = "http://localhost:5006/main?h=3&N=60"
    meta = export_meta({"view": "x", "models": "reference"}, url=url, now=now)
    text = to_csv({"freq_Hz": np.array([1.0, 2.0])}, meta, "x")
    got, cols = read_csv(text)
    assert got["exported"] == "2026-12-01 22:05 UTC" and got["page URL"] == url
    assert got["models"] == "reference" and "fbs_core version" in got


def test_uncoupled_export_has_hz_in_the_frequency_column_and_a_unit_line():
    res = Results()
    res.state.case.param.update(show_uncoupled=True, dof="rx", spindle_input="y")
    r = res.uncoupled
    assert list(r.columns)[0] == "freq_Hz"
    np.testing.assert_array_equal(r.columns["freq_Hz"], fbs_core.harmonic(1).frequencies())
    # rotation rx per metre of road at the hub; rotation rx per force y at the chassis
    assert "tire_*: (rad/s)/m" in r.meta["unit"] and "chassis: rad/(N s)" in r.meta["unit"]
    for name in ("error_map", "suggested"):
        assert getattr(res, name).meta["models"] == res.state.data.models.describe()
    res.close()


def test_the_short_link_keeps_only_values_that_differ_from_the_defaults():
    q = {"h": 1, "N": 120, "dof": "z", "noise": 10.0, "fdep": False, "view": "present"}
    assert short_query(q) == {"N": 120, "view": "present"}
    # the kept values reproduce the state: applied to a default state they give q
    state = DashboardState()
    state.case.n_modes = 120
    assert state.case.harmonic == 1 and state.noise.noise == 10.0


# -- sections other views contribute -----------------------------------------------------
def test_a_published_result_becomes_a_report_section_while_it_is_current():
    """Every current result beyond the report's own sections is a section of it: its
    description as a table and its dB columns over frequency as curves (a pin against the
    current state here); a result of a tab looked at is reported while it is of the
    current values, and left out once they changed."""
    res = Results()
    res.state.noise.rounds = 30
    res.pin("base")  # N = 50
    res.state.case.n_modes = 80
    extra = report_data(res).extra
    # the store's own tire-quality result is one too; uncoupled not shown: not reported
    assert [e.key for e in extra] == ["tire_quality", "pinned-1"]
    pin = extra[1]
    assert pin.heading == "Pinned state 'base' against the current state"
    r = res.pinned[0]
    np.testing.assert_array_equal(pin.curves["pin base"], r.columns["pin_base_dB"])
    np.testing.assert_array_equal(pin.curves["current"], res.response.columns["truncated_dB"])
    snap = report_data(res)
    name, html = build_html(snap)
    assert 'id="pinned-1"' in html and "N=50 bushing:z" in html
    assert 'id="figure-pinned-1"' in html  # its curves are drawn
    _, pdf = build_pdf(snap)
    assert pdf.startswith(b"%PDF")
    res.state.analysis.tab = "phase"  # shown: its results are current, and reported
    assert "phase" in [e.key for e in report_data(res).extra]
    res.state.analysis.tab = ""  # looked at, and still of the current values: reported
    assert "phase" in [e.key for e in report_data(res).extra]
    res.state.case.n_modes = 90  # the phase view of N = 80 is left behind: not reported
    assert "phase" not in [e.key for e in report_data(res).extra]
    res.close()


def test_extra_sections_refuse_curves_of_another_length():
    with pytest.raises(ValueError, match="curve 'a' has shape"):
        ExtraSection("k", "K", freq=np.arange(3.0), curves={"a": np.zeros(4)})


# -- the page's insertion point --------------------------------------------------------
def test_extra_cards_are_inserted_below_the_plots():
    made = []

    def card(parts: PageParts):
        made.append(parts)
        return parts.card("Extra card", "extra content", 200, css_classes=["extra-card"])

    EXTRA_CARDS.append(card)
    try:
        state = DashboardState()
        state.noise.rounds = 30
        app = create_app(state)
    finally:
        EXTRA_CARDS.remove(card)
    main = app.main[0]
    assert made and made[0].results is app.results and made[0].page is app.page
    assert "extra-card" in main.objects[-1].css_classes
    app.results.close()


# -- the data in use on every plot -------------------------------------------------------
@pytest.mark.parametrize("key", ["mobility", "truncation", "scatter", "eigen", "uncoupled"])
def test_every_plot_title_names_the_data_in_use(key):
    import dataclasses

    from app.datasource import Models
    from app.page.titles import view_title
    from app.results import Snapshot

    s = Snapshot.of(DashboardState())
    tb, stem = view_title(key, s, "http://localhost:5006/main?h=1")
    assert any(line.startswith("Data: reference models") for line in tb.lines)
    assert "_upload" not in stem
    up = Models(
        tire=None, chassis=object(), key="tire=reference;chassis=abc123", chassis_name="rig.uff"
    )
    tb, stem = view_title(key, dataclasses.replace(s, models=up))
    assert any(line.startswith("Data: uploaded chassis 'rig.uff'") for line in tb.lines)
    assert "_upload" in stem  # the saved image's name says so too
