"""Named physical parameters of the reference models and their documented ranges.

The thesis' noise study scales FRF elements at random (eqs. 5.2-5.4); its section 7 asks
for the corridor of *systematic* errors: "simultaneous change of physical properties such
as mass and stiffness". Each :class:`Parameter` here is one physical property of the
reference tire (:class:`~fbs_core.tire.TireParameters`) or chassis
(:class:`~fbs_core.chassis.ChassisParameters`) with the range it plausibly takes between
tires, cars and production; its sources are in ``docs/corridor.md``. A value outside the
range is allowed if it is physical (a user's range); the range is what the study samples.

A parameter is applied to a base parameter set by :meth:`Parameter.apply`. At its nominal
value (the base's own) the base is returned unchanged, so the nominal variant *is* the
reference model, bit for bit.

===========================  =======  ======================================================
name                         unit     what it changes
===========================  =======  ======================================================
inflation_pressure           Pa       ``T_p = p b R`` and the lateral tension ``n_y`` (both
                                      proportional to p)
belt_bending_stiffness       N m^2    ``EI`` of the belt
sidewall_radial_stiffness    N/m^2    ``k_w``
sidewall_tangential_stiffn.  N/m^2    ``k_v``
tread_mass                   kg       ``m_belt`` (belt and tread)
tire_damping                 1        ``zeta``, the modal damping ratio
wheel_load                   N        ``F_z0`` (static deflection, patch, pre-stress)
body_bushing_stiffness       1        factor on the six stiffnesses of the four body bushings
body_bushing_loss            1        their loss factor
link_stiffness               1        factor on the six stiffnesses of the link bushing
link_loss                    1        its loss factor
knuckle_mass                 kg       ``carrier_mass`` (inertia scaled with it)
arm_mass                     kg       mass of the A-arm tubes (their density)
arm_stiffness                1        factor on the A-arm tubes' modulus
===========================  =======  ======================================================
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..chassis import ChassisParameters, ChassisVariantParameters
from ..errors import ParameterError
from ..tire.params import DEFAULT_PARAMETERS, TireParameters

__all__ = [
    "MODELS",
    "PARAMETERS",
    "Parameter",
    "ParameterError",
    "ParameterSpace",
    "apply_values",
    "parameter",
]

#: The two models a parameter can belong to.
MODELS = ("tire", "chassis")


def _tube_mass(p: ChassisParameters) -> float:
    """Mass of the two A-arm tubes (kg): density x tube area x the two lengths."""
    from ..chassis import STEEL_RHO

    d, t = p.arm_tube
    area = np.pi / 4 * (d**2 - (d - 2 * t) ** 2)
    apex = np.asarray(p.arm_apex_xyz, float)
    L, W = p.subframe_half
    length = sum(
        float(np.linalg.norm(apex - np.array([x, W, 0.0]))) for x in (p.arm_roots_x, -p.arm_roots_x)
    )
    return float(STEEL_RHO * area * length * getattr(p, "arm_mass_scale", 1.0))


def _variant(p: ChassisParameters) -> ChassisVariantParameters:
    if isinstance(p, ChassisVariantParameters):
        return p
    return ChassisVariantParameters(**dataclasses.asdict(p))


def _scaled(t: tuple[float, ...], s: float) -> tuple[float, ...]:
    return tuple(float(x) * s for x in t)


# name -> (model, getter, setter); a setter gets the base and the new value (never the
# nominal one: apply() returns the base itself then)
_Get = Callable[[Any], float]
_Set = Callable[[Any, float], Any]


def _tire_pressure_set(p: TireParameters, v: float) -> TireParameters:
    s = v / (p.T_p / (p.b * p.R))
    return dataclasses.replace(p, T_p=p.T_p * s, n_y=p.n_y * s)


def _knuckle_set(p: ChassisParameters, v: float) -> ChassisParameters:
    s = v / p.carrier_mass
    ix, iy, iz = (float(x) * s for x in p.carrier_inertia)
    return dataclasses.replace(p, carrier_mass=float(v), carrier_inertia=(ix, iy, iz))


def _arm_mass_set(p: ChassisParameters, v: float) -> ChassisParameters:
    q = _variant(p)
    return dataclasses.replace(q, arm_mass_scale=q.arm_mass_scale * v / _tube_mass(q))


def _field(name: str) -> tuple[_Get, _Set]:
    return (lambda p: float(getattr(p, name))), (
        lambda p, v: dataclasses.replace(p, **{name: float(v)})
    )


def _factor(name: str, scale_field: str | None = None) -> tuple[_Get, _Set]:
    """A factor on a tuple field (nominal 1 = the base); or on a variant's scale field."""
    if scale_field is not None:
        return (lambda p: float(getattr(p, scale_field, 1.0))), (
            lambda p, v: dataclasses.replace(_variant(p), **{scale_field: float(v)})  # type: ignore[arg-type]
        )
    return (lambda p: 1.0), (
        lambda p, v: dataclasses.replace(p, **{name: _scaled(getattr(p, name), float(v))})
    )


_MAPS: dict[str, tuple[str, _Get, _Set]] = {
    "inflation_pressure": ("tire", lambda p: float(p.T_p / (p.b * p.R)), _tire_pressure_set),
    "belt_bending_stiffness": ("tire", *_field("EI")),
    "sidewall_radial_stiffness": ("tire", *_field("k_w")),
    "sidewall_tangential_stiffness": ("tire", *_field("k_v")),
    "tread_mass": ("tire", *_field("m_belt")),
    "tire_damping": ("tire", *_field("zeta")),
    "wheel_load": ("tire", *_field("F_z0")),
    "body_bushing_stiffness": ("chassis", *_factor("bushing_stiffness")),
    "body_bushing_loss": ("chassis", *_field("bushing_loss")),
    "link_stiffness": ("chassis", *_factor("link_stiffness")),
    "link_loss": ("chassis", *_field("link_loss")),
    "knuckle_mass": ("chassis", lambda p: float(p.carrier_mass), _knuckle_set),
    "arm_mass": ("chassis", _tube_mass, _arm_mass_set),
    "arm_stiffness": ("chassis", *_factor("", "arm_stiffness_scale")),
}


@dataclass(frozen=True)
class Parameter:
    """One named physical parameter of a reference model and the range a study samples.

    Parameters
    ----------
    name : str
        One of :data:`PARAMETERS`.
    model : {"tire", "chassis", "custom"}
        The model it belongs to; ``"custom"``: a parameter of the caller's own model, which
        a design samples and :mod:`.sensitivity` ranks, but :meth:`apply` does not know.
    unit : str
        SI unit of its values (``"1"``: a ratio or a factor).
    low, high : float
        The range sampled (uniformly) by a study, ``low < high``.
    bounds : tuple of float
        Physical limits of any value: ``bounds[0] < value < bounds[1]`` (e.g. a loss factor
        in (0, 1)).
    description : str
        What it is and what it changes in the model.
    source : str
        Where the nominal value and the range come from (details in docs/corridor.md).
    """

    name: str
    model: str
    unit: str
    low: float
    high: float
    bounds: tuple[float, float]
    description: str
    source: str

    def __post_init__(self) -> None:
        if self.model not in (*MODELS, "custom"):
            raise ParameterError(
                f"unknown model {self.model!r} of parameter {self.name!r}; allowed: "
                f"{', '.join((*MODELS, 'custom'))}"
            )
        if self.model != "custom" and _MAPS.get(self.name, ("",))[0] != self.model:
            raise ParameterError(
                f"unknown {self.model} parameter {self.name!r}; known: "
                f"{', '.join(n for n, m in _MAPS.items() if m[0] == self.model)} (or model "
                "'custom' for a parameter of your own model: sampled, not applied)"
            )
        self.check(self.low)
        self.check(self.high)
        if not self.low < self.high:
            raise ParameterError(
                f"range of {self.name} must have low < high, got [{self.low:g}, {self.high:g}]"
            )

    def check(self, value: float) -> float:
        """The value as a float, or :class:`ParameterError` naming the allowed interval."""
        v = float(value)
        lo, hi = self.bounds
        if not (np.isfinite(v) and lo < v < hi):
            raise ParameterError(
                f"{self.name} = {value!r} {self.unit} is not physical; allowed: "
                f"{lo:g} < {self.name} < {hi:g}"
            )
        return v

    def with_range(self, low: float, high: float) -> Parameter:
        """The same parameter sampled over ``[low, high]`` (checked against its bounds)."""
        return dataclasses.replace(self, low=float(low), high=float(high))

    def _known(self) -> tuple[str, _Get, _Set]:
        if self.model == "custom":
            raise ParameterError(
                f"{self.name!r} is a custom parameter: the caller's model applies it"
            )
        return _MAPS[self.name]

    def nominal(self, base: Any = None) -> float:
        """The value in ``base`` (default: the reference model's parameters)."""
        return self._known()[1](_default(self.model) if base is None else base)

    def apply(self, base: Any, value: float) -> Any:
        """``base`` (TireParameters or ChassisParameters) with this parameter at ``value``.

        At the base's own value the base itself is returned (the nominal variant is the
        reference model, bit for bit).
        """
        v = self.check(value)
        if v == self.nominal(base):
            return base
        return self._known()[2](base, v)


def _default(model: str) -> Any:
    return DEFAULT_PARAMETERS if model == "tire" else ChassisParameters()


def _p(
    name: str, unit: str, low: float, high: float, bounds: tuple[float, float], d: str, s: str
) -> Parameter:
    return Parameter(name, _MAPS[name][0], unit, low, high, bounds, d, s)


_INF = float("inf")

#: Every named parameter with its default range (see docs/corridor.md for the sources).
PARAMETERS: dict[str, Parameter] = {
    p.name: p
    for p in (
        _p(
            "inflation_pressure",
            "Pa",
            180e3,
            260e3,
            (0.0, _INF),
            "inflation pressure p; sets the belt's hoop tension T_p = p b R and its lateral "
            "membrane tension n_y (both proportional to p); nominal 220.8 kPa",
            "nominal: MF-Swift 205/60R15 at 2.2 bar (Pacejka 2006, table A3.1); range: "
            "placard 2.0-2.6 bar, and under-inflation by 0.4 bar is common (NHTSA, Tire "
            "Pressure Special Study, 2001)",
        ),
        _p(
            "belt_bending_stiffness",
            "N m^2",
            1.0,
            10.0,
            (0.0, _INF),
            "circumferential bending stiffness EI of the belt",
            "ring models of passenger tires: 1-10 N m^2, 5 typical (reference-models.md 2.2; "
            "Gong 1993)",
        ),
        _p(
            "sidewall_radial_stiffness",
            "N/m^2",
            1.0e6,
            1.4e6,
            (0.0, _INF),
            "radial sidewall foundation stiffness k_w per unit circumference",
            "nominal from the 80 Hz rim-fixed translation (reference-models.md 2.2); table "
            "A3.1 of Pacejka 2006 gives 74 Hz (k -14 %); range -16 %..+18 %",
        ),
        _p(
            "sidewall_tangential_stiffness",
            "N/m^2",
            4.4e5,
            8.2e5,
            (0.0, _INF),
            "tangential sidewall foundation stiffness k_v per unit circumference",
            "nominal from the 70 Hz rim-fixed wind-up mode (reference-models.md 2.2); table "
            "A3.1 of Pacejka 2006 gives 56 Hz (k -36 %); range -36 %..+20 %",
        ),
        _p(
            "tread_mass",
            "kg",
            5.5,
            7.5,
            (0.0, _INF),
            "mass of belt and tread m_belt",
            "MF-Swift belt mass 7.0-7.1 kg (Pacejka 2006, table A3.1); a worn tread (8 -> "
            "1.6 mm) loses about 1.5 kg of rubber (0.30 m^2 x 6.4 mm x 1150 kg/m^3 x 0.7 "
            "land ratio), production +0.5 kg",
        ),
        _p(
            "tire_damping",
            "1",
            0.02,
            0.10,
            (0.0, 1.0),
            "modal damping ratio zeta of the non-rotating tire",
            "MF-Swift 0.04 (reference-models.md 2.2); table A3.1's belt damping may mean "
            "0.11-0.14 (docs/tire-model.md): 0.02-0.10",
        ),
        _p(
            "wheel_load",
            "N",
            3000.0,
            5000.0,
            (0.0, _INF),
            "static wheel load F_z0 (static deflection, patch length and pressure, pre-stress)",
            "FNOMIN 4000 N (Pacejka 2006, table A3.1); rear wheel of a mid-size car between "
            "driver only and fully laden, +-25 %",
        ),
        _p(
            "body_bushing_stiffness",
            "1",
            0.8,
            1.25,
            (0.0, _INF),
            "factor on the six stiffnesses of each of the four subframe-to-body bushings",
            "assumption: production tolerance and temperature/amplitude dependence of "
            "rubber mounts, +-20 % (factor 0.8-1.25)",
        ),
        _p(
            "body_bushing_loss",
            "1",
            0.10,
            0.20,
            (0.0, 1.0),
            "hysteretic loss factor of the body bushings",
            "rubber bushings 0.1-0.2 (reference-models.md 3)",
        ),
        _p(
            "link_stiffness",
            "1",
            0.8,
            1.25,
            (0.0, _INF),
            "factor on the six stiffnesses of the link bushing (links, spring and mounts)",
            "assumption, as the body bushings: +-20 %",
        ),
        _p(
            "link_loss",
            "1",
            0.05,
            0.20,
            (0.0, 1.0),
            "hysteretic loss factor of the link bushing",
            "rubber 0.1-0.2 (reference-models.md 3); down to 0.05 for the steel spring's share",
        ),
        _p(
            "knuckle_mass",
            "kg",
            15.0,
            21.0,
            (0.0, _INF),
            "mass of the wheel carrier (knuckle, bearing, brake); its inertia scales with it",
            "assumption: cast iron vs aluminium knuckle, brake size: +-3 kg about 18 kg "
            "(reference-models.md 3)",
        ),
        _p(
            "arm_mass",
            "kg",
            1.2,
            1.8,
            (0.0, _INF),
            "mass of the two A-arm tubes (their density; the stiffness unchanged); nominal "
            "1.52 kg (steel, 35 x 3 mm, 0.64 m)",
            "assumption: +-20 % (brackets, welds, paint, wall tolerance)",
        ),
        _p(
            "arm_stiffness",
            "1",
            0.8,
            1.2,
            (0.0, _INF),
            "factor on the A-arm tubes' Young's modulus (their axial, bending and torsional "
            "stiffness; the mass unchanged)",
            "assumption: +-20 % (wall thickness and section tolerances, welded joints)",
        ),
    )
}


def parameter(name: str) -> Parameter:
    """The named parameter with its default range.

    Raises
    ------
    ParameterError
        For an unknown name, listing the known ones.
    """
    if name not in PARAMETERS:
        raise ParameterError(f"unknown parameter {name!r}; known: {', '.join(PARAMETERS)}")
    return PARAMETERS[name]


@dataclass(frozen=True)
class ParameterSpace:
    """The parameters a study varies, in order (the columns of its design).

    Parameters
    ----------
    parameters : tuple of Parameter
        Distinct names.
    """

    parameters: tuple[Parameter, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "parameters", tuple(self.parameters))
        names = [p.name for p in self.parameters]
        if not names:
            raise ParameterError("a parameter space needs at least one parameter")
        if len(set(names)) != len(names):
            raise ParameterError(f"parameters must be distinct, got {names}")

    @classmethod
    def from_names(
        cls,
        names: Iterable[str],
        ranges: Mapping[str, Sequence[float]] | None = None,
    ) -> ParameterSpace:
        """A space of named parameters with their default ranges, or the ``ranges`` given.

        Parameters
        ----------
        names : iterable of str
            Names from :data:`PARAMETERS`.
        ranges : mapping of str to (low, high), optional
            Ranges replacing the defaults (names must be in ``names``).

        Raises
        ------
        ParameterError
            For unknown names, ranges of parameters not listed, or bad ranges.
        """
        names = list(names)
        ranges = dict(ranges or {})
        extra = sorted(set(ranges) - set(names))
        if extra:
            raise ParameterError(f"ranges given for parameters not varied: {extra}")
        out = []
        for n in names:
            p = parameter(n)
            if n in ranges:
                r = tuple(ranges[n])
                if len(r) != 2:
                    raise ParameterError(f"range of {n} must be [low, high], got {list(r)}")
                p = p.with_range(*r)
            out.append(p)
        return cls(tuple(out))

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    @property
    def low(self) -> np.ndarray:
        return np.array([p.low for p in self.parameters])

    @property
    def high(self) -> np.ndarray:
        return np.array([p.high for p in self.parameters])

    def __len__(self) -> int:
        return len(self.parameters)

    def scale(self, unit: np.ndarray) -> np.ndarray:
        """Values ``low + u (high - low)`` of points ``u`` of the unit cube, shape (n, k)."""
        u = np.asarray(unit, float)
        out: np.ndarray = self.low + u * (self.high - self.low)
        return out

    def nominal(
        self, tire: TireParameters = DEFAULT_PARAMETERS, chassis: ChassisParameters | None = None
    ) -> dict[str, float]:
        """The values of the base models (default the reference ones)."""
        ch = ChassisParameters() if chassis is None else chassis
        return {p.name: p.nominal(tire if p.model == "tire" else ch) for p in self.parameters}

    def to_dict(self) -> list[dict[str, Any]]:
        """The parameters as plain rows (name, model, unit, low, high) for storage."""
        return [
            {"name": p.name, "model": p.model, "unit": p.unit, "low": p.low, "high": p.high}
            for p in self.parameters
        ]


def apply_values(
    values: Mapping[str, float],
    tire: TireParameters = DEFAULT_PARAMETERS,
    chassis: ChassisParameters | None = None,
) -> tuple[TireParameters, ChassisParameters]:
    """The tire and chassis parameters of a variant: the bases with ``values`` applied.

    Parameters
    ----------
    values : mapping of str to float
        Parameter name -> value (names of :data:`PARAMETERS`, in any order).
    tire, chassis : optional
        The bases (default the reference models).

    Returns
    -------
    (TireParameters, ChassisParameters)
        Unchanged bases where every value is nominal.

    Raises
    ------
    ParameterError
        For unknown names or unphysical values.
    """
    t: Any = tire
    c: Any = ChassisParameters() if chassis is None else chassis
    for name, v in values.items():
        p = parameter(name)
        if p.model == "tire":
            t = p.apply(t, v)
        else:
            c = p.apply(c, v)
    return t, c
