"""BLAS threads in the server: one per pool against OpenBLAS's default, idle and busy cores.

The server stage (``docker/entrypoint.py``) runs with ``OPENBLAS_NUM_THREADS=1`` unless the
deployment sets it. This prints why: the first page's dense linear algebra (the chassis'
modal decomposition, a 264-DOF complex eigenproblem; the reference error map of harmonic 1
with its coupled responses), each figure the best of ``--repeat`` fresh processes, with
OpenBLAS's default (a thread per core) and with one thread, first on idle cores, then with
every core kept busy by a spinning process (as the server's event loop, numba threads and
other sessions' bands keep them). The two settings alternate, so that both see the same
machine.

Usage::

    .venv/bin/python bench/bench_blas_threads.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = """
import json, time
import numpy as np
import fbs_core as fc
from fbs_core import chassis
from fbs_core.studies import truncation_map
t = time.perf_counter()
chassis._modal(fc.ChassisModel().params)
modal = time.perf_counter() - t
tire, ch = fc.reference_tire(), fc.reference_chassis()
t = time.perf_counter()
truncation_map(fc.harmonic(1), tire=tire, chassis=ch)
study = time.perf_counter() - t
print(json.dumps({"modal": modal, "map": study}))
"""


def spin(stop) -> None:  # a busy core
    while not stop.is_set():
        pass


def child(threads: str | None) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if threads is not None:
        env["OPENBLAS_NUM_THREADS"] = threads
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    out = subprocess.run(
        [sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(repeat: int) -> dict:
    best: dict = {}
    for _ in range(repeat):
        for name, threads in (("default", None), ("one", "1")):
            r = child(threads)
            for k, v in r.items():
                best[(name, k)] = min(best.get((name, k), float("inf")), v)
    return best


def report(title: str, best: dict) -> None:
    print(f"\n{title} (load {os.getloadavg()[0]:.1f}); best of the fresh processes:")
    for k, label in (("modal", "chassis modal decomposition"), ("map", "error map, harmonic 1")):
        d, o = best[("default", k)], best[("one", k)]
        print(
            f"  {label:30s} default {d:7.3f} s   one thread {o:7.3f} s   "
            f"default / one {d / o:5.1f}x"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"{os.cpu_count()} cores; OpenBLAS default: a thread per core")
    report("idle cores", measure(args.repeat))
    stop = mp.Event()
    spinners = [mp.Process(target=spin, args=(stop,)) for _ in range(os.cpu_count() or 1)]
    for p in spinners:
        p.start()
    try:
        time.sleep(0.5)
        report(f"every core busy ({len(spinners)} spinning processes)", measure(args.repeat))
    finally:
        stop.set()
        for p in spinners:
            p.join()


if __name__ == "__main__":
    main()
