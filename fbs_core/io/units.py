"""Units and quantities of FRF data: units labels, SI factors, declared quantities.

An FRF is a receptance (m/N), mobility (m/(N s)) or accelerance (m/(N s^2)),
thesis table 2.1; each step multiplies by ``j omega``. This module reads units
labels, turns file units into SI entry by entry, decides the quantity from what
a file declares, what its units imply and what the caller asks, and checks the
declaration against the low-frequency slope of the data.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..dofs import parse_label
from ..errors import FrequencyGridError, QuantityError
from ..frf import FRF, QUANTITIES

__all__ = [
    "Units",
    "parse_units",
    "si_factors",
    "check_quantity_arg",
    "reconcile_quantity",
    "frequency_from_units",
    "low_frequency_slope",
    "quantity_notes",
]

_LENGTH = {
    "m": 1.0,
    "mm": 1e-3,
    "cm": 1e-2,
    "um": 1e-6,
    "µm": 1e-6,
    "μm": 1e-6,
    "in": 0.0254,
    "ft": 0.3048,
}
_FORCE = {"n": 1.0, "kn": 1e3, "lbf": 4.4482216152605}
_G = 9.80665


@dataclass(frozen=True)
class Units:
    """An FRF units label and what it means in SI.

    ``quantity`` is None when the label does not identify one; the scales turn
    file units into SI (a length of 1 file unit is ``length`` m, and so on).
    """

    label: str
    quantity: str | None
    length: float = 1.0
    force: float = 1.0
    g: bool = False

    @property
    def is_si(self) -> bool:
        return self.length == 1.0 and self.force == 1.0 and not self.g


def parse_units(label: str | None) -> Units | None:
    """Read an FRF units label such as ``"m/(N s)"``, ``"mm/s/N"`` or ``"g/N"``.

    Exponents as ``s^2``, ``s2`` or ``s**2``; ``/`` divides the next factor or
    parenthesised group. Returns None for an empty label or one that is not
    understood (the caller reports it as unchecked).

    Raises
    ------
    QuantityError
        For units that are an inverse FRF (dynamic stiffness, impedance, apparent
        mass), so that they are not mistaken for an FRF.
    """
    if label is None or not str(label).strip() or str(label).strip().upper() == "NONE":
        return None
    s = str(label).strip().replace("**", "^").replace("·", " ").replace("*", " ")
    tokens = re.findall(r"\(|\)|/|[A-Za-zµμ]+\^?-?\d*", s)
    if "".join(tokens).replace(" ", "") != re.sub(r"[\s.]", "", s):
        return None
    dims = {"L": 0, "T": 0, "F": 0}
    scale = {"L": 1.0, "F": 1.0}
    g = [False]

    def factor(tok: str, power: int) -> bool:
        m = re.fullmatch(r"([A-Za-zµμ]+)\^?(-?\d{0,2})", tok)
        if m is None or m.group(2) == "-":
            return False
        name, e = m.group(1), int(m.group(2) or 1)
        if abs(e) > 4:
            return False
        p = power * e
        low = name.lower()
        if name in _LENGTH or low in ("m", "mm", "cm", "um"):
            dims["L"] += p
            scale["L"] *= _LENGTH.get(name, _LENGTH.get(low, 1.0)) ** p
        elif low in ("s", "sec"):
            dims["T"] += p
        elif low in _FORCE:
            dims["F"] += p
            scale["F"] *= _FORCE[low] ** p
        elif low == "kg":  # N s^2 / m
            dims["F"] += p
            dims["T"] += 2 * p
            dims["L"] -= p
        elif name == "g":
            dims["L"] += p
            dims["T"] -= 2 * p
            g[0] = True
        elif low == "rad":
            pass
        else:
            return False
        return True

    def group(i: int, power: int) -> int | None:
        sign = 1
        while i < len(tokens):
            t = tokens[i]
            if t == ")":
                return i
            if t == "/":
                sign = -1
                i += 1
                continue
            if t == "(":
                j = group(i + 1, power * sign)
                if j is None or j >= len(tokens):
                    return None
                i = j + 1
            elif not factor(t, power * sign):
                return None
            else:
                i += 1
            sign = 1
        return i

    end = group(0, 1)
    if end is None or end != len(tokens):
        return None
    L, T, F = dims["L"], dims["T"], dims["F"]
    if (L, F) == (-1, 1) or (L, F) == (0, 1):
        kind = {0: "dynamic stiffness", -1: "impedance", -2: "apparent mass"}.get(-T, "inverse")
        raise QuantityError(
            f"units {label!r} are those of a {kind} (force per motion), not of an FRF; "
            "invert the data to receptance, mobility or accelerance first"
        )
    quantity = None
    if L == 1 and F == -1:
        quantity = {0: "receptance", -1: "mobility", -2: "accelerance"}.get(T)
    length = scale["L"] if L == 1 else 1.0
    force = 1.0 / scale["F"] if F == -1 else 1.0
    return Units(str(label).strip(), quantity, length, force, g[0])


def si_factors(units: Units, outputs: Sequence[str], inputs: Sequence[str]) -> np.ndarray:
    """Factors ``(n_out, n_in)`` turning each entry from file units into SI.

    A translational output scales with the length unit (and ``g``), a moment input
    with force x length, a force input with the force unit; rotations in rad do not
    scale.
    """
    t_out = np.array([parse_label(o)[1] in ("x", "y", "z") for o in outputs], dtype=float)
    r_in = np.array([parse_label(i)[1] in ("rx", "ry", "rz") for i in inputs], dtype=float)
    length = units.length * (_G if units.g else 1.0)
    out = length**t_out
    inn = (1.0 / units.force) * (units.length**r_in)
    return out[:, None] / inn[None, :]


def low_frequency_slope(frf: FRF) -> float | None:
    """Median log-log slope of the driving-point magnitudes over the lowest lines.

    A grounded structure's receptance is flat (slope 0), its mobility rises with
    slope +1 and its accelerance with +2 (thesis table 2.1: each step multiplies by
    ``j omega``); a free-free one has slopes -2, -1, 0. Uses the lines up to twice
    the lowest positive frequency (at least 3). None when there are no driving
    points or too few lines.
    """
    pts = [(frf.outputs.index(d), frf.inputs.index(d)) for d in frf.inputs if d in frf.outputs]
    pos = np.flatnonzero(frf.freq > 0)
    if not pts or pos.size < 3:
        return None
    f = frf.freq[pos]
    n = max(3, int(np.searchsorted(f, 2 * f[0], side="right")))
    n = min(n, f.size)
    slopes = []
    for o, i in pts:
        m = np.abs(frf.data[pos[:n], o, i])
        if np.all(m > 0):
            slopes.append(np.polyfit(np.log(f[:n]), np.log(m), 1)[0])
    return float(np.median(slopes)) if slopes else None


def quantity_notes(frf: FRF) -> list[str]:
    """Plausibility notes on the declared quantity from the low-frequency slope."""
    s = low_frequency_slope(frf)
    if s is None:
        return []
    p = QUANTITIES[frf.quantity]
    expected = (p, p - 2)
    if min(abs(s - e) for e in expected) <= 0.5:
        return []
    fits = [q for q, pq in QUANTITIES.items() if min(abs(s - pq), abs(s - pq + 2)) <= 0.5]
    hint = f"; it fits a {' or '.join(fits)}" if fits else ""
    return [
        f"check the quantity: the driving points rise with slope {s:+.1f} per decade at "
        f"the lowest lines, while a {frf.quantity} has {expected[0]:+d} (grounded) or "
        f"{expected[1]:+d} (free){hint}"
    ]


def check_quantity_arg(quantity: str | None) -> str | None:
    """Validate a user-given quantity (None passes)."""
    if quantity is not None and quantity not in QUANTITIES:
        raise QuantityError(f"unknown quantity {quantity!r}; allowed: {', '.join(QUANTITIES)}")
    return quantity


def reconcile_quantity(
    declared: str | None, units: Units | None, given: str | None, where: str
) -> str:
    """Decide the quantity from the file's declaration, its units and the caller.

    Raises
    ------
    QuantityError
        When two of them disagree, or none says what the data are.
    """
    check_quantity_arg(given)
    from_units = units.quantity if units is not None else None
    if declared and from_units and declared != from_units:
        raise QuantityError(
            f"{where} declares a {declared} but its units {units.label!r} are those of a "
            f"{from_units}"
        )
    q = declared or from_units
    if given and q and given != q:
        raise QuantityError(
            f"{where} holds a {q}, but quantity={given!r} was requested; convert after "
            f"loading with FRF.to({given!r}) instead"
        )
    q = q or given
    if q is None:
        raise QuantityError(
            f"{where} does not say whether it holds receptance, mobility or accelerance; "
            "pass quantity=..."
        )
    return q


def frequency_from_units(freq: np.ndarray, unit: str | None, where: str) -> np.ndarray:
    """Convert an abscissa in Hz, rad/s, kHz or cpm to Hz (anything else raises)."""
    u = (unit or "Hz").strip().lower().replace(" ", "")
    factors = {
        "hz": 1.0,
        "hertz": 1.0,
        "1/s": 1.0,
        "khz": 1e3,
        "rad/s": 1 / (2 * np.pi),
        "cpm": 1 / 60.0,
        "none": 1.0,
        "": 1.0,
    }
    if u not in factors:
        raise FrequencyGridError(
            f"{where}: unknown frequency unit {unit!r}; allowed: Hz, kHz, rad/s, cpm"
        )
    return np.asarray(freq, dtype=float) * factors[u]
