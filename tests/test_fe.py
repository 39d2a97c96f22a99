"""Beam elements, rigid bodies and springs against closed-form mechanics."""

import numpy as np
import pytest
import scipy.linalg as sla

from fbs_core.errors import DataFormatError, DOFError
from fbs_core.fe import (
    FEModel,
    Material,
    Section,
    beam_element,
    beam_local_matrices,
    offset_transform,
    rigid_body_mass,
)

STEEL = Material(E=210e9, nu=0.3, rho=8000.0)
BAR = Section.rectangle(0.01, 0.04)
# free-free Euler-Bernoulli beam: beta_n L (Blevins, Formulas for natural frequency, table 8-1)
BETA_L = np.array([4.730040745, 7.853204624, 10.99560784])


def _skewed_beam(n=60, model=False):
    m = FEModel()
    m.add_node("a", (0.0, 0.0, 0.0))
    m.add_node("b", (1.2, 0.5, -0.3))
    m.add_beam("a", "b", BAR, STEEL, n, up=(0.3, 0.2, 1.0))
    L = float(np.linalg.norm([1.2, 0.5, -0.3]))
    return (m.system(), L, m) if model else (m.system(), L)


def test_free_free_beam_frequencies_match_closed_form_in_any_orientation():
    s, L = _skewed_beam()
    w2 = sla.eigh(s.K.toarray().real, s.M.toarray(), eigvals_only=True)
    f = np.sqrt(np.abs(w2)) / (2 * np.pi)
    assert np.all(f[:6] < 0.1)  # six rigid-body modes
    mu = STEEL.rho * BAR.A
    exact = np.sort(
        np.concatenate(
            [BETA_L**2 / (2 * np.pi * L**2) * np.sqrt(STEEL.E * I / mu) for I in (BAR.Iy, BAR.Iz)]
        )
    )[:4]
    bending = np.sort(f[6:12])[:4]
    np.testing.assert_allclose(bending, exact, rtol=1e-4)


def test_rigid_motions_are_strain_free_and_carry_the_total_mass():
    s, L, model = _skewed_beam(8, model=True)
    K, M = s.K.toarray(), s.M.toarray()
    xyz = np.array([model.xyz(n) for n in model.nodes])
    for k in range(6):
        theta = np.eye(3)[k - 3] if k >= 3 else np.zeros(3)
        u = np.zeros((9, 6))
        u[:, :3] = (np.eye(3)[k] if k < 3 else 0) + np.cross(theta, xyz)
        u[:, 3:] = theta
        assert np.abs(K @ u.ravel()).max() < 1e-6 * np.abs(K).max()
    u = np.zeros((9, 6))
    u[:, 2] = 1.0
    assert u.ravel() @ M @ u.ravel() == pytest.approx(STEEL.rho * BAR.A * L, rel=1e-12)


def test_cantilever_tip_deflection_and_torsion():
    L, P = 1.5, 100.0
    m = FEModel()
    m.add_node("root", (0, 0, 0))
    m.add_node("tip", (0, L, 0))  # along global y
    m.add_beam("root", "tip", BAR, STEEL, 10)
    m.add_spring("root", None, [1e18] * 6)
    s = m.system()
    K = s.K.toarray().real
    i = s.dofs.index("tip:z")
    x = np.linalg.solve(K, np.eye(s.n)[:, i] * P)
    # local z = global z for a horizontal beam: bending about local y uses Iy
    assert x[i] == pytest.approx(P * L**3 / (3 * STEEL.E * BAR.Iy), rel=1e-9)
    j = s.dofs.index("tip:ry")  # twist about the beam axis (global y)
    x = np.linalg.solve(K, np.eye(s.n)[:, j])
    assert x[j] == pytest.approx(L / (STEEL.G * BAR.J), rel=1e-9)


def test_hysteretic_loss_factor_scales_stiffness_only():
    K0, M0 = beam_local_matrices(0.1, BAR, STEEL)
    K1, M1 = beam_local_matrices(0.1, BAR, Material(210e9, 0.3, 8000.0, eta=0.05))
    np.testing.assert_allclose(K1, K0 * (1 + 0.05j))
    np.testing.assert_array_equal(M0, M1)


def test_rigid_body_mass_with_offset_parallel_axis():
    r = np.array([0.1, -0.2, 0.3])
    Mb = rigid_body_mass(2.0, [0.1, 0.2, 0.3], offset=r)
    # rotation about z at the node moves the CoG by theta x r
    Izz = Mb[5, 5]
    assert Izz == pytest.approx(0.3 + 2.0 * (r[0] ** 2 + r[1] ** 2))
    assert np.allclose(Mb, Mb.T)
    assert np.all(np.linalg.eigvalsh(Mb) > 0)


def test_spring_with_offsets_transmits_moment_arm():
    m = FEModel()
    m.add_node("a", (0, 0, 0))
    blk = m.add_spring("a", None, [0, 0, 1000.0, 0, 0, 0], offset_a=(0.5, 0, 0))
    # vertical spring 0.5 m along x: rotation about y of the node gives M = k r^2
    assert blk[4, 4].real == pytest.approx(1000.0 * 0.25)
    T = offset_transform((0.5, 0, 0))
    assert T[2, 4] == pytest.approx(-0.5)


def test_bad_input_raises():
    with pytest.raises(DataFormatError, match="material"):
        Material(E=-1, nu=0.3, rho=1.0)
    with pytest.raises(DataFormatError, match="positive"):
        Section(A=0, Iy=1, Iz=1, J=1)
    with pytest.raises(DataFormatError, match="coincide"):
        beam_element((0, 0, 0), (0, 0, 0), BAR, STEEL)
    with pytest.raises(DataFormatError, match="parallel"):
        beam_element((0, 0, 0), (1, 0, 0), BAR, STEEL, up=(2, 0, 0))
    m = FEModel()
    m.add_node("a", (0, 0, 0))
    with pytest.raises(DOFError, match="duplicate"):
        m.add_node("a", (1, 0, 0))
    with pytest.raises(DOFError, match="unknown node 'b'"):
        m.add_beam("a", "b", BAR, STEEL, 2)
    with pytest.raises(DataFormatError, match="6 values"):
        m.add_spring("a", None, [1.0, 2.0])
    with pytest.raises(DataFormatError, match="rigid body"):
        rigid_body_mass(-1.0, [1, 1, 1])
