"""One session flooding the compute, in process: what another session's control changes cost.

Issue 20, finding "one session flooding the compute". Two sessions' stores
(:class:`app.store.Results`, bands on their own threads as when served) in one process:

- the hostile session asks for a 200,000-round band (harmonic 7, frequency-dependent
  noise) and changes its seed every ``--every`` seconds (each change cancels the running
  band and starts a new one);
- the victim (1,000-round bands) changes N, the harmonic (with a new seed: a new band) and
  the response DOF in turn, from this thread (as Panel's worker thread does); per change:
  the time to its first published result (what the first plot update waits for), the
  time until every published result of the change is out (the setter returns), and the
  time until its own band of the new settings is published.

The same changes run first without the flood. Also printed: how long threads waited for
the band kernels' process-wide lock (``fbs_core.studies.band_kernel.LOCK``), and how late a
thread that sleeps 5 ms wakes up (the interpreter lock and the cores: what Bokeh's event
loop would feel). No server, no websocket, no drawing: the compute side of the page.

Usage::

    python bench/bench_flood.py                    # 12 victim changes alone, then flooded
    python bench/bench_flood.py --changes 24 --every 1
    python bench/bench_flood.py --single           # 10,000-round h7 band alone, 3 times
"""

from __future__ import annotations

import argparse
import statistics
import threading
import time

import numpy as np

from app.state import DashboardState
from app.store import Results
from fbs_core.studies import band_kernel

RESULTS = ("response", "error_map", "suggested", "eigen", "uncoupled", "band_curves")


class TimedLock:
    """The kernels' lock, recording how long each acquisition waited (by thread name)."""

    def __init__(self, lock) -> None:
        self._lock = lock
        self.waits: dict[str, list[float]] = {}

    def __enter__(self):
        t0 = time.perf_counter()
        self._lock.acquire()
        name = threading.current_thread().name.split("-")[0]
        self.waits.setdefault(name, []).append(time.perf_counter() - t0)
        return self

    def __exit__(self, *exc):
        self._lock.release()
        return False

    def acquire(self, *a, **k):
        return self._lock.acquire(*a, **k)

    def release(self):
        self._lock.release()


class Probe(threading.Thread):
    """Sleeps 5 ms again and again and records how late it woke up."""

    def __init__(self) -> None:
        super().__init__(name="probe", daemon=True)
        self.late: list[float] = []
        self.stop = threading.Event()

    def run(self) -> None:
        while not self.stop.is_set():
            t0 = time.perf_counter()
            time.sleep(0.005)
            self.late.append(time.perf_counter() - t0 - 0.005)


def _wait(cond, timeout: float) -> bool:
    t0 = time.perf_counter()
    while not cond():
        if time.perf_counter() - t0 > timeout:
            return False
        time.sleep(0.002)
    return True


def _store(**noise) -> Results:
    state = DashboardState()
    state.noise.param.update(**noise)
    return Results(state, background=True)


def _changes(victim: Results, n: int, seed0: int, timeout: float) -> dict[str, list]:
    """``n`` victim changes (N, harmonic + seed, DOF in turn): times in ms."""
    out: dict[str, list] = {"kind": [], "first": [], "all": [], "band": []}
    stamps: list[float] = []
    for name in RESULTS:
        victim.param.watch(lambda e: stamps.append(time.perf_counter()), name)
    modes = [50, 100, 150]
    dofs = ["z", "x", "y"]
    for k in range(n):
        kind = ("N", "harmonic", "dof")[k % 3]
        n0 = len(stamps)
        band0 = victim.band
        t0 = time.perf_counter()
        if kind == "N":
            victim.state.case.n_modes = modes[(modes.index(victim.state.case.n_modes) + 1) % 3]
        elif kind == "harmonic":
            h = victim.state.case.harmonic % 7 + 1
            victim.state.noise.seed = seed0 + k  # the band of this seed is not cached
            victim.state.case.harmonic = h
        else:
            victim.state.case.dof = dofs[(dofs.index(victim.state.case.dof) + 1) % 3]
        t_all = time.perf_counter() - t0
        first = (stamps[n0] - t0) if len(stamps) > n0 else t_all
        ok = _wait(lambda: not victim.band_status.busy and victim.band is not None, timeout)
        t_band = (time.perf_counter() - t0) if ok else timeout
        out["kind"].append(kind)
        out["first"].append(1000 * first)
        out["all"].append(1000 * t_all)
        out["band"].append(1000 * t_band if victim.band is not band0 or kind != "dof" else 0)
    return out


def _stats(v: list[float]) -> str:
    a = np.asarray(v, float)
    return (
        f"p50 {np.percentile(a, 50):6.0f} / p95 {np.percentile(a, 95):6.0f} / max {a.max():6.0f} ms"
    )


def _report(label: str, r: dict[str, list]) -> None:
    print(f"  {label}")
    print(f"    first result published  {_stats(r['first'])}")
    print(f"    all results published   {_stats(r['all'])}")
    bands = [b for b, k in zip(r["band"], r["kind"], strict=True) if k != "dof"]
    print(f"    own band published      {_stats(bands)}  (N and harmonic changes)")
    for kind in ("N", "harmonic", "dof"):
        f = [x for x, k in zip(r["first"], r["kind"], strict=True) if k == kind]
        print(f"      {kind:8s} first: {' '.join(f'{x:.0f}' for x in f)}")


def flood(args) -> None:
    lock = TimedLock(band_kernel.LOCK)
    band_kernel.LOCK = lock  # read by band_kernel.band_lines at every call
    victim = _store(rounds=args.victim_rounds)
    print("warming up (every harmonic once, its maps and band cached) ...", flush=True)
    for h in list(range(2, 8)) + [1]:
        victim.state.case.harmonic = h
        _wait(lambda: not victim.band_status.busy, 300)
    for n in (100, 150, 50):
        victim.state.case.n_modes = n
    probe = Probe()
    probe.start()
    time.sleep(1.0)
    probe_idle = list(probe.late)
    lock.waits.clear()
    alone = _changes(victim, args.changes, 10_000, args.timeout)
    waits_alone = {k: list(v) for k, v in lock.waits.items()}
    hostile = _store(rounds=args.flood_rounds, frequency_dependent=True)
    hostile.state.case.harmonic = 7
    stop = threading.Event()
    sent = [0]

    def hostile_loop():
        while not stop.is_set():
            hostile.state.noise.seed = 50_000 + sent[0]
            sent[0] += 1
            stop.wait(args.every)

    th = threading.Thread(target=hostile_loop, name="hostile", daemon=True)
    th.start()
    time.sleep(args.every * 3)
    lock.waits.clear()
    n_probe = len(probe.late)
    t0 = time.perf_counter()
    flooded = _changes(victim, args.changes, 20_000, args.timeout)
    secs = time.perf_counter() - t0
    probe_flood = probe.late[n_probe:]
    stop.set()
    th.join()
    hostile.close()
    probe.stop.set()
    print(f"\nvictim ({args.victim_rounds:,}-round bands), {args.changes} changes (N, h, DOF)")
    _report("alone", alone)
    _report(
        f"under the flood ({sent[0]} hostile {args.flood_rounds:,}-round h7 fdep bands "
        f"requested in {secs:.0f} s)",
        flooded,
    )
    for label, w in (("alone", waits_alone), ("flood", lock.waits)):
        for name, v in sorted(w.items()):
            print(
                f"  kernel-lock waits ({label}) {name:12s} n={len(v):4d} "
                f"mean {1000 * statistics.fmean(v):6.1f} / max {1000 * max(v):7.1f} ms"
            )
    for label, v in (("idle", probe_idle), ("flood", probe_flood)):
        if v:
            print(
                f"  5 ms sleeper, late by ({label}): p50 {1000 * np.percentile(v, 50):.1f} / "
                f"p99 {1000 * np.percentile(v, 99):.1f} / max {1000 * max(v):.1f} ms"
            )


def single(args) -> None:
    import fbs_core

    fbs_core.scatter_band(7, rounds=100, n_modes=50)  # compiled
    times = []
    for k in range(args.repeat):
        t0 = time.perf_counter()
        fbs_core.scatter_band(7, rounds=10_000, n_modes=50, seed=k)
        times.append(time.perf_counter() - t0)
    print(f"10,000-round h7 band alone: {' '.join(f'{t:.2f}' for t in times)} s")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--changes", type=int, default=12)
    ap.add_argument("--every", type=float, default=1.0, help="s between hostile requests")
    ap.add_argument("--flood-rounds", type=int, default=200_000)
    ap.add_argument("--victim-rounds", type=int, default=1_000)
    ap.add_argument("--timeout", type=float, default=60.0, help="s to wait for a victim band")
    ap.add_argument("--single", action="store_true", help="time a 10,000-round h7 band")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    single(args) if args.single else flood(args)


if __name__ == "__main__":
    main()
