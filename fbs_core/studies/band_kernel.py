"""The scatter band's compiled kernel over plain arrays (thesis section 5.2, eqs. 5.2-5.4).

The public way to run the Monte-Carlo rounds of a band over any range of its lines:
:func:`fbs_core.scatter_band` runs all lines in chunks (bounded in memory and duration),
a campaign (:mod:`fbs_core.campaign.work`) runs blocks of lines on Dask workers. Both
call :func:`band_lines` on the arrays of :func:`kernel_arrays` and get the same numbers
to the last bit, whatever the split: the noise factors of round ``r`` at line ``l`` are a
pure function of ``(seed, r, l)`` (:mod:`._rng`) and the lines are global indices.

- :func:`kernel_arrays`: the four subsystem matrices checked and laid out for the kernel
  (real and imaginary parts, read-only, C-contiguous, and each line's pivot order);
- :func:`noise_flags`: which subsystems a noise target makes noisy;
- :func:`band_lines`: the band statistics of the lines ``l0 .. l1 - 1`` over all rounds
  into a :class:`BandStats` (the parallel kernel, one band at a time: :data:`LOCK`);
- :func:`seed_key`: the 64-bit key of a band's seed;
- :func:`responses`: the complex responses of chosen rounds (a round regenerated alone,
  the noise-free reference), bit for bit those inside the band.
"""

from __future__ import annotations

import threading
import time
import warnings
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray, IntArray
from ..errors import DataFormatError, FBSError
from ..vocabulary import readonly
from . import _noise_kernels
from ._rng import seed_key

__all__ = [
    "TARGETS",
    "LOCK",
    "KernelArrays",
    "BandStats",
    "target_name",
    "noise_flags",
    "kernel_arrays",
    "band_lines",
    "responses",
    "reference_response",
    "seed_key",
]

#: Where the noise goes: the tire, the chassis (the thesis' "vehicle") or both.
TARGETS = ("tire", "chassis", "both")
#: Deprecated spellings of a target (one release).
_OLD_TARGETS = {"vehicle": "chassis"}

#: One compiled parallel run at a time (some numba threading layers abort on concurrent
#: launches from several Python threads, e.g. a dashboard serving two sessions); the
#: serial kernel (a few rounds, the reference) runs without it.
LOCK = threading.Lock()

_EMPTY_MAG = np.empty((0, 0, 0))
#: Lines per group of the fused kernel (:func:`._noise_kernels.noisy_band_stats`), by
#: ``frequency_dependent``: one line (its rounds stay in the core's cache); several lines
#: share the factors of frequency-independent noise.
_GROUP = {True: 1, False: 4}
_EMPTY_CPLX = np.empty((0, 0, 0), np.complex128)

#: The kernel inputs of a band: real and imaginary parts of ``Y_jj^A (n_f, n_j, n_j)``,
#: ``v_j (n_f, n_j)``, ``Y_jj^E (n_f, n_j, n_j)`` and ``Y_ej^E (n_f, n_e, n_j)``, then the
#: pivot order of every line ``(n_f, n_j)`` (see :func:`kernel_arrays`).
KernelArrays = tuple[
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    IntArray,
]


def target_name(target: str, *, warn: bool = True) -> str:
    """The name in :data:`TARGETS` of a noise target; ``"vehicle"`` is the deprecated name of
    ``"chassis"`` (a ``DeprecationWarning`` when ``warn``; bands stored with it still load).

    Raises
    ------
    FBSError
        For an unknown target, naming the allowed ones.
    """
    if target in _OLD_TARGETS:
        if warn:
            warnings.warn(
                f"noise target {target!r} is deprecated; use {_OLD_TARGETS[target]!r}",
                DeprecationWarning,
                stacklevel=3,
            )
        return _OLD_TARGETS[target]
    if target not in TARGETS:
        raise FBSError(f"unknown noise target {target!r}; allowed: {', '.join(TARGETS)}")
    return target


def noise_flags(target: str) -> tuple[bool, bool]:
    """Which subsystems get noise under ``target``: ``(tire, chassis)`` (eq. 5.2: tire only,
    5.3: chassis only, 5.4: both).

    Raises
    ------
    FBSError
        For an unknown target.
    """
    t = target_name(target, warn=False)
    return t in ("tire", "both"), t in ("chassis", "both")


def _split(z: ComplexArray) -> tuple[FloatArray, FloatArray]:
    # read-only, C-contiguous: one compiled signature for the band and single rounds
    return readonly(np.ascontiguousarray(z.real, float)), readonly(
        np.ascontiguousarray(z.imag, float)
    )


def kernel_arrays(YjjA: ArrayLike, vj: ArrayLike, YjjE: ArrayLike, YejE: ArrayLike) -> KernelArrays:
    """The subsystem matrices of a band checked and laid out for the kernel.

    Parameters
    ----------
    YjjA : array_like, shape (n_f, n_j, n_j)
        Tire mobility at the interface ``Y_jj^A``.
    vj : array_like, shape (n_f, n_j)
        Free interface velocity of the tire ``Y_ja^A F_a``.
    YjjE : array_like, shape (n_f, n_j, n_j)
        Chassis mobility at the interface ``Y_jj^E``.
    YejE : array_like, shape (n_f, n_e, n_j)
        Chassis transfer mobility ``Y_ej^E``.

    Returns
    -------
    KernelArrays
        Read-only arrays (see :data:`KernelArrays`).

    Raises
    ------
    DataFormatError
        For arrays of the wrong shapes or with non-finite values.
    """
    A, a, E, B = (np.asarray(x) for x in (YjjA, vj, YjjE, YejE))
    if A.ndim != 3 or A.shape[1] != A.shape[2]:
        raise DataFormatError(f"YjjA must have shape (n_f, n_j, n_j), got {A.shape}")
    nf, nj = A.shape[:2]
    if a.shape != (nf, nj):
        raise DataFormatError(f"vj must have shape (n_f, n_j) = {(nf, nj)}, got {a.shape}")
    if E.shape != (nf, nj, nj):
        raise DataFormatError(f"YjjE must have shape {(nf, nj, nj)}, got {E.shape}")
    if B.ndim != 3 or B.shape[0] != nf or B.shape[2] != nj:
        raise DataFormatError(
            f"YejE must have shape (n_f, n_e, {nj}) with n_f = {nf}, got {B.shape}"
        )
    for name, x in (("YjjA", A), ("vj", a), ("YjjE", E), ("YejE", B)):
        if not np.all(np.isfinite(x)):
            raise DataFormatError(f"{name} contains non-finite values")
    order = readonly(_noise_kernels.pivot_order(A, E))
    return (*_split(A), *_split(a), *_split(E), *_split(B), order)


@dataclass(frozen=True, eq=False)
class BandStats:
    """The band statistics of lines of a band, filled by :func:`band_lines`.

    Attributes
    ----------
    minimum, maximum : ndarray, shape (n_l, n_e)
        Minimum and maximum of ``|v_e|`` over the rounds.
    argmin_round, argmax_round : ndarray of int, shape (n_l, n_e)
        First round attaining them.
    percentiles : ndarray, shape (n_q, n_l, n_e)
        The percentiles ``q`` over the rounds (numpy's "linear" definition).
    conv_minimum, conv_maximum : ndarray, shape (n_k, n_l, n_e)
        Running minimum and maximum after the first ``checkpoints[k]`` rounds.
    """

    minimum: FloatArray
    maximum: FloatArray
    argmin_round: IntArray
    argmax_round: IntArray
    percentiles: FloatArray
    conv_minimum: FloatArray
    conv_maximum: FloatArray

    @classmethod
    def empty(cls, n_lines: int, n_e: int, n_q: int, n_k: int) -> BandStats:
        """Statistics of ``n_lines`` lines, ``n_q`` percentiles and ``n_k`` checkpoints, to fill."""
        return cls(
            np.empty((n_lines, n_e)),
            np.empty((n_lines, n_e)),
            np.empty((n_lines, n_e), np.int64),
            np.empty((n_lines, n_e), np.int64),
            np.empty((n_q, n_lines, n_e)),
            np.empty((n_k, n_lines, n_e)),
            np.empty((n_k, n_lines, n_e)),
        )


def band_lines(
    arrays: KernelArrays,
    l0: int,
    l1: int,
    key: np.uint64,
    rounds: IntArray,
    noise: float,
    tire: bool,
    chassis: bool,
    frequency_dependent: bool,
    q: FloatArray,
    checkpoints: IntArray,
    out: BandStats,
    row: int = 0,
    work: FloatArray | None = None,
) -> float:
    """Band statistics of lines ``l0 .. l1 - 1`` over the rounds ``rounds`` (eqs. 5.2-5.4).

    Parameters
    ----------
    arrays : KernelArrays
        From :func:`kernel_arrays`.
    l0, l1 : int
        Global line indices (a range gives exactly the numbers of the whole band).
    key : numpy.uint64
        The band's key (:func:`seed_key` of its seed).
    rounds : ndarray of int64, shape (R,)
        The rounds (``0 .. R - 1`` for a band).
    noise : float
        ``p``: factors uniform in ``[1 - p, 1 + p]``.
    tire, chassis : bool
        Which subsystems get noise (:func:`noise_flags`).
    frequency_dependent : bool
        New factors at every line (True) or one set per round (False).
    q : ndarray, shape (n_q,)
        Percentile levels in %.
    checkpoints : ndarray of int64, shape (n_k,)
        Ascending round counts in ``1 .. R`` of :attr:`BandStats.conv_minimum`.
    out : BandStats
        Written at rows ``row .. row + l1 - l0 - 1``.
    work : ndarray, shape (>= l1 - l0, n_e, R), optional
        Working memory of the magnitudes (``8 R n_e`` bytes per line), reused across calls.
        Each thread computes all rounds of one line at a time and that line's statistics
        while they are in its cache (:func:`._noise_kernels.noisy_band_stats`), so only
        its first lines are used (one per thread), unless the block has fewer lines than
        there are threads: then the threads share the rounds of all its lines.

    Returns
    -------
    float
        Seconds spent computing (holding :data:`LOCK`; the wait for it excluded).

    Raises
    ------
    FBSError
        For a line range outside the band or outside ``out``.
    """
    nf, ne = arrays[0].shape[0], arrays[6].shape[1]
    nl = l1 - l0
    if not 0 <= l0 < l1 <= nf:
        raise FBSError(f"line block {l0}..{l1} outside 0..{nf}")
    if not (0 <= row and row + nl <= out.minimum.shape[0]):
        raise FBSError(f"rows {row}..{row + nl} outside the {out.minimum.shape[0]} of the stats")
    R = int(rounds.size)
    if work is not None and (work.shape[0] < nl or work.shape[1:] != (ne, R)):
        raise FBSError(f"work must have shape (>= {nl}, {ne}, {R}), got {work.shape}")
    fd = bool(frequency_dependent)
    with LOCK:
        t0 = time.perf_counter()
        n_workers = numba.get_num_threads()
        group = _GROUP[fd]
        if nl >= n_workers * group:
            # each thread runs all rounds of its lines and their statistics in its cache
            n_buf = n_workers * group
            if work is not None and work.shape[0] >= n_buf:
                buf = work[:n_buf].reshape(n_workers, group, ne, R)
            else:
                buf = np.empty((n_workers, group, ne, R))
            _noise_kernels.noisy_band_stats(
                *arrays, l0, l1, key, rounds, float(noise), bool(tire), bool(chassis), fd,
                group, buf, q, checkpoints, out.minimum, out.maximum, out.argmin_round,
                out.argmax_round, out.percentiles, out.conv_minimum, out.conv_maximum, row,
            )  # fmt: skip
            return time.perf_counter() - t0
        # fewer lines than threads (a first, probing chunk): the threads share the rounds
        m = np.empty((nl, ne, R)) if work is None else work[:nl]
        _noise_kernels.noisy_block_run(
            *arrays, l0, l1, key, rounds, float(noise), bool(tire), bool(chassis), fd, m,
            _EMPTY_CPLX,
        )  # fmt: skip
        _noise_kernels.band_stats(
            m, q, checkpoints, out.minimum, out.maximum, out.argmin_round, out.argmax_round,
            out.percentiles, out.conv_minimum, out.conv_maximum, row,
        )  # fmt: skip
        return time.perf_counter() - t0


def responses(
    arrays: KernelArrays,
    key: np.uint64,
    rounds: IntArray,
    noise: float,
    tire: bool,
    chassis: bool,
    frequency_dependent: bool,
) -> ComplexArray:
    """Complex responses ``v_e`` of the rounds ``rounds`` at every line, shape ``(n, n_f, n_e)``.

    Bit for bit the rounds inside :func:`band_lines` with the same arguments. Up to
    ``LANES`` rounds run on the calling thread without :data:`LOCK` (a page's few rounds
    never wait for another band).
    """
    nf, ne = arrays[0].shape[0], arrays[6].shape[1]
    rids = np.asarray(rounds, np.int64)
    out = np.empty((rids.size, nf, ne), np.complex128)
    fd = bool(frequency_dependent)
    args = (*arrays, 0, nf, key, rids, float(noise), bool(tire), bool(chassis), fd, _EMPTY_MAG, out)
    if rids.size <= _noise_kernels.LANES:  # one block: one thread either way, no lock needed
        _noise_kernels.noisy_block_run_serial(*args)
    else:
        with LOCK:
            _noise_kernels.noisy_block_run(*args)
    return out


def reference_response(arrays: KernelArrays) -> ComplexArray:
    """The noise-free response (eq. 4.1, all factors 1), shape ``(n_f, n_e)``: exactly the
    kernel's result, the reference of a band."""
    out: ComplexArray = responses(
        arrays, np.uint64(0), np.zeros(1, np.int64), 0.0, False, False, False
    )[0]
    return out
