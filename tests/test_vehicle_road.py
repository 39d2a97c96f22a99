"""The road as each wheel sees it, checked against closed forms.

Truth:

- a rigid car body (bounce, roll, pitch) on four corners, each a damped wheel mass
  between a suspension spring-damper and a tire spring-damper on the road. With the
  wheel eliminated a corner acts on the body with ``F = P r - Q z_b`` (``r`` the road
  under it, ``z_b`` the body point above it), ``P = D_s D_t / Delta``,
  ``Q = D_s (D_t - w^2 m_u) / Delta``, ``Delta = D_s + D_t - w^2 m_u``,
  ``D = k + j w c``; the body's equations are 3 x 3 (and split into 2 x 2 + 1 x 1 for
  a car symmetric in y), solved by Cramer's rule. The rear wheels meet the front's
  road ``L / v`` later. The code gets there another way: the body and wheel masses
  as a free FE model solved directly for its hub FRFs, massless spring tires as hub
  FRFs, eq. 4.1 with the four hubs as one interface (``couple_wheels``), and the road
  of :class:`Road`;
- ISO 8608: the class levels are the standard's table, ``G_d(n0) = 16e-6 * 4^k``
  (A..H) with ``n0 = 0.1`` cycles/m and slope -2; the variance of a band of
  wavelengths is the same in space and in time;
- the coherency of two tracks on an isotropic road: numerical integration of the
  two-dimensional spectrum ``S(kappa) ~ kappa^-3`` (w = 2) against the closed form
  ``2 pi n B K_1(2 pi n B)``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from fbs_core import FRF, SecondOrderSystem
from fbs_core.dofs import DIRECTIONS, node_labels
from fbs_core.errors import DOFError, FBSError
from fbs_core.fe import FEModel, offset_transform, rigid_body_mass
from fbs_core.vehicle import (
    ISO_8608,
    WHEELS,
    Road,
    RoadProfile,
    couple_wheels,
    iso8608_psd,
    isotropic_coherence,
)

V_KMH = 72.0
F = np.array([0.6, 1.1, 1.6, 2.2, 3.3, 5.0, 7.0, 9.5, 12.0, 15.0, 22.0, 40.0])
SPINDLES = [lab for w in WHEELS for lab in node_labels(f"spindle_{w}")]
BODY = ["cg:z", "cg:rx", "cg:ry"]


def rigid_car(a, b, t, m, Ixx, Iyy, corner_f, corner_r):
    """Body (node cg) and four wheel masses (spindle_w) on suspension spring-dampers."""
    fe = FEModel()
    h = 0.5  # the corners sit at the height of the centre of gravity: no pitch-surge coupling
    fe.add_node("cg", (0.0, 0.0, h))
    fe.add_mass("cg", rigid_body_mass(m, (Ixx, Iyy, 0.7 * Iyy)))
    pos = {"fl": (a, t / 2), "fr": (a, -t / 2), "rl": (-b, t / 2), "rr": (-b, -t / 2)}
    dash = []
    for w, (x, y) in pos.items():
        k_s, c_s, m_u, _, _ = corner_f if w[0] == "f" else corner_r
        node = fe.add_node(f"spindle_{w}", (x, y, h))
        fe.add_mass(node, rigid_body_mass(m_u, (0.5, 0.8, 0.5)))
        fe.add_spring("cg", node, [3e4, 3e4, k_s, 0.0, 0.0, 0.0], offset_a=(x, y, 0.0))
        dash.append((node, (x, y), c_s))
    s = fe.system()
    C = np.zeros((s.n, s.n))
    for node, (x, y), c in dash:  # vertical dashpot between the body point and the wheel
        bvec = np.zeros(s.n)
        i, j = s.dofs.index("cg:x"), s.dofs.index(f"{node}:x")
        bvec[i : i + 6] -= offset_transform((x, y, 0.0))[2]
        bvec[j + 2] += 1.0
        C += c * np.outer(bvec, bvec)
    full = SecondOrderSystem(s.M.toarray(), C, s.K.toarray(), s.dofs)
    return full.frf(F, SPINDLES + BODY, SPINDLES)


def spring_tire(k_t, c_t):
    """A massless tire: hub mobility ``j w D^-1``; the free hub follows the road in z."""
    jw = 2j * np.pi * F
    D = np.diag([2e5, 2e5, 0.0, 5e3, 5e3, 5e3]).astype(complex)[None] + 0 * jw[:, None, None]
    D[:, 2, 2] = k_t + jw * c_t
    Y = jw[:, None, None] * np.linalg.inv(D)
    v = np.zeros((F.size, 6, 1), complex)
    v[:, 2, 0] = jw
    hub = node_labels("hub")
    return FRF(F, Y, hub, hub), FRF(F, v, hub, ["patch"])


def closed_form(a, b, t, m, Ixx, Iyy, corner_f, corner_r, r):
    """Body velocity (z, rx, ry) for road inputs ``r`` (n_f, 4) at the wheels."""
    w = 2 * np.pi * F
    out = np.empty((F.size, 3), complex)
    xs = {"fl": a, "fr": a, "rl": -b, "rr": -b}
    ys = {"fl": t / 2, "fr": -t / 2, "rl": t / 2, "rr": -t / 2}
    for i, wi in enumerate(w):
        A = -(wi**2) * np.diag([m, Ixx, Iyy]).astype(complex)
        rhs = np.zeros(3, complex)
        for k, wheel in enumerate(WHEELS):
            k_s, c_s, m_u, k_t, c_t = corner_f if wheel[0] == "f" else corner_r
            Ds, Dt = k_s + 1j * wi * c_s, k_t + 1j * wi * c_t
            delta = Ds + Dt - wi**2 * m_u
            P, Q = Ds * Dt / delta, Ds * (Dt - wi**2 * m_u) / delta
            g = np.array([1.0, ys[wheel], -xs[wheel]])  # z_b = z + y rx - x ry
            A += Q * np.outer(g, g)
            rhs += P * g * r[i, k]
        # Cramer's rule on the 3 x 3 (closed form)
        det = np.linalg.det(A)
        q = np.array(
            [np.linalg.det(np.column_stack([rhs if j == c else A[:, j] for j in range(3)]))
             for c in range(3)]
        ) / det  # fmt: skip
        out[i] = 1j * wi * q
    return out


CORNER_F = (2.4e4, 1.6e3, 40.0, 1.8e5, 80.0)  # k_s, c_s, m_u, k_t, c_t
CORNER_R = (2.0e4, 1.3e3, 35.0, 1.8e5, 80.0)


@pytest.mark.parametrize(
    "geometry",
    [
        # symmetric: bounce and pitch uncouple (a = b, identical corners)
        dict(a=1.35, b=1.35, t=1.5, m=1250.0, Ixx=480.0, Iyy=2000.0, cf=CORNER_F, cr=CORNER_F),
        # a real car: centre of gravity ahead of the middle, softer rear corners
        dict(a=1.15, b=1.55, t=1.55, m=1300.0, Ixx=520.0, Iyy=2150.0, cf=CORNER_F, cr=CORNER_R),
    ],
)
@pytest.mark.parametrize("tracks", ["in phase", "anti-phase", 0.3])
def test_rigid_car_on_a_delayed_road_equals_the_closed_form(geometry, tracks):
    g = geometry
    car = rigid_car(g["a"], g["b"], g["t"], g["m"], g["Ixx"], g["Iyy"], g["cf"], g["cr"])
    tires = {w: spring_tire(*(g["cf"] if w[0] == "f" else g["cr"])[3:]) for w in WHEELS}
    L = g["a"] + g["b"]
    T = couple_wheels(car, tires, "6dof", wheelbase=L, track=g["t"], outputs=BODY)
    r = T.apply(Road(speed_kmh=V_KMH, tracks=tracks))
    d = np.exp(-2j * np.pi * F * L / (V_KMH / 3.6))  # the rear meets the road L / v later
    rho = {"in phase": 1.0, "anti-phase": -1.0}.get(tracks, tracks)
    parts = {
        "road_in_phase": np.sqrt((1 + rho) / 2) * np.stack([1 + 0 * d, 1 + 0 * d, d, d], 1),
        "road_anti_phase": np.sqrt((1 - rho) / 2) * np.stack([1 + 0 * d, -1 + 0 * d, d, -d], 1),
    }
    level2 = np.zeros((F.size, 3))
    for name, u in parts.items():
        ref = closed_form(g["a"], g["b"], g["t"], g["m"], g["Ixx"], g["Iyy"], g["cf"], g["cr"], u)
        level2 += np.abs(ref) ** 2
        if np.all(u == 0):
            assert name not in r.components
            continue
        got = r.response.sel(inputs=name).data[:, :, 0]
        scale = np.abs(ref).max(axis=0) + 1e-300
        assert np.abs(got - ref).max(axis=0).max() <= 1e-8 * scale.max(), name
    np.testing.assert_allclose(r.level**2, level2, rtol=1e-8, atol=1e-12 * level2.max())


def test_wheelbase_filtering_of_the_symmetric_car():
    """Bounce sees (1 + exp(-j w L / v)) / 2 of the road: zero where f L / v = 1/2, while the
    front wheels alone excite it fully; pitch vanishes where f L / v = 1."""
    a = b = 1.35
    L = a + b
    v = V_KMH / 3.6
    f_null, f_pitch = v / (2 * L), v / L  # 3.70 Hz and 7.41 Hz
    global F
    saved = F
    try:
        F = np.array([f_null, f_pitch])
        car = rigid_car(a, b, 1.5, 1250.0, 480.0, 2000.0, CORNER_F, CORNER_F)
        tires = {w: spring_tire(*CORNER_F[3:]) for w in WHEELS}
        T = couple_wheels(car, tires, wheelbase=L, track=1.5, outputs=BODY)
        both = T.apply(Road(speed_kmh=V_KMH)).response.data[:, :, 0]
        front = T.apply(Road(speed_kmh=V_KMH, wheels=("fl", "fr"))).response.data[:, :, 0]
    finally:
        F = saved
    z, ry = 0, 2
    assert abs(both[0, z]) < 1e-9 * abs(front[0, z])  # bounce cancelled at f L / v = 1/2
    assert abs(both[1, ry]) < 1e-9 * abs(front[1, ry])  # pitch cancelled at f L / v = 1
    assert abs(both[1, z]) > 1.9 * abs(front[1, z])  # bounce doubled there


def test_iso8608_classes_and_the_space_time_conversion():
    assert list(ISO_8608) == list("ABCDEFGH")
    levels = np.array(list(ISO_8608.values()))
    np.testing.assert_allclose(levels, 16e-6 * 4.0 ** np.arange(8))  # ISO 8608 table
    n = np.array([0.05, 0.1, 0.2, 1.0])
    np.testing.assert_allclose(iso8608_psd(n, 256e-6), 256e-6 * (n / 0.1) ** -2.0)
    p = RoadProfile("C")
    # variance of the wavelengths 1..10 m: in space and at 80 km/h in time
    v = 80 / 3.6
    n1, n2 = 0.1, 1.0
    space = quad(lambda x: p.psd(x), n1, n2)[0]
    time = quad(lambda f: p.psd(f / v) / v, n1 * v, n2 * v)[0]
    assert time == pytest.approx(space, rel=1e-10)
    assert space == pytest.approx(256e-6 * 0.01 * (1 / n1 - 1 / n2), rel=1e-10)
    # the road's amplitude spectral density at the wheels is sqrt(G(f))
    labels, U = Road(speed_kmh=80.0, profile=p).components([4.0], 2.7, 1.5)
    assert labels == ("road_in_phase",)
    assert abs(U[0, 0, 0]) == pytest.approx(np.sqrt(p.psd(4.0 / v) / v), rel=1e-12)


@pytest.mark.parametrize("nB", [0.02, 0.1, 0.3, 1.0])
def test_isotropic_coherency_integrates_the_two_dimensional_spectrum(nB):
    """Tracks B apart on an isotropic road with S_1(n) ~ n^-2: S_2(kappa) ~ kappa^-3 and
    rho = int S_2(sqrt(n^2 + m^2)) cos(2 pi m B) dm / int S_2(sqrt(n^2 + m^2)) dm."""
    B, n = 1.0, nB

    def s2(m):
        return (n * n + m * m) ** -1.5

    num = quad(s2, 0, np.inf, weight="cos", wvar=2 * np.pi * B)[0]
    den = quad(s2, 0, np.inf)[0]
    assert isotropic_coherence(n, B) == pytest.approx(num / den, rel=1e-7)


def test_track_components_and_bad_input():
    labels, U = Road(wavelength=0.5, tracks=-0.5).components([10.0, 20.0], 2.7, 1.5)
    assert labels == ("road_in_phase", "road_anti_phase")
    d = np.exp(-2j * np.pi * 2.7 / 0.5)  # the same phase at every line of a harmonic case
    np.testing.assert_allclose(U[:, 2, 0] / U[:, 0, 0], d)
    # the two components rebuild the coherency: E[z_L conj(z_R)] = rho
    cross = (U[:, 0, :] * np.conj(U[:, 1, :])).sum(-1)
    np.testing.assert_allclose(cross.real, -0.5)
    assert Road(wavelength=0.5, wheels=("rl",)).components([10.0], 2.7, 1.5)[1][0, :, 0][
        [0, 1, 3]
    ].tolist() == [0, 0, 0]
    with pytest.raises(FBSError, match="not both"):
        Road(wavelength=0.5, speed_kmh=50.0)
    with pytest.raises(FBSError, match="positive"):
        Road(speed_kmh=-3.0)
    with pytest.raises(FBSError, match="allowed: 'in phase'"):
        Road(wavelength=0.5, tracks="opposite")
    with pytest.raises(FBSError, match=r"\[-1, 1\]"):
        Road(wavelength=0.5, tracks=1.5)
    with pytest.raises(FBSError, match="fixed speed"):
        Road(wavelength=0.5, profile=RoadProfile("A"))
    with pytest.raises(FBSError, match="allowed: A, B"):
        RoadProfile("J")
    with pytest.raises(DOFError, match="allowed: fl, fr, rl, rr"):
        Road(wavelength=0.5, wheels=("front",))
    assert DIRECTIONS[2] == "z"
