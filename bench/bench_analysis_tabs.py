"""Analysis tabs of other sessions against a victim's control changes (issue 28), figures printed.

Issue 28: four tabs flipping the phase view's DOF and N raised another session's p95 from
319 to 733 ms and the server's memory by 437 MB; stepping N on the speed tab (a thread per
step, computing the next speed map ahead) raised it from 207 to 1145 ms and the memory by
505 MB. This benchmark serves the app (``panel serve app/main.py --num-threads 4 --warm``,
one server per ``--tree``), opens sessions with the Bokeh protocol client
(``bench/load_clients.py``: no browser) and measures a victim on the main page changing N,
the harmonic (with a new seed: a scatter band) and the response DOF in turn (the time to
its first plot update; ``bench/attack_suite.py``'s victim):

- alone;
- while ``--attackers`` sessions on the phase tab flip their DOF and N every
  ``--every`` seconds without waiting for the page (the peaks' coupled modes of every state
  they pass through are asked for);
- while as many sessions on the speed tab step N one step at a time (every step asks for
  the next speed map ahead).

The server's resident memory is printed before, at its peak during and after each attack.
With several ``--tree`` the scenarios alternate between the trees' servers in one run (the
other server idle), so old and new code see the same machine load.

Usage::

    .venv/bin/python bench/bench_analysis_tabs.py --tree /path/to/old/checkout --tree .
    .venv/bin/python bench/bench_analysis_tabs.py --changes 24 --attackers 4 --every 0.25
"""

from __future__ import annotations

import argparse
import asyncio
import os
import sys
import threading
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from attack_suite import (  # noqa: E402
    _dof_buttons,
    _n_slider,
    _open,
    _timed_change,
    _timed_changes,
    free_port,
)
from bench_dashboard import ROOT, start_server  # noqa: E402


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


class Memory:
    """The server's resident memory: before, peak while in the block, after."""

    def __init__(self, pid: int):
        self.pid = pid

    def __enter__(self):
        self.before = self.peak = rss_mb(self.pid)
        self._stop = threading.Event()

        def sample():
            while not self._stop.wait(0.05):
                self.peak = max(self.peak, rss_mb(self.pid))

        self._t = threading.Thread(target=sample, daemon=True)
        self._t.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._t.join()
        self.after = rss_mb(self.pid)

    def text(self) -> str:
        return f"RSS {self.before:.0f} -> peak {self.peak:.0f} -> {self.after:.0f} MB"


async def _send(sess, raw) -> None:
    """Send widget changes as BokehJS would, without waiting for the page."""
    from bokeh.document.events import ModelChangedEvent

    events = []
    for m, attr, value in raw:
        m.set_from_json(attr, value, setter=sess)
        events.append(ModelChangedEvent(sess.doc, m, attr, value))
    await sess._send(events)


async def phase_flipper(sess, stop: asyncio.Event, every: float, k0: int) -> int:
    """Flip the DOF and N of a session on the phase tab until ``stop``; changes sent."""
    n_slider, dof = _n_slider(sess), _dof_buttons(sess)
    k = k0
    while not stop.is_set():
        if k % 2:
            raw = [(dof, "active", k % 6)]
        else:
            idx = 4 + (k // 2) % 12  # N = 50, 60, ... 160
            raw = [(n_slider, a, idx) for a in ("value", "value_throttled")]
        await _send(sess, raw)
        k += 1
        try:
            await asyncio.wait_for(stop.wait(), every)
        except TimeoutError:
            pass
    return k - k0


async def speed_stepper(sess, stop: asyncio.Event, every: float, k0: int) -> int:
    """Step N of a session on the speed tab one step at a time, up and down."""
    n_slider = _n_slider(sess)
    k = k0
    while not stop.is_set():
        idx = 4 + abs((k % 24) - 12)  # 50 .. 170 .. 50, one step at a time
        await _send(sess, [(n_slider, a, idx) for a in ("value", "value_throttled")])
        k += 1
        try:
            await asyncio.wait_for(stop.wait(), every)
        except TimeoutError:
            pass
    return k - k0


async def scenario(base: str, pid: int, kind: str, args, seed0: int) -> tuple:
    """The victim's first-update times (ms) alone (``kind`` None) or under ``kind``."""
    victim = await _open(base, f"/main?rounds={args.victim_rounds}", None)
    await victim.settle(120, 1.0)
    for h in range(2, 9):  # every harmonic once: its truncation map is cached
        await _timed_change(victim, {"Harmonic": (h - 1) % 7 + 1}, 120)
    attackers, tasks, stop = [], [], asyncio.Event()
    mem = Memory(pid)
    with mem:
        if kind is not None:
            tab = "phase" if kind == "phase" else "speed"
            for _ in range(args.attackers):
                s = await _open(base, f"/main?atab={tab}&rounds=200", None)
                await s.settle(120, 1.0)
                attackers.append(s)
            work = phase_flipper if kind == "phase" else speed_stepper
            tasks = [
                asyncio.ensure_future(work(s, stop, args.every, 7 * i))
                for i, s in enumerate(attackers)
            ]
            await asyncio.sleep(3 * args.every)
        _, first, _ = await _timed_changes(victim, args.changes, 120, seed0)
        stop.set()
        sent = sum([await t for t in tasks])
        for s in attackers:
            await s.close()
        await victim.close()
        await asyncio.sleep(2.0)  # what the server keeps once the attack ended
    return first, sent, mem.text()


def _stats(ms: list[float]) -> str:
    a = np.asarray(ms)
    return f"p50 {np.median(a):6.0f} ms  p95 {np.percentile(a, 95):6.0f} ms  max {a.max():6.0f} ms"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tree", action="append", type=Path, help="a checkout (repeat)")
    ap.add_argument("--changes", type=int, default=18, help="victim changes per scenario")
    ap.add_argument("--attackers", type=int, default=4)
    ap.add_argument("--every", type=float, default=0.25, help="seconds between their changes")
    ap.add_argument("--victim-rounds", type=int, default=1000)
    ap.add_argument("--threads", type=int, default=4)
    args = ap.parse_args()
    trees = [t.resolve() for t in (args.tree or [ROOT])]
    print(
        f"cores: {os.cpu_count()}, load average: {os.getloadavg()[0]:.1f}; "
        f"{args.attackers} attackers every {args.every:g} s; victim: {args.changes} changes "
        f"(N, harmonic + seed, DOF), {args.victim_rounds:,}-round bands; trees: "
        + ", ".join(map(str, trees))
    )
    servers = []
    try:
        for tree in trees:
            port = free_port()
            proc, ready = start_server(port, args.threads, True, tree)
            servers.append((tree, proc, port, ready))
        for tree, proc, _port, ready in servers:
            if ready.get(timeout=900) is None:
                print("".join(proc.log))
                raise RuntimeError(f"the server of {tree} did not start")
        results: dict = {}
        for i, kind in enumerate((None, "phase", "speed")):
            for tree, proc, port, _ in servers:  # alternate: the same load for each tree
                first, sent, mem = asyncio.run(
                    scenario(f"http://127.0.0.1:{port}", proc.pid, kind, args, 10_000 * (i + 1))
                )
                results[(tree, kind)] = (first, sent, mem)
                what = {None: "victim alone", "phase": "phase tabs", "speed": "speed tabs"}[kind]
                extra = f" ({sent} changes sent by the attackers)" if kind else ""
                print(f"[{tree.name}] {what:13s} first update: {_stats(first)}  {mem}{extra}")
        return 0
    finally:
        for _tree, proc, _port, _ in servers:
            proc.kill()
            proc.wait()


if __name__ == "__main__":
    raise SystemExit(main())
