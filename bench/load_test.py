"""Many users at once: concurrent browser sessions against one dashboard server.

Every session is a separate playwright browser context (its own cookies, its own Bokeh
session on the server), like a meeting participant's browser. All sessions open the page
at once, wait for the plots, then each moves a slider through its own sequence of values
(``--changes`` times). Per change the latency is measured inside the page: from setting the
slider's model value (what bokehjs does when a user drags it) to the first change of the
plot data in ``Bokeh.documents[0]`` ("first update") and to the last one before the data
stay quiet ("settled").

Checks (any failure -> exit status 1):

- no errors: every page loads, every change updates the plots, no JavaScript error in any
  page, no traceback in the server log;
- no session sees another's state: at the end each session's slider holds the value that
  session set last, and its plot data equal those of a fresh reference session that set the
  same value alone (sessions ending on the same value agree; a cross-session leak of state
  or of cached mutable results would make them differ).

Prints page-load and change latencies (median, p95, max) per number of sessions, and the
largest number of sessions whose p95 first-update latency stays under ``--target`` (1 s).

Servers (loopback only, stopped at the end by PID or container ID):
  --url URL          an already running server
  --serve            ``panel serve`` of the app via docker/entrypoint.py (no Docker)
  --docker IMAGE     ``docker run --cpus CPUS`` of the image (default 2 CPUs)

Examples:
  python bench/load_test.py --serve --sessions 20
  python bench/load_test.py --docker tire-fbs:proof --cpus 2 --sessions 5,10,20,30
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
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

DIGEST_JS = """() => {
  const doc = Bokeh.documents[0], shown = new Set();
  for (const root of doc.roots()) {
    shown.add(root);
    for (const m of root.references()) shown.add(m);
  }
  const out = [];
  for (const m of shown) {
    if (m.type !== 'ColumnDataSource') continue;
    const cols = m.data instanceof Map ? [...m.data.entries()] : Object.entries(m.data);
    let n = 0, s = 0;
    for (const [name, col] of cols) {
      if (col == null || col.length === undefined || typeof col === 'string') continue;
      n += col.length;
      for (let i = 0; i < col.length; i++) {
        const v = col[i];
        if (typeof v === 'number' && Number.isFinite(v)) s += v * Math.sqrt(i + 2) + v * v;
      }
    }
    out.push(n + ':' + s.toPrecision(10));
  }
  return out.sort().join('|');
}"""

READY_JS = """() => window.Bokeh && Bokeh.documents.length > 0 &&
  [...Bokeh.documents[0].all_models].some(m => m.type === 'ColumnDataSource' &&
    Object.values(m.data instanceof Map ? Object.fromEntries(m.data) : m.data)
      .some(c => c && c.length > 0)) &&
  [...Bokeh.documents[0].all_models].some(m => m.type.endsWith('Slider'))"""

#: The slider to move: ``#k`` is the k-th slider model (0-based, document order), else the
#: first one whose title contains ``title`` (any if empty).
SLIDER_JS = """(title) => {
  const all = [...Bokeh.documents[0].all_models].filter(m => m.type.endsWith('Slider'));
  if (title.startsWith('#')) return all[parseInt(title.slice(1))];
  return all.find(m => !title || String(m.title).includes(title));
}"""

SLIDER_INFO_JS = f"""(title) => {{
  const m = ({SLIDER_JS})(title);
  return m ? {{title: m.title, value: m.value, start: m.start, end: m.end, step: m.step}} : null;
}}"""

#: Set the slider value and time the plot-data changes; returns [first, settled] in ms.
CHANGE_JS = f"""async ([title, value, timeout, quiet]) => {{
  const digest = {DIGEST_JS};
  const m = ({SLIDER_JS})(title);
  const before = digest();
  const t0 = performance.now();
  m.setv({{value: value, value_throttled: value}});
  let first = null, last = null, current = before;
  while (performance.now() - t0 < timeout) {{
    await new Promise(r => setTimeout(r, 25));
    const now = performance.now();
    const d = digest();
    if (d !== current) {{ current = d; last = now; if (first === null) first = now; }}
    if (last !== null && now - last > quiet) break;
  }}
  return first === null ? null : [first - t0, last - t0];
}}"""

#: True while the page reports a computation in progress (the scatter band's progress bar):
#: under load a band can take longer than any fixed quiet time.
BUSY_JS = """() => [...Bokeh.documents[0].all_models].some(
  m => m.css_classes && m.css_classes.includes('scatter-progress') && m.active === true)"""

SETTLE_JS = f"""async ([timeout, quiet]) => {{
  const digest = {DIGEST_JS};
  const busy = {BUSY_JS};
  const t0 = performance.now();
  let current = digest(), last = t0;
  while (performance.now() - t0 < timeout) {{
    await new Promise(r => setTimeout(r, 50));
    const d = digest();
    if (d !== current || busy()) {{ current = d; last = performance.now(); }}
    if (performance.now() - last > quiet) return current;
  }}
  return null;
}}"""


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
    context: object = None
    page: object = None


def chromium_args() -> dict:
    for path in ("/usr/bin/chromium", "/usr/bin/chromium-browser"):
        if os.path.exists(path):
            return {"executable_path": path,
                    "args": ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"]}
    return {}


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


async def open_page(browser, url: str, timeout_s: float):
    context = await browser.new_context(viewport={"width": 1400, "height": 1000})
    page = await context.new_page()
    return context, page


async def run_session(browser, url: str, index: int, changes: int, title: str,
                      timeout_s: float, start_delay: float) -> SessionResult:
    res = SessionResult(index)
    await asyncio.sleep(start_delay)
    context, page = await open_page(browser, url, timeout_s)
    res.context, res.page = context, page  # kept open for the isolation check
    page.on("pageerror", lambda exc: res.errors.append(
        f"page error: {exc}; stack: {' | '.join((exc.stack or '').splitlines()[:6])}"))
    ms = timeout_s * 1000
    try:
        t0 = time.monotonic()
        await page.goto(url, timeout=ms)
        await page.wait_for_function(READY_JS, timeout=ms, polling=100)
        res.load_s = time.monotonic() - t0
        if await page.evaluate(SETTLE_JS, [ms, 1000]) is None:
            res.errors.append("plot data never settled after load")
            return res
        info = await page.evaluate(SLIDER_INFO_JS, title)
        if info is None:
            res.errors.append(f"no slider with title containing {title!r}")
            return res
        for value in targets(slider_values(info), index, changes, info["value"]):
            lat = await page.evaluate(CHANGE_JS, [title, value, ms, 400])
            res.last_value = value
            if lat is None:
                res.errors.append(f"setting the slider to {value} changed no plot data")
                continue
            res.first_ms.append(lat[0])
            res.settled_ms.append(lat[1])
        res.final_value = (await page.evaluate(SLIDER_INFO_JS, title))["value"]
    except Exception as exc:  # a failed session is reported, the others go on
        res.errors.append(f"{type(exc).__name__}: {str(exc).splitlines()[0]}")
    return res


async def final_digest(res: SessionResult, timeout_s: float) -> None:
    """Plot data of a session once nothing changes for 3 s any more; closes the session."""
    try:
        if not res.errors:
            res.final_digest = await res.page.evaluate(SETTLE_JS, [timeout_s * 1000, 3000])
    finally:
        await res.context.close()


async def reference_page(browser, url: str, title: str, value: float, timeout_s: float):
    """A lone fresh session that sets the slider to ``value`` (left open for its digest)."""
    context, page = await open_page(browser, url, timeout_s)
    ms = timeout_s * 1000
    try:
        await page.goto(url, timeout=ms)
        await page.wait_for_function(READY_JS, timeout=ms, polling=100)
        await page.evaluate(SETTLE_JS, [ms, 1000])
        info = await page.evaluate(SLIDER_INFO_JS, title)
        if info["value"] != value:
            await page.evaluate(CHANGE_JS, [title, value, ms, 400])
    except Exception:
        await context.close()
        raise
    return context, page


async def page_digest(context, page, timeout_s: float) -> str | None:
    """Plot data of a page once nothing changes for 3 s any more; closes it."""
    try:
        return await page.evaluate(SETTLE_JS, [timeout_s * 1000, 3000])
    finally:
        await context.close()


def pct(values: list[float], q: float) -> float:
    s = sorted(values)
    if not s:
        return float("nan")
    return s[min(len(s) - 1, max(0, int(round(q / 100 * len(s) + 0.5)) - 1))]


def summary(values: list[float]) -> str:
    if not values:
        return "n/a"
    return (f"median {statistics.median(values):7.0f}  p95 {pct(values, 95):7.0f}  "
            f"max {max(values):7.0f}")


async def wait_server_idle(cpu_s, timeout_s: float, quiet_s: float = 3.0,
                           busy_share: float = 0.1) -> bool:
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


async def run_level(url: str, n: int, changes: int, title: str, timeout_s: float,
                    check_isolation: bool, cpu_s=None) -> dict:
    from playwright.async_api import async_playwright

    async with async_playwright() as p:
        browser = await p.chromium.launch(**chromium_args())
        try:
            t0 = time.monotonic()
            results = await asyncio.gather(*(
                run_session(browser, url, i, changes, title, timeout_s, 0.1 * i)
                for i in range(n)))
            wall = time.monotonic() - t0
            problems = [f"session {r.index}: {e}" for r in results for e in r.errors]
            for r in results:
                if not r.errors and r.final_value != r.last_value:
                    problems.append(f"session {r.index}: slider shows {r.final_value}, "
                                    f"but this session set {r.last_value} last")
            refs: dict = {}
            if check_isolation:
                values = sorted({r.last_value for r in results if not r.errors})
                ref_pages = await asyncio.gather(*(
                    reference_page(browser, url, title, v, timeout_s) for v in values))
            # under a backlog a page can be quiet for seconds with updates still queued on
            # the server: take every digest once the server itself is idle
            idle = await wait_server_idle(cpu_s, timeout_s)
            if check_isolation:
                digests = await asyncio.gather(*(
                    page_digest(c, pg, timeout_s) for c, pg in ref_pages))
                refs = dict(zip(values, digests, strict=True))
            await asyncio.gather(*(final_digest(r, timeout_s) for r in results))
            if check_isolation:
                for r in results:
                    if r.errors or r.final_digest is None:
                        continue
                    if r.final_digest != refs.get(r.last_value):
                        problems.append(
                            f"session {r.index}: plot data differ from a lone session's "
                            f"at slider value {r.last_value}"
                            + ("" if idle else " (server never idle before the check)"))
        finally:
            await browser.close()
    first = [x for r in results for x in r.first_ms]
    settled = [x for r in results for x in r.settled_ms]
    loads = [r.load_s * 1000 for r in results if r.load_s is not None]
    return {"sessions": n, "changes": len(first), "wall_s": wall, "load_ms": loads,
            "first_ms": first, "settled_ms": settled, "problems": problems,
            "distinct_final_states": len(refs)}


# ---- servers -------------------------------------------------------------------------------


def host_busy_s() -> float:
    """CPU seconds the whole host has been busy (all cores), from /proc/stat."""
    with open("/proc/stat") as f:
        fields = [int(x) for x in f.readline().split()[1:]]
    busy = sum(fields) - fields[3] - (fields[4] if len(fields) > 4 else 0)  # minus idle, iowait
    return busy / os.sysconf("SC_CLK_TCK")


def proc_tree_cpu_s(pid: int) -> float:
    """CPU seconds of a process and its live descendants (utime + stime, /proc)."""
    tick = os.sysconf("SC_CLK_TCK")
    children: dict[int, list[int]] = {}
    times: dict[int, float] = {}
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat") as f:
                st = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(st[1]), []).append(int(d))
        times[int(d)] = (int(st[11]) + int(st[12])) / tick
    total, todo = 0.0, [pid]
    while todo:
        p = todo.pop()
        total += times.get(p, 0.0)
        todo.extend(children.get(p, []))
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

    def __init__(self, threads: int):
        self.port = free_port()
        self.log = tempfile.NamedTemporaryFile("w+", suffix=".log", delete=False)
        env = {**os.environ, "FBS_PORT": str(self.port), "FBS_ADDRESS": "127.0.0.1",
               "FBS_NUM_THREADS": str(threads),
               "BOKEH_ALLOW_WS_ORIGIN": f"127.0.0.1:{self.port}"}
        self.proc = subprocess.Popen([sys.executable, str(ROOT / "docker" / "entrypoint.py")],
                                     env=env, stdout=self.log, stderr=subprocess.STDOUT)
        self.url = f"http://127.0.0.1:{self.port}/"
        wait_http(self.url + "liveness", 60, lambda: self.proc.poll() is None)

    def logs(self) -> str:
        self.log.seek(0)
        return self.log.read()

    def cpu_s(self) -> float | None:
        return proc_tree_cpu_s(self.proc.pid)

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

    def __init__(self, image: str, cpus: float, threads: int):
        self.port = free_port()
        self.cid = subprocess.run(
            ["docker", "run", "-d", "--cpus", str(cpus), "-p", f"127.0.0.1:{self.port}:5006",
             "-e", f"BOKEH_ALLOW_WS_ORIGIN=127.0.0.1:{self.port}",
             "-e", f"FBS_NUM_THREADS={threads}", image],
            check=True, capture_output=True, text=True).stdout.strip()
        self.url = f"http://127.0.0.1:{self.port}/"
        try:
            wait_http(self.url + "liveness", 120, self._running)
        except Exception:
            self.stop()
            raise

    def _running(self) -> bool:
        out = subprocess.run(["docker", "inspect", "-f", "{{.State.Running}}", self.cid],
                             capture_output=True, text=True).stdout.strip()
        return out == "true"

    def logs(self) -> str:
        return subprocess.run(["docker", "logs", self.cid], capture_output=True,
                              text=True).stdout

    def cpu_s(self) -> float | None:
        """CPU seconds of the container (cgroup v2 or v1 accounting), None if unknown."""
        for path, scale, key in (
                (f"/sys/fs/cgroup/system.slice/docker-{self.cid}.scope/cpu.stat", 1e-6,
                 "usage_usec"),
                (f"/sys/fs/cgroup/docker/{self.cid}/cpu.stat", 1e-6, "usage_usec"),
                (f"/sys/fs/cgroup/cpuacct/docker/{self.cid}/cpuacct.usage", 1e-9, None)):
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
    ap.add_argument("--sessions", default="20",
                    help="concurrent sessions; a comma list sweeps levels (20)")
    ap.add_argument("--changes", type=int, default=5, help="slider changes per session (5)")
    ap.add_argument("--slider", default="",
                    help="slider to move: part of its title, or #k for the k-th (first)")
    ap.add_argument("--target", type=float, default=1000.0, help="p95 target in ms (1000)")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds per wait (120)")
    ap.add_argument("--max-sessions", type=int, default=60, help="safety bound (60)")
    ap.add_argument("--no-isolation-check", action="store_true")
    ap.add_argument("--json", help="write the figures to this file")
    args = ap.parse_args(argv)
    levels = [int(x) for x in args.sessions.split(",")]
    if any(n < 1 or n > args.max_sessions for n in levels):
        ap.error(f"--sessions must be within 1..{args.max_sessions}")

    server = None
    if args.serve:
        server = LocalServer(args.threads)
    elif args.docker:
        server = DockerServer(args.docker, args.cpus, args.threads)
    url = server.url if server else args.url
    where = (f"docker {args.docker} --cpus {args.cpus}" if args.docker
             else "local panel serve" if args.serve else url)
    print(f"load test: {where}, {args.threads} threads, {os.cpu_count()} host cores, "
          f"load average {os.getloadavg()[0]:.1f}")
    rows, failed = [], False
    try:
        for n in levels:
            cpu0 = server.cpu_s() if server is not None else None
            host0, t0 = host_busy_s(), time.monotonic()
            row = asyncio.run(run_level(url, n, args.changes, args.slider, args.timeout,
                                        not args.no_isolation_check,
                                        server.cpu_s if server is not None else None))
            cpu1 = server.cpu_s() if server is not None else None
            row["host_cpu_s"] = host_busy_s() - host0
            row["accounted_s"] = time.monotonic() - t0  # incl. the isolation check
            row["server_cpu_s"] = None if cpu0 is None or cpu1 is None else cpu1 - cpu0
            rows.append(row)
            print(f"\n== {n} concurrent sessions, {row['changes']} changes, "
                  f"{row['wall_s']:.1f} s wall, {row['distinct_final_states']} distinct "
                  f"final states checked against lone sessions")
            print(f"   page load to plots (ms)  {summary(row['load_ms'])}")
            print(f"   change -> first update   {summary(row['first_ms'])}")
            print(f"   change -> settled        {summary(row['settled_ms'])}")
            if row["server_cpu_s"] is not None:
                # where the cores went: on one machine the browsers compete with the server
                print(f"   CPU over {row['accounted_s']:.0f} s (sessions and isolation check): "
                      f"server {row['server_cpu_s']:.1f} s, everything else on the host "
                      f"(browsers, this script) {row['host_cpu_s'] - row['server_cpu_s']:.1f} s, "
                      f"of {os.cpu_count() * row['accounted_s']:.0f} core-seconds")
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
                print("\n".join(lines[bad[0]:bad[0] + 25]))
    finally:
        if server is not None:
            server.stop()
    ok = [r["sessions"] for r in rows
          if not r["problems"] and r["first_ms"] and pct(r["first_ms"], 95) < args.target]
    print(f"\nlargest tested number of sessions with p95 first update < {args.target:.0f} ms: "
          f"{max(ok) if ok else 'none'}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
