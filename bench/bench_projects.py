"""What the projects store costs: an upload, a listing, a page, a start over many projects.

Usage (from the repository root)::

    python bench/bench_projects.py [--projects 50] [--mib 10] [--dir /tmp/somewhere]

Prints, side by side in one run: the time to add a candidate of ``--mib`` MiB (write, fsync,
rename, commit) against writing and fsync-ing the same bytes alone (the price of the
record and the rename), the time to list ``--projects`` projects for a user and to open one,
and the start's scan (quick_check and clean-up of every project). The data directory is a
temporary one on the same file system as ``--dir`` (default: the system's temporary
directory); fsync times depend on that disk.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.projects import Projects, parse_groups  # noqa: E402


def _median(f, n: int = 5) -> float:
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--projects", type=int, default=50)
    ap.add_argument("--mib", type=float, default=10.0)
    ap.add_argument("--dir", default=None)
    args = ap.parse_args()
    cfg = parse_groups("oem:alice;supplier_x:carol")
    with tempfile.TemporaryDirectory(dir=args.dir) as d:
        p = Projects(d, cfg)
        ids = [
            p.create_project("alice", f"project {k}", {"oem": None, "supplier_x": ["X"]}).id
            for k in range(args.projects)
        ]
        size = int(args.mib * 2**20)
        counter = iter(range(10**6))

        def add() -> None:
            i = next(counter)
            data = i.to_bytes(8, "little") * (size // 8)
            p.add_candidate("alice", ids[0], f"t{i}.h5", data, {"name": f"t{i}", "supplier": "X"})

        def raw() -> None:
            data = os.urandom(8) * (size // 8)
            path = Path(d) / "raw.bin"
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
            os.write(fd, data)
            os.fsync(fd)
            os.close(fd)

        t_add, t_raw = _median(add), _median(raw)
        print(f"add a {args.mib:g} MiB candidate      {t_add * 1e3:8.1f} ms (median of 5)")
        print(f"write + fsync the bytes alone  {t_raw * 1e3:8.1f} ms  (ratio {t_add / t_raw:.2f})")
        t_list = _median(lambda: p.list_projects("carol"))
        print(f"list {args.projects} projects (supplier)   {t_list * 1e3:8.1f} ms")
        t_open = _median(lambda: p.open_project("carol", ids[0]))
        print(f"open a project (audited)       {t_open * 1e3:8.1f} ms")
        t0 = time.perf_counter()
        Projects(d, cfg)
        print(
            f"start: scan {args.projects} projects       {(time.perf_counter() - t0) * 1e3:8.1f} ms"
        )


if __name__ == "__main__":
    main()
