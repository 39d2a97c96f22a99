"""The tread's first-order slip states are no vibration modes, and are shown as what they are.

Physics (docs/tire-model.md, "Slip in the contact"): the tread of each patch zone slips on
a damper ``c = C / v`` in series with its contact spring. The stored pair 0 of the
reference tire holds two poles at 0: the whole tire translating in x or y strains no
spring (``K x = 0``), so a steady force at the hub makes it slide on the summed slip
dampers: a frequency-independent, real hub mobility ``v / C_kappa`` fore-aft and
``v / C_alpha`` lateral, and no belt deformation. Pair 1 holds two negative real poles,
the relaxation of the slip law, ``lambda = -v / sigma`` with ``sigma_x = C_kappa / k_cx``.
Neither oscillates: no eigenfrequency, no period, no shape to animate. Both are part of
the synthesis (the sum of every pair is the direct solve of the tire's matrices).
"""

import numpy as np
import pytest

import fbs_core
from app.results import Snapshot
from app.results.modes import mode_shape_result, participation_result
from app.state import DashboardState
from fbs_core.analysis import mode_participation, pair_kinds, tire_mode_shape
from fbs_core.tire.terms import mode_terms

V_KMH = 30.0  # an operating point of the reference tire


@pytest.fixture(scope="module")
def tire():
    return fbs_core.reference_tire()


def test_the_first_pairs_are_the_sliding_and_relaxation_states(tire):
    first, sliding = pair_kinds(tire.poles)
    assert first[:2].tolist() == [True, True] and not first[2:].any()
    assert sliding.tolist() == [True] + [False] * (sliding.size - 1)
    P, v = tire.params, V_KMH / 3.6
    lam = np.sort(tire.poles_at(V_KMH)[2:4].real)  # pair 1: real, negative
    assert np.all(tire.poles_at(V_KMH)[2:4].imag == 0)
    # the fore-aft relaxation pole is -v / sigma_x (the lateral one couples the belt's
    # lateral compliance in series: only its order of magnitude, -v / sigma_y +-15 %)
    np.testing.assert_allclose(lam[0], -v * P.k_cx / P.C_kappa, rtol=0.02)
    np.testing.assert_allclose(lam[1], -v * P.k_cy / P.C_alpha, rtol=0.15)


def test_the_sliding_pair_is_the_hub_on_the_slip_dampers_and_all_pairs_are_the_direct_solve(
    tire,
):
    f = np.array([5.0, 35.0, 80.0, 139.0])
    jw = 2j * np.pi * f
    T = mode_terms(tire, f, np.full(f.size, V_KMH), 0)
    Y = jw[None, :, None] * T.dynamic[:, :, :36]  # mobility per pair, (n_p, n_f, 36)
    Y = Y.reshape(Y.shape[0], f.size, 6, 6)
    P, v = tire.params, V_KMH / 3.6
    slide = Y[0]
    # a damper: real and the same at every frequency
    np.testing.assert_allclose(slide, slide[:1].repeat(f.size, 0), rtol=1e-9, atol=1e-15)
    assert np.abs(slide.imag).max() < 1e-9 * np.abs(slide).max()
    np.testing.assert_allclose(slide[0, 0, 0].real, v / P.C_kappa, rtol=0.03)
    np.testing.assert_allclose(slide[0, 1, 1].real, v / P.C_alpha, rtol=0.03)
    assert np.abs(slide[0, 3:, 3:]).max() < 1e-12  # a translation: no hub rotation
    # the sum of every pair (sliding and relaxation included) is the direct solve
    s = tire.system(V_KMH)
    M, C, K = (np.asarray(getattr(s, m).toarray() if hasattr(getattr(s, m), "toarray")
                          else getattr(s, m)) for m in "MCK")  # fmt: skip
    hub = [s.dofs.index(f"hub:{d}") for d in fbs_core.DIRECTIONS]
    for k, w in enumerate(2 * np.pi * f):
        Z = K + 1j * w * C - w**2 * M
        direct = 1j * w * np.linalg.solve(Z, np.eye(Z.shape[0])[:, hub])[hub]
        np.testing.assert_allclose(
            Y[:, k].sum(0), direct, rtol=1e-6, atol=1e-6 * np.abs(direct).max()
        )
        # without the sliding pair the hub could not slide: off by its damper mobility
        assert abs(Y[1:, k].sum(0)[0, 0] - direct[0, 0]) > 0.5 * v / P.C_kappa


def test_the_sliding_state_has_no_belt_deformation_a_belt_mode_has(tire):
    slide = tire_mode_shape(0, V_KMH, tire)
    relax = tire_mode_shape(1, V_KMH, tire)
    hub = tire_mode_shape(5, V_KMH, tire)  # 16.5 Hz: the hub on the vertical contact springs
    belt = tire_mode_shape(15, V_KMH, tire)  # ~98 Hz ip n=1 belt mode
    assert (slide.kind, relax.kind, hub.kind, belt.kind) == (
        "sliding", "relaxation", "vibration", "vibration",
    )  # fmt: skip
    assert slide.pole.imag == pytest.approx(0, abs=1e-9) and abs(slide.pole) < 1e-9
    assert slide.deformation < 1e-9  # a rigid translation of the wheel
    assert hub.deformation > 0.05 and belt.deformation > 0.5


def _snap(**kw):
    st = DashboardState()
    st.case.param.update(harmonic=1, dof="z")
    st.analysis.param.update(tab="modes", **kw)
    return Snapshot.of(st)


def test_the_ranking_ranks_vibration_modes_and_says_what_the_slip_states_are():
    s = _snap()
    r = participation_result(s)
    f = fbs_core.harmonic(1).frequencies()
    p = mode_participation(1, (f[0], f[f <= s.f_max + 1e-9][-1]))
    first = set(np.flatnonzero(p.first_order).tolist())
    bars = r.draw["mode"]
    assert bars and not first & set(bars)  # no slip state among the ranked bars
    # the ranking is the vibration modes' own order by the measure
    vib = [int(p.modes[i]) for i in np.argsort(-p.loo[:, 2], kind="stable") if i not in first]
    assert bars == vib[: len(bars)]
    # the slip states are listed, unranked, with their measure and what they are
    assert "tread sliding" in r.draw["unranked"] and "tread relaxation" in r.draw["unranked"]
    c = r.columns
    slip = c["slip_state"] > 0
    assert np.isnan(c["rank"][slip]).all() and np.isnan(c["freq_Hz"][slip]).all()
    assert sorted(c["mode"][slip].astype(int).tolist()) == sorted(first)
    # the shape shown first is the first vibration mode's
    assert mode_shape_result(s).draw["mode"] == bars[0]


def test_a_picked_slip_state_says_what_it_is_instead_of_a_shape():
    r = mode_shape_result(_snap(mode_pick=0, mode_speed=V_KMH))
    assert r.draw["ready"] is False and r.draw["kind"] == "sliding"
    assert "no vibration" in r.caption and "rigid body" in r.caption
    r = mode_shape_result(_snap(mode_pick=1, mode_speed=V_KMH))
    assert r.draw["kind"] == "relaxation" and "time constant" in r.caption
