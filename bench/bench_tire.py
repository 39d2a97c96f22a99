"""Timing of the reference tire: loading, truncation sums, builder, direct solve.

Usage: ``.venv/bin/python bench/bench_tire.py``. Prints figures; asserts nothing.
Target: all 7 harmonics x 40 truncations (N = 10, 20, ..., 400) in < 1 s total.
"""

from __future__ import annotations

import time

import numpy as np

from fbs_core import HARMONICS, reference_tire
from fbs_core.tire import storage
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
    t, _ = timed(lambda: storage.load_tire_model(storage.DATA_FILE))
    print(f"load data/reference_tire.h5:                     {t * 1e3:8.1f} ms")
    tire = reference_tire()
    ns = list(range(10, 401, 10))
    n_lines = sum(h.frequencies().size for h in HARMONICS)

    def all_truncations():
        return [tire.truncations(h.frequencies(), h, ns) for h in HARMONICS]

    t, _ = timed(all_truncations)
    print(f"truncations, 7 harmonics x {len(ns)} N ({n_lines} lines): {t * 1e3:8.1f} ms")
    f = HARMONICS[6].frequencies()
    t, _ = timed(lambda: tire.patch_response(f, 7))
    print(f"patch_response case 7, all modes ({f.size} lines):  {t * 1e3:8.1f} ms")
    t, _ = timed(lambda: build_tire_system(73.0, tire.params))
    print(f"build_tire_system at one speed (cached operators): {t * 1e3:8.1f} ms")
    s = build_tire_system(73.0, tire.params)
    t, _ = timed(lambda: s.frf(f, s.dofs[:6], s.dofs[:6]), repeat=1)
    print(f"direct solve 200 DOFs, {f.size} lines:              {t * 1e3:8.1f} ms")
    t, _ = timed(build_modal_model, repeat=1)
    print(f"build the modal model (6 speeds, eig + tracking):  {t * 1e3:8.1f} ms")


if __name__ == "__main__":
    main()
