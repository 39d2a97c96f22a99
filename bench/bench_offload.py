"""Another session's control-change latency while one session runs a 200,000-round band,
with the band computed in the server process and offloaded to a Dask cluster, side by side.

Two dashboard servers run at once (``panel serve`` through docker/entrypoint.py, as
``bench/load_test.py --serve`` does): one without ``FBS_DASK_SCHEDULER`` (the band runs in
the server, taking turns with the other sessions' bands), one pointed at a LocalCluster of
``--workers`` worker processes started here (the band runs on the workers). Each has a
probe session (a Bokeh protocol client, ``bench/load_clients.py``) that moves the harmonic
slider (2, 3, 4, ...: its plots and its own ``--probe-rounds`` band recompute; each value is
visited once before the samples, so the shared caches are warm). Per sample and server, in
alternation (the same machine load for both):

- ``idle``: the probe's latency with nothing else running;
- ``hog``: a second session opens, moves to harmonic 7 and asks for a 200,000-round band,
  the probe's latency is measured while that band runs, then the hog session is closed
  (its band is cancelled: between chunks in the server, its futures on the cluster).

Printed: median and p95 of the time from the slider change to the first plot update and to
the settled plots (the probe's own band included), per server and condition, and whether the
hog's band was still running after each probe. The workers run on this machine's cores too,
so offloading moves the work off the server process, not off the machine: what it removes
is the competition inside the server (its threads, the band turns, the kernels' lock).

Usage::

    .venv/bin/python bench/bench_offload.py [--samples 8] [--workers 2]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from load_clients import BokehSession  # noqa: E402
from load_test import LocalServer  # noqa: E402

from fbs_core.campaign import SCHEDULER_ENV  # noqa: E402

SLIDER = "Harmonic"
TIMEOUT_S = 300.0


def stats(ms: list[float]) -> str:
    a = np.asarray(ms, float)
    if a.size == 0:
        return "no samples"
    return f"median {np.median(a):7.0f} ms   p95 {np.percentile(a, 95):7.0f} ms   (n={a.size})"


async def open_session(url: str) -> BokehSession:
    s = BokehSession()
    await s.open(url, TIMEOUT_S)
    await s.settle(TIMEOUT_S, 1.0)
    return s


async def set_input(s: BokehSession, title: str, value) -> None:
    """Set the value of the input widget titled ``title`` as BokehJS sends it."""
    from bokeh.document.events import ModelChangedEvent

    m = next(m for m in s.doc.models if getattr(m, "title", None) == title)
    m.set_from_json("value", value, setter=s)
    await s._send([ModelChangedEvent(s.doc, m, "value", value)])


async def wait_busy(s: BokehSession, timeout_s: float = TIMEOUT_S) -> bool:
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout_s:
        if s._busy():
            return True
        await asyncio.sleep(0.05)
    return False


async def measure(args, servers: dict) -> None:
    values = [2, 3, 4]  # harmonics: every change recomputes the probe's plots and band
    probes = {}
    for name, srv in servers.items():
        probes[name] = p = await open_session(srv.url)
        await set_input(p, "Rounds R", args.probe_rounds)
        await p.settle(TIMEOUT_S, 1.0)
        for v in (*values, 1):  # warm: every value once
            await p.change(SLIDER, v, TIMEOUT_S, 0.5)
    lat = {(n, c, k): [] for n in servers for c in ("idle", "hog") for k in ("first", "done")}
    still_busy = {n: [] for n in servers}
    seed = 1000
    turn = dict.fromkeys(servers, 0)  # each probe cycles through the values: always a change
    for sample in range(args.samples):
        for name, srv in servers.items():
            probe = probes[name]
            for cond in ("idle", "hog"):
                hog = None
                if cond == "hog":
                    seed += 1
                    hog = await open_session(srv.url)
                    await hog.change(SLIDER, 7, TIMEOUT_S, 0.5)
                    await hog.settle(TIMEOUT_S, 0.5)
                    await set_input(hog, "Seed", seed)
                    await set_input(hog, "Rounds R", 200_000)
                    if not await wait_busy(hog):
                        raise RuntimeError(f"[{name}] the hog's band never started")
                    await asyncio.sleep(1.0)  # well into the band
                v = values[turn[name] % len(values)]
                turn[name] += 1
                r = await probe.change(SLIDER, v, TIMEOUT_S, 0.5)
                if r is None:
                    raise RuntimeError(f"[{name}] the probe's plots did not change")
                lat[(name, cond, "first")].append(r[0])
                lat[(name, cond, "done")].append(r[1])
                if hog is not None:
                    still_busy[name].append(hog._busy())
                    await hog.close()  # the page closes: its band is cancelled
                    await asyncio.sleep(1.5)  # the cancelled band stops
        print(f"sample {sample + 1}/{args.samples} done", file=sys.stderr)
    print()
    for name in servers:
        for cond in ("idle", "hog"):
            for k, what in (("first", "first update"), ("done", "settled")):
                print(f"{name:11s} {cond:5s} {what:13s} {stats(lat[(name, cond, k)])}")
        print(
            f"{name:11s} hog band still running after the probe: "
            f"{sum(still_busy[name])}/{len(still_busy[name])}"
        )
    for p in probes.values():
        await p.close()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=8)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--threads", type=int, default=4)
    ap.add_argument("--probe-rounds", type=int, default=2000)
    args = ap.parse_args()
    from distributed import Client, LocalCluster

    cluster = LocalCluster(
        n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=":0"
    )
    client = Client(cluster)
    servers: dict[str, LocalServer] = {}
    try:
        client.wait_for_workers(args.workers)
        servers["in-process"] = LocalServer(args.threads, start_s=TIMEOUT_S)
        os.environ[SCHEDULER_ENV] = cluster.scheduler_address
        try:
            servers["offloaded"] = LocalServer(args.threads, start_s=TIMEOUT_S)
        finally:
            del os.environ[SCHEDULER_ENV]
        print(
            f"cores: {os.cpu_count()}, load average {os.getloadavg()[0]:.1f} (the machine is "
            f"shared with other jobs); {args.workers} Dask worker processes on this machine; "
            f"--num-threads {args.threads}; hog: 200,000 rounds at harmonic 7; probe: slider "
            f"harmonic with a {args.probe_rounds:,}-round band of its own"
        )
        asyncio.run(measure(args, servers))
    finally:
        for srv in servers.values():
            srv.stop()
        client.close()
        cluster.close()


if __name__ == "__main__":
    main()
