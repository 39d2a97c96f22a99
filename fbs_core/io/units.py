"""Units and quantities of FRF data: units labels, SI factors, declared quantities.

An FRF is a receptance (m/N), mobility (m/(N s)) or accelerance (m/(N s^2)),
thesis table 2.1; each step multiplies by ``j omega``. This module reads units
labels, turns file units into SI entry by entry, decides the quantity from what
a file declares, what its units imply and what the caller asks, and checks the
declaration against the low-frequency slope of the data.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import FrequencyGridError, QuantityError
from ..frf import FRF, QUANTITIES
from ..units import Units, kinds_of, parse_units

__all__ = [
    "Units",
    "parse_units",
    "si_factors",
    "check_quantity_arg",
    "reconcile_quantity",
    "frequency_from_units",
    "low_frequency_slope",
    "quantity_notes",
    "kinds_text",
    "parse_kinds",
    "units_line",
    "units_note",
]


def units_line(frf: FRF) -> str:
    """The single ``units`` label a file stores for an FRF: the SI unit of its first
    entry (``m/(N s)`` for a translation per force). Readers derive the unit system
    and the quantity from it and convert every entry by its kind."""
    return str(frf.units[0, 0])


def units_note(units: Units | None) -> list[str]:
    """Import note saying how the file's units label was understood."""
    if units is None:
        return []
    what = f"{units.quantity}, " if units.quantity else ""
    conv = "SI, no conversion" if units.is_si else "converted to SI"
    return [f"units {units.label!r} read as {what}{units.summary()} ({conv})"]


def kinds_text(kinds: Mapping[str, str]) -> str:
    """``"patch=road; q1=generalised"``: kind overrides as text for file headers."""
    return "; ".join(f"{k}={v}" for k, v in kinds.items())


def parse_kinds(text: object, where: str) -> dict[str, str] | None:
    """Inverse of :func:`kinds_text` (None for an empty text)."""
    from ..units import INPUT_KINDS, OUTPUT_KINDS

    if not isinstance(text, str) or not text.strip():
        return None
    out = {}
    for part in text.split(";"):
        if not part.strip():
            continue
        lab, sep, k = part.partition("=")
        if not sep or k.strip() not in {*OUTPUT_KINDS, *INPUT_KINDS}:
            raise QuantityError(
                f"{where}: kinds entry {part.strip()!r} is not label=kind with kind one of "
                f"{', '.join(dict.fromkeys([*OUTPUT_KINDS, *INPUT_KINDS]))}"
            )
        out[lab.strip()] = k.strip()
    return out or None


def si_factors(
    units: Units,
    outputs: Sequence[str],
    inputs: Sequence[str],
    kinds: Mapping[str, str] | None = None,
    quantity: str | None = None,
) -> np.ndarray:
    """Factors ``(n_out, n_in)`` turning each entry from file units into SI.

    Each entry is converted by what it is (:func:`fbs_core.units.output_kind`,
    :func:`~fbs_core.units.input_kind`): a translation scales with the length unit
    (or ``g``), a rotation with the angle unit, both over the time unit to the power
    of the quantity; a force input with the force unit, a moment with force x length,
    a road input with the length unit (:meth:`fbs_core.units.Units.factor`).
    """
    outs, ins = kinds_of(outputs, inputs, kinds)
    return np.array([[units.factor(o, i, quantity) for i in ins] for o in outs], dtype=float)


def low_frequency_slope(frf: FRF) -> float | None:
    """Median log-log slope of the driving-point magnitudes over the lowest lines.

    A grounded structure's receptance is flat (slope 0), its mobility rises with
    slope +1 and its accelerance with +2 (thesis table 2.1: each step multiplies by
    ``j omega``); a free-free one has slopes -2, -1, 0. Uses the lines up to twice
    the lowest positive frequency (at least 3). None when there are no driving
    points or too few lines.
    """
    o_pos = {o: k for k, o in enumerate(frf.outputs)}
    pts = [(o_pos[d], k) for k, d in enumerate(frf.inputs) if d in o_pos]
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
    declared: str | None,
    units: Units | None,
    given: str | None,
    where: str,
    label: str | None = None,
) -> str:
    """Decide the quantity from the file's declaration, its units and the caller.

    Raises
    ------
    QuantityError
        When two of them disagree, or none says what the data are.
    """
    check_quantity_arg(given)
    from_units = units.quantity if units is not None else None
    if declared and units is not None and from_units and declared != from_units:
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
    if q is None and label and str(label).strip() and str(label).strip().upper() != "NONE":
        raise QuantityError(
            f"{where}: its units label {str(label).strip()!r} is not understood as an FRF "
            "unit (known: m mm cm um in ft / N kN mN lbf / s ms / rad deg / g, e.g. "
            "'mm/(s N)', 'g/lbf', '(1/N)*(m/s²)'), and nothing else says whether it holds "
            "receptance, mobility or accelerance; pass quantity=..."
        )
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
