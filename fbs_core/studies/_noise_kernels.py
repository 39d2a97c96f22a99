"""Compiled kernels of the noise study: small complex solves, noisy eq. 4.1, band statistics.

Everything here works on plain arrays (no labels). Per frequency line ``l``:

- ``A[l]`` ``(n_j, n_j)`` tire hub mobility ``Y_jj^A``,
- ``a[l]`` ``(n_j,)`` free hub velocity of the tire ``Y_ja^A F_a``,
- ``E[l]`` ``(n_j, n_j)`` chassis spindle mobility ``Y_jj^E``,
- ``B[l]`` ``(n_e, n_j)`` chassis transfer mobility ``Y_ej^E``,

and the noisy response of thesis eqs. 5.2-5.4 is

    v_e = (S_B o B) [ (S_A o A) + (S_E o E) ]^-1 (s_a o a)

(``o`` the element-wise product). The scaling factors of one round and line are
consecutive segments of one counter-based stream (:mod:`._rng`)::

    elements [0, n_j^2)                       S_A  (row major)
             [n_j^2, n_j^2 + n_j)             s_a
             [n_j^2 + n_j, 2 n_j^2 + n_j)     S_E  (row major)
             [2 n_j^2 + n_j, ... + n_e n_j)   S_B  (row major)

so tire-only noise uses exactly the tire factors of the same round with noise in
both subsystems. ``n_j (n_j + 1)`` is even, so the tire part ends on a word boundary.

Speed: the solves run on ``LANES`` rounds at once in structure-of-arrays layout
(real and imaginary parts apart, rounds innermost), so that the compiler vectorises
the elimination over rounds; partial pivoting is decided per round (lane). The rows
of every line enter in the pivot order of the noise-free matrix (:func:`pivot_order`),
so that row exchanges, which cannot be vectorised, are rare in the noisy lanes.
"""

from __future__ import annotations

from typing import Literal, TypedDict

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike, NDArray

from .._typing import ComplexArray, FloatArray, IntArray
from ._rng import GOLDEN, mix64, mix64_np


# nogil: a band computed for one dashboard session must not stall the event loop that
# serves all the others
class _JitOptions(TypedDict):
    cache: bool
    fastmath: bool | set[str]
    error_model: Literal["python", "numpy"]
    nogil: bool


_JIT = _JitOptions(cache=True, fastmath=False, error_model="numpy", nogil=True)
#: The solve's options: fused multiply-add allowed ("contract"; the updates are written as
#: ``w - m_r b_r + m_i b_i``, two FMAs each), no other fast-math flag (NaN and inf keep
#: their meaning). The factors and the magnitudes stay uncontracted: numpy recomputes
#: both bit for bit (:func:`noise_factors`, the tests' ``sqrt(re**2 + im**2)``).
_JIT_FMA = _JitOptions(cache=True, fastmath={"contract"}, error_model="numpy", nogil=True)

#: Rounds solved together in one vectorised block: per-loop overhead (index arithmetic,
#: alias checks) dominates below; 128 measured faster than 64 and as fast as 256.
LANES = 128

_ONE = np.uint64(1)
_S32 = np.uint64(32)
_LO32 = np.uint64(0xFFFFFFFF)
_INV32 = 2.0**-32
#: The bits of the float64 2**21, whose mantissa step is 2**-31: OR-ed with a 32-bit ``u``
#: they are the float64 ``2**21 + u 2**-31``.
_EXP21 = np.uint64(0x4140000000000000)
#: ``(2**21 + u 2**-31) - (2**21 + 1)`` is ``2 u 2**-32 - 1`` exactly (a representable
#: difference), in one operation instead of four.
_SHIFT = 2.0**21 + 1.0


def n_elements(nj: int, ne: int) -> int:
    """Number of scaling factors per round and line."""
    return 2 * nj * nj + nj + ne * nj


# -- lanes of rounds ------------------------------------------------------------------------


@njit(**_JIT)
def _round_keys(key: np.uint64, rids: IntArray, base: NDArray[np.uint64]) -> None:
    """``base[3] = mix(key + (r + 1) G)`` of the ``LANES`` rounds ``rids``: the first level of
    :func:`._rng.stream_base`, the same at every line of a block of rounds."""
    for v in range(LANES):
        base[3, v] = mix64(key + (np.uint64(rids[v]) + _ONE) * GOLDEN)


@njit(**_JIT)
def _lane_factors(
    line: int,
    p: float,
    k0: int,
    k1: int,
    s: FloatArray,
    base: NDArray[np.uint64],
) -> None:
    """Factors of words ``k0 .. k1-1`` of the ``LANES`` rounds whose keys are in ``base[3]``
    (:func:`_round_keys`) at stream line ``line`` into ``s (n_el, LANES)`` (padded lanes cost
    nothing extra).

    ``base (4, LANES)`` is workspace: the lanes' stream bases, then the two halves of a
    word as the bits of ``2**21 + u 2**-31`` (``u`` the 32-bit half), read back as float64:
    ``(2**21 + u 2**-31) - (2**21 + 1)`` is exactly ``2 u 2**-32 - 1``, without the scalar
    integer conversion AVX2 lacks, so that the words of all lanes are hashed and
    converted in vector registers (bit for bit the factors of :func:`noise_factors`). Arrays
    are indexed in full, never sliced: a view costs two atomic reference counts.
    """
    n_el = s.shape[0]
    for v in range(LANES):
        base[0, v] = mix64(base[3, v] + (np.uint64(line) + _ONE) * GOLDEN)  # stream_base
    as_float = base.view(np.float64)
    for k in range(k0, k1):
        kk = (np.uint64(k) + _ONE) * GOLDEN
        e = 2 * k
        for v in range(LANES):
            w = mix64(base[0, v] + kk)
            base[1, v] = (w >> _S32) | _EXP21
            base[2, v] = (w & _LO32) | _EXP21
        for v in range(LANES):
            s[e, v] = 1.0 + p * (as_float[1, v] - _SHIFT)
        if e + 1 < n_el:
            for v in range(LANES):
                s[e + 1, v] = 1.0 + p * (as_float[2, v] - _SHIFT)


@njit(**_JIT_FMA)
def _lane_solve(
    Ar: FloatArray,
    Ai: FloatArray,
    ar: FloatArray,
    ai: FloatArray,
    Er: FloatArray,
    Ei: FloatArray,
    Br: FloatArray,
    Bi: FloatArray,
    order: IntArray,
    line: int,
    s: FloatArray,
    W: FloatArray,
    X: FloatArray,
    piv: IntArray,
    pm: FloatArray,
    Y: FloatArray,
) -> None:
    """Noisy eq. 4.1 at line ``line`` for all lanes: ``Y (2, n_e, LANES)`` (real and
    imaginary parts) from factors ``s``.

    Rows enter in ``order[line]`` (the partial-pivoting order of the noise-free matrix),
    which changes no result but makes row exchanges in the noisy lanes rare; each
    factor stays bound to its original matrix element. Workspace: ``W (2, n_j, n_j,
    LANES)`` the matrix and its LU factors, ``X (4, n_j, LANES)`` the solution and the
    reciprocal pivots. Arrays are indexed in full, never sliced (a view costs two atomic
    reference counts).
    """
    nj = Ar.shape[1]
    oa = nj * nj
    oE = oa + nj
    # interface matrix and right-hand side
    for i in range(nj):
        o = order[line, i]
        for k in range(nj):
            ia = o * nj + k
            ie = oE + o * nj + k
            A_r = Ar[line, o, k]
            A_i = Ai[line, o, k]
            E_r = Er[line, o, k]
            E_i = Ei[line, o, k]
            for v in range(LANES):
                W[0, i, k, v] = s[ia, v] * A_r + s[ie, v] * E_r
                W[1, i, k, v] = s[ia, v] * A_i + s[ie, v] * E_i
        a_r = ar[line, o]
        a_i = ai[line, o]
        for v in range(LANES):
            X[0, i, v] = s[oa + o, v] * a_r
            X[1, i, v] = s[oa + o, v] * a_i
    for k in range(nj):
        _pivot(W, X, k, piv, pm)
        _eliminate(W, X, k)
    _back_substitute(W, X)
    _transfer(Br, Bi, line, s, oE + oa, X, Y)


@njit(**_JIT_FMA)
def _pivot(W: FloatArray, X: FloatArray, k: int, piv: IntArray, pm: FloatArray) -> None:
    """Partial pivoting in column ``k``, per lane (pivot ``|Re| + |Im|``), rows of ``W``
    and ``X[:2]`` exchanged; the search runs in vector registers, the exchanges (rare:
    rows enter in the noise-free pivot order) lane by lane."""
    nj = W.shape[1]
    for v in range(LANES):
        pm[v] = abs(W[0, k, k, v]) + abs(W[1, k, k, v])
        piv[v] = k
    for i in range(k + 1, nj):
        for v in range(LANES):
            t = abs(W[0, i, k, v]) + abs(W[1, i, k, v])
            if t > pm[v]:
                pm[v] = t
                piv[v] = i
    swaps = 0
    for v in range(LANES):
        swaps += piv[v] != k
    if swaps == 0:
        return
    for v in range(LANES):
        q = piv[v]
        if q != k:
            for j in range(k, nj):
                for c in range(2):
                    t = W[c, k, j, v]
                    W[c, k, j, v] = W[c, q, j, v]
                    W[c, q, j, v] = t
            for c in range(2):
                t = X[c, k, v]
                X[c, k, v] = X[c, q, v]
                X[c, q, v] = t


@njit(**_JIT_FMA)
def _eliminate(W: FloatArray, X: FloatArray, k: int) -> None:
    """Step ``k`` of the LU elimination of ``W``, applied to ``x = X[:2]`` on the fly:
    ``X[2:4, k]`` the reciprocal pivot, the multipliers stored in place of column ``k``."""
    nj = W.shape[1]
    for v in range(LANES):
        pr = W[0, k, k, v]
        pi = W[1, k, k, v]
        # one division, two products: divisions are the slowest vector operation
        d = 1.0 / (pr * pr + pi * pi)
        X[2, k, v] = pr * d
        X[3, k, v] = -pi * d
    for i in range(k + 1, nj):
        # multipliers m = W[i, k] / W[k, k], stored in place of W[i, k]
        for v in range(LANES):
            wr = W[0, i, k, v]
            wi = W[1, i, k, v]
            W[0, i, k, v] = wr * X[2, k, v] - wi * X[3, k, v]
            W[1, i, k, v] = wr * X[3, k, v] + wi * X[2, k, v]
        for j in range(k + 1, nj):
            for v in range(LANES):
                mr = W[0, i, k, v]
                mi = W[1, i, k, v]
                W[0, i, j, v] = W[0, i, j, v] - mr * W[0, k, j, v] + mi * W[1, k, j, v]
                W[1, i, j, v] = W[1, i, j, v] - mr * W[1, k, j, v] - mi * W[0, k, j, v]
        for v in range(LANES):
            mr = W[0, i, k, v]
            mi = W[1, i, k, v]
            X[0, i, v] = X[0, i, v] - mr * X[0, k, v] + mi * X[1, k, v]
            X[1, i, v] = X[1, i, v] - mr * X[1, k, v] - mi * X[0, k, v]


@njit(**_JIT_FMA)
def _back_substitute(W: FloatArray, X: FloatArray) -> None:
    """``x = X[:2]`` from the upper triangle of ``W`` and the reciprocal pivots ``X[2:4]``."""
    nj = W.shape[1]
    for i in range(nj - 1, -1, -1):
        for j in range(i + 1, nj):
            for v in range(LANES):
                X[0, i, v] = X[0, i, v] - W[0, i, j, v] * X[0, j, v] + W[1, i, j, v] * X[1, j, v]
                X[1, i, v] = X[1, i, v] - W[0, i, j, v] * X[1, j, v] - W[1, i, j, v] * X[0, j, v]
        for v in range(LANES):
            cr = X[0, i, v]
            ci = X[1, i, v]
            X[0, i, v] = cr * X[2, i, v] - ci * X[3, i, v]
            X[1, i, v] = cr * X[3, i, v] + ci * X[2, i, v]


@njit(**_JIT_FMA)
def _transfer(
    Br: FloatArray, Bi: FloatArray, line: int, s: FloatArray, oB: int, X: FloatArray, Y: FloatArray
) -> None:
    """``v_e = (S_B o B) x`` into ``Y (2, n_e, LANES)``; ``S_B`` from row ``oB`` of ``s``."""
    ne, nj = Br.shape[1], Br.shape[2]
    for e in range(ne):
        for v in range(LANES):
            Y[0, e, v] = 0.0
            Y[1, e, v] = 0.0
        for k in range(nj):
            sb = oB + e * nj + k
            b_r = Br[line, e, k]
            b_i = Bi[line, e, k]
            for v in range(LANES):
                br = s[sb, v] * b_r
                bi = s[sb, v] * b_i
                Y[0, e, v] = Y[0, e, v] + br * X[0, k, v] - bi * X[1, k, v]
                Y[1, e, v] = Y[1, e, v] + br * X[1, k, v] + bi * X[0, k, v]


@njit(**_JIT)
def _workspace(
    nj: int, ne: int, n_el: int
) -> tuple[
    FloatArray, NDArray[np.uint64], FloatArray, FloatArray, FloatArray, IntArray, FloatArray
]:
    s = np.ones((n_el, LANES))
    base = np.empty((4, LANES), np.uint64)
    W = np.empty((2, nj, nj, LANES))
    X = np.empty((4, nj, LANES))
    Y = np.empty((2, ne, LANES))
    piv = np.empty(LANES, np.int64)
    pm = np.empty(LANES)
    return s, base, W, X, Y, piv, pm


@njit(**_JIT)
def _block_lines(
    b: int,
    Ar: FloatArray,
    Ai: FloatArray,
    ar: FloatArray,
    ai: FloatArray,
    Er: FloatArray,
    Ei: FloatArray,
    Br: FloatArray,
    Bi: FloatArray,
    order: IntArray,
    l0: int,
    l1: int,
    key: np.uint64,
    rids: IntArray,
    p: float,
    tire: bool,
    vehicle: bool,
    freq_dep: bool,
    mag: FloatArray,
    m0: int,
    cplx: ComplexArray,
    s: FloatArray,
    base: NDArray[np.uint64],
    W: FloatArray,
    X: FloatArray,
    Y: FloatArray,
    piv: IntArray,
    pm: FloatArray,
    lane_ids: IntArray,
) -> None:
    """Block ``b`` of ``LANES`` rounds at lines ``l0 .. l1-1`` in the given workspace
    (:func:`_workspace`, ``lane_ids`` ``LANES`` int64): ``|v_e|`` into
    ``mag[line - m0, e, round]`` if ``mag.size``, else the complex response into ``cplx``.
    Frequency-independent noise draws the factors once, at line ``l0``."""
    nj = Ar.shape[1]
    ne = Br.shape[1]
    n_el = 2 * nj * nj + nj + ne * nj
    k_tire = (nj * nj + nj) // 2
    k_all = (n_el + 1) // 2
    nr = rids.size
    want_mag = mag.size > 0
    r0 = b * LANES
    nv = min(LANES, nr - r0)
    for v in range(LANES):
        lane_ids[v] = rids[r0 + min(v, nv - 1)]  # pad with the last round (not written)
    _round_keys(key, lane_ids, base)
    # the words of the noisy subsystems (the tire's first): one call, one stream base a line
    k0 = 0 if tire else k_tire
    k1 = k_all if vehicle else k_tire
    for line in range(l0, l1):
        if (freq_dep or line == l0) and k0 < k1:
            _lane_factors(line if freq_dep else 0, p, k0, k1, s, base)
        _lane_solve(Ar, Ai, ar, ai, Er, Ei, Br, Bi, order, line, s, W, X, piv, pm, Y)
        if want_mag:
            for e in range(ne):
                for v in range(nv):
                    mag[line - m0, e, r0 + v] = np.sqrt(
                        Y[0, e, v] * Y[0, e, v] + Y[1, e, v] * Y[1, e, v]
                    )
        else:
            for e in range(ne):
                for v in range(nv):
                    cplx[r0 + v, line, e] = complex(Y[0, e, v], Y[1, e, v])


@njit(**_JIT)
def _block(
    b: int,
    Ar: FloatArray,
    Ai: FloatArray,
    ar: FloatArray,
    ai: FloatArray,
    Er: FloatArray,
    Ei: FloatArray,
    Br: FloatArray,
    Bi: FloatArray,
    order: IntArray,
    l0: int,
    l1: int,
    key: np.uint64,
    rids: IntArray,
    p: float,
    tire: bool,
    vehicle: bool,
    freq_dep: bool,
    mag: FloatArray,
    cplx: ComplexArray,
) -> None:
    """Block ``b`` of ``LANES`` rounds of :func:`noisy_block_run` (all its lines)."""
    nj = Ar.shape[1]
    ne = Br.shape[1]
    n_el = 2 * nj * nj + nj + ne * nj
    s, base, W, X, Y, piv, pm = _workspace(nj, ne, n_el)
    lane_ids = np.empty(LANES, np.int64)
    _block_lines(
        b, Ar, Ai, ar, ai, Er, Ei, Br, Bi, order, l0, l1, key, rids, p, tire, vehicle,
        freq_dep, mag, l0, cplx, s, base, W, X, Y, piv, pm, lane_ids,
    )  # fmt: skip


@njit(parallel=True, **_JIT)
def noisy_block_run(
    Ar: FloatArray,
    Ai: FloatArray,
    ar: FloatArray,
    ai: FloatArray,
    Er: FloatArray,
    Ei: FloatArray,
    Br: FloatArray,
    Bi: FloatArray,
    order: IntArray,
    l0: int,
    l1: int,
    key: np.uint64,
    rids: IntArray,
    p: float,
    tire: bool,
    vehicle: bool,
    freq_dep: bool,
    mag: FloatArray,
    cplx: ComplexArray,
) -> None:
    """Noisy responses of rounds ``rids`` at lines ``l0 .. l1-1``.

    ``order (n_f, n_j)`` is the row order of each line (:func:`pivot_order`).
    Writes ``|v_e|`` into ``mag (l1-l0, n_e, n_rounds)`` if ``mag.size`` (band mode),
    else the complex response into ``cplx (n_rounds, n_f, n_e)`` (regeneration mode).
    Lines are global indices, so a chunk of lines gives the same numbers as the whole.
    ``tire``/``vehicle`` select which factors are random (the others are 1);
    frequency-independent noise uses stream line 0 for every line. The blocks of
    ``LANES`` rounds run in parallel (numba's threading layer).
    """
    n_blocks = (rids.size + LANES - 1) // LANES
    for b in prange(n_blocks):
        _block(
            b, Ar, Ai, ar, ai, Er, Ei, Br, Bi, order, l0, l1, key, rids, p, tire, vehicle,
            freq_dep, mag, cplx,
        )  # fmt: skip


@njit(**_JIT)
def noisy_block_run_serial(
    Ar: FloatArray,
    Ai: FloatArray,
    ar: FloatArray,
    ai: FloatArray,
    Er: FloatArray,
    Ei: FloatArray,
    Br: FloatArray,
    Bi: FloatArray,
    order: IntArray,
    l0: int,
    l1: int,
    key: np.uint64,
    rids: IntArray,
    p: float,
    tire: bool,
    vehicle: bool,
    freq_dep: bool,
    mag: FloatArray,
    cplx: ComplexArray,
) -> None:
    """:func:`noisy_block_run` on the calling thread alone, bit for bit the same numbers.

    It never enters numba's threading layer, so any thread may run it at any time (no
    lock): the single rounds a page regenerates (one block of ``LANES`` rounds, which the
    parallel version would run on one thread anyway) never wait for another session's
    band.
    """
    n_blocks = (rids.size + LANES - 1) // LANES
    for b in range(n_blocks):
        _block(
            b, Ar, Ai, ar, ai, Er, Ei, Br, Bi, order, l0, l1, key, rids, p, tire, vehicle,
            freq_dep, mag, cplx,
        )  # fmt: skip


def pivot_order(A: ComplexArray, E: ComplexArray) -> IntArray:
    """Row order of partial pivoting (pivot ``|Re| + |Im|``) of ``A + E`` at every line.

    ``A, E`` complex ``(n_f, n, n)``; returns ``(n_f, n)`` int64: row ``i`` of the
    reordered system is original row ``order[l, i]``.
    """
    W = np.array(A + E, dtype=np.complex128)
    nf, n = W.shape[:2]
    order = np.tile(np.arange(n, dtype=np.int64), (nf, 1))
    lines = np.arange(nf)
    for k in range(n):
        col = W[:, k:, k]
        p = k + np.argmax(np.abs(col.real) + np.abs(col.imag), axis=1)
        W[lines, k], W[lines, p] = W[lines, p].copy(), W[lines, k].copy()
        order[lines, k], order[lines, p] = order[lines, p].copy(), order[lines, k].copy()
        piv = W[:, k, k]
        ok = piv != 0
        m = np.zeros((nf, n - k - 1), np.complex128)
        m[ok] = W[ok, k + 1 :, k] / piv[ok, None]
        W[:, k + 1 :, k:] -= m[:, :, None] * W[:, None, k, k:]
    return order


def noise_factors(
    key: int | np.uint64,
    rounds: ArrayLike,
    lines: ArrayLike,
    p: float,
    nj: int,
    ne: int,
    tire: bool,
    vehicle: bool,
) -> FloatArray:
    """The scaling factors of ``(rounds[i], lines[i])``, shape ``(n, n_elements)``.

    Plain numpy (uint64 arithmetic wraps modulo 2**64), bit-identical to the factors
    the compiled kernel draws; for inspecting single rounds.
    """
    n_el = n_elements(nj, ne)
    k_tire = (nj * nj + nj) // 2
    k_all = (n_el + 1) // 2
    r = np.asarray(rounds, np.int64).astype(np.uint64)
    ln = np.asarray(lines, np.int64).astype(np.uint64)
    with np.errstate(over="ignore"):
        base = mix64_np(mix64_np(np.uint64(key) + (r + _ONE) * GOLDEN) + (ln + _ONE) * GOLDEN)
        k = np.arange(k_all, dtype=np.uint64)
        w = mix64_np(base[:, None] + (k[None, :] + _ONE) * GOLDEN)
    u = np.empty((r.size, 2 * k_all))
    u[:, 0::2] = (w >> _S32).astype(np.float64) * _INV32
    u[:, 1::2] = (w & _LO32).astype(np.float64) * _INV32
    s = 1.0 + p * (2.0 * u[:, :n_el] - 1.0)
    out = np.ones((r.size, n_el))
    if tire:
        out[:, : 2 * k_tire] = s[:, : 2 * k_tire]
    if vehicle:
        out[:, 2 * k_tire :] = s[:, 2 * k_tire :]
    return out


# -- statistics over rounds -----------------------------------------------------------------


@njit(**_JIT)
def _select(buf: FloatArray, k: int, lo: int) -> None:
    """Partially sort ``buf[lo:]`` in place so that ``buf[k]`` is its k-th smallest (Hoare);
    ``buf[:lo]`` must already hold the ``lo`` smallest values."""
    hi = buf.size - 1
    while lo < hi:
        pivot = buf[(lo + hi) // 2]
        i = lo
        j = hi
        while i <= j:
            while buf[i] < pivot:
                i += 1
            while buf[j] > pivot:
                j -= 1
            if i <= j:
                t = buf[i]
                buf[i] = buf[j]
                buf[j] = t
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            return


@njit(**_JIT)
def _order_stat_pair(buf: FloatArray, k: int) -> tuple[float, float]:
    """``(x_(k), x_(k+1))``, 0-based order statistics of ``buf`` (reordered in place)."""
    _select(buf, k, 0)
    lo = buf[k]
    hi = lo
    if k + 1 < buf.size:
        hi = buf[k + 1]
        for i in range(k + 2, buf.size):
            if buf[i] < hi:
                hi = buf[i]
    return lo, hi


_SAMPLE = 256
_SLACK = 16  # sample ranks on either side of the target (about sqrt(_SAMPLE))


@njit(**_JIT)
def _order_stat_pair_sampled(
    col: FloatArray, k: int, sample: FloatArray, mid: FloatArray
) -> tuple[float, float]:
    """``(x_(k), x_(k+1))`` of ``col`` (unchanged) by sample-bracketed selection.

    A sorted stride sample of ``col`` gives bounds that bracket ranks ``k`` and
    ``k + 1`` with high probability (Floyd & Rivest, CACM 18(3), 1975); one pass counts
    the values below the bracket and collects those inside it into ``mid``, where
    the exact selection runs. Falls back to a full selection when the bracket misses.
    ``mid`` needs ``col.size + 1`` places.
    """
    n = col.size
    m = sample.size
    j = (k * m) // n
    a = j - _SLACK
    b = j + 1 + _SLACK
    lo_v = -np.inf if a < 0 else sample[a]
    hi_v = np.inf if b >= m else sample[b]
    below = 0
    nmid = 0
    for i in range(n):  # branch-free: unconditional store, conditional advance
        x = col[i]
        below += x < lo_v
        mid[nmid] = x
        nmid += (x >= lo_v) & (x <= hi_v)
    if below <= k and k + 1 < below + nmid:
        return _order_stat_pair(mid[:nmid], k - below)
    buf = col.copy()
    return _order_stat_pair(buf, k)


_BINS = 4096


@njit(**_JIT)
def _bin_indices(col: FloatArray, mn: float, scale: float) -> NDArray[np.int32]:
    """The histogram bin ``min(floor((x - mn) scale), _BINS - 1)`` of every value of ``col``
    (at least ``mn``), computed once for both passes of :func:`_order_stats_histogram` in a
    vectorised loop (no memory dependence between values); empty if ``col`` holds a NaN
    (whose bin would be no index at all)."""
    n = col.size
    bins = np.empty(n, np.int32)
    top = np.int32(_BINS - 1)
    nan = 0
    for i in range(n):
        x = col[i]
        nan += x != x
        bins[i] = min(np.int32((x - mn) * scale), top)
    if nan:
        return np.empty(0, np.int32)
    return bins


@njit(**_JIT)
def _order_stats_histogram(
    col: FloatArray, mn: float, mx: float, ranks: IntArray, out: FloatArray
) -> bool:
    """Order statistics ``x_(ranks[i])`` (0-based) of ``col`` (unchanged) into ``out``.

    One pass sorts the values into ``_BINS`` equal bins over ``[mn, mx]`` (the bin index
    ``floor((x - mn) * scale)`` is monotone in ``x``: every floating-point step is), the
    bin prefix counts locate each rank's bin, a second pass gathers the values of those
    few bins, and an exact selection runs inside each. Two passes serve all ranks (the
    sampled bracket needs one pass per percentile; the bins are computed once,
    :func:`_bin_indices`). Returns False, with nothing written, when a rank's bin is too
    full (heavy outliers stretch the bins) or the data are not finite (a NaN has no bin);
    the caller then falls back to :func:`_order_stat_pair_sampled`.
    """
    n = col.size
    if not (np.isfinite(mn) and np.isfinite(mx)) or mx <= mn:
        return False
    scale = _BINS / (mx - mn)
    if not np.isfinite(scale):
        return False
    bins = _bin_indices(col, mn, scale)
    if bins.size == 0:
        return False
    counts = np.zeros(_BINS, np.int64)
    for i in range(n):
        counts[bins[i]] += 1
    starts = np.empty(_BINS + 1, np.int64)
    starts[0] = 0
    for b in range(_BINS):
        starts[b + 1] = starts[b] + counts[b]
    cap = max(256, n // 16)
    fill = np.full(_BINS, -1, np.int64)
    rank_bin = np.empty(ranks.size, np.int64)
    total = 0
    for i in range(ranks.size):
        b = np.searchsorted(starts, ranks[i], side="right") - 1
        rank_bin[i] = b
        if fill[b] < 0:
            if counts[b] > cap:
                return False
            fill[b] = total
            total += counts[b]
    buf = np.empty(total + 1)
    for i in range(n):
        b = bins[i]
        o = fill[b]
        if o >= 0:
            buf[o] = col[i]
            fill[b] = o + 1
    for i in range(ranks.size):
        b = rank_bin[i]
        end = fill[b]  # one past the bin's segment after the gather
        seg = buf[end - counts[b] : end]
        k = ranks[i] - starts[b]
        _select(seg, k, 0)
        out[i] = seg[k]
    return True


#: Rounds per block of the minimum and maximum pass (:func:`_column_stats`): the first
#: round attaining an extreme is searched again inside its block only.
_BLOCK = 256


@njit(**_JIT)
def _running_extremes(col: FloatArray, a: int, b: int, mn: float, mx: float) -> tuple[float, float]:
    """``mn, mx`` updated by ``col[a:b]`` as ``v < mn`` / ``v > mx`` in round order would
    (NaN never wins, a NaN ``mn`` stays), in four independent chains that run in parallel."""
    l0 = l1 = l2 = l3 = mn
    h0 = h1 = h2 = h3 = mx
    n4 = a + (b - a) // 4 * 4
    for r in range(a, n4, 4):
        v0 = col[r]
        v1 = col[r + 1]
        v2 = col[r + 2]
        v3 = col[r + 3]
        l0 = v0 if v0 < l0 else l0
        l1 = v1 if v1 < l1 else l1
        l2 = v2 if v2 < l2 else l2
        l3 = v3 if v3 < l3 else l3
        h0 = v0 if v0 > h0 else h0
        h1 = v1 if v1 > h1 else h1
        h2 = v2 if v2 > h2 else h2
        h3 = v3 if v3 > h3 else h3
    for r in range(n4, b):
        v = col[r]
        l0 = v if v < l0 else l0
        h0 = v if v > h0 else h0
    # the chains started from mn, so any value below it is a value of col
    l0 = l1 if l1 < l0 else l0
    l2 = l3 if l3 < l2 else l2
    h0 = h1 if h1 > h0 else h0
    h2 = h3 if h3 > h2 else h2
    return (l2 if l2 < l0 else l0), (h2 if h2 > h0 else h0)


@njit(**_JIT)
def _first_index(col: FloatArray, start: int, x: float) -> int:
    """The first round from ``start`` on whose value is ``x`` (``start`` if none: NaN)."""
    for r in range(start, col.size):
        if col[r] == x:
            return r
    return start


@njit(**_JIT)
def _column_stats(
    col: FloatArray,
    qs: FloatArray,
    checkpoints: IntArray,
    lo: FloatArray,
    hi: FloatArray,
    arg_lo: IntArray,
    arg_hi: IntArray,
    pct: FloatArray,
    conv_lo: FloatArray,
    conv_hi: FloatArray,
    line: int,
    e: int,
) -> None:
    """The statistics of :func:`band_stats` of one column ``col (R,)`` (the rounds of
    line ``line``, response ``e``; ``col`` is not changed)."""
    R = col.size
    mn = col[0]
    mx = col[0]
    imn = 0  # start of the block where the minimum is first attained
    imx = 0
    kc = 0
    a = 0
    while a < R:
        end = min(a + _BLOCK, R)
        if kc < checkpoints.size and a < checkpoints[kc] < end:
            end = checkpoints[kc]
        bmn, bmx = _running_extremes(col, a, end, mn, mx)
        if bmn < mn:
            mn = bmn
            imn = a
        if bmx > mx:
            mx = bmx
            imx = a
        while kc < checkpoints.size and checkpoints[kc] == end:
            conv_lo[kc, line, e] = mn
            conv_hi[kc, line, e] = mx
            kc += 1
        a = end
    imn = _first_index(col, imn, mn)
    imx = _first_index(col, imx, mx)
    lo[line, e] = mn
    hi[line, e] = mx
    arg_lo[line, e] = imn
    arg_hi[line, e] = imx
    if qs.size == 0:
        return
    big = R > 4 * _SAMPLE
    from_hist = False
    if big:
        # all percentiles of the column from one histogram (two passes in all)
        ranks = np.empty(2 * qs.size, np.int64)
        for iq in range(qs.size):
            k = min(int(np.floor((R - 1) * qs[iq] / 100.0)), R - 2)
            ranks[2 * iq] = k
            ranks[2 * iq + 1] = k + 1
        stats = np.empty(2 * qs.size)
        from_hist = _order_stats_histogram(col, mn, mx, ranks, stats)
        if not from_hist:  # declined: sample-bracketed selection, one pass per level
            sample = np.empty(_SAMPLE)
            for i in range(_SAMPLE):
                sample[i] = col[(i * R) // _SAMPLE]
            sample.sort()
            mid = np.empty(R + 1)
    for iq in range(qs.size):
        h = (R - 1) * qs[iq] / 100.0
        k = int(np.floor(h))
        if k >= R - 1:
            pct[iq, line, e] = mx
            continue
        t = h - k
        if from_hist:
            a0 = stats[2 * iq]
            b0 = stats[2 * iq + 1]
        elif big:
            a0, b0 = _order_stat_pair_sampled(col, k, sample, mid)
        else:
            a0, b0 = _order_stat_pair(col.copy(), k)
        d = b0 - a0
        # numpy's _lerp: a + d t, evaluated from b for t >= 0.5
        pct[iq, line, e] = b0 - d * (1.0 - t) if t >= 0.5 else a0 + d * t


@njit(parallel=True, **_JIT)
def band_stats(
    mag: FloatArray,
    qs: FloatArray,
    checkpoints: IntArray,
    lo: FloatArray,
    hi: FloatArray,
    arg_lo: IntArray,
    arg_hi: IntArray,
    pct: FloatArray,
    conv_lo: FloatArray,
    conv_hi: FloatArray,
    l0: int,
) -> None:
    """Band statistics over the rounds of ``mag (n_l, n_e, R)`` (rounds last).

    Writes, for lines ``l0 .. l0 + n_l - 1`` of the outputs: minimum and maximum
    (``lo``, ``hi`` ``(n_f, n_e)``) and the first rounds attaining them
    (``arg_lo``, ``arg_hi``); the percentiles ``qs`` in % (``pct (n_q, n_f, n_e)``,
    numpy's default "linear" method); the running minimum and maximum after the
    first ``checkpoints[k]`` rounds (``conv_lo``, ``conv_hi`` ``(n_k, n_f, n_e)``,
    checkpoints ascending, each in ``1 .. R``).
    """
    nl, ne, R = mag.shape
    for c in prange(nl * ne):
        li = c // ne
        e = c - li * ne
        _column_stats(
            mag[li, e], qs, checkpoints, lo, hi, arg_lo, arg_hi, pct, conv_lo, conv_hi,
            l0 + li, e,
        )  # fmt: skip


# -- rounds and statistics fused, line by line ----------------------------------------------


@njit(parallel=True, **_JIT)
def noisy_band_stats(
    Ar: FloatArray,
    Ai: FloatArray,
    ar: FloatArray,
    ai: FloatArray,
    Er: FloatArray,
    Ei: FloatArray,
    Br: FloatArray,
    Bi: FloatArray,
    order: IntArray,
    l0: int,
    l1: int,
    key: np.uint64,
    rids: IntArray,
    p: float,
    tire: bool,
    vehicle: bool,
    freq_dep: bool,
    group: int,
    buf: FloatArray,
    qs: FloatArray,
    checkpoints: IntArray,
    lo: FloatArray,
    hi: FloatArray,
    arg_lo: IntArray,
    arg_hi: IntArray,
    pct: FloatArray,
    conv_lo: FloatArray,
    conv_hi: FloatArray,
    row: int,
) -> None:
    """:func:`noisy_block_run` (band mode) then :func:`band_stats`, fused: bit for bit their
    statistics of lines ``l0 .. l1-1``, written at rows ``row ..`` of the outputs.

    Worker ``w`` (``buf (n_workers, group, n_e, R)``, one worker per thread) takes the
    groups of ``group`` lines ``w, w + n_workers, ...``, runs all rounds of a group into
    ``buf[w]`` (a few hundred kB: it stays in the core's cache) and computes the group's
    statistics from there, instead of writing the magnitudes of all lines to memory and
    reading them back. Each value is computed exactly as in the two kernels; only the
    order of the work changes, so the numbers do not depend on the number of threads.
    Frequency-independent noise draws the factors once per group and block of rounds.
    """
    nj = Ar.shape[1]
    ne = Br.shape[1]
    n_el = 2 * nj * nj + nj + ne * nj
    n_workers = buf.shape[0]
    n_groups = (l1 - l0 + group - 1) // group
    n_blocks = (rids.size + LANES - 1) // LANES
    for w in prange(n_workers):
        s, base, W, X, Y, piv, pm = _workspace(nj, ne, n_el)
        lane_ids = np.empty(LANES, np.int64)
        no_cplx = np.empty((0, 0, 0), np.complex128)
        mag = buf[w]
        for g in range(w, n_groups, n_workers):
            g0 = l0 + g * group
            g1 = min(l1, g0 + group)
            for b in range(n_blocks):
                _block_lines(
                    b, Ar, Ai, ar, ai, Er, Ei, Br, Bi, order, g0, g1, key, rids, p, tire,
                    vehicle, freq_dep, mag, g0, no_cplx, s, base, W, X, Y, piv, pm,
                    lane_ids,
                )  # fmt: skip
            for line in range(g0, g1):
                for e in range(ne):
                    _column_stats(
                        mag[line - g0, e], qs, checkpoints, lo, hi, arg_lo, arg_hi, pct,
                        conv_lo, conv_hi, row + line - l0, e,
                    )  # fmt: skip
