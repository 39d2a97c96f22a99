"""Truncated modal sums of the tire at lines of their own speed (compiled kernel).

The sums behind every synthesis of :class:`~fbs_core.tire.model.TireModel`: for lines
``l`` (Laplace variable ``s_l = j omega_l``, speed ``v_l`` inside interval ``k`` of the
operating points) and blocks ``b`` of retained modes (ranks ``e_b .. e_(b+1) - 1`` at the
operating point nearest the line, thesis section 5.1),

    H_b(l) = sum_(r in b) R_r(v_l) / (s_l - lambda_r(v_l))          (eq. 2.5 by blocks)

with poles and residues interpolated in speed (:mod:`.interp`): weights ``w_i(v_l)`` on
the interval's nodes for a mode outside every cluster, the characteristic polynomial
and moments for a cluster of close modes (its rational form when the whole cluster lies
in one block, its interpolated roots when a block edge splits it).

Every term is written as a coefficient times a stored residue row, ``e * Z_i[r]``
(``Z_i`` the residues at node ``i``): for a lone mode ``e = w_i / (s - lambda)``; the
moments ``m_(i,q) = sum_r z_(i,r)^q Z_i[r]`` of a cluster fold into
``e = w_i sum_q h_q z_(i,r)^q`` (``h_q`` the partial-fraction factors at the line), so
a cluster costs no more than its members and no moments are stored. Lines of one
interval and operating point are taken in tiles so that each residue row serves all of
them from cache; a tile's ``1 / (s - lambda)`` of all modes come first, in one loop the
compiler vectorises; the blocks' sums join the sums up to the previous block as each
block ends (no array of all blocks' sums); the loops index elements and take no array
views, and the innermost functions are inlined: each array view or argument of a call
costs two atomic reference counts (the kernel's CPU time for the seven maps
0.18 -> 0.14 s, the numbers the same to rounding). Nothing is kept between calls: a
line's sums depend on that line alone
(the same bits whatever else is computed, in any order, on any thread), so a call's tiles
are dealt to a few threads of the process (the kernel releases the GIL; one per core,
:func:`_run_tiles`): the seven truncation maps of the reference tire 0.21 -> 0.12 s on two
cores (``bench/bench_tire_lines.py``).

Roots of a split cluster's polynomial (3 or 4 members; 2 in closed form) come from the
Aberth-Ehrlich iteration (O. Aberth, Math. Comp. 27, 1973) started from the member
poles interpolated like lone poles, to the last bits of the roots; the companion
matrix's eigenvalues are the fallback should it not converge.
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, TypedDict

import numpy as np
from numba import njit

from .._typing import ComplexArray, FloatArray, IntArray
from ..errors import FBSError
from .interp import KMAX

if TYPE_CHECKING:
    from .interp import Cluster

__all__ = ["Flat", "flatten", "truncated_sums", "TILE"]

#: Lines of one interval and operating point summed together (residue rows reused).
TILE = 16
#: Residue columns of the hub mobility (6 x 6, row major) and of one patch load (6).
_N_MOB = 36
_N_PATCH = 6
#: Largest cluster the kernel takes.
_KMAX = KMAX
#: Aberth iterations before the companion-matrix fallback.
_MAX_ITER = 60
#: A root is taken when ``|P(z)|`` is below this times ``sum |a_i| |z|^(k-i)`` (backward error).
_EPS = 8 * np.finfo(float).eps


@dataclass(frozen=True)
class Flat:
    """The clusters of every interval in flat arrays (depends on the tire only).

    Attributes
    ----------
    node0, n_nodes : ndarray of int, shape (n_int,)
        First operating point and number of nodes (2 or 4) of every interval's stencil.
    cluster_of : ndarray of int, shape (n_int, n_m)
        Cluster of every mode in every interval (-1: outside every cluster).
    cl_ptr : ndarray of int, shape (n_int + 1,)
        Clusters of interval ``k``: ``cl_ptr[k] .. cl_ptr[k+1] - 1``.
    size : ndarray of int, shape (n_cl,)
    members : ndarray of int, shape (n_cl, 4)
        Member modes (first ``size``), in the order of :class:`.interp.Cluster`.
    c, rho : ndarray, shape (n_cl,)
        Centre and scale of the scaled poles ``z = (lambda - c) / rho``.
    a : ndarray, complex, shape (n_cl, 4, 5)
        Coefficients of the characteristic polynomial at the nodes (leading 1).
    z : ndarray, complex, shape (n_cl, 4, 4)
        Scaled member poles at the nodes.
    """

    node0: IntArray
    n_nodes: IntArray
    cluster_of: IntArray
    cl_ptr: IntArray
    size: IntArray
    members: IntArray
    c: ComplexArray
    rho: FloatArray
    a: ComplexArray
    z: ComplexArray


def flatten(nodes: tuple[slice, ...], n_modes: int, clusters: list[tuple[Cluster, ...]]) -> Flat:
    """:class:`Flat` from the stencils ``nodes`` and the cluster batches of every interval."""
    n_int = len(nodes)
    cl_ptr = [0]
    cluster_of = np.full((n_int, n_modes), -1, np.int64)
    rows: list[tuple[int, IntArray, complex, float, ComplexArray, ComplexArray]] = []
    for k in range(n_int):
        for cl in clusters[k]:
            n_c, kc = cl.members.shape
            for j in range(n_c):
                cluster_of[k, cl.members[j]] = len(rows)
                rows.append((kc, cl.members[j], cl.c[j], cl.rho[j], cl.a[:, j], cl.z[:, j]))
        cl_ptr.append(len(rows))
    n_cl = len(rows)
    size = np.zeros(n_cl, np.int64)
    mem = np.zeros((n_cl, _KMAX), np.int64)
    c = np.zeros(n_cl, complex)
    rho = np.ones(n_cl)
    a = np.zeros((n_cl, 4, _KMAX + 1), complex)
    z = np.zeros((n_cl, 4, _KMAX), complex)
    for i, (kc, m, cc, rr, aa, zz) in enumerate(rows):
        size[i], c[i], rho[i] = kc, cc, rr
        mem[i, :kc] = m
        a[i, : aa.shape[0], : kc + 1] = aa
        z[i, : zz.shape[0], :kc] = zz
    node0 = np.array([nd.start for nd in nodes], np.int64)
    n_nodes = np.array([nd.stop - nd.start for nd in nodes], np.int64)
    out = Flat(
        node0,
        n_nodes,
        cluster_of,
        np.array(cl_ptr, np.int64),
        size,
        mem,
        c,
        rho,
        a,
        z,
    )
    for arr in vars(out).values():
        arr.setflags(write=False)
    return out


def truncated_sums(
    flat: Flat,
    poles: ComplexArray,
    Zr: FloatArray,
    Zi: FloatArray,
    s: ComplexArray,
    k: IntArray,
    w: FloatArray,
    op: IntArray,
    order: IntArray,
    block: IntArray,
    rank: IntArray,
    n_ranked: int,
    patch: int | None,
    n_blocks: int,
    n_out: int,
    static: bool,
    extra: ComplexArray | None = None,
) -> tuple[ComplexArray, ComplexArray | None]:
    """Mobility and patch velocity of every line up to every block (module docstring).

    Parameters
    ----------
    flat : Flat
    poles : ndarray, shape (n_s, n_m)
    Zr, Zi : ndarray, shape (n_s, n_m, n_res)
        Real and imaginary parts of the residues at the operating points.
    s : ndarray, complex, shape (n_l,)
        ``j omega`` of every line.
    k : ndarray of int, shape (n_l,)
        Interval of every line.
    w : ndarray, shape (n_l, 4)
        Weights of the interval's nodes (zero beyond its ``n_nodes``).
    op : ndarray of int, shape (n_l,)
        Operating point whose ranking sets the blocks (the nearest one).
    order, rank : ndarray of int, shape (n_s, n_m)
        The modes by rank at every operating point (eigenfrequency order) and the rank
        of every mode (inverse permutations).
    block : ndarray of int, shape (n_s, n_m)
        Block of every mode ranked at every operating point, -1: left out.
    n_ranked : int
        Modes summed: ranks ``0 .. n_ranked - 1`` (the blocks cover them in order).
    patch : int or None
        Residue columns summed: the 36 of the hub mobility (``Z[..., :36]``), then the 6
        from ``patch`` on (the hub velocity of one patch load), if given.
    n_blocks, n_out : int
        Blocks summed, and how many of them (the first) are returned.
    static : bool
        Compensate the modes of the blocks after each returned one by their quasi-static
        parts ``R_r / (-lambda_r)`` (zero poles: none); the blocks then reach all modes.
    extra : ndarray, shape (n_l, n_cols), optional
        A receptance added to every returned sum (the residual of modes not delivered).

    Returns
    -------
    Y : ndarray, shape (n_out, n_l, 6, 6)
        ``j omega`` times the receptance sums over blocks ``0 .. b`` (hub mobility).
    v : ndarray, shape (n_out, n_l, 6) or None
        The same for the patch load's columns (free hub velocity), if ``patch``.
    """
    n_l = s.size
    key = k * poles.shape[0] + op
    by_tile = np.argsort(key, kind="stable")
    ks = key[by_tile]
    starts = np.flatnonzero(np.r_[True, ks[1:] != ks[:-1]])
    ends = np.r_[starts[1:], n_l]
    firsts = [a for a0, b in zip(starts, ends, strict=True) for a in range(a0, b, TILE)]
    Y = np.empty((n_out, n_l, _N_MOB), complex)
    v = np.empty((n_out, n_l, _N_PATCH if patch is not None else 0), complex)
    args = (
        np.ascontiguousarray(s, complex),
        np.ascontiguousarray(w, float),
        np.ascontiguousarray(k, np.int64),
        np.ascontiguousarray(op, np.int64),
        flat.node0,
        flat.n_nodes,
        np.ascontiguousarray(poles.real),
        np.ascontiguousarray(poles.imag),
        Zr,
        Zi,
        -1 if patch is None else int(patch),
        flat.cluster_of,
        flat.size,
        flat.members,
        flat.c,
        flat.rho,
        flat.a,
        flat.z,
        np.ascontiguousarray(order, np.int64),
        np.ascontiguousarray(block, np.int64),
        np.ascontiguousarray(rank, np.int64),
        int(n_ranked),
        int(n_blocks),
        static,
        _EMPTY_EXTRA if extra is None else np.ascontiguousarray(extra, complex),
        Y,
        v,
    )
    tiles = [by_tile[a:b].astype(np.int64) for a, b in zip(firsts, firsts[1:] + [n_l], strict=True)]
    _run_tiles(tiles, args)
    return Y.reshape(n_out, n_l, 6, 6), (v if patch is not None else None)


#: Fewest tiles worth a second thread (a tile is 16 lines: ~1 ms of work at most).
MIN_TILES_PER_THREAD = 4
#: Most threads one call uses.
MAX_THREADS = 4
#: Environment variable capping the threads of a call (a positive integer; ``1``: the
#: calling thread only, e.g. to measure the CPU cost on a machine whose cores are busy).
THREADS_ENV = "FBS_TIRE_SUM_THREADS"


def _thread_cap() -> int:
    """:data:`MAX_THREADS`, or less as :data:`THREADS_ENV` asks."""
    raw = os.environ.get(THREADS_ENV, "").strip()
    if not raw:
        return MAX_THREADS
    if not raw.isdigit() or int(raw) < 1:
        raise FBSError(f"{THREADS_ENV}={raw!r}: must be a positive integer (threads per call)")
    return min(int(raw), MAX_THREADS)


_pool: tuple[int, ThreadPoolExecutor] | None = None
_pool_lock = threading.Lock()


def _threads(n_tiles: int) -> int:
    """Threads for ``n_tiles`` tiles: one per usable core (at most :data:`MAX_THREADS`, or
    the cap of :data:`THREADS_ENV`) with at least :data:`MIN_TILES_PER_THREAD` tiles each;
    one on a thread of lowered priority (work computed ahead, which must not take cores
    from interactive work)."""
    try:
        cores = len(os.sched_getaffinity(0))
        # nicer than the main thread (on Linux a thread's priority is its own; the main
        # thread's id is the process id)
        nice = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
        niced = nice > os.getpriority(os.PRIO_PROCESS, os.getpid())
    except (AttributeError, OSError):  # no affinity / per-thread priorities (not Linux)
        cores, niced = os.cpu_count() or 1, False
    if niced:
        return 1
    return max(1, min(cores, _thread_cap(), n_tiles // MIN_TILES_PER_THREAD))


def _executor() -> ThreadPoolExecutor:
    """The process's pool of helper threads (a new one in a forked child, whose copy of the
    parent's pool has no threads)."""
    global _pool
    with _pool_lock:
        if _pool is None or _pool[0] != os.getpid():
            pool = ThreadPoolExecutor(MAX_THREADS - 1, thread_name_prefix="fbs-tire-sums")
            _pool = (os.getpid(), pool)
        return _pool[1]


def _run_tiles(tiles: list[IntArray], args: tuple[Any, ...]) -> None:
    """:func:`_kernel` over ``tiles`` (the line indices of each tile), the tiles dealt in
    turn to up to :func:`_threads` threads: the calling one and helper threads of the
    process (the kernel releases the GIL). Every line's sums are computed by one thread from
    that line's data alone and written to that line's rows: the same bits on any number
    of threads."""
    n = _threads(len(tiles))
    parts = []
    for t in range(n):
        mine = tiles[t::n]
        sizes = np.array([0] + [x.size for x in mine], np.int64)
        lines = np.concatenate(mine) if mine else np.zeros(0, np.int64)
        parts.append((lines, np.cumsum(sizes)))
    s_, w_, k_, *rest = args
    futures = [
        _executor().submit(_kernel, s_, w_, lines, ptr, k_, *rest) for lines, ptr in parts[1:]
    ]
    try:
        _kernel(s_, w_, parts[0][0], parts[0][1], k_, *rest)
    finally:
        for f in futures:
            f.result()


_EMPTY_EXTRA = np.zeros((0, 0), complex)


class _JitOptions(TypedDict, total=False):
    cache: bool
    nogil: bool
    error_model: Literal["python", "numpy"]
    fastmath: bool
    inline: Literal["never", "always"]


# nogil: a session's sums must not stall the threads serving the others
_JIT = _JitOptions(cache=True, nogil=True, error_model="numpy", fastmath=False)
#: The same, inlined into the caller: no call, so no reference counts on the arguments
#: (two atomic operations per array argument per call otherwise).
_INLINE = _JitOptions(**_JIT, inline="always")


@njit(**_INLINE)
def _mac(
    acc: FloatArray,
    slot: int,
    nt: int,
    cr: FloatArray,
    ci: FloatArray,
    Zr: FloatArray,
    Zi: FloatArray,
    n0: int,
    nn: int,
    r: int,
    p0: int,
) -> None:
    """``acc[slot, 0 / 1, t, c] += sum_i coef[t, i] * Z[n0 + i, r, column c]`` (real /
    imaginary part) for the tile's lines ``t``: the 36 hub mobility columns, then the 6
    of the patch at ``p0`` (none if ``p0 < 0``). The rows of all nodes in one pass, real
    and imaginary parts apart and fixed loop lengths, so that the compiler vectorises over
    the columns (the patch's 6, unrolled, stay scalar: faster than a vector loop with its
    checks); every element by full indices (no array views)."""
    q = p0 - _N_MOB  # patch column c (from 36 on in acc) is column c + q of Z
    for t in range(nt):
        if nn == 4:
            a0, b0, a1, b1 = cr[t, 0], ci[t, 0], cr[t, 1], ci[t, 1]
            a2, b2, a3, b3 = cr[t, 2], ci[t, 2], cr[t, 3], ci[t, 3]
            for c in range(_N_MOB):
                acc[slot, 0, t, c] += (
                    (a0 * Zr[n0, r, c] - b0 * Zi[n0, r, c])
                    + (a1 * Zr[n0 + 1, r, c] - b1 * Zi[n0 + 1, r, c])
                    + (a2 * Zr[n0 + 2, r, c] - b2 * Zi[n0 + 2, r, c])
                    + (a3 * Zr[n0 + 3, r, c] - b3 * Zi[n0 + 3, r, c])
                )
                acc[slot, 1, t, c] += (
                    (a0 * Zi[n0, r, c] + b0 * Zr[n0, r, c])
                    + (a1 * Zi[n0 + 1, r, c] + b1 * Zr[n0 + 1, r, c])
                    + (a2 * Zi[n0 + 2, r, c] + b2 * Zr[n0 + 2, r, c])
                    + (a3 * Zi[n0 + 3, r, c] + b3 * Zr[n0 + 3, r, c])
                )
            if p0 >= 0:
                for c in range(_N_MOB, _N_MOB + _N_PATCH):
                    acc[slot, 0, t, c] += (
                        (a0 * Zr[n0, r, c + q] - b0 * Zi[n0, r, c + q])
                        + (a1 * Zr[n0 + 1, r, c + q] - b1 * Zi[n0 + 1, r, c + q])
                        + (a2 * Zr[n0 + 2, r, c + q] - b2 * Zi[n0 + 2, r, c + q])
                        + (a3 * Zr[n0 + 3, r, c + q] - b3 * Zi[n0 + 3, r, c + q])
                    )
                    acc[slot, 1, t, c] += (
                        (a0 * Zi[n0, r, c + q] + b0 * Zr[n0, r, c + q])
                        + (a1 * Zi[n0 + 1, r, c + q] + b1 * Zr[n0 + 1, r, c + q])
                        + (a2 * Zi[n0 + 2, r, c + q] + b2 * Zr[n0 + 2, r, c + q])
                        + (a3 * Zi[n0 + 3, r, c + q] + b3 * Zr[n0 + 3, r, c + q])
                    )
        else:  # the end intervals: linear, two nodes
            a0, b0, a1, b1 = cr[t, 0], ci[t, 0], cr[t, 1], ci[t, 1]
            for c in range(_N_MOB):
                acc[slot, 0, t, c] += (a0 * Zr[n0, r, c] - b0 * Zi[n0, r, c]) + (
                    a1 * Zr[n0 + 1, r, c] - b1 * Zi[n0 + 1, r, c]
                )
                acc[slot, 1, t, c] += (a0 * Zi[n0, r, c] + b0 * Zr[n0, r, c]) + (
                    a1 * Zi[n0 + 1, r, c] + b1 * Zr[n0 + 1, r, c]
                )
            if p0 >= 0:
                for c in range(_N_MOB, _N_MOB + _N_PATCH):
                    acc[slot, 0, t, c] += (a0 * Zr[n0, r, c + q] - b0 * Zi[n0, r, c + q]) + (
                        a1 * Zr[n0 + 1, r, c + q] - b1 * Zi[n0 + 1, r, c + q]
                    )
                    acc[slot, 1, t, c] += (a0 * Zi[n0, r, c + q] + b0 * Zr[n0, r, c + q]) + (
                        a1 * Zi[n0 + 1, r, c + q] + b1 * Zr[n0 + 1, r, c + q]
                    )


@njit(**_JIT)
def _fold(
    acc: FloatArray,
    slot: int,
    lines: IntArray,
    nt: int,
    w: FloatArray,
    nn: int,
    kc: int,
    H: ComplexArray,
    ib: int,
    ps_: int,
    z_all: ComplexArray,
    members: IntArray,
    cc: int,
    n0: int,
    Zr: FloatArray,
    Zi: FloatArray,
    p0: int,
    cr: FloatArray,
    ci: FloatArray,
) -> None:
    """A cluster's terms ``w_i sum_q H[ib, ps_, t, q] z_(i,j)^q Z_i[member j]`` (cluster
    ``cc``) into ``acc[slot]``: its moments ``sum_j z_(i,j)^q Z_i[member j]`` folded into
    the coefficients."""
    for j in range(kc):
        for i in range(nn):
            x = z_all[cc, i, j]
            for t in range(nt):
                e = H[ib, ps_, t, kc - 1]
                for q in range(kc - 2, -1, -1):
                    e = e * x + H[ib, ps_, t, q]
                e = w[lines[t], i] * e
                cr[t, i] = e.real
                ci[t, i] = e.imag
        _mac(acc, slot, nt, cr, ci, Zr, Zi, n0, nn, members[cc, j], p0)


@njit(**_INLINE)
def _partials(a: ComplexArray, kc: int, z: complex, out: ComplexArray) -> None:
    """Horner partial sums ``out[i] = sum_(i' <= i) a[i'] z^(i - i')``, i = 0..kc."""
    out[0] = a[0]
    for i in range(1, kc + 1):
        out[i] = out[i - 1] * z + a[i]


@njit(**_JIT)
def _norm1(x: complex) -> float:
    """``|Re x| + |Im x|`` (between ``|x|`` and ``sqrt(2) |x|``, without a square root)."""
    return abs(x.real) + abs(x.imag)


@njit(**_INLINE)
def _roots(al: ComplexArray, kc: int, z0: ComplexArray, sign: float, out: ComplexArray) -> None:
    """Roots of ``z^kc + al[1] z^(kc-1) + ... + al[kc]`` sorted by ``sign * Im`` (ascending).

    Two roots in closed form (as :func:`.interp.cluster_at`); more by the Aberth-Ehrlich
    iteration from the start values ``z0`` until every root is one of a polynomial within
    rounding of ``al`` (backward error), with the companion matrix's eigenvalues as
    fallback. The result depends on this polynomial and start only.
    """
    if kc == 2:
        d = np.sqrt(al[1] ** 2 / 4 - al[2])
        out[0] = -al[1] / 2 + d
        out[1] = -al[1] / 2 - d
    else:
        m1, m2, m3 = _norm1(al[1]), _norm1(al[2]), _norm1(al[3])
        m4 = _norm1(al[4]) if kc == 4 else 0.0
        for j in range(kc):
            out[j] = z0[j]
        for j in range(kc):  # distinct start values
            for i in range(j):
                if _norm1(out[j] - out[i]) < 1e-6:
                    out[j] += 1e-3 * np.exp(1j * (0.5 + j))
        ok = False
        for _ in range(_MAX_ITER):
            ok = True
            for j in range(kc):
                x = out[j]
                ax = _norm1(x)
                p = x + al[1]
                dp = 1.0 + 0j
                bnd = ax + m1
                dp = dp * x + p
                p = p * x + al[2]
                bnd = bnd * ax + m2
                dp = dp * x + p
                p = p * x + al[3]
                bnd = bnd * ax + m3
                if kc == 4:
                    dp = dp * x + p
                    p = p * x + al[4]
                    bnd = bnd * ax + m4
                if _norm1(p) <= _EPS * bnd:  # a root of a polynomial within rounding of al
                    continue
                ok = False
                # the Aberth step x - ratio / (1 - ratio sm), ratio = p / dp, with the sum
                # sm = sum_(i != j) 1 / (x - x_i) as one fraction num / den: one complex
                # division instead of kc + 1
                num = 0j
                den = 1.0 + 0j
                for i in range(kc):
                    if i != j:
                        d = x - out[i]
                        num = num * d + den
                        den = den * d
                out[j] = x - (p * den) / (dp * den - p * num)
            if ok:
                break
        for j in range(kc):
            if not np.isfinite(out[j]):
                ok = False
        if not ok:
            comp = np.zeros((kc, kc), np.complex128)
            for i in range(kc):
                comp[0, i] = -al[i + 1]
            for i in range(1, kc):
                comp[i, i - 1] = 1.0
            ev = np.linalg.eigvals(comp)
            for i in range(kc):
                out[i] = ev[i]
    for j in range(1, kc):  # insertion sort by sign * Im
        x = out[j]
        i = j - 1
        while i >= 0 and sign * out[i].imag > sign * x.imag:
            out[i + 1] = out[i]
            i -= 1
        out[i + 1] = x


@njit(**_JIT)
def _inverse(dr: float, di: float, u: float) -> tuple[float, float]:
    """``u / (dr + j di)`` for a real ``u`` = +-1: the operations of complex division in
    compiled code (Smith's, as CPython's) less those with a zero or a unit, so the same bits
    as ``u / d``; without its branches on the path, so that a loop of them vectorises."""
    big = abs(dr) >= abs(di)
    ratio = di / dr if big else dr / di
    den = dr + di * ratio if big else dr * ratio + di
    re = u / den if big else (u * ratio) / den
    im = (-(u * ratio)) / den if big else (-u) / den
    return re, im


@njit(**_JIT)
def _reciprocals(
    lines: IntArray,
    nt: int,
    s: ComplexArray,
    w: FloatArray,
    Pr: FloatArray,
    Pi: FloatArray,
    n0: int,
    nn: int,
    static: bool,
    Tr: FloatArray,
    Ti: FloatArray,
) -> None:
    """``T[0, t, r] = 1 / (s_t - lambda_r)`` and, if ``static``, ``T[1, t, r] = -1 / lambda_r``
    (zero for a zero pole) of every mode at the tile's lines, the poles interpolated with
    the lines' weights: once per line for all modes, vectorised over the modes (the same
    operations for every mode and line). Unused for the members of clusters."""
    n_m = Pr.shape[1]
    for t in range(nt):
        ln = lines[t]
        sr, si = s[ln].real, s[ln].imag
        w0, w1 = w[ln, 0], w[ln, 1]
        w2, w3 = (w[ln, 2], w[ln, 3]) if nn == 4 else (0.0, 0.0)
        pr0, pr1, pi0, pi1 = Pr[n0], Pr[n0 + 1], Pi[n0], Pi[n0 + 1]
        pr2, pr3, pi2, pi3 = (
            (Pr[n0 + 2], Pr[n0 + 3], Pi[n0 + 2], Pi[n0 + 3]) if nn == 4 else (pr0, pr1, pi0, pi1)
        )
        lr, li = Tr[1, t], Ti[1, t]  # the interpolated poles, until the static terms
        if nn == 4:
            for r in range(n_m):
                lr[r] = ((w0 * pr0[r] + w1 * pr1[r]) + w2 * pr2[r]) + w3 * pr3[r]
                li[r] = ((w0 * pi0[r] + w1 * pi1[r]) + w2 * pi2[r]) + w3 * pi3[r]
        else:
            for r in range(n_m):
                lr[r] = w0 * pr0[r] + w1 * pr1[r]
                li[r] = w0 * pi0[r] + w1 * pi1[r]
        tr, ti = Tr[0, t], Ti[0, t]
        for r in range(n_m):
            tr[r], ti[r] = _inverse(sr - lr[r], si - li[r], 1.0)
        if static:
            for r in range(n_m):
                a, b = lr[r], li[r]
                if a != 0.0 or b != 0.0:
                    lr[r], li[r] = _inverse(a, b, -1.0)
                else:
                    lr[r], li[r] = 0.0, 0.0


@njit(**_JIT)
def _store(
    b: int,
    xr: FloatArray,
    xi: FloatArray,
    nt: int,
    lines: IntArray,
    s: ComplexArray,
    extra: ComplexArray,
    Y: ComplexArray,
    v: ComplexArray,
) -> None:
    """The sums ``x`` of the tile's lines up to block ``b``, plus ``extra``, times ``j omega``
    into ``Y[b]`` (hub mobility) and ``v[b]`` (the patch's 6 columns, if any)."""
    n_v = v.shape[2]
    for t in range(nt):
        ln = lines[t]
        sl = s[ln]
        for c in range(_N_MOB):
            x = xr[t, c] + 1j * xi[t, c]
            if extra.shape[0] > 0:
                x = x + extra[ln, c]
            Y[b, ln, c] = x * sl
        for c in range(n_v):
            x = xr[t, _N_MOB + c] + 1j * xi[t, _N_MOB + c]
            if extra.shape[0] > 0:
                x = x + extra[ln, _N_MOB + c]
            v[b, ln, c] = x * sl


@njit(**_JIT)
def _close(
    b: int,
    n_pass: int,
    nt: int,
    acc: FloatArray,
    run: FloatArray,
    pend: FloatArray,
    has_pend: Any,
    cum: FloatArray,
    lines: IntArray,
    s: ComplexArray,
    extra: ComplexArray,
    Y: ComplexArray,
    v: ComplexArray,
) -> None:
    """The end of block ``b``: its sum (the parts of split clusters that waited for it, then
    its own terms) joins the sums of the blocks before it (``run``, in block order, as
    ``np.cumsum``), and its accumulator is cleared. The sums up to ``b`` are stored at once
    if ``b`` is returned, or kept in ``cum`` until the static parts' totals are known
    (:func:`_finish`)."""
    nc = acc.shape[3]
    for ps_ in range(n_pass):
        waits = has_pend[ps_, b]
        for h in range(2):
            for t in range(nt):
                if waits:
                    for c in range(nc):
                        run[ps_, h, t, c] += pend[ps_, b, h, t, c] + acc[ps_, h, t, c]
                        acc[ps_, h, t, c] = 0.0
                else:
                    for c in range(nc):
                        run[ps_, h, t, c] += acc[ps_, h, t, c]
                        acc[ps_, h, t, c] = 0.0
        has_pend[ps_, b] = False
    if b >= Y.shape[0]:
        return
    if n_pass == 2:
        cum[b, :, :, :nt] = run[:, :, :nt]
    else:
        _store(b, run[0, 0], run[0, 1], nt, lines, s, extra, Y, v)


@njit(**_JIT)
def _finish(
    run: FloatArray,
    cum: FloatArray,
    lines: IntArray,
    nt: int,
    s: ComplexArray,
    extra: ComplexArray,
    Y: ComplexArray,
    v: ComplexArray,
) -> None:
    """With the static parts: the sums up to every returned block plus the static parts of
    the modes after it (the total less the running sum), plus ``extra``, times ``j omega``."""
    n_v = v.shape[2]
    for b in range(Y.shape[0]):
        for t in range(nt):
            ln = lines[t]
            sl = s[ln]
            for c in range(_N_MOB + n_v):
                x = cum[b, 0, 0, t, c] + 1j * cum[b, 0, 1, t, c]
                tot0 = run[1, 0, t, c] + 1j * run[1, 1, t, c]
                cum0 = cum[b, 1, 0, t, c] + 1j * cum[b, 1, 1, t, c]
                x = x + (tot0 - cum0)
                if extra.shape[0] > 0:
                    x = x + extra[ln, c]
                x = x * sl
                if c < _N_MOB:
                    Y[b, ln, c] = x
                else:
                    v[b, ln, c - _N_MOB] = x


@njit(**_JIT)
def _tile(
    lines: IntArray,
    kk: int,
    op: int,
    s: ComplexArray,
    w: FloatArray,
    node0: IntArray,
    n_nodes: IntArray,
    Pr: FloatArray,
    Pi: FloatArray,
    Zr: FloatArray,
    Zi: FloatArray,
    p0: int,
    cluster_of: IntArray,
    size: IntArray,
    members: IntArray,
    cc_all: ComplexArray,
    rho_all: FloatArray,
    a_all: ComplexArray,
    z_all: ComplexArray,
    order: IntArray,
    block: IntArray,
    rank: IntArray,
    n_ranked: int,
    n_blocks: int,
    static: bool,
    extra: ComplexArray,
    Y: ComplexArray,
    v: ComplexArray,
    acc: FloatArray,
    run: FloatArray,
    pend: FloatArray,
    has_pend: Any,
    cum: FloatArray,
    Tr: FloatArray,
    Ti: FloatArray,
) -> None:
    """The sums of one tile: lines of interval ``kk`` ranked at ``op``, into ``Y`` and ``v``.

    The modes are taken by rank, so the blocks come one after the other: each is summed in
    a small accumulator (``acc``: [pass, re/im, line, column], the dynamic terms then the
    static ones) that joins the sums of the blocks before it (``run``) when it ends. A
    cluster is taken whole at its lowest-ranked member; the part of a split cluster in a
    later block waits in ``pend`` until that block ends.
    """
    nt = lines.size
    n0 = node0[kk]
    nn = n_nodes[kk]
    n_pass = 2 if static else 1  # the dynamic terms, then the static ones
    acc[:, :, :nt] = 0.0
    run[:, :, :nt] = 0.0
    _reciprocals(lines, nt, s, w, Pr, Pi, n0, nn, static, Tr, Ti)
    cr = np.zeros((TILE, 4))  # coefficients of the residue rows at the nodes
    ci = np.zeros((TILE, 4))
    H = np.empty((_KMAX, 2, TILE, _KMAX), np.complex128)  # a cluster: [block, pass, t, q]
    blocks = np.empty(_KMAX, np.int64)  # the blocks of a cluster's members
    hs = np.empty((TILE, _KMAX, _KMAX), np.complex128)  # split: per root, per q
    ps = np.empty((TILE, _KMAX), np.complex128)  # split: poles of the roots
    al = np.empty(_KMAX + 1, np.complex128)
    bb = np.empty(_KMAX + 1, np.complex128)
    zr = np.empty(_KMAX, np.complex128)
    z0 = np.empty(_KMAX, np.complex128)
    smem = np.empty(_KMAX, np.int64)
    rblk = np.empty(_KMAX, np.int64)
    cur = 0
    for rk in range(n_ranked):  # modes by rank: the blocks one after the other
        r = order[op, rk]
        b = block[op, r]
        while cur < b:
            _close(cur, n_pass, nt, acc, run, pend, has_pend, cum, lines, s, extra, Y, v)
            cur += 1
        cc = cluster_of[kk, r]
        if cc < 0:  # outside every cluster: e = w_i / (s - lambda)
            for ps_ in range(n_pass):
                for t in range(nt):
                    ln = lines[t]
                    tr, ti = Tr[ps_, t, r], Ti[ps_, t, r]
                    for i in range(nn):
                        cr[t, i] = w[ln, i] * tr
                        ci[t, i] = w[ln, i] * ti
                _mac(acc, ps_, nt, cr, ci, Zr, Zi, n0, nn, r, p0)
            continue
        # a cluster, all of it at its lowest-ranked member
        kc = size[cc]
        first = True
        whole = True
        for j in range(kc):
            if block[op, members[cc, j]] != b:
                whole = False
            if rank[op, members[cc, j]] < rk:
                first = False
        if not first:
            continue
        c = cc_all[cc]
        rho = rho_all[cc]
        n_blk = 0
        if whole:  # rational form N(z) / (rho P(z)): H_q = b_(k-1-q) / (rho b_k)
            blocks[0] = b
            n_blk = 1
            for t in range(nt):
                ln = lines[t]
                for q in range(kc + 1):
                    x = 0j
                    for i in range(nn):
                        x += w[ln, i] * a_all[cc, i, q]
                    al[q] = x
                for ps_ in range(n_pass):
                    _partials(al, kc, ((s[ln] if ps_ == 0 else 0j) - c) / rho, bb)
                    inv = 1.0 / (rho * bb[kc])
                    for q in range(kc):
                        H[0, ps_, t, q] = bb[kc - 1 - q] * inv
        else:  # split by a block edge: roots, the lowest to the member ranked lowest here
            for j in range(kc):
                smem[j] = members[cc, j]
            for j in range(1, kc):  # insertion sort by rank
                m = smem[j]
                i = j - 1
                while i >= 0 and rank[op, smem[i]] > rank[op, m]:
                    smem[i + 1] = smem[i]
                    i -= 1
                smem[i + 1] = m
            for j in range(kc):
                rblk[j] = block[op, smem[j]]
            sign = 1.0 if c.imag >= 0 else -1.0
            for t in range(nt):
                ln = lines[t]
                for q in range(kc + 1):
                    x = 0j
                    for i in range(nn):
                        x += w[ln, i] * a_all[cc, i, q]
                    al[q] = x
                for j in range(kc):
                    x = 0j
                    for i in range(nn):
                        x += w[ln, i] * z_all[cc, i, j]
                    z0[j] = x
                _roots(al, kc, z0, sign, zr)
                for j in range(kc):  # root j: N(z_j) / P'(z_j) by moments, pole c + rho z_j
                    if rblk[j] < 0:
                        continue
                    dp = 1.0 + 0j
                    for i in range(kc):
                        if i != j:
                            dp *= zr[j] - zr[i]
                    _partials(al, kc, zr[j], bb)
                    inv = 1.0 / dp
                    for q in range(kc):
                        hs[t, j, q] = bb[kc - 1 - q] * inv
                    ps[t, j] = c + rho * zr[j]
            for j0 in range(kc):  # every block of the members once, with all its roots
                bj = rblk[j0]
                if bj < 0:
                    continue
                seen = False
                for j in range(j0):
                    if rblk[j] == bj:
                        seen = True
                if seen:
                    continue
                blocks[n_blk] = bj
                for t in range(nt):
                    ln = lines[t]
                    for q in range(kc):
                        H[n_blk, 0, t, q] = 0j
                        H[n_blk, 1, t, q] = 0j
                    for j in range(j0, kc):
                        if rblk[j] != bj:
                            continue
                        d = 1.0 / (s[ln] - ps[t, j])
                        d0 = -1.0 / ps[t, j] if ps[t, j] != 0 else 0j
                        for q in range(kc):
                            H[n_blk, 0, t, q] += hs[t, j, q] * d
                            H[n_blk, 1, t, q] += hs[t, j, q] * d0
                n_blk += 1
        for ib in range(n_blk):  # into this block's accumulator, or to wait for a later one
            bj = blocks[ib]
            for ps_ in range(n_pass):
                later = bj != b  # a later block's part: alone first, in the spare slot 2
                slot = 2 if later else ps_
                if later:
                    acc[2, :, :nt] = 0.0
                _fold(
                    acc,
                    slot,
                    lines,
                    nt,
                    w,
                    nn,
                    kc,
                    H,
                    ib,
                    ps_,
                    z_all,
                    members,
                    cc,
                    n0,
                    Zr,
                    Zi,
                    p0,
                    cr,
                    ci,
                )
                if not later:
                    continue
                if not has_pend[ps_, bj]:
                    pend[ps_, bj, :, :nt] = 0.0
                    has_pend[ps_, bj] = True
                for h in range(2):
                    for t in range(nt):
                        for cl in range(acc.shape[3]):
                            pend[ps_, bj, h, t, cl] += acc[2, h, t, cl]
    while cur < n_blocks:
        _close(cur, n_pass, nt, acc, run, pend, has_pend, cum, lines, s, extra, Y, v)
        cur += 1
    if static:
        _finish(run, cum, lines, nt, s, extra, Y, v)


@njit(**_JIT)
def _kernel(
    s: ComplexArray,
    w: FloatArray,
    lines_all: IntArray,
    ptr: IntArray,
    kint: IntArray,
    op_all: IntArray,
    node0: IntArray,
    n_nodes: IntArray,
    Pr: FloatArray,
    Pi: FloatArray,
    Zr: FloatArray,
    Zi: FloatArray,
    p0: int,
    cluster_of: IntArray,
    size: IntArray,
    members: IntArray,
    cc_all: ComplexArray,
    rho_all: FloatArray,
    a_all: ComplexArray,
    z_all: ComplexArray,
    order: IntArray,
    block: IntArray,
    rank: IntArray,
    n_ranked: int,
    n_blocks: int,
    static: bool,
    extra: ComplexArray,
    Y: ComplexArray,
    v: ComplexArray,
) -> None:
    """All tiles one after the other, on the calling thread (the GIL released)."""
    nc = _N_MOB + (_N_PATCH if p0 >= 0 else 0)
    n_m = Pr.shape[1]
    # the block's sums [pass, re/im, line, column], then a split cluster's part in a later
    # block (acc[2])
    acc = np.zeros((3, 2, TILE, nc))
    run = np.zeros((2, 2, TILE, nc))  # the sums of the blocks before it
    pend = np.zeros((2, n_blocks, 2, TILE, nc))  # split clusters' parts in later blocks
    has_pend = np.zeros((2, n_blocks), np.bool_)
    cum = np.zeros((Y.shape[0] if static else 0, 2, 2, TILE, nc))  # static: sums up to b
    Tr = np.zeros((2, TILE, n_m))  # 1 / (s - lambda), -1 / lambda of every mode
    Ti = np.zeros((2, TILE, n_m))
    for ti in range(ptr.size - 1):
        lines = lines_all[ptr[ti] : ptr[ti + 1]]
        _tile(
            lines,
            kint[lines[0]],
            op_all[lines[0]],
            s,
            w,
            node0,
            n_nodes,
            Pr,
            Pi,
            Zr,
            Zi,
            p0,
            cluster_of,
            size,
            members,
            cc_all,
            rho_all,
            a_all,
            z_all,
            order,
            block,
            rank,
            n_ranked,
            n_blocks,
            static,
            extra,
            Y,
            v,
            acc,
            run,
            pend,
            has_pend,
            cum,
            Tr,
            Ti,
        )
