"""The belt-wave Campbell diagram's first call, this tree beside another git revision.

Usage: ``.venv/bin/python bench/bench_waves.py [--ref main] [--busy 0,4] [--limit 1200]``.
Prints figures; asserts nothing. Target: ``fbs_core.analysis.wave_campbell()`` of the
reference tire < 2 s the first time in a process, the same numbers as ``--ref``, and on a
busy machine a bounded time.

Each side runs in a process of its own (a first call: nothing cached): this tree, and the
tree of ``--ref`` extracted with ``git archive`` (its ``fbs_core`` and ``data``). Each
process times the first ``wave_campbell()`` (wall and CPU) after the reference tire is
loaded, and writes the branches' frequencies and labels; the table says whether both sides
hold the same numbers. ``--busy N`` runs N processes spinning on the CPU beside each
measurement (a machine shared with other work); a side that takes longer than ``--limit``
seconds is stopped and shown as ``> limit``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time
import numpy as np
import fbs_core
from fbs_core.analysis import wave_campbell
tire = fbs_core.reference_tire()
t0, c0 = time.perf_counter(), time.process_time()
cb = wave_campbell()
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
np.savez(sys.argv[1], freq=cb.freq, labels=np.array(cb.labels()))
print(json.dumps({"wall": wall, "cpu": cpu, "file": fbs_core.__file__}))
"""


def extract(ref: str, where: Path) -> Path:
    """The tree of ``ref`` (fbs_core and data) under ``where``."""
    blob = subprocess.run(
        ["git", "-C", str(ROOT), "archive", ref, "fbs_core", "data"],
        check=True,
        capture_output=True,
    ).stdout
    tar = where / "ref.tar"
    tar.write_bytes(blob)
    with tarfile.open(tar) as t:
        t.extractall(where / "tree", filter="data")
    return where / "tree"


def measure(tree: Path, out: Path, busy: int, limit: float) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(busy)]
    try:
        t0 = time.perf_counter()
        try:
            p = subprocess.run(
                [sys.executable, "-c", CHILD, str(out)],
                env=env,
                capture_output=True,
                text=True,
                timeout=limit,
                cwd=tree,
            )
        except subprocess.TimeoutExpired:
            return {"wall": None, "cpu": None, "total": time.perf_counter() - t0}
        if p.returncode:
            raise SystemExit(p.stderr)
        r = json.loads(p.stdout.strip().splitlines()[-1])
        r["total"] = time.perf_counter() - t0
        assert Path(r["file"]).resolve().is_relative_to(tree.resolve()), r["file"]
        return r
    finally:
        for b in burners:
            b.kill()
            b.wait()


def fmt(x: float | None, limit: float) -> str:
    return f"> {limit:.0f}" if x is None else f"{x:.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ref", default="main", help="the git revision to compare with")
    ap.add_argument("--busy", default="0", help="spinning processes beside, e.g. 0,4")
    ap.add_argument("--limit", type=float, default=1200.0, help="longest wait per side (s)")
    a = ap.parse_args()
    print(f"{os.cpu_count()} cores; first wave_campbell() of the reference tire per process")
    print(f"{'busy':>4} | {a.ref + ' wall s':>12} {'cpu s':>7} | {'this wall s':>12} {'cpu s':>7}"
          f" | {'ratio':>6} | same numbers")  # fmt: skip
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        ref_tree = extract(a.ref, tmp)
        for busy in (int(x) for x in a.busy.split(",")):
            old = measure(ref_tree, tmp / "old.npz", busy, a.limit)
            new = measure(ROOT, tmp / "new.npz", busy, a.limit)
            same = "-"
            if old["wall"] is not None and new["wall"] is not None:
                o, n = np.load(tmp / "old.npz"), np.load(tmp / "new.npz")
                if o["freq"].shape == n["freq"].shape and list(o["labels"]) == list(n["labels"]):
                    dev = np.nanmax(np.abs(n["freq"] / o["freq"] - 1))
                    same = f"yes (labels equal, max rel. freq. difference {dev:.1e})"
                else:
                    same = "NO: other branches"
            ratio = (
                f"{old['wall'] / new['wall']:.0f}x"
                if old["wall"] is not None and new["wall"] is not None
                else "-"
            )
            print(
                f"{busy:>4} | {fmt(old['wall'], a.limit):>12} {fmt(old['cpu'], a.limit):>7} | "
                f"{fmt(new['wall'], a.limit):>12} {fmt(new['cpu'], a.limit):>7} | {ratio:>6} | "
                f"{same}"
            )


if __name__ == "__main__":
    main()
