"""Memory of uploads: resident memory before, during and after (issue 28, memory findings).

Part 1, in this process: a session's data source reads a wide CSV file (a few rows of many
columns, the issue's "expanded 21x outside the sandbox") and a valid chassis file; the
resident memory (RSS) before, at its peak (sampled every 20 ms) and after (garbage
collected) of each reading.

Part 2, a server as the image starts it (``docker/entrypoint.py``, ``bench/attack_suite.py``'s
LocalServer): the server's RSS before, with ``--sessions`` sessions that each uploaded a
valid chassis file of its own, and after those sessions were closed and Bokeh destroyed
them; three rounds, so the later ones show what closed sessions leave behind once the
caches are filled.

    python bench/bench_upload_memory.py
    python bench/bench_upload_memory.py --only process      # part 1 only
"""

from __future__ import annotations

import argparse
import asyncio
import gc
import sys
import threading
import time
import urllib.request
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def rss_mb(pid: str | int = "self") -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


class Peak:
    """RSS of ``pid`` before, at the peak of and after a ``with`` block."""

    def __init__(self, pid: str | int = "self"):
        self.pid = pid

    def __enter__(self):
        gc.collect()
        self.before = self.peak = rss_mb(self.pid)
        self._stop = threading.Event()

        def sample():
            while not self._stop.wait(0.02):
                self.peak = max(self.peak, rss_mb(self.pid))

        self._t = threading.Thread(target=sample, daemon=True)
        self._t.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._t.join()
        gc.collect()
        self.after = rss_mb(self.pid)

    def text(self) -> str:
        return (
            f"RSS before {self.before:.0f} MB, during (peak) {self.peak:.0f} MB "
            f"(+{self.peak - self.before:.0f}), after {self.after:.0f} MB "
            f"(+{self.after - self.before:.0f})"
        )


def chassis_file(scale: float = 1.0) -> bytes:
    """The reference chassis mobility (times ``scale``: another file, another cache entry)
    on every harmonic's lines, as a MATLAB file whose nodes are named spindle and bushing
    (the upload form's defaults)."""
    import numpy as np

    import fbs_core
    from fbs_core.io import save_frf

    grid = np.arange(13.0, 422.01, 0.5)
    y = fbs_core.reference_chassis().mobility(grid)
    return save_frf(y.replace(data=y.data * scale), format="mat")


def part_process() -> None:
    from attack_suite import _csv

    from app.datasource import DataSource

    print("== 1. in this process: a session's data source reads uploads")
    good = chassis_file()
    DataSource().load_chassis(good, "warm-up.mat")  # imports and caches out of the figures
    for what, name, raw in (
        ("valid chassis MAT file", "c.mat", chassis_file(1.01)),
        ("wide CSV, 3 rows x 9,999 complex columns", "w.csv", _csv(3, 9_999, 5)),
        ("wide CSV, 3 rows x 50,000 complex columns (--big)", "w.csv", _csv(3, 50_000, 5)),
    ):
        ds = DataSource()
        with Peak() as p:
            t0 = time.perf_counter()
            ok = ds.load_chassis(raw, name)
            secs = time.perf_counter() - t0
        print(f"  {what}: {len(raw) / 2**20:.1f} MB, {'read' if ok else 'refused'} in {secs:.1f} s")
        if not ok:
            print(f"    ({ds.error[:110]})")
        print(f"    {p.text()}")
        del ds


def part_server(sessions: int) -> None:
    import attack_suite as a

    print(f"\n== 2. a server: {sessions} sessions upload a valid chassis file, then close")
    server = a.LocalServer(4)
    try:
        cookie = a.login(server.base, server.user, server.password)

        async def round_trip(k: int):
            tabs = [await a._open(server.base, "/main", cookie) for _ in range(sessions)]
            for i, sess in enumerate(tabs):
                await sess.settle(120, 0.5)
                content = chassis_file(1.0 + 0.01 * (k * sessions + i))  # every user's own
                await a._upload(sess, await a._upload_widget(sess, "chassis"), f"c{i}.mat", content)
            t0 = time.perf_counter()
            while time.perf_counter() - t0 < 300:
                answers = [a._alerts(s) for s in tabs]
                if all("c" in summ and ".mat" in summ for _, summ in answers):
                    break
                await asyncio.sleep(0.5)
            during = server.rss_mb()
            for sess in tabs:
                await sess.close()
            return during

        before = server.rss_mb()
        print(f"  server RSS at start: {before:.0f} MB")
        for k in (1, 2, 3):
            during = asyncio.run(round_trip(k))
            # Bokeh destroys a closed session after its unused lifetime (15 s), checked every
            # 17 s; then Panel and the app drop the page
            time.sleep(45)
            urllib.request.urlopen(server.base + "/liveness", timeout=10).read()
            after = server.rss_mb()
            print(
                f"  round {k}: before {before:.0f} MB, during ({sessions} sessions with an "
                f"upload) {during:.0f} MB (+{during - before:.0f}), after they closed "
                f"{after:.0f} MB (+{after - before:.0f}; {(after - before) / sessions:.0f} MB "
                "per closed session)"
            )
            before = after
    finally:
        server.stop()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=("process", "server"))
    ap.add_argument("--sessions", type=int, default=4)
    args = ap.parse_args(argv)
    if args.only in (None, "process"):
        part_process()
    if args.only in (None, "server"):
        part_server(args.sessions)
    return 0


if __name__ == "__main__":
    sys.exit(main())
