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
them from cache. Nothing is kept between calls: a line's sums depend on that line alone
(the same bits whatever else is computed, in any order, on any thread), so a call's tiles
are dealt to a few threads of the process (the kernel releases the GIL; one per core,
:func:`_run_tiles`): the seven truncation maps of the reference tire 0.21 -> 0.12 s on two
cores (``bench/bench_tire_lines.py``, issue 33).

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
        poles,
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


class _JitOptions(TypedDict):
    cache: bool
    nogil: bool
    error_model: Literal["python", "numpy"]
    fastmath: bool


# nogil: a session's sums must not stall the threads serving the others
_JIT = _JitOptions(cache=True, nogil=True, error_model="numpy", fastmath=False)


@njit(**_JIT)
def _mac(
    accr: FloatArray,
    acci: FloatArray,
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
    """``acc[t, c] += sum_i coef[t, i] * Z[n0 + i, r, column c]`` for the tile's lines
    ``t``: the 36 hub mobility columns, then the 6 of the patch at ``p0`` (none if
    ``p0 < 0``). The rows of all nodes in one pass, real and imaginary parts apart and
    fixed loop lengths, so that the compiler vectorises over the columns."""
    for t in range(nt):
        dr = accr[t]
        di = acci[t]
        if nn == 4:
            a0, b0, a1, b1 = cr[t, 0], ci[t, 0], cr[t, 1], ci[t, 1]
            a2, b2, a3, b3 = cr[t, 2], ci[t, 2], cr[t, 3], ci[t, 3]
            r0, i0, r1, i1 = Zr[n0, r], Zi[n0, r], Zr[n0 + 1, r], Zi[n0 + 1, r]
            r2, i2, r3, i3 = Zr[n0 + 2, r], Zi[n0 + 2, r], Zr[n0 + 3, r], Zi[n0 + 3, r]
            for c in range(_N_MOB):
                dr[c] += (
                    (a0 * r0[c] - b0 * i0[c])
                    + (a1 * r1[c] - b1 * i1[c])
                    + (a2 * r2[c] - b2 * i2[c])
                    + (a3 * r3[c] - b3 * i3[c])
                )
                di[c] += (
                    (a0 * i0[c] + b0 * r0[c])
                    + (a1 * i1[c] + b1 * r1[c])
                    + (a2 * i2[c] + b2 * r2[c])
                    + (a3 * i3[c] + b3 * r3[c])
                )
            if p0 >= 0:
                for c in range(_N_PATCH):
                    q = p0 + c
                    dr[_N_MOB + c] += (
                        (a0 * r0[q] - b0 * i0[q])
                        + (a1 * r1[q] - b1 * i1[q])
                        + (a2 * r2[q] - b2 * i2[q])
                        + (a3 * r3[q] - b3 * i3[q])
                    )
                    di[_N_MOB + c] += (
                        (a0 * i0[q] + b0 * r0[q])
                        + (a1 * i1[q] + b1 * r1[q])
                        + (a2 * i2[q] + b2 * r2[q])
                        + (a3 * i3[q] + b3 * r3[q])
                    )
        else:  # the end intervals: linear, two nodes
            a0, b0, a1, b1 = cr[t, 0], ci[t, 0], cr[t, 1], ci[t, 1]
            r0, i0, r1, i1 = Zr[n0, r], Zi[n0, r], Zr[n0 + 1, r], Zi[n0 + 1, r]
            for c in range(_N_MOB):
                dr[c] += (a0 * r0[c] - b0 * i0[c]) + (a1 * r1[c] - b1 * i1[c])
                di[c] += (a0 * i0[c] + b0 * r0[c]) + (a1 * i1[c] + b1 * r1[c])
            if p0 >= 0:
                for c in range(_N_PATCH):
                    q = p0 + c
                    dr[_N_MOB + c] += (a0 * r0[q] - b0 * i0[q]) + (a1 * r1[q] - b1 * i1[q])
                    di[_N_MOB + c] += (a0 * i0[q] + b0 * r0[q]) + (a1 * i1[q] + b1 * r1[q])


@njit(**_JIT)
def _fold(
    accr: FloatArray,
    acci: FloatArray,
    lines: IntArray,
    nt: int,
    w: FloatArray,
    nn: int,
    kc: int,
    H: ComplexArray,
    z_cl: ComplexArray,
    mem: IntArray,
    n0: int,
    Zr: FloatArray,
    Zi: FloatArray,
    p0: int,
    cr: FloatArray,
    ci: FloatArray,
) -> None:
    """A cluster's terms ``w_i sum_q H[t, q] z_(i,j)^q Z_i[member j]``: its moments
    ``sum_j z_(i,j)^q Z_i[member j]`` folded into the coefficients."""
    for j in range(kc):
        for i in range(nn):
            x = z_cl[i, j]
            for t in range(nt):
                e = H[t, kc - 1]
                for q in range(kc - 2, -1, -1):
                    e = e * x + H[t, q]
                e = w[lines[t], i] * e
                cr[t, i] = e.real
                ci[t, i] = e.imag
        _mac(accr, acci, nt, cr, ci, Zr, Zi, n0, nn, mem[j], p0)


@njit(**_JIT)
def _partials(a: ComplexArray, kc: int, z: complex, out: ComplexArray) -> None:
    """Horner partial sums ``out[i] = sum_(i' <= i) a[i'] z^(i - i')``, i = 0..kc."""
    out[0] = a[0]
    for i in range(1, kc + 1):
        out[i] = out[i - 1] * z + a[i]


@njit(**_JIT)
def _norm1(x: complex) -> float:
    """``|Re x| + |Im x|`` (between ``|x|`` and ``sqrt(2) |x|``, without a square root)."""
    return abs(x.real) + abs(x.imag)


@njit(**_JIT)
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
                ratio = p / dp
                sm = 0j
                for i in range(kc):
                    if i != j:
                        sm += 1.0 / (x - out[i])
                out[j] = x - ratio / (1.0 - ratio * sm)
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
def _flush(tb: ComplexArray, b: int, nt: int, accr: FloatArray, acci: FloatArray) -> None:
    """Add an accumulator to block ``b`` of the tile's sums and clear it."""
    n = tb.shape[2]
    for t in range(nt):
        row = tb[b, t]
        for c in range(n):
            row[c] += accr[t, c] + 1j * acci[t, c]
            accr[t, c] = 0.0
            acci[t, c] = 0.0


@njit(**_JIT)
def _finish(
    tb: ComplexArray,
    tb0: ComplexArray,
    lines: IntArray,
    nt: int,
    s: ComplexArray,
    static: bool,
    extra: ComplexArray,
    Y: ComplexArray,
    v: ComplexArray,
) -> None:
    """The tile's block sums -> sums up to every returned block (as ``np.cumsum``), with
    the static parts of the modes after it and ``extra``, times ``j omega``."""
    n_out = Y.shape[0]
    n_cols = tb.shape[2]
    n_v = v.shape[2]
    cum = np.empty(n_cols, np.complex128)
    cum0 = np.empty(n_cols, np.complex128)
    tot0 = np.empty(n_cols, np.complex128)
    for t in range(nt):
        ln = lines[t]
        if static:
            tot0[:] = tb0[0, t]
            for b in range(1, tb0.shape[0]):
                for c in range(n_cols):
                    tot0[c] += tb0[b, t, c]
            cum0[:] = 0.0
        cum[:] = 0.0
        for b in range(n_out):
            for c in range(n_cols):
                cum[c] += tb[b, t, c]
                x = cum[c]
                if static:
                    cum0[c] += tb0[b, t, c]
                    x = x + (tot0[c] - cum0[c])
                if extra.shape[0] > 0:
                    x = x + extra[ln, c]
                x = x * s[ln]
                if c < _N_MOB:
                    Y[b, ln, c] = x
                elif n_v > 0:
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
    poles: ComplexArray,
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
    static: bool,
    tb: ComplexArray,
    tb0: ComplexArray,
) -> None:
    """The block sums ``tb`` (and static parts ``tb0``) of one tile: lines of interval
    ``kk`` ranked at ``op``.

    The modes are taken by rank, so the blocks come one after the other and each is
    summed in a small accumulator; a cluster is taken whole at its lowest-ranked member
    (the part of a split cluster in a later block goes straight to that block's sums).
    """
    nt = lines.size
    n_cols = tb.shape[2]
    n0 = node0[kk]
    nn = n_nodes[kk]
    n_pass = 2 if static else 1  # the dynamic terms, then the static ones
    acc = np.zeros((2, 2, TILE, n_cols))  # the current block's sums: [pass, re/im]
    xacc = np.zeros((2, TILE, n_cols))  # a split cluster's part in a later block
    cr = np.zeros((TILE, 4))  # coefficients of the residue rows at the nodes
    ci = np.zeros((TILE, 4))
    T = np.empty((2, TILE), np.complex128)  # a lone mode: 1 / (s - lambda), -1 / lambda
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
        if b != cur:
            for ps_ in range(n_pass):
                _flush(tb if ps_ == 0 else tb0, cur, nt, acc[ps_, 0], acc[ps_, 1])
            cur = b
        cc = cluster_of[kk, r]
        if cc < 0:  # outside every cluster: e = w_i / (s - lambda)
            for t in range(nt):
                ln = lines[t]
                lam = 0j
                for i in range(nn):
                    lam += w[ln, i] * poles[n0 + i, r]
                T[0, t] = 1.0 / (s[ln] - lam)
                T[1, t] = -1.0 / lam if lam != 0 else 0j
            for ps_ in range(n_pass):
                for t in range(nt):
                    for i in range(nn):
                        e = w[lines[t], i] * T[ps_, t]
                        cr[t, i] = e.real
                        ci[t, i] = e.imag
                _mac(acc[ps_, 0], acc[ps_, 1], nt, cr, ci, Zr, Zi, n0, nn, r, p0)
            continue
        # a cluster, all of it at its lowest-ranked member
        kc = size[cc]
        mem = members[cc]
        first = True
        whole = True
        for j in range(kc):
            if block[op, mem[j]] != b:
                whole = False
            if rank[op, mem[j]] < rk:
                first = False
        if not first:
            continue
        c = cc_all[cc]
        rho = rho_all[cc]
        z_cl = z_all[cc]
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
                smem[j] = mem[j]
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
                        x += w[ln, i] * z_cl[i, j]
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
        for ib in range(n_blk):  # into this block's accumulator, or straight into a later one
            here = blocks[ib] == b
            for ps_ in range(n_pass):
                ar = acc[ps_, 0] if here else xacc[0]
                ai = acc[ps_, 1] if here else xacc[1]
                _fold(ar, ai, lines, nt, w, nn, kc, H[ib, ps_], z_cl, mem, n0, Zr, Zi, p0, cr, ci)
                if not here:
                    _flush(tb if ps_ == 0 else tb0, blocks[ib], nt, ar, ai)
    for ps_ in range(n_pass):
        _flush(tb if ps_ == 0 else tb0, cur, nt, acc[ps_, 0], acc[ps_, 1])


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
    poles: ComplexArray,
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
    n_cols = _N_MOB + v.shape[2]
    tb = np.empty((n_blocks, TILE, n_cols), np.complex128)  # a tile's block sums
    tb0 = np.empty((n_blocks if static else 0, TILE, n_cols), np.complex128)
    for ti in range(ptr.size - 1):
        lines = lines_all[ptr[ti] : ptr[ti + 1]]
        nt = lines.size
        tb[:, :nt] = 0.0
        tb0[:, :nt] = 0.0
        _tile(
            lines,
            kint[lines[0]],
            op_all[lines[0]],
            s,
            w,
            node0,
            n_nodes,
            poles,
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
            static,
            tb,
            tb0,
        )
        _finish(tb, tb0, lines, nt, s, static, extra, Y, v)
