"""Variance-based sensitivity: which parameter moves the response most, per frequency band.

The output of a variant is the level of its bushing response in a frequency band,
``L = 10 log10(mean over the band's lines of |v_e|^2)`` dB (an energy mean; one value per
band and DOF), :func:`band_levels`. Its variance over the parameter ranges is split by the
Sobol' indices (Sobol', Math. Comput. Simul. 55 (2001) 271-280):

- first order ``S_i = V[E(Y | X_i)] / V(Y)``: the share of the variance ``X_i`` causes
  alone;
- total ``S_Ti = E[V(Y | X_~i)] / V(Y)``: its share with every interaction it has.

They are estimated from a Saltelli design (:func:`~.design.sample_design`, ``"saltelli"``:
``f_A``, ``f_B``, ``f_ABi`` the outputs of the rows of A, B and AB_i) with the estimators
recommended by Saltelli et al., Comput. Phys. Commun. 181 (2010) 259-270, table 2:

- ``S_i  = mean(f_B (f_ABi - f_A)) / V``          (Saltelli 2010, eq. (b))
- ``S_Ti = mean((f_A - f_ABi)^2) / (2 V)``        (Jansen 1999, eq. (f))

with ``V`` the variance of ``f_A`` and ``f_B`` together, and ``f_B`` centred on their mean
(the expectation is unchanged, the estimator's variance no longer grows with the squared
mean of a level of about -100 dB). Their convergence is shown two
ways: the indices of the design's prefixes ``N/8, N/4, N/2, N`` (a Sobol' sequence's
prefix is itself balanced) and bootstrap 95 % intervals (rows resampled, Archer, Saltelli
& Sobol', J. Stat. Comput. Simul. 58 (1997) 99-120).

A parameter whose ``S_Ti`` is small can be fixed at its nominal value; ``sum S_i`` near 1
means the parameters act additively on the band level.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from ..errors import DataFormatError, DOFError, FBSError
from ..vocabulary import DIRECTIONS
from ..vocabulary import readonly as _ro
from .design import Design

__all__ = ["Sensitivity", "band_levels", "sensitivity", "sobol_indices", "third_octave_bands"]


def third_octave_bands(fmin: float, fmax: float) -> FloatArray:
    """One-third-octave bands covering ``[fmin, fmax]``, clipped to it.

    Base-2 bands of IEC 61260-1: centres ``1000 2^(b/3)`` Hz, edges ``centre 2^(+-1/6)``.

    Returns
    -------
    ndarray, shape (n_b, 2)
        ``[low, high]`` of every band that overlaps ``[fmin, fmax]`` by more than a tenth of
        its own width, clipped to it; a thinner sliver at either end joins its neighbour
        (the first band starts at ``fmin``, the last ends at ``fmax``).

    Examples
    --------
    >>> third_octave_bands(34.8, 139.0).round(1).tolist()[:2]
    [[34.8, 44.2], [44.2, 55.7]]
    """
    if not (np.isfinite(fmin) and np.isfinite(fmax) and 0 < fmin < fmax):
        raise FBSError(f"need 0 < fmin < fmax, got {fmin!r}, {fmax!r}")
    b0 = int(np.floor(3 * np.log2(fmin / 1000.0))) - 1
    b1 = int(np.ceil(3 * np.log2(fmax / 1000.0))) + 1
    out = []
    for b in range(b0, b1 + 1):
        c = 1000.0 * 2.0 ** (b / 3)
        lo, hi = c * 2 ** (-1 / 6), c * 2 ** (1 / 6)
        a, z = max(lo, fmin), min(hi, fmax)
        if z - a > 0.1 * (hi - lo):
            out.append([a, z])
    if not out:  # a range inside a tenth of one band
        out.append([fmin, fmax])
    out[0][0], out[-1][1] = fmin, fmax  # a sliver left out joins its neighbour
    return np.array(out, float)


def band_levels(freq: ArrayLike, responses: ArrayLike, bands: ArrayLike) -> FloatArray:
    """Energy-mean level of every response in every band, dB re 1 (unit of the response).

    Parameters
    ----------
    freq : array_like, shape (n_f,)
    responses : array_like, shape (n_v, n_f, n_e)
    bands : array_like, shape (n_b, 2)
        ``[low, high]`` in Hz; a line belongs to a band when ``low <= f < high`` (the last
        band includes its upper edge).

    Returns
    -------
    ndarray, shape (n_v, n_b, n_e)
        ``10 log10(mean |v|^2)`` over the band's lines.

    Raises
    ------
    FBSError
        When a band holds no line.
    """
    f = np.asarray(freq, float)
    v = np.asarray(responses)
    e = np.asarray(bands, float).reshape(-1, 2)
    if v.ndim != 3 or v.shape[1] != f.size:
        raise DataFormatError(f"responses must have shape (n_v, {f.size}, n_e), got {v.shape}")
    p = np.abs(v) ** 2
    out = np.empty((v.shape[0], e.shape[0], v.shape[2]))
    for b, (lo, hi) in enumerate(e):
        m = (f >= lo) & ((f < hi) if b < e.shape[0] - 1 else (f <= hi))
        if not m.any():
            raise FBSError(f"band {lo:g}-{hi:g} Hz holds no line of the grid")
        out[:, b] = 10 * np.log10(p[:, m].mean(axis=1))
    return out


def _indices(fA: FloatArray, fB: FloatArray, fAB: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Saltelli 2010 first order and Jansen total: fA, fB (N, ...), fAB (k, N, ...)."""
    both = np.concatenate([fA, fB])
    V = np.var(both, axis=0)
    # centred: E[f_B (f_ABi - f_A)] is unchanged by a shift of f (E[f_ABi - f_A] = 0), but
    # its estimator's variance grows with the squared mean (a band level of -100 dB)
    fBc = fB - both.mean(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        S1 = np.mean(fBc[None] * (fAB - fA[None]), axis=1) / V
        ST = 0.5 * np.mean((fA[None] - fAB) ** 2, axis=1) / V
    return S1, ST


def sobol_indices(design: Design, y: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """First-order and total Sobol' indices of outputs ``y`` of a Saltelli design.

    Parameters
    ----------
    design : Design
        A ``"saltelli"`` design of ``N (k + 2)`` rows.
    y : array_like, shape (N (k + 2), ...)
        The outputs of its rows (any trailing shape, e.g. bands x DOFs).

    Returns
    -------
    first, total : ndarray, shape (k, ...)
        NaN where the output does not vary.

    Raises
    ------
    ParameterError
        For a design that is not a Saltelli design.
    DataFormatError
        When ``y`` has not one row per variant.
    """
    blocks = design.blocks()
    y = np.asarray(y, float)
    if y.shape[0] != design.n:
        raise DataFormatError(f"y must have {design.n} rows (one per variant), got {y.shape[0]}")
    fAB = np.stack([y[blocks[f"AB_{n}"]] for n in design.names])
    return _indices(y[blocks["A"]], y[blocks["B"]], fAB)


@dataclass(frozen=True, eq=False)
class Sensitivity:
    """Sobol' indices of the band levels per band and DOF, with their convergence.

    Parameters
    ----------
    names : tuple of str
        The parameters (k).
    bands : ndarray, shape (n_b, 2)
        Band edges in Hz.
    dofs : tuple of str
        Response DOFs (n_e).
    first, total : ndarray, shape (k, n_b, n_e)
        First-order and total indices.
    first_ci, total_ci : ndarray, shape (2, k, n_b, n_e)
        Bootstrap 95 % intervals (2.5 and 97.5 percentiles).
    steps : ndarray of int, shape (n_c,)
        Base rows ``N'`` of the convergence checkpoints (the last is ``N``).
    first_steps, total_steps : ndarray, shape (n_c, k, n_b, n_e)
        The indices from the first ``N'`` rows of every block.
    mean, std : ndarray, shape (n_b, n_e)
        Mean and standard deviation of the band level (dB) over A and B.
    harmonic : int or None
    """

    names: tuple[str, ...]
    bands: FloatArray
    dofs: tuple[str, ...]
    first: FloatArray
    total: FloatArray
    first_ci: FloatArray
    total_ci: FloatArray
    steps: Any
    first_steps: FloatArray
    total_steps: FloatArray
    mean: FloatArray
    std: FloatArray
    harmonic: int | None = None

    def _dof(self, dof: str | int) -> int:
        if isinstance(dof, str):
            if dof not in self.dofs:
                raise DOFError(f"unknown response DOF {dof!r}; available: {', '.join(self.dofs)}")
            return self.dofs.index(dof)
        return int(dof)

    @property
    def total_change(self) -> FloatArray:
        """Largest change of any total index from each checkpoint to the final one,
        shape (n_c,): below a few hundredths the ranking has settled."""
        d = np.abs(self.total_steps - self.total[None])
        out: FloatArray = np.nanmax(d.reshape(d.shape[0], -1), axis=1)
        return out

    def ranking(self, dof: str | int, band: int) -> list[dict[str, Any]]:
        """Parameters by decreasing total index for one DOF and band (a table's rows).

        Returns
        -------
        list of dict
            ``rank``, ``parameter``, ``total``, ``total_low``, ``total_high``, ``first``.
        """
        j, b = self._dof(dof), int(band)
        if not 0 <= b < self.bands.shape[0]:
            raise FBSError(f"band index must be in 0..{self.bands.shape[0] - 1}, got {band}")
        st = self.total[:, b, j]
        order = np.argsort(-np.nan_to_num(st, nan=-np.inf), kind="stable")
        return [
            {
                "rank": r + 1,
                "parameter": self.names[i],
                "total": float(st[i]),
                "total_low": float(self.total_ci[0, i, b, j]),
                "total_high": float(self.total_ci[1, i, b, j]),
                "first": float(self.first[i, b, j]),
            }
            for r, i in enumerate(order)
        ]

    def table(self) -> list[dict[str, Any]]:
        """Every band, DOF and parameter as plain rows (for CSV and a meeting's table):
        ``band_low``, ``band_high``, ``dof``, then the columns of :meth:`ranking`, and the
        band level's ``std_db``."""
        rows = []
        for j, d in enumerate(self.dofs):
            for b, (lo, hi) in enumerate(self.bands):
                for r in self.ranking(j, b):
                    rows.append(
                        {
                            "band_low": float(lo),
                            "band_high": float(hi),
                            "dof": d,
                            **r,
                            "std_db": float(self.std[b, j]),
                        }
                    )
        return rows

    def leaders(self, dof: str | int) -> list[dict[str, Any]]:
        """Per band, the parameter with the largest total index for ``dof`` (one row each):
        ``band_low``, ``band_high``, ``parameter``, ``total``, ``second`` (the runner-up)
        and ``std_db`` (how much the band level moves at all)."""
        j = self._dof(dof)
        out = []
        for b, (lo, hi) in enumerate(self.bands):
            r = self.ranking(j, b)
            out.append(
                {
                    "band_low": float(lo),
                    "band_high": float(hi),
                    "parameter": r[0]["parameter"],
                    "total": r[0]["total"],
                    "second": r[1]["parameter"] if len(r) > 1 else "",
                    "std_db": float(self.std[b, j]),
                }
            )
        return out


def sensitivity(
    design: Design,
    freq: ArrayLike,
    responses: ArrayLike,
    *,
    bands: ArrayLike | None = None,
    dofs: Sequence[str] | None = None,
    n_bootstrap: int = 200,
    seed: int = 0,
    harmonic: int | None = None,
) -> Sensitivity:
    """Sobol' indices of the band levels of a Saltelli design's responses.

    Parameters
    ----------
    design : Design
        ``"saltelli"``, ``N (k + 2)`` rows.
    freq : array_like, shape (n_f,)
    responses : array_like, shape (N (k + 2), n_f, n_e)
        Complex responses of the rows.
    bands : array_like, shape (n_b, 2), optional
        Default: the one-third-octave bands of the grid (:func:`third_octave_bands`).
    dofs : sequence of str, optional
        Labels (default ``bushing:x`` ...).
    n_bootstrap : int
        Resamples of the rows for the 95 % intervals (0: none, NaN intervals).
    seed : int
        Of the bootstrap resampling.
    harmonic : int, optional

    Returns
    -------
    Sensitivity
    """
    f = np.asarray(freq, float)
    e = third_octave_bands(f[0], f[-1]) if bands is None else np.asarray(bands, float)
    y = band_levels(f, responses, e)  # (n, n_b, n_e)
    S1, ST = sobol_indices(design, y)
    blk = design.blocks()
    N = design.n_base
    fA, fB = y[blk["A"]], y[blk["B"]]
    fAB = np.stack([y[blk[f"AB_{n}"]] for n in design.names])  # (k, N, n_b, n_e)
    steps = [s for s in (N // 8, N // 4, N // 2) if s >= 4] + [N]
    s1s, sts = zip(*(_indices(fA[:s], fB[:s], fAB[:, :s]) for s in steps), strict=True)
    rng = np.random.default_rng(seed)
    nb = int(n_bootstrap)
    if nb > 0:
        b1, bt = [], []
        for _ in range(nb):
            r = rng.integers(0, N, N)
            a, c = _indices(fA[r], fB[r], fAB[:, r])
            b1.append(a)
            bt.append(c)
        with warnings.catch_warnings():  # an output that never varies: NaN, said above
            warnings.simplefilter("ignore", RuntimeWarning)
            ci1 = np.nanpercentile(np.array(b1), [2.5, 97.5], axis=0)
            cit = np.nanpercentile(np.array(bt), [2.5, 97.5], axis=0)
    else:
        ci1 = cit = np.full((2, *S1.shape), np.nan)
    both = np.concatenate([fA, fB])
    ne = y.shape[2]
    labels = tuple(f"bushing:{d}" for d in DIRECTIONS)[:ne]
    return Sensitivity(
        names=design.names,
        bands=_ro(e),
        dofs=labels if dofs is None else tuple(dofs),
        first=_ro(S1),
        total=_ro(ST),
        first_ci=_ro(ci1),
        total_ci=_ro(cit),
        steps=_ro(np.array(steps)),
        first_steps=_ro(np.array(s1s)),
        total_steps=_ro(np.array(sts)),
        mean=_ro(both.mean(axis=0)),
        std=_ro(both.std(axis=0)),
        harmonic=harmonic,
    )
