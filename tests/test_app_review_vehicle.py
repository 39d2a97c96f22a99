"""The review in vehicle scope: targets at the car's response points and their verdict.

Truth: the car's response computed here by the core directly
(:func:`fbs_core.vehicle.vehicle_response` with each candidate's tire on its four wheels, all
modes, on the harmonic's grid), past the app's caches and joins; the targets are flat lines
placed a known number of dB above or below those responses' peaks, so every status, worst
exceedance and margin is known by construction.
"""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core
from app.state import DashboardState
from app.store import Results
from fbs_core.tire import TireModel
from fbs_core.tire.storage import save_tire_model
from fbs_core.vehicle import vehicle_response

H = 2
TRACKS = "anti-phase"
WHEELS = ("fl", "fr", "rl")


def _tire(scale: float, tag: str) -> TireModel:
    t = fbs_core.reference_tire()
    return TireModel(
        t.speeds, t.poles * scale, t.psi, t.chi, t.wavelengths, t.participation,
        meta={"source": tag},
    )  # fmt: skip


@pytest.fixture(scope="module")
def soft():
    return _tire(0.96, "soft")


def _session(tmp_path, soft) -> tuple[DashboardState, Results]:
    st = DashboardState()
    store = Results(st)
    raw = save_tire_model(soft, tmp_path / "soft.h5").read_bytes()
    assert st.data.load_tire(raw, "soft.h5"), st.data.error
    st.case.param.update(scope="vehicle", harmonic=H, tracks=TRACKS, wheels=list(WHEELS))
    return st, store


def _peak_db(model: TireModel | None, dof: str, k: int = H) -> float:
    """The car's level peak at ``dof`` (dB re 1 (m/s)/m), the core's own car response."""
    kw = {} if model is None else {"tire": model}
    r = vehicle_response(
        k, None, fbs_core.harmonic(k).frequencies(), tracks=TRACKS, wheels=WHEELS,
        outputs=dof.split(":")[0], **kw,
    )  # fmt: skip
    return float(20 * np.log10(r.level[:, list(r.outputs).index(dof)].max()))


def _flat_csv(dof: str, level_db: float, k: int = H) -> bytes:
    f = fbs_core.harmonic(k).frequencies()
    return (
        "# tire-fbs target\n# quantity: mobility\n# scale: dB\n"
        f"# harmonic: {k}\nfreq [Hz],{dof}\n{float(f[0])!r},{float(level_db)!r}\n"
        f"{float(f[-1])!r},{float(level_db)!r}\n"
    ).encode()


def test_targets_at_two_points_of_the_car_are_judged_for_every_candidate(tmp_path, soft):
    st, store = _session(tmp_path, soft)
    seat, strut = "seat_fl:z", "strut_fr:x"
    ref_seat, soft_seat = _peak_db(None, seat), _peak_db(soft, seat)
    ref_strut, soft_strut = _peak_db(None, strut), _peak_db(soft, strut)
    assert abs(soft_seat - ref_seat) > 0.3  # another tire, another car response
    # the seat's target 2 dB above the reference's peak; the strut's 1.5 dB below the soft's
    seat_level = ref_seat + 2.0
    strut_level = soft_strut - 1.5
    assert st.data.load_targets(_flat_csv(seat, seat_level), "seat.csv"), st.data.error
    assert st.data.load_targets(_flat_csv(strut, strut_level), "strut.csv"), st.data.error
    r = store.verdict
    assert r.draw["state"] == "done", r.caption
    v = r.core["verdict"]
    judged = {(x.candidate, x.dof) for x in v.rows if x.harmonic == H}
    assert judged == {(c, d) for c in ("reference", "soft.h5") for d in (seat, strut)}
    assert {x.dof for x in v.rows} == {seat, strut}  # only the car's points with a target
    row = v.row("reference", H, seat)
    assert row.status == "pass" and row.margin_db == pytest.approx(2.0, abs=1e-6)
    row = v.row("soft.h5", H, seat)
    assert row.worst_db == pytest.approx(soft_seat - seat_level, abs=1e-6)
    assert row.status == ("fail" if soft_seat > seat_level else "pass")
    row = v.row("soft.h5", H, strut)
    assert row.status == "fail" and row.worst_db == pytest.approx(1.5, abs=1e-6)
    row = v.row("reference", H, strut)
    assert row.worst_db == pytest.approx(ref_strut - strut_level, abs=1e-6)
    # the header names the scope, the road and the points judged
    assert "(strut_fr, seat_fl)" in r.meta["responses"]  # in the car's order of points
    assert "anti-phase" in r.meta["tracks (right against left)"]
    assert "car" in r.filename and "at the car's strut_fr, seat_fl" in r.caption
    # the report's verdict section says what was judged: the car's points
    from app.report.content import verdict_section

    text = verdict_section(v).paragraphs[0]
    assert "the car's strut_fr, seat_fl" in text and "four wheels" in text


def test_the_road_and_the_scope_choose_what_is_judged(tmp_path, soft):
    st, store = _session(tmp_path, soft)
    seat = "seat_rr:y"
    assert st.data.load_targets(_flat_csv(seat, _peak_db(None, seat) + 1.0), "t.csv")
    in_anti = store.verdict.core["verdict"].row("reference", H, seat)
    assert in_anti.margin_db == pytest.approx(1.0, abs=1e-6)
    # the same target in phase: another road, another response, another margin
    st.case.tracks = "in phase"
    r = vehicle_response(
        H, None, fbs_core.harmonic(H).frequencies(), tracks="in phase", wheels=WHEELS,
        outputs="seat_rr",
    )  # fmt: skip
    peak = 20 * np.log10(r.level[:, list(r.outputs).index(seat)].max())
    got = store.verdict.core["verdict"].row("reference", H, seat)
    assert got.worst_db == pytest.approx(peak - (_peak_db(None, seat) + 1.0), abs=1e-6)
    # the corner judges the bushing's targets only: none here
    st.case.scope = "corner"
    r = store.verdict
    assert r.draw["state"] == "no targets" and "No target at the bushing" in r.caption


def test_vehicle_scope_without_a_target_at_the_car_says_so(tmp_path, soft):
    st, store = _session(tmp_path, soft)
    f = fbs_core.harmonic(H).frequencies()
    csv = _flat_csv("bushing:z", -20.0)
    assert st.data.load_targets(csv, "bushing.csv"), st.data.error
    r = store.verdict
    assert r.draw["state"] == "no targets"
    assert "No target at the car's response points" in r.caption
    # the incumbent rule judges the point shown: the incumbent itself passes by its margin
    st.case.point = "seat_fl"
    assert st.data.set_incumbent("reference", 3.0), st.data.error
    v = store.verdict.core["verdict"]
    rows = [x for x in v.rows if x.candidate == "reference"]
    assert {x.point for x in v.rows} == {"seat_fl"} and len(rows) == 6 * 7
    assert all(x.status == "pass" and x.margin_db == pytest.approx(3.0) for x in rows)
    # the overlay draws the incumbent's line at the point and DOF shown
    st.case.dof = "z"
    d = store.review_curves.draw
    assert d["target"] is not None and "incumbent reference +3 dB" in d["target_label"]
    r = vehicle_response(
        H, None, f, tracks=TRACKS, wheels=WHEELS, outputs="seat_fl",
    )  # fmt: skip
    want = 20 * np.log10(r.level[:, list(r.outputs).index("seat_fl:z")]) + 3.0
    np.testing.assert_allclose(d["target"], want, atol=1e-6)


def test_a_target_at_a_point_the_car_does_not_have_is_refused(tmp_path, soft):
    st, _store = _session(tmp_path, soft)
    before = st.data.review
    assert not st.data.load_targets(_flat_csv("seat_xx:z", -10.0), "bad.csv")
    assert "seat_xx:z" in st.data.error and "seat_fl:z" in st.data.error
    assert st.data.review is before


def test_the_cars_noise_band_needs_a_coherent_road(tmp_path, soft):
    st, store = _session(tmp_path, soft)
    seat = "seat_fl:z"
    assert st.data.load_targets(_flat_csv(seat, _peak_db(None, seat) + 1.0), "t.csv")
    st.case.param.update(tracks="coherence", coherence=0.3)
    st.noise.param.update(rounds=20, verdict_band=True)
    r = store.verdict
    assert r.draw["state"] == "problem" and "coherent road" in r.caption
    assert "0.3" in r.caption


def test_the_cars_noise_band_judges_a_target_only_its_upper_edge_crosses():
    """A flat target at the seat between the car's nominal peak and its noise band's upper
    95 % edge there: the nominal passes, the band does not. Truth: the core's own car band
    (same seed and rounds: the same draws) and the core's verdict of it."""
    from fbs_core.vehicle import vehicle_scatter_band
    from fbs_core.verdict import NoiseEdge, verdict

    st = DashboardState()
    store = Results(st)
    st.case.param.update(scope="vehicle", tracks="in phase", point="seat_fl")
    st.noise.param.update(noise=10.0, target="both", rounds=60, seed=5, percentile=90)
    dof = "seat_fl:z"
    f = fbs_core.harmonic(H).frequencies()
    nominal = vehicle_response(H, None, f, tracks="in phase", outputs="seat_fl")
    band = vehicle_scatter_band(
        H, noise=0.1, target="both", rounds=60, seed=5, outputs="seat_fl",
        tracks="in phase", percentiles=(5.0, 95.0),
    )  # fmt: skip
    j = list(band.dofs).index(dof)
    peak = 20 * np.log10(nominal.level[:, list(nominal.outputs).index(dof)].max())
    edge = 20 * np.log10(band.percentiles[1][:, j].max())
    assert edge > peak + 0.2  # the band lifts the edge above the nominal peak
    level = peak + (edge - peak) / 2
    assert st.data.load_targets(_flat_csv(dof, level), "seat.csv"), st.data.error
    assert store.verdict.core["verdict"].row("reference", H, dof).status == "pass"
    st.noise.verdict_band = True
    r = store.verdict
    got = r.core["verdict"].row("reference", H, dof)
    assert got.status == "fails within the noise band"
    direct = verdict(
        {("reference", H): nominal.response},
        st.data.review.targets,
        {("reference", H): NoiseEdge.of_band(band, 95.0)},
    ).row("reference", H, dof)
    assert got.band_worst_db == pytest.approx(direct.band_worst_db, abs=1e-6)
    assert got.band_freq == direct.band_freq and got.worst_db == pytest.approx(direct.worst_db)
