"""Physical units of FRF entries: what each output and input is, and the unit that follows.

An FRF entry ``Y[f, o, i]`` is the motion of output ``o`` per unit excitation of input
``i`` (thesis table 2.1). Its unit follows from three things:

* the **output kind**: ``"translation"`` (m), ``"rotation"`` (rad) or ``"generalised"``
  (dimensionless);
* the **input kind**: ``"force"`` (N), ``"moment"`` (N m), ``"road"`` (m of road
  displacement amplitude, the input ``patch`` of the tire) or ``"generalised"``;
* the **quantity**: receptance (motion), mobility (motion per second) or accelerance
  (motion per second squared).

Kinds come from the DOF direction (``x y z`` translation / force, ``rx ry rz`` rotation /
moment, :mod:`fbs_core.dofs`); generalised DOFs (labels without a direction) are
``"generalised"`` unless named in :data:`DEFAULT_KINDS` (``patch`` is a road input) or
overridden per FRF (``FRF(..., kinds={"patch": "road"})``).

This module is the one source of the unit strings: every exporter (CSV, UFF 58
records 8-10, MATLAB, HDF5) and every plot label takes them from :func:`frf_unit`,
:func:`response_unit` and :func:`excitation_unit`. :func:`parse_units` reads labels
written by other programs (``"mm/s/kN"``, ``"(1/N)*(m/s²)"``, ``"g/lbf"``,
``"deg/(N m)"``) into a :class:`Units`, whose :meth:`Units.factor` converts an entry
of any kind to SI.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from .dofs import parse_label
from .errors import QuantityError
from .vocabulary import ROTATIONS

__all__ = [
    "OUTPUT_KINDS",
    "INPUT_KINDS",
    "DEFAULT_KINDS",
    "QUANTITY_POWER",
    "output_kind",
    "input_kind",
    "response_unit",
    "excitation_unit",
    "frf_unit",
    "Units",
    "parse_units",
    "STANDARD_GRAVITY",
]

#: Output kinds and the SI unit of their displacement.
OUTPUT_KINDS: dict[str, str] = {"translation": "m", "rotation": "rad", "generalised": "1"}
#: Input kinds and their SI unit (``road``: metre of road displacement amplitude).
INPUT_KINDS: dict[str, str] = {"force": "N", "moment": "N m", "road": "m", "generalised": "1"}
#: Kinds of generalised DOFs known to the library (by label).
DEFAULT_KINDS: dict[str, str] = {"patch": "road"}
#: Power of ``j omega`` of each quantity (thesis table 2.1).
QUANTITY_POWER: dict[str, int] = {"receptance": 0, "mobility": 1, "accelerance": 2}
#: Standard gravity in m/s^2 (the unit ``g`` of accelerometers), exact by definition.
STANDARD_GRAVITY = 9.80665


def output_kind(label: str, kinds: Mapping[str, str] | None = None) -> str:
    """Kind of an output DOF: ``translation``, ``rotation`` or ``generalised``.

    Examples
    --------
    >>> output_kind("hub:rz"), output_kind("bushing:x"), output_kind("patch")
    ('rotation', 'translation', 'generalised')
    """
    k = (kinds or {}).get(label)
    if k in OUTPUT_KINDS:
        return k
    d = parse_label(label)[1]
    if d is None:
        k = DEFAULT_KINDS.get(label)
        return k if k in OUTPUT_KINDS else "generalised"
    return "rotation" if d in ROTATIONS else "translation"


def input_kind(label: str, kinds: Mapping[str, str] | None = None) -> str:
    """Kind of an input DOF: ``force``, ``moment``, ``road`` or ``generalised``.

    Examples
    --------
    >>> input_kind("spindle:ry"), input_kind("spindle:z"), input_kind("patch")
    ('moment', 'force', 'road')
    """
    k = (kinds or {}).get(label)
    if k in INPUT_KINDS:
        return k
    d = parse_label(label)[1]
    if d is None:
        k = DEFAULT_KINDS.get(label)
        return k if k in INPUT_KINDS else "generalised"
    return "moment" if d in ROTATIONS else "force"


def _power(quantity: str) -> int:
    if quantity not in QUANTITY_POWER:
        raise QuantityError(f"unknown quantity {quantity!r}; allowed: {', '.join(QUANTITY_POWER)}")
    return QUANTITY_POWER[quantity]


def response_unit(kind: str, quantity: str) -> str:
    """SI unit of the response: ``m``, ``m/s``, ``m/s^2``, ``rad/s``, ``1/s`` ...

    Examples
    --------
    >>> response_unit("rotation", "mobility")
    'rad/s'
    """
    if kind not in OUTPUT_KINDS:
        raise QuantityError(f"unknown output kind {kind!r}; allowed: {', '.join(OUTPUT_KINDS)}")
    base, p = OUTPUT_KINDS[kind], _power(quantity)
    return base if p == 0 else f"{base}/s" if p == 1 else f"{base}/s^{p}"


def excitation_unit(kind: str) -> str:
    """SI unit of an input: ``N``, ``N m``, ``m`` (road) or ``1``."""
    if kind not in INPUT_KINDS:
        raise QuantityError(f"unknown input kind {kind!r}; allowed: {', '.join(INPUT_KINDS)}")
    return INPUT_KINDS[kind]


def frf_unit(out_kind: str, in_kind: str, quantity: str) -> str:
    """SI unit of an FRF entry, e.g. ``m/(N s)``, ``rad/(N m s)``, ``(m/s)/m``.

    Examples
    --------
    >>> frf_unit("translation", "force", "mobility")
    'm/(N s)'
    >>> frf_unit("rotation", "moment", "receptance")
    'rad/(N m)'
    >>> frf_unit("translation", "road", "mobility"), frf_unit("rotation", "road", "mobility")
    ('(m/s)/m', '(rad/s)/m')
    """
    resp = response_unit(out_kind, quantity)
    exc = excitation_unit(in_kind)
    p = _power(quantity)
    if in_kind == "generalised":
        return resp
    if in_kind == "road":
        return f"{resp}/m" if p == 0 else f"({resp})/m"
    base = OUTPUT_KINDS[out_kind]
    den = exc + ("" if p == 0 else " s" if p == 1 else f" s^{p}")
    return f"{base}/({den})" if " " in den else f"{base}/{den}"


# -- reading unit labels ---------------------------------------------------------------
# unit name -> (dimension, SI value of one unit); dimensions L length, F force, T time,
# A angle; "g" and "kg" are compound and handled apart
_UNITS_EXACT: dict[str, tuple[str, float]] = {
    "m": ("L", 1.0),
    "mm": ("L", 1e-3),
    "cm": ("L", 1e-2),
    "um": ("L", 1e-6),
    "in": ("L", 0.0254),
    "inch": ("L", 0.0254),
    "ft": ("L", 0.3048),
    "N": ("F", 1.0),
    "kN": ("F", 1e3),
    "mN": ("F", 1e-3),
    "lbf": ("F", 4.4482216152605),
    "s": ("T", 1.0),
    "sec": ("T", 1.0),
    "ms": ("T", 1e-3),
    "min": ("T", 60.0),
    "rad": ("A", 1.0),
    "mrad": ("A", 1e-3),
    "deg": ("A", math.pi / 180),
    "degree": ("A", math.pi / 180),
    "degrees": ("A", math.pi / 180),
}
# case-insensitive fallbacks (never "mn": milli- or mega-newton?)
_UNITS_LOWER = {
    k.lower(): v
    for k, v in _UNITS_EXACT.items()
    if k.lower() not in ("mn",) and k not in ("ms", "min")
}
_UNITS_LOWER.update({"ms": ("T", 1e-3)})

_SUPERSCRIPTS = str.maketrans(
    {
        "²": "^2",
        "³": "^3",
        "¹": "^1",
        "⁴": "^4",
        "⁻": "-",
        "·": " ",
        "⋅": " ",
        "×": " ",
        "*": " ",
        "µ": "u",
        "μ": "u",
        "°": "deg",
        "[": "(",
        "]": ")",
        "{": "(",
        "}": ")",
    }
)


@dataclass(frozen=True)
class Units:
    """A unit label read from a file and what it means in SI.

    Attributes
    ----------
    label : str
        The label as written.
    quantity : str or None
        ``receptance`` / ``mobility`` / ``accelerance`` when the label is that of an FRF.
    length : float
        Metres per length unit of the response (``mm`` -> 1e-3).
    force : float
        Newtons per force unit (``kN`` -> 1e3, ``lbf`` -> 4.448...).
    g : bool
        The response is in ``g`` (standard gravity, 9.80665 m/s^2).
    time, angle : float
        Seconds per time unit, radians per angle unit (``deg`` -> pi/180).
    road : float
        Metres per length unit of the excitation (road displacement, moment arm);
        the response's length unit when the label has none there.
    kinds : (str, str) or None
        Output and input kind the label describes (``("translation", "force")``).
    """

    label: str
    quantity: str | None
    length: float = 1.0
    force: float = 1.0
    g: bool = False
    time: float = 1.0
    angle: float = 1.0
    road: float | None = None
    kinds: tuple[str, str] | None = None

    @property
    def is_si(self) -> bool:
        """True when no entry of any kind needs converting."""
        return (
            self.length == 1.0
            and self.force == 1.0
            and not self.g
            and self.time == 1.0
            and self.angle == 1.0
            and self.road in (None, 1.0)
        )

    def factor(self, out_kind: str, in_kind: str, quantity: str | None = None) -> float:
        """SI value of one file unit of an entry of the given kinds.

        The response scales with the length (or ``g``) or angle unit over the time unit
        to the power of the quantity; the input with the force unit, force x length
        (moment), or length (road).
        """
        q = quantity or self.quantity
        p = QUANTITY_POWER.get(q, 0) if q else 0
        tp = self.time ** (-p)
        if out_kind == "translation":
            out = STANDARD_GRAVITY if self.g and p == 2 else self.length * tp
        elif out_kind == "rotation":
            out = self.angle * tp
        else:
            out = tp
        arm = self.length if self.road is None else self.road
        inn = {"force": self.force, "moment": self.force * arm, "road": arm}.get(in_kind, 1.0)
        return out / inn

    def summary(self) -> str:
        """The unit system in words, e.g. ``mm, kN, s, rad`` (for import summaries)."""
        names = []
        for value, table, dim in (
            (self.length, _UNITS_EXACT, "L"),
            (self.force, _UNITS_EXACT, "F"),
            (self.time, _UNITS_EXACT, "T"),
            (self.angle, _UNITS_EXACT, "A"),
        ):
            name = next((k for k, (d, v) in table.items() if d == dim and v == value), None)
            names.append(name or f"{value:g} SI")
        if self.g:
            names[0] = "g"
        return ", ".join(names)


def _tokens(s: str) -> list[str] | None:
    toks = re.findall(r"\(|\)|/|[A-Za-z]+(?:\^?-?\d+)?|\d+(?:\^?-?\d+)?", s)
    if "".join(toks).replace(" ", "") != re.sub(r"\s", "", s):
        return None
    return toks


def parse_units(label: str | None) -> Units | None:
    """Read an FRF or response unit label such as ``"m/(N s)"``, ``"mm/s/kN"``, ``"g/lbf"``.

    Accepts exponents as ``s^2``, ``s2``, ``s**2``, ``s²``, ``s^-1``; products with
    spaces, ``*``, ``·``; ``/`` divides the next factor or parenthesised group; ``1``
    as a factor (``(1/N)*(m/s²)``). Units: m mm cm um in ft; N kN mN lbf; s ms min;
    rad mrad deg; g (standard gravity); kg (N s^2/m).

    Returns
    -------
    Units or None
        None for an empty label, ``NONE``, or a label that is not understood (the
        caller quotes it in its message).

    Raises
    ------
    QuantityError
        For units of an inverse FRF (force per motion: dynamic stiffness, impedance,
        apparent mass), so that they are not mistaken for an FRF.

    Examples
    --------
    >>> u = parse_units("mm/s/kN")
    >>> u.quantity, u.length, u.force
    ('mobility', 0.001, 1000.0)
    """
    if label is None:
        return None
    raw = str(label).strip()
    if not raw or raw.upper() == "NONE":
        return None
    s = raw.replace("**", "^").translate(_SUPERSCRIPTS)
    toks = _tokens(s)
    if toks is None:
        return None
    dims = {"L": 0, "F": 0, "T": 0, "A": 0}
    first: dict[str, float] = {}
    road: list[float] = []
    g = [False]

    def factor(tok: str, power: int) -> bool:
        m = re.fullmatch(r"([A-Za-z]+|\d+)\^?(-?\d{0,2})", tok)
        if m is None or m.group(2) == "-":
            return False
        name, e = m.group(1), int(m.group(2) or 1)
        if abs(e) > 4:
            return False
        p = power * e
        if name.isdigit():
            return name == "1"
        if name == "g":
            dims["L"] += p
            dims["T"] -= 2 * p
            g[0] = True
            return True
        if name.lower() == "kg":
            dims["F"] += p
            dims["T"] += 2 * p
            dims["L"] -= p
            return True
        unit = _UNITS_EXACT.get(name) or _UNITS_LOWER.get(name.lower())
        if unit is None:
            return False
        dim, value = unit
        dims[dim] += p
        if dim == "L" and p < 0:
            road.append(value)
        else:
            first.setdefault(dim, value)
        return True

    def group(i: int, power: int) -> int | None:
        sign = 1
        while i < len(toks):
            t = toks[i]
            if t == ")":
                return i
            if t == "/":
                sign = -1
                i += 1
                continue
            if t == "(":
                j = group(i + 1, power * sign)
                if j is None or j >= len(toks):
                    return None
                i = j + 1
            elif not factor(t, power * sign):
                return None
            else:
                i += 1
            sign = 1
        return i

    end = group(0, 1)
    if end is None or end != len(toks):
        return None
    L, F, T, A = dims["L"], dims["F"], dims["T"], dims["A"]
    if F > 0:
        kind = {0: "dynamic stiffness", -1: "impedance", -2: "apparent mass"}.get(-T, "inverse")
        raise QuantityError(
            f"units {raw!r} are those of a {kind} (force per motion), not of an FRF; "
            "invert the data to receptance, mobility or accelerance first"
        )
    kinds = {
        (0, 1, -1): ("translation", "force"),
        (1, 0, -1): ("rotation", "force"),
        (0, 0, -1): ("translation", "moment"),
        (1, -1, -1): ("rotation", "moment"),
        (0, -1, -1): ("rotation", "moment"),  # rad left out: 1/(N m s)
        (0, 0, 0): ("translation", "road"),
        (1, -1, 0): ("rotation", "road"),
        (0, 1, 0): ("translation", "generalised"),
        (1, 0, 0): ("rotation", "generalised"),
    }.get((A, L, F))
    quantity = {0: "receptance", 1: "mobility", 2: "accelerance"}.get(-T) if kinds else None
    if quantity is None:
        kinds = None
    length = first.get("L", road[0] if road else 1.0)
    force = first.get("F", 1.0)
    return Units(
        raw,
        quantity,
        length=length,
        force=force,
        g=g[0],
        time=first.get("T", 1.0),
        angle=first.get("A", 1.0),
        road=road[0] if road else None,
        kinds=kinds,
    )


def kinds_of(
    outputs: Sequence[str], inputs: Sequence[str], kinds: Mapping[str, str] | None = None
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Output and input kinds of label lists (see :func:`output_kind`, :func:`input_kind`)."""
    return (
        tuple(output_kind(o, kinds) for o in outputs),
        tuple(input_kind(i, kinds) for i in inputs),
    )
