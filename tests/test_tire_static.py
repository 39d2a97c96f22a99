"""The statically loaded tire (issue 14, item 2): patch, pressure, hoop-force pre-stress.

Truth: closed forms (the chord of a stiff ring pressed into the road, the membrane
limit of the patch length, the mean hoop-force drop F_z / (2 pi) of a ring carrying a
load through its bottom, the first-order frequency shift of a ring under a uniform
tension change), a second discretisation (twice the circumferential orders), and an
independent quadrature of the geometric stiffness' Fourier integrals.
"""

import dataclasses
from functools import lru_cache

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.optimize import brentq

from fbs_core.errors import DataFormatError
from fbs_core.tire import DEFAULT_PARAMETERS, TireParameters, patch_load
from fbs_core.tire.ring import (
    _fields,
    _free_operators,
    _rim_local,
    belt_labels,
    patch_length,
    static_state,
    system_matrices,
)
from fbs_core.tire.static import solve_static_state

P = dataclasses.replace(DEFAULT_PARAMETERS, camber=0.0, toe=0.0, mu_y0=0.0, slip_zones=0)


def test_stiff_ring_pressed_into_the_road_is_the_chord():
    """A ring that does not deform: the patch is the chord of the road through the
    circle, ``L = 2 R arccos(1 - d / R)``, and the tread force the closed-form integral
    ``k_t b_c R [2 a (d - R) + 2 R sin a]``."""
    p = P
    basis, _, K0, _, _ = _free_operators(p)
    nb = basis.size
    kt, Fz = 5e8, 4000.0
    st = solve_static_state(
        1e14 * np.eye(nb),
        lambda th, y: _fields(p, basis, th, y),
        lambda th, y: _rim_local(th, y, p.R),
        R=p.R,
        b=p.b,
        b_c=p.b_c,
        k_v=p.k_v,
        k_w=p.k_w,
        k_t=kt,
        F_z0=Fz,
    )

    def force(d):
        a = np.arccos(1 - d / p.R)
        return kt * p.b_c * p.R * (2 * a * (d - p.R) + 2 * p.R * np.sin(a))

    d = brentq(lambda x: force(x) - Fz, 1e-6, 0.05)
    assert st.d == pytest.approx(d, rel=1e-3)
    assert st.L_c == pytest.approx(2 * p.R * np.arccos(1 - d / p.R), rel=0.02)
    assert np.abs(st.x_belt).max() < 1e-9


def test_patch_length_between_the_membrane_limit_and_published_data():
    """The belt carries the load through its inflation tension and its sidewalls. A
    membrane belt without sidewalls would have the contact pressure equal to the
    inflation pressure, L = F_z / (p b) (p b = T_p / R per unit length); the sidewalls
    carry a share and shorten it. MF-Swift 205/60R15 (Pacejka 2006, table A3.1:
    q_a1 = 0.135, q_a2 = 0.035, a = R0 (q_a2 F_z/F_z0 + q_a1 sqrt(F_z/F_z0))) gives
    2 a = 0.106 m at the nominal load."""
    L = patch_length(DEFAULT_PARAMETERS)
    p = DEFAULT_PARAMETERS
    membrane = p.F_z0 / (p.T_p / p.R)
    assert 0.8 * membrane < L < membrane
    assert L == pytest.approx(2 * 0.313 * (0.035 + 0.135), rel=0.15)
    # more load, longer patch; the round belt keeps the parameter
    heavy = dataclasses.replace(p, F_z0=6000.0)
    assert patch_length(heavy) > 1.2 * L
    assert patch_length(dataclasses.replace(p, static_deflection=0)) == p.L_c


@lru_cache(maxsize=2)
def doubled():
    return dataclasses.replace(P, orders=tuple(2 * n for n in P.orders))


def test_second_discretisation_twice_the_orders():
    a, b = static_state(P), static_state(doubled())
    assert b.L_c == pytest.approx(a.L_c, rel=0.03)
    assert b.d == pytest.approx(a.d, rel=0.03)
    i = np.argmin(np.abs(a.theta - np.pi / 2))
    assert b.dN[i] == pytest.approx(a.dN[i], rel=0.05)
    assert b.dN.mean() == pytest.approx(a.dN.mean(), rel=0.02)


def test_mean_hoop_force_drop_carries_the_load():
    """A ring loaded by the road at its bottom: the n = 0 part of the inward contact
    load, F_z / (2 pi R), lowers the mean hoop force by F_z / (2 pi) (the sidewall
    springs' radial n = 0 share is small)."""
    st = static_state(P)
    assert st.dN.mean() == pytest.approx(-P.F_z0 / (2 * np.pi), rel=0.05)
    # the tension drops most under the patch, where the road takes the pressure's load
    i = np.argmin(np.abs(st.theta - np.pi / 2))
    assert st.dN[i] < 1.5 * st.dN.mean() and st.dN.max() > 0.5 * st.dN.mean()


def test_geometric_stiffness_couples_orders_like_its_fourier_integral():
    """For the in-plane ring (u = cos n theta, w = -u_theta) the rotation is
    (w_theta - u) / R = (n^2 - 1) cos(n theta) / R, so the geometric stiffness between
    orders n and m is (n^2-1)(m^2-1)/R int dN cos(n theta) cos(m theta) dtheta:
    non-zero for m = n +/- k, which the uniform inflation tension never couples. The
    integral by a fine trapezoid rule on a periodic interpolant of dN (an independent
    discretisation)."""
    st = static_state(P)
    labels = belt_labels(P)
    th = np.append(st.theta, 2 * np.pi)
    dn = np.append(st.dN, st.dN[0])

    def dN(t):
        return np.interp(t, th, dn)

    for n, m in ((3, 4), (5, 6), (5, 7), (8, 8), (2, 9)):
        i = 6 + labels.index(f"belt.ip.n{n:02d}c")
        j = 6 + labels.index(f"belt.ip.n{m:02d}c")
        t = np.linspace(0.0, 2 * np.pi, 40001)  # a grid unrelated to the model's
        ref = np.trapezoid(dN(t) * np.cos(n * t) * np.cos(m * t), t)
        ref *= (n**2 - 1) * (m**2 - 1) / P.R
        assert st.K_sigma[i, j] == pytest.approx(ref, rel=0.02, abs=1e-3 * abs(ref) + 1.0)
        if n != m:
            assert abs(ref) > 1.0  # a real coupling


def test_pre_stress_lowers_the_ring_frequencies_by_the_mean_tension_drop():
    """First-order perturbation of the rim-fixed ring (no road): a uniform hoop-force
    change dN_0 adds dN_0 (n^2 - 1)^2 / R^2 per unit length to the ring's stiffness, so
    the mean omega^2 of the cos / sin pair of order n moves by
    dN_0 (n^2 - 1)^2 / (R^2 rhoA (n^2 + 1)); the non-uniform part splits the pair at
    second order only."""
    ring = dataclasses.replace(P, orders=(10, -1, -1, -1, -1, -1, -1, -1))
    st = static_state(dataclasses.replace(ring, k_tread=P.k_tread))
    basis, M, K0, _, _ = _free_operators(ring)
    b = slice(6, None)
    w0 = sla.eigh(K0[b, b], M[b, b], eigvals_only=True)
    w1 = sla.eigh(K0[b, b] + st.K_sigma[b, b], M[b, b], eigvals_only=True)
    # the eigenvalues in order: n = 0 (one), then pairs; orders sort by frequency here
    for n in range(3, 8):
        k = 2 * n - 1  # index of the first of the pair of order n (n = 1 .. 10 pairs)
        shift = 0.5 * (w1[k] + w1[k + 1] - w0[k] - w0[k + 1])
        expected = st.dN.mean() * (n**2 - 1) ** 2 / (P.R**2 * ring.rhoA * (n**2 + 1))
        assert shift == pytest.approx(expected, rel=0.1), n


def test_loaded_tire_dynamics_use_the_patch_and_the_pre_stress():
    """With the static deflection the belt block of K is the round belt's on the loaded
    patch plus the geometric stiffness (nothing else changes), and the contact springs
    keep their totals (the hub stands on k_cz whatever the patch length)."""
    loaded = dataclasses.replace(P, slip_zones=2)
    round_ = dataclasses.replace(loaded, static_deflection=0, L_c=patch_length(P))
    _, _, _, K1 = system_matrices(0.0, loaded)
    _, _, _, K0 = system_matrices(0.0, round_)
    nb = P.n_belt
    dK = K1 - K0
    assert patch_length(loaded) == patch_length(P)  # the slip states do not change statics
    np.testing.assert_allclose(dK[: 6 + nb, : 6 + nb], static_state(P).K_sigma, atol=1e-6)
    assert np.abs(dK[6 + nb :]).max() < 1e-6  # the slip states are untouched


def test_lumped_patch_load_is_the_centre_value():
    """Without the exp(jkx) modulation every wavelength loads the patch like the longest:
    vertical resultant k_cz, longitudinal -j k F_z0."""
    lumped = dataclasses.replace(P, patch_wave=0)
    for lam in (0.646, 0.0789):
        f = patch_load(lam, lumped)
        g = patch_load(lam, P)
        k = 2 * np.pi / lam
        # the resultant on a rigid translation of the whole tire in x and z (static
        # condensation of the road-free stiffness: rigid motions cost no energy)
        free = dataclasses.replace(P, k_cx=0.0, k_cy=0.0, k_cz=0.0)
        Kf = system_matrices(0.0, free)[3]
        r = np.zeros((Kf.shape[0], 2))
        r[[0, 2], [0, 1]] = 1.0
        r[6:] = -np.linalg.solve(Kf[6:, 6:], Kf[6:, [0, 2]])
        F = r.T @ f
        np.testing.assert_allclose(F[1], P.k_cz, rtol=1e-6)
        np.testing.assert_allclose(F[0], -1j * k * P.F_z0, rtol=1e-6)
        if lam < 0.1:
            assert abs((r.T @ g)[1]) < 0.5 * P.k_cz  # the modulated short wave averages out


def test_static_state_needs_a_load():
    basis, _, K0, _, _ = _free_operators(P)
    nb = basis.size
    with pytest.raises(DataFormatError, match="wheel load"):
        solve_static_state(
            K0[6 : 6 + nb, 6 : 6 + nb],
            lambda th, y: _fields(P, basis, th, y),
            lambda th, y: _rim_local(th, y, P.R),
            R=P.R,
            b=P.b,
            b_c=P.b_c,
            k_v=P.k_v,
            k_w=P.k_w,
            k_t=5e8,
            F_z0=0.0,
        )
    # without load or road the tire is linearised about the round belt
    free = TireParameters(k_cx=0, k_cy=0, k_cz=0, slip_zones=0)
    assert patch_length(free) == free.L_c
