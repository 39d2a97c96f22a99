"""What the modes look like: data to draw tire modes, coupled modes and deflection shapes.

Three kinds of shape, each returned as plain arrays of coordinates per animation frame
(one period of the oscillation, ``Re(x e^(j phi_k))`` at ``phi_k = 2 pi k / n_frames``),
scaled for display:

* :func:`tire_mode_shape`: a mode of the tire model (a stored pair, as the participation
  tables number them) at a chosen speed, as the deformed belt: the tire's matrices at
  that speed (``tire.system(v)``) give the mode's physical shape (shift-invert at the
  model's pole, the nearest eigenvalue), and :func:`fbs_core.tire.belt.belt_surface`
  turns its belt coordinates into the belt surface (ring in the wheel plane, the width
  shape across) and its hub DOFs into the rim's rigid motion. Its dominant ring order
  and travelling direction come with it (-1 forward: the crest runs with the spin);
  :attr:`BeltShape.crest` is the angle of the largest outward displacement of the
  centre line per frame, which moves with the wave;
* :func:`coupled_mode_shapes`: the modes of the assembled tire + chassis
  (:func:`fbs_core.analysis.coupled_system`, the system whose eigenvalues are the poles
  of the coupled FRF) nearest a frequency, as the tire's belt plus the chassis' FE nodes
  and edges (:func:`chassis_geometry`), in vehicle axes, the tire placed at the spindle;
* :func:`operating_shape`: the operating deflection shape at one frequency of a harmonic
  case, the assembled system's response to the patch load at the line's speed
  (``v = 3.6 f lambda``), drawn the same way.

One scale per shape: the largest displacement of the drawn points is ``scale`` times the
tire radius (the tire and the chassis in one shape share it, so their relative motion
is true).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .._typing import ComplexArray, FloatArray, IntArray
from ..chassis import build_chassis, reference_chassis
from ..direct import SecondOrderSystem
from ..errors import FBSError
from ..harmonics import harmonic as _harmonic
from ..prediction import coupled_dofs
from ..tire.belt import belt_coordinates, belt_surface, dominant, order_content
from ..tire.ring import wheel_rotation
from ..vocabulary import TRANSLATIONS
from .peaks import _first_order, coupled_system

__all__ = [
    "BeltShape",
    "ChassisShape",
    "CoupledShape",
    "TireModeShape",
    "chassis_geometry",
    "coupled_mode_shapes",
    "operating_shape",
    "tire_mode_shape",
]


@dataclass(frozen=True, eq=False)
class BeltShape:
    """The tire's belt and rim over one period, wheel axes unless placed in a vehicle.

    Attributes
    ----------
    theta : ndarray, shape (n_t,)
        Angles of the points (rad; 0 forward, ``pi / 2`` the patch centre, increasing
        in the spin direction).
    y : ndarray, shape (n_y,)
        Lateral positions across the width (m).
    phase : ndarray, shape (n_k,)
        Phase of every frame (rad).
    belt : ndarray, shape (n_k, n_t, n_y, 3)
        Displaced belt points (m).
    rim : ndarray, shape (n_k, n_t, 3)
        Displaced rim circle.
    rest_belt : ndarray, shape (n_t, n_y, 3)
        The undeformed belt (the shape is drawn against it).
    crest : ndarray, shape (n_k,)
        Angle (rad, unwrapped) of one crest of the dominant ring order ``n`` on the
        centre line in every frame (the phase of the order's Fourier coefficient of the
        radial displacement over ``n``): it advances by ``2 pi / n`` per period with the
        spin (increasing) for a forward wave, against it for a backward wave, and stays
        (or jumps by ``pi / n``) for a standing one; zeros for order 0.
    scale : float
        Display factor applied to the displacements.
    """

    theta: FloatArray
    y: FloatArray
    phase: FloatArray
    belt: FloatArray
    rim: FloatArray
    rest_belt: FloatArray
    crest: FloatArray
    scale: float

    @property
    def ring(self) -> FloatArray:
        """Centre line of the belt (the ring in the wheel plane), shape (n_k, n_t, 3)."""
        r: FloatArray = self.belt[:, :, self.y.size // 2]
        return r

    def section(self, theta: float) -> FloatArray:
        """The width shape across at the angle nearest ``theta`` (rad), (n_k, n_y, 3)."""
        i = int(np.argmin(np.abs(np.angle(np.exp(1j * (self.theta - theta))))))
        s: FloatArray = self.belt[:, i]
        return s


@dataclass(frozen=True, eq=False)
class TireModeShape:
    """A tire mode at one speed as the deformed belt.

    Attributes
    ----------
    mode : int
        Stored pair index in the modal model.
    speed_kmh : float
    pole : complex
        Eigenvalue of the tire's matrices at that speed (rad/s).
    model_pole : complex
        The modal model's (interpolated) pole of the mode.
    freq : float
        ``Im(pole) / 2 pi`` in Hz (0 for a first-order mode).
    family : str
        Dominant belt family (``ip``, ``op``, ``w1`` ... ``w6``).
    order : int
        Dominant ring order.
    share : float
        Its share of the belt's ``sum m |q|^2``.
    direction : str
        ``"forward"``, ``"backward"`` or ``"standing"``.
    travelling : float
        Travelling index of the dominant order (-1 forward, +1 backward).
    hub_share : float
        Share of the mode's ``sum m |x|^2`` in the hub (rim) DOFs.
    shape : BeltShape
    kind : str
        ``"vibration"`` (an oscillation), ``"sliding"`` (a zero pole: the whole tire slides
        on the tread's slip dampers) or ``"relaxation"`` (a negative real pole: the slip
        law's first-order lag); :data:`fbs_core.analysis.KINDS`.
    deformation : float
        Share of the belt's displacement that is no rigid motion with the hub,
        ``||d - (t + r x p)|| / ||d||`` over the drawn belt points ``p`` (``t``, ``r`` the
        hub's translation and rotation): 0 for a wheel moving as a rigid body (the sliding
        states, ``K x = 0``), of order 1 for a belt mode.
    """

    mode: int
    speed_kmh: float
    pole: complex
    model_pole: complex
    freq: float
    family: str
    order: int
    share: float
    direction: str
    travelling: float
    hub_share: float
    shape: BeltShape
    kind: str = "vibration"
    deformation: float = float("nan")


@dataclass(frozen=True, eq=False)
class ChassisShape:
    """The chassis' FE nodes over one period, vehicle axes.

    Attributes
    ----------
    nodes : tuple of str, length n_n
    rest : ndarray, shape (n_n, 3)
        Node positions (m).
    points : ndarray, shape (n_k, n_n, 3)
        Displaced nodes.
    edges : ndarray of int, shape (n_e, 2)
        Node pairs joined by a beam element or a spring (to draw lines).
    """

    nodes: tuple[str, ...]
    rest: FloatArray
    points: FloatArray
    edges: IntArray


@dataclass(frozen=True, eq=False)
class CoupledShape:
    """A shape of the coupled tire + chassis: a mode or an operating deflection shape.

    Attributes
    ----------
    kind : str
        ``"mode"`` or ``"ods"``.
    freq : float
        Eigenfrequency (mode) or excitation frequency (ODS), Hz.
    pole : complex or None
        The eigenvalue (modes only).
    speed_kmh : float
    tire : BeltShape
        In vehicle axes, centred at the spindle.
    chassis : ChassisShape
    tire_share : float
        Share of ``sum m |x|^2`` in the tire's DOFs (the rest is in the chassis).
    family, order, direction : str, int, str
        The belt's dominant family, ring order and direction.
    """

    kind: str
    freq: float
    pole: complex | None
    speed_kmh: float
    tire: BeltShape
    chassis: ChassisShape
    tire_share: float
    family: str
    order: int
    direction: str


def _modes_near(
    system: SecondOrderSystem, sigma: complex, k: int
) -> tuple[ComplexArray, ComplexArray]:
    """Eigenvalues nearest ``sigma`` and their shapes ``x`` (columns), shift-invert on the
    first-order form (a dense LU for a dense system such as the tire's)."""
    A, B = _first_order(system)
    n = system.n
    N = A.shape[0]
    if not any(sp.issparse(getattr(system, m)) for m in "MCK"):
        lu = sla.lu_factor((A - sigma * B).toarray())
        Bd = B.toarray()

        def matvec(z: ComplexArray) -> ComplexArray:
            out: ComplexArray = sla.lu_solve(lu, Bd @ z)
            return out

    else:
        slu = spla.splu((A - sigma * B).tocsc())

        def matvec(z: ComplexArray) -> ComplexArray:
            out: ComplexArray = slu.solve(B @ z)
            return out

    op = spla.LinearOperator((N, N), matvec=matvec, dtype=complex)
    mu, Z = spla.eigs(op, k=min(k, N - 2), which="LM", v0=np.ones(N, complex), tol=1e-10)
    lam = sigma + 1.0 / mu
    order = np.argsort(np.abs(lam - sigma))
    return lam[order], Z[:n, order]


@dataclass(frozen=True, eq=False)
class _Parts:
    """Undeformed belt and rim points with their complex displacements (wheel axes)."""

    theta: FloatArray
    y: FloatArray
    rest: FloatArray
    d: ComplexArray
    rim: FloatArray
    d_rim: ComplexArray
    coords: Any

    @property
    def largest(self) -> float:
        return max(float(np.abs(self.d).max()), float(np.abs(self.d_rim).max()), 1e-300)


def _parts(
    x: ComplexArray, dofs: Any, params: Any, n_theta: int, n_y: int, prefix: str = ""
) -> _Parts:
    co = belt_coordinates(dofs, prefix)
    theta = 2 * np.pi * np.arange(n_theta) / n_theta
    y = np.linspace(-params.b / 2, params.b / 2, n_y)
    rest, d, rim, d_rim = belt_surface(x, co, theta, y, params)
    return _Parts(theta, y, rest, d, rim, d_rim, co)


def _belt_shape(
    p: _Parts,
    s: float,
    n_frames: int,
    order: int,
    placement: tuple[FloatArray, FloatArray] | None = None,
) -> BeltShape:
    """Frames of the belt and rim, displacements times ``s``; ``placement = (centre, Q)``
    puts them in vehicle axes. ``order``: the ring order whose crest is followed."""
    phase = 2 * np.pi * np.arange(n_frames) / n_frames
    rot = np.exp(1j * phase)
    belt = p.rest[None] + s * np.real(p.d[None] * rot[:, None, None, None])
    rim = p.rim[None] + s * np.real(p.d_rim[None] * rot[:, None, None])
    # crest of the order: the phase of its Fourier coefficient of the centre line's
    # radial displacement, frame by frame (theta of one crest, unwrapped)
    c = p.y.size // 2
    er = np.stack([np.cos(p.theta), np.zeros_like(p.theta), -np.sin(p.theta)], axis=-1)
    radial = np.real(np.einsum("ti,ti->t", p.d[:, c], er)[None] * rot[:, None])  # (n_k, n_t)
    crest = np.zeros(n_frames)
    if order >= 1:
        coef = radial @ np.exp(-1j * order * p.theta)
        crest = np.unwrap(-np.angle(coef)) / order  # r = cos(n theta - b): coef ~ e^(-j b)
    rest = p.rest
    if placement is not None:
        centre, Q = placement
        belt, rim, rest = (centre + a @ Q.T for a in (belt, rim, rest))
    return BeltShape(p.theta, p.y, phase, belt, rim, rest, crest, float(s))


def tire_mode_shape(
    mode: int,
    speed_kmh: float,
    tire: Any = None,
    *,
    n_frames: int = 24,
    n_theta: int = 96,
    n_y: int = 9,
    scale: float = 0.1,
) -> TireModeShape:
    """A stored mode of the tire model at ``speed_kmh`` as the deformed belt.

    Parameters
    ----------
    mode : int
        Stored pair index (as :func:`fbs_core.analysis.mode_participation` numbers them).
    speed_kmh : float
        Speed within the model's operating points.
    tire : TireModel, optional
        With physical parameters (default the reference tire).
    n_frames, n_theta, n_y : int
        Frames over one period, points around and across the belt.
    scale : float
        Largest displacement drawn, as a fraction of the tire radius.

    Returns
    -------
    TireModeShape

    Raises
    ------
    FBSError
        For a mode index out of range or bad drawing sizes.
    DataFormatError
        For a model without physical parameters.
    OperatingPointError
        For a speed outside the operating points.
    """
    if tire is None:
        from .. import reference_tire

        tire = reference_tire()
    n_p = tire.n_modes // 2
    if isinstance(mode, bool) or int(mode) != mode or not 0 <= mode < n_p:
        raise FBSError(f"mode must be a stored pair index 0..{n_p - 1}, got {mode!r}")
    _check_sizes(n_frames, n_theta, n_y, scale)
    v = float(speed_kmh)
    model_pole = complex(tire.poles_at(v)[2 * int(mode)])
    s = tire.system(v)  # DataFormatError without parameters
    # shift next to the pole (never onto it: the tread's sliding modes have zero poles)
    sigma = model_pole - 1e-3 * (1.0 + abs(model_pole))
    lam, X = _modes_near(s, sigma, 8)
    # several eigenvalues about as near (degenerate or close modes): the one whose hub
    # shape resembles the stored mode's at the nearest operating point
    d = np.abs(lam - model_pole)
    cand = np.flatnonzero(d <= d.min() + 0.05 * abs(model_pole.real) + 1e-9 * (1 + abs(model_pole)))
    i_op = int(np.argmin(np.abs(np.asarray(tire.speeds) - v)))
    ref = np.asarray(tire.psi)[i_op, 2 * int(mode)]
    hub = X[:6, cand]
    mac = np.abs(ref.conj() @ hub) ** 2 / np.maximum(
        (np.abs(ref) ** 2).sum() * (np.abs(hub) ** 2).sum(axis=0), 1e-300
    )
    pick = int(cand[np.argmax(mac)])
    x = X[:, pick]
    pole = complex(lam[pick])
    parts = _parts(x, s.dofs, tire.params, n_theta, n_y)
    co = parts.coords
    m = np.real(np.diag(np.asarray(s.M)))
    content, trav = order_content(x, co, m)
    fam, order, share, direction = dominant(content, trav)
    shape = _belt_shape(parts, scale * tire.params.R / parts.largest, n_frames, int(order[0]))
    e = m * np.abs(x) ** 2
    if abs(model_pole.imag) > 0:
        kind = "vibration"
    else:
        from .participation import ZERO_RATE

        kind = "sliding" if abs(model_pole) < ZERO_RATE else "relaxation"
    return TireModeShape(
        mode=int(mode),
        speed_kmh=float(speed_kmh),
        pole=pole,
        model_pole=model_pole,
        freq=float(abs(pole.imag) / (2 * np.pi)),
        family=str(fam[0]),
        order=int(order[0]),
        share=float(share[0]),
        direction=str(direction[0]),
        travelling=float(trav[0].reshape(-1)[np.argmax(content[0])]),
        hub_share=float(e[co.hub].sum() / max(e.sum(), 1e-300)),
        shape=shape,
        kind=kind,
        deformation=_deformation(x, parts, tire.params),
    )


def _deformation(x: ComplexArray, parts: _Parts, params: Any) -> float:
    """Share of the belt's displacement that is no rigid motion with the hub (wheel axes:
    the hub's translation ``t`` and rotation ``r`` moved to every belt point ``p``)."""
    Q = wheel_rotation(params)
    hub = np.asarray(x)[parts.coords.hub]
    t, r = Q.T @ hub[:3], Q.T @ hub[3:]
    rigid = t + np.cross(r, parts.rest)  # (n_t, n_y, 3)
    total = float(np.linalg.norm(parts.d))
    return float(np.linalg.norm(parts.d - rigid) / total) if total > 0 else 0.0


def _check_sizes(n_frames: int, n_theta: int, n_y: int, scale: float) -> None:
    for name, val, lo in (("n_frames", n_frames, 1), ("n_theta", n_theta, 8), ("n_y", n_y, 1)):
        if isinstance(val, bool) or int(val) != val or val < lo:
            raise FBSError(f"{name} must be an integer >= {lo}, got {val!r}")
    if not (np.isfinite(scale) and scale > 0):
        raise FBSError(f"scale must be a positive fraction of the tire radius, got {scale!r}")


@functools.lru_cache(maxsize=8)
def _geometry(params: Any) -> tuple[tuple[str, ...], FloatArray, IntArray]:
    fe = build_chassis(params)
    nodes = fe.nodes
    xyz = np.array([fe.xyz(n) for n in nodes])
    pos = {n: i for i, n in enumerate(nodes)}
    edges = np.array(sorted({tuple(sorted((pos[a], pos[b]))) for a, b in fe.edges()}), np.intp)
    return nodes, xyz, edges


def chassis_geometry(chassis: Any = None) -> tuple[tuple[str, ...], FloatArray, IntArray]:
    """Node names, positions (n_n, 3, m, vehicle axes) and edges (n_e, 2) of the chassis'
    FE model (beam elements and springs between two nodes), to draw it.

    Raises
    ------
    FBSError
        For a chassis without an FE model (an FRF chassis).
    """
    chassis = reference_chassis() if chassis is None else chassis
    if not hasattr(chassis, "params"):
        raise FBSError("the chassis has no FE model to draw (an FRF chassis?)")
    return _geometry(chassis.params)


def _coupled_shape(
    kind: str,
    freq: float,
    pole: complex | None,
    speed: float,
    x: ComplexArray,
    system: SecondOrderSystem,
    tire: Any,
    chassis: Any,
    n_frames: int,
    n_theta: int,
    n_y: int,
    scale: float,
) -> CoupledShape:
    nodes, xyz, edges = chassis_geometry(chassis)
    dofs = list(system.dofs)
    pos = {d: i for i, d in enumerate(dofs)}
    spindle = int(nodes.index("spindle"))
    centre = xyz[spindle]
    Q = wheel_rotation(tire.params)
    parts = _parts(x, dofs, tire.params, n_theta, n_y, "tire/")
    co = parts.coords
    # chassis node translations; a coupled spindle DOF is merged into the tire's hub DOF
    disp = np.zeros((len(nodes), 3), complex)
    for i, nd in enumerate(nodes):
        for j, d in enumerate(TRANSLATIONS):
            lab = f"chassis/{nd}:{d}"
            if lab in pos:
                disp[i, j] = x[pos[lab]]
            elif nd == "spindle":
                disp[i, j] = x[pos[f"tire/hub:{d}"]]
    s = scale * tire.params.R / max(parts.largest, float(np.abs(disp).max()), 1e-300)
    M = system.M
    m = np.real(M.diagonal() if sp.issparse(M) else np.diag(np.asarray(M)))
    content, trav = order_content(x, co, m)
    fam, order, _, direction = dominant(content, trav)
    tire_shape = _belt_shape(parts, s, n_frames, int(order[0]), (centre, Q))
    rot = np.exp(1j * tire_shape.phase)
    points = xyz[None] + s * np.real(disp[None] * rot[:, None, None])
    ch = ChassisShape(nodes, xyz, points, edges)
    e = m * np.abs(x) ** 2
    t_idx = [i for i, d in enumerate(dofs) if d.startswith("tire/")]
    return CoupledShape(
        kind,
        float(freq),
        pole,
        float(speed),
        tire_shape,
        ch,
        float(e[t_idx].sum() / max(e.sum(), 1e-300)),
        str(fam[0]),
        int(order[0]),
        str(direction[0]),
    )


def coupled_mode_shapes(
    freq_hz: float,
    speed_kmh: float,
    coupling: str = "6dof",
    n: int = 3,
    *,
    tire: Any = None,
    chassis: Any = None,
    n_frames: int = 24,
    n_theta: int = 72,
    n_y: int = 5,
    scale: float = 0.1,
) -> tuple[CoupledShape, ...]:
    """The coupled system's modes nearest ``freq_hz`` as tire plus chassis deflection.

    Parameters
    ----------
    freq_hz : float
        Frequency in Hz (e.g. a peak of the coupled response).
    speed_kmh : float
        Vehicle speed (along a harmonic line: ``3.6 f lambda``).
    coupling : {"6dof", "5dof"}
    n : int
        Number of modes (nearest first).
    tire, chassis : optional
        Default the reference models (the tire with physical parameters, the chassis
        an FE model).
    n_frames, n_theta, n_y, scale
        As :func:`tire_mode_shape`.

    Returns
    -------
    tuple of CoupledShape
        Eigenvalues equal :func:`fbs_core.analysis.coupled_modes_near` (the same system).

    Raises
    ------
    FBSError
        For a non-positive frequency, ``n < 1`` or bad drawing sizes.
    """
    if not (np.isfinite(freq_hz) and freq_hz > 0):
        raise FBSError(f"freq_hz must be a positive frequency in Hz, got {freq_hz!r}")
    if isinstance(n, bool) or int(n) != n or n < 1:
        raise FBSError(f"n must be an integer >= 1, got {n!r}")
    _check_sizes(n_frames, n_theta, n_y, scale)
    coupled_dofs(coupling)
    tire, chassis = _models(tire, chassis)
    s = coupled_system(float(speed_kmh), coupling, tire=tire, chassis=chassis)
    sigma = 2j * np.pi * float(freq_hz)
    lam, X = _modes_near(s, sigma, max(3 * int(n), 8))
    pos = np.flatnonzero(lam.imag > 0)
    pos = pos[np.argsort(np.abs(lam[pos].imag / (2 * np.pi) - freq_hz), kind="stable")][: int(n)]
    return tuple(
        _coupled_shape(
            "mode",
            lam[i].imag / (2 * np.pi),
            complex(lam[i]),
            float(speed_kmh),
            X[:, i],
            s,
            tire,
            chassis,
            n_frames,
            n_theta,
            n_y,
            scale,
        )
        for i in pos
    )


def _models(tire: Any, chassis: Any) -> tuple[Any, Any]:
    if tire is None:
        from .. import reference_tire

        tire = reference_tire()
    return tire, reference_chassis() if chassis is None else chassis


def operating_shape(
    harmonic: int,
    freq_hz: float,
    coupling: str = "6dof",
    *,
    speed_kmh: float | None = None,
    tire: Any = None,
    chassis: Any = None,
    n_frames: int = 24,
    n_theta: int = 72,
    n_y: int = 5,
    scale: float = 0.1,
) -> CoupledShape:
    """The operating deflection shape of the coupled system at one frequency of a case.

    The assembled tire + chassis at the line's speed ``v = 3.6 f lambda`` (or
    ``speed_kmh``) solved for the patch load of the harmonic's wavelength at ``freq_hz``
    (``(K - omega^2 M + j omega C) x = f``, eq. 2.2; the physics behind eq. 4.1 with all
    modes).

    Parameters
    ----------
    harmonic : int
        Case 1..7 (its wavelength; along its line unless ``speed_kmh`` is given).
    freq_hz : float
        Excitation frequency in Hz.
    coupling : {"6dof", "5dof"}
    speed_kmh : float, optional
        Keyword only: a fixed speed instead of the harmonic line.
    tire, chassis, n_frames, n_theta, n_y, scale
        As :func:`coupled_mode_shapes`.

    Returns
    -------
    CoupledShape
        ``kind="ods"``; the displacement per metre of road amplitude, scaled.

    Raises
    ------
    FBSError
        For a non-positive frequency or bad drawing sizes.
    HarmonicError
        For an unknown case.
    """
    h = _harmonic(harmonic)
    if not (np.isfinite(freq_hz) and freq_hz > 0):
        raise FBSError(f"freq_hz must be a positive frequency in Hz, got {freq_hz!r}")
    _check_sizes(n_frames, n_theta, n_y, scale)
    coupled_dofs(coupling)
    tire, chassis = _models(tire, chassis)
    v = float(h.speed_at(float(freq_hz))) if speed_kmh is None else float(speed_kmh)
    s = coupled_system(v, coupling, tire=tire, chassis=chassis)
    w = 2 * np.pi * float(freq_hz)
    Z = (sp.csc_matrix(s.K) - w**2 * sp.csc_matrix(s.M) + 1j * w * sp.csc_matrix(s.C)).tocsc()
    load = tire.patch_load(v, h.wavelength)
    b = np.zeros(s.n, complex)
    t_idx = [i for i, d in enumerate(s.dofs) if d.startswith("tire/")]
    b[t_idx] = load
    x = spla.spsolve(Z, b)
    return _coupled_shape(
        "ods", float(freq_hz), None, v, x, s, tire, chassis, n_frames, n_theta, n_y, scale
    )
