"""Table 5.1 of the vehicle side beside the tire's (issue 30, thesis section 7).

Usage: ``.venv/bin/python scripts/print_chassis_truncation.py [--threshold 0.2]``

For every harmonic: the tire modes table 5.1 suggests (chassis exact) and the chassis
modes the same criterion suggests with the tire exact (:func:`fbs_core.studies.
chassis_truncation_map`), plain and with the residual flexibility of the chassis modes
left out, up to 130 and 160 Hz, with the eigenfrequency of the highest kept chassis mode.
Criterion: eq. 5.1 below the threshold at every floating-band centre up to ``f_max``,
largest over the six bushing DOFs, 6-DOF coupling.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from fbs_core import reference_chassis  # noqa: E402
from fbs_core.studies import chassis_truncation_map, suggest_modes  # noqa: E402

HARMONICS = range(1, 8)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threshold", type=float, default=0.2, help="eq. 5.1 threshold (0.2 = 20 %%)")
    a = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f}; threshold {a.threshold:.0%}")
    fr = reference_chassis().eigenfrequencies()
    t0 = time.perf_counter()
    plain = [chassis_truncation_map(k) for k in HARMONICS]
    comp = [chassis_truncation_map(k, residual=True) for k in HARMONICS]
    t_ch = time.perf_counter() - t0
    t0 = time.perf_counter()
    tire = suggest_modes(a.threshold, 130.0)
    t_tire = time.perf_counter() - t0
    head = f"{'':34s}" + "".join(f"{k:>6d}" for k in HARMONICS)
    for f_max in (130.0, 160.0):
        print(f"\nup to {f_max:g} Hz")
        print(head)
        n_t = suggest_modes(a.threshold, f_max, maps=tire.maps).n_modes
        print(f"{'tire modes (table 5.1)':34s}" + "".join(f"{x:6d}" for x in n_t))
        for label, maps in (("chassis modes", plain), ("chassis modes, residual", comp)):
            n = np.array([m.suggest(a.threshold, f_max) for m in maps])
            print(f"{label:34s}" + "".join(f"{x:6d}" for x in n))
            top = "".join(f"{fr[x - 1]:6.0f}" for x in n)
            print(f"{'  highest kept eigenfreq. (Hz)':34s}" + top)
    print(f"\n14 maps of the chassis {t_ch:.1f} s; 7 maps of the tire {t_tire:.1f} s")


if __name__ == "__main__":
    main()
