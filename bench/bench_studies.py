"""Speed of the sensitivity studies (issue 5), figures printed side by side.

Run:  .venv/bin/python bench/bench_studies.py            (cold JIT: fresh numba cache)
      .venv/bin/python bench/bench_studies.py --warm     (reuse the on-disk numba cache)

Each figure is the best of a few runs, with the CPU time of all threads beside it: on a
shared machine the wall times grow with the load average (printed first), the CPU times
much less.

Targets (2-core machine): full truncation study (7 harmonics x 40 N x 6 DOFs x floating
band) < 1 s; scatter band R = 10,000, 400 lines, frequency-dependent noise in both
subsystems < 0.3 s (issue 33; issue 5 asked < 1.5 s) and >= 10x faster than the plain
numpy baseline (batched np.linalg.solve over rounds x lines) run beside it.
"""

from __future__ import annotations

import os
import sys
import tempfile

if "--warm" not in sys.argv:
    os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="fbs-bench-numba-")

import resource  # noqa: E402
import time  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402

import fbs_core as fc  # noqa: E402
from fbs_core.studies import scatter_band_arrays, suggest_modes  # noqa: E402


def _t(fn, repeat=3):
    """Best wall time of ``repeat`` runs, the CPU time (all threads) of that run, result."""
    best, cpu = np.inf, np.nan
    out = None
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        out = fn()
        dt = time.perf_counter() - t
        if dt < best:
            best, cpu = dt, time.process_time() - c
    return best, cpu, out


def _rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _peak_rss_mb(fn):
    """Peak resident memory (MB) while ``fn`` runs (Linux: high-water mark reset first)."""
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
        with open("/proc/self/status") as fh:
            base = next(int(x.split()[1]) for x in fh if x.startswith("VmRSS"))
    except OSError:
        base = None
    fn()
    with open("/proc/self/status") as fh:
        hwm = next(int(x.split()[1]) for x in fh if x.startswith("VmHWM"))
    return hwm / 1024, (None if base is None else (hwm - base) / 1024)


def numpy_baseline(YjjA, vj, YjjE, YejE, p, R, seed=0, percentiles=(5.0, 95.0), chunk=8):
    """Plain numpy: uniform factors from a Generator, batched np.linalg.solve over
    rounds x lines (chunks of lines), then min / max / percentiles over rounds."""
    rng = np.random.default_rng(seed)
    nf, nj = vj.shape
    ne = YejE.shape[1]
    lo = np.empty((nf, ne))
    hi = np.empty((nf, ne))
    pct = np.empty((len(percentiles), nf, ne))
    for l0 in range(0, nf, chunk):
        sl = slice(l0, min(nf, l0 + chunk))
        n = sl.stop - sl.start

        def u(*shape, n=n):
            return rng.uniform(1 - p, 1 + p, size=(R, n) + shape)

        W = u(nj, nj) * YjjA[sl] + u(nj, nj) * YjjE[sl]
        x = np.linalg.solve(W, (u(nj) * vj[sl])[..., None])[..., 0]
        y = np.abs(np.einsum("rfek,rfk->rfe", u(ne, nj) * YejE[sl], x))
        lo[sl] = y.min(0)
        hi[sl] = y.max(0)
        pct[:, sl] = np.percentile(y, percentiles, axis=0)
    return lo, hi, pct


def scatter_inputs(nf=400, k=4):
    """Reference tire + chassis along harmonic k on nf lines (synthetic if no tire yet)."""
    h = fc.harmonic(k)
    f = np.linspace(*h.freq_range, nf)
    try:
        tire = fc.reference_tire()
        Y, v = tire.truncations(f, h, [tire.n_modes])
        C = fc.reference_chassis().mobility(f).data
        return Y[0], v[0], C[:, :6], C[:, 6:], "reference models"
    except (AttributeError, ImportError):
        rng = np.random.default_rng(0)

        def c(*s):
            return rng.normal(size=s) + 1j * rng.normal(size=s)

        return c(nf, 6, 6), c(nf, 6), c(nf, 6, 6), c(nf, 6, 6), "synthetic arrays"


def main():
    print(
        f"{os.cpu_count()} cores, numba {numba.__version__} with {numba.get_num_threads()} "
        f"threads, load average {os.getloadavg()[0]:.1f} (other jobs slow every figure), "
        f"numba cache: {'warm (on disk)' if '--warm' in sys.argv else 'cold (fresh dir)'}"
    )

    # -- JIT ----------------------------------------------------------------------------
    A, a, E, B, src = scatter_inputs(400)
    t = time.perf_counter()
    scatter_band_arrays(A[:4], a[:4], E[:4], B[:4], 0.1, "both", 64, True, seed=0)
    print(f"JIT compile / cache load of the scatter kernels: {time.perf_counter() - t:6.2f} s")

    # -- scatter band -------------------------------------------------------------------
    R = 10_000
    print(
        f"\nscatter band, R = {R}, {A.shape[0]} lines, 6 DOFs, frequency-dependent noise in "
        f"both subsystems ({src}):"
    )
    t_nb, c_nb, band = _t(lambda: scatter_band_arrays(A, a, E, B, 0.1, "both", R, True, seed=0))
    t_np, c_np, (lo, hi, pct) = _t(lambda: numpy_baseline(A, a, E, B, 0.1, R), repeat=1)
    t_nb2, c_nb2, _ = _t(lambda: scatter_band_arrays(A, a, E, B, 0.1, "both", R, True, seed=0))
    if t_nb2 < t_nb:
        t_nb, c_nb = t_nb2, c_nb2
    nth = numba.get_num_threads()
    print(
        f"  numba kernel (min/max, 5/95 %, convergence): {t_nb:7.3f} s wall, {c_nb:7.3f} s CPU "
        f"({c_nb / nth:.3f} s per thread)   target < 0.3 s on 2 cores (issue 33): "
        f"{'met' if t_nb < 0.3 else 'NOT met'}"
    )
    print(f"  numpy baseline (batched np.linalg.solve):    {t_np:7.3f} s wall, {c_np:7.3f} s CPU")
    print(f"  speed-up: {t_np / t_nb:6.1f}x wall, {c_np / c_nb:6.1f}x CPU   target >= 10x")
    d = np.abs(20 * np.log10(band.maximum / hi))
    print(
        f"  (independent random streams: upper edges differ by median {np.median(d):.2f} dB, "
        f"95 % of lines within {np.percentile(d, 95):.2f} dB)"
    )
    t_fi, c_fi, _ = _t(lambda: scatter_band_arrays(A, a, E, B, 0.1, "both", R, False, seed=0))
    t_ti, c_ti, _ = _t(lambda: scatter_band_arrays(A, a, E, B, 0.1, "tire", R, True, seed=0))
    print(
        f"  frequency-independent noise, both: {t_fi:7.3f} s wall ({c_fi:.3f} s CPU); "
        f"frequency-dependent, tire only: {t_ti:7.3f} s wall ({c_ti:.3f} s CPU)"
    )
    t_r, _, _ = _t(lambda: band.round(int(band.argmax_round[200, 2])), repeat=5)
    print(f"  regenerate one round: {1e3 * t_r:7.2f} ms")

    # -- memory: 2,000 lines ------------------------------------------------------------
    A2, a2, E2, B2, _ = scatter_inputs(2000)
    t2 = time.perf_counter()
    peak, delta = _peak_rss_mb(
        lambda: scatter_band_arrays(A2, a2, E2, B2, 0.1, "both", R, True, seed=0)
    )
    t2 = time.perf_counter() - t2
    print(
        f"\nscatter band R = {R} x 2,000 lines x 6 DOFs: {t2:6.2f} s; peak RSS {peak:.0f} MB "
        f"(+{delta:.0f} MB over the process before; all rounds at once would be "
        f"{R * 2000 * 6 * 8 / 1e6:.0f} MB)"
    )

    # -- truncation study ---------------------------------------------------------------
    try:
        tire = fc.reference_tire()
    except AttributeError:
        print("\ntruncation study: reference tire not available yet")
        return
    chassis = fc.reference_chassis()
    n = np.arange(10, tire.n_modes + 1, 10)
    t = time.perf_counter()
    s = suggest_modes(0.2, 160.0, tire=tire, chassis=chassis)
    t_first = time.perf_counter() - t
    t_tr, c_tr, s = _t(lambda: suggest_modes(0.2, 160.0, tire=tire, chassis=chassis))
    nl = sum(m.freq.size for m in s.maps)
    print(
        f"\ntruncation study, 7 harmonics x {n.size} N x 6 DOFs x floating band "
        f"({nl} lines): {t_tr:6.3f} s wall, {c_tr:6.3f} s CPU   target < 1 s"
    )
    print(
        f"  (first call {t_first:.3f} s: includes the chassis' one-off modal decomposition "
        "and its synthesis cache)"
    )
    t_130, _, s130 = _t(lambda: suggest_modes(0.2, 130.0, maps=s.maps, tire=tire))
    print(f"  re-reading the table for another f_max from the maps: {1e3 * t_130:6.2f} ms")
    print(s130.table())
    print(s.table())


if __name__ == "__main__":
    main()
