"""Compiled kernels of the studies: small complex solves and the counter-based RNG."""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.studies import _noise_kernels, _rng

MASK = (1 << 64) - 1
G = 0x9E3779B97F4A7C15


def _mix(z):
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
    return z ^ (z >> 31)


def _factors_python(seed, r, line, p, n_el):
    """Pure-Python SplitMix64 streams, as documented in fbs_core.studies._rng."""
    key = _mix((seed + G) & MASK)
    base = _mix((_mix((key + (r + 1) * G) & MASK) + (line + 1) * G) & MASK)
    out = []
    for k in range((n_el + 1) // 2):
        w = _mix((base + (k + 1) * G) & MASK)
        hi, lo = (w >> 32) * 2.0**-32, (w & 0xFFFFFFFF) * 2.0**-32
        out += [1 + p * (2 * hi - 1), 1 + p * (2 * lo - 1)]
    return np.array(out[:n_el])


def _rand_c(rng, *shape):
    return rng.normal(size=shape) + 1j * rng.normal(size=shape)


def _numba_solve(A, b):
    """Solve ``A x = b`` with the production kernel: eq. 4.1 with ``Y_jj^E = 0``,
    ``Y_ej^E = I`` and no noise gives ``x = A^-1 b`` at every "line"."""
    m, n = b.shape
    eye = np.broadcast_to(np.eye(n), (m, n, n))
    zero = np.zeros((m, n, n))
    args = [np.ascontiguousarray(x) for z in (A, b) for x in (z.real, z.imag)]
    args[4:4] = [zero, zero]
    args += [np.ascontiguousarray(eye), zero, _noise_kernels.pivot_order(A, 0 * A)]
    for x in args:
        x.setflags(write=False)  # the signature the library compiles
    out = np.empty((1, m, n), complex)
    _noise_kernels.noisy_block_run(
        *args,
        0,
        m,
        _rng.seed_key(0),
        np.zeros(1, np.int64),
        0.0,
        False,
        False,
        False,
        np.empty((0, 0, 0)),
        out,
    )
    return out[0]


def test_numba_solve_equals_numpy_solve():
    rng = np.random.default_rng(0)
    A = _rand_c(rng, 500, 6, 6)
    A[:50, 0, 0] = 0.0  # forces a row exchange
    A[50:100] *= np.logspace(-6, 6, 6)  # badly scaled columns
    A[100:150, :, :3] *= 1e-8  # small leading pivots
    b = _rand_c(rng, 500, 6)
    x = _numba_solve(A, b)
    ref = np.linalg.solve(A, b[..., None])[..., 0]
    np.testing.assert_allclose(x, ref, rtol=1e-9, atol=0)
    np.testing.assert_allclose(np.einsum("mij,mj->mi", A, x), b, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("n", [1, 2, 5, 6])
def test_numba_solve_any_small_size(n):
    rng = np.random.default_rng(n)
    A = _rand_c(rng, 40, n, n)
    b = _rand_c(rng, 40, n)
    np.testing.assert_allclose(
        _numba_solve(A, b), np.linalg.solve(A, b[..., None])[..., 0], rtol=1e-10
    )


def test_numpy_factors_equal_kernel_factors():
    """noise_factors (numpy) and the compiled lanes draw the same numbers: a kernel run with
    A = I, E = 0, B = I gives y = s_a o a, i.e. the factors of the load vector."""
    n, m = 6, 3
    a = np.ones((m, n), complex)
    eye = np.ascontiguousarray(np.broadcast_to(np.eye(n), (m, n, n)))
    zero = np.zeros((m, n, n))
    args = [
        eye,
        zero,
        a.real.copy(),
        a.imag.copy(),
        zero,
        zero,
        eye,
        zero,
        np.tile(np.arange(n), (m, 1)),
    ]
    for x in args:
        x.setflags(write=False)
    rids = np.array([0, 7, 33], np.int64)
    out = np.empty((3, m, n), complex)
    key = _rng.seed_key(9)
    _noise_kernels.noisy_block_run(
        *args, 0, m, key, rids, 0.1, True, False, True, np.empty((0, 0, 0)), out
    )
    lines = np.tile(np.arange(m), 3)
    s = _noise_kernels.noise_factors(key, np.repeat(rids, m), lines, 0.1, n, n, True, False)
    S = fc.studies.scatter.split_factors(s.reshape(3, m, -1), n, n)
    # y = S_A^-1-free: with A = I scaled by S_A (diagonal only matters), x = s_a / diag(S_A)
    d = np.einsum("rfii->rfi", S["Yjj_A"])
    np.testing.assert_allclose(out, S["vj_A"] / d, rtol=1e-13)


def test_lane_kernel_equals_numpy_on_random_systems():
    """Noisy eq. 4.1 of the vectorised kernel == np.linalg.solve with the same factors."""
    rng = np.random.default_rng(2)
    nf, nj, ne = 7, 6, 6
    A, E, B = _rand_c(rng, nf, nj, nj), _rand_c(rng, nf, nj, nj), _rand_c(rng, nf, ne, nj)
    a = _rand_c(rng, nf, nj)
    A[:, 0, 0] = -E[:, 0, 0]  # zero pivot in the noise-free matrix
    key = _rng.seed_key(5)
    rids = np.array([0, 3, 40, 41, 77], np.int64)  # spans two lane blocks
    for fd in (False, True):
        out = np.empty((rids.size, nf, ne), complex)
        args = [x for z in (A, a, E, B) for x in (z.real.copy(), z.imag.copy())]
        args.append(_noise_kernels.pivot_order(A, E))
        for x in args:
            x.setflags(write=False)
        _noise_kernels.noisy_block_run(
            *args, 0, nf, key, rids, 0.1, True, True, fd, np.empty((0, 0, 0)), out
        )
        lines = np.tile(np.arange(nf) if fd else np.zeros(nf, np.int64), rids.size)
        s = _noise_kernels.noise_factors(key, np.repeat(rids, nf), lines, 0.1, nj, ne, True, True)
        S = fc.studies.scatter.split_factors(s.reshape(rids.size, nf, -1), nj, ne)
        x = np.linalg.solve(S["Yjj_A"] * A + S["Yjj_E"] * E, (S["vj_A"] * a)[..., None])
        y = np.einsum("rfek,rfk->rfe", S["Yej_E"] * B, x[..., 0])
        np.testing.assert_allclose(out, y, rtol=1e-10, atol=1e-12 * np.abs(y).max())


def test_pivot_order_is_lapack_partial_pivoting():
    import scipy.linalg as sla

    rng = np.random.default_rng(4)
    A, E = _rand_c(rng, 30, 6, 6), _rand_c(rng, 30, 6, 6)
    A[:10] *= np.logspace(-5, 5, 6)[:, None]  # rows of very different size
    order = _noise_kernels.pivot_order(A, E)
    for line in range(30):
        P = sla.lu(A[line] + E[line])[0]
        np.testing.assert_array_equal(order[line], np.argmax(P, axis=0))


def test_row_order_changes_no_result():
    rng = np.random.default_rng(5)
    m, n = 20, 6
    A, b = _rand_c(rng, m, n, n), _rand_c(rng, m, n)
    x = _numba_solve(A, b)
    # the kernel pre-orders rows by pivoting; any other order gives the same solution
    eye = np.ascontiguousarray(np.broadcast_to(np.eye(n), (m, n, n)))
    zero = np.zeros((m, n, n))
    args = [
        A.real.copy(),
        A.imag.copy(),
        b.real.copy(),
        b.imag.copy(),
        zero,
        zero,
        eye,
        zero,
        np.tile(np.arange(n)[::-1].copy(), (m, 1)),
    ]
    for y in args:
        y.setflags(write=False)
    out = np.empty((1, m, n), complex)
    _noise_kernels.noisy_block_run(
        *args,
        0,
        m,
        _rng.seed_key(0),
        np.zeros(1, np.int64),
        0.0,
        False,
        False,
        False,
        np.empty((0, 0, 0)),
        out,
    )
    np.testing.assert_allclose(out[0], x, rtol=1e-10)


def test_rng_matches_python_reference():
    n_el = _noise_kernels.n_elements(6, 6)
    for seed, r, line in [(0, 0, 0), (1, 9999, 0), (12345, 17, 1999), (2**63 + 5, 3, 7)]:
        key = _rng.seed_key(seed)
        s = _noise_kernels.noise_factors(
            key, np.array([r]), np.array([line]), 0.1, 6, 6, True, True
        )
        np.testing.assert_array_equal(s[0], _factors_python(seed, r, line, 0.1, n_el))


def test_rng_is_uniform_on_the_interval_and_independent():
    p = 0.1
    n = 4000
    key = _rng.seed_key(0)
    s = _noise_kernels.noise_factors(key, np.arange(n), np.zeros(n, np.int64), p, 6, 6, True, True)
    assert s.min() >= 1 - p and s.max() < 1 + p
    u = (s.ravel() - (1 - p)) / (2 * p)
    # mean 1/2, variance 1/12 of U(0, 1); histogram flat (chi-square, 20 bins)
    assert abs(u.mean() - 0.5) < 5 * np.sqrt(1 / 12 / u.size)
    assert abs(u.var() - 1 / 12) < 0.002
    hist = np.histogram(u, bins=20, range=(0, 1))[0]
    expected = u.size / 20
    chi2 = ((hist - expected) ** 2 / expected).sum()
    assert chi2 < 50  # 19 dof: P(chi2 > 50) ~ 1e-4
    # neighbouring elements and rounds are uncorrelated
    assert abs(np.corrcoef(s[:, 0], s[:, 1])[0, 1]) < 0.06
    assert abs(np.corrcoef(s[:-1, 0], s[1:, 0])[0, 1]) < 0.06


def test_rng_streams_differ_by_seed_round_and_line():
    key0, key1 = _rng.seed_key(0), _rng.seed_key(1)
    r = np.array([0, 0, 1]), np.array([0, 1, 0])
    s0 = _noise_kernels.noise_factors(key0, *r, 0.1, 6, 6, True, True)
    s1 = _noise_kernels.noise_factors(key1, *r, 0.1, 6, 6, True, True)
    assert not np.any(s0[0] == s0[1]) and not np.any(s0[0] == s0[2])
    assert not np.any(s0 == s1)


def test_seed_validation():
    assert _rng.as_seed(7) == 7
    g1, g2 = np.random.default_rng(3), np.random.default_rng(3)
    assert _rng.as_seed(g1) == _rng.as_seed(g2)
    for bad in (-1, 2**64, 1.5, "1", True):
        with pytest.raises(fc.FBSError, match="seed"):
            _rng.as_seed(bad)


def _stats(mag, qs):
    nl, ne, R = mag.shape
    ck = np.array([R], np.int64)
    out = [np.empty((nl, ne)) for _ in range(2)] + [np.empty((nl, ne), np.int64) for _ in range(2)]
    pct = np.empty((len(qs), nl, ne))
    conv = [np.empty((1, nl, ne)) for _ in range(2)]
    _noise_kernels.band_stats(mag, np.asarray(qs, float), ck, *out, pct, *conv, 0)
    return out, pct


@pytest.mark.parametrize("R", [7, 1000, 5000])
def test_band_percentiles_equal_numpy(R):
    """Both selection paths (plain quickselect, sample-bracketed) against np.percentile."""
    rng = np.random.default_rng(R)
    mag = rng.lognormal(size=(3, 4, R))
    mag[0, 0] = 2.0  # all equal
    mag[0, 1, : R // 2] = 1.0  # many ties
    qs = (0.0, 0.1, 5.0, 50.0, 95.0, 99.9, 100.0)
    (lo, hi, alo, ahi), pct = _stats(mag.copy(), qs)
    np.testing.assert_allclose(pct, np.percentile(mag, qs, axis=-1), rtol=1e-14, atol=0)
    np.testing.assert_array_equal(lo, mag.min(-1))
    np.testing.assert_array_equal(hi, mag.max(-1))
    np.testing.assert_array_equal(alo, mag.argmin(-1))
    np.testing.assert_array_equal(ahi, mag.argmax(-1))


def test_band_percentiles_when_the_sample_misleads():
    """An adversarial column whose stride sample is unrepresentative: the bracket misses
    and the exact fallback selection must still give numpy's percentiles."""
    R = 5000
    rng = np.random.default_rng(0)
    col = rng.uniform(1.0, 2.0, R)
    m = _noise_kernels._SAMPLE
    col[(np.arange(m) * R) // m] = 1e-3 * (1 + np.arange(m))  # sample: all tiny
    col[1] = 1e9  # an outlier: the histogram's bins are too coarse, it declines too
    assert not _noise_kernels._order_stats_histogram(
        col, col.min(), col.max(), np.array([R // 2]), np.empty(1)
    )
    mag = np.ascontiguousarray(np.broadcast_to(col, (1, 1, R)))
    qs = (5.0, 50.0, 95.0)
    _, pct = _stats(mag.copy(), qs)
    np.testing.assert_allclose(pct[:, 0, 0], np.percentile(col, qs), rtol=1e-14)


@pytest.mark.parametrize("shape", ["lognormal", "ties", "outliers"])
def test_histogram_order_statistics_are_exact(shape):
    """The one-histogram selection of many ranks gives the exact order statistics
    (against a full sort), or declines (heavy outliers) and leaves the work to the
    sampled selection, whose percentiles still equal numpy's."""
    R = 10_000
    rng = np.random.default_rng(1)
    col = rng.lognormal(size=R)
    if shape == "ties":
        col[::50] = np.median(col)  # 200 equal values, in one bin
    if shape == "outliers":
        col[:5] = 1e12  # all others fall into the first bin
    ranks = np.array([0, 1, 499, 500, 4999, 5000, 9498, 9499, 9998, 9999], np.int64)
    out = np.full(ranks.size, np.nan)
    before = col.copy()
    ok = _noise_kernels._order_stats_histogram(col, col.min(), col.max(), ranks, out)
    np.testing.assert_array_equal(col, before)  # the column is left as it was
    assert ok == (shape != "outliers")
    if ok:
        np.testing.assert_array_equal(out, np.sort(col)[ranks])
    else:
        assert np.all(np.isnan(out))
    mag = np.ascontiguousarray(np.broadcast_to(col, (1, 1, R)))
    qs = (1.0, 5.0, 50.0, 95.0, 99.0)
    _, pct = _stats(mag.copy(), qs)
    np.testing.assert_allclose(pct[:, 0, 0], np.percentile(col, qs), rtol=1e-14, atol=0)


def _running_reference(col, ck):
    """Minimum, maximum, first rounds attaining them and the checkpoint values, as the
    plain round-by-round loop ``v < mn`` / ``v > mx`` gives them (NaN never wins)."""
    mn = mx = col[0]
    imn = imx = 0
    conv = {}
    for r, v in enumerate(col):
        if v < mn:
            mn, imn = v, r
        if v > mx:
            mx, imx = v, r
        conv[r + 1] = (mn, mx)
    return mn, mx, imn, imx, np.array([conv[c] for c in ck])


@pytest.mark.parametrize("case", ["repeats", "nan_inside", "nan_first", "inf"])
def test_extremes_and_checkpoints_equal_the_round_loop(case):
    """The blocked minimum / maximum pass: the first round attaining an extreme when it
    recurs in later blocks, checkpoints on and beside block edges (and repeated), NaN
    skipped unless it is round 0, against the round-by-round loop."""
    R = 3000
    rng = np.random.default_rng(5)
    col = rng.lognormal(size=R)
    b = _noise_kernels._BLOCK
    col[[b - 1, b + 3, 2 * b + 1, R - 1]] = col.min() / 2  # the minimum, 4 times
    col[[3, b, 7 * b + 2]] = col.max() * 2
    if case == "nan_inside":
        col[[1, b + 1, R - 2]] = np.nan
    elif case == "nan_first":
        col[0] = np.nan
    elif case == "inf":
        col[b + 5] = np.inf
    ck = np.array([1, 3, b - 1, b, b, b + 1, 2 * b + 2, R], np.int64)
    mag = np.ascontiguousarray(np.broadcast_to(col, (1, 1, R)))
    out = [np.empty((1, 1)) for _ in range(2)] + [np.empty((1, 1), np.int64) for _ in range(2)]
    conv = [np.empty((ck.size, 1, 1)) for _ in range(2)]
    _noise_kernels.band_stats(mag, np.empty(0), ck, *out, np.empty((0, 1, 1)), *conv, 0)
    mn, mx, imn, imx, want = _running_reference(col, ck)
    np.testing.assert_array_equal([o[0, 0] for o in out], [mn, mx, imn, imx])
    np.testing.assert_array_equal(conv[0][:, 0, 0], want[:, 0])
    np.testing.assert_array_equal(conv[1][:, 0, 0], want[:, 1])


def test_histogram_declines_a_column_with_nan():
    """A NaN between finite values has no histogram bin: the histogram declines (instead of
    counting it at a stray index) and the band statistics still come out, minimum and
    maximum skipping the NaN."""
    R = 5000
    col = np.random.default_rng(2).lognormal(size=R)
    col[[7, 100, 4000]] = np.nan
    lo, hi = np.nanmin(col), np.nanmax(col)
    out = np.full(2, -1.0)
    assert not _noise_kernels._order_stats_histogram(col, lo, hi, np.array([10, 11]), out)
    np.testing.assert_array_equal(out, -1.0)
    mag = np.ascontiguousarray(np.broadcast_to(col, (1, 1, R)))
    (mn, mx, amn, amx), pct = _stats(mag.copy(), (5.0, 95.0))
    assert (mn[0, 0], mx[0, 0], amn[0, 0], amx[0, 0]) == (
        lo,
        hi,
        np.nanargmin(col),
        np.nanargmax(col),
    )
    assert pct.shape == (2, 1, 1)
