"""End to end: the reference tire and a perturbed supplier tire through eq. 4.1, judged.

The responses come from the real coupling (:func:`fbs_core.bushing_response` with each
tire); the verdict's numbers are checked against a direct computation written here: the
level ``20 log10 |v|`` of the response data, the shipped example targets evaluated with
their points written out (straight lines in dB over ``log10 f``), the maximum of the
difference, its line and the speed ``3.6 f lambda``; the noise band's edge against the
95th percentile of its rounds regenerated one by one.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.candidates import Candidate, CandidateSet
from fbs_core.errors import FBSError
from fbs_core.targets import IncumbentTarget, read_targets
from fbs_core.verdict import FAIL, NOISE_FAIL, PASS, NoiseEdge, verdict

ROOT = Path(__file__).resolve().parents[1]
HARMONICS = (2, 4)
N_MODES = 60
#: The example target file's points (data/targets/bushing_targets.csv), dB re 1 (m/s)/m.
POINTS_HZ = np.array([10.0, 40.0, 100.0, 450.0])
POINTS_DB = {
    "bushing:x": np.array([28.0, 24.0, 18.0, 0.0]),
    "bushing:y": np.array([28.0, 24.0, 22.0, 5.0]),
    "bushing:z": np.array([20.0, 15.0, 10.0, 5.0]),
}
WAVELENGTH = {2: 0.499, 4: 0.2395}  # m, thesis table 5.1


@pytest.fixture(scope="module")
def review():
    ref = fc.reference_tire()
    # supplier B: every complex pole 3 % higher (eigenfrequencies +3 %, same damping ratios)
    b_tire = dataclasses.replace(ref, poles=ref.poles * 1.03, params=None, meta={})
    cands = CandidateSet(
        [
            Candidate.reference(),
            Candidate("supplier B", "b" * 24, b_tire, supplier="B", size="205/55 R16"),
        ]
    )
    resp = {}
    for c in cands:
        for k in HARMONICS:
            f = fc.harmonic(k).frequencies(2.0)
            resp[(c.name, k)] = fc.bushing_response(k, N_MODES, f, tire=c.model)
    f4 = fc.harmonic(4).frequencies(2.0)
    band = fc.scatter_band(4, noise=0.1, rounds=200, n_modes=N_MODES, freq=f4, tire=ref, seed=3)
    return cands, resp, band


def test_the_perturbed_tire_responds_otherwise(review):
    _, resp, _ = review
    a, b = resp[("reference", 4)].data, resp[("supplier B", 4)].data
    diff = np.abs(20 * np.log10(np.abs(b) / np.abs(a)))
    assert diff.max() > 3.0  # the case is not trivial: the two candidates differ


@pytest.mark.parametrize("offset", [0.0, -2.5, -3.5])
def test_the_verdict_agrees_with_a_direct_maximum(review, offset):
    """The example targets moved by ``offset`` dB (-3.5: the reference's harmonic-4 rows
    pass, fail within the noise band and fail)."""
    cands, resp, band = review
    targets = [
        dataclasses.replace(t, level_db=t.level_db + offset)
        for t in read_targets(ROOT / "data" / "targets" / "bushing_targets.csv")
    ]
    v = verdict(resp, targets, {("reference", 4): band}, candidates=cands)
    assert len(v.rows) == 2 * len(HARMONICS) * 3
    rounds = np.abs(band.rounds_response(np.arange(200)))  # (rounds, n_f, n_dof)
    for (name, k), frf in resp.items():
        f = frf.freq
        for dof, pts in POINTS_DB.items():
            level = 20 * np.log10(np.abs(frf.data[:, frf.outputs.index(dof), 0]))
            target = np.interp(np.log10(f), np.log10(POINTS_HZ), pts) + offset
            d = level - target
            i = int(np.argmax(d))
            r = v.row(name, k, dof)
            assert r.worst_db == pytest.approx(d[i], abs=1e-9)
            assert r.freq == f[i]
            assert r.speed == pytest.approx(3.6 * f[i] * WAVELENGTH[k], rel=1e-12)
            assert r.lines == f.size
            assert r.digest == cands.get(name).digest
            if d[i] > 0:
                assert r.status == FAIL
            else:
                assert r.margin_db == pytest.approx(-d[i], abs=1e-9)
            if (name, k) == ("reference", 4):
                # the band's upper edge: the 95th percentile of its 200 rounds, regenerated
                j = band.dofs.index(dof)
                upper = np.percentile(rounds[:, :, j], 95.0, axis=0)
                bd = 20 * np.log10(upper) - target
                assert r.band_worst_db == pytest.approx(bd.max(), abs=1e-6)
                assert r.band_q == 95.0
                if d[i] <= 0:
                    assert r.status == (NOISE_FAIL if bd.max() > 0 else PASS)
            elif d[i] <= 0:
                assert r.status == PASS and np.isnan(r.band_worst_db)
    if offset == -3.5:  # every status is exercised against the direct computation
        assert {r.status for r in v.rows if (r.candidate, r.harmonic) == ("reference", 4)} == {
            PASS,
            NOISE_FAIL,
            FAIL,
        }
    # the ranking: status, then the largest worst_db over the rows
    worst = {n: max(r.worst_db for r in v.rows if r.candidate == n) for n in cands.names}
    status = {s.candidate: s.status for s in v.ranking}
    key = {n: (("pass", NOISE_FAIL, "fail").index(status[n]), worst[n]) for n in cands.names}
    assert [s.candidate for s in v.ranking] == sorted(cands.names, key=key.__getitem__)
    assert v.to_csv().decode().count("\n") > len(v.rows)


def test_the_incumbent_plus_half_a_decibel(review):
    cands, resp, _ = review
    v = verdict(resp, [IncumbentTarget("reference", 0.5)], candidates=cands)
    for k in HARMONICS:
        a = np.abs(resp[("reference", k)].data[:, :, 0])
        b = np.abs(resp[("supplier B", k)].data[:, :, 0])
        for o, dof in enumerate(fc.node_labels("bushing")):
            assert v.row("reference", k, dof).margin_db == pytest.approx(0.5, abs=1e-9)
            d = 20 * np.log10(b[:, o] / a[:, o]) - 0.5
            r = v.row("supplier B", k, dof)
            assert r.worst_db == pytest.approx(d.max(), abs=1e-9)
            assert r.status == (FAIL if d.max() > 0 else PASS)
    assert v.ranking[0].candidate == "reference"


def test_a_band_percentile_it_does_not_hold_is_refused(review):
    _, _, band = review
    with pytest.raises(FBSError, match="percentiles 5, 95 %"):
        NoiseEdge.of_band(band, q=50.0)
    assert NoiseEdge.of_band(band, q=100.0).upper.max() == pytest.approx(band.maximum.max())


def test_vehicle_scope_response_points_are_judged(review):
    """The car's seat and bushing points (outputs ``point:dir``) with uncorrelated track
    components (here anti-phase and in phase at a partial coherence) judged like the
    bushing: the level is the root of the summed squares over the components."""
    cands, _, _ = review
    f = fc.harmonic(4).frequencies(4.0)
    pts = ("seat_fl:z", "bushing_rl:z")
    resp = {
        (c.name, 4): fc.vehicle_response(
            4, N_MODES, f, tracks=0.5, outputs=("seat_fl", "bushing_rl"), tire=c.model
        ).response.sel(outputs=pts)
        for c in cands
    }
    targets = [fc.Target.segments(p, [(30.0, -5.0), (150.0, 5.0)]) for p in pts]
    v = verdict(resp, targets, candidates=cands)
    assert [r.point for r in v.rows[:2]] == ["seat_fl", "bushing_rl"]
    for (name, _), frf in resp.items():
        assert len(frf.inputs) == 2  # two uncorrelated components
        for o, p in enumerate(pts):
            level = 10 * np.log10(np.sum(np.abs(frf.data[:, o, :]) ** 2, axis=1))
            target = np.interp(np.log10(f), np.log10([30.0, 150.0]), [-5.0, 5.0])
            d = level - target
            r = v.row(name, 4, p)
            assert r.worst_db == pytest.approx(d.max(), abs=1e-9)
            assert r.freq == f[np.argmax(d)]
