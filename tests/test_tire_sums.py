"""The compiled modal sums of the tire (fbs_core.tire.sums) against a direct evaluation.

Truth: the interpolation of :mod:`fbs_core.tire.interp` evaluated directly, line by line
and mode by mode, as the numpy code before the kernel did: every mode outside a cluster
with its pole and residue interpolated by the Lagrange weights, every cluster whole in a
block by its rational form (``interp.cluster_sum`` with the stored moments) and a cluster
split by a block edge by its roots (``interp.cluster_at``: companion eigenvalues), each
root to the member ranked alike at the nearer operating point. The kernel folds the
moments into its coefficients and finds the roots by the Aberth iteration, so the sums
agree to rounding (1e-12 of the largest, per line), not bit for bit. Then: a line's sums
do not depend on the other lines of the call (bit for bit), whatever came before.
"""

import multiprocessing
import os
import subprocess
import sys
import threading

import numpy as np
import pytest

from fbs_core import harmonic
from fbs_core.tire import TireModel, interp, reference_tire, sums


@pytest.fixture(scope="module")
def tire():
    return reference_tire()


def direct_sums(tire, freq, speeds, n_list, h_index, residual=False):
    """Mobility (n_N, n_f, 6, 6) and velocity (n_N, n_f, 6): the old path, line by line."""
    f = np.asarray(freq, float)
    v_all = np.asarray(speeds, float) * np.ones(f.size)
    k = tire.interval_of(v_all)
    sp = tire.speeds
    t = np.clip((v_all - sp[k]) / (sp[k + 1] - sp[k]), 0.0, 1.0)
    cols = np.arange(36)
    if h_index is not None:
        cols = np.r_[cols, 36 + 6 * h_index + np.arange(6)]
    edges = np.r_[0, n_list]
    full = edges if edges[-1] == tire.n_modes else np.r_[edges, tire.n_modes]
    n_b = len(full) - 1
    dyn = np.zeros((n_b, f.size, cols.size), complex)
    sta = np.zeros_like(dyn)
    intervals = {}
    for line in range(f.size):
        kk = int(k[line])
        if kk not in intervals:  # the clusters with their moments, as before the kernel
            intervals[kk] = tire.interval(kk, cols)
        iv = intervals[kk]
        v = sp[kk] + t[line] * (sp[kk + 1] - sp[kk])
        w = interp.lagrange_weights(iv.speeds, [v])  # (1, n_nodes)
        s = 2j * np.pi * f[line]
        # truncation order at the nearer operating point: pairs by eigenfrequency there
        pairs = np.argsort(tire.poles[kk + int(t[line] >= 0.5), 0::2].imag, kind="stable")
        order = np.stack([2 * pairs, 2 * pairs + 1], axis=-1).ravel()
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        block = np.searchsorted(full, rank, side="right") - 1
        block[rank >= full[-1]] = -1
        inside = np.zeros(tire.n_modes, bool)
        for cl in iv.clusters:
            inside[cl.members.ravel()] = True
            for c in range(cl.members.shape[0]):
                one = interp.subset(cl, [c])
                b = block[one.members[0]]
                if np.all(b == b[0]):
                    if b[0] >= 0:
                        dyn[b[0], line] += interp.cluster_sum(one, w, [s])[0]
                        sta[b[0], line] += interp.cluster_sum(one, w, [0.0])[0]
                    continue
                p, r = interp.cluster_at(one, w)  # roots by |Im|, lowest first
                ranked = one.members[0][np.argsort(rank[one.members[0]])]
                for j, m in enumerate(ranked):
                    if block[m] >= 0:
                        dyn[block[m], line] += r[0, 0, j] / (s - p[0, 0, j])
                        sta[block[m], line] += -r[0, 0, j] / p[0, 0, j]
        for m in np.flatnonzero(~inside):
            if block[m] < 0:
                continue
            lam = (w @ iv.poles[:, m])[0]
            R = (w @ iv.residues[:, m])[0]
            dyn[block[m], line] += R / (s - lam)
            if lam != 0:
                sta[block[m], line] += -R / lam
    nb = len(n_list)
    out = np.cumsum(dyn, axis=0)[:nb]
    if residual and n_list != [tire.n_modes]:
        out += sta.sum(axis=0)[None] - np.cumsum(sta, axis=0)[:nb]
    out *= 2j * np.pi * f[None, :, None]
    Y = out[:, :, :36].reshape(nb, f.size, 6, 6)
    return Y, (out[:, :, 36:] if h_index is not None else None)


def close_per_line(a, b, rtol=1e-12):
    """``|a - b| <= rtol * max |b|`` line by line (axis 1), over everything else."""
    scale = np.abs(b).max(axis=tuple(i for i in range(b.ndim) if i != 1), keepdims=True)
    err = np.abs(a - b) / scale
    assert err.max() <= rtol, (err.max(), np.unravel_index(err.argmax(), err.shape))


@pytest.mark.parametrize(
    "k, df, n_list",
    [
        (2, 4.0, list(range(10, 401, 10))),  # every block edge splits some clusters
        (5, 3.0, [60]),
        (7, 7.0, [30, 44, 196, 400]),
    ],
)
def test_truncations_equal_the_direct_evaluation(tire, k, df, n_list):
    h = harmonic(k)
    f = h.frequencies(df)
    hi = tire._harmonic_index(h)
    for residual in (False, True):
        Y, v = tire.truncations(f, h, n_list, residual=residual)
        Yd, vd = direct_sums(tire, f, h.speed_at(f), n_list, hi, residual)
        close_per_line(Y, Yd)
        close_per_line(v, vd)


def test_fixed_speeds_and_any_line_order_equal_the_direct_evaluation(tire):
    rng = np.random.default_rng(3)
    f = rng.uniform(5.0, 400.0, 36)
    v = rng.uniform(20.0, 120.0, 36)
    v[:20] = 73.3  # many lines at one speed, as a speed map
    v[20:25] = tire.speeds[[0, 5, 21, -2, -1]]  # at operating points, both ends included
    for n, h_index in ((None, 3), (100, None), (48, 6)):
        Y, x = tire.synthesis(f, v, h_index, n)
        Yd, xd = direct_sums(tire, f, v, [n or tire.n_modes], h_index)
        close_per_line(Y, Yd[0])
        if h_index is not None:
            close_per_line(x, xd[0])
    fs = np.sort(f[:20])
    Y = tire.hub_mobility(fs, 73.3, n_modes=100, residual=True).data
    close_per_line(Y[None], direct_sums(tire, fs, v[:20], [100], None, True)[0])


def test_linear_and_cluster_interpolation_equal_the_direct_evaluation(tire):
    """Two-node stencils everywhere: plain linear weights (no clusters) and clusters with
    linear weights, on a model of fewer operating points."""
    sub = np.flatnonzero(np.isin(tire.speeds, (20.0, 40.0, 60.0, 80.0, 100.0, 120.0)))
    data = (
        tire.speeds[sub],
        tire.poles[sub],
        tire.psi[sub],
        tire.chi[sub],
        tire.wavelengths,
        tire.participation[sub],
    )
    h = harmonic(4)
    f = h.frequencies(4.0)
    for how in ("linear", "cluster"):
        model = TireModel(*data, interpolation=how)
        assert (how == "linear") == (model._flat().size.size == 0)
        n_list = [20, 50, 130, 400]
        Y, v = model.truncations(f, h, n_list, residual=True)
        Yd, vd = direct_sums(model, f, h.speed_at(f), n_list, 3, True)
        close_per_line(Y, Yd)
        close_per_line(v, vd)


def test_a_lines_sums_do_not_depend_on_the_other_lines(tire):
    """Bit for bit: every line is summed alone, so a subset of the lines, in another
    order, gives the same numbers as the whole grid (and a repeated call the same)."""
    h = harmonic(6)
    f = h.frequencies(1.0)
    ns = [10, 60, 140, 400]
    Y, v = tire.truncations(f, h, ns, residual=True)
    pick = np.random.default_rng(0).permutation(f.size)[:17]
    Ys, vs = tire._sums(f[pick], h.speed_at(f[pick]), ns, tire._harmonic_index(h), True)
    assert np.array_equal(Ys, Y[:, pick]) and np.array_equal(vs, v[:, pick])
    Y2, v2 = tire.truncations(f, h, ns, residual=True)
    assert np.array_equal(Y2, Y) and np.array_equal(v2, v)


_FRESH = """
import numpy as np, fbs_core
from fbs_core import harmonic
tire = fbs_core.reference_tire()
{before}
h = harmonic(3)
Y, v = tire.truncations(h.frequencies(2.0), h, [20, 90, 400], residual=True)
np.save({out!r}, np.concatenate([Y.ravel(), v.ravel()]))
"""


def test_numbers_do_not_depend_on_what_the_process_computed_before(tmp_path):
    """A fresh process and one that first computed other harmonics, counts and speeds
    give the same bits."""
    before = (
        "for k in (7, 3, 1):\n"
        "    g = harmonic(k).frequencies(1.0)\n"
        "    tire.truncations(g, harmonic(k), [60])\n"
        "    tire.truncations(g, harmonic(k), list(range(10, 401, 10)), residual=True)\n"
        "tire.hub_mobility(np.linspace(10, 300, 50), 66.6, n_modes=40)"
    )
    out = []
    for i, code in enumerate(("", before)):
        path = tmp_path / f"{i}.npy"
        src = _FRESH.format(before=code, out=str(path))
        subprocess.run([sys.executable, "-c", src], check=True)
        out.append(np.load(path))
    assert np.array_equal(out[0], out[1])


def test_the_reciprocals_are_complex_division_bit_for_bit():
    """The kernel's vectorised ``u / d`` (u = +-1, lone modes' ``1 / (s - lambda)`` and
    ``-1 / lambda``) against Python's complex division (the algorithm of compiled code)."""
    rng = np.random.default_rng(5)
    re = rng.normal(size=400) * 10.0 ** rng.uniform(-3, 4, 400)
    im = rng.normal(size=400) * 10.0 ** rng.uniform(-3, 4, 400)
    re[:5], im[5:10] = 0.0, 0.0  # on the axes
    for u in (1.0, -1.0):
        for a, b in zip(re, im, strict=True):
            want = u / complex(a, b)
            got = sums._inverse(a, b, u)
            assert (got[0], got[1]) == (want.real, want.imag), (a, b, u)


@pytest.mark.parametrize("kc", [3, 4])
def test_the_roots_of_a_split_cluster_equal_the_companion_eigenvalues(kc):
    """The Aberth iteration (one complex division per step) against numpy's eigenvalues
    of the companion matrix, for the scaled poles of a cluster (``(lambda - c) / rho``:
    around 0, within about 1, two of them closer), from start values off by a few
    percent; sorted by ``sign * Im``."""
    rng = np.random.default_rng(kc)
    out = np.empty(4, complex)
    for trial in range(300):
        z = rng.uniform(-1, 1, kc) + 1j * rng.uniform(-1, 1, kc)
        z[1] = z[0] + 10.0 ** rng.uniform(-2, 0) * np.exp(2j * np.pi * rng.random())
        al = np.zeros(5, complex)
        al[: kc + 1] = np.poly(z)
        start = np.zeros(4, complex)
        start[:kc] = z + 0.03 * (rng.normal(size=kc) + 1j * rng.normal(size=kc))
        sign = 1.0 if trial % 2 else -1.0
        sums._roots(al, kc, start, sign, out)
        comp = np.zeros((kc, kc), complex)
        comp[0] = -al[1 : kc + 1]
        comp[np.arange(1, kc), np.arange(kc - 1)] = 1.0
        want = np.linalg.eigvals(comp)
        want = want[np.argsort(sign * want.imag, kind="stable")]
        assert np.abs(out[:kc] - want).max() <= 1e-12, (trial, out[:kc], want)


def _union_find_groups(lam0, lam1, kappa, moving):
    """The groups of close modes by a plain union-find (the former implementation)."""
    n = lam0.size
    parent = list(range(n))

    def find(i):
        while parent[i] != i:
            i = parent[i]
        return i

    for lam in (lam0, lam1):
        for i in range(n):
            for j in range(i + 1, n):
                near = abs(lam[i] - lam[j]) < kappa * (abs(lam[i].real) + abs(lam[j].real))
                if near and (moving[i] or moving[j]):
                    a, b = find(i), find(j)
                    parent[max(a, b)] = min(a, b)
    roots = [find(i) for i in range(n)]
    return [np.flatnonzero(np.array(roots) == r) for r in sorted(set(roots))]


def test_groups_of_close_modes_equal_a_union_find():
    rng = np.random.default_rng(1)
    for _ in range(20):
        n = 40
        lam0 = -rng.uniform(1, 10, n) + 1j * np.sort(rng.uniform(0, 300, n))
        lam1 = lam0 + rng.normal(scale=3.0, size=n) + 1j * rng.normal(scale=3.0, size=n)
        moving = rng.random(n) < 0.7
        groups = interp._components(lam0, lam1, np.arange(n), 0.3, moving)
        expect = _union_find_groups(lam0, lam1, 0.3, moving)
        assert [g.tolist() for g in groups] == [g.tolist() for g in expect]


def test_interval_refuses_what_it_does_not_hold(tire):
    from fbs_core.errors import FBSError
    from fbs_core.tire import OperatingPointError

    n_int = tire.speeds.size - 1
    assert tire.interval_of([tire.speeds[0], tire.speeds[-1]]).tolist() == [0, n_int - 1]
    with pytest.raises(OperatingPointError, match="outside the operating points"):
        tire.interval_of(tire.speeds[-1] + 1.0)
    for k, cols in ((-1, None), (n_int, None), (0, [36 + 6 * tire.wavelengths.size]), (0, [0.5])):
        with pytest.raises(FBSError, match="must be 0.."):
            tire.interval(k, cols)
    iv = tire.interval(3, [0, 7])
    assert iv.residues.shape == (iv.speeds.size, tire.n_modes, 2)
    assert not iv.residues.flags.writeable


def _threaded(monkeypatch, n):
    """The kernel's tiles on ``n`` threads; the threads that ran a tile are recorded."""
    ran = set()
    kernel = sums._kernel

    def kernel_here(*args):
        ran.add(threading.get_ident())
        return kernel(*args)

    monkeypatch.setattr(sums, "_threads", lambda n_tiles: min(n, max(1, n_tiles)))
    monkeypatch.setattr(sums, "_kernel", kernel_here)
    return ran


def test_the_tiles_on_several_threads_give_the_same_bits(tire, monkeypatch):
    """Issue 33: a call's tiles dealt to helper threads (the kernel releases the GIL); each
    line is still summed by one thread from its own data: bit for bit one thread's sums."""
    h = harmonic(5)
    f = h.frequencies(0.5)
    ns = [10, 60, 140, 400]
    ran = _threaded(monkeypatch, 1)
    Y1, v1 = tire.truncations(f, h, ns, residual=True)
    assert len(ran) == 1
    ran = _threaded(monkeypatch, 3)
    Y3, v3 = tire.truncations(f, h, ns, residual=True)
    assert len(ran) == 3 and threading.get_ident() in ran
    assert np.array_equal(Y3, Y1) and np.array_equal(v3, v1)


def test_work_at_a_lowered_priority_keeps_to_its_own_thread():
    """Work computed ahead runs niced (app.runtime.background): it takes no helper threads,
    which would run at the normal priority beside the pages."""
    out = {}

    def probe(lower):
        if lower:
            os.setpriority(
                os.PRIO_PROCESS, threading.get_native_id(), os.getpriority(os.PRIO_PROCESS, 0) + 5
            )
        out[lower] = sums._threads(1000)

    for lower in (False, True):
        t = threading.Thread(target=probe, args=(lower,))
        t.start()
        t.join()
    cores = len(os.sched_getaffinity(0))
    assert out == {False: min(cores, sums.MAX_THREADS), True: 1}


def test_an_environment_variable_caps_the_threads(monkeypatch):
    """``FBS_TIRE_SUM_THREADS=1`` keeps a call's tiles on the calling thread (the bench's
    single-thread figures); a value that is no positive integer is refused."""
    from fbs_core.errors import FBSError

    monkeypatch.setattr(sums.os, "sched_getaffinity", lambda pid: set(range(8)))
    monkeypatch.delenv(sums.THREADS_ENV, raising=False)
    assert sums._threads(1000) == sums.MAX_THREADS
    for raw, want in (("1", 1), ("2", 2), (" 3 ", 3), ("64", sums.MAX_THREADS)):
        monkeypatch.setenv(sums.THREADS_ENV, raw)
        assert sums._threads(1000) == want
    assert sums._threads(4) == 1  # still no more threads than the tiles are worth
    for raw in ("0", "-1", "two", "1.5"):
        monkeypatch.setenv(sums.THREADS_ENV, raw)
        with pytest.raises(FBSError, match=sums.THREADS_ENV):
            sums._threads(1000)


def _child_sums(q):
    import fbs_core

    sums._threads = lambda n_tiles: 2  # the parent's pool has no threads in this process
    h = harmonic(2)
    Y, _ = fbs_core.reference_tire().truncations(h.frequencies(1.0), h, [40, 400])
    q.put(Y)


def test_a_forked_child_makes_its_own_helper_threads(tire, monkeypatch):
    """A process forked after the pool was made (report and upload children) gets a pool of
    its own; with the parent's copy, whose threads do not exist there, the call would hang."""
    _threaded(monkeypatch, 2)
    h = harmonic(2)
    Y, _ = tire.truncations(h.frequencies(1.0), h, [40, 400])
    assert sums._pool is not None  # made by the call above
    ctx = multiprocessing.get_context("fork")
    q = ctx.Queue()
    p = ctx.Process(target=_child_sums, args=(q,))
    p.start()
    got = q.get(timeout=300)  # waits for the child's result (a hang fails here)
    p.join(300)
    assert np.array_equal(got, Y)
