"""The corridor of systematic errors: the spread of the coupled response over variants.

The thesis' scatter band (section 5.2, eqs. 5.2-5.4) is the spread of ``|v_e|`` when the
FRF elements carry random errors; its section 7 asks for "a noise corridor for systematic
errors" from "simultaneous change of physical properties such as mass and stiffness". The
corridor here is that: at every line and bushing DOF, the minimum, maximum and percentiles
of ``|v_e|`` over the variants of a design (:mod:`.design`), each variant a rebuilt pair of
models (:mod:`.models`), with the nominal response beside it. :meth:`Corridor.beside`
compares it with a scatter band of the same harmonic, line by line.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray, IntArray
from ..errors import DataFormatError, DOFError, FBSError
from ..frf import check_grid
from ..vocabulary import DIRECTIONS, magnitude_db
from ..vocabulary import readonly as _ro

__all__ = ["Corridor", "corridor"]


@dataclass(frozen=True, eq=False)
class Corridor:
    """Spread of ``|v_e|`` over the variants of a design, per line and DOF.

    Parameters
    ----------
    freq : ndarray, shape (n_f,)
        Lines in Hz.
    dofs : tuple of str
        Response DOF labels (n_e).
    nominal : ndarray, shape (n_f, n_e)
        Complex response of the nominal models.
    minimum, maximum : ndarray, shape (n_f, n_e)
        Minimum and maximum of ``|v_e|`` over the variants (the corridor's edges).
    argmin_variant, argmax_variant : ndarray of int, shape (n_f, n_e)
        The first variant attaining them (a row of the design).
    q : ndarray, shape (n_q,)
        Percentile levels in %.
    percentiles : ndarray, shape (n_q, n_f, n_e)
        Percentiles of ``|v_e|`` over the variants (numpy's "linear" definition).
    n_variants : int
    harmonic : int or None
    """

    freq: FloatArray
    dofs: tuple[str, ...]
    nominal: ComplexArray
    minimum: FloatArray
    maximum: FloatArray
    argmin_variant: IntArray
    argmax_variant: IntArray
    q: FloatArray
    percentiles: FloatArray
    n_variants: int
    harmonic: int | None = None

    def dof_index(self, dof: str | int) -> int:
        """Column of a DOF label (or an index)."""
        if isinstance(dof, str):
            if dof not in self.dofs:
                raise DOFError(f"unknown response DOF {dof!r}; available: {', '.join(self.dofs)}")
            return self.dofs.index(dof)
        return int(dof)

    @property
    def width_db(self) -> FloatArray:
        """``20 log10(maximum / minimum)``, shape (n_f, n_e): the corridor's width in dB."""
        return magnitude_db(self.maximum / self.minimum, floor=None)

    @property
    def above_db(self) -> FloatArray:
        """How far the upper edge lies above the nominal response, dB, (n_f, n_e)."""
        return magnitude_db(self.maximum / np.abs(self.nominal), floor=None)

    @property
    def below_db(self) -> FloatArray:
        """How far the lower edge lies below the nominal response, dB, (n_f, n_e)."""
        return magnitude_db(np.abs(self.nominal) / self.minimum, floor=None)

    def beside(self, band: Any) -> list[dict[str, Any]]:
        """The corridor beside a noise scatter band of the same lines, one row per DOF.

        Parameters
        ----------
        band : ScatterBand
            From :func:`fbs_core.scatter_band` on the corridor's lines (``minimum`` /
            ``maximum`` of ``|v_e|``, its ``dofs`` among the corridor's).

        Returns
        -------
        list of dict
            Per DOF: ``dof``, ``corridor_median_db`` / ``corridor_max_db`` (width, median
            and largest over the lines), ``band_median_db`` / ``band_max_db`` (the noise
            band's), ``share_wider`` (the share of lines where the corridor is the wider)
            and ``share_outside`` (the share of lines where some variant leaves the noise
            band, above or below: the systematic error exceeds what the noise explains).

        Raises
        ------
        FBSError
            When the band's lines are not the corridor's.
        """
        f = np.asarray(band.freq, float)
        if f.shape != self.freq.shape or not np.allclose(f, self.freq, rtol=1e-12, atol=0):
            raise FBSError(
                f"the band's lines ({f.size}, {f[0]:g}-{f[-1]:g} Hz) are not the corridor's "
                f"({self.freq.size}, {self.freq[0]:g}-{self.freq[-1]:g} Hz)"
            )
        rows = []
        bw = magnitude_db(np.asarray(band.maximum) / np.asarray(band.minimum), floor=None)
        for j, d in enumerate(band.dofs):
            i = self.dof_index(d)
            cw = self.width_db[:, i]
            out = (self.maximum[:, i] > band.maximum[:, j]) | (
                self.minimum[:, i] < band.minimum[:, j]
            )
            rows.append(
                {
                    "dof": d,
                    "corridor_median_db": float(np.median(cw)),
                    "corridor_max_db": float(np.max(cw)),
                    "band_median_db": float(np.median(bw[:, j])),
                    "band_max_db": float(np.max(bw[:, j])),
                    "share_wider": float(np.mean(cw > bw[:, j])),
                    "share_outside": float(np.mean(out)),
                }
            )
        return rows


def corridor(
    freq: ArrayLike,
    responses: ArrayLike,
    nominal: ArrayLike,
    *,
    dofs: Sequence[str] | None = None,
    percentiles: ArrayLike = (5.0, 50.0, 95.0),
    harmonic: int | None = None,
) -> Corridor:
    """The corridor of the responses of ``n_v`` variants.

    Parameters
    ----------
    freq : array_like, shape (n_f,)
        Lines in Hz.
    responses : array_like, shape (n_v, n_f, n_e)
        Complex (or magnitude) responses of the variants.
    nominal : array_like, shape (n_f, n_e)
        Response of the nominal models.
    dofs : sequence of str, optional
        Labels (default ``bushing:x`` ...).
    percentiles : sequence of float
        Levels in %.
    harmonic : int, optional
        Recorded with the corridor.

    Returns
    -------
    Corridor

    Raises
    ------
    DataFormatError
        For shapes that do not agree or non-finite responses.
    FBSError
        For percentile levels outside [0, 100].
    """
    f = check_grid(freq)
    v = np.asarray(responses)
    if v.ndim != 3 or v.shape[1] != f.size or v.shape[0] < 1:
        raise DataFormatError(
            f"responses must have shape (n_variants, n_f={f.size}, n_e), got {v.shape}"
        )
    nom = np.asarray(nominal, complex)
    if nom.shape != v.shape[1:]:
        raise DataFormatError(f"nominal must have shape {v.shape[1:]}, got {nom.shape}")
    mag = np.abs(v)
    if not np.all(np.isfinite(mag)) or not np.all(np.isfinite(nom)):
        raise DataFormatError("responses and nominal must be finite")
    qs = np.atleast_1d(np.asarray(percentiles, float))
    if qs.ndim != 1 or np.any(~np.isfinite(qs) | (qs < 0) | (qs > 100)):
        raise FBSError(f"percentiles must be levels in [0, 100] %, got {qs.tolist()}")
    ne = v.shape[2]
    labels = tuple(f"bushing:{d}" for d in DIRECTIONS)[:ne]
    labels = labels if dofs is None else tuple(dofs)
    if len(labels) != ne:
        raise DataFormatError(f"{len(labels)} DOF labels for {ne} responses")
    return Corridor(
        freq=_ro(f),
        dofs=labels,
        nominal=_ro(nom),
        minimum=_ro(mag.min(axis=0)),
        maximum=_ro(mag.max(axis=0)),
        argmin_variant=_ro(mag.argmin(axis=0)),
        argmax_variant=_ro(mag.argmax(axis=0)),
        q=_ro(qs),
        percentiles=_ro(np.percentile(mag, qs, axis=0)),
        n_variants=int(v.shape[0]),
        harmonic=harmonic,
    )
