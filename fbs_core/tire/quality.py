"""How well a modal tire model predicts between its operating points.

Two measures, both in dB of level:

* :func:`level_errors`: the difference of two responses (e.g. the shipped
  prediction and a direct solution at the exact speed of every line), judged
  where the true level is within ``within_db`` of the peak of its DOF and
  everywhere above a floor ``floor_db`` below that peak;
* :func:`interpolation_quality`: from the model's data alone (a supplier's model
  has no matrices to compare with), leave one operating point out, predict it
  from its neighbours and report the difference in dB per harmonic band.

:func:`speed_coverage` warns (:class:`SpeedRangeWarning`) when a harmonic band
needs speeds outside the stored operating points.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import FBSError
from ..vocabulary import magnitude_db

if TYPE_CHECKING:
    from ..harmonics import Harmonic
    from .model import TireModel

__all__ = [
    "InterpolationQuality",
    "LevelErrors",
    "SpeedRangeWarning",
    "interpolation_quality",
    "level_errors",
    "speed_coverage",
]


@dataclass(frozen=True)
class LevelErrors:
    """Worst level difference in dB, near the peak and anywhere above the floor.

    Attributes
    ----------
    near_peak : float
        Largest ``|20 log10(|pred| / |true|)|`` where the true level is within
        ``within_db`` of its DOF's peak.
    anywhere : float
        The same over all lines above ``floor_db`` below the peak.
    near_peak_at, anywhere_at : tuple of int
        Index ``(line, dof)`` of the worst line.
    within_db, floor_db : float
    """

    near_peak: float
    anywhere: float
    near_peak_at: tuple[int, int]
    anywhere_at: tuple[int, int]
    within_db: float
    floor_db: float


def level_errors(
    pred: ArrayLike, true: ArrayLike, within_db: float = 30.0, floor_db: float = 120.0
) -> LevelErrors:
    """Worst level error of ``pred`` against ``true`` per DOF column (dB).

    Parameters
    ----------
    pred, true : array_like, shape (n_f, n_dof)
        Complex responses on the same lines; the peak of each DOF is the maximum
        of ``|true|`` over the lines.
    within_db : float
        Lines with a true level at least ``peak - within_db`` count as near the peak.
    floor_db : float
        Lines more than ``floor_db`` below the DOF's peak are ignored (numerical floor).

    Returns
    -------
    LevelErrors
    """
    p = np.asarray(pred)
    t = np.asarray(true)
    if p.shape != t.shape or p.ndim != 2:
        raise FBSError(f"pred and true must have one shape (n_f, n_dof), got {p.shape}, {t.shape}")
    tiny = np.finfo(float).tiny
    lt = magnitude_db(t, floor=tiny)
    lp = magnitude_db(p, floor=tiny)
    rel = lt - lt.max(axis=0)
    err = np.abs(lp - lt)
    near = np.where(rel >= -within_db, err, -np.inf)
    above = np.where(rel >= -floor_db, err, -np.inf)
    i = np.unravel_index(np.argmax(near), near.shape)
    j = np.unravel_index(np.argmax(above), above.shape)
    return LevelErrors(
        float(near[i]),
        float(above[j]),
        (int(i[0]), int(i[1])),
        (int(j[0]), int(j[1])),
        float(within_db),
        float(floor_db),
    )


class SpeedRangeWarning(UserWarning):
    """A harmonic band needs vehicle speeds outside the model's operating points."""


def speed_coverage(tire: TireModel, harmonic: int | Harmonic) -> tuple[float, float]:
    """Part of a harmonic's band that the model's operating points cover, in Hz.

    Warns :class:`SpeedRangeWarning` when the band ``v = 3.6 f lambda`` over the
    harmonic's speed range (30-120 km/h) needs speeds outside the stored ones
    (the model is interpolated between them, never extrapolated: lines outside
    raise :class:`~fbs_core.tire.OperatingPointError`).

    Returns
    -------
    (f_lo, f_hi) : tuple of float
        Covered band in Hz (``f_lo > f_hi`` when nothing is covered).
    """
    from ..harmonics import harmonic as _harmonic

    h = _harmonic(harmonic)
    lo, hi = h.freq_range
    s0, s1 = float(tire.speeds[0]), float(tire.speeds[-1])
    c_lo = max(lo, s0 / 3.6 / h.wavelength)
    c_hi = min(hi, s1 / 3.6 / h.wavelength)
    if c_lo > lo * (1 + 1e-9) or c_hi < hi * (1 - 1e-9):
        warnings.warn(
            f"{h.name}: the band {lo:.4g}-{hi:.4g} Hz needs speeds "
            f"{h.speed_range[0]:g}-{h.speed_range[1]:g} km/h, the model covers "
            f"{s0:g}-{s1:g} km/h; lines outside {c_lo:.4g}-{c_hi:.4g} Hz are not predicted "
            "(no extrapolation)",
            SpeedRangeWarning,
            stacklevel=2,
        )
    return c_lo, c_hi


@dataclass(frozen=True)
class InterpolationQuality:
    """Leave-one-out estimate of the interpolation error between operating points.

    Attributes
    ----------
    harmonics : tuple of int
    speeds : ndarray, shape (n_l,)
        The operating points left out, km/h.
    mobility_db, patch_db : ndarray, shape (n_h, n_l)
        Level error in dB, ``20 log10(1 + |X_pred - X| / |X|)`` (Frobenius norm over
        the hub mobility, vector norm over the free hub velocity), at the line of
        harmonic ``h`` that the left-out speed excites, ``f = v / (3.6 lambda)``;
        NaN where the speed lies outside the harmonic's speed range.
    worst_db : ndarray, shape (n_h,)
        Largest of both over the speeds of each harmonic (NaN if none).
    """

    harmonics: tuple[int, ...]
    speeds: np.ndarray
    mobility_db: np.ndarray
    patch_db: np.ndarray
    worst_db: np.ndarray

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able summary: worst dB per harmonic and the method."""
        return {
            "method": "leave one operating point out, predict it from the others "
            "(twice the spacing: an upper estimate)",
            "worst_db": {
                str(k): (None if not np.isfinite(w) else round(float(w), 3))
                for k, w in zip(self.harmonics, self.worst_db, strict=True)
            },
        }


def interpolation_quality(
    tire: TireModel, harmonics: Sequence[int] = (1, 2, 3, 4, 5, 6, 7)
) -> InterpolationQuality:
    """Interpolation quality of a modal tire model from its data alone (leave one out).

    Every interior operating point is left out in turn and predicted from its
    neighbours (the same interpolation the model uses between its points, over
    twice the spacing, so the estimate is conservative); the prediction is compared
    with the stored (exact) model at that speed, at the line each harmonic excites
    there. Needs no physical parameters: works for a supplier's model.

    Parameters
    ----------
    tire : TireModel
        At least 3 operating points.
    harmonics : sequence of int

    Returns
    -------
    InterpolationQuality
    """
    from ..harmonics import harmonic
    from .model import TireModel

    sp = np.asarray(tire.speeds, float)
    if sp.size < 3:
        raise FBSError(f"leave-one-out needs at least 3 operating points, the model has {sp.size}")
    hs = [harmonic(k) for k in harmonics]
    inner = np.arange(1, sp.size - 1)
    mob = np.full((len(hs), inner.size), np.nan)
    pat = np.full((len(hs), inner.size), np.nan)
    for j, i in enumerate(int(x) for x in inner):
        # the stencil of the interval (i - 1, i + 1) without i: its cubic nodes i - 2 .. i + 2
        keep = [q for q in range(max(0, i - 2), min(sp.size, i + 3)) if q != i]
        part = TireModel(
            sp[keep],
            tire.poles[keep],
            tire.psi[keep],
            tire.chi[keep],
            tire.wavelengths,
            tire.participation[keep],
            interpolation=tire.interpolation,
        )
        v = float(sp[i])
        for a, h in enumerate(hs):
            if not h.speed_range[0] <= v <= h.speed_range[1]:
                continue
            f = np.array([v / 3.6 / h.wavelength])
            hi = tire._harmonic_index(h)
            Y, x = tire.synthesis(f, [v], hi)  # stored: exact at the operating point
            Yp, xp = part.synthesis(f, [v], hi)
            assert x is not None and xp is not None  # a harmonic index was given
            mob[a, j] = magnitude_db(1 + np.linalg.norm(Yp - Y) / np.linalg.norm(Y))
            pat[a, j] = magnitude_db(1 + np.linalg.norm(xp - x) / np.linalg.norm(x))
    both = np.fmax(mob, pat)
    worst = np.array([np.nanmax(r) if np.isfinite(r).any() else np.nan for r in both])
    ro = [np.array(a) for a in (sp[inner], mob, pat, worst)]
    for arr in ro:
        arr.setflags(write=False)
    return InterpolationQuality(tuple(h.k for h in hs), *ro)
