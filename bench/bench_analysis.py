"""Speed of the analysis functions of issue 18 on the reference models.

Run:  .venv/bin/python bench/bench_analysis.py            (add --shape for the Campbell
      diagram's shape criterion: one dense complex-mode solve per operating point)

Each line: median and maximum wall time of ``repeat`` calls with the same arguments,
each call computing afresh (the reference-model caches of ``speed_map`` are bypassed by
passing the models explicitly; the chassis FRFs on a grid and the tire's system
matrices are cached by their own modules after the first call, as in the dashboard).
Target: median < 200 ms per dashboard update at typical sizes. The load average is
printed first: on a shared machine wall times grow with it; the CPU time (all
threads of this process, median) much less.
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

import fbs_core as fc
from fbs_core import analysis as an


def _t(fn, repeat=5):
    times, cpus, out = [], [], None
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        out = fn()
        times.append(time.perf_counter() - t)
        cpus.append(time.process_time() - c)
    return float(np.median(times)), float(np.max(times)), float(np.median(cpus)), out


def row(name, fn, repeat=5):
    med, mx, cpu, out = _t(fn, repeat)
    flag = "" if med < 0.2 else "  (> 200 ms)"
    print(
        f"{name:<56s} median {1e3 * med:7.1f} ms  max {1e3 * mx:7.1f} ms  "
        f"cpu {1e3 * cpu:7.1f} ms{flag}",
        flush=True,
    )
    return out


def main():
    print(f"load average: {os.getloadavg()}  cores: {os.cpu_count()}")
    tire, ch = fc.reference_tire(), fc.reference_chassis()
    # warm the module caches the dashboard also keeps warm (chassis FRFs per grid,
    # tire matrices per speed, coupled system per speed)
    for k in (1, 7):
        fc.bushing_response(k)
        an.speed_map(k, 40)
    r1 = fc.bushing_response(1, 100)
    r7 = fc.bushing_response(7)
    print("\ncontributions (eq. 4.1 terms), along the harmonic line")
    row("bushing_contributions(1, N=100)   86 lines", lambda: an.bushing_contributions(1, 100))
    row("bushing_contributions(7, N=400)  634 lines", lambda: an.bushing_contributions(7))
    row(
        "bushing_contributions(4, N=400, speed=80 km/h)",
        lambda: an.bushing_contributions(4, None, speed_kmh=80.0),
    )

    print("\npeaks and modes nearby")
    row("peak_labels(harmonic 7, bushing:z)", lambda: an.peak_labels(r7, "bushing:z", harmonic=7))
    row(
        "peak_labels(harmonic 1, n_nearby=2), first call per speed",
        lambda: an.peak_labels(r1, "bushing:z", harmonic=1, n_nearby=2, tire=tire, chassis=ch),
        repeat=3,
    )
    s60 = an.coupled_system(60.0)
    row("system_modes_near(coupled 458 DOFs, 38 Hz, 3)", lambda: an.system_modes_near(s60, 38.0, 3))

    print("\nphase views, cursors, comparison")
    row("bode(harmonic 7 response, 634 x 6)", lambda: an.bode(r7))
    row("delta_cursor", lambda: an.delta_cursor(r7, 150.0, 300.0, "bushing:z"))
    r7b = fc.bushing_response(7, 130)
    row("db_difference(N=400 vs N=130, harmonic 7)", lambda: an.db_difference(r7, r7b))
    ma = fc.truncation_map(1)
    mb = fc.truncation_map(1, coupling="5dof")
    row("truncation_map_difference(harmonic 1, 40 N)", lambda: an.truncation_map_difference(ma, mb))

    print("\nacross speed")
    row("campbell(reference tire, 41 speeds, slope criterion)", lambda: an.campbell(tire))
    row(
        "speed_map(1, N=100)  21 speeds x 86 lines",
        lambda: an.speed_map(1, 100, tire=tire, chassis=ch),
    )
    row(
        "speed_map(4, N=130)  21 speeds x 290 lines",
        lambda: an.speed_map(4, 130, tire=tire, chassis=ch),
    )
    row(
        "speed_map(7, N=400)  21 speeds x 704 lines",
        lambda: an.speed_map(7, None, tire=tire, chassis=ch),
        repeat=3,
    )
    row("speed_map(7, N=400) cached (reference models)", lambda: an.speed_map(7))
    if "--shape" in sys.argv:
        an.campbell.__globals__["_shape_index"].cache_clear()
        row("campbell(..., method='shape'), first call", lambda: an.campbell(method="shape"), 1)

    print("\npinned states and CSV")
    sources = {"tire": an.digest(tire), "chassis": an.digest(ch)}
    row("digest(reference tire)", lambda: an.digest(tire))
    p = row(
        "pin_state(harmonic 7 response) + to_json",
        lambda: an.pin_state("a", r7, {"harmonic": 7}, sources).to_json(),
    )
    row("PinnedState.from_json (harmonic 7 response)", lambda: an.PinnedState.from_json(p))
    c1 = an.bushing_contributions(1, 100)
    row("to_csv(contributions, harmonic 1)", lambda: an.to_csv(c1, sources))
    m1 = an.speed_map(1, 100)
    row("to_csv(speed map harmonic 1, one output)", lambda: an.to_csv(m1, sources))


if __name__ == "__main__":
    main()
