"""First-order band of the FRF noise vs the Monte-Carlo scatter band (issue 32).

Run:  .venv/bin/python bench/bench_firstorder.py [--harmonics 1 4 7] [--rounds 4000]

Prints, side by side in one run:

1. speed: the first-order band of one harmonic (target < 100 ms), from the subsystem
   arrays (kernel), warm (arrays cached, as beside a scatter band) and cold (tire synthesis
   included), beside the Monte-Carlo band of 10,000 rounds;
2. agreement: for every harmonic, noise level and target, the first-order standard
   deviation of |v| over the Monte-Carlo one of the scatter band's rounds (the same
   noise: factors 1 + U(-p, p) on every element), as the share of lines x DOFs within
   5 % / 10 % and the worst ratio;
3. where they disagree: the lines x DOFs binned by the Monte-Carlo relative spread
   std/|v| (a small response against its spread: antiresonances) and by the interface
   matrix's condition number, with the share within 10 % in each bin.

The Monte-Carlo standard deviation from R rounds has a standard error of about
1/sqrt(2 R) (1.1 % at R = 4000): the agreement is judged against that.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import fbs_core  # noqa: E402
from fbs_core.studies import _models  # noqa: E402
from fbs_core.studies.firstorder import (  # noqa: E402
    compare_with_band,
    first_order_band,
    first_order_band_arrays,
)


def best(fn, repeat=5):
    t = np.inf
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        t = min(t, time.perf_counter() - t0)
    return t, out


def speed(harmonics):
    print("== speed: first-order band of one harmonic (target < 100 ms), best of 5")
    print(f"{'h':>2} {'lines':>5} {'cold s':>8} {'warm ms':>8} {'kernel ms':>9} {'MC R=1e4 s':>10}")
    tire = fbs_core.reference_tire()
    for k in harmonics:
        h = fbs_core.harmonic(k)
        f = h.frequencies()
        t0 = time.perf_counter()
        fo = first_order_band(k, 0.1, "both")  # first call: tire synthesis included
        cold = time.perf_counter() - t0
        warm, _ = best(lambda k=k: first_order_band(k, 0.1, "both"))
        dirs = _models.coupled_directions("6dof")
        YjjE, YejE, _ = _models.chassis_arrays(None, f, dirs)
        YjjA, vj = _models.tire_arrays(tire, f, h, [tire.n_modes], dirs)
        a = (YjjA[0], vj[0], YjjE, YejE)
        kern, _ = best(lambda a=a: first_order_band_arrays(*a, noise=0.1, target="both"))
        mc, _ = best(lambda k=k: fbs_core.scatter_band(k, 0.1, "both", 10_000, seed=1), repeat=1)
        print(
            f"{k:>2} {fo.freq.size:>5} {cold:>8.2f} {warm * 1e3:>8.1f} {kern * 1e3:>9.1f} "
            f"{mc:>10.2f}"
        )


def agreement(harmonics, rounds):
    print(f"\n== agreement: first-order std / Monte-Carlo std of |v| (R = {rounds})")
    print(
        f"{'h':>2} {'p':>5} {'target':>7} {'median |r-1|':>12} {'<5%':>6} {'<10%':>6} "
        f"{'min r':>6} {'max r':>6}"
    )
    pooled = []
    for k in harmonics:
        for p in (0.01, 0.05, 0.1, 0.2):
            for target in ("tire", "chassis", "both"):
                fo = first_order_band(k, p, target)
                band = fbs_core.scatter_band(k, p, target, rounds, seed=7)
                c = compare_with_band(fo, band, max_rounds=rounds)
                r = c["ratio"]
                e = np.abs(r - 1)
                print(
                    f"{k:>2} {p:>5.2f} {target:>7} {np.median(e):>12.3f} {np.mean(e < 0.05):>6.1%} "
                    f"{np.mean(e < 0.1):>6.1%} {r.min():>6.2f} {r.max():>6.2f}"
                )
                if target == "both":
                    pooled.append((p, c))
    return pooled


def _label(lo, hi, fmt):
    return f">= {fmt(lo)}" if not np.isfinite(hi) else f"{fmt(lo)}-{fmt(hi)}"


def _binned(name, x, e, bins, fmt):
    labels = [_label(lo, hi, fmt) for lo, hi in zip(bins[:-1], bins[1:], strict=True)]
    print(f"  {name:<22}" + "".join(f"{lab:>15}" for lab in labels))
    row = []
    for lo, hi in zip(bins[:-1], bins[1:], strict=True):
        m = (x >= lo) & (x < hi)
        row.append(f"{np.mean(e[m] < 0.1):6.1%} ({m.sum():>5})" if m.any() else "-")
    print(f"  {'within 10 % (count)':<22}" + "".join(f"{r:>15}" for r in row))


def where(pooled):
    print("\n== where they disagree (target both, all harmonics pooled): lines x DOFs binned")
    for p in sorted({p for p, _ in pooled}):
        cs = [c for q, c in pooled if q == p]
        e = np.concatenate([np.abs(c["ratio"] - 1).ravel() for c in cs])
        rel = np.concatenate([c["mc_relative_std"].ravel() for c in cs])
        cond = np.concatenate([np.repeat(c["condition"], c["ratio"].shape[1]) for c in cs])
        print(f"p = {p:g}")
        _binned("MC std / |v|", rel, e, [0, 0.05, 0.1, 0.2, 0.4, np.inf], lambda x: f"{x:g}")
        _binned("cond(Y_A + Y_E)", cond, e, [1, 30, 100, 300, np.inf], lambda x: f"{x:g}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--harmonics", type=int, nargs="+", default=[1, 4, 7])
    ap.add_argument("--rounds", type=int, default=4000)
    a = ap.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    speed(a.harmonics)
    where(agreement(a.harmonics, a.rounds))


if __name__ == "__main__":
    main()
