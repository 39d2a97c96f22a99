"""The reference car's structure: a body grillage carrying two strut fronts and the rear axle.

Built on the beam/spring toolkit :mod:`fbs_core.fe`, in ISO 8855 vehicle axes (x
forward, y left, z up) with the origin on the ground below the centre of the
front axle. Three parts:

- **Body** (:class:`BodyParameters`): a grillage of steel beams in the floor plane
  (front rails continuing as floor longitudinals to the rear panel, sills, cross
  members, a tunnel) with posts up to the strut towers and the rear damper
  towers. The sections are *effective* ones: a beam grillage has no floor panel,
  roof or pillars, so the sections of the main members are sized to give the
  first torsion and bending frequencies of a trimmed mid-size body
  (``scripts/build_reference_vehicle.py --tune``), while their area gives the mass
  of a body in white. Trim, powertrain, seats, doors, glass and fuel are lumped
  masses whose centres of gravity sit above the floor (rigid offsets), so that the
  sprung mass, its centre of gravity and its inertias are those of a mid-size car
  (docs/vehicle-model.md, sources there).
- **Front corners** (:class:`FrontParameters`): a MacPherson strut: a rigid
  knuckle (the hub node ``spindle_f<side>``) on a lower control arm (two steel
  beams with a front and a rear rubber bushing to the body), a strut (coil
  spring along its axis, stiff across it) to a strut-top node on a rubber top
  mount in the strut tower, a tie rod to the steering rack, and a viscous damper
  in the strut.
- **Rear axle**: the thesis' rear corner of :mod:`fbs_core.chassis` on both sides
  of one subframe. Every number is the corner's (:class:`~fbs_core.chassis.
  ChassisParameters`); the left half is the corner translated to the rear axle,
  the right half its exact mirror image, and the subframe, which the single
  corner already models at full width, is shared (its right side member meshed
  through the right arm's roots). The four subframe bushings go to body nodes
  instead of ground, and a viscous damper joins each carrier to the body.

The right side of everything is the mirror image of the left: positions
``y -> -y`` and every 6 x 6 stiffness ``T K T`` with ``T = diag(MIRROR)``
(:mod:`.layout`), an exact change of coordinates. Dampers are kept apart from the
hysteretic stiffness (:class:`Damper`): they are viscous and low rank, and
:mod:`.model` couples them exactly to the modal solution.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .._typing import FloatArray
from ..chassis import STEEL_E, STEEL_NU, STEEL_RHO, ChassisParameters
from ..errors import DataFormatError
from ..fe import FEModel, Material, Section, rigid_body_mass
from .layout import MIRROR

__all__ = [
    "BodyParameters",
    "FrontParameters",
    "Damper",
    "build_structure",
    "oriented_stiffness",
    "RESPONSE_NODES",
]

Vec3 = tuple[float, float, float]
Stiff6 = tuple[float, float, float, float, float, float]

#: Response nodes of the reference car (each with six DOFs): the thesis' bushing on
#: both sides of the rear subframe, the rear bushing of each front lower arm, the
#: strut tops (chassis side of the top mounts) and four seat-rail points on the floor.
RESPONSE_NODES: tuple[str, ...] = (
    "bushing_rl",
    "bushing_rr",
    "bushing_fl",
    "bushing_fr",
    "strut_fl",
    "strut_fr",
    "seat_fl",
    "seat_fr",
    "seat_rl",
    "seat_rr",
)

_T6 = np.asarray(MIRROR)


@dataclass(frozen=True)
class BodyParameters:
    """Every number of the body grillage (SI units; left half, the right is mirrored).

    Attributes
    ----------
    wheelbase : float
        Front to rear axle, m (the rear subframe mounts follow it).
    floor_z : float
        Height of the floor grillage above the ground, m.
    rail_y, sill_y, seat_y, rack_y : float
        Lateral positions (left side) of the rails, the sills, the seat-rail response
        points and the steering rack ends, m.
    x_bumper, x_arm_front, x_arm_rear, x_dash, x_seat_front, x_seat_rear, x_heel, \
x_rear_panel : float
        Stations along the body (x, m): bumper, the front lower arms' front and rear
        bushings, dash, front seat rails, heel kick (rear seat), rear panel; the rear
        subframe mounts sit at ``-wheelbase +- subframe half length``.
    front_tower, rear_tower : (float, float, float)
        Strut-top and rear damper-top points on the body (left), m.
    rail, sill, cross, tunnel, tower : (A, Iy, Iz, J)
        Effective sections of the members (m^2, m^4): floor longitudinals (front rails
        continued to the rear panel), sills, cross members, tunnel, tower posts.
    loss : float
        Loss factor of the trimmed body (hysteretic).
    element_length : float
        Target beam element length, m.
    lumped : tuple of (node, mass, height, inertia)
        Lumped masses: node, or a template with ``{s}`` for both sides; mass (kg);
        height of its centre of gravity above the node (m); inertia about it (kg m^2).
    """

    wheelbase: float = 2.70
    floor_z: float = 0.22
    rail_y: float = 0.45
    sill_y: float = 0.72
    seat_y: float = 0.30
    rack_y: float = 0.30
    # stations (x) along the body: bumper, lower-arm front and rear bushings, dash, front
    # seat front and rear rails, heel kick (rear seat), rear subframe front and rear
    # mounts, rear panel
    x_bumper: float = 0.85
    x_arm_front: float = 0.15
    x_arm_rear: float = -0.25
    x_dash: float = -0.65
    x_seat_front: float = -1.25
    x_seat_rear: float = -1.75
    x_heel: float = -2.20
    x_rear_panel: float = -3.70
    front_tower: Vec3 = (-0.03, 0.67, 0.80)
    rear_tower: Vec3 = (-2.75, 0.55, 0.62)
    # tuned (scripts/build_reference_vehicle.py --tune): the vertical bending Iy of the
    # longitudinal members sets the first bending mode, the stiffness of the cross
    # members and towers and the torsion constant J of all members the first torsion mode
    rail: tuple[float, float, float, float] = (1.5e-3, 1.086e-5, 4.0e-6, 8.102e-6)
    sill: tuple[float, float, float, float] = (1.8e-3, 3.62e-5, 1.0e-5, 2.592e-5)
    cross: tuple[float, float, float, float] = (1.2e-3, 4.861e-6, 3.0e-6, 6.481e-6)
    tunnel: tuple[float, float, float, float] = (1.2e-3, 1.448e-5, 4.0e-6, 9.722e-6)
    tower: tuple[float, float, float, float] = (1.2e-3, 9.722e-6, 9.722e-6, 1.296e-5)
    loss: float = 0.06
    element_length: float = 0.30
    # (node, or a template with {s} for both sides; mass kg; height of its centre of
    # gravity above the node m; inertia about it kg m^2)
    lumped: tuple[tuple[str, float, float, Vec3], ...] = (
        ("b.rail_{s}.bumper", 42.0, 0.25, (0.8, 0.8, 0.8)),  # bumper, radiator, powertrain
        ("b.rail_{s}.arm_front", 60.0, 0.33, (2.0, 2.0, 2.0)),  # powertrain (200 kg)
        ("b.rail_{s}.arm_rear", 20.0, 0.33, (1.0, 1.0, 1.0)),
        ("b.tower_f{s}", 18.0, 0.0, (0.3, 0.3, 0.3)),  # battery, wiper, HVAC intake
        ("b.sill_{s}.dash", 50.0, 0.45, (1.0, 1.0, 1.0)),  # cockpit, HVAC, A-pillar, glass
        ("seat_f{s}", 30.0, 0.35, (1.0, 1.0, 1.0)),  # front seats
        ("b.sill_{s}.seat_front", 48.0, 0.55, (3.0, 1.0, 2.0)),  # front door, B-pillar, trim
        ("b.sill_{s}.seat_rear", 42.0, 0.70, (2.0, 1.0, 1.5)),  # roof, headliner, rear door
        ("b.sill_{s}.heel", 40.0, 0.60, (2.0, 1.0, 1.0)),  # C-pillar, rear glass, trim
        ("seat_r{s}", 25.0, 0.30, (1.0, 1.0, 1.0)),  # rear bench
        ("b.rail_{s}.sub_front", 25.0, 0.10, (1.0, 1.0, 1.0)),  # fuel tank, fuel
        ("b.rail_{s}.sub_rear", 15.0, 0.35, (1.0, 1.0, 1.0)),  # boot, spare wheel
        ("b.rail_{s}.rear_panel", 15.0, 0.30, (0.5, 0.5, 0.5)),  # rear bumper, lights
        ("b.c.tunnel_mid", 30.0, 0.0, (1.0, 1.0, 1.0)),  # exhaust, shift, console
    )


@dataclass(frozen=True)
class FrontParameters:
    """Every number of a front strut corner (left one; the right is mirrored).

    Stiffnesses ``(x, y, z, rx, ry, rz)`` in N/m and N m/rad, in global axes unless
    said otherwise; loss factors of the hysteretic (rubber / steel) parts.

    Attributes
    ----------
    spindle_xyz : (float, float, float)
        Wheel centre (the hub node), m.
    knuckle_mass, knuckle_inertia
        Knuckle with hub bearing, brake disc and caliper: kg, kg m^2 (about the centre).
    ball_offset, ball_stiffness
        Lower ball joint (offset from the wheel centre, m) and its translational
        stiffness (N/m; rotations free).
    arm_box, arm_elements
        Lower control arm: steel box ``(b, h, wall)`` m and beam elements per branch.
    arm_front_bushing, arm_rear_bushing, bushing_loss
        The arm's two rubber bushings to the body and their loss factor.
    strut_offset, strut_top
        Strut's lower mount on the knuckle (offset) and its top point (global), m.
    strut_axial, strut_transverse, strut_bending, strut_torsion, strut_loss
        Strut in its own axes: the coil spring along it (N/m), the rod in its guide
        across it (N/m), bending and the free rotation about its axis (N m/rad).
    strut_top_mass
        Upper spring seat, top-mount inner part and rod, kg.
    top_mount_axial, top_mount_radial, top_mount_tilt, top_mount_torsion
        Rubber top mount in strut axes.
    tie_rod_offset, tie_rod_stiffness
        Steering arm point on the knuckle (offset) and the tie rod's axial stiffness.
    steel_loss
        Loss factor of the steel parts.
    damper
        Viscous damper in the strut, N s/m.
    """

    spindle_xyz: Vec3 = (0.0, 0.775, 0.30)
    knuckle_mass: float = 20.0
    knuckle_inertia: Vec3 = (0.35, 0.30, 0.35)
    # lower ball joint on the knuckle (offset from the wheel centre): a stiff
    # spherical joint (translations only)
    ball_offset: Vec3 = (0.0, -0.07, -0.16)
    ball_stiffness: float = 5.0e7
    # lower control arm: steel box, from the ball joint to the two body bushings
    arm_box: tuple[float, float, float] = (0.03, 0.05, 0.003)
    arm_elements: int = 3
    arm_front_bushing: Stiff6 = (1.5e6, 8.0e6, 8.0e6, 200.0, 300.0, 300.0)
    arm_rear_bushing: Stiff6 = (1.2e6, 4.0e6, 1.5e6, 200.0, 200.0, 100.0)
    bushing_loss: float = 0.15
    # strut: from its lower mount on the knuckle (offset) to the strut-top node;
    # stiffness in strut axes (axial along the strut = coil spring, across = the rod
    # in its guide, rotations about the axis free in the top bearing)
    strut_offset: Vec3 = (0.0, -0.03, 0.17)
    strut_top: Vec3 = (-0.03, 0.67, 0.80)
    strut_axial: float = 2.3e4
    strut_transverse: float = 2.0e6
    strut_bending: float = 2.0e4
    strut_torsion: float = 5.0
    strut_loss: float = 0.05
    strut_top_mass: float = 2.0
    # top mount (rubber) between strut top and the strut tower, strut axes
    top_mount_axial: float = 1.2e6
    top_mount_radial: float = 2.5e6
    top_mount_tilt: float = 150.0
    top_mount_torsion: float = 2.0
    # tie rod: axial spring from the steering arm (offset) to the rack on the body
    tie_rod_offset: Vec3 = (-0.13, -0.08, -0.04)
    tie_rod_stiffness: float = 5.0e6
    steel_loss: float = 0.005
    damper: float = 1500.0


@dataclass(frozen=True)
class Damper:
    """A viscous dashpot ``c`` along ``axis`` between a point on node ``a`` (at
    ``offset_a``) and a point on node ``b`` (``offset_b``), both rigidly attached.

    ``axis`` is a unit vector in vehicle axes; the dashpot force is
    ``c axis . (v_b - v_a)``.
    """

    name: str
    a: str
    b: str
    offset_a: Vec3
    offset_b: Vec3
    axis: Vec3
    c: float


@dataclass
class _Builder:
    m: FEModel = field(default_factory=FEModel)
    dampers: list[Damper] = field(default_factory=list)


def _unit(v: Sequence[float] | FloatArray) -> FloatArray:
    a = np.asarray(v, float)
    n = float(np.linalg.norm(a))
    if n == 0:
        raise DataFormatError("zero-length axis")
    out: FloatArray = a / n
    return out


def _axes(axis: Sequence[float] | FloatArray) -> FloatArray:
    """Rows: a unit ``axis`` as local z and two unit vectors across it (3 x 3)."""
    ez = _unit(axis)
    ref = np.array([1.0, 0.0, 0.0]) if abs(ez[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    ex = _unit(ref - ez * (ref @ ez))
    ey = np.cross(ez, ex)
    return np.vstack([ex, ey, ez])


def oriented_stiffness(local: Sequence[float], R: FloatArray) -> FloatArray:
    """6 x 6 global stiffness of a spring given by its diagonal ``local`` in its own
    axes (rows of ``R``: the spring's axes in vehicle axes), ``Rb^T diag(k) Rb``."""
    Rb = np.kron(np.eye(2), R)
    out: FloatArray = Rb.T @ np.diag(np.asarray(local, float)) @ Rb
    return out


def _mirror6(K: FloatArray, side: int) -> FloatArray:
    if side > 0:
        return K
    out: FloatArray = _T6[:, None] * K * _T6[None, :]
    return out


def _mirror3(v: Sequence[float] | FloatArray, side: int) -> Vec3:
    a = np.asarray(v, float)
    return (float(a[0]), float(side * a[1]), float(a[2]))


def _n_el(p: FloatArray, q: FloatArray, h: float) -> int:
    return max(1, round(float(np.linalg.norm(q - p)) / h))


def _side_name(side: int) -> str:
    return "l" if side > 0 else "r"


def _body(b: _Builder, p: BodyParameters) -> dict[str, str]:
    """The grillage; returns the attachment nodes of the suspensions by key."""
    m = b.m
    steel = Material(STEEL_E, STEEL_NU, STEEL_RHO, p.loss)
    secs = {k: Section(*getattr(p, k)) for k in ("rail", "sill", "cross", "tunnel", "tower")}
    z = p.floor_z
    sub_half = ChassisParameters().subframe_half[0]
    rail_x = {
        "bumper": p.x_bumper,
        "arm_front": p.x_arm_front,
        "arm_rear": p.x_arm_rear,
        "dash": p.x_dash,
        "seat_front": p.x_seat_front,
        "seat_rear": p.x_seat_rear,
        "heel": p.x_heel,
        "sub_front": -p.wheelbase + sub_half,
        "sub_rear": -p.wheelbase - sub_half,
        "rear_panel": p.x_rear_panel,
    }
    sill_x = {k: rail_x[k] for k in ("dash", "seat_front", "seat_rear", "heel")}

    def beam(a: str, c: str, sec: str) -> None:
        pa, pc = m.xyz(a), m.xyz(c)
        m.add_beam(a, c, secs[sec], steel, _n_el(pa, pc, p.element_length), (0, 0, 1))

    def chain(nodes: Sequence[str], sec: str) -> None:
        for a, c in zip(nodes[:-1], nodes[1:], strict=True):
            beam(a, c, sec)

    centre = {
        k: m.add_node(f"b.c.{k}", (x, 0.0, z)) for k, x in rail_x.items() if k not in ("sub_front",)
    }
    centre["tunnel_mid"] = m.add_node("b.c.tunnel_mid", (0.5 * (p.x_seat_rear + p.x_heel), 0, z))
    names: dict[str, str] = {}
    for side in (1, -1):
        s = _side_name(side)
        rail = {
            k: m.add_node(f"b.rail_{s}.{k}", (x, side * p.rail_y, z)) for k, x in rail_x.items()
        }
        sill = {
            k: m.add_node(f"b.sill_{s}.{k}", (x, side * p.sill_y, z)) for k, x in sill_x.items()
        }
        chain(list(rail.values()), "rail")
        chain(list(sill.values()), "sill")
        rack = m.add_node(f"b.rack_{s}", (p.x_arm_rear, side * p.rack_y, z))
        seat_f = m.add_node(f"seat_f{s}", (p.x_seat_front, side * p.seat_y, z))
        seat_r = m.add_node(f"seat_r{s}", (p.x_heel, side * p.seat_y, z))
        crosses: list[list[str]] = [
            [rail["bumper"], centre["bumper"]],
            [rail["arm_front"], centre["arm_front"]],
            [rail["arm_rear"], rack, centre["arm_rear"]],
            [sill["dash"], rail["dash"], centre["dash"]],
            [sill["seat_front"], rail["seat_front"], seat_f, centre["seat_front"]],
            [sill["seat_rear"], rail["seat_rear"], centre["seat_rear"]],
            [sill["heel"], rail["heel"], seat_r, centre["heel"]],
            [rail["sub_rear"], centre["sub_rear"]],
            [rail["rear_panel"], centre["rear_panel"]],
        ]
        for members in crosses:
            chain(members, "cross")
        # towers: posts from the rails up to the strut tower (and on to the dash) and to
        # the rear damper tower
        ft = m.add_node(f"b.tower_f{s}", _mirror3(p.front_tower, side))
        rt = m.add_node(f"b.tower_r{s}", _mirror3(p.rear_tower, side))
        for a, b_ in (
            (rail["arm_front"], ft),
            (rail["arm_rear"], ft),
            (ft, sill["dash"]),
            (rail["sub_front"], rt),
            (rail["sub_rear"], rt),
        ):
            beam(a, b_, "tower")
        names.update(
            {
                f"arm_front_{s}": rail["arm_front"],
                f"arm_rear_{s}": rail["arm_rear"],
                f"rack_{s}": rack,
                f"tower_f{s}": ft,
                f"tower_r{s}": rt,
                f"sub_front_{s}": rail["sub_front"],
                f"sub_rear_{s}": rail["sub_rear"],
            }
        )
    chain([centre[k] for k in ("dash", "seat_front", "seat_rear", "tunnel_mid", "heel")], "tunnel")
    for where, mass, dz, inertia in p.lumped:
        targets = [where.format(s=s) for s in "lr"] if "{s}" in where else [where]
        for t in targets:
            m.add_mass(t, rigid_body_mass(mass, inertia, (0.0, 0.0, dz)))
    return names


def _axial(k: float, axis: FloatArray) -> FloatArray:
    """6 x 6 stiffness of an axial spring ``k`` along the unit vector ``axis``."""
    K = np.zeros((6, 6))
    K[:3, :3] = k * np.outer(axis, axis)
    return K


def _front(b: _Builder, p: FrontParameters, side: int, body: dict[str, str]) -> None:
    """One strut corner, built for the left and mirrored for the right."""
    m = b.m
    s = _side_name(side)
    w = f"f{s}"
    steel = Material(STEEL_E, STEEL_NU, STEEL_RHO, p.steel_loss)
    hub = np.asarray(p.spindle_xyz, float)
    spindle = m.add_node(f"spindle_{w}", _mirror3(hub, side))
    m.add_mass(spindle, rigid_body_mass(p.knuckle_mass, p.knuckle_inertia))
    # lower ball joint: translations only
    ball = m.add_node(f"{w}.ball", _mirror3(hub + p.ball_offset, side))
    k_ball = np.diag([p.ball_stiffness] * 3 + [0.0] * 3)
    m.add_spring(spindle, ball, k_ball, p.steel_loss, offset_a=_mirror3(p.ball_offset, side))
    # lower control arm and its two rubber bushings to the body
    front = m.add_node(f"{w}.arm_front", m.xyz(body[f"arm_front_{s}"]))
    rear = m.add_node(f"bushing_{w}", m.xyz(body[f"arm_rear_{s}"]))
    box = Section.box(*p.arm_box)
    for end, tag in ((front, "f"), (rear, "r")):
        m.add_beam(ball, end, box, steel, p.arm_elements, (0, 0, 1), prefix=f"{w}.arm_{tag}.")
    m.add_spring(front, body[f"arm_front_{s}"], p.arm_front_bushing, p.bushing_loss)
    m.add_spring(rear, body[f"arm_rear_{s}"], p.arm_rear_bushing, p.bushing_loss)
    # strut: coil spring along its axis, stiff across it, to the strut top; top mount
    lower = hub + p.strut_offset
    axis = _unit(np.asarray(p.strut_top) - lower)  # left side
    R = _axes(axis)
    k_strut = oriented_stiffness(
        (p.strut_transverse,) * 2 + (p.strut_axial,) + (p.strut_bending,) * 2 + (p.strut_torsion,),
        R,
    )
    k_mount = oriented_stiffness(
        (p.top_mount_radial,) * 2
        + (p.top_mount_axial,)
        + (p.top_mount_tilt,) * 2
        + (p.top_mount_torsion,),
        R,
    )
    top = m.add_node(f"strut_{w}", _mirror3(p.strut_top, side))
    m.add_mass(top, rigid_body_mass(p.strut_top_mass, (0.01, 0.01, 0.005)))
    # the strut is the knuckle's rigid extension up to the strut top with a telescopic
    # joint there: both ends of the spring at the strut-top point (rigid-body invariant)
    m.add_spring(
        spindle,
        top,
        _mirror6(k_strut, side),
        p.strut_loss,
        offset_a=_mirror3(np.asarray(p.strut_top) - hub, side),
    )
    m.add_spring(top, body[f"tower_f{s}"], _mirror6(k_mount, side), p.bushing_loss)
    b.dampers.append(
        Damper(
            f"damper_{w}",
            spindle,
            top,
            _mirror3(p.strut_offset, side),
            (0.0, 0.0, 0.0),
            _mirror3(axis, side),
            p.damper,
        )
    )
    # tie rod: axial, from the steering arm to the rack end on the body
    outer = hub + p.tie_rod_offset
    rack = np.asarray(m.xyz(body[f"rack_{s}"]), float) * np.array([1.0, side, 1.0])  # left
    k_tie = _axial(p.tie_rod_stiffness, _unit(rack - outer))
    m.add_spring(
        spindle,
        body[f"rack_{s}"],
        _mirror6(k_tie, side),
        p.steel_loss,
        offset_a=_mirror3(p.tie_rod_offset, side),
    )


def _rear_axle(
    b: _Builder,
    p: ChassisParameters,
    origin: FloatArray,
    damper_offset: Vec3,
    damper: float,
    body: dict[str, str],
) -> None:
    """The thesis' rear corner on both sides of one subframe (see the module doc).

    ``origin`` is the subframe centre in vehicle axes (the corner's own origin).
    """
    m = b.m
    steel = Material(STEEL_E, STEEL_NU, STEEL_RHO, p.steel_loss)
    L, W = p.subframe_half
    h = p.element_length

    def at(xyz: Sequence[float], side: int) -> Vec3:
        return _mirror3(np.asarray(xyz, float), side)

    def pos(xyz: Sequence[float]) -> FloatArray:
        out: FloatArray = origin + np.asarray(xyz, float)
        return out

    def beam(a: str, c: str, sec: Section, n: int | None = None, prefix: str | None = None) -> None:
        pa, pc = m.xyz(a), m.xyz(c)
        m.add_beam(a, c, sec, steel, n or _n_el(pa, pc, h), (0, 0, 1), prefix=prefix)

    side_box, cross_box = Section.box(*p.side_box), Section.box(*p.cross_box)
    bracket_f = m.add_node("r.bracket_f", pos((L, 0.0, 0.0)))
    bracket_r = m.add_node("r.bracket_r", pos((-L, 0.0, 0.0)))
    corners: dict[int, tuple[str, str]] = {}
    for side in (1, -1):
        s = _side_name(side)
        front = m.add_node(f"bushing_r{s}", pos(at((L, W, 0.0), side)))
        back = m.add_node(f"r.sf_r{s}", pos(at((-L, W, 0.0), side)))
        root_f = m.add_node(f"r.root_f{s}", pos(at((p.arm_roots_x, W, 0.0), side)))
        root_r = m.add_node(f"r.root_r{s}", pos(at((-p.arm_roots_x, W, 0.0), side)))
        corners[side] = (front, back)
        for a, c in ((front, root_f), (root_f, root_r), (root_r, back)):
            beam(a, c, side_box)
        # carrier on the link bushing, A-arm to the side member
        spindle = m.add_node(f"spindle_r{s}", pos(at(p.spindle_xyz, side)))
        apex = m.add_node(f"r.apex_{s}", pos(at(p.arm_apex_xyz, side)))
        tube = Section.tube(*p.arm_tube)
        for root in (root_f, root_r):
            beam(apex, root, tube, p.arm_elements, prefix=f"r.arm_{root[2:]}.")
        m.add_mass(spindle, rigid_body_mass(p.carrier_mass, p.carrier_inertia))
        c, sn = np.cos(np.radians(p.link_pitch_deg)), np.sin(np.radians(p.link_pitch_deg))
        R = np.array([[c, 0.0, sn], [0.0, 1.0, 0.0], [-sn, 0.0, c]])
        k_link = oriented_stiffness(p.link_stiffness, R)  # the corner's link (left)
        centre = np.add(p.spindle_xyz, p.link_offset)
        m.add_spring(
            spindle,
            apex,
            _mirror6(k_link, side),
            p.link_loss,
            offset_a=at(p.link_offset, side),
            offset_b=at(centre - np.asarray(p.arm_apex_xyz), side),
        )
        # the subframe bushings go to the body instead of ground
        m.add_spring(front, body[f"sub_front_{s}"], p.bushing_stiffness, p.bushing_loss)
        m.add_spring(back, body[f"sub_rear_{s}"], p.bushing_stiffness, p.bushing_loss)
        # damper from the carrier to the rear tower
        lower = pos(p.spindle_xyz) + np.asarray(damper_offset)  # left
        tower = np.asarray(m.xyz(body[f"tower_r{s}"])) * np.array([1.0, side, 1.0])
        axis = _unit(tower - lower)
        b.dampers.append(
            Damper(
                f"damper_r{s}",
                spindle,
                body[f"tower_r{s}"],
                _mirror3(damper_offset, side),
                (0.0, 0.0, 0.0),
                _mirror3(axis, side),
                damper,
            )
        )
    (fl, bl), (fr, br) = corners[1], corners[-1]
    for a, c in ((fl, bracket_f), (fr, bracket_f), (bl, bracket_r), (br, bracket_r)):
        beam(a, c, cross_box)  # from each side's corner to the middle (mirror-symmetric mesh)
    for node in (bracket_f, bracket_r):
        m.add_mass(node, rigid_body_mass(p.bracket_mass, p.bracket_inertia))


def build_structure(
    body: BodyParameters,
    front: FrontParameters,
    rear: ChassisParameters,
    wheel_z: float,
    rear_damper_offset: Vec3,
    rear_damper: float,
) -> tuple[FEModel, tuple[Damper, ...]]:
    """The FE model of the whole car without tires, and its viscous dampers.

    Returns
    -------
    FEModel
        Hysteretic stiffness ``K (1 + j eta)`` and mass; free-free (the tires carry
        the car).
    tuple of Damper
        The four suspension dampers.
    """
    b = _Builder()
    names = _body(b, body)
    for side in (1, -1):
        _front(b, front, side, names)
    origin = np.array([-body.wheelbase, 0.0, wheel_z - rear.spindle_xyz[2]])
    _rear_axle(b, rear, origin, rear_damper_offset, rear_damper, names)
    return b.m, tuple(b.dampers)
