"""The statically loaded tire: contact patch, pressure and hoop-force pre-stress.

The rolling tire's linear dynamics (:mod:`.ring`) are linearised about a state. The
round belt is the simplest one; the tire on the road carries the wheel load ``F_z0``
and is flattened over a contact patch whose length follows from the load. This module
solves that static state with the tire's own belt (Ritz basis, sidewall foundation,
inflation tension, bending) and a unilateral contact: the tread (stiffness ``k_t``
per unit area) presses on the flat road only where the deformed belt reaches it.

* For a road raised by ``d`` into the round belt (rim fixed), a point at
  ``theta = pi/2 + phi`` of the belt penetrates it by
  ``pen = d - R (1 - cos phi) - dz(x_s)`` (``dz`` the upward displacement of the belt
  there); the contact pressure is ``k_t max(pen, 0)``. The belt's static coordinates
  ``x_s`` solve ``(K_b + k_t sum_active dz dz^T dA) x_s = k_t sum_active (d - R(1 -
  cos phi)) dz dA`` with the active set iterated to consistency, and ``d`` is found so
  that the contact force equals ``F_z0``.
* The patch length is where the pressure is positive. ``k_t`` is the tread rubber's
  compression stiffness per area (``TireParameters.k_tread``), stiff against the belt,
  so that the patch is set by how the belt flattens: in the limit of a membrane belt
  without sidewall springs the contact pressure equals the inflation pressure and
  ``L_c = F_z0 / (p b_c)``; the sidewall springs carry part of the load and shorten it.
* Pre-stress: the static loads change the belt's hoop force. For the inextensible belt
  it follows from equilibrium (thin ring; bending shear ``EI w''' / R^3`` neglected):
  tangentially ``dN/dtheta = -R q_t`` and on average ``<N> - T_p = R <q_r>``
  (``q_t, q_r`` the tangential and outward radial static loads per unit circumference:
  sidewall springs and the contact pressure). The hoop force acting on the rotations
  of the belt's cross-section gives the geometric stiffness
  ``1/2 int dN(theta) / b [((w_theta - u) / R)^2 + (v_theta / R)^2] dA``; unlike the
  uniform inflation tension it depends on theta and so couples the circumferential
  orders ``n`` and ``n +/- k`` (``k`` the orders of ``dN``). The rotations are those
  relative to the rigid rim, so that rigid motions of the whole tire, among them its
  steady rolling (in the space-fixed frame a time shift of the static state), cost no
  energy; the belt's wind-up relative to the rim then feels ``dN`` too (about 1 % of
  the sidewall's torsional stiffness, an approximation of this first-order model).

Sources: the unilateral ring-on-road contact and its flattening as in Gong (1993, ch. 4)
and Pacejka (2006, sec. 9.2, the flexible ring on an elastic foundation); the static
patch half length there, ``a ~ sqrt(2 R delta)`` for a stiff belt pressed in by
``delta``, is the limiting case tested in ``tests/test_tire_static.py``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from numpy.polynomial import legendre
from scipy.optimize import brentq

from ..errors import DataFormatError

__all__ = ["StaticState", "solve_static_state"]

#: Half-angle of the search grid for the patch (rad) and its number of points.
PHI_MAX = 0.45
N_PHI = 241
#: Points of the fine circumferential grid of the hoop force.
N_THETA = 1024


@dataclass(frozen=True)
class StaticState:
    """The statically loaded tire (rim fixed, wheel axes).

    Attributes
    ----------
    d : float
        Penetration of the road into the round belt at the patch centre, m (the rim's
        deflection towards the road relative to the undeformed belt).
    L_c : float
        Length of the contact patch, m.
    k_t : float
        Tread stiffness per unit area of the patch, N/m^3.
    x_belt : ndarray
        Static belt coordinates (Ritz amplitudes of :func:`.ring.belt_labels`).
    theta, dN : ndarray
        Fine circumferential grid and the hoop-force change ``N(theta) - T_p`` there, N.
    K_sigma : ndarray
        Geometric stiffness of ``dN`` on the hub DOFs (wheel axes) and the belt
        coordinates, shape (6 + n_belt, 6 + n_belt).
    """

    d: float
    L_c: float
    k_t: float
    x_belt: np.ndarray
    theta: np.ndarray
    dN: np.ndarray
    K_sigma: np.ndarray

    def penetration(self, theta: np.ndarray, dz: np.ndarray, R: float) -> np.ndarray:
        """Static penetration of the tread into the road at belt points ``theta`` whose
        upward displacement rows are ``dz`` (n_points, n_belt); >= 0, m."""
        pen = self.d - R * (1.0 - np.sin(theta)) - dz @ self.x_belt
        return np.asarray(np.clip(pen, 0.0, None), dtype=float)


#: ``fields(theta, y)``: the belt's displacement fields on the grid theta x y.
Fields = Callable[[np.ndarray, np.ndarray], dict[str, np.ndarray]]
#: ``rim(theta, y)``: (radial, tangential, lateral) rim displacement per hub DOF.
Rim = Callable[[np.ndarray, float], list[np.ndarray]]


def _vertical(F: dict[str, np.ndarray], theta_pts: np.ndarray) -> np.ndarray:
    """Upward (wheel z) displacement rows at points of angle ``theta_pts``."""
    th = theta_pts[:, None]
    return np.asarray(-F["w"] * np.sin(th) - F["u"] * np.cos(th), dtype=float)


def _contact(
    K: np.ndarray,
    dz: np.ndarray,
    g: np.ndarray,
    w: np.ndarray,
    kt: float,
    d: float,
    start: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Belt solution for road height ``d`` with the active set iterated from ``start``;
    returns ``(x, pen, force)``."""
    active = start.copy()
    for _ in range(100):
        Da = dz[active]
        A = K + kt * (Da * w[active, None]).T @ Da
        x = sla.solve(A, kt * Da.T @ (w[active] * (d + g[active])), assume_a="sym")
        pen = d + g - dz @ x
        new = pen > 0
        if np.array_equal(new, active):
            break
        active = new
    else:  # pragma: no cover - the active set of a convex contact converges
        raise DataFormatError("static contact: the active set did not converge")
    pen = np.where(active, pen, 0.0)
    return x, pen, kt * float(w @ pen)


def solve_static_state(
    K_belt: np.ndarray,
    fields: Fields,
    rim: Rim,
    *,
    R: float,
    b: float,
    b_c: float,
    k_v: float,
    k_w: float,
    k_t: float,
    F_z0: float,
) -> StaticState:
    """Static contact of the belt (stiffness ``K_belt``, rim fixed) with the flat road.

    ``fields(theta, y)`` returns the belt's displacement fields (``u, v, w`` and their
    derivatives, rows theta-major over the grid ``theta x y``) as in :mod:`.ring`;
    ``rim(theta, y)`` the rigid rim's (radial, tangential, lateral) displacement at
    the belt points per hub DOF, each of shape (n_theta, 6).
    See the module docstring for the equations.
    """
    if F_z0 <= 0 or k_t <= 0:
        raise DataFormatError(
            f"the static state needs a wheel load and a tread: F_z0 = {F_z0}, k_t = {k_t}"
        )
    phi = np.linspace(-PHI_MAX, PHI_MAX, N_PHI)
    yq, wyq = legendre.leggauss(4)
    y = yq * b_c / 2
    th = np.pi / 2 + phi
    F = fields(th, y)
    thp = np.repeat(th, y.size)
    dz = _vertical(F, thp)
    wphi = np.full(N_PHI, R * (phi[1] - phi[0]))
    wphi[[0, -1]] *= 0.5
    w = np.outer(wphi, wyq * b_c / 2).ravel()
    g = -R * (1.0 - np.sin(thp))
    kt = float(k_t)
    warm = [g > 0]

    def force(dd: float) -> float:
        x, pen, f = _contact(K_belt, dz, g, w, kt, dd, warm[0])
        warm[0] = pen > 0
        return f - F_z0

    d = float(brentq(force, 1e-7, 0.2, xtol=1e-12))
    x, pen, _ = _contact(K_belt, dz, g, w, kt, d, warm[0])
    line = pen.reshape(N_PHI, y.size) @ wyq  # pressure integrated over the width
    on = np.flatnonzero(line > 0)
    if on.size == 0 or on[0] == 0 or on[-1] == N_PHI - 1:
        raise DataFormatError(f"static contact patch does not fit the grid |phi| < {PHI_MAX} rad")
    # zero crossings of the line pressure, linear between grid points
    i0, i1 = on[0], on[-1]
    p0 = phi[i0 - 1] + (phi[i0] - phi[i0 - 1]) * (-line[i0 - 1]) / (line[i0] - line[i0 - 1])
    p1 = phi[i1] + (phi[i1 + 1] - phi[i1]) * line[i1] / (line[i1] - line[i1 + 1])
    L = R * (p1 - p0)

    # hoop force from the equilibrium of the static loads on the fine grid
    theta = 2 * np.pi * np.arange(N_THETA) / N_THETA
    dth = 2 * np.pi / N_THETA
    q_t = np.zeros(N_THETA)
    q_r = np.zeros(N_THETA)
    for ye in (-b / 2, b / 2):  # sidewall springs, half at each edge, rim fixed
        Fe = fields(theta, np.array([ye]))
        q_t -= 0.5 * k_v * (Fe["u"] @ x)
        q_r -= 0.5 * k_w * (Fe["w"] @ x)
    # contact pressure (upward on the belt) on the fine grid, integrated over b_c
    near = np.abs(theta - np.pi / 2) < PHI_MAX
    Fn = fields(theta[near], y)
    tn = np.repeat(theta[near], y.size)
    pn = kt * np.clip(d - R * (1 - np.sin(tn)) - _vertical(Fn, tn) @ x, 0.0, None)
    qline = pn.reshape(-1, y.size) @ (wyq * b_c / 2)
    # e_z = -cos(theta) e_theta - sin(theta) e_r
    q_t[near] += -np.cos(theta[near]) * qline
    q_r[near] += -np.sin(theta[near]) * qline
    # dN/dtheta = -R q_t, integrated from the top of the tire (theta = 3 pi / 2)
    start = N_THETA * 3 // 4
    order = np.roll(np.arange(N_THETA), -start)
    Nrel = -R * np.concatenate([[0.0], np.cumsum(q_t[order][:-1]) * dth])
    dN = np.empty(N_THETA)
    dN[order] = Nrel
    dN += R * q_r.mean() - dN.mean()

    # geometric stiffness of the hoop-force change on the rotations of the belt's
    # cross-section relative to the rim (hub DOFs first, then the belt coordinates):
    # the rigid motions of the whole tire, and so its steady rolling (a time shift in
    # the space-fixed frame), cost nothing. Every second point of the grid is exact for
    # the products of the basis' orders (<= 2 x 20) with the orders of dN below
    # N_THETA / 2 - 40.
    yb, wyb = legendre.leggauss(8)
    th2 = theta[::2]
    Ff = fields(th2, yb * b / 2)
    nb = K_belt.shape[0]
    h = 1e-6
    rot_ip = np.zeros((th2.size * yb.size, 6 + nb))
    rot_op = np.zeros_like(rot_ip)
    rot_ip[:, 6:] = (Ff["w_th"] - Ff["u"]) / R
    rot_op[:, 6:] = Ff["v_th"] / R
    for j, yy in enumerate(yb * b / 2):
        wr, ur, vr = rim(th2, yy)
        wr_th = (rim(th2 + h, yy)[0] - rim(th2 - h, yy)[0]) / (2 * h)
        vr_th = (rim(th2 + h, yy)[2] - rim(th2 - h, yy)[2]) / (2 * h)
        rot_ip[j :: yb.size, :6] = -(wr_th - ur) / R
        rot_op[j :: yb.size, :6] = -vr_th / R
    wts = np.outer(np.full(th2.size, 2 * R * dth) * dN[::2] / b, wyb * b / 2).ravel()
    K_sigma = (rot_ip * wts[:, None]).T @ rot_ip + (rot_op * wts[:, None]).T @ rot_op
    K_sigma = 0.5 * (K_sigma + K_sigma.T)
    return StaticState(float(d), float(L), float(kt), x, theta, dN, K_sigma)
