"""The verdict against hand-made cases whose numbers are known in closed form.

Truth: responses built here line by line with a level chosen at each line (a peak of
known height at a known line, a rise that crosses the target only at the band's last
line, a constant level under a V-shaped target), noise edges built as the nominal level
times a known factor, and the harmonic's speed line v = 3.6 f lambda written out with
the wavelength of thesis table 5.1.
"""

from __future__ import annotations

import csv
import io
import math

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.errors import DOFError, FBSError, FrequencyGridError, QuantityError
from fbs_core.targets import IncumbentTarget, Target
from fbs_core.verdict import FAIL, NOISE_FAIL, NOT_JUDGED, PASS, NoiseEdge, verdict

BUSHING = fc.node_labels("bushing")
LAMBDA_4 = 0.2395  # m, harmonic 4 (thesis table 5.1 band 34.8-139 Hz)
F = np.arange(36.0, 138.0 + 1e-9, 2.0)  # harmonic 4's lines, 2 Hz apart


def response(levels_db: dict[str, np.ndarray], freq: np.ndarray = F, phase: float = 0.7):
    """A bushing response with the given level (dB re 1 (m/s)/m) per DOF, -80 dB elsewhere."""
    data = np.full((freq.size, 6, 1), 1e-4, complex)
    for dof, db in levels_db.items():
        data[:, BUSHING.index(dof), 0] = 10 ** (np.asarray(db) / 20) * np.exp(1j * phase)
    return fc.FRF(freq, data, BUSHING, ["patch"])


def flat(dof: str, db: float, lo: float = 30.0, hi: float = 150.0, **kw) -> Target:
    return Target.segments(dof, [(lo, db), (hi, db)], axis="linear", **kw)


def test_a_peak_of_known_height_above_a_flat_target():
    f0 = 72.0
    level = -30.0 + 12.0 * np.exp(-(((F - f0) / 6.0) ** 2))  # -18 dB at 72 Hz exactly
    v = verdict({("A", 4): response({"bushing:z": level})}, [flat("bushing:z", -21.5)])
    (r,) = v.rows
    assert r.status == FAIL
    assert r.worst_db == pytest.approx(3.5, abs=1e-9)
    assert r.exceedance_db == pytest.approx(3.5, abs=1e-9)
    assert r.freq == f0
    assert r.speed == pytest.approx(3.6 * f0 * LAMBDA_4, rel=1e-12)
    assert math.isnan(r.margin_db)
    assert r.lines == F.size and r.point == "bushing" and r.harmonic == 4


def test_a_crossing_only_at_the_last_line_of_the_band_fails_there():
    level = np.linspace(-40.0, -19.0, F.size)  # rises 21 dB; only the last line tops -20
    v = verdict({("A", 4): response({"bushing:x": level})}, [flat("bushing:x", -20.0)])
    (r,) = v.rows
    assert r.status == FAIL
    assert r.freq == F[-1] and r.worst_db == pytest.approx(1.0, abs=1e-9)
    # and at the first line alike (one rule for every line)
    v2 = verdict({("A", 4): response({"bushing:x": level[::-1]})}, [flat("bushing:x", -20.0)])
    assert v2.rows[0].freq == F[0] and v2.rows[0].worst_db == pytest.approx(1.0, abs=1e-9)


def test_the_margin_is_the_smallest_distance_below_the_target():
    # constant -40 dB under a V: -25 dB at 40 and 80 Hz, -35 dB at 60 Hz: 5 dB at 60 Hz
    t = Target.segments("bushing:y", [(40, -25), (60, -35), (80, -25)], axis="linear")
    v = verdict({("A", 4): response({"bushing:y": np.full(F.size, -40.0)})}, [t])
    (r,) = v.rows
    assert r.status == PASS
    assert r.margin_db == pytest.approx(5.0, abs=1e-9) and r.worst_db == pytest.approx(-5.0)
    assert r.freq == 60.0 and r.exceedance_db == 0.0
    assert r.lines == np.count_nonzero((F >= 40) & (F <= 80))  # only its range is judged


def test_a_level_equal_to_the_target_passes_with_zero_margin():
    v = verdict(
        {("A", 4): response({"bushing:z": np.full(F.size, -20.0)})}, [flat("bushing:z", -20.0)]
    )
    assert v.rows[0].status == PASS and v.rows[0].margin_db == pytest.approx(0.0, abs=1e-9)


def test_fails_within_the_noise_band():
    f0 = 100.0
    level = -30.0 + 18.0 * np.exp(-(((F - f0) / 4.0) ** 2))  # -12 dB at 100 Hz
    nominal = 10 ** (level / 20)
    upper = np.tile(nominal[:, None], (1, 6)) * 10 ** (3.0 / 20)  # +3 dB everywhere
    edge = NoiseEdge(F, BUSHING, upper, q=95.0)
    target = flat("bushing:z", -10.0)  # nominal 2 dB below, the edge 1 dB above
    v = verdict({("A", 4): response({"bushing:z": level})}, [target], {("A", 4): edge})
    (r,) = v.rows
    assert r.status == NOISE_FAIL
    assert r.margin_db == pytest.approx(2.0, abs=1e-9)
    assert r.band_worst_db == pytest.approx(1.0, abs=1e-9)
    assert r.band_freq == f0 and r.band_q == 95.0
    assert r.band_speed == pytest.approx(3.6 * f0 * LAMBDA_4, rel=1e-12)
    # a band that stays below passes
    low = NoiseEdge(F, BUSHING, upper * 10 ** (-1.5 / 20))
    v2 = verdict({("A", 4): response({"bushing:z": level})}, [target], {("A", 4): low})
    assert v2.rows[0].status == PASS and v2.rows[0].band_worst_db == pytest.approx(-0.5)


def test_a_band_crossing_only_at_its_first_line_counts():
    level = np.full(F.size, -30.0)
    upper = np.full((F.size, 6), 10 ** (-30.0 / 20))
    upper[0, 2] = 10 ** (-24.0 / 20)  # only the band's first line reaches above -25 dB
    v = verdict(
        {("A", 4): response({"bushing:z": level})},
        [flat("bushing:z", -25.0)],
        {("A", 4): NoiseEdge(F, BUSHING, upper)},
    )
    r = v.rows[0]
    assert r.status == NOISE_FAIL and r.band_freq == F[0]
    assert r.band_worst_db == pytest.approx(1.0, abs=1e-9)


def test_quantity_and_dof_kinds_of_the_target_are_converted():
    # |v| = 0.5 / (2 pi f) under a flat accelerance target of 1 (m/s^2)/m: 6.02 dB margin
    level = 20 * np.log10(0.5 / (2 * np.pi * F))
    t = flat("bushing:z", 0.0, quantity="accelerance")
    r = verdict({("A", 4): response({"bushing:z": level})}, [t]).rows[0]
    assert r.status == PASS and r.margin_db == pytest.approx(20 * math.log10(2.0), abs=1e-9)


def test_several_uncorrelated_inputs_add_in_power():
    data = np.zeros((F.size, 1, 2), complex)
    data[:, 0, 0], data[:, 0, 1] = 0.6, 0.8j  # sqrt(0.36 + 0.64) = 1: 0 dB
    Y = fc.FRF(F, data, ["seat_fl:z"], ["road_in_phase", "road_anti_phase"],
               kinds={"road_in_phase": "road", "road_anti_phase": "road"})  # fmt: skip
    r = verdict({("A", 4): Y}, [flat("seat_fl:z", -1.0)]).rows[0]
    assert r.status == FAIL and r.worst_db == pytest.approx(1.0, abs=1e-9)


def test_a_target_outside_the_lines_is_not_judged_and_harmonic_targets_take_precedence():
    level = np.full(F.size, -30.0)
    general = flat("bushing:z", -20.0)
    only_h5 = flat("bushing:x", -20.0, lo=150.0, hi=400.0)
    for4 = flat("bushing:z", -35.0, harmonic=4)
    resp = {("A", 4): response({"bushing:z": level, "bushing:x": level})}
    v = verdict(resp, [general, only_h5, for4])
    assert v.row("A", 4, "bushing:z").status == FAIL  # the harmonic-4 target (-35 dB)
    assert v.row("A", 4, "bushing:z").worst_db == pytest.approx(5.0)
    assert v.row("A", 4, "bushing:x").status == NOT_JUDGED
    assert [r.dof for r in v.rows] == ["bushing:x", "bushing:z"]  # DOFs without targets: none


def test_the_incumbent_plus_margin():
    base = -30.0 + 10.0 * np.sin(F / 9.0)
    resp = {
        ("incumbent", 4): response({"bushing:z": base}),
        ("louder", 4): response({"bushing:z": base + 2.0}),
    }
    v = verdict(resp, [IncumbentTarget("incumbent", 3.0, dofs=("bushing:z",))])
    assert v.row("incumbent", 4, "bushing:z").margin_db == pytest.approx(3.0, abs=1e-9)
    assert v.row("louder", 4, "bushing:z").margin_db == pytest.approx(1.0, abs=1e-9)
    v1 = verdict(resp, [IncumbentTarget("incumbent", 1.0, dofs=("bushing:z",))])
    assert v1.row("louder", 4, "bushing:z").worst_db == pytest.approx(1.0, abs=1e-9)
    assert v1.row("louder", 4, "bushing:z").status == FAIL
    with pytest.raises(FBSError, match="no response to harmonic 5"):
        verdict({**resp, ("louder", 5): response({}, np.arange(52.0, 200.0, 2.0))},
                [IncumbentTarget("incumbent", 1.0)])  # fmt: skip


def test_the_ranking_passes_first_then_noise_band_then_fails():
    level = {"A": -40.0, "B": -37.0, "C": -32.0, "D": -36.0, "E": -39.0}
    resp = {(n, 4): response({"bushing:z": np.full(F.size, db)}) for n, db in level.items()}
    up = np.full((F.size, 6), 10 ** (-33.0 / 20))
    bands = {("D", 4): NoiseEdge(F, BUSHING, up)}  # D's edge tops the -35 dB target
    v = verdict(resp, [flat("bushing:z", -35.0)], bands)
    order = [(s.rank, s.candidate, s.status) for s in v.ranking]
    assert order == [
        (1, "A", PASS),  # margin 5
        (2, "E", PASS),  # margin 4
        (3, "B", PASS),  # margin 2
        (4, "D", NOISE_FAIL),
        (5, "C", FAIL),  # 3 dB over
    ]
    assert v.ranking[-1].worst_db == pytest.approx(3.0) and v.ranking[-1].fails == 1
    # two failing candidates: the smaller exceedance first
    resp2 = {**resp, ("F", 4): response({"bushing:z": np.full(F.size, -34.0)})}
    names = [s.candidate for s in verdict(resp2, [flat("bushing:z", -35.0)]).ranking]
    assert names[-2:] == ["F", "C"]


def test_bad_input_is_refused_naming_the_problem():
    r = {("A", 4): response({"bushing:z": np.full(F.size, -30.0)})}
    with pytest.raises(DOFError, match="'hub:z'.*response DOFs"):
        verdict(r, [flat("hub:z", -20.0)])
    with pytest.raises(FBSError, match="two targets for bushing:z"):
        verdict(r, [flat("bushing:z", -20.0), flat("bushing:z", -25.0)])
    other = NoiseEdge(F[:-1], BUSHING, np.ones((F.size - 1, 6)))
    with pytest.raises(FrequencyGridError, match="one grid"):
        verdict(r, [flat("bushing:z", -20.0)], {("A", 4): other})
    with pytest.raises(FrequencyGridError, match="outside the 4th harmonic band"):
        verdict({("A", 4): response({}, np.array([20.0, 30.0]))}, [flat("bushing:z", 0.0)])
    with pytest.raises(QuantityError, match="per force"):
        verdict(r, [flat("bushing:z", -20.0, input_kind="force")])
    with pytest.raises(fc.HarmonicError):
        verdict({("A", 8): r[("A", 4)]}, [])
    with pytest.raises(FBSError, match="incumbent 'B' has no responses"):
        verdict(r, [IncumbentTarget("B")])


def test_csv_export_has_a_metadata_header_and_the_rows():
    level = -30.0 + 12.0 * np.exp(-(((F - 72.0) / 6.0) ** 2))
    v = verdict(
        {
            ("=cmd", 4): response({"bushing:z": level}),
            ("B", 4): response({"bushing:z": level - 10}),
        },
        [flat("bushing:z", -21.5)],
    )
    text = v.to_csv({"meeting": "supplier review"}).decode()
    head = [ln for ln in text.splitlines() if ln.startswith("# ") and ":" in ln]
    assert "# tire-fbs verdict" in text.splitlines()[0]
    assert any(ln.startswith("# fbs_core_version: ") for ln in head)
    assert "# meeting: supplier review" in head
    blocks = text.split("# table: ")
    rows = list(csv.DictReader(io.StringIO(blocks[1].split("\n", 1)[1])))
    assert [r["candidate"] for r in rows] == ["'=cmd", "B"]  # no spreadsheet formula
    assert float(rows[0]["worst_db"]) == pytest.approx(3.5, abs=1e-9)
    assert float(rows[0]["speed_kmh"]) == pytest.approx(3.6 * 72.0 * LAMBDA_4)
    assert rows[1]["status"] == "pass" and float(rows[1]["margin_db"]) == pytest.approx(6.5)
    ranking = list(csv.DictReader(io.StringIO(blocks[2].split("\n", 1)[1])))
    assert [r["candidate"] for r in ranking] == ["B", "'=cmd"]


def test_a_candidate_with_nothing_judged_ranks_last():
    f5 = np.arange(52.0, 200.0, 2.0)  # harmonic 5's lines
    resp = {
        ("A", 4): response({"bushing:z": np.full(F.size, -10.0)}),  # fails by 10 dB
        ("B", 5): response({"bushing:z": np.full(f5.size, -30.0)}, f5),
    }
    v = verdict(resp, [flat("bushing:z", -20.0, harmonic=4)])
    assert [(s.candidate, s.status) for s in v.ranking] == [("A", FAIL), ("B", NOT_JUDGED)]
    assert math.isnan(v.ranking[1].worst_db)
    # B's harmonic has no target: B has no row at all
    assert {r.candidate for r in v.rows} == {"A"}
    with pytest.raises(FBSError, match="no verdict row for 'B', harmonic 5"):
        v.row("B", 5, "bushing:z")
