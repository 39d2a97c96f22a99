"""Which modes matter and what they look like (issue 30): cost of every new analysis.

Usage: ``.venv/bin/python bench/bench_modes.py [--repeat 5]``. Prints figures; asserts
nothing. Targets: participation for one harmonic and DOF < 300 ms; a shape's data
< 200 ms.

Medians (and maxima) of the wall time, and the process CPU time of the median call, on
the reference models after one warm-up call (caches of the models' operators filled):

* ``mode_participation(k)`` for every harmonic (the whole band; all six DOFs come from
  the same solves, so one DOF costs the same), its per-mode synthesis (``mode_terms``),
  and for cases 5-7 the band up to 160 Hz (the tire model's validity, thesis 5.1);
* ``tire_mode_shape`` of a few modes at speeds between the operating points;
* ``coupled_mode_shapes`` (3 modes near a peak) and ``operating_shape``;
* ``select_modes`` by leave-one-out ranking and by greedy elimination;
* ``chassis_truncation_map`` per harmonic;
* ``wave_campbell`` of the reference tire (43 operating points; first call, then cached);
* ``--app``: the dashboard's own paths (issue 30's Modes tab): the participation row of a
  harmonic (``app.results.modes.participation_result``: the band up to f_max = 160 Hz, one
  DOF's ranking, its CSV columns; cache cleared before every call), a change of DOF (the
  same participation from the cache), and a click's shape (``mode_shape_result`` of a mode
  not drawn yet). The in-page time of a click: ``bench/bench_mode_click.py``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from functools import partial

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import fbs_core as fc  # noqa: E402
from fbs_core.analysis import (  # noqa: E402
    coupled_mode_shapes,
    mode_participation,
    operating_shape,
    select_modes,
    tire_mode_shape,
    wave_campbell,
)
from fbs_core.studies import chassis_truncation_map  # noqa: E402
from fbs_core.tire.terms import mode_terms  # noqa: E402


def timed(fn, repeat):
    fn()  # warm-up
    wall, cpu = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    i = sorted(range(repeat), key=lambda j: wall[j])[repeat // 2]
    return statistics.median(wall), max(wall), cpu[i]


def show(label, t, target=None):
    med, mx, cpu = t
    goal = (
        ""
        if target is None
        else f"   goal < {target * 1e3:.0f} ms: {'met' if med < target else 'NOT met'}"
    )
    print(f"{label:46s} {med * 1e3:8.1f} ms (max {mx * 1e3:7.1f}, cpu {cpu * 1e3:7.1f}){goal}")


def app_paths(r: int) -> None:
    """The Modes tab's results as the dashboard makes them (module notes)."""
    from app.results import Snapshot
    from app.results import modes_compute as mc
    from app.results.modes import mode_shape_result, participation_result
    from app.state import DashboardState

    base = Snapshot.of(DashboardState()).replace(tab="modes", f_max=160.0)

    def cold(fn, s):
        def call():
            mc._participation.cache_clear()
            mc._shape.cache_clear()
            return fn(s)

        return call

    for k in range(1, 8):
        s = base.replace(harmonic=k)
        lo, hi = mc.participation_band(k, s.f_max)
        show(
            f"app: participation row h{k} ({lo:g}-{hi:g} Hz)",
            timed(cold(participation_result, s), r),
            0.3,
        )
    s = base.replace(harmonic=4)
    participation_result(s)
    show("app: participation row, DOF change (cached)", timed(
        lambda: participation_result(s.replace(dof="rx")), r), 0.3)  # fmt: skip
    for mode, v in ((7, 88.4), (19, 70.0), (3, 30.2)):
        s = base.replace(mode_pick=mode, mode_speed=v)
        show(f"app: click -> shape row, mode {mode} at {v} km/h", timed(
            cold(mode_shape_result, s), r), 0.2)  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--app", action="store_true", help="only the dashboard's paths")
    a = ap.parse_args()
    r = a.repeat
    print(f"load average {os.getloadavg()[0]:.1f} (shared machine), {r} repeats")
    if a.app:
        app_paths(r)
        return
    tire = fc.reference_tire()
    for k in range(1, 8):
        h = fc.harmonic(k)
        f = h.frequencies()
        hi = tire._harmonic_index(h)
        t = timed(partial(mode_participation, k), r)
        show(f"mode_participation({k}), {f.size} lines", t, 0.3)
        show("  of it mode_terms", timed(partial(mode_terms, tire, f, h.speed_at(f), hi), r))
        if h.freq_range[1] > 160.0:  # the tire model's range of validity (thesis 5.1)
            band = (h.freq_range[0], 160.0)
            t = timed(partial(mode_participation, k, band), r)
            show(f"mode_participation({k}) up to 160 Hz", t, 0.3)
    for mode, v in ((5, 61.3), (30, 61.3), (60, 97.1), (120, 33.3)):
        show(f"tire_mode_shape({mode}, {v})", timed(partial(tire_mode_shape, mode, v), r), 0.2)
    t = timed(partial(coupled_mode_shapes, 37.0, 60.0), r)
    show("coupled_mode_shapes(37 Hz, 60 km/h, n=3)", t)
    show("operating_shape(4, 80 Hz)", timed(partial(operating_shape, 4, 80.0), r))
    for k in (1, 4, 7):
        for by in ("loo_floating", "greedy"):
            show(f"select_modes({k}, by={by!r})", timed(partial(select_modes, k, by=by), 1))
    for k in (1, 4, 7):
        show(f"chassis_truncation_map({k})", timed(partial(chassis_truncation_map, k), r))
    t0 = time.perf_counter()
    wave_campbell()
    t1 = time.perf_counter()
    wave_campbell()
    t2 = time.perf_counter()
    print(f"{'wave_campbell() first / cached':46s} {t1 - t0:8.1f} s / {1e3 * (t2 - t1):.2f} ms")


if __name__ == "__main__":
    main()
