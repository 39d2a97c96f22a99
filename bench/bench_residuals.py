"""Residual compensation (issue 15): suggested tire modes with and without residuals.

Usage: ``.venv/bin/python bench/bench_residuals.py``. Prints figures; asserts nothing.

Thesis table 5.1 from the truncation error maps (eq. 5.1, 12 Hz floating band, max over
the six bushing DOFs, 6-DOF coupling) of the plain truncated tire and of the same
truncation with the modes left out compensated by their quasi-static part (upper
residual flexibility), at 20 % and 10 % up to 130 and 160 Hz; then the cost of the
compensated maps against the plain ones, measured side by side in one run.
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from fbs_core import reference_tire  # noqa: E402
from fbs_core.studies import suggest_modes, truncation_map  # noqa: E402


def maps(residual: bool):
    reference_tire()  # loaded before the clock starts
    t0 = time.perf_counter()
    out = [truncation_map(k, residual=residual) for k in range(1, 8)]
    return out, time.perf_counter() - t0


def main():
    print(f"load average {os.getloadavg()[0]:.1f} (shared machine)")
    plain, t_plain = maps(False)
    comp, t_comp = maps(True)
    plain2, t_plain2 = maps(False)  # again, beside it: the machine's load drifts
    t_plain = min(t_plain, t_plain2)
    print("suggested number of modes (thesis table 5.1), max over the 6 bushing DOFs")
    print("threshold  f_max  | " + " ".join(f"{k:>5d}" for k in range(1, 8)) + " | total")
    for thr in (0.2, 0.1):
        for fmax in (130.0, 160.0):
            a = suggest_modes(thr, fmax, maps=plain)
            b = suggest_modes(thr, fmax, maps=comp)
            for label, s in (("plain", a), ("residual", b)):
                print(
                    f"{thr * 100:5.0f} %  {fmax:5.0f}  {label:9s}| "
                    + " ".join(f"{n:5d}" for n in s.n_modes)
                    + f" | {int(np.sum(s.n_modes)):5d}"
                )
    print(
        f"cost: 7 truncation maps (40 N each) plain {t_plain:.2f} s, with residuals "
        f"{t_comp:.2f} s: ratio {t_comp / t_plain:.2f} (goal <= 1.5)"
    )


if __name__ == "__main__":
    main()
