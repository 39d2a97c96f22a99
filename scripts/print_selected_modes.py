"""Selected tire modes side by side with thesis table 5.1 (issue 30).

Usage: ``.venv/bin/python scripts/print_selected_modes.py [--threshold 0.2] [--step 10]``

For every harmonic and for predictions up to 130 and 160 Hz: the modes table 5.1 needs
(the lowest ``N``, :func:`fbs_core.suggest_modes`, plain and with residual compensation)
next to the modes a selection needs (:func:`fbs_core.analysis.select_modes`: ranked by
participation, by the leave-one-out error, and greedy elimination by the leave-one-out
error; each plain and with the rest compensated by its residual). The criterion is the
same everywhere: eq. 5.1 below the threshold at every floating-band centre up to
``f_max``, largest over the six bushing DOFs, 6-DOF coupling, counts in steps of 10.
Prints the counts per harmonic, their totals and the time per variant.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from fbs_core.analysis import select_modes  # noqa: E402
from fbs_core.studies import suggest_modes, truncation_map  # noqa: E402

HARMONICS = range(1, 8)
VARIANTS = (
    ("by participation", "level"),
    ("by leave-one-out", "loo_floating"),
    ("greedy elimination", "greedy"),
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threshold", type=float, default=0.2, help="eq. 5.1 threshold (0.2 = 20 %%)")
    ap.add_argument("--step", type=int, default=10, help="count step in modes (thesis: 10)")
    a = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f}; threshold {a.threshold:.0%}, step {a.step}")
    t0 = time.perf_counter()
    plain = [truncation_map(k) for k in HARMONICS]
    t_plain = time.perf_counter() - t0
    t0 = time.perf_counter()
    comp = [truncation_map(k, residual=True) for k in HARMONICS]
    t_comp = time.perf_counter() - t0
    head = f"{'':38s}" + "".join(f"{k:>6d}" for k in HARMONICS) + "  total    time"
    for f_max in (130.0, 160.0):
        print(f"\nmodes needed up to {f_max:g} Hz (thesis table 5.1 layout)")
        print(head)
        for label, maps, t in (
            ("lowest N (table 5.1)", plain, t_plain),
            ("lowest N, residual", comp, t_comp),
        ):
            n = suggest_modes(a.threshold, f_max, maps=maps).n_modes
            print(f"{label:38s}" + "".join(f"{x:6d}" for x in n) + f"{n.sum():7d} {t:6.1f} s")
        for label, by in VARIANTS:
            for residual in (False, True):
                t0 = time.perf_counter()
                sel = [
                    select_modes(k, a.threshold, f_max, by=by, residual=residual, step=a.step)
                    for k in HARMONICS
                ]
                t = time.perf_counter() - t0
                name = f"selected {label}" + (", residual" if residual else "")
                n = np.array([s.n_modes for s in sel])
                print(f"{name:38s}" + "".join(f"{x:6d}" for x in n) + f"{n.sum():7d} {t:6.1f} s")
                if by == "greedy" and not residual:
                    for s in sel:
                        print(f"{'':6s}case {s.harmonic}: pairs {s.selected.tolist()}")


if __name__ == "__main__":
    main()
