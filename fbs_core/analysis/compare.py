"""Comparison of two states: level difference of two FRFs and of two truncation maps.

Two FRFs are compared line by line only on the same grid with the same DOFs and
quantity: a mismatch raises (:class:`~fbs_core.errors.FrequencyGridError`,
:class:`~fbs_core.errors.DOFError`, :class:`~fbs_core.errors.QuantityError`),
never a silent interpolation (design note "fail on mismatched grids"; use
``FRF.interpolate`` explicitly). The difference is that of the levels,
``20 log10 |a| - 20 log10 |b| = 20 log10 |a / b|``, with the phase of ``a / b``.
Two truncation maps (thesis eq. 5.1, figs. 5.6-5.7) are compared as the
difference of their errors on the same mode counts, centre frequencies and DOFs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import DOFError, FBSError, FrequencyGridError, QuantityError
from ..frf import FRF
from ..vocabulary import magnitude_db

__all__ = ["LevelDifference", "MapDifference", "db_difference", "truncation_map_difference"]


@dataclass(frozen=True, eq=False)
class LevelDifference:
    """Level and phase difference of two FRFs (``a`` relative to ``b``).

    Attributes
    ----------
    freq : ndarray, shape (n_f,)
        Frequencies in Hz.
    outputs, inputs : tuple of str
        DOF labels shared by both FRFs.
    db : ndarray, shape (n_f, n_out, n_in)
        ``20 log10 |a| - 20 log10 |b|`` (``+inf`` / ``-inf`` / NaN where an FRF is 0).
    phase_deg : ndarray, shape (n_f, n_out, n_in)
        Phase of ``a / b`` in degrees, in (-180, 180].
    """

    freq: np.ndarray
    outputs: tuple[str, ...]
    inputs: tuple[str, ...]
    db: np.ndarray
    phase_deg: np.ndarray

    def max_abs_db(self) -> float:
        """Largest absolute level difference over all lines and elements (finite ones)."""
        d = np.abs(self.db[np.isfinite(self.db)])
        return float(d.max()) if d.size else 0.0

    def export_mapping(self) -> dict[str, Any]:
        """Arrays with axes for :func:`fbs_core.io.export_result`."""
        dims = ("freq", "output", "input")
        return {
            "db": (dims, self.db),
            "phase_deg": (dims, self.phase_deg),
            "coords": {"freq": self.freq, "output": list(self.outputs), "input": list(self.inputs)},
        }


def db_difference(a: FRF, b: FRF) -> LevelDifference:
    """Level difference in dB (and phase difference) of FRF ``a`` relative to ``b``.

    Parameters
    ----------
    a, b : FRF
        Same frequency lines, outputs, inputs and quantity.

    Returns
    -------
    LevelDifference

    Raises
    ------
    FrequencyGridError
        Different frequency lines (interpolate one explicitly first).
    DOFError
        Different outputs or inputs, naming both.
    QuantityError
        Different quantities.

    Examples
    --------
    >>> import numpy as np
    >>> from fbs_core import FRF
    >>> a = FRF([1.0, 2.0], np.full((2, 1, 1), 10.0), ["b:z"], ["patch"])
    >>> b = FRF([1.0, 2.0], np.full((2, 1, 1), 1.0), ["b:z"], ["patch"])
    >>> db_difference(a, b).db[:, 0, 0].tolist()
    [20.0, 20.0]
    """
    a.require_grid(b, "the two states")
    for what in ("outputs", "inputs"):
        la, lb = getattr(a, what), getattr(b, what)
        if la != lb:
            raise DOFError(
                f"the two states have different {what}: {list(la)} vs {list(lb)}; select the "
                "same DOFs in both (FRF.sel) before comparing"
            )
    if a.quantity != b.quantity:
        raise QuantityError(
            f"the two states are different quantities ({a.quantity} vs {b.quantity}); "
            "convert one with .to(...) first"
        )
    with np.errstate(divide="ignore", invalid="ignore"):
        db = magnitude_db(a.data, floor=None) - magnitude_db(b.data, floor=None)
        ph = np.degrees(np.angle(a.data * np.conj(b.data)))
    return LevelDifference(a.freq, a.outputs, a.inputs, db, ph)


@dataclass(frozen=True, eq=False)
class MapDifference:
    """Difference of two truncation error maps (``a`` minus ``b``).

    Attributes
    ----------
    n_modes : ndarray of int, shape (n_N,)
        Retained-mode counts.
    centres : ndarray, shape (n_c,)
        Centre frequencies of the floating band in Hz.
    dofs : tuple of str, length n_dof
        Response DOFs.
    error_a, error_b : ndarray, shape (n_N, n_c, n_dof)
        Eq. 5.1 errors of the two maps.
    diff : ndarray, shape (n_N, n_c, n_dof)
        ``error_a - error_b`` (0.05 = five percentage points worse in ``a``).
    max_diff : ndarray, shape (n_N, n_c)
        Difference of the maxima over the DOFs (thesis fig. 5.6 views).
    """

    n_modes: np.ndarray
    centres: np.ndarray
    dofs: tuple[str, ...]
    error_a: np.ndarray
    error_b: np.ndarray
    diff: np.ndarray
    max_diff: np.ndarray

    def export_mapping(self) -> dict[str, Any]:
        """Arrays with axes for :func:`fbs_core.io.export_result`."""
        dims = ("n_modes", "centre", "dof")
        return {
            "diff": (dims, self.diff),
            "max_diff": (dims[:2], self.max_diff),
            "coords": {"n_modes": self.n_modes, "centre": self.centres, "dof": list(self.dofs)},
        }


def truncation_map_difference(a: Any, b: Any) -> MapDifference:
    """Difference map of two truncation maps (:func:`fbs_core.truncation_map` results).

    Parameters
    ----------
    a, b : TruncationMap
        Same retained-mode counts, centre frequencies and response DOFs.

    Returns
    -------
    MapDifference

    Raises
    ------
    FBSError
        Different retained-mode counts.
    FrequencyGridError
        Different centre frequencies.
    DOFError
        Different response DOFs.
    """
    na, nb = np.asarray(a.n_modes), np.asarray(b.n_modes)
    if na.shape != nb.shape or np.any(na != nb):
        raise FBSError(
            f"the maps have different retained-mode counts ({na.tolist()} vs {nb.tolist()}); "
            "compute both with the same n_modes"
        )
    ca, cb = np.asarray(a.centres), np.asarray(b.centres)
    if ca.shape != cb.shape or not np.allclose(ca, cb, rtol=1e-12, atol=0):
        raise FrequencyGridError(
            f"the maps have different centre frequencies ({ca.size} centres "
            f"{ca[0]:g}-{ca[-1]:g} Hz vs {cb.size} centres {cb[0]:g}-{cb[-1]:g} Hz); "
            "compute both on the same band grid"
        )
    if tuple(a.dofs) != tuple(b.dofs):
        raise DOFError(f"the maps have different DOFs: {list(a.dofs)} vs {list(b.dofs)}")
    ea, eb = np.asarray(a.error), np.asarray(b.error)
    return MapDifference(na, ca, tuple(a.dofs), ea, eb, ea - eb, ea.max(axis=-1) - eb.max(axis=-1))
