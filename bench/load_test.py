"""Many users at once: concurrent sessions against one dashboard server.

Every session is a separate Bokeh session on the server, like a meeting participant's
browser tab. Two kinds of client (``bench/load_clients.py``):

- ``--client browser`` (default): a playwright chromium context with one page; latencies
  are measured inside the page with ``performance.now()``;
- ``--client bokeh``: a Bokeh websocket protocol client holding a replica of the document
  (what the page holds, without rendering); a small fraction of a browser's CPU, so on one
  machine the figures are the server's rather than the browsers';
- ``--client raw``: the Bokeh websocket protocol without a replica (the page fetched for its
  session token, document-ready and slider changes sent as BokehJS sends them, only message
  headers and patch contents decoded); a fraction of the Bokeh client's CPU, so 50 sessions
  do not saturate the clients' core. Its isolation check pulls each session's document
  once more at the end.

All sessions open at once and wait for their plots to settle ("open to settled plots");
once every session is open, each moves a slider through its own sequence of values
(``--changes`` times), all sessions at the same time. Per change: the time from setting
the slider's model value (what BokehJS does when a user releases it) to the first change
of the plot data ("first update") and to the last one before the data stay quiet
("settled").

Checks (any failure -> exit status 1):

- no errors: every page loads, every change updates the plots, no JavaScript error in any
  page, no traceback in the server log;
- no session sees another's state: at the end each session's slider holds the value that
  session set last, and its plot data equal those of a fresh reference session that set the
  same value alone (sessions ending on the same value agree; a cross-session leak of state
  or of cached mutable results would make them differ).

The clients' cores' busy share during the changes (all processes, /proc/stat) and this
script's own share say whether a figure is the server's or the clients' (CLIENT-LIMITED).

Prints page-load and change latencies (median, p95, max) per number of sessions, and the
largest number of sessions whose p95 first-update latency stays under ``--target`` (1 s).

A session's cost in memory (``--serve`` and ``--docker``): the resident memory of the server
(its process and the processes it started) before a level, once all its sessions are open,
and after they all closed: the closed sessions destroyed by Bokeh (its log says so for each)
and the server idle again, which includes Panel's garbage collection after destroyed
sessions. Per session: (open - before) / n and (after - before) / n, what the closed
sessions kept in resident memory (the allocator keeps freed memory for reuse); and the
pages the server itself counts alive at its first thawed collection after they all ended
(``app/runtime/collector.py``: 0 when no closed page was kept).

Servers (loopback only, stopped at the end by PID or container ID):
  --url URL          an already running server
  --serve            ``panel serve`` of the app via docker/entrypoint.py (no Docker)
  --docker IMAGE     ``docker run --cpus CPUS`` of the image (default 2 CPUs)

Examples:
  python bench/load_test.py --serve --sessions 20
  python bench/load_test.py --docker tire-fbs:proof --cpus 2 --client bokeh --sessions 1,2,5,10,20
  python bench/load_test.py --docker tire-fbs:proof --cpus 2 --sessions 5,10,20,30
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import re
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from load_clients import BokehSession, BrowserSession, RawSession, chromium_args  # noqa: E402


@dataclass
class SessionResult:
    index: int
    load_s: float | None = None
    first_ms: list[float] = field(default_factory=list)
    settled_ms: list[float] = field(default_factory=list)
    last_value: float | None = None
    final_value: float | None = None
    final_digest: str | None = None
    errors: list[str] = field(default_factory=list)
    session: object = None


def slider_values(info: dict, k: int = 7) -> list[float]:
    """At most ``k`` evenly spaced values of a slider, its ends included.

    Few values keep the number of distinct final states (and of reference sessions) small.
    """
    start, end, step = info["start"], info["end"], info["step"] or 1
    n = int(round((end - start) / step)) + 1
    picks = sorted({round(j * (n - 1) / (k - 1)) for j in range(k)}) if n > k else range(n)
    values = [start + j * step for j in picks]
    return [int(v) if float(v).is_integer() else v for v in values]


def targets(values: list[float], index: int, changes: int, current: float) -> list[float]:
    """The session's own sequence of slider values: each differs from the one before."""
    seq, prev = [], current
    for k in range(changes):
        j = (index + 3 * k + 1) % len(values)
        while values[j] == prev:
            j = (j + 1) % len(values)
        seq.append(values[j])
        prev = values[j]
    return seq


#: Above this share of a core the single-threaded protocol clients (bokeh, raw) throttle
#: themselves (they send a session's next change only once its last one is done): such a
#: level does not count for the capacity figure.
CLIENT_LIMIT = 0.75
#: Above this busy share of the clients' cores the browsers (whose CPU this script does not
#: see) wait for a core.
CORES_LIMIT = 0.9
#: On a saturated clients' core (other processes on it), protocol clients using more than
#: this share of it wanted more than they got.
CLIENT_SHARED_LIMIT = 0.25
#: Above this share of a core taken by processes other than ours (the machine is shared)
#: the figures carry their noise: said in the output.
NEIGHBOURS_LIMIT = 0.25


def client_limited(row: dict) -> str | None:
    """Why a level's figures are (also) the clients', or None. The protocol clients are
    this script; a browser's CPU shows only as the busy share of the clients' cores."""
    busy = row.get("clients_cores_busy")
    if row["client"] != "browser":
        own = row["script_core_share"]
        if own > CLIENT_LIMIT:
            return (
                f"the protocol clients used {100 * own:.0f}% of their core"
                f" (limit {100 * CLIENT_LIMIT:.0f}%)"
            )
        # a full core shared with other processes: clients needing a good part of it
        # got less than they needed (a mostly idle client is still served promptly)
        if busy is not None and busy > CORES_LIMIT and own > CLIENT_SHARED_LIMIT:
            return (
                f"the clients' core was {100 * busy:.0f}% busy, other processes included, and"
                f" the protocol clients needed {100 * own:.0f}% of it"
                f" (limit {100 * CLIENT_SHARED_LIMIT:.0f}% on a full core)"
            )
        return None
    if row.get("other_cores_busy") is not None and busy is not None and busy > CORES_LIMIT:
        return f"the clients' cores were {100 * busy:.0f}% busy (limit {100 * CORES_LIMIT:.0f}%)"
    return None


def neighbours(row: dict) -> dict[str, float]:
    """The share of a core that processes other than the server and this script took
    during the changes, on the clients' and on the server's cores (when pinned)."""
    if row.get("other_cores_busy") is None:
        return {}
    out = {}
    if row["client"] != "browser":  # a browser's CPU is not this script's
        out["clients'"] = row["clients_cores_busy"] - row["script_core_share"]
    if row.get("server_core_share") is not None:
        out["server's"] = row["other_cores_busy"] - row["server_core_share"]
    return out


def core_shares(row: dict, client: str) -> str:
    """Who kept which cores busy during the changes, in words."""
    script = "this script" + (" and its protocol clients" if client != "browser" else "")
    own = f"{script} {100 * row['script_core_share']:.0f}%"
    server = row.get("server_core_share")
    server_text = "" if server is None else f"the server {100 * server:.0f}%"
    if row.get("other_cores_busy") is None:  # nothing pinned: every core is everyone's
        return f"of a core: {own}" + (f", {server_text}" if server_text else "")
    return (
        f"clients' core(s) busy {100 * row['clients_cores_busy']:.0f}% ({own}); "
        f"server's core(s) busy {100 * row['other_cores_busy']:.0f}%"
        + (f" ({server_text})" if server_text else "")
    )


class AllOpen:
    """Lets the sessions start changing only once every session has opened (or failed)."""

    def __init__(self, n: int, server_cpu_s=None, server_rss_mb=None):
        self._left, self._event = n, asyncio.Event()
        self._server_cpu_s = server_cpu_s or (lambda: None)
        self._server_rss_mb = server_rss_mb or (lambda: None)
        self.rss_open_mb = None

    def arrive(self) -> None:
        self._left -= 1
        if self._left <= 0 and not self._event.is_set():
            # the change phase starts: where this script's CPU time goes from here on
            self.at = (time.monotonic(), time.process_time(), self._server_cpu_s())
            self.cores_at = cores_busy_s()
            self.rss_open_mb = self._server_rss_mb()  # every session open, none changed yet
            self._event.set()

    async def wait(self) -> None:
        await self._event.wait()


async def run_session(
    new_session,
    url: str,
    index: int,
    changes: int,
    title: str,
    timeout_s: float,
    start_delay: float,
    all_open: AllOpen,
) -> SessionResult:
    res = SessionResult(index)
    await asyncio.sleep(start_delay)
    res.session = sess = new_session()  # kept open for the isolation check
    res.errors = sess.errors  # page or protocol errors and the runner's own, in one list
    arrived = False
    try:
        t0 = time.monotonic()
        await sess.open(url, timeout_s)
        if await sess.settle(timeout_s, 1.0) is None:
            res.errors.append("plot data never settled after load")
            return res
        res.load_s = time.monotonic() - t0 - 1.0  # minus the quiet second of settle
        info = await sess.slider_info(title)
        if info is None:
            res.errors.append(f"no slider with title containing {title!r}")
            return res
        all_open.arrive()
        arrived = True
        await all_open.wait()
        for value in targets(slider_values(info), index, changes, info["value"]):
            lat = await sess.change(title, value, timeout_s, 0.4)
            res.last_value = value
            if lat is None:
                res.errors.append(f"setting the slider to {value} changed no plot data")
                continue
            res.first_ms.append(lat[0])
            res.settled_ms.append(lat[1])
        res.final_value = (await sess.slider_info(title))["value"]
    except Exception as exc:  # a failed session is reported, the others go on
        res.errors.append(f"{type(exc).__name__}: {(str(exc).splitlines() or [''])[0]}")
    finally:
        if not arrived:
            all_open.arrive()
    return res


async def final_digest(res: SessionResult, timeout_s: float) -> None:
    """Plot data of a session once nothing changes for 3 s any more; closes the session."""
    try:
        if not res.errors:
            if await res.session.settle(timeout_s, 3.0) is not None:
                res.final_digest = await res.session.plot_digest(timeout_s)
    finally:
        await res.session.close()


async def reference_session(new_session, url: str, title: str, value: float, timeout_s: float):
    """A lone fresh session that sets the slider to ``value`` (left open for its digest)."""
    sess = new_session()
    try:
        await sess.open(url, timeout_s)
        await sess.settle(timeout_s, 1.0)
        info = await sess.slider_info(title)
        if info["value"] != value:
            await sess.change(title, value, timeout_s, 0.4)
    except Exception:
        await sess.close()
        raise
    return sess


async def warm_up(new_session, url: str, title: str, timeout_s: float) -> float:
    """One session visits every value the sessions will set (the server's shared result
    cache then holds them, as after a while of use); returns the seconds it took."""
    t0 = time.monotonic()
    sess = new_session()
    try:
        await sess.open(url, timeout_s)
        await sess.settle(timeout_s, 1.0)
        info = await sess.slider_info(title)
        for value in slider_values(info):
            if value == info["value"]:
                continue  # what the page opened with is computed already
            await sess.change(title, value, timeout_s, 0.4)
            await sess.settle(timeout_s, 0.5)
    finally:
        await sess.close()
    return time.monotonic() - t0


def session_factory(client: str, stack: contextlib.AsyncExitStack):
    """A coroutine giving a function that makes a new (unopened) session of this kind."""

    async def make():
        if client == "bokeh":
            return BokehSession
        if client == "raw":
            return RawSession
        from playwright.async_api import async_playwright

        p = await stack.enter_async_context(async_playwright())
        browser = await p.chromium.launch(**chromium_args())
        stack.push_async_callback(browser.close)
        return lambda: BrowserSession(browser)

    return make()


async def run_warm_up(url: str, title: str, timeout_s: float, client: str) -> float:
    async with contextlib.AsyncExitStack() as stack:
        return await warm_up(await session_factory(client, stack), url, title, timeout_s)


async def session_digest(sess, timeout_s: float) -> str | None:
    """Plot data of a session once nothing changes for 3 s any more; closes it."""
    try:
        if await sess.settle(timeout_s, 3.0) is None:
            return None
        return await sess.plot_digest(timeout_s)
    finally:
        await sess.close()


def pct(values: list[float], q: float) -> float:
    s = sorted(values)
    if not s:
        return float("nan")
    return s[min(len(s) - 1, max(0, int(round(q / 100 * len(s) + 0.5)) - 1))]


def summary(values: list[float]) -> str:
    if not values:
        return "n/a"
    return (
        f"median {statistics.median(values):7.0f}  p95 {pct(values, 95):7.0f}  "
        f"max {max(values):7.0f}"
    )


async def wait_server_idle(
    cpu_s, timeout_s: float, quiet_s: float = 3.0, busy_share: float = 0.1
) -> bool:
    """Wait until the server has used under ``busy_share`` of a core for ``quiet_s``
    seconds (so no update is still queued behind a backlog); False if it never is, or
    if the server's CPU time cannot be read."""
    if cpu_s is None or cpu_s() is None:
        return False
    t_end = time.monotonic() + timeout_s
    last, quiet = cpu_s(), 0.0
    while time.monotonic() < t_end:
        await asyncio.sleep(1.0)
        now = cpu_s()
        quiet = quiet + 1.0 if now - last < busy_share else 0.0
        last = now
        if quiet >= quiet_s:
            return True
    return False


async def run_level(
    url: str,
    n: int,
    changes: int,
    title: str,
    timeout_s: float,
    check_isolation: bool,
    cpu_s=None,
    client: str = "browser",
    rss_mb=None,
) -> dict:
    async with contextlib.AsyncExitStack() as stack:
        new_session = await session_factory(client, stack)

        t0 = time.monotonic()
        all_open = AllOpen(n, cpu_s, rss_mb)
        results = await asyncio.gather(
            *(
                run_session(new_session, url, i, changes, title, timeout_s, 0.1 * i, all_open)
                for i in range(n)
            )
        )
        wall = time.monotonic() - t0
        # this script's (and its Bokeh clients') share of a core while the sessions changed:
        # near 1 would mean the clients themselves delayed what they measured
        change_wall = time.monotonic() - all_open.at[0]
        script_share = (time.process_time() - all_open.at[1]) / change_wall
        # every process's share of the clients' cores and of the others (the server's when
        # pinned): the machine is shared, a busy core need not be this script's doing
        cores = cores_busy_s()
        mine = os.sched_getaffinity(0)

        def share(cpus: set[int]) -> float | None:
            if not cpus:
                return None
            busy = sum(cores[c] - all_open.cores_at[c] for c in cpus)
            return busy / (change_wall * len(cpus))

        clients_share, others_share = share(mine), share(set(cores) - mine)
        server_share = None if all_open.at[2] is None else (cpu_s() - all_open.at[2]) / change_wall
        n_changes = sum(len(r.first_ms) for r in results)
        server_per_change = (
            None
            if all_open.at[2] is None or not n_changes
            else (cpu_s() - all_open.at[2]) / n_changes
        )
        problems = [f"session {r.index}: {e}" for r in results for e in r.errors]
        for r in results:
            if not r.errors and r.final_value != r.last_value:
                problems.append(
                    f"session {r.index}: slider shows {r.final_value}, "
                    f"but this session set {r.last_value} last"
                )
        refs: dict = {}
        if check_isolation:
            values = sorted({r.last_value for r in results if not r.errors})
            ref_sessions = await asyncio.gather(
                *(reference_session(new_session, url, title, v, timeout_s) for v in values)
            )
        # under a backlog a session can be quiet for seconds with updates still queued on
        # the server: take every digest once the server itself is idle
        idle = await wait_server_idle(cpu_s, timeout_s)
        if check_isolation:
            digests = await asyncio.gather(
                *(session_digest(sess, timeout_s) for sess in ref_sessions)
            )
            refs = dict(zip(values, digests, strict=True))
            problems += [
                f"reference session at {v}: {e}"
                for v, sess in zip(values, ref_sessions, strict=True)
                for e in sess.errors
            ]
        n_early = [len(r.errors) for r in results]
        await asyncio.gather(*(final_digest(r, timeout_s) for r in results))
        # errors reported after the changes (a late page error, a patch that failed)
        problems += [
            f"session {r.index}: {e}"
            for r, k in zip(results, n_early, strict=True)
            for e in r.errors[k:]
        ]
        if check_isolation:
            for r in results:
                if r.errors or r.final_digest is None:
                    continue
                if r.final_digest != refs.get(r.last_value):
                    problems.append(
                        f"session {r.index}: plot data differ from a lone session's "
                        f"at slider value {r.last_value}"
                        + ("" if idle else " (server never idle before the check)")
                    )
    first = [x for r in results for x in r.first_ms]
    settled = [x for r in results for x in r.settled_ms]
    loads = [r.load_s * 1000 for r in results if r.load_s is not None]
    return {
        "sessions": n,
        "client": client,
        "changes": len(first),
        "wall_s": wall,
        "load_ms": loads,
        "first_ms": first,
        "settled_ms": settled,
        # by change round: the first round is every session changing at the same instant
        "first_ms_by_round": [
            [r.first_ms[k] for r in results if len(r.first_ms) > k] for k in range(changes)
        ],
        "problems": problems,
        "distinct_final_states": len(refs),
        "change_phase_s": change_wall,
        "script_core_share": script_share,
        "clients_cores_busy": clients_share,
        "other_cores_busy": others_share,
        "server_core_share": server_share,
        "server_cpu_per_change_s": server_per_change,
        "rss_open_mb": all_open.rss_open_mb,
        "reference_sessions": len(refs),
    }


# ---- servers -------------------------------------------------------------------------------


def host_busy_s() -> float:
    """CPU seconds the whole host has been busy (all cores), from /proc/stat."""
    with open("/proc/stat") as f:
        fields = [int(x) for x in f.readline().split()[1:]]
    busy = sum(fields) - fields[3] - (fields[4] if len(fields) > 4 else 0)  # minus idle, iowait
    return busy / os.sysconf("SC_CLK_TCK")


def cores_busy_s() -> dict[int, float]:
    """CPU seconds each core has been busy (all processes), from /proc/stat."""
    tick = os.sysconf("SC_CLK_TCK")
    out = {}
    with open("/proc/stat") as f:
        for line in f:
            name, *fields = line.split()
            if not name.startswith("cpu") or name == "cpu":
                continue
            if not name[3:].isdigit():
                break
            v = [int(x) for x in fields]
            out[int(name[3:])] = (sum(v) - v[3] - (v[4] if len(v) > 4 else 0)) / tick
    return out


def proc_tree(pid: int) -> list[int]:
    """A process and its live descendants (their PIDs, from /proc)."""
    children: dict[int, list[int]] = {}
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat") as f:
                ppid = int(f.read().rsplit(")", 1)[1].split()[1])
        except OSError:
            continue
        children.setdefault(ppid, []).append(int(d))
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        todo.extend(children.get(p, []))
    return out


def proc_tree_rss_mb(pid: int) -> float:
    """Resident memory (MB) of a process and its live descendants (VmRSS, /proc)."""
    total = 0.0
    for p in proc_tree(pid):
        try:
            with open(f"/proc/{p}/status") as f:
                total += next(int(x.split()[1]) for x in f if x.startswith("VmRSS")) / 1024
        except (OSError, StopIteration):
            pass
    return total


#: What the app logs when a page's session starts and when Bokeh destroyed it (app/main.py).
SESSION_STARTED, SESSION_ENDED = "a page's session started", "a page's session ended"


#: What the quiet collector logs after a thawed collection (app/runtime/collector.py).
ALIVE = re.compile(r"quiet full collection \(thawed\): \d+ ms; alive: pages (\d+)")


async def pages_alive(server, timeout_s: float) -> int | None:
    """The pages alive at the server's first thawed collection after the last session
    ended (its log), waited for up to ``timeout_s``; None if none came."""
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        logs = server.logs()
        found = list(ALIVE.finditer(logs, max(0, logs.rfind(SESSION_ENDED))))
        if found:
            return int(found[-1].group(1))
        await asyncio.sleep(0.5)
    return None


async def wait_sessions_ended(server, timeout_s: float) -> bool:
    """Wait until every page's session the server started has ended, by its log (Bokeh
    destroys a closed session after its unused lifetime, 15 s, checked every 17 s)."""
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        logs = server.logs()
        if logs.count(SESSION_ENDED) >= logs.count(SESSION_STARTED):
            return True
        await asyncio.sleep(1.0)
    return False


def proc_tree_cpu_s(pid: int) -> float:
    """CPU seconds of a process and its live descendants (utime + stime, /proc)."""
    tick = os.sysconf("SC_CLK_TCK")
    total = 0.0
    for p in proc_tree(pid):
        try:
            with open(f"/proc/{p}/stat") as f:
                st = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += (int(st[11]) + int(st[12])) / tick
    return total


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_http(url: str, timeout_s: float, alive=lambda: True) -> None:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        try:
            with urllib.request.urlopen(url, timeout=5) as r:
                if r.status == 200:
                    return
        except OSError:
            pass
        if not alive():
            raise RuntimeError("the server exited")
        time.sleep(0.5)
    raise RuntimeError(f"{url} did not answer within {timeout_s:.0f} s")


class LocalServer:
    """``panel serve`` through the container's entrypoint, on a loopback port."""

    def __init__(self, threads: int, cpuset: set[int] | None = None, start_s: float = 60):
        self.port = free_port()
        self.log = tempfile.NamedTemporaryFile("w+", suffix=".log", delete=False)
        env = {
            **os.environ,
            "FBS_PORT": str(self.port),
            "FBS_ADDRESS": "127.0.0.1",
            "FBS_NUM_THREADS": str(threads),
            "BOKEH_ALLOW_WS_ORIGIN": f"127.0.0.1:{self.port}",
        }
        pin = None if cpuset is None else (lambda: os.sched_setaffinity(0, cpuset))
        self.proc = subprocess.Popen(
            [sys.executable, str(ROOT / "docker" / "entrypoint.py")],
            env=env,
            stdout=self.log,
            stderr=subprocess.STDOUT,
            preexec_fn=pin,
        )
        self.url = f"http://127.0.0.1:{self.port}/"
        wait_http(self.url + "liveness", start_s, lambda: self.proc.poll() is None)

    def logs(self) -> str:
        self.log.seek(0)
        return self.log.read()

    def cpu_s(self) -> float | None:
        return proc_tree_cpu_s(self.proc.pid)

    def rss_mb(self) -> float | None:
        return proc_tree_rss_mb(self.proc.pid)

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.log.close()
        os.unlink(self.log.name)


class DockerServer:
    """``docker run --cpus`` of the image on a loopback port, removed at the end."""

    def __init__(self, image: str, cpus: float, threads: int, cpuset: set[int] | None = None):
        self.port = free_port()
        pin = [] if cpuset is None else ["--cpuset-cpus", ",".join(map(str, sorted(cpuset)))]
        self.cid = subprocess.run(
            [
                "docker",
                "run",
                "-d",
                "--cpus",
                str(cpus),
                *pin,
                "-p",
                f"127.0.0.1:{self.port}:5006",
                "-e",
                f"BOKEH_ALLOW_WS_ORIGIN=127.0.0.1:{self.port}",
                "-e",
                f"FBS_NUM_THREADS={threads}",
                image,
            ],
            check=True,
            capture_output=True,
            text=True,
        ).stdout.strip()
        self.url = f"http://127.0.0.1:{self.port}/"
        try:
            wait_http(self.url + "liveness", 120, self._running)
        except Exception:
            self.stop()
            raise

    def _running(self) -> bool:
        out = subprocess.run(
            ["docker", "inspect", "-f", "{{.State.Running}}", self.cid],
            capture_output=True,
            text=True,
        ).stdout.strip()
        return out == "true"

    def logs(self) -> str:
        return subprocess.run(["docker", "logs", self.cid], capture_output=True, text=True).stdout

    def cpu_s(self) -> float | None:
        """CPU seconds of the container (cgroup v2 or v1 accounting), None if unknown."""
        for path, scale, key in (
            (f"/sys/fs/cgroup/system.slice/docker-{self.cid}.scope/cpu.stat", 1e-6, "usage_usec"),
            (f"/sys/fs/cgroup/docker/{self.cid}/cpu.stat", 1e-6, "usage_usec"),
            (f"/sys/fs/cgroup/cpuacct/docker/{self.cid}/cpuacct.usage", 1e-9, None),
        ):
            try:
                text = Path(path).read_text()
            except OSError:
                continue
            if key is None:
                return int(text) * scale
            for line in text.splitlines():
                if line.startswith(key):
                    return int(line.split()[1]) * scale
        return None

    def rss_mb(self) -> float | None:
        """Resident memory of the container's processes (its main process's tree)."""
        pid = subprocess.run(
            ["docker", "inspect", "-f", "{{.State.Pid}}", self.cid],
            capture_output=True,
            text=True,
        ).stdout.strip()
        return proc_tree_rss_mb(int(pid)) if pid.isdigit() and int(pid) > 0 else None

    def stop(self) -> None:
        subprocess.run(["docker", "rm", "-f", self.cid], capture_output=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--url", help="URL of a running dashboard")
    src.add_argument("--serve", action="store_true", help="serve the app locally (no Docker)")
    src.add_argument("--docker", metavar="IMAGE", help="run this image with docker")
    ap.add_argument("--cpus", type=float, default=2.0, help="docker run --cpus (2)")
    ap.add_argument("--threads", type=int, default=4, help="server worker threads (4)")
    ap.add_argument(
        "--sessions", default="20", help="concurrent sessions; a comma list sweeps levels (20)"
    )
    ap.add_argument("--changes", type=int, default=5, help="slider changes per session (5)")
    ap.add_argument(
        "--slider",
        default="Harmonic",
        help="slider to move: part of its title, or #k for the k-th (Harmonic)",
    )
    ap.add_argument(
        "--client",
        choices=("browser", "bokeh", "raw"),
        default="browser",
        help="sessions as chromium pages (browser), as Bokeh protocol clients with a "
        "document replica (bokeh: no rendering, a small fraction of a browser's CPU) or "
        "as raw protocol clients (raw: no replica, a fraction of the bokeh client's CPU)",
    )
    ap.add_argument("--target", type=float, default=1000.0, help="p95 target in ms (1000)")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds per wait (120)")
    ap.add_argument("--max-sessions", type=int, default=60, help="safety bound (60)")
    ap.add_argument(
        "--server-cpus",
        metavar="LIST",
        help="pin the server to these host CPUs (e.g. '1'; docker --cpuset-cpus) "
        "and this script with its clients to the others, so the two never "
        "compete for a core",
    )
    ap.add_argument(
        "--cold",
        action="store_true",
        help="no warm-up: the first level also pays for computing the results "
        "that the server then shares between sessions",
    )
    ap.add_argument("--no-isolation-check", action="store_true")
    ap.add_argument("--json", help="write the figures to this file")
    args = ap.parse_args(argv)
    levels = [int(x) for x in args.sessions.split(",")]
    if any(n < 1 or n > args.max_sessions for n in levels):
        ap.error(f"--sessions must be within 1..{args.max_sessions}")

    server_cpus = None
    if args.server_cpus:
        if args.url:
            ap.error("--server-cpus needs --serve or --docker")
        server_cpus = {int(x) for x in args.server_cpus.split(",")}
        rest = set(os.sched_getaffinity(0)) - server_cpus
        if not rest or not server_cpus <= set(range(os.cpu_count())):
            ap.error(
                f"--server-cpus {args.server_cpus}: needs host CPUs that exist and "
                f"leaves none for the clients"
            )
        os.sched_setaffinity(0, rest)  # browsers and threads started later inherit it
        args.cpus = min(args.cpus, float(len(server_cpus)))
    server = None
    if args.serve:
        server = LocalServer(args.threads, server_cpus)
    elif args.docker:
        server = DockerServer(args.docker, args.cpus, args.threads, server_cpus)
    url = server.url if server else args.url
    where = (
        f"docker {args.docker} --cpus {args.cpus}"
        if args.docker
        else "local panel serve"
        if args.serve
        else url
    )
    if server_cpus is not None:
        where += (
            f", server on CPU {args.server_cpus}, clients on CPU "
            f"{','.join(map(str, sorted(os.sched_getaffinity(0))))}"
        )
    print(
        f"load test: {where}, {args.threads} threads, sessions as {args.client} clients, "
        f"{os.cpu_count()} host cores, "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    rows, failed = [], False

    def settle() -> tuple[bool, float | None]:
        """Wait until every page's session has ended and the server is idle; its resident
        memory then (None without a server of ours)."""
        if server is None:
            return False, None
        ended = asyncio.run(wait_sessions_ended(server, 120))
        asyncio.run(wait_server_idle(server.cpu_s, 60))
        return ended, server.rss_mb()

    def kept() -> int | None:  # pages alive once all ended and collected (None: no server)
        return None if server is None else asyncio.run(pages_alive(server, 60))

    try:
        if not args.cold:
            took = asyncio.run(run_warm_up(url, args.slider, args.timeout, args.client))
            print(f"warm-up: one session visited every slider value in {took:.1f} s")
        for n in levels:
            # Bokeh destroys the closed sessions of the last level within about 32 s
            # (unused-session lifetime 15 s, checked every 17 s): let that happen before
            # this level rather than during its changes
            _, rss0 = settle()
            cpu0 = server.cpu_s() if server is not None else None
            host0, t0, self0 = host_busy_s(), time.monotonic(), time.process_time()
            row = asyncio.run(
                run_level(
                    url,
                    n,
                    args.changes,
                    args.slider,
                    args.timeout,
                    not args.no_isolation_check,
                    server.cpu_s if server is not None else None,
                    args.client,
                    server.rss_mb if server is not None else None,
                )
            )
            ended, rss1 = settle()
            row["rss_mb"] = (rss0, row["rss_open_mb"], rss1)
            row["pages_alive"] = kept()
            row["sessions_ended"] = ended
            cpu1 = server.cpu_s() if server is not None else None
            row["host_cpu_s"] = host_busy_s() - host0
            row["script_cpu_s"] = time.process_time() - self0  # incl. Bokeh clients
            row["accounted_s"] = time.monotonic() - t0  # incl. the isolation check
            row["server_cpu_s"] = None if cpu0 is None or cpu1 is None else cpu1 - cpu0
            rows.append(row)
            print(
                f"\n== {n} concurrent sessions, {row['changes']} changes, "
                f"{row['wall_s']:.1f} s wall, {row['distinct_final_states']} distinct "
                f"final states checked against lone sessions"
            )
            print(f"   open to settled plots    {summary(row['load_ms'])}   (all opening at once)")
            print(
                f"   change -> first update   {summary(row['first_ms'])}   (all changing, "
                "once all are open)"
            )
            print(f"   change -> settled        {summary(row['settled_ms'])}")
            rounds = [x for x in row["first_ms_by_round"] if x]
            if len(rounds) > 1:  # the first round: all sessions changing at one instant
                print(
                    "   first update by round    "
                    + "; ".join(
                        f"{k + 1}: {statistics.median(x):.0f}/{pct(x, 95):.0f}"
                        for k, x in enumerate(rounds)
                    )
                    + "   (median/p95 ms)"
                )
            print(f"   change phase {row['change_phase_s']:.1f} s; {core_shares(row, args.client)}")
            if row["server_cpu_per_change_s"] is not None:
                print(
                    f"   server CPU {1000 * row['server_cpu_per_change_s']:.0f} ms per change"
                    f" ({row['changes']} changes)"
                )
            shared = {k: v for k, v in neighbours(row).items() if v > NEIGHBOURS_LIMIT}
            if shared:
                print(
                    "   SHARED MACHINE: other processes took "
                    + ", ".join(f"{100 * v:.0f}% of the {k} core" for k, v in shared.items())
                    + " during the changes; compare figures side by side only"
                )
            limited = client_limited(row)
            print(
                f"   CLIENT-LIMITED: {limited}; they sent their changes late or stamped the "
                "server's patches late, and this level measured the clients as well"
                if limited
                else "   not client-limited: the latencies are the server's"
            )
            if row["server_cpu_s"] is not None:
                # where the cores went: on one machine the browsers compete with the server
                print(
                    f"   CPU over {row['accounted_s']:.0f} s (sessions and isolation check): "
                    f"server {row['server_cpu_s']:.1f} s, everything else on the host "
                    f"{row['host_cpu_s'] - row['server_cpu_s']:.1f} s (of which this "
                    f"script{' and its protocol clients' if args.client != 'browser' else ''} "
                    f"{row['script_cpu_s']:.1f} s), of {os.cpu_count() * row['accounted_s']:.0f}"
                    " core-seconds"
                )
            if rss0 is not None and row["rss_open_mb"] is not None and rss1 is not None:
                print(
                    f"   server memory (RSS, MB): before {rss0:.0f}, all {n} open "
                    f"{row['rss_open_mb']:.0f} (+{(row['rss_open_mb'] - rss0) / n:.1f} per "
                    f"session), after all closed{'' if ended else ' (NOT all ended in 120 s)'}"
                    f" and idle {rss1:.0f} ({rss1 - rss0:+.0f}: "
                    f"{(rss1 - rss0) / n:+.1f} per closed session)"
                )
            if server is not None:
                alive = row["pages_alive"]
                print(
                    "   pages alive after all closed and a collection (the server's count): "
                    + ("none logged within 60 s" if alive is None else str(alive))
                )
            if row["problems"]:
                failed = True
                print(f"   PROBLEMS ({len(row['problems'])}):")
                for p in row["problems"][:20]:
                    print(f"     {p}")
            else:
                print("   no errors; every session saw only its own state")
        if server is not None:
            logs = server.logs()
            lines = logs.splitlines()
            bad = [i for i, ln in enumerate(lines) if "Traceback" in ln or " ERROR " in ln]
            if bad:
                failed = True
                print(f"\nserver log has {len(bad)} error lines; the first:")
                print("\n".join(lines[bad[0] : bad[0] + 25]))
    finally:
        if server is not None:
            server.stop()
    ok = [
        r["sessions"]
        for r in rows
        if not r["problems"]
        and r["first_ms"]
        and pct(r["first_ms"], 95) < args.target
        and not client_limited(r)
    ]
    print(
        f"\nlargest tested number of sessions with p95 first update < {args.target:.0f} ms"
        " (clients below saturation)" + ": "
        f"{max(ok) if ok else 'none'}"
    )
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
