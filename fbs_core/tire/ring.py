"""Mass, damping, gyroscopic and stiffness matrices of the rolling reference tire.

The belt is a thin cylindrical band (radius ``R``, width ``b``) described in a
space-fixed (Eulerian) frame, so that the contact patch stands still while the
belt material flows through it at the spin ``Omega = v / R``. Its displacement
field (tangential ``u``, lateral ``v``, radial ``w``) is expanded in
circumferential Fourier orders ``n`` times width-wise shapes (a Ritz basis):

* ``ip``: in-plane inextensible ring, ``u = a T(theta)``, ``w = -du/dtheta``
  (Huang & Soedel 1987; Gong 1993);
* ``op``: lateral ring ``v = a T`` with plane cross-sections, ``u = -y v_theta / R``
  (out-of-plane ring, Kindt, Sas & Desmet 2009);
* ``w1``: cross-section tilt, ``w = a (2y/b) T``;
* ``w2`` .. ``w6``: width-wise bending families ``w = a cos(m pi (y/b + 1/2)) T``
  (orthotropic plate on an elastic foundation, Kropp 1989),

with ``T`` = ``cos(n theta)`` or ``sin(n theta)``. Energies are integrated by
quadrature (exact for the trigonometric and polynomial products):

* kinetic energy of the belt in the Eulerian frame,
  ``1/2 int rhoA' |d_t d + Omega d_theta d|^2 dA`` (``d_theta`` acting on the
  rotating base vectors too), gives M, the gyroscopic G(Omega) and the
  centrifugal softening;
* the hoop tension ``rhoA Omega^2 R^2`` of the spinning belt and the inflation
  tension ``T_p`` (with the pressure acting as a follower load) give the
  geometric stiffness; for the inextensible ring the Omega^2 terms cancel and the
  ring's closed form (reference-models.md sec. 2.1) is reproduced exactly;
* bending ``(w_thth + w)/R^2``, width bending ``w_yy``, twist
  ``(w_thy - u_y)/R``, circumferential membrane strain ``(u_th + w)/R``
  (lateral bending of the belt) and lateral tension on the width-wise bending;
* sidewall foundation springs at the belt edges relative to the rigid rim;
* contact springs spread over the space-fixed patch at the bottom.

The rim is rigid, its mass and inertia belong to the tire, and its centre is the
hub with 6 DOFs in vehicle coordinates (ISO 8855: x forward, y left, z up).
Ring frame: ``e_r(theta) = (cos theta, 0, -sin theta)``,
``e_theta = (-sin theta, 0, -cos theta)``, ``e_y = (0, 1, 0)``; theta is measured
from the forward direction about +y, which is also the spin direction of a
forward rolling wheel, and the patch centre lies at theta = pi/2. The hub DOFs
are the rim's translations and small rotations in these vehicle axes, so no
further transformation is needed.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import scipy.linalg as sla
from numpy.polynomial import legendre

from ..direct import SecondOrderSystem
from ..dofs import node_labels
from .params import DEFAULT_PARAMETERS, FAMILIES, TireParameters
from .static import StaticState, solve_static_state

#: Patch data of :func:`_operators`: forward and lateral position and weight of every
#: patch point, the wheel-axes components (x, y, z) of the belt shapes there, zone areas,
#: the static contact pressure at every point and the patch length.
type _Contact = tuple[
    np.ndarray,
    np.ndarray,
    np.ndarray,
    tuple[np.ndarray, np.ndarray, np.ndarray],
    np.ndarray,
    np.ndarray,
    float,
]

__all__ = [
    "HUB_DOFS",
    "build_tire_system",
    "system_matrices",
    "patch_load",
    "belt_labels",
    "omega_of_speed",
    "ring_closed_form",
    "wheel_rotation",
    "lateral_load_coefficient",
    "slip_damping",
    "slip_labels",
    "static_state",
    "patch_length",
]

#: Hub DOF labels in vehicle coordinates.
HUB_DOFS: tuple[str, ...] = node_labels("hub")


def omega_of_speed(speed_kmh: float, params: TireParameters = DEFAULT_PARAMETERS) -> float:
    """Spin in rad/s of a wheel rolling at ``speed_kmh`` (``Omega = v / R``)."""
    return float(speed_kmh) / 3.6 / params.R


@dataclass(frozen=True)
class _Basis:
    """Belt basis functions: family index, order and kind (0 = cos, 1 = sin)."""

    fam: np.ndarray
    n: np.ndarray
    kind: np.ndarray

    @property
    def size(self) -> int:
        return self.fam.size


def _basis(params: TireParameters) -> _Basis:
    fam, n, kind = [], [], []
    for f, nmax in enumerate(params.orders):
        for order in range(nmax + 1):
            for k in (0, 1) if order else (0,):
                fam.append(f)
                n.append(order)
                kind.append(k)
    return _Basis(np.array(fam), np.array(n), np.array(kind))


def belt_labels(params: TireParameters = DEFAULT_PARAMETERS) -> tuple[str, ...]:
    """Generalised DOF labels of the belt, e.g. ``"belt.ip.n02s"``."""
    b = _basis(params)
    return tuple(
        f"belt.{FAMILIES[f]}.n{n:02d}" + ("" if n == 0 else "cs"[k])
        for f, n, k in zip(b.fam, b.n, b.kind, strict=True)
    )


def slip_labels(params: TireParameters = DEFAULT_PARAMETERS) -> tuple[str, ...]:
    """Labels of the first-order slip states of the tread zones, e.g. ``"slip.z0.x"``
    (zone 0 at the front of the patch; x longitudinal, y lateral, road axes)."""
    return tuple(f"slip.z{z}.{d}" for z in range(params.slip_zones) for d in "xy")


def _trig(n: np.ndarray, kind: np.ndarray, theta: np.ndarray, d: int) -> np.ndarray:
    """d-th theta-derivative of cos(n theta) (kind 0) or sin(n theta) (kind 1).

    Returns shape (n_theta, n_basis).
    """
    # cos(x + d pi/2) is the d-th derivative of cos; sin(x) = cos(x - pi/2)
    ph = np.outer(theta, n) - 0.5 * np.pi * kind[None, :] + 0.5 * np.pi * d
    T: np.ndarray = np.cos(ph) * (n[None, :] ** d).astype(float)
    return T


def _width(fam: np.ndarray, y: np.ndarray, b: float, d: int) -> np.ndarray:
    """d-th y-derivative of the width shape of each family, shape (n_y, n_basis)."""
    eta = 2 * y / b
    out = np.zeros((y.size, fam.size))
    for f in np.unique(fam):
        cols = fam == f
        name = FAMILIES[f]
        if name in ("ip", "op"):
            g = np.ones_like(eta) if d == 0 else np.zeros_like(eta)
        elif name == "w1":
            g = eta if d == 0 else (np.full_like(eta, 2 / b) if d == 1 else np.zeros_like(eta))
        else:  # cos(m pi (y/b + 1/2)): free-edge strip shapes across the width
            k = int(name[1:]) * np.pi / b
            g = k**d * np.cos(k * (y + b / 2) + 0.5 * np.pi * d)
        out[:, cols] = g[:, None]
    return out


def _fields(
    params: TireParameters, basis: _Basis, theta: np.ndarray, y: np.ndarray
) -> dict[str, np.ndarray]:
    """Local displacement components and derivatives at the grid ``theta x y``.

    Returns a dict of arrays of shape (n_theta * n_y, n_basis), theta-major.
    """
    R = params.R
    fam = basis.fam
    T = [_trig(basis.n, basis.kind, theta, d) for d in range(4)]
    g = [_width(fam, y, params.b, d) for d in range(3)]

    def prod(t: np.ndarray, w: np.ndarray) -> np.ndarray:  # (nth, nb) x (ny, nb) -> (nth*ny, nb)
        p: np.ndarray = (t[:, None, :] * w[None, :, :]).reshape(-1, fam.size)
        return p

    is_ = {name: (fam == i)[None, :].astype(float) for i, name in enumerate(FAMILIES)}
    plate = np.isin(fam, [i for i, name in enumerate(FAMILIES) if name.startswith("w")])
    bending = plate & (fam != FAMILIES.index("w1"))
    yy = np.broadcast_to(y[None, :, None], (theta.size, y.size, 1)).reshape(-1, 1)
    F: dict[str, np.ndarray] = {}
    # ip: u = T, w = -T'
    # op: v = T, u = -y T' / R
    # plate families: w = g(y) T
    F["u"] = is_["ip"] * prod(T[0], g[0]) - is_["op"] * yy * prod(T[1], g[0]) / R
    F["u_th"] = is_["ip"] * prod(T[1], g[0]) - is_["op"] * yy * prod(T[2], g[0]) / R
    F["u_y"] = -is_["op"] * prod(T[1], g[0]) / R
    F["v"] = is_["op"] * prod(T[0], g[0])
    F["v_th"] = is_["op"] * prod(T[1], g[0])
    F["w"] = -is_["ip"] * prod(T[1], g[0]) + plate * prod(T[0], g[0])
    F["w_th"] = -is_["ip"] * prod(T[2], g[0]) + plate * prod(T[1], g[0])
    F["w_thth"] = -is_["ip"] * prod(T[3], g[0]) + plate * prod(T[2], g[0])
    F["w_y"] = plate * prod(T[0], g[1])
    F["w_yy"] = plate * prod(T[0], g[2])
    F["w_thy"] = plate * prod(T[1], g[1])
    F["w_y_bend"] = bending * F["w_y"]
    F["v_hat"] = F["v"] * (basis.n > 0)[None, :]
    return F


def _gram(a: np.ndarray, wts: np.ndarray, b: np.ndarray | None = None) -> np.ndarray:
    """``sum_p wts_p a_p b_p^T`` for field arrays (n_p, n_basis), on non-zero columns only."""
    b = a if b is None else b
    ia = np.flatnonzero(np.any(a != 0, axis=0))
    ib = ia if b is a else np.flatnonzero(np.any(b != 0, axis=0))
    out = np.zeros((a.shape[1], b.shape[1]))
    out[np.ix_(ia, ib)] = (a[:, ia] * wts[:, None]).T @ b[:, ib]
    return out


def _rim_local(theta: np.ndarray, y: float, R: float) -> list[np.ndarray]:
    """Rim rigid-body displacement at (R, theta, y) in local components.

    Returns three arrays (radial, tangential, lateral) of shape (n_theta, 6):
    per hub DOF x, y, z, rx, ry, rz.
    """
    c, s = np.cos(theta), np.sin(theta)
    er = np.stack([c, 0 * c, -s], -1)
    et = np.stack([-s, 0 * c, -c], -1)
    ey = np.broadcast_to([0.0, 1.0, 0.0], er.shape)
    p = R * er + y * ey
    out = []
    for e in (er, et, ey):
        cols = [e[:, i] for i in range(3)]  # translations
        for i in range(3):  # rotations: (beta_i x p) . e
            unit = np.zeros(3)
            unit[i] = 1.0
            cols.append(np.einsum("pi,pi->p", np.cross(unit, p), e))
        out.append(np.stack(cols, -1))
    return out


@lru_cache(maxsize=8)
def _free_operators(
    params: TireParameters,
) -> tuple[_Basis, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Speed-independent pieces without the road: basis, M, K0, A, Kw2."""
    R, b = params.R, params.b
    basis = _basis(params)
    nb = basis.size
    n_th = 2 * max(params.orders) + 8  # trapezoid rule exact for the products
    theta = 2 * np.pi * np.arange(n_th) / n_th
    yg, wy = legendre.leggauss(24)
    y, wy = yg * b / 2, wy * b / 2
    F = _fields(params, basis, theta, y)
    wts = np.outer(np.full(n_th, 2 * np.pi / n_th * R), wy).ravel()  # dA = R dtheta dy
    rho_s = params.m_belt / (2 * np.pi * R * b)

    # belt local vector field and its theta-derivative (incl. rotating base vectors)
    d_t, d_y, d_r = F["u"], F["v"], F["w"]
    dd_t, dd_y, dd_r = F["u_th"] + F["w"], F["v_th"], F["w_th"] - F["u"]
    Mb = rho_s * (_gram(d_t, wts) + _gram(d_y, wts) + _gram(d_r, wts))
    A1 = rho_s * (_gram(d_t, wts, dd_t) + _gram(d_y, wts, dd_y) + _gram(d_r, wts, dd_r))
    soft = -rho_s * (_gram(dd_t, wts) + _gram(dd_y, wts) + _gram(dd_r, wts))
    hoop = rho_s * (_gram(dd_r, wts) + _gram(dd_y, wts))  # times Omega^2 R^2 / R^2
    K2 = soft + hoop

    n_p = params.T_p / b
    E_m = 12 * params.EI_lat / b**3
    Kb = (
        n_p
        / R**2
        * (
            _gram(dd_r, wts)
            + _gram(F["u_th"], wts)
            - _gram(F["u"], wts)
            + _gram(F["v_th"], wts)
            - _gram(F["v_hat"], wts)
        )
        + params.EI / b / R**4 * _gram(F["w_thth"] + F["w"], wts)
        + params.D_y * _gram(F["w_yy"], wts)
        + params.D_t / R**2 * _gram(F["w_thy"] - F["u_y"], wts)
        + E_m / R**2 * _gram(F["u_th"] + F["w"], wts)
        + params.n_y * _gram(F["w_y_bend"], wts)
    )

    n = 6 + nb
    M = np.zeros((n, n))
    K0 = np.zeros((n, n))
    A = np.zeros((n, n))
    Kw2 = np.zeros((n, n))
    M[6:, 6:] = Mb
    K0[6:, 6:] = Kb
    A[6:, 6:] = A1
    Kw2[6:, 6:] = K2
    M[:6, :6] = np.diag([params.m_rim] * 3 + [params.I_rim_d, params.I_rim_p, params.I_rim_d])

    # sidewall foundation at the two belt edges, relative to the rigid rim
    wth = np.full(n_th, 2 * np.pi / n_th * R)
    for ye in (-b / 2, b / 2):
        Fe = _fields(params, basis, theta, np.array([ye]))
        rr, rt, ry = _rim_local(theta, ye, R)
        for belt, rim, k in (
            (Fe["w"], rr, params.k_w),
            (Fe["u"], rt, params.k_v),
            (Fe["v"], ry, params.k_lat),
        ):
            rel = np.hstack([-rim, belt])
            K0 += 0.5 * k * _gram(rel, wth)
    return basis, M, K0, A, Kw2


@lru_cache(maxsize=8)
def static_state(params: TireParameters = DEFAULT_PARAMETERS) -> StaticState:
    """The statically loaded tire under ``F_z0`` (:mod:`.static`): patch length,
    static belt shape and pressure, hoop-force pre-stress and its geometric stiffness."""
    basis, _, K0, _, _ = _free_operators(params)
    nb = basis.size
    return solve_static_state(
        K0[6 : 6 + nb, 6 : 6 + nb],
        lambda th, y: _fields(params, basis, th, y),
        lambda th, y: _rim_local(th, y, params.R),
        R=params.R,
        b=params.b,
        b_c=params.b_c,
        k_v=params.k_v,
        k_w=params.k_w,
        k_t=params.k_tread,
        F_z0=params.F_z0,
    )


def patch_length(params: TireParameters = DEFAULT_PARAMETERS) -> float:
    """Length of the contact patch in m: of the static solution under ``F_z0`` with
    ``static_deflection``, else the parameter ``L_c``."""
    return static_state(params).L_c if _loaded(params) else params.L_c


def _loaded(params: TireParameters) -> bool:
    """Whether the dynamics are linearised about the loaded tire (needs load and road)."""
    return bool(params.static_deflection and params.F_z0 > 0 and params.k_cz > 0)


@lru_cache(maxsize=8)
def _operators(
    params: TireParameters,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, _Contact]:
    """Speed-independent pieces: M, K0, the Omega-linear A, Omega^2 part, contact data."""
    R = params.R
    basis, M0, K00, A0, Kw20 = _free_operators(params)
    M, K0, A, Kw2 = M0.copy(), K00.copy(), A0.copy(), Kw20.copy()
    nb = basis.size
    st = static_state(params) if _loaded(params) else None
    if st is not None:  # pre-stress of the loaded tire: geometric stiffness of dN(theta)
        K0[: 6 + nb, : 6 + nb] += st.K_sigma
    L_c = patch_length(params)

    # contact patch: space-fixed springs at the bottom (theta = pi/2), in zones along the
    # patch (composite Gauss rule); with slip, the tread of each zone slips as one
    nz = max(params.slip_zones, 1)
    xz, wz = legendre.leggauss(max(48 // nz, 16))
    edges = np.linspace(-1.0, 1.0, nz + 1)
    lo, hi = edges[:-1, None], edges[1:, None]
    xg = (0.5 * (lo + hi) + 0.5 * (hi - lo) * xz).ravel()  # zone 0 at theta < pi/2: front
    wx = (0.5 * (hi - lo) * wz).ravel()
    zone_of = np.repeat(np.arange(nz), xz.size)
    half = L_c / 2 / R
    th_c = np.pi / 2 + half * xg
    yc, wyc = legendre.leggauss(16)
    Fc = _fields(params, basis, th_c, yc * params.b_c / 2)
    wc = np.outer(wx * half * R, wyc * params.b_c / 2).ravel()
    thp = np.repeat(th_c, yc.size)[:, None]
    dx = Fc["w"] * np.cos(thp) - Fc["u"] * np.sin(thp)
    dz = -Fc["w"] * np.sin(thp) - Fc["u"] * np.cos(thp)
    dw = (dx, Fc["v"], dz)  # wheel-axes components of the belt displacement in the patch
    Q = wheel_rotation(params)
    dv = [sum(Q[i, j] * dw[j] for j in range(3)) for i in range(3)]  # road (vehicle) axes
    area = L_c * params.b_c
    ns = params.n_slip
    Kc = np.zeros((nb + ns, nb + ns))
    zp = np.repeat(zone_of, yc.size)  # zone of every patch point
    for i, k in ((0, params.k_cx), (1, params.k_cy), (2, params.k_cz)):
        d = np.hstack([dv[i], np.zeros((dv[i].shape[0], ns))])
        if i < 2 and ns:  # tangential: spring between the belt and its zone's slipping tread
            d[np.arange(zp.size), nb + 2 * zp + i] = -1.0
        Kc += k / area * _gram(d, wc)
    n_all = 6 + nb + ns
    M, K0, A, Kw2 = (np.pad(a, (0, ns)) for a in (M, K0, A, Kw2))
    assert M.shape == (n_all, n_all)
    K0[6:, 6:] += Kc
    x_patch = -R * (thp[:, 0] - np.pi / 2)  # forward coordinate in the patch (wheel axes)
    y_patch = np.tile(yc * params.b_c / 2, th_c.size)
    zone_area = np.bincount(zp, weights=wc, minlength=nz)
    # static contact pressure at the patch points (N/m^2): uniform on the round belt, the
    # static solution's distribution on the loaded tire (scaled to carry exactly F_z0)
    if st is None:
        p_static = np.full(wc.size, params.F_z0 / area)
    else:
        p_static = st.k_t * st.penetration(thp[:, 0], dw[2], R)
        p_static *= params.F_z0 / float(wc @ p_static)
    contact: _Contact = (x_patch, y_patch, wc, dw, zone_area, p_static, L_c)
    return M, K0, A, Kw2, contact


def wheel_rotation(params: TireParameters = DEFAULT_PARAMETERS) -> np.ndarray:
    """Wheel axes in vehicle axes (columns), shape (3, 3), from camber and toe.

    ``Q = R_z(-toe) R_x(-camber)`` for the left wheel of the reference chassis
    (ISO 8855 camber, negative with the top of the wheel towards the vehicle;
    toe-in positive with its front towards the vehicle). A vector with wheel
    components ``a_w`` has vehicle components ``Q a_w`` (thesis section 4.1.2,
    the transformation of the tire model to the vehicle's coordinates).
    """
    c, s = np.cos(-params.camber), np.sin(-params.camber)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    c, s = np.cos(-params.toe), np.sin(-params.toe)
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    Q: np.ndarray = rz @ rx
    return Q


def lateral_load_coefficient(params: TireParameters = DEFAULT_PARAMETERS) -> float:
    """Lateral force per unit wheel load ``mu_y = dF_y / dF_z`` (vehicle y) at zero speed
    change: conicity and ply steer ``mu_y0``, the toe-in slip angle times the load
    sensitivity of the cornering stiffness, and the camber thrust (Pacejka 2006,
    sec. 3.2: ``F_y = K_ya(F_z) alpha + K_yg(F_z) gamma + S_Vy``)."""
    p = params
    return p.mu_y0 - p.cornering_load * p.toe + p.camber_thrust * p.camber


def _to_vehicle(a: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Congruence ``T^T a T`` with ``T = diag(Q^T, Q^T, I)``: hub DOFs in vehicle axes."""
    T6 = np.zeros((6, 6))
    T6[:3, :3] = T6[3:, 3:] = Q.T
    out = np.array(a, dtype=float, copy=True)
    out[:6, :] = T6.T @ out[:6, :]
    out[:, :6] = out[:, :6] @ T6
    return out


def _sym(a: np.ndarray) -> np.ndarray:
    s: np.ndarray = 0.5 * (a + a.T)
    return s


@lru_cache(maxsize=8)
def _damping(params: TireParameters) -> np.ndarray:
    """Viscous damping D with modal damping ratio ``zeta`` on every mode at 0 km/h.

    ``D = M Phi diag(2 zeta omega_r) Phi^T M`` with the mass-normalised real
    modes ``Phi`` of the non-rotating tire standing on the road.
    """
    M, K0, *_ = _operators(params)
    m = M.shape[0] - params.n_slip  # DOFs with mass; the tread sticks (slip states held)
    w2, phi = sla.eigh(_sym(K0[:m, :m]), _sym(M[:m, :m]))
    MP = M[:m, :m] @ phi
    D = np.zeros_like(M)
    D[:m, :m] = _sym(MP @ np.diag(2 * params.zeta * np.sqrt(np.maximum(w2, 0.0))) @ MP.T)
    return D


def slip_damping(speed_kmh: float, params: TireParameters = DEFAULT_PARAMETERS) -> np.ndarray:
    """Slip dampers of the tread zones, ``C_kappa / v`` and ``C_alpha / v`` shared by area.

    Returns the diagonal, shape (n_slip,), in N s/m: longitudinal and lateral per zone.
    A tread zone of stiffness ``k`` in series with its slip damper ``c`` relaxes with the
    time constant ``c / k = sigma / v``, the first-order relaxation-length model of the
    contact (Pacejka 2006, sec. 7.2; reference-models.md 2.3); below ``v_low`` the
    damper is held at ``C / v_low``.
    """
    if not params.slip_zones:
        return np.zeros(0)
    *_, contact = _operators(params)
    share = contact[4] / contact[4].sum()
    v = max(abs(float(speed_kmh)) / 3.6, params.v_low)
    return np.column_stack([params.C_kappa / v * share, params.C_alpha / v * share]).ravel()


def system_matrices(
    speed_kmh: float, params: TireParameters = DEFAULT_PARAMETERS
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``M, D, G, K`` of the rolling tire at ``speed_kmh`` (dense, real, shape (n, n)).

    ``M x'' + (D + G(Omega)) x' + K(Omega) x = f`` with ``G`` skew and odd in
    ``Omega``, ``K`` symmetric and even in ``Omega``.
    """
    Om = omega_of_speed(speed_kmh, params)
    M, K0, A, Kw2, _ = _operators(params)
    G = Om * (A - A.T)
    # rigid rim spinning about +y: gyroscopic coupling of rx and rz
    G[3, 5] -= Om * params.I_rim_p
    G[5, 3] += Om * params.I_rim_p
    K = _sym(K0 + Om**2 * Kw2)
    D = _damping(params).copy()
    ns = params.n_slip
    if ns:
        D[-ns:, -ns:] += np.diag(slip_damping(speed_kmh, params))
    Q = wheel_rotation(params)
    M, D, G, K = (_to_vehicle(a, Q) for a in (M, D, G, K))
    return _sym(M), _sym(D), 0.5 * (G - G.T), _sym(K)


def build_tire_system(
    speed_kmh: float, params: TireParameters = DEFAULT_PARAMETERS
) -> SecondOrderSystem:
    """The rolling tire as a labelled second-order system at ``speed_kmh``.

    Parameters
    ----------
    speed_kmh : float
        Vehicle speed in km/h (negative reverses the spin).
    params : TireParameters

    Returns
    -------
    SecondOrderSystem
        ``M``, ``C = D + G(Omega)``, ``K(Omega)``; DOFs ``hub:x`` ... ``hub:rz``
        (vehicle coordinates) followed by the belt coordinates
        (:func:`belt_labels`).
    """
    M, D, G, K = system_matrices(speed_kmh, params)
    return SecondOrderSystem(M, D + G, K, HUB_DOFS + belt_labels(params) + slip_labels(params))


def patch_load(wavelength: float, params: TireParameters = DEFAULT_PARAMETERS) -> np.ndarray:
    """Load vector of a unit road wave rolled under the patch, shape (n_dof,).

    The road profile ``h(x) = exp(j 2 pi x / lambda)`` (1 m amplitude, x forward
    along the vehicle from the patch centre) is enforced through the vertical
    contact springs (traction ``k_cz / (L_c b_c) h``), and the static contact
    pressure ``p0 = F_z0 / (L_c b_c)`` acting normal to the inclined road adds the
    longitudinal traction ``-p0 dh/dx``. With camber the pressure varies across
    the width (the lower shoulder carries more), and the lateral force of toe,
    camber and conicity follows the vertical traction,
    ``q_y = mu_y q_z`` (:func:`lateral_load_coefficient`). Tractions are in
    vehicle axes and act on the belt through :func:`wheel_rotation`. The patch is
    space fixed, so the load depends on the wavelength only; it oscillates at
    ``f = v / lambda``.
    Units: N per metre of road amplitude.
    """
    M, *_, contact = _operators(params)
    x, y, wc, dw, _, p_static, L_c = contact
    Q = wheel_rotation(params)
    k = 2 * np.pi / wavelength
    if params.patch_wave:  # road wave along the vehicle x axis, point by point
        h = np.exp(1j * k * (Q[0, 0] * x + Q[0, 1] * y))
    else:  # lumped: the whole patch sees the wave at its centre
        h = np.ones(x.size, complex)
    area = L_c * params.b_c
    qz = params.k_cz / area * h
    # static pressure: a cambered wheel presses its lower shoulder harder into the road
    tilt = params.k_cz * (Q[2, 0] * x + Q[2, 1] * y) / params.F_z0 if params.F_z0 > 0 else 0.0
    p0 = p_static * np.clip(1.0 - tilt, 0.0, None)
    qv = (-p0 * 1j * k * h, lateral_load_coefficient(params) * qz, qz)  # vehicle axes
    f = np.zeros(M.shape[0], complex)
    for j in range(3):  # wheel component j of the traction, on the wheel component j of d
        qw = sum(Q[i, j] * qv[i] for i in range(3))
        f[6 : 6 + dw[j].shape[1]] += (wc * qw) @ dw[j]
    return f


def ring_closed_form(
    n: int, speed_kmh: float, params: TireParameters = DEFAULT_PARAMETERS
) -> tuple[float, float]:
    """Forward and backward in-plane ring frequencies (Hz) of order ``n``, rim fixed.

    ``M_n = rhoA (n^2+1)``, ``K_n = EI n^2 (n^2-1)^2/R^4 + T_p n^2 (n^2-1)/R^2
    + k_w n^2 + k_v``, ``g_n = rhoA Omega n (n^2-1)``,
    ``omega = (+/- g_n + sqrt(g_n^2 + M_n K_n)) / M_n`` (Huang & Soedel 1987;
    reference-models.md sec. 2.1). Returns ``(f_plus, f_minus)``.
    """
    p = params
    Om = omega_of_speed(speed_kmh, p)
    Mn = p.rhoA * (n**2 + 1)
    Kn = (
        p.EI * n**2 * (n**2 - 1) ** 2 / p.R**4
        + p.T_p * n**2 * (n**2 - 1) / p.R**2
        + p.k_w * n**2
        + p.k_v
    )
    g = p.rhoA * Om * n * (n**2 - 1)
    r = np.sqrt(g**2 + Mn * Kn)
    return (g + r) / Mn / (2 * np.pi), (-g + r) / Mn / (2 * np.pi)
