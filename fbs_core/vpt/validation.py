"""The reference chassis "measured" at a knuckle: the truth of the VPT validation.

The reference chassis' wheel carrier is one rigid node (``spindle``, :mod:`fbs_core.chassis`),
so points on it move exactly as rigid offsets and a virtual point of them would be exact by
construction. To test the transformation on physics it cannot know, this module gives the
carrier a flexible knuckle: three steel tube arms (80 x 10 mm, 95-115 mm long, two beam
elements each, :mod:`fbs_core.fe`) welded to the spindle node, with a 10 g tri-axial
accelerometer at each tip. Every other part of the chassis is that of
:func:`fbs_core.reference_chassis`; the arms' 5.6 kg are taken off the carrier's lumped mass
(18 kg in all, as the reference's). The arms' first flexible mode (spindle clamped) is near
5.6 kHz, far above the analysis band (2-450 Hz), as a cast knuckle's is; arms of 30 mm rod
were too soft: their local compliance under the impacts gave 18 % errors at 100 Hz.

The measurement, as test engineers lay it out (docs/vpt.md): the three tri-axial sensors on
the arm tips, each in its own rotated frame (sensors are glued where the surface allows, not
along the vehicle axes), and 12 impacts: x, y and z at the middle of each arm and one skew
impact on each tip. Sensor channels ``sa:x .. sc:z`` (the sensor's own axes), impacts
``ma:x .. mc:z`` and ``ta:z``, ``tb:z``, ``tc:z``: a label names the channel, its direction
cosines say where it points.

:func:`knuckle_measurement` returns the "measured" set (sensor channels by impacts, plus the
bushing channels by impacts) beside the exact 6-DOF spindle FRFs, all by direct solution of
the same FE model (:meth:`fbs_core.direct.SecondOrderSystem.frf`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike

from .._typing import FloatArray
from ..chassis import BUSHING, SPINDLE, ChassisParameters, build_chassis
from ..direct import SecondOrderSystem
from ..fe import FEModel, Material, Section, rigid_body_mass
from ..frf import FRF
from .geometry import Channels, Layout

__all__ = [
    "KnuckleMeasurement",
    "knuckle_model",
    "knuckle_layout",
    "knuckle_measurement",
    "knuckle_flexible_mode",
    "perturbed_layout",
    "ARMS",
]

#: Arm tips relative to the spindle (m), vehicle axes: front-upper, rear-upper, lower.
ARMS: dict[str, tuple[float, float, float]] = {
    "a": (0.09, -0.03, 0.04),
    "b": (-0.09, -0.03, 0.05),
    "c": (0.015, -0.04, -0.105),
}
#: Rotation of each sensor's frame (degrees about x, y, z of the vehicle, applied in that order).
SENSOR_FRAMES: dict[str, tuple[float, float, float]] = {
    "a": (30.0, 30.0, -30.0),
    "b": (0.0, 0.0, 30.0),
    "c": (30.0, 0.0, 30.0),
}
#: Skew impact direction on each tip (unit vectors after normalisation).
TIP_IMPACTS: dict[str, tuple[float, float, float]] = {
    "a": (0.0, 0.6, 0.8),
    "b": (0.7, 0.7, 0.0),
    "c": (0.3, -0.8, -0.5),
}
#: Outer diameter and wall of the knuckle arms' steel tube (m).
ARM_TUBE = (0.080, 0.010)
SENSOR_MASS = 0.010
STEEL = Material(210e9, 0.3, 7850.0, 0.002)


def _rotation(angles_deg: tuple[float, float, float]) -> FloatArray:
    ax, ay, az = np.radians(angles_deg)
    Rx = np.array([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
    Ry = np.array([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
    Rz = np.array([[np.cos(az), -np.sin(az), 0], [np.sin(az), np.cos(az), 0], [0, 0, 1]])
    out: FloatArray = Rz @ Ry @ Rx
    return out


def _add_arms(m: FEModel, spindle: FloatArray) -> None:
    rod = Section.tube(*ARM_TUBE)
    for k, off in ARMS.items():
        m.add_node(f"k{k}", spindle + np.asarray(off))
        up = (0.0, 1.0, 0.0) if abs(off[2]) > 0.1 else (0.0, 0.0, 1.0)
        m.add_beam("spindle", f"k{k}", rod, STEEL, 2, up, prefix=f"m{k}_")
        m.add_mass(f"k{k}", rigid_body_mass(SENSOR_MASS, (2e-7, 2e-7, 2e-7)))


def arms_mass() -> float:
    """Mass of the three knuckle arms (kg), taken off the carrier's lumped mass."""
    rod = Section.tube(*ARM_TUBE)
    return float(sum(STEEL.rho * rod.A * np.linalg.norm(o) for o in ARMS.values()))


def knuckle_model(params: ChassisParameters | None = None) -> FEModel:
    """The reference chassis with the flexible knuckle arms and sensors (see module).

    The arms are part of the carrier: their mass is taken off its lumped mass, so the
    carrier weighs what the reference's does (its inertia grows by the arms' own)."""
    p = ChassisParameters() if params is None else params
    m = build_chassis(replace(p, carrier_mass=p.carrier_mass - arms_mass()))
    _add_arms(m, np.asarray(p.spindle_xyz, float))
    return m


@functools.lru_cache(maxsize=2)
def _system(params: ChassisParameters) -> SecondOrderSystem:
    return knuckle_model(params).system()


def knuckle_flexible_mode(params: ChassisParameters | None = None) -> float:
    """First eigenfrequency (Hz) of the knuckle arms with the spindle node clamped."""
    p = ChassisParameters() if params is None else params
    m = FEModel()
    m.add_node("spindle", p.spindle_xyz)
    _add_arms(m, np.asarray(p.spindle_xyz, float))
    s = m.system()
    free = [i for i, d in enumerate(s.dofs) if not d.startswith("spindle:")]
    K = s.K.toarray()[np.ix_(free, free)].real
    M = s.M.toarray()[np.ix_(free, free)]
    lam = sla.eigh(K, M, eigvals_only=True, subset_by_index=[0, 0])
    return float(np.sqrt(lam[0]) / (2 * np.pi))


def knuckle_layout(params: ChassisParameters | None = None) -> Layout:
    """The nominal layout: 3 tri-axial sensors (9 channels), 12 impacts, virtual point at
    the spindle (node ``spindle``)."""
    p = ChassisParameters() if params is None else params
    S = np.asarray(p.spindle_xyz, float)
    s_lab, s_pos, s_dir = [], [], []
    for k, off in ARMS.items():
        R = _rotation(SENSOR_FRAMES[k])
        for j, d in enumerate("xyz"):
            s_lab.append(f"s{k}:{d}")
            s_pos.append(S + np.asarray(off))
            s_dir.append(R[:, j])
    i_lab, i_pos, i_dir = [], [], []
    for k, off in ARMS.items():
        for j, d in enumerate("xyz"):
            i_lab.append(f"m{k}:{d}")
            i_pos.append(S + 0.5 * np.asarray(off))
            i_dir.append(np.eye(3)[j])
    for k, off in ARMS.items():
        v = np.asarray(TIP_IMPACTS[k])
        i_lab.append(f"t{k}:z")
        i_pos.append(S + np.asarray(off))
        i_dir.append(v / np.linalg.norm(v))
    return Layout(
        Channels(s_lab, s_pos, s_dir, "sensor"),
        Channels(i_lab, i_pos, i_dir, "impact"),
        S,
        "spindle",
    )


def _fe_node(label: str) -> str:
    """FE node of a channel: sensors ``s?`` and tip impacts ``t?`` on the tip ``k?``,
    mid-arm impacts ``m?`` on the arm's middle node ``m?_1``."""
    node = label.split(":")[0]
    return f"k{node[1]}" if node[0] in "st" else f"m{node[1]}_1"


@dataclass(frozen=True, eq=False)
class KnuckleMeasurement:
    """A simulated VPT measurement and its exact answer.

    Attributes
    ----------
    measured : FRF
        Outputs: the 9 sensor channels then ``bushing:x .. bushing:rz``; inputs: the 12
        impacts (the layout's labels).
    exact : FRF
        Outputs ``spindle:*`` then ``bushing:*``; inputs ``spindle:*``: the FE model's own
        6-DOF FRFs at the wheel centre.
    layout : Layout
        The nominal layout used to make ``measured``.
    """

    measured: FRF
    exact: FRF
    layout: Layout


def knuckle_measurement(
    freq: ArrayLike,
    quantity: str = "accelerance",
    layout: Layout | None = None,
    params: ChassisParameters | None = None,
) -> KnuckleMeasurement:
    """The knuckle model "measured" at ``layout`` and its exact spindle FRFs.

    Parameters
    ----------
    freq : array_like
        Lines in Hz (> 0).
    quantity : str
        What the simulated sensors measure (accelerometers: ``"accelerance"``).
    layout : Layout, optional
        Where the channels are; default :func:`knuckle_layout`. Its channels must sit on
        the model's measurement nodes (sensor ``s?`` and tip impacts ``t?`` at the arm tips,
        ``m?`` at the arm middles); their directions are free.
    params : ChassisParameters, optional

    Returns
    -------
    KnuckleMeasurement
    """
    p = ChassisParameters() if params is None else params
    lay = knuckle_layout(p) if layout is None else layout
    s = _system(p)
    nodes = sorted({_fe_node(x) for x in lay.sensors.labels})
    trans = [f"{n}:{ax}" for n in nodes for ax in "xyz"]
    loads = {}
    idx = {d: i for i, d in enumerate(s.dofs)}
    for lab, e in zip(lay.impacts.labels, lay.impacts.directions, strict=True):
        v = np.zeros(s.n)
        n = _fe_node(lab)
        for j, ax in enumerate("xyz"):
            v[idx[f"{n}:{ax}"]] = e[j]
        loads[lab] = v
    H = s.frf(
        freq,
        outputs=list(SPINDLE + BUSHING) + trans,
        inputs=list(SPINDLE),
        loads=loads,
        quantity=quantity,
    )
    d = H.data
    n_sb = len(SPINDLE) + len(BUSHING)
    pos = {n: n_sb + 3 * i for i, n in enumerate(nodes)}
    rows = []
    for lab, e in zip(lay.sensors.labels, lay.sensors.directions, strict=True):
        a = pos[_fe_node(lab)]
        rows.append(np.einsum("j,fjk->fk", e, d[:, a : a + 3, 6:]))
    meas = np.concatenate([np.stack(rows, axis=1), d[:, 6:12, 6:]], axis=1)
    measured = FRF(
        H.freq, meas, list(lay.sensors.labels) + list(BUSHING), list(lay.impacts.labels), quantity
    )
    exact = FRF(H.freq, d[:, :12, :6], list(SPINDLE + BUSHING), list(SPINDLE), quantity)
    return KnuckleMeasurement(measured, exact, lay)


def perturbed_layout(
    layout: Layout,
    position_error: float = 0.002,
    angle_error_deg: float = 2.0,
    seed: int = 0,
) -> Layout:
    """The layout as an engineer would write it down: every point off by ``position_error``
    metres (a random direction, the same for all channels of a point) and every channel's
    direction off by ``angle_error_deg`` (about a random perpendicular axis)."""
    rng = np.random.default_rng(seed)

    def move(ch: Channels, what: str) -> Channels:
        pts: dict[tuple[float, ...], FloatArray] = {}
        P, D = [], []
        for r, e in zip(ch.positions, ch.directions, strict=True):
            key = tuple(np.round(r, 9))
            if key not in pts:
                v = rng.normal(size=3)
                pts[key] = r + position_error * v / np.linalg.norm(v)
            P.append(pts[key])
            a = np.cross(e, rng.normal(size=3))
            a /= np.linalg.norm(a)
            t = np.radians(angle_error_deg)
            D.append(e * np.cos(t) + np.cross(a, e) * np.sin(t))
        return Channels(ch.labels, np.array(P), np.array(D), what)

    return Layout(
        move(layout.sensors, "sensor"), move(layout.impacts, "impact"), layout.origin, layout.node
    )


def noisy(frf: FRF, level: float = 0.01, seed: int = 0) -> FRF:
    """``frf`` with complex Gaussian noise of relative standard deviation ``level`` on
    every entry (``Y (1 + level (n_1 + j n_2) / sqrt 2)``)."""
    rng = np.random.default_rng(seed)
    z = (rng.normal(size=frf.shape) + 1j * rng.normal(size=frf.shape)) / np.sqrt(2)
    return frf.replace(data=frf.data * (1 + level * z))
