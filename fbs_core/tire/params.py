"""Parameters of the reference tire (a 205/60 R15 passenger-car tire).

Every value has a source or a derivation; see ``docs/tire-model.md``. The ring
values (R, rhoA, k_w, k_v, T_p, EI) reproduce the MF-Swift 205/60R15 default tire
data (rim-fixed belt frequencies 80 Hz longitudinal, 40 Hz lateral, 50 Hz yaw,
70 Hz wind-up; Schmeitz / TNO MF-Swift 6.1 data set, via
``../shared/design/reference-models.md`` section 2.2).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Any

import numpy as np

from ..errors import DataFormatError

__all__ = ["TireParameters", "FAMILIES", "DEFAULT_PARAMETERS"]

#: Belt mode families, in the order of :attr:`TireParameters.orders`:
#: ``ip`` in-plane inextensible ring (u, w = -du/dtheta); ``op`` out-of-plane
#: (lateral) ring v with plane cross-sections; ``w1`` cross-section tilt
#: (w linear across the width); ``w2`` ... ``w6`` width-wise bending families
#: (w ~ cos(m pi (y/b + 1/2)), the free-edge strip shapes), after Kropp (1989).
FAMILIES: tuple[str, ...] = ("ip", "op", "w1", "w2", "w3", "w4", "w5", "w6")

#: Parameters that may be negative (alignment angles in rad, conicity per unit load),
#: limited to |value| <= ANGLE_LIMIT (small-angle alignment of a road wheel).
SIGNED: tuple[str, ...] = ("camber", "toe", "mu_y0")
ANGLE_LIMIT = 0.2
#: On/off switches of physics (0 or 1).
SWITCHES: tuple[str, ...] = ("static_deflection", "patch_wave")


@dataclass(frozen=True)
class TireParameters:
    """Physical parameters of the reference rolling tire (SI units).

    Attributes
    ----------
    R : float
        Belt radius in m (also the rolling radius: ``Omega = v / R``).
    b : float
        Belt width in m.
    m_belt : float
        Belt (plus tread) mass in kg; ``rhoA = m_belt / (2 pi R)``.
    EI : float
        Circumferential bending stiffness of the belt in N m^2.
    EI_lat : float
        Lateral (in-surface) bending stiffness of the belt in N m^2; sets the
        circumferential membrane stiffness ``E_m = 12 EI_lat / b^3`` (N/m).
    D_y : float
        Bending stiffness across the width per unit length, N m.
    D_t : float
        Twisting stiffness of the belt per unit length, N m.
    T_p : float
        Hoop tension from inflation, ``p b R``, in N.
    n_y : float
        Membrane tension across the width, N/m (acts on the width-wise bending).
    k_w, k_v, k_lat : float
        Radial, tangential and lateral sidewall foundation stiffness per unit
        circumference, N/m^2, split equally over the two belt edges.
    m_rim, I_rim_p, I_rim_d : float
        Mass (kg), polar and diametral inertia (kg m^2) of the rigid rim with
        the beads and sidewalls lumped onto it.
    L_c, b_c : float
        Contact patch length and width in m.
    k_cx, k_cy, k_cz : float
        Total contact stiffness of the patch, longitudinal, lateral and
        vertical, N/m, spread uniformly over the patch.
    F_z0 : float
        Static wheel load in N (the contact pressure tilted by the road slope
        gives the longitudinal part of the patch load).
    zeta : float
        Modal damping ratio of the non-rotating tire.
    camber : float
        Camber angle of the wheel in rad (ISO 8855, the left rear wheel of the
        reference chassis: negative = top of the wheel inclined towards the
        vehicle). The wheel plane is rotated by ``-camber`` about the vehicle x
        axis: the road normal and the road wave are no longer in the wheel plane,
        the static contact pressure varies across the width, and the camber
        thrust varies with the wheel load (``camber_thrust``).
    toe : float
        Toe-in angle of the wheel in rad (positive: the front of the left wheel
        turned towards the vehicle). The wheel plane is rotated by ``-toe`` about
        the vehicle z axis; the slip angle it imposes gives a lateral force that
        varies with the wheel load (``cornering_load``).
    cornering_load : float
        Load sensitivity of the cornering stiffness, ``d K_ya / d F_z`` at
        ``F_z0``, per rad.
    camber_thrust : float
        Camber stiffness per unit load, ``K_yg / F_z``, per rad.
    C_kappa, C_alpha : float
        Longitudinal slip stiffness (N) and cornering stiffness (N/rad) at ``F_z0``.
        With the contact stiffness they set the relaxation lengths of the tread in
        the patch, ``sigma_x = C_kappa / k_cx``, ``sigma_y = C_alpha / k_cy``.
    v_low : float
        Speed in m/s below which the slip damping ``C / v`` is held at ``C / v_low``
        (Magic Formula's low-speed limit VXLOW), so that the tire standing still has
        finite matrices.
    slip_zones : int
        Number of zones along the patch whose tread slips as one (each zone adds a
        longitudinal and a lateral first-order slip state); 0: the tread sticks to the
        road (tangential contact springs to the ground).
    static_deflection : int
        1: the dynamics are linearised about the statically loaded tire
        (:mod:`.static`): the contact patch has the length the wheel load ``F_z0``
        flattens (replacing ``L_c``; the totals ``k_cx, k_cy, k_cz`` are spread over
        it), the static contact pressure has the distribution of that solution, and
        the hoop-force change of the static loads adds its geometric stiffness
        (coupling circumferential orders n and n +/- k). 0: the round belt with the
        patch length ``L_c`` and a uniform pressure.
    k_tread : float
        Compression stiffness of the tread per unit area, N/m^3 (``E / h`` of the tread
        rubber); only the static contact uses it (the patch length and pressure).
    patch_wave : int
        1: the road wave modulates the patch load point by point,
        ``h(x) = exp(j 2 pi x / lambda)``; 0: every point of the patch sees the wave
        at the patch centre (``h = 1``, the lumped load of a point contact), to
        measure what the modulation does.
    mu_y0 : float
        Conicity and ply-steer lateral force per unit load at zero slip and
        camber, ``F_y0 / F_z`` (vehicle y; its sign depends on the tire and its
        mounting side).
    orders : tuple of int
        Highest circumferential order kept in each family of :data:`FAMILIES`
        (-1 drops the family).
    """

    R: float = 0.30
    b: float = 0.16
    m_belt: float = 7.0
    EI: float = 5.0
    EI_lat: float = 250.0
    D_y: float = 1.0
    D_t: float = 6.0
    T_p: float = 10.6e3
    n_y: float = 1.5e4
    k_w: float = 1.19e6
    k_v: float = 6.84e5
    k_lat: float = 2.3e5
    m_rim: float = 10.0
    I_rim_p: float = 0.40
    I_rim_d: float = 0.25
    L_c: float = 0.15
    b_c: float = 0.13
    k_cx: float = 6.0e5
    k_cy: float = 2.0e5
    k_cz: float = 4.0e5
    F_z0: float = 4000.0
    zeta: float = 0.04
    # rear-wheel alignment: static camber -1.5 deg, toe-in 10' per wheel, the middle of
    # the usual passenger-car rear axle settings (camber -1 deg to -2 deg, toe-in 5' to
    # 15' per wheel: Reimpell, Betzler & Stoll, The Automotive Chassis, 2nd ed. 2001,
    # sec. 3.5-3.6; Heissing & Ersoy, Chassis Handbook, 2011, sec. 3.3)
    camber: float = float(np.deg2rad(-1.5))
    toe: float = float(np.deg2rad(10.0 / 60.0))
    # Magic Formula 205/60R15, F_z0 = 4000 N (Pacejka, Tire and Vehicle Dynamics, 2nd ed.
    # 2006, table A3.1: PKY1 = -14.95, PKY2 = 2.13): K_ya = PKY1 F_z0 sin(2 atan(F_z /
    # (PKY2 F_z0))) = 46 kN/rad, whose slope at F_z0 is 7.35 per rad
    cornering_load: float = 7.35
    # camber stiffness of a radial passenger-car tire ~ 0.1 K_ya ~ F_z per rad
    # (Pacejka 2006, sec. 3.2 and table A3.1; Gillespie, Fundamentals of Vehicle
    # Dynamics, 1992, ch. 10: camber stiffness about 1/10 of the cornering stiffness)
    camber_thrust: float = 1.0
    mu_y0: float = 0.0
    # Magic Formula 205/60R15 (Pacejka 2006, table A3.1, checked against two independent
    # transcriptions of the table): C_kappa = PKX1 F_z0 with PKX1 = 21.51 (was 21.69
    # here before, a misquote); C_alpha = K_ya(F_z0) = 14.95 F_z0 sin(2 atan(1 / 2.13))
    # = 46 kN/rad (PKY1 = -14.95, PKY2 = 2.130, PKY4 = 2).
    # Relaxation lengths of the tread: 86e3 / 6e5 = 0.143 m, 46e3 / 2e5 = 0.23 m, of the
    # order of the patch length, as in the brush model (Pacejka 2006, sec. 7.2)
    C_kappa: float = 86.04e3
    C_alpha: float = 46.0e3
    v_low: float = 1.0
    slip_zones: int = 2
    static_deflection: int = 1
    # tread rubber in compression: E ~ 5 MPa over ~10 mm tread and base rubber (passenger
    # tread compounds E = 3-8 MPa; Gent & Walter, The Pneumatic Tire, NHTSA 2006, ch. 7)
    k_tread: float = 5.0e8
    patch_wave: int = 1
    # the last family keeps orders up to 9 so that 198 DOFs with mass and 4 slip states
    # give 400 complex modes, as the thesis' model (orders up to 10 without slip)
    orders: tuple[int, ...] = (16, 6, 14, 14, 12, 11, 10, 9)

    def __post_init__(self) -> None:
        object.__setattr__(self, "orders", tuple(int(n) for n in self.orders))
        if float(self.slip_zones) != int(self.slip_zones) or not 0 <= self.slip_zones <= 8:
            raise DataFormatError(f"slip_zones must be an integer 0..8, got {self.slip_zones}")
        object.__setattr__(self, "slip_zones", int(self.slip_zones))
        for name in SWITCHES:
            v = getattr(self, name)
            if v not in (0, 1, True, False):
                raise DataFormatError(f"{name} must be 0 or 1, got {v!r}")
            object.__setattr__(self, name, int(v))
        if len(self.orders) != len(FAMILIES):
            raise DataFormatError(
                f"orders must give one entry per family {FAMILIES}, got {self.orders}"
            )
        for f in fields(self):
            if f.name in ("orders", "slip_zones", *SWITCHES):
                continue
            v = getattr(self, f.name)
            if f.name in SIGNED:
                if not np.isfinite(v) or abs(v) > ANGLE_LIMIT:
                    raise DataFormatError(
                        f"tire parameter {f.name} must be finite with |{f.name}| <= "
                        f"{ANGLE_LIMIT}, got {v}"
                    )
                continue
            if not np.isfinite(v) or v < 0:
                raise DataFormatError(f"tire parameter {f.name} must be finite and >= 0, got {v}")

    @property
    def rhoA(self) -> float:
        """Belt mass per unit circumference, kg/m."""
        return self.m_belt / (2 * np.pi * self.R)

    @property
    def n_belt(self) -> int:
        """Number of belt generalised coordinates."""
        return sum(2 * n + 1 for n in self.orders if n >= 0)

    @property
    def n_slip(self) -> int:
        """Number of first-order slip states (longitudinal and lateral per zone)."""
        return 2 * self.slip_zones

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["orders"] = list(self.orders)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TireParameters:
        known = {f.name for f in fields(cls)}
        unknown = set(d) - known
        if unknown:
            raise DataFormatError(
                f"unknown tire parameter(s) {sorted(unknown)}; known: {sorted(known)}"
            )
        kw: dict[str, Any] = {
            k: (
                tuple(int(x) for x in v)
                if k == "orders"
                else (int(v) if k in ("slip_zones", *SWITCHES) else float(v))
            )
            for k, v in d.items()
        }
        return cls(**kw)


DEFAULT_PARAMETERS = TireParameters()
