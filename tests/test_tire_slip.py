"""Slip in the contact: first-order relaxation of the tread (issue 14).

Truth: the closed form of a tread spring in series with its slip damper (the
relaxation-length model, Pacejka 2006 sec. 7.2) for a rigid motion of the whole
tire, and a first-order perturbation estimate of the slip damping of the fore-aft /
wind-up mode from the stick model's mode shape.
"""

import dataclasses

import numpy as np
import pytest
import scipy.linalg as sla

from fbs_core.tire import DEFAULT_PARAMETERS, HUB_DOFS, complex_modes
from fbs_core.tire.ring import build_tire_system, slip_damping, system_matrices

P = dataclasses.replace(DEFAULT_PARAMETERS, camber=0.0, toe=0.0, mu_y0=0.0)
STICK = dataclasses.replace(P, slip_zones=0)


def test_relaxation_lengths_from_the_published_data():
    p = DEFAULT_PARAMETERS
    sigma_x, sigma_y = p.C_kappa / p.k_cx, p.C_alpha / p.k_cy
    # of the order of the patch length (brush model: about half of it and more)
    assert 0.5 * p.L_c < sigma_x < 2.0 * p.L_c and 0.5 * p.L_c < sigma_y < 2.0 * p.L_c
    c = slip_damping(72.0, p)  # 20 m/s
    np.testing.assert_allclose(c[0::2].sum(), p.C_kappa / 20.0)
    np.testing.assert_allclose(c[1::2].sum(), p.C_alpha / 20.0)
    np.testing.assert_allclose(slip_damping(0.0, p), slip_damping(3.6 * p.v_low, p))


@pytest.mark.parametrize("zones", [1, 2, 3])
@pytest.mark.parametrize("speed", [20.0, 100.0])
def test_rigid_tire_on_the_road_is_a_first_order_relaxation(speed, zones):
    """Whole tire moved rigidly along the road: the tangential contact force is
    k c j w / (k + c j w), i.e. k j w tau / (1 + j w tau), tau = sigma / v."""
    p = dataclasses.replace(P, slip_zones=zones)
    M, D, G, K = system_matrices(speed, p)
    free = dataclasses.replace(STICK, k_cx=0.0, k_cy=0.0, k_cz=0.0)
    Kf = system_matrices(0.0, free)[3]
    ns = p.n_slip
    m = K.shape[0] - ns
    v = speed / 3.6
    for axis, k, C in ((0, p.k_cx, p.C_kappa), (1, p.k_cy, p.C_alpha)):
        r = np.zeros(m)
        r[axis] = 1.0  # hub translated, belt following rigidly
        r[6:] = -np.linalg.solve(Kf[6:, 6:], Kf[6:, axis])
        tau = C / (k * v)
        for f in (2.0, 20.0, 200.0):
            jw = 2j * np.pi * f
            Zss = K[m:, m:] + jw * D[m:, m:]
            Zsr = K[m:, :m] @ r
            Z = r @ K[:m, :m] @ r - Zsr @ np.linalg.solve(Zss, Zsr)
            expected = k * jw * tau / (1 + jw * tau)
            np.testing.assert_allclose(Z, expected, rtol=1e-6)


def fore_aft_mode(s, md):
    """Pair index of the in-plane hub mode near 38 Hz (largest hub:x in 25-60 Hz)."""
    pos = np.flatnonzero(md.poles[0::2].imag > 0)
    f = md.frequencies[pos]
    x = np.abs(md.psi[HUB_DOFS.index("hub:x"), 0::2][pos])
    sel = np.flatnonzero((f > 25) & (f < 60))
    return pos[sel[np.argmax(x[sel])]]


def test_slip_damping_of_the_fore_aft_mode():
    """Extra damping ratio ~ 1/2 eta e_c: loss factor of the tread zone
    eta = k / (w c) = v / (w sigma) times the share e_c of the mode's strain energy
    in the longitudinal contact springs (first-order perturbation of the stick mode)."""
    # stick mode at 0 km/h: real, with its strain energy share in k_cx
    M, _, _, K = system_matrices(0.0, STICK)
    Kx0 = system_matrices(0.0, dataclasses.replace(STICK, k_cx=0.0))[3]
    w2, phi = sla.eigh(K, M)
    f0 = np.sqrt(np.maximum(w2, 0)) / (2 * np.pi)
    cand = np.flatnonzero((f0 > 25) & (f0 < 60))
    k = cand[np.argmax(np.abs(phi[HUB_DOFS.index("hub:x"), cand]))]
    e_c = phi[:, k] @ (K - Kx0) @ phi[:, k] / w2[k]
    zetas = {}
    for v in (20.0, 120.0):
        s = build_tire_system(v, P)
        md = complex_modes(s.M, s.C, s.K)
        ss = build_tire_system(v, STICK)
        ms = complex_modes(ss.M, ss.C, ss.K)
        r, rs = fore_aft_mode(s, md), fore_aft_mode(ss, ms)
        zetas[v] = md.damping_ratios[r] - ms.damping_ratios[rs]
        if v == 20.0:
            eta = (v / 3.6) / (2 * np.pi * md.frequencies[r] * P.C_kappa / P.k_cx)
            assert zetas[v] == pytest.approx(0.5 * eta * e_c, rel=0.25)
    assert 0.03 < zetas[20.0] < 0.1
    assert zetas[120.0] > 3 * zetas[20.0]  # C_kappa / v: the tread slips more at speed
