"""Lateral asymmetry of the reference tire: camber, toe and conicity (issue 14).

Truth: the rotation of a tire on an isotropic road is a change of coordinates
(exact congruence of the hub mobility), and the resultant of the road wave on
the rigid tire is the closed-form integral of the tractions over the patch,
with the lateral force per unit load of toe, camber and conicity
(Pacejka 2006, sec. 3.2).
"""

import dataclasses

import numpy as np
import pytest

from fbs_core.tire import DEFAULT_PARAMETERS, HUB_DOFS, TireParameters, patch_load
from fbs_core.tire.ring import (
    build_tire_system,
    lateral_load_coefficient,
    system_matrices,
    wheel_rotation,
)

SYM = dataclasses.replace(DEFAULT_PARAMETERS, camber=0.0, toe=0.0, mu_y0=0.0)
LATERAL = [HUB_DOFS.index(d) for d in ("hub:y", "hub:rx", "hub:rz")]


def test_default_alignment_is_a_rear_wheel():
    p = DEFAULT_PARAMETERS
    assert np.deg2rad(-2.0) <= p.camber <= np.deg2rad(-1.0)
    assert np.deg2rad(5 / 60) <= p.toe <= np.deg2rad(15 / 60)
    # toe-in and negative camber of a left wheel both push it towards the vehicle (-y)
    mu = lateral_load_coefficient(p)
    assert -0.1 < mu < -0.02


@pytest.mark.parametrize("speed", [0.0, 80.0])
def test_rotated_tire_on_an_isotropic_road_is_a_change_of_coordinates(speed):
    """Equal contact stiffness in all directions: camber and toe only rotate the
    hub axes, so Y_vehicle = Q6 Y_wheel Q6^T exactly (Q6 = diag(Q, Q))."""
    # tread sticking: the slip states act in the road plane only, which is not isotropic
    iso = dataclasses.replace(SYM, k_cx=4e5, k_cy=4e5, k_cz=4e5, slip_zones=0)
    rot = dataclasses.replace(iso, camber=np.deg2rad(-3.0), toe=np.deg2rad(2.0))
    f = np.linspace(5.0, 200.0, 15)
    Yw = build_tire_system(speed, iso).frf(f, HUB_DOFS, HUB_DOFS).data
    Yv = build_tire_system(speed, rot).frf(f, HUB_DOFS, HUB_DOFS).data
    Q = wheel_rotation(rot)
    Q6 = np.kron(np.eye(2), Q)
    expected = Q6 @ Yw @ Q6.T
    assert np.abs(Yv - expected).max() < 1e-9 * np.abs(Yw).max()
    # and it is not the unrotated mobility: the lateral DOFs pick up z, x, ry
    assert np.abs(Yv - Yw).max() > 1e-3 * np.abs(Yw).max()


def rigid_translations(params: TireParameters) -> np.ndarray:
    """Rigid translations of the whole tire along the vehicle axes, shape (n_dof, 3):
    hub translated, belt following (static condensation of the road-free stiffness,
    which costs no energy for rigid motions)."""
    free = dataclasses.replace(params, k_cx=0.0, k_cy=0.0, k_cz=0.0, slip_zones=0)
    _, _, _, K = system_matrices(0.0, free)
    m = K.shape[0]
    r = np.zeros((m + params.n_slip, 3))  # the slip states carry no load
    r[:3] = np.eye(3)
    r[6:m] = -np.linalg.solve(K[6:, 6:], K[6:, :3])
    return r


@pytest.mark.parametrize("wavelength", [0.646, 0.166, 0.0789])
@pytest.mark.parametrize(
    "alignment",
    [
        {"camber": np.deg2rad(-1.5)},
        {"camber": np.deg2rad(-1.5), "toe": np.deg2rad(10 / 60)},
        {"camber": 0.0, "toe": 0.0, "mu_y0": 0.03},
    ],
)
def test_resultant_of_the_road_wave(wavelength, alignment):
    """Resultant force of the unit road wave on the tire, in vehicle axes.

    With h(x) = exp(j k x) along the vehicle's x: F_z = k_cz s, F_y = mu_y F_z,
    F_x = -j k F_z0 s' with s = mean of h over the patch (the pressure gradient
    of camber is odd across the width and drops out); toe turns the wave's crest
    by the toe angle across the patch.
    """
    # the closed form is for a uniform static pressure: the round belt (the loaded
    # tire's pressure distribution is tested in test_tire_static.py)
    p = dataclasses.replace(SYM, static_deflection=0, **alignment)
    f = patch_load(wavelength, p)
    F = rigid_translations(p).T @ f
    Q = wheel_rotation(p)
    k = 2 * np.pi / wavelength

    def mean_h(a, L):  # mean of exp(j k a x) over |x| <= L / 2
        return np.sinc(k * a * L / 2 / np.pi)

    s = mean_h(Q[0, 0], p.L_c) * mean_h(Q[0, 1], p.b_c)
    Fz = p.k_cz * s
    np.testing.assert_allclose(F[2], Fz, rtol=1e-6)
    np.testing.assert_allclose(F[1], lateral_load_coefficient(p) * Fz, rtol=1e-6, atol=1e-9 * Fz)
    if alignment.get("toe", 0.0) == 0.0:  # uniform in y: the gradient term vanishes exactly
        np.testing.assert_allclose(F[0], -1j * k * p.F_z0 * s, rtol=1e-6)


def test_symmetric_tire_has_no_lateral_response_and_the_rear_wheel_has():
    f = np.arange(13.0, 51.5, 1.0)
    out = {}
    for name, p in (("sym", SYM), ("rear", DEFAULT_PARAMETERS)):
        s = build_tire_system(60.0, p)
        v = np.abs(s.frf(f, HUB_DOFS, [], loads={"p": patch_load(0.646, p)}).data[:, :, 0])
        out[name] = v
    z = HUB_DOFS.index("hub:z")
    assert out["sym"][:, LATERAL].max() < 1e-8 * out["sym"][:, z].max()
    # camber projects about sin(1.5 deg) = 0.026 of the vertical motion onto y
    ratio = out["rear"][:, HUB_DOFS.index("hub:y")].max() / out["rear"][:, z].max()
    assert 0.01 < ratio < 0.1
    assert out["rear"][:, LATERAL].min(axis=0).min() > 1e-6 * out["rear"][:, z].max()
