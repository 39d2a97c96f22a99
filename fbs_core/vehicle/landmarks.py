"""Landmarks of the reference car: its modes beside the ranges published for mid-size cars.

Two modal models, both real (undamped) eigenproblems ``K v = omega^2 M v`` on the
real part of the hysteretic stiffness:

- the **trimmed body alone**, free-free (body grillage with its lumped masses, no
  suspension): its first torsion and first vertical bending modes are what body
  engineers quote (a trimmed body hung on soft supports);
- the **car on its tires** at standstill: the structure of :mod:`.structure` with
  each tire condensed onto its hub (static condensation of the tire's matrices at
  0 km/h, ``K_h = K_hh - K_hb K_bb^-1 K_bh``, and the consistent mass of that
  static shape; Guyan 1965), the right tires mirrored. It gives the ride modes
  (bounce, pitch, roll), the wheel hop of the front and rear axle and the body
  modes on the suspension.

Modes are identified by their shapes, not by their order: the ride modes by the
body's rigid-body motion about its centre of gravity (least-squares fit of the
body nodes), wheel hop by the kinetic energy in the hubs' vertical DOFs, torsion
and bending of the free body by the share of vertical kinetic energy that is
antisymmetric or symmetric in y, and on the suspension by the best MAC with
them. Sources of the ranges: docs/vehicle-model.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla

from .._typing import FloatArray
from ..errors import FBSError
from ..fe import offset_transform
from ..vocabulary import DIRECTIONS
from .layout import MIRROR, WHEELS
from .model import VehicleModel, _structure, reference_vehicle
from .structure import BodyParameters, _body, _Builder

__all__ = [
    "Landmark",
    "SOURCES",
    "landmark_table",
    "body_modes",
    "body_torsion_bending",
    "modes_on_tires",
    "mass_properties",
    "MASS_SOURCES",
]

_REFS = {
    "gillespie": "Gillespie, Fundamentals of Vehicle Dynamics, SAE 1992, ch. 5 (ride)",
    "heydinger": "Heydinger et al., Measured vehicle inertial parameters, SAE 1999-01-1336",
    "body": "typical published ranges for mid-size cars; cf. Malen, Fundamentals "
    "of Automobile Body Structure Design, SAE 2011",
}

#: Landmark -> (low Hz, high Hz, source). Derived ranges say how in docs/vehicle-model.md.
SOURCES: dict[str, tuple[float, float, str]] = {
    "bounce": (1.0, 1.5, _REFS["gillespie"]),
    "pitch": (1.0, 1.8, _REFS["gillespie"]),
    "roll": (
        1.2,
        2.1,
        "derived: bounce range x (track / 2) / roll radius of gyration 0.55-0.65 m ("
        + _REFS["heydinger"]
        + ")",
    ),
    "wheel hop front": (10.0, 15.0, _REFS["gillespie"]),
    "wheel hop rear": (10.0, 15.0, _REFS["gillespie"]),
    "body torsion (trimmed body)": (25.0, 40.0, _REFS["body"]),
    "body bending (trimmed body)": (30.0, 45.0, _REFS["body"]),
    "body torsion (on suspension)": (25.0, 40.0, _REFS["body"]),
    "body bending (on suspension)": (30.0, 45.0, _REFS["body"]),
}


@dataclass(frozen=True)
class Landmark:
    """One landmark: the model's value beside its published range.

    Attributes
    ----------
    name : str
    frequency : float
        The model's value (Hz for modes; the unit in ``name`` for mass properties).
    low, high : float
        The published range.
    source : str
        Where the range comes from (docs/vehicle-model.md).
    """

    name: str
    frequency: float
    low: float
    high: float
    source: str

    @property
    def inside(self) -> bool:
        return self.low <= self.frequency <= self.high


def _mirror_pairs(xyz: dict[str, Sequence[float]]) -> list[tuple[str, str | None]]:
    """Each node with y >= 0 and its mirror twin (None on the centre line)."""
    key = {tuple(np.round(np.asarray(p, float), 9)): n for n, p in xyz.items()}
    out: list[tuple[str, str | None]] = []
    for n, p in xyz.items():
        if abs(p[1]) < 1e-9:
            out.append((n, None))
        elif p[1] > 0:
            twin = key.get((round(p[0], 9), round(-p[1], 9), round(p[2], 9)))
            if twin is None:
                raise FBSError(f"node {n!r} has no mirror twin: the body is not symmetric")
            out.append((n, twin))
    return out


def _sym_anti(
    V: FloatArray, Mdiag: FloatArray, dofs: Sequence[str], pairs: list[tuple[str, str | None]]
) -> FloatArray:
    """Vertical kinetic energy symmetric / antisymmetric in y per mode, ``(n_m, 2)``."""
    pos = {d: i for i, d in enumerate(dofs)}
    out = np.zeros((V.shape[1], 2))
    for a, b in pairs:
        i = pos[f"{a}:z"]
        if b is None:
            out[:, 0] += Mdiag[i] * V[i] ** 2
            continue
        j = pos[f"{b}:z"]
        m = Mdiag[i] + Mdiag[j]
        out[:, 0] += m * (0.5 * (V[i] + V[j])) ** 2
        out[:, 1] += m * (0.5 * (V[i] - V[j])) ** 2
    return out


def body_modes(body: BodyParameters | None = None) -> tuple[FloatArray, FloatArray, Any]:
    """Free-free modes of the trimmed body alone (real, mass normalised).

    Returns
    -------
    freq : ndarray, shape (n,)
        Hz (six rigid-body modes first).
    shapes : ndarray, shape (n_dof, n)
    system : SecondOrderSystem
        The body's FE system (labelled DOFs).
    """
    b = _Builder()
    _body(b, BodyParameters() if body is None else body)
    s = b.m.system()
    w2, V = sla.eigh(s.K.toarray().real, s.M.toarray())
    return np.sqrt(np.abs(w2)) / (2 * np.pi), V, (s, {n: b.m.xyz(n) for n in b.m.nodes})


def _first(freq: FloatArray, share: FloatArray, other: FloatArray, lo: float = 5.0) -> int:
    """First elastic mode above ``lo`` Hz whose vertical kinetic energy is mostly of one
    kind: ``share`` (of the total) above 0.3 and above the ``other`` kind's share."""
    ok = np.flatnonzero((freq > lo) & (share > 0.3) & (share > other))
    if ok.size == 0:
        raise FBSError("no global body mode of that kind found: check the body's symmetry")
    return int(ok[0])


def _body_global(body: BodyParameters | None) -> tuple[FloatArray, FloatArray, Any, int, int]:
    fb, Vb, (sb, xyz_b) = body_modes(body)
    e = _sym_anti(Vb, sb.M.diagonal(), sb.dofs, _mirror_pairs(xyz_b))
    tot = np.einsum("im,im->m", Vb, sb.M @ Vb)
    k_tor = _first(fb, e[:, 1] / tot, e[:, 0] / tot)
    k_ben = _first(fb, e[:, 0] / tot, e[:, 1] / tot)
    return fb, Vb, (sb, xyz_b), k_tor, k_ben


def body_torsion_bending(body: BodyParameters | None = None) -> tuple[float, float]:
    """First torsion and first vertical bending frequency (Hz) of the free trimmed body."""
    fb, _, _, k_tor, k_ben = _body_global(body)
    return float(fb[k_tor]), float(fb[k_ben])


def _tire_hub(tire: Any) -> tuple[FloatArray, FloatArray]:
    """Static condensation of the tire at 0 km/h onto its hub: ``(K_h, M_h)`` 6 x 6."""
    s = tire.system(0.0)
    K, M = np.asarray(s.K).real, np.asarray(s.M).real
    h, b = slice(0, 6), slice(6, None)
    T = np.vstack([np.eye(6), -np.linalg.solve(K[b, b], K[b, h])])
    Kh: FloatArray = T.T @ K @ T
    Mh: FloatArray = T.T @ M @ T
    return 0.5 * (Kh + Kh.T), 0.5 * (Mh + Mh.T)


def modes_on_tires(
    vehicle: VehicleModel | None = None, tire: Any = None
) -> tuple[FloatArray, FloatArray, Any]:
    """Modes of the car on its tires (tires condensed at standstill, right ones mirrored).

    Returns ``(freq Hz, shapes (n_dof, n), (system, M with the tire masses))``.
    """
    vehicle = reference_vehicle() if vehicle is None else vehicle
    if tire is None:
        from .. import reference_tire

        tire = reference_tire()
    s = vehicle.system()
    K, M = s.K.toarray().real, s.M.toarray()
    Kh, Mh = _tire_hub(tire)
    T = np.asarray(MIRROR)
    for w in WHEELS:
        i = s.dofs.index(f"spindle_{w}:x")
        S = np.ones(6) if w in ("fl", "rl") else T
        K[i : i + 6, i : i + 6] += S[:, None] * Kh * S[None]
        M[i : i + 6, i : i + 6] += S[:, None] * Mh * S[None]
    w2, V = sla.eigh(K, M)
    return np.sqrt(np.abs(w2)) / (2 * np.pi), V, (s, M)


def landmark_table(vehicle: VehicleModel | None = None, tire: Any = None) -> list[Landmark]:
    """The landmarks of the car beside their published ranges (:data:`SOURCES`).

    Parameters
    ----------
    vehicle : VehicleModel, optional
        Default the reference car; tire: default the reference tire (needs its
        physical matrices).

    Returns
    -------
    list of Landmark
        Ride (bounce, pitch, roll), wheel hop front and rear, body torsion and bending
        of the trimmed body and on the suspension.
    """
    vehicle = reference_vehicle() if vehicle is None else vehicle
    found: dict[str, float] = {}
    # the trimmed body alone
    fb, Vb, (sb, xyz_b), k_tor, k_ben = _body_global(vehicle.params.body)
    found["body torsion (trimmed body)"] = float(fb[k_tor])
    found["body bending (trimmed body)"] = float(fb[k_ben])
    # the car on its tires
    f, V, (s, M) = modes_on_tires(vehicle, tire)
    xyz = _structure(vehicle.params).xyz
    R = np.zeros((s.n, 6))
    for n, p in xyz.items():
        i = s.dofs.index(f"{n}:x")
        R[i : i + 6] = offset_transform(np.asarray(p))
    MR = R.T @ M @ R
    m = MR[0, 0]
    cg = np.array([MR[1, 5], 0.0, MR[0, 4]]) / m
    body = [n for n in xyz if n in xyz_b]
    ib = [s.dofs.index(f"{n}:{d}") for n in body for d in DIRECTIONS]
    Rb = np.concatenate([offset_transform(np.asarray(xyz[n]) - cg) for n in body])
    q = np.linalg.lstsq(Rb, V[ib], rcond=None)[0]  # (6, n_m) rigid motion about the CG
    Jc = MR[3:, 3:] - m * (np.dot(cg, cg) * np.eye(3) - np.outer(cg, cg))
    ride = np.vstack([m * q[2] ** 2, Jc[0, 0] * q[3] ** 2, Jc[1, 1] * q[4] ** 2])
    ride = ride / np.maximum(ride.sum(axis=0), 1e-300)
    low = (f > 0.3) & (f < 4.0)
    for k, name in enumerate(("bounce", "roll", "pitch")):
        found[name] = float(f[low][np.argmax(ride[k][low])])
    kin = V * (M @ V)
    for axle, wheels in (("front", ("fl", "fr")), ("rear", ("rl", "rr"))):
        iz = [s.dofs.index(f"spindle_{w}:z") for w in wheels]
        share = kin[iz].sum(axis=0)
        band = (f > 5.0) & (f < 30.0)
        found[f"wheel hop {axle}"] = float(f[band][np.argmax(share[band])])
    # body modes on the suspension: best MAC with the free body's modes on the body DOFs
    jb = [sb.dofs.index(f"{n}:{d}") for n in body for d in DIRECTIONS]
    band = (f > 15.0) & (f < 60.0)
    for k, name in ((k_tor, "torsion"), (k_ben, "bending")):
        ref = Vb[jb, k]
        mac = (ref @ V[ib]) ** 2 / ((ref @ ref) * np.einsum("im,im->m", V[ib], V[ib]))
        found[f"body {name} (on suspension)"] = float(f[band][np.argmax(mac[band])])
    return [Landmark(n, found[n], *SOURCES[n]) for n in SOURCES]


#: Mass properties of a mid-size car: (low, high, source); derived ones say how.
MASS_SOURCES: dict[str, tuple[float, float, str]] = {
    "wheelbase (m)": (
        2.65,
        2.80,
        "D-segment sedans, manufacturer data (e.g. VW Passat B6 "
        "2.709 m, Toyota Camry XV40 2.775 m)",
    ),
    "track front (m)": (1.50, 1.60, "same cars (Passat B6 1.552 m)"),
    "track rear (m)": (
        1.48,
        1.60,
        "same cars (the thesis' corner puts the rear wheel centre 0.75 m off the centre line)",
    ),
    "mass with tires (kg)": (1300.0, 1600.0, "kerb mass of D-segment sedans, manufacturer data"),
    "front axle load (%)": (50.0, 62.0, "front-engined cars, front- or rear-wheel drive"),
    "centre of gravity height (m)": (0.45, 0.60, _REFS["heydinger"]),
    "roll inertia Ixx (kg m^2)": (400.0, 700.0, _REFS["heydinger"]),
    "pitch inertia Iyy (kg m^2)": (1800.0, 2800.0, _REFS["heydinger"]),
    "yaw inertia Izz (kg m^2)": (2000.0, 3000.0, _REFS["heydinger"]),
    "pitch dynamic index k_y^2 / (a b)": (0.8, 1.2, _REFS["gillespie"]),
}


def mass_properties(vehicle: VehicleModel | None = None, tire: Any = None) -> list[Landmark]:
    """Geometry, mass, centre of gravity and inertias of the car on its tires (tires as
    their condensed hub mass), beside the ranges of :data:`MASS_SOURCES`.

    The :class:`Landmark` rows carry the value in ``frequency`` (a number in the unit of
    the row's name)."""
    vehicle = reference_vehicle() if vehicle is None else vehicle
    _, _, (s, M) = modes_on_tires(vehicle, tire)
    xyz = _structure(vehicle.params).xyz
    R = np.zeros((s.n, 6))
    for n, p in xyz.items():
        i = s.dofs.index(f"{n}:x")
        R[i : i + 6] = offset_transform(np.asarray(p))
    MR = R.T @ M @ R
    m = MR[0, 0]
    cg = np.array([MR[1, 5], 0.0, MR[0, 4]]) / m
    J = MR[3:, 3:] - m * (np.dot(cg, cg) * np.eye(3) - np.outer(cg, cg))
    L = vehicle.wheelbase
    a = -cg[0] - 0.0  # front axle at x = 0
    b = L - a
    values = {
        "wheelbase (m)": L,
        "track front (m)": vehicle.track[0],
        "track rear (m)": vehicle.track[1],
        "mass with tires (kg)": m,
        "front axle load (%)": 100 * b / L,
        "centre of gravity height (m)": cg[2],
        "roll inertia Ixx (kg m^2)": J[0, 0],
        "pitch inertia Iyy (kg m^2)": J[1, 1],
        "yaw inertia Izz (kg m^2)": J[2, 2],
        "pitch dynamic index k_y^2 / (a b)": J[1, 1] / m / (a * b),
    }
    return [Landmark(k, float(values[k]), *MASS_SOURCES[k]) for k in MASS_SOURCES]
