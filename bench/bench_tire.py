"""Timing of the reference tire: loading, truncation sums, builder, direct solve.

Usage: ``.venv/bin/python bench/bench_tire.py``. Prints figures; asserts nothing.
Target: all 7 harmonics x 40 truncations (N = 10, 20, ..., 400) in < 1 s total. Beside
the shipped model (41 operating points, cubic + cluster interpolation), the same data at
the thesis' 6 operating points with linear weights, timed in the same run.
"""

from __future__ import annotations

import os
import time

import numpy as np

from fbs_core import HARMONICS, reference_tire
from fbs_core.tire import TireModel, storage
from fbs_core.tire.build import build_modal_model
from fbs_core.tire.ring import build_tire_system


def timed(fn, repeat=3):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main():
    t, _ = timed(lambda: storage.read_tire_h5(storage.DATA_FILE))
    print(f"load data/reference_tire.h5:                     {t * 1e3:8.1f} ms")
    tire = reference_tire()
    ns = list(range(10, 401, 10))
    n_lines = sum(h.frequencies().size for h in HARMONICS)

    sub = np.flatnonzero(np.isin(tire.speeds, (20.0, 40.0, 60.0, 80.0, 100.0, 120.0)))
    thesis = TireModel(
        tire.speeds[sub],
        tire.poles[sub],
        tire.psi[sub],
        tire.chi[sub],
        tire.wavelengths,
        tire.participation[sub],
        interpolation="linear",
    )
    for label, model in (("shipped", tire), ("6 points, linear", thesis)):
        for what, n in (("all modes", [model.n_modes]), (f"{len(ns)} N", ns)):
            t, _ = timed(
                lambda m=model, n=n: [m.truncations(h.frequencies(), h, n) for h in HARMONICS]
            )
            print(
                f"truncations {label:16s} 7 harmonics x {what:9s} ({n_lines} lines): "
                f"{t * 1e3:8.1f} ms"
            )
    f = HARMONICS[6].frequencies()
    t, _ = timed(lambda: tire.patch_response(f, 7))
    print(f"patch_response case 7, all modes ({f.size} lines):  {t * 1e3:8.1f} ms")
    t, _ = timed(lambda: build_tire_system(73.0, tire.params))
    print(f"build_tire_system at one speed (cached operators): {t * 1e3:8.1f} ms")
    s = build_tire_system(73.0, tire.params)
    t, _ = timed(lambda: s.frf(f, s.dofs[:6], s.dofs[:6]), repeat=1)
    print(f"direct solve 200 DOFs, {f.size} lines:              {t * 1e3:8.1f} ms")
    t, _ = timed(lambda: build_modal_model(speeds=(20.0, 40.0, 60.0, 80.0, 100.0, 120.0)), 1)
    print(f"build the modal model (6 speeds, eig + tracking):  {t * 1e3:8.1f} ms")
    print(f"load average {os.getloadavg()[0]:.1f} (shared machine)")


if __name__ == "__main__":
    main()
