"""Monte-Carlo noise scatter band of the coupled response (thesis section 5.2).

Every element of the subsystem FRFs is scaled by a factor uniform in
``[1 - p, 1 + p]`` and the bushing response of eq. 4.1 is recomputed, ``R`` times:

- tire only (eq. 5.2):     ``Y_ej^E [S o Y_jj^A + Y_jj^E]^-1 S o (Y_ja^A F_a)``
- chassis only (eq. 5.3):  ``S o Y_ej^E [Y_jj^A + S o Y_jj^E]^-1 Y_ja^A F_a``
  (the thesis' "vehicle": the chassis substructure)
- both (eq. 5.4):          ``S o Y_ej^E [S o Y_jj^A + S o Y_jj^E]^-1 S o (Y_ja^A F_a)``

The thesis writes one symbol ``S`` but describes it as "a scaling matrix ... with
the dimension of the FRF matrix or response matrix of the considered subsystems",
each element multiplied by "a corresponding error element". Here every element of
every matrix gets its own independent factor: ``S_A`` for ``Y_jj^A``, ``s_a`` for
``Y_ja^A F_a``, ``S_E`` for ``Y_jj^E`` and ``S_B`` for ``Y_ej^E`` (the same symbol
cannot be one matrix: the factors multiply a 6x6 matrix and a 6-vector). The FRFs
are scaled element by element, without symmetrising (rotating tires are not
reciprocal). ``frequency_dependent=False`` draws one set per round (the curves shift
up or down, thesis fig. 5.10); ``True`` draws a new set at every line (imitates
measurement noise, fig. 5.11).

The band is the minimum and maximum of ``|v_e|`` over the rounds at every line and
DOF (the thesis' corridor), plus percentiles. Random numbers are counter based
(:mod:`._rng`): the factors of round ``r`` at line ``l`` are a pure function of
``(seed, r, l)``, so :meth:`ScatterBand.round` regenerates any round alone, and the
rounds are processed in chunks of lines whose size is bounded by ``max_chunk_bytes``
(R = 10,000 rounds over 2,000 lines and 6 DOFs: about 64 MB of working memory).
"""

from __future__ import annotations

import threading
import warnings
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray, IntArray
from ..errors import DataFormatError, FBSError, StudyCancelled
from ..frf import check_grid
from ..harmonics import Harmonic
from ..vocabulary import DIRECTIONS, magnitude_db
from ..vocabulary import readonly as _ro
from . import _models, _noise_kernels
from ._finite import require_finite
from ._rng import as_seed, seed_key
from .band_kernel import (
    LOCK,
    TARGETS,
    BandStats,
    KernelArrays,
    band_lines,
    kernel_arrays,
    noise_flags,
    reference_response,
    responses,
    target_name,
)

#: Largest number of Monte-Carlo rounds of one band (one line's working memory,
#: ``8 R n_e`` bytes, stays below 50 MB for six responses).
MAX_ROUNDS = 1_000_000

__all__ = [
    "EDGES_JUDGED_WITHIN_DB",
    "TARGETS",
    "ScatterBand",
    "Convergence",
    "scatter_band",
    "scatter_band_arrays",
    "target_name",
]

#: Default bound of one chunk's duration (s): the band asks ``cancel`` (and takes its
#: turn) between chunks, so this is how long a cancel or another study waits at most.
CHUNK_SECONDS = 0.1
#: Measured seconds per round and line of the parallel kernel, by ``(n_j, n_e,
#: frequency_dependent)``: sizes the first chunk of the next band (see ``max_chunk_seconds``)
_RATE: dict[tuple[int, int, bool], float] = {}
#: Rounds x lines of a first chunk when no rate is known yet (a few ms of work)
_PROBE = 50_000
#: The process-wide lock of the parallel kernel (:data:`.band_kernel.LOCK`, the same object)
_LOCK = LOCK
_Inputs = tuple[KernelArrays, np.uint64]


def _renamed_edge(cls: str, old: str, new: str) -> None:
    warnings.warn(
        f"{cls}.{old} is deprecated (it is the {new} over the rounds, not a percentile); "
        f"use {cls}.{new}",
        DeprecationWarning,
        stacklevel=3,
    )


def _db(x: FloatArray) -> FloatArray:
    return magnitude_db(x, floor=None)  # ratios of magnitudes: -inf at 0, no floor


@dataclass(frozen=True, eq=False)
class Convergence:
    """Band edges after the first ``rounds[k]`` rounds, to judge whether ``R`` is enough.

    The thesis chose ``R`` "so that the borders stopped changing"; here the edges
    are recorded at checkpoints as rounds are added.

    Attributes
    ----------
    rounds : ndarray of int, shape (n_k,)
        Checkpoints, ascending; the last is the total number of rounds.
    minimum, maximum : ndarray, shape (n_k, n_f, n_dof)
        Running minimum and maximum of ``|v_e|`` (the band's lower and upper edges;
        ``lower`` / ``upper`` are their deprecated names).
    """

    rounds: IntArray
    minimum: FloatArray
    maximum: FloatArray

    @property
    def lower(self) -> FloatArray:
        """Deprecated name of :attr:`minimum` (one release)."""
        _renamed_edge("Convergence", "lower", "minimum")
        return self.minimum

    @property
    def upper(self) -> FloatArray:
        """Deprecated name of :attr:`maximum` (one release)."""
        _renamed_edge("Convergence", "upper", "maximum")
        return self.maximum

    @property
    def upper_change_db(self) -> FloatArray:
        """Largest gap (dB, over lines and DOFs) between the upper edge at each
        checkpoint and the final one, shape ``(n_k,)``; 0 at the last checkpoint."""
        gap: FloatArray = np.nanmax(_db(self.maximum[-1] / self.maximum), axis=(1, 2))
        return gap

    @property
    def lower_change_db(self) -> FloatArray:
        """Largest gap (dB) between the lower edge at each checkpoint and the final one."""
        gap: FloatArray = np.nanmax(_db(self.minimum / self.minimum[-1]), axis=(1, 2))
        return gap

    @cached_property
    def step_change_db(self) -> FloatArray:
        """Largest change (dB) of either edge from one checkpoint to the next, ``(n_k - 1,)``.

        Computed once per band (read-only): every page showing the band asks for it."""
        up: FloatArray = np.nanmax(_db(self.maximum[1:] / self.maximum[:-1]), axis=(1, 2))
        lo: FloatArray = np.nanmax(_db(self.minimum[:-1] / self.minimum[1:]), axis=(1, 2))
        return _ro(np.maximum(up, lo))

    def summary(self) -> str:
        """One line per checkpoint: rounds and the remaining change of both edges in dB."""
        lines = ["rounds   upper edge to final (dB)   lower edge to final (dB)"]
        for r, u, lo in zip(self.rounds, self.upper_change_db, self.lower_change_db, strict=True):
            lines.append(f"{int(r):>6d}   {u:24.3f}   {lo:24.3f}")
        return "\n".join(lines)


#: The lines a band's edges are judged on by default: within this many dB of the peak of
#: the unpolluted response at each DOF (:meth:`ScatterBand.percentile_confidence_db`).
EDGES_JUDGED_WITHIN_DB = 30.0
#: Normal quantile of a two-sided 95 % confidence.
Z95_TWO_SIDED = 1.959963984540054


def _interp_levels(q: FloatArray, lv: FloatArray, x: float) -> FloatArray:
    """The levels ``lv`` (n_q, ...) at the percentile ``x``, linear between stored ones."""
    i = int(np.clip(np.searchsorted(q, x) - 1, 0, q.size - 2))
    t = (x - q[i]) / (q[i + 1] - q[i])
    out: FloatArray = (1 - t) * lv[i] + t * lv[i + 1]
    return out


@dataclass(frozen=True, eq=False)
class ScatterBand:
    """Noise corridor of the coupled response (thesis figs. 5.9-5.11).

    Attributes
    ----------
    freq : ndarray, shape (n_f,)
        Frequency lines in Hz.
    dofs : tuple of str, length n_dof
        Response DOF labels.
    reference : ndarray, shape (n_f, n_dof)
        Unpolluted complex response (exactly the kernel's result with all factors 1).
    minimum, maximum : ndarray, shape (n_f, n_dof)
        Minimum and maximum of ``|v_e|`` over the rounds (the corridor's edges; ``lower`` /
        ``upper`` are their deprecated names, kept for one release).
    argmin_round, argmax_round : ndarray of int, shape (n_f, n_dof)
        First round attaining them (regenerate it with :meth:`round`).
    q : ndarray, shape (n_q,)
        Percentile levels in % (e.g. 5, 95).
    percentiles : ndarray, shape (n_q, n_f, n_dof)
        Percentiles of ``|v_e|`` over the rounds (numpy's "linear" definition).
    convergence : Convergence
    noise : float
        The noise level ``p`` as a fraction (0.1 = factors in [0.9, 1.1]).
    target, rounds, frequency_dependent, seed, harmonic
        The other settings.
    """

    freq: FloatArray
    dofs: tuple[str, ...]
    reference: ComplexArray
    minimum: FloatArray
    maximum: FloatArray
    argmin_round: IntArray
    argmax_round: IntArray
    q: FloatArray
    percentiles: FloatArray
    convergence: Convergence
    noise: float
    target: str
    rounds: int
    frequency_dependent: bool
    seed: int
    harmonic: int | None
    _inputs: _Inputs

    @classmethod
    def of_kernel(cls, arrays: KernelArrays, seed: int, **fields: Any) -> ScatterBand:
        """The band of the statistics ``fields`` (all attributes but ``seed``) whose rounds
        :meth:`round` regenerates from the kernel arrays of :func:`.band_kernel.kernel_arrays`
        and the seed (e.g. a band assembled from blocks of lines computed elsewhere)."""
        seed = int(seed)
        return cls(seed=seed, _inputs=(arrays, seed_key(seed)), **fields)

    @property
    def lower(self) -> FloatArray:
        """Deprecated name of :attr:`minimum` (one release)."""
        _renamed_edge("ScatterBand", "lower", "minimum")
        return self.minimum

    @property
    def upper(self) -> FloatArray:
        """Deprecated name of :attr:`maximum` (one release)."""
        _renamed_edge("ScatterBand", "upper", "maximum")
        return self.maximum

    def _dof(self, dof: str | int) -> int:
        if isinstance(dof, str):
            if dof not in self.dofs:
                from ..errors import DOFError

                raise DOFError(f"unknown response DOF {dof!r}; available: {', '.join(self.dofs)}")
            return self.dofs.index(dof)
        return int(dof)

    #: Regenerated rounds kept per band (:meth:`round`): the pages showing a band draw the
    #: same few rounds again for every DOF and percentile change.
    ROUND_CACHE = 4

    def round(self, r: int) -> ComplexArray:
        """The complex response of round ``r``, shape ``(n_f, n_dof)``, regenerated alone.

        Identical (bit for bit) to the round inside the batch. Read-only: the last
        :attr:`ROUND_CACHE` rounds asked for are kept with the band.

        Raises
        ------
        FBSError
            For ``r`` outside ``0 .. rounds - 1``.
        """
        r = int(r)
        cache, lock = self._round_cache
        with lock:
            v = cache.get(r)
            if v is not None:
                cache.move_to_end(r)
                return v
        v = _ro(self.rounds_response([r])[0])
        with lock:
            cache[r] = v
            while len(cache) > self.ROUND_CACHE:
                cache.popitem(last=False)
        return v

    @cached_property
    def _round_cache(self) -> tuple[OrderedDict[int, ComplexArray], threading.Lock]:
        return OrderedDict(), threading.Lock()

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without the cache of regenerated rounds and its lock (a band crosses to
        another process with a report's data; the rounds are regenerated there)."""
        state = dict(self.__dict__)
        state.pop("_round_cache", None)
        return state

    def rounds_response(self, rounds: ArrayLike) -> ComplexArray:
        """Complex responses of several rounds, shape ``(n, n_f, n_dof)``."""
        rids = np.atleast_1d(np.asarray(rounds, np.int64))
        if rids.ndim != 1 or np.any((rids < 0) | (rids >= self.rounds)):
            raise FBSError(f"round indices must be in 0..{self.rounds - 1}, got {rids.tolist()}")
        arrays, key = self._inputs
        tire, chassis = noise_flags(self.target)
        return responses(arrays, key, rids, self.noise, tire, chassis, self.frequency_dependent)

    def peak_round(self, freq: float, dof: str | int, which: str = "max") -> int:
        """The round giving the highest (``"max"``) or lowest (``"min"``) ``|v_e|`` at the
        line nearest ``freq`` (the curves of thesis figs. 5.10-5.11)."""
        if which not in ("max", "min"):
            raise FBSError(f"which must be 'max' or 'min', got {which!r}")
        line = int(np.argmin(np.abs(self.freq - freq)))
        arr = self.argmax_round if which == "max" else self.argmin_round
        return int(arr[line, self._dof(dof)])

    def percentile_interval_db(
        self, edge: float, z: float = Z95_TWO_SIDED
    ) -> tuple[FloatArray, FloatArray]:
        """The confidence interval (dB) of the band's ``edge`` % percentile at every line
        and DOF: ``(low, high)``, arrays of shape ``(n_f, n_dof)``.

        The rank of the empirical q-quantile of R independent rounds is binomial, so the
        true quantile lies between the empirical quantiles of ``q -+ z sqrt(q (1 - q) / R)``
        with the normal confidence of ``z`` (1.96: 95 %; distribution-free, from order
        statistics); those are read off the stored percentiles, interpolated linearly in
        ``q`` (and clipped to the stored ones).
        """
        q = np.asarray(self.q, float)
        lv = magnitude_db(np.asarray(self.percentiles, float))  # (n_q, n_f, n_dof)
        r = max(int(self.rounds), 1)
        dq = 100 * z * np.sqrt(edge / 100 * (1 - edge / 100) / r)
        lo = float(np.clip(edge - dq, q[0], q[-1]))
        hi = float(np.clip(edge + dq, q[0], q[-1]))
        return _interp_levels(q, lv, lo), _interp_levels(q, lv, hi)

    def percentile_confidence_db(
        self, width: float = 90, within_db: float = EDGES_JUDGED_WITHIN_DB
    ) -> float:
        """How well R rounds fix the central percentile band: the largest 95 % confidence
        half-width (dB, :meth:`percentile_interval_db`) of its two edges over the lines
        within ``within_db`` of each DOF's peak. It falls as ``1 / sqrt(R)``: four times
        the rounds halve it. (The minimum and maximum over the rounds are extreme values
        that do not settle as rounds are added; the percentiles do.)

        Parameters
        ----------
        width : float
            The central band in percent (90: the 5 % and 95 % percentiles; the band must
            hold them and neighbours on both sides).
        within_db : float
            Lines more than this below a DOF's peak reference level are left out (the deep
            antiresonances, where a level in dB swings from round to round).

        Returns
        -------
        float
            dB; NaN when no line qualifies.
        """
        q = np.asarray(self.q, float)
        lv = magnitude_db(np.asarray(self.percentiles, float))
        ref = magnitude_db(np.abs(np.asarray(self.reference)))  # (n_f, n_dof)
        keep = ref >= np.nanmax(ref, axis=0, keepdims=True) - within_db
        worst = np.nan
        for edge in ((100 - width) / 2, (100 + width) / 2):
            at = lv[int(np.argmin(np.abs(q - edge)))]
            low, high = self.percentile_interval_db(edge)
            half = np.where(keep, np.maximum(at - low, high - at), np.nan)
            if np.isfinite(half).any():
                top = float(np.nanmax(half))
                worst = top if worst != worst else max(worst, top)
        return float(worst)

    def factors(self, r: int, line: int = 0) -> dict[str, FloatArray]:
        """The scaling factors of round ``r`` at line index ``line``:
        ``{"Yjj_A": (n_j, n_j), "vj_A": (n_j,), "Yjj_E": (n_j, n_j), "Yej_E": (n_e, n_j)}``
        (1 where no noise is applied; ``line`` is ignored without frequency dependence)."""
        arrays, key = self._inputs
        nj, ne = arrays[2].shape[1], arrays[6].shape[1]
        tire, vehicle = noise_flags(self.target)
        stream_line = line if self.frequency_dependent else 0
        s = _noise_kernels.noise_factors(
            key, np.array([r], np.int64), np.array([stream_line]), self.noise, nj, ne, tire, vehicle
        )[0]
        return split_factors(s, nj, ne)


def split_factors(s: FloatArray, nj: int, ne: int) -> dict[str, FloatArray]:
    """The four scaling arrays of one stream of factors (layout of :mod:`._noise_kernels`)."""
    o1, o2, o3 = nj * nj, nj * nj + nj, 2 * nj * nj + nj
    return {
        "Yjj_A": s[..., :o1].reshape(s.shape[:-1] + (nj, nj)),
        "vj_A": s[..., o1:o2],
        "Yjj_E": s[..., o2:o3].reshape(s.shape[:-1] + (nj, nj)),
        "Yej_E": s[..., o3 : o3 + ne * nj].reshape(s.shape[:-1] + (ne, nj)),
    }


def _chunk_lines(seconds: float | None, rate: float | None, rounds: int, max_lines: int) -> int:
    """Lines of the next chunk: within ``seconds`` at ``rate`` (s per round and line), a
    probe of about :data:`_PROBE` round-lines when the rate is not known, at least one line
    and at most ``max_lines`` (the memory bound)."""
    if seconds is None:
        return max_lines
    if rate is None:
        return int(max(1, min(max_lines, _PROBE // rounds)))
    return int(max(1, min(max_lines, seconds / (rate * rounds))))


def default_checkpoints(rounds: int) -> IntArray:
    """1-2-5 steps from 10 up to ``rounds`` (always ending at ``rounds``)."""
    out: list[int] = []
    dec = 10
    while dec < rounds:
        out += [m * dec for m in (1, 2, 5) if m * dec < rounds]
        dec *= 10
    return np.array(out + [rounds], np.int64)


def scatter_band_arrays(
    YjjA: ArrayLike,
    vj: ArrayLike,
    YjjE: ArrayLike,
    YejE: ArrayLike,
    noise: float = 0.1,
    target: str = "both",
    rounds: int = 10_000,
    frequency_dependent: bool = False,
    seed: int | np.integer[Any] | np.random.Generator = 0,
    *,
    freq: ArrayLike | None = None,
    dofs: Sequence[str] | None = None,
    harmonic: int | None = None,
    percentiles: ArrayLike = (5.0, 95.0),
    checkpoints: ArrayLike | None = None,
    max_chunk_bytes: float = 64e6,
    max_chunk_seconds: float | None = CHUNK_SECONDS,
    cancel: Callable[[], bool] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> ScatterBand:
    """The scatter band from arrays (the kernel behind :func:`scatter_band`).

    Parameters
    ----------
    YjjA : ndarray, shape (n_f, n_j, n_j)
        Tire mobility at the interface ``Y_jj^A``.
    vj : ndarray, shape (n_f, n_j)
        Free interface velocity of the tire ``Y_ja^A F_a``.
    YjjE : ndarray, shape (n_f, n_j, n_j)
        Chassis mobility at the interface ``Y_jj^E``.
    YejE : ndarray, shape (n_f, n_e, n_j)
        Chassis transfer mobility ``Y_ej^E``.
    noise : float
        ``p``: factors uniform in ``[1 - p, 1 + p]`` (0.1 = +-10 %), ``0 <= p < 1``.
    target : {"tire", "chassis", "both"}
        Eq. 5.2, 5.3 or 5.4.
    rounds : int
        Number of rounds ``R``.
    frequency_dependent : bool
        New factors at every line (True) or one set per round (False).
    seed : int or numpy.random.Generator
        Reproducibility key (a generator contributes one draw).
    freq : array_like, optional
        Frequencies of the lines (default ``0, 1, ...``); ``dofs`` response labels.
    percentiles : sequence of float
        Percentile levels in %.
    checkpoints : sequence of int, optional
        Round counts at which the band edges are recorded (default 10, 20, 50, ...).
    max_chunk_bytes : float
        Working-memory bound of one chunk of lines (``8 R n_e`` bytes per line).
    max_chunk_seconds : float or None
        Duration bound of one chunk of lines (default :data:`CHUNK_SECONDS`, 0.1 s): each
        chunk gets as many lines as the measured time per line of the previous chunk (or
        of the last band of the same shape) allows within it, at least one line. Chunks
        never change the result; short ones let ``cancel`` act (and other studies take
        their turn) within about this time. None: chunks bounded by memory only.
    cancel : callable, optional
        Called without arguments before each chunk of lines; when it returns True the
        study stops with :class:`~fbs_core.errors.StudyCancelled` (a dashboard whose
        settings changed). It may also wait (e.g. to take turns with other studies).
    progress : callable, optional
        Called as ``progress(lines_done, lines_total)`` before the first chunk of lines and
        after each one (a progress indicator: done/total and the time left).

    Returns
    -------
    ScatterBand

    Raises
    ------
    StudyCancelled
        When ``cancel()`` returned True.
    FBSError
        For a bad noise level, target, round count, percentile or checkpoint.
    DataFormatError
        For arrays of the wrong shapes or with non-finite values.
    SingularInterfaceError
        If the (noisy) interface matrix is singular at some line.
    """
    arrays = kernel_arrays(YjjA, vj, YjjE, YejE)
    nf, nj = arrays[2].shape
    ne = arrays[6].shape[1]
    if not (0.0 <= noise < 1.0):
        raise FBSError(f"noise must be in [0, 1) (0.1 = +-10 %), got {noise!r}")
    target = target_name(target)
    tire, chassis = noise_flags(target)
    if isinstance(rounds, bool) or not isinstance(rounds, int | np.integer) or rounds < 1:
        raise FBSError(f"rounds must be a positive integer, got {rounds!r}")
    if rounds > MAX_ROUNDS:
        raise FBSError(
            f"rounds must be at most {MAX_ROUNDS:,} (the band edges settle long before; "
            f"see the convergence checkpoints), got {rounds:,}"
        )
    rounds = int(rounds)
    qs = np.atleast_1d(np.asarray(percentiles, float))
    if qs.ndim != 1 or np.any(~np.isfinite(qs) | (qs < 0) | (qs > 100)):
        raise FBSError(f"percentiles must be levels in [0, 100] %, got {qs.tolist()}")
    ck = default_checkpoints(rounds) if checkpoints is None else np.asarray(checkpoints, np.int64)
    if ck.ndim != 1 or ck.size == 0 or np.any(np.diff(ck) <= 0) or ck[0] < 1 or ck[-1] > rounds:
        raise FBSError(
            f"checkpoints must be ascending round counts in 1..{rounds}, "
            f"got {np.asarray(checkpoints).tolist()}"
        )
    if ck[-1] != rounds:
        ck = np.append(ck, rounds)
    f = np.arange(nf, dtype=float) if freq is None else check_grid(freq)
    if f.size != nf:
        raise DataFormatError(f"{f.size} frequencies for {nf} lines")
    if dofs is None:
        dofs = tuple(f"bushing:{d}" for d in DIRECTIONS)[:ne]
    dofs = tuple(dofs)
    if len(dofs) != ne:
        raise DataFormatError(f"{len(dofs)} response labels for {ne} response DOFs")
    seed = as_seed(seed)
    key = seed_key(seed)

    ref = reference_response(arrays)
    st = BandStats.empty(nf, ne, qs.size, ck.size)
    per_line = 8 * ne * rounds
    max_lines = int(max(1, min(nf, max_chunk_bytes // per_line)))
    mag = np.empty((max_lines, ne, rounds))
    rids = np.arange(rounds, dtype=np.int64)
    shape = (nj, ne, bool(frequency_dependent))
    rate = _RATE.get(shape) if max_chunk_seconds is not None else None
    chunk = _chunk_lines(max_chunk_seconds, rate, rounds, max_lines)
    if progress is not None:
        progress(0, nf)
    l0 = 0
    while l0 < nf:
        if cancel is not None and cancel():
            raise StudyCancelled(f"scatter band cancelled after {l0} of {nf} lines")
        l1 = min(nf, l0 + chunk)
        if nf - l1 < chunk // 4:  # no short tail chunk (one turn more for a few lines)
            l1 = min(nf, l0 + max_lines)
        spent = band_lines(
            arrays, l0, l1, key, rids, noise, tire, chassis, bool(frequency_dependent), qs, ck, st,
            row=l0, work=mag,
        )  # fmt: skip
        if max_chunk_seconds is not None:
            rate = _RATE[shape] = max(spent, 1e-9) / ((l1 - l0) * rounds)
            chunk = _chunk_lines(max_chunk_seconds, rate, rounds, max_lines)
        if progress is not None:
            progress(l1, nf)
        l0 = l1
    del mag
    lo, hi = st.minimum, st.maximum
    for name, x in (("reference", np.abs(ref)), ("upper edge", hi), ("lower edge", lo)):
        require_finite(
            x,
            f,
            f"{name} of the scatter band",
            "the (noisy) interface matrix Y_jj^A + Y_jj^E is singular there",
        )
    return ScatterBand(
        freq=_ro(f),
        dofs=dofs,
        reference=_ro(ref),
        minimum=_ro(lo),
        maximum=_ro(hi),
        argmin_round=_ro(st.argmin_round),
        argmax_round=_ro(st.argmax_round),
        q=_ro(qs),
        percentiles=_ro(st.percentiles),
        convergence=Convergence(_ro(ck), _ro(st.conv_minimum), _ro(st.conv_maximum)),
        noise=float(noise),
        target=target,
        rounds=rounds,
        frequency_dependent=bool(frequency_dependent),
        seed=seed,
        harmonic=harmonic,
        _inputs=(arrays, key),
    )


#: Subsystem arrays of the last few bands, so that a band differing only in its noise
#: settings (seed, level, target, rounds) does not synthesise the tire again: key ->
#: ``(tire, chassis, arrays)``; the models are held to check identity (no id reuse).
_Subsystems = tuple[ComplexArray, ComplexArray, ComplexArray, ComplexArray, tuple[str, ...]]
_INPUTS: OrderedDict[tuple[Any, ...], tuple[Any, Any, _Subsystems]] = OrderedDict()
_INPUTS_SIZE = 8
_INPUTS_LOCK = threading.Lock()


def _subsystem_arrays(
    tire: Any, chassis: Any, f: FloatArray, h: Harmonic, n: int, dirs: tuple[str, ...]
) -> _Subsystems:
    """``(Y_jj^A, v_j, Y_jj^E, Y_ej^E, response labels)`` of one band, read-only, cached.

    Models are immutable; they are matched by identity (``chassis`` None: the reference).
    """
    key = (id(tire), id(chassis), h.k, f.tobytes(), n, dirs)
    with _INPUTS_LOCK:
        hit = _INPUTS.get(key)
        if hit is not None and hit[0] is tire and hit[1] is chassis:
            _INPUTS.move_to_end(key)
            return hit[2]
    YjjE, YejE, resp = _models.chassis_arrays(chassis, f, dirs)
    YjjA, vj = _models.tire_arrays(tire, f, h, [n], dirs)
    out = (_ro(YjjA[0]), _ro(vj[0]), _ro(YjjE), _ro(YejE), resp)
    with _INPUTS_LOCK:
        _INPUTS[key] = (tire, chassis, out)
        _INPUTS.move_to_end(key)
        while len(_INPUTS) > _INPUTS_SIZE:
            _INPUTS.popitem(last=False)
    return out


def scatter_band(
    harmonic: int | Harmonic,
    noise: float = 0.1,
    target: str = "both",
    rounds: int = 10_000,
    frequency_dependent: bool = False,
    seed: int | np.integer[Any] | np.random.Generator = 0,
    *,
    n_modes: int | None = None,
    freq: ArrayLike | None = None,
    df: float = 0.5,
    tire: Any = None,
    chassis: Any = None,
    coupling: str | Sequence[str] = "6dof",
    percentiles: ArrayLike = (5.0, 95.0),
    checkpoints: ArrayLike | None = None,
    max_chunk_bytes: float = 64e6,
    max_chunk_seconds: float | None = CHUNK_SECONDS,
    cancel: Callable[[], bool] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> ScatterBand:
    """Noise scatter band of the bushing response for one harmonic (thesis 5.2, eqs. 5.2-5.4).

    Parameters
    ----------
    harmonic : int or Harmonic
        Excitation case 1..7.
    noise, target, rounds, frequency_dependent, seed
        See :func:`scatter_band_arrays`.
    n_modes : int, optional
        Retained tire modes (default all).
    freq : array_like, optional
        Frequency lines in Hz; default ``harmonic.frequencies(df)``.
    tire, chassis : optional
        Models (default the reference ones); ``chassis`` may be an FRF on ``freq``.
    coupling : {"6dof", "5dof"} or sequence of directions
    percentiles, checkpoints, max_chunk_bytes, max_chunk_seconds, cancel, progress
        See :func:`scatter_band_arrays`.

    Returns
    -------
    ScatterBand

    Examples
    --------
    >>> import fbs_core
    >>> band = fbs_core.scatter_band(4, noise=0.1, rounds=1000)    # doctest: +SKIP
    >>> r = band.peak_round(42.0, "bushing:z")                     # doctest: +SKIP
    >>> curve = band.round(r)                                      # doctest: +SKIP
    """
    target = target_name(target)
    h = _models.resolve_harmonic(harmonic)
    tire = _models.resolve_tire(tire)
    dirs = _models.coupled_directions(coupling)
    f = h.frequencies(df) if freq is None else check_grid(freq)
    n_total = _models.total_modes(tire)
    n = n_total if n_modes is None else int(n_modes)
    if not 1 <= n <= n_total:
        raise FBSError(f"n_modes must be in 1..{n_total} (the tire's modes), got {n_modes!r}")
    YjjA, vj, YjjE, YejE, resp = _subsystem_arrays(tire, chassis, f, h, n, dirs)
    return scatter_band_arrays(
        YjjA,
        vj,
        YjjE,
        YejE,
        noise,
        target,
        rounds,
        frequency_dependent,
        seed,
        freq=f,
        dofs=resp,
        harmonic=h.k,
        percentiles=percentiles,
        checkpoints=checkpoints,
        max_chunk_bytes=max_chunk_bytes,
        max_chunk_seconds=max_chunk_seconds,
        cancel=cancel,
        progress=progress,
    )
