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

The bushing's rotations cannot be measured directly; a test glues sensors around it and
transforms them to a second virtual point (:func:`fbs_core.vpt.response_point`). With
``bushing="arms"`` the model carries three short stiff steel arms (40 x 8 mm tube, 75-78 mm
long, two beam elements each) welded to the ``bushing`` node, a 10 g tri-axial sensor at
each tip (nodes ``bushing_a .. bushing_c``, channels in the sensors' own turned frames), and
the measured set holds those channels instead of the bushing's own DOFs; their first
flexible mode (bushing node clamped, :func:`bushing_arms_flexible_mode`) is far above the
band. With ``bushing="rigid"`` the same channels are the bushing node's rigid-body motion,
``u_s = e . (u_b + theta_b x r_s)`` (IMAC 2015 eq. 2), on the unmodified model: the
transformation's exact case.
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
    "perturbed_channels",
    "ARMS",
    "BUSHING_ARMS",
    "bushing_sensors",
    "bushing_arms_flexible_mode",
    "bushing_error_bound",
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
#: Sensors around the bushing: arm tips relative to the bushing node (m), vehicle axes.
BUSHING_ARMS: dict[str, tuple[float, float, float]] = {
    "a": (0.06, 0.03, 0.04),
    "b": (-0.03, 0.06, 0.035),
    "c": (0.02, -0.04, -0.06),
}
#: Rotation of each bushing sensor's frame (degrees about x, y, z, as :data:`SENSOR_FRAMES`):
#: turned so that every channel's leverage stays below 0.76 (docs/vpt.md, layout rule 4).
BUSHING_FRAMES: dict[str, tuple[float, float, float]] = {
    "a": (0.0, -30.0, -30.0),
    "b": (0.0, 30.0, 0.0),
    "c": (0.0, -30.0, 0.0),
}
#: Outer diameter and wall of the bushing sensors' steel arms (m).
BUSHING_ARM_TUBE = (0.040, 0.008)
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


def _add_bushing_arms(m: FEModel, bushing: FloatArray) -> None:
    rod = Section.tube(*BUSHING_ARM_TUBE)
    for k, off in BUSHING_ARMS.items():
        m.add_node(f"bushing_{k}", bushing + np.asarray(off))
        up = (1.0, 0.0, 0.0) if abs(off[0]) < 0.05 else (0.0, 0.0, 1.0)
        m.add_beam("bushing", f"bushing_{k}", rod, STEEL, 2, up, prefix=f"bushing_arm{k}_")
        m.add_mass(f"bushing_{k}", rigid_body_mass(SENSOR_MASS, (2e-7, 2e-7, 2e-7)))


def bushing_point(params: ChassisParameters | None = None) -> FloatArray:
    """Position of the reference chassis' bushing node (m)."""
    p = ChassisParameters() if params is None else params
    return build_chassis(p).xyz("bushing")


def bushing_sensors(params: ChassisParameters | None = None) -> Channels:
    """The nominal sensors around the bushing: 3 tri-axial sensors (9 channels
    ``bushing_a:x .. bushing_c:z``) at the arm tips of :data:`BUSHING_ARMS`, each in its
    own turned frame (:data:`BUSHING_FRAMES`)."""
    b = bushing_point(params)
    lab, pos, dirs = [], [], []
    for k, off in BUSHING_ARMS.items():
        R = _rotation(BUSHING_FRAMES[k])
        for j, d in enumerate("xyz"):
            lab.append(f"bushing_{k}:{d}")
            pos.append(b + np.asarray(off))
            dirs.append(R[:, j])
    return Channels(lab, pos, dirs, "sensor")


def bushing_arms_flexible_mode(params: ChassisParameters | None = None) -> float:
    """First eigenfrequency (Hz) of the bushing sensors' arms with the bushing node clamped."""
    m = FEModel()
    b = bushing_point(params)
    m.add_node("bushing", b)
    _add_bushing_arms(m, b)
    return _clamped_mode(m, "bushing")


def _clamped_mode(m: FEModel, node: str) -> float:
    s = m.system()
    free = [i for i, d in enumerate(s.dofs) if not d.startswith(f"{node}:")]
    K = s.K.toarray()[np.ix_(free, free)].real
    M = s.M.toarray()[np.ix_(free, free)]
    lam = sla.eigh(K, M, eigvals_only=True, subset_by_index=[0, 0])
    return float(np.sqrt(lam[0]) / (2 * np.pi))


def arms_mass() -> float:
    """Mass of the three knuckle arms (kg), taken off the carrier's lumped mass."""
    rod = Section.tube(*ARM_TUBE)
    return float(sum(STEEL.rho * rod.A * np.linalg.norm(o) for o in ARMS.values()))


def knuckle_model(params: ChassisParameters | None = None, bushing_arms: bool = False) -> FEModel:
    """The reference chassis with the flexible knuckle arms and sensors (see module).

    The arms are part of the carrier: their mass is taken off its lumped mass, so the
    carrier weighs what the reference's does (its inertia grows by the arms' own). With
    ``bushing_arms`` the sensors' arms around the bushing are added too (their 1.5 kg are
    the subframe's more: the exact FRFs are those of the same model)."""
    p = ChassisParameters() if params is None else params
    m = build_chassis(replace(p, carrier_mass=p.carrier_mass - arms_mass()))
    _add_arms(m, np.asarray(p.spindle_xyz, float))
    if bushing_arms:
        _add_bushing_arms(m, m.xyz("bushing"))
    return m


@functools.lru_cache(maxsize=4)
def _system(params: ChassisParameters, bushing_arms: bool = False) -> SecondOrderSystem:
    return knuckle_model(params, bushing_arms).system()


def knuckle_flexible_mode(params: ChassisParameters | None = None) -> float:
    """First eigenfrequency (Hz) of the knuckle arms with the spindle node clamped."""
    p = ChassisParameters() if params is None else params
    m = FEModel()
    m.add_node("spindle", p.spindle_xyz)
    _add_arms(m, np.asarray(p.spindle_xyz, float))
    return _clamped_mode(m, "spindle")


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
        Outputs: the 9 sensor channels then ``bushing:x .. bushing:rz`` (or, with sensors
        around the bushing, their channels ``bushing_a:x ..``); inputs: the 12 impacts (the
        layout's labels).
    exact : FRF
        Outputs ``spindle:*`` then ``bushing:*``; inputs ``spindle:*``: the FE model's own
        6-DOF FRFs at the wheel centre.
    layout : Layout
        The nominal layout used to make ``measured``.
    bushing_sensors : Channels or None
        The sensors around the bushing used to make ``measured`` (None: direct outputs).
    exact_bushing : FRF
        The FE model's bushing DOFs ``bushing:x .. bushing:rz`` by the 12 impacts: what a
        second virtual point of ``bushing_sensors`` should give (``Y_bm``).
    """

    measured: FRF
    exact: FRF
    layout: Layout
    bushing_sensors: Channels | None = None
    exact_bushing: FRF | None = None


def knuckle_measurement(
    freq: ArrayLike,
    quantity: str = "accelerance",
    layout: Layout | None = None,
    params: ChassisParameters | None = None,
    bushing: str = "direct",
    bushing_layout: Channels | None = None,
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
    bushing : {"direct", "rigid", "arms"}
        What the set holds at the bushing: its own six DOFs (``"direct"``), or sensor
        channels around it, as the bushing node's rigid-body motion (``"rigid"``, exact for
        a second virtual point) or on the FE arms of the module docstring (``"arms"``).
    bushing_layout : Channels, optional
        The sensors around the bushing (default :func:`bushing_sensors`); with ``"arms"``
        they must sit on the arm tips ``bushing_a .. bushing_c``, directions free.

    Returns
    -------
    KnuckleMeasurement
    """
    if bushing not in ("direct", "rigid", "arms"):
        raise ValueError(f"bushing={bushing!r}; allowed: 'direct', 'rigid', 'arms'")
    p = ChassisParameters() if params is None else params
    lay = knuckle_layout(p) if layout is None else layout
    s = _system(p, bushing == "arms")
    bl: Channels | None = None
    if bushing != "direct":
        bl = bushing_layout if bushing_layout is not None else bushing_sensors(p)
    nodes = sorted({_fe_node(x) for x in lay.sensors.labels})
    b_nodes = (
        sorted({x.split(":")[0] for x in bl.labels}) if bl is not None and bushing == "arms" else []
    )
    trans = [f"{n}:{ax}" for n in nodes + b_nodes for ax in "xyz"]
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
    Yb = d[:, 6:12, 6:]  # the bushing's own six DOFs by the impacts
    if bl is None:
        b_rows, b_labels = Yb, list(BUSHING)
    else:
        r0 = bushing_point(p)
        if bushing == "rigid":  # e . (u_b + theta_b x r) = [e, r x e] . q_b
            R = np.hstack([bl.directions, np.cross(bl.positions - r0, bl.directions)])
            b_rows = np.einsum("kj,fjm->fkm", R, Yb)
        else:
            bpos = {n: n_sb + 3 * (len(nodes) + i) for i, n in enumerate(b_nodes)}
            b_rows = np.zeros((d.shape[0], len(bl), d.shape[2] - 6), complex)
            for k, (lab, e) in enumerate(zip(bl.labels, bl.directions, strict=True)):
                a = bpos[lab.split(":")[0]]  # the arm tip's translations
                b_rows[:, k] = np.einsum("j,fjk->fk", e, d[:, a : a + 3, 6:])
        b_labels = list(bl.labels)
    meas = np.concatenate([np.stack(rows, axis=1), b_rows], axis=1)
    measured = FRF(
        H.freq, meas, list(lay.sensors.labels) + b_labels, list(lay.impacts.labels), quantity
    )
    exact = FRF(H.freq, d[:, :12, :6], list(SPINDLE + BUSHING), list(SPINDLE), quantity)
    exact_b = FRF(H.freq, Yb, list(BUSHING), list(lay.impacts.labels), quantity)
    return KnuckleMeasurement(measured, exact, lay, bl, exact_b)


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
    return Layout(
        _moved(layout.sensors, "sensor", position_error, angle_error_deg, rng),
        _moved(layout.impacts, "impact", position_error, angle_error_deg, rng),
        layout.origin,
        layout.node,
    )


def perturbed_channels(
    channels: Channels,
    position_error: float = 0.002,
    angle_error_deg: float = 2.0,
    seed: int = 0,
) -> Channels:
    """Sensor channels as written down with the errors of :func:`perturbed_layout` (e.g.
    the sensors around the bushing)."""
    rng = np.random.default_rng(seed)
    return _moved(channels, "sensor", position_error, angle_error_deg, rng)


def _moved(
    ch: Channels, what: str, position_error: float, angle_error_deg: float, rng: np.random.Generator
) -> Channels:
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


def bushing_error_bound(
    m: KnuckleMeasurement,
    noise: float = 0.01,
    position_error: float = 0.002,
    angle_error_deg: float = 2.0,
    quantity: str = "mobility",
    sigmas: float = 5.0,
) -> FloatArray:
    """First-order bound of the second virtual point's error under a real test's errors.

    The response transformation maps the channels' error ``y - R^ q`` by ``T_u``
    (IMAC 2015 eq. 5); per channel k that error is its noise (below ``sigmas * noise *
    |y_k|``), its direction error ``(e_k - e^_k) . u(r_k)`` (below ``2 sin(angle / 2)
    |u(r_k)|``) and its position error ``e^_k . (theta x dr_k)`` (below ``dr |theta|``):

        ``|dq_i| <= sum_k |T_ik| (sigmas noise |y_k| + 2 sin(a / 2) |u(r_k)| + dr |theta|)``

    with ``u(r_k) = u_b + theta x (r_k - r_b)`` from the FE model's exact bushing DOFs.

    Parameters
    ----------
    m : KnuckleMeasurement
        Made with sensors around the bushing (``bushing="rigid"`` or ``"arms"``).
    noise, position_error, angle_error_deg : float
        Relative noise (standard deviation), point error (m), direction error (degrees), as
        :func:`noisy`, :func:`perturbed_channels`.
    quantity : str
        The FRF quantity of the bound (relative errors are the same in each).
    sigmas : float
        Noise bound in standard deviations.

    Returns
    -------
    ndarray, shape (n_freq, 6, n_impacts)
        Bound of ``|q_b - Y_bm|`` per line, bushing DOF and impact.
    """
    if m.bushing_sensors is None or m.exact_bushing is None:
        raise ValueError("the measurement has no sensors around the bushing")
    ch = m.bushing_sensors
    r0 = bushing_point()
    Rb = np.hstack([ch.directions, np.cross(ch.positions - r0, ch.directions)])
    T = np.abs(np.linalg.pinv(Rb))
    qb = m.exact_bushing.to(quantity).data
    u, th = qb[:, :3], qb[:, 3:]
    arm = ch.positions - r0
    ur = u[:, None] + np.cross(th[:, None], arm[None, :, :, None], axisa=2, axisb=2, axisc=2)
    y = m.measured.to(quantity).sel(outputs=list(ch.labels)).data
    per = (
        sigmas * noise * np.abs(y)
        + 2 * np.sin(np.radians(angle_error_deg) / 2) * np.linalg.norm(ur, axis=2)
        + position_error * np.linalg.norm(th, axis=1)[:, None]
    )
    out: FloatArray = np.einsum("ik,fkj->fij", T, per)
    return out


def noisy(frf: FRF, level: float = 0.01, seed: int = 0) -> FRF:
    """``frf`` with complex Gaussian noise of relative standard deviation ``level`` on
    every entry (``Y (1 + level (n_1 + j n_2) / sqrt 2)``)."""
    rng = np.random.default_rng(seed)
    z = (rng.normal(size=frf.shape) + 1j * rng.normal(size=frf.shape)) / np.sqrt(2)
    return frf.replace(data=frf.data * (1 + level * z))
