"""The Campbell diagrams checked against the ring's closed form (issue 30).

Usage: ``.venv/bin/python scripts/print_campbell_check.py``  (about a minute)

1. The modal model's own branches (:func:`fbs_core.campbell`, tracked when the model
   was built): how often the "slope" and "shape" direction labels agree on the
   branches that shift by more than 10 Hz over 20-120 km/h, and whether any branch
   near the closed-form forward wave of orders 4-8 rises with speed like it.
2. The branches that follow the waves (:func:`fbs_core.analysis.wave_campbell`): for
   every in-plane ring order 2..8 and direction, the largest deviation from the closed
   form over the speeds, the mean slope against the closed form's, and the purity of
   the carrier.
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from fbs_core import campbell, reference_tire  # noqa: E402
from fbs_core.analysis import wave_campbell  # noqa: E402
from fbs_core.tire import ring_closed_form  # noqa: E402


def model_branches() -> None:
    tire = reference_tire()
    t0 = time.perf_counter()
    slope = campbell(tire, method="slope")
    shape = campbell(tire, method="shape")
    print(f"1. the model's tracked branches (campbell, {time.perf_counter() - t0:.0f} s)")
    shift = np.abs(slope.slope * (slope.speeds[-1] - slope.speeds[0]))
    big = shift > 10.0
    agree = slope.direction[big] == shape.direction[big]
    print(
        f"   slope and shape labels agree on {agree.mean():.0%} of the {big.sum()} branches "
        f"shifting > 10 Hz"
    )
    sb = np.sum((shape.direction == "standing") & (slope.direction == "backward"))
    print(f"   labelled standing by shape and backward by slope: {sb} branches")
    for n in range(4, 9):
        fp = np.array([ring_closed_form(n, v)[0] for v in slope.speeds])
        cf_slope = np.polyfit(slope.speeds, fp, 1)[0]
        near = np.all(np.abs(slope.freq / fp[:, None] - 1) < 0.10, axis=0)
        some = np.any(np.abs(slope.freq / fp[:, None] - 1) < 0.10, axis=0)
        rising = some & (slope.slope > 0)
        print(
            f"   n = {n} forward: closed-form slope {cf_slope:+.2f} Hz per km/h; branches "
            f"within 10 % at every speed {near.sum()}, somewhere {some.sum()}, of those "
            f"rising {rising.sum()} (slopes {np.round(slope.slope[some], 2).tolist()})"
        )


def wave_branches() -> None:
    t0 = time.perf_counter()
    cb = wave_campbell(fmax=None)
    print(f"2. branches that follow the waves (wave_campbell, {time.perf_counter() - t0:.0f} s)")
    print("   order direction   deviation from the closed form   slope (Hz per km/h)  purity")
    for n in range(2, 9):
        for d in ("forward", "backward"):
            b = cb.find("ip", n, d)
            rel = cb.freq[:, b] / cb.closed_form[:, b] - 1
            s = np.polyfit(cb.speeds, cb.freq[:, b], 1)[0]
            s0 = np.polyfit(cb.speeds, cb.closed_form[:, b], 1)[0]
            print(
                f"   {n:5d} {d:9s}   {100 * np.nanmin(rel):+6.1f} % .. "
                f"{100 * np.nanmax(rel):+6.1f} %"
                f"             {s:+.3f} ({s0:+.3f})      {cb.purity[:, b].min():.2f}-"
                f"{cb.purity[:, b].max():.2f}"
            )
    print(
        f"   steps flagged as veering (carrier MAC < {cb.veer_mac}): {cb.veering.sum()} of "
        f"{cb.veering.size}; branches with any: {cb.veering.any(axis=0).sum()} of "
        f"{cb.freq.shape[1]}"
    )


if __name__ == "__main__":
    print(f"load average {os.getloadavg()[0]:.1f}")
    model_branches()
    wave_branches()
