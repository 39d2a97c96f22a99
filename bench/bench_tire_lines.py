"""The tire along the harmonic lines: this tree against older trees, side by side (issue 33).

Usage::

    .venv/bin/python bench/bench_tire_lines.py [--rounds 7] [--old f883415] [--before 6070f09]

Prints figures; asserts nothing. The trees of the revisions ``--old`` (the linear tire
of 6 operating points, before the speed fidelity of issue 13) and ``--before`` (the
speed fidelity's numpy sums, before the compiled kernel of :mod:`fbs_core.tire.sums`)
are exported with ``git archive`` into a temporary directory; each tree, and this
working tree, runs in a process of its own (``PYTHONPATH`` set to the tree, its own
shipped data) that loads the reference models once and then computes, when asked, the
seven truncation maps (:func:`fbs_core.truncation_map`, 40 counts N = 10 .. 400, the
default grids). The processes are asked in turn, round after round, so that the load of
the shared machine falls on all of them alike; the figures are medians over the rounds
and the ratios are taken round by round. Reported beside the steady state: the first
seven maps of a fresh process after loading the models (this tree: the tire's clusters
found on first use and numba's compiled code loaded from its cache).

This tree runs twice: as it comes (the tire sums on a few threads, one per core) and with
the tire sums on the calling thread only (``FBS_TIRE_SUM_THREADS=1``, "1 thread"), whose
wall time is what a machine with every core busy sees; CPU time (``process_time``) is
printed for all.

Goal (issue 33): all 7 maps within 1.2x the time of ``--old``. The load average is
printed before and after (``uptime``): on a shared machine only the ratios mean much.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent

#: Run inside every tree's process: load, time the first maps, then serve "maps" requests.
WORKER = r"""
import json, os, sys, time
t0 = time.perf_counter()
import fbs_core as fc
tire, chassis = fc.reference_tire(), fc.reference_chassis()
loaded = time.perf_counter() - t0

def maps():
    w, c = time.perf_counter(), time.process_time()
    for k in range(1, 8):
        fc.truncation_map(k, tire=tire, chassis=chassis)
    return time.perf_counter() - w, time.process_time() - c

first = maps()
try:  # threads of the tire sums (trees before them: 1)
    from fbs_core.tire import sums
    threads = sums._threads(1000)
except (ImportError, AttributeError):
    threads = 1
print(json.dumps({"file": fc.__file__, "load": loaded, "first": first, "threads": threads,
                  "points": int(tire.speeds.size), "modes": int(tire.n_modes)}), flush=True)
for line in sys.stdin:
    if line.strip() != "maps":
        break
    print(json.dumps({"maps": maps()}), flush=True)
"""


def export(rev: str, into: Path) -> Path:
    """The tree of ``rev`` (``git archive``) in ``into/rev``."""
    dest = into / rev
    dest.mkdir(parents=True)
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", rev], check=True, capture_output=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    return dest


def start(tree: Path, **extra: str) -> subprocess.Popen[str]:
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    env.update(extra)
    return subprocess.Popen(
        [sys.executable, "-c", WORKER],
        cwd=tree,
        env=env,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )


def ask(proc: subprocess.Popen[str], cmd: str | None = None) -> dict:
    assert proc.stdin is not None and proc.stdout is not None
    if cmd is not None:
        proc.stdin.write(cmd + "\n")
        proc.stdin.flush()
    line = proc.stdout.readline()
    if not line:
        raise RuntimeError(f"worker {proc.args} ended")
    return json.loads(line)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--old", default="f883415", help="the linear tire (issue 33's reference)")
    ap.add_argument(
        "--before", default="6070f09", help="the numpy sums of the speed fidelity ('' to skip)"
    )
    args = ap.parse_args(argv)
    print(f"uptime: {os.getloadavg()} (1, 5, 15 min load of {os.cpu_count()} cores)")
    with tempfile.TemporaryDirectory(prefix="fbs-bench-trees-") as tmp:
        trees = {f"old {args.old}": export(args.old, Path(tmp))}
        if args.before:
            trees[f"before {args.before}"] = export(args.before, Path(tmp))
        procs = {name: start(tree) for name, tree in trees.items()}
        procs["this, 1 thread"] = start(ROOT, FBS_TIRE_SUM_THREADS="1")
        procs["this tree"] = start(ROOT)
        try:
            info = {name: ask(p) for name, p in procs.items()}
            for name, d in info.items():
                print(
                    f"{name:16s} {d['points']:3d} operating points, {d['modes']} modes, "
                    f"tire sums on up to {d['threads']} thread(s); "
                    f"models loaded in {d['load']:.2f} s, first 7 maps {d['first'][0]:.3f} s "
                    f"wall ({d['first'][1]:.3f} s CPU)"
                )
            wall = {name: [] for name in procs}
            cpu = {name: [] for name in procs}
            for _ in range(args.rounds):
                for name, p in procs.items():  # in turn: the load falls on all alike
                    w, c = ask(p, "maps")["maps"]
                    wall[name].append(w)
                    cpu[name].append(c)
        finally:
            for p in procs.values():
                if p.stdin is not None:
                    p.stdin.close()
                p.wait()
    names = list(procs)
    ref, one, new = names[0], names[-2], names[-1]
    print(f"\n7 truncation maps (40 N each), {args.rounds} rounds in turn; median wall (CPU):")
    for name in names:
        print(f"  {name:16s} {np.median(wall[name]):7.3f} s ({np.median(cpu[name]):.3f} s CPU)")
    for this in (one, new):
        for name in names[:-2]:
            r = np.array(wall[this]) / np.array(wall[name])
            rc = np.array(cpu[this]) / np.array(cpu[name])
            print(
                f"  {this:14s} / {name:16s} wall {np.median(r):5.2f}x (rounds {r.min():.2f}-"
                f"{r.max():.2f}), CPU {np.median(rc):5.2f}x"
            )

    def ratio(this: str, of: dict[str, list[float]]) -> float:
        return float(np.median(np.array(of[this]) / np.array(of[ref])))

    r, r1, rc = ratio(new, wall), ratio(one, wall), ratio(new, cpu)
    print(
        f"GOAL: within 1.2x of {ref} (medians of the per-round ratios): "
        f"wall {r:.2f}x {'met' if r <= 1.2 else 'NOT met'}; "
        f"wall on 1 thread {r1:.2f}x {'met' if r1 <= 1.2 else 'NOT met'}; "
        f"CPU {rc:.2f}x {'met' if rc <= 1.2 else 'NOT met'}"
    )
    print(f"uptime: {os.getloadavg()}")


if __name__ == "__main__":
    main()
