"""The words of the domain, written once: DOF directions, couplings, speeds, dB, read-only arrays.

Every module of :mod:`fbs_core` takes these from here instead of spelling them again
(``tests/test_vocabulary.py`` scans the core's code for other spellings), and so does the
dashboard.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

__all__ = [
    "COUPLED_DIRECTIONS",
    "COUPLINGS",
    "DB_FLOOR",
    "DIRECTIONS",
    "ROTATIONS",
    "TRANSLATIONS",
    "EIGEN_SPEEDS",
    "HARMONIC_CASES",
    "fraction",
    "magnitude_db",
    "percent",
    "readonly",
]

#: Directions of a node: three translations and three rotations about the vehicle axes
#: (thesis eq. 2.15; ISO 8855: x forward, y left, z up). DOF labels are ``"node:dir"``.
DIRECTIONS: tuple[str, ...] = ("x", "y", "z", "rx", "ry", "rz")
#: The translations of :data:`DIRECTIONS` (outputs in m, inputs forces).
TRANSLATIONS: tuple[str, ...] = DIRECTIONS[:3]
#: The rotations of :data:`DIRECTIONS` (outputs in rad, inputs moments).
ROTATIONS: tuple[str, ...] = DIRECTIONS[3:]

#: The hub directions each coupling option joins to the spindle: ``"6dof"`` all six (a
#: braked wheel, as in the thesis), ``"5dof"`` all but the wheel spin ``ry`` (free rolling).
COUPLED_DIRECTIONS: dict[str, tuple[str, ...]] = {
    "6dof": DIRECTIONS,
    "5dof": tuple(d for d in DIRECTIONS if d != "ry"),
}
#: Hub coupling options (the keys of :data:`COUPLED_DIRECTIONS`).
COUPLINGS: tuple[str, ...] = tuple(COUPLED_DIRECTIONS)

#: Operating speeds of the eigenfrequency-versus-N curves (thesis fig. 5.8), km/h.
EIGEN_SPEEDS: tuple[float, ...] = (20.0, 80.0, 120.0)

#: The harmonic excitation cases of the thesis (fig. 4.4).
HARMONIC_CASES: tuple[int, ...] = tuple(range(1, 8))

#: Magnitudes are floored at this value before the dB conversion (no ``-inf`` at zeros).
DB_FLOOR = 1e-30


def percent[Ratio: (float, np.ndarray)](fraction: Ratio) -> Ratio:
    """A ratio of the core in percent, as the dashboard shows it (0.2 -> 20.0).

    The core takes and returns ratios as fractions: the noise level ``p`` (0.1 = +-10 %),
    the eq. 5.1 error and its threshold (0.2 = 20 %). The dashboard shows percent; this and
    :func:`fraction` are its only conversions.

    Examples
    --------
    >>> percent(0.2)
    20.0
    """
    return fraction * 100.0


def fraction[Ratio: (float, np.ndarray)](percent: Ratio) -> Ratio:
    """A percentage of the dashboard as the core's fraction (20.0 -> 0.2); see :func:`percent`.

    Examples
    --------
    >>> fraction(10.0)
    0.1
    """
    return percent / 100.0


def readonly(a: ArrayLike, dtype: DTypeLike | None = None) -> np.ndarray:
    """A read-only copy of ``a`` (results are immutable: nobody can change them in place).

    Parameters
    ----------
    a : array_like
        The values.
    dtype : data-type, optional
        Type of the copy (default: that of ``a``).

    Examples
    --------
    >>> r = readonly([1.0, 2.0])
    >>> r.flags.writeable
    False
    """
    out = np.array(a, dtype=dtype, copy=True)
    out.setflags(write=False)
    return out


def magnitude_db(x: ArrayLike, ref: float = 1.0, floor: float | None = DB_FLOOR) -> np.ndarray:
    """``20 log10(|x| / ref)`` in dB re ``ref``.

    Parameters
    ----------
    x : array_like
        Real or complex amplitudes (any shape).
    ref : float
        Reference amplitude of 0 dB.
    floor : float or None
        Magnitudes below ``floor * ref`` count as ``floor * ref`` (finite levels at exact
        zeros); ``None`` keeps ``-inf`` there.

    Examples
    --------
    >>> float(magnitude_db(10.0))
    20.0
    >>> float(magnitude_db(0.0))
    -600.0
    """
    mag = np.abs(np.asarray(x)) / ref
    if floor is not None:
        mag = np.maximum(mag, floor)
    with np.errstate(divide="ignore"):
        out: np.ndarray = 20.0 * np.log10(mag)
    return out
