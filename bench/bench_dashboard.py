"""Browser-measured latency of the dashboard (issue 6), figures printed.

Starts ``panel serve app/main.py`` (as ``scripts/serve.sh`` does: ``--num-threads``,
``--warm``), opens it in chromium (playwright) and measures inside the page, with
``performance.now()``, the time from a control change to the updated plot data in the Bokeh
document (the named ColumnDataSource of the view):

- retained modes N, harmonic and response DOF: median and 95th percentile;
- the scatter band with R rounds (default 10,000): a new seed until the band's data change;
- server start: process launch to "app running", and to the first rendered plot;
- with ``--vehicle``: vehicle scope (issue 31), the page opened with ``?scope=vehicle``: a
  wheel toggled (front-left on/off), the track relation (in phase / anti-phase), the
  response point, N and the harmonic, each until the car's response view changes
  (``mobility.truncated``), and a wheel toggle until the per-wheel view and the car's
  truncation map change (``wheels.lines``, ``truncation.map``); the band at the car's
  default rounds (``--vehicle-rounds``);
- with ``--analysis``: the Analysis card's views (issue 18), each in a fresh page opened on
  its tab (``?atab=...``): N, harmonic and DOF changes until the view's own source changes
  (phase: ``phase.b``; contributions: ``contributions.lines``; across speed:
  ``speedmap.image``; compare, one pin made first: ``compare.diff1``), and the time to
  open each tab in a loaded page. ``--only-analysis`` skips the other measurements.

Usage::

    .venv/bin/python bench/bench_dashboard.py [--rounds 10000] [--samples 20]
    .venv/bin/python bench/bench_dashboard.py --tree /path/to/old/checkout --tree .
    .venv/bin/python bench/bench_dashboard.py --only-analysis --samples 14
    .venv/bin/python bench/bench_dashboard.py --only-analysis --tabs phase,compare
    .venv/bin/python bench/bench_dashboard.py --only-vehicle --samples 12

With several ``--tree`` (source checkouts of the project), one server per tree runs at the
same time and the samples alternate between them: a before/after comparison under the same
machine load. The trees' first pages are opened one after the other, each after the
previous tree's band, so "server start -> ..." of a later tree includes the earlier trees'
first pages (its "page request -> plot" does not: it is timed from its own request; until
issue 33 it was timed from the server's start line and so included them too). First pages
side by side, alternated: ``bench/bench_first_page.py``.
"""

from __future__ import annotations

import argparse
import os
import queue
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
from playwright.sync_api import sync_playwright

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = "/usr/bin/chromium"
ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
    "--disable-sync",
]

# Set a widget model's value (or click a radio button) and resolve with the milliseconds
# until the named source's data differ (polled every 2 ms).
JS_MEASURE = """
async ([kind, cls, value, name, timeout]) => {
  const models = () => [...Bokeh.documents[0].all_models];
  const src = () => models().filter(m => m.name === name && m.type === 'ColumnDataSource')[0];
  const fp = () => { const d = src().data; let s = '';
    for (const [k, v] of Object.entries(d)) { const a = k === 'image' ? v[0] : v;
      let t = 0, i = 0; for (const x of a) { if (Number.isFinite(x)) t += x * (1 + i % 7); i++; }
      s += k + i + ':' + t + ';'; } return s; };
  const before = fp();
  const t0 = performance.now();
  if (kind === 'value') {
    const w = models().filter(m => m.css_classes && m.css_classes.includes(cls)
                              && 'value' in m && m.type === 'Slider')[0];
    w.value = value;
  } else if (kind === 'select') {
    const w = models().filter(m => m.css_classes && m.css_classes.includes(cls)
                              && 'value' in m && 'options' in m)[0];
    w.value = value;
  } else {
    const w = models().filter(m => m.css_classes && m.css_classes.includes(cls)
                              && 'active' in m)[0];
    w.active = value;
  }
  return await new Promise((resolve, reject) => {
    const check = () => {
      const dt = performance.now() - t0;
      if (fp() !== before) resolve(dt);
      else if (dt > timeout) reject(new Error('no change of ' + name));
      else setTimeout(check, 2);
    };
    check();
  });
}
"""

# A new seed; resolve with the milliseconds until the band's data change.
JS_BAND = """
async ([seed]) => {
  const ms = [...Bokeh.documents[0].all_models];
  const w = ms.filter(m => m.css_classes && m.css_classes.includes('ctl-noise-seed')
                           && 'value' in m)[0];
  const src = ms.filter(m => m.name === 'scatter.minmax')[0];
  const before = src.data.upper[3];
  // a typed number's field holds text (issue 29), an older numeric field a number
  const t0 = performance.now(); w.value = typeof w.value === 'string' ? String(seed) : seed;
  return await new Promise(r => { const c = () => {
    if (src.data.upper[3] !== before) r(performance.now() - t0);
    else setTimeout(c, 5); }; c(); });
}
"""

JS_READY = """(name) => { if (!(window.Bokeh && Bokeh.documents.length)) return false;
  const m = [...Bokeh.documents[0].all_models].filter(
      m => m.name === name && m.type === 'ColumnDataSource')[0];
  if (!m) return false; const k = Object.keys(m.data)[0];
  return k !== undefined && m.data[k].length > 0; }"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server(port: int, threads: int, warm: bool, tree: Path = ROOT):
    cmd = [
        sys.executable,
        "-m",
        "panel",
        "serve",
        "app/main.py",
        "--port",
        str(port),
        "--address",
        "127.0.0.1",
        "--num-threads",
        str(threads),
    ]
    if warm:
        cmd.append("--warm")
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    if tree != ROOT:  # that tree's app and fbs_core before the installed ones
        env["PYTHONPATH"] = os.pathsep.join([str(tree), env.get("PYTHONPATH", "")])
    proc = subprocess.Popen(
        cmd,
        cwd=tree,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
    )
    ready: queue.Queue = queue.Queue()
    proc.log = []  # the server's output, printed if the benchmark fails

    def pump():
        for line in proc.stdout:
            proc.log.append(line)
            if "Bokeh app running at" in line:
                ready.put(time.perf_counter())
        ready.put(None)

    threading.Thread(target=pump, daemon=True).start()
    return proc, ready


def stats(ms: list[float]) -> str:
    a = np.asarray(ms)
    return (
        f"median {np.median(a):7.0f} ms   p95 {np.percentile(a, 95):7.0f} ms   "
        f"min {a.min():6.0f}   max {a.max():6.0f}   (n={a.size})"
    )


def wait_band_idle(page, timeout=300_000):
    """Wait until no scatter band is being computed (its progress bar is hidden)."""
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].filter(m => m.css_classes && "
        "m.css_classes.includes('scatter-progress')).every(m => m.active === false)",
        timeout=timeout,
        polling=50,
    )


JS_PIN = """() => { const ms = [...Bokeh.documents[0].all_models];
  const box = ms.filter(m => m.css_classes && m.css_classes.includes('ctl-analysis-pin_name')
                        && 'value' in m)[0];
  box.value = 'bench'; }"""

JS_TAB_OPEN = """async ([tab, name, timeout]) => {
  const t0 = performance.now();
  const ms = () => [...Bokeh.documents[0].all_models];
  const tabs = ms().filter(m => m.css_classes && m.css_classes.includes('analysis-tabs'))[0];
  const names = tabs.tabs.map(t => t.title);
  tabs.active = names.indexOf(tab);
  return await new Promise((resolve, reject) => { const c = () => {
    const s = ms().filter(m => m.name === name && m.type === 'ColumnDataSource')[0];
    const dt = performance.now() - t0;
    if (s) { const k = Object.keys(s.data)[0];
             const v = k === 'image' ? s.data.image[0] : s.data[k];
             if (v && v.length > 1) { resolve(dt); return; } }
    if (dt > timeout) reject(new Error('no data in ' + name)); else setTimeout(c, 5); }; c(); });
}"""


def analysis_bench(servers, measure, modes, n, rounds, only=None):
    """Latency of the Analysis card's views (issue 18), printed like the others
    (``only``: the tabs to measure, default all)."""
    harmonics = [int(h) for h in np.resize([2, 3, 4, 5, 6, 7, 1], n)]
    dofs = [int(d) for d in np.resize([0, 1, 3, 4, 5, 2], n)]
    views = {
        "phase": "phase.b",
        "contributions": "contributions.lines",
        "speed": "speedmap.image",
        "compare": "compare.diff1",
    }
    for tab, name in views.items():
        if only and tab not in only:
            continue
        for _tree, page, _proc, port, *_ in servers:
            page.goto(
                f"http://127.0.0.1:{port}/main?rounds={rounds}&atab={tab}",
                timeout=300_000,
                wait_until="commit",
            )
            page.wait_for_function(JS_READY, arg="mobility.truncated", timeout=300_000)
            if tab == "compare":  # one pin, then the difference to it is what changes
                page.wait_for_function(JS_READY, arg="compare.curve0", timeout=300_000)
                page.evaluate(JS_PIN)
                page.locator(".ctl-analysis-pin button").first.click()
                page.wait_for_function(JS_READY, arg="compare.curve1", timeout=300_000)
            page.wait_for_function(JS_READY, arg=name, timeout=300_000)
            wait_band_idle(page)
        # the difference to a pin of another harmonic is empty (another grid): on a change
        # of harmonic (and after it, of DOF) the compare tab's current curve is what changes
        hname = "compare.curve0" if tab == "compare" else name
        res = {
            f"{tab}: modes N ({name})": measure("value", "ctl-case-n_modes", modes, name),
            f"{tab}: harmonic ({hname})": measure("value", "ctl-case-harmonic", harmonics, hname),
        }
        res[f"{tab}: response DOF ({hname})"] = measure("active", "ctl-case-dof", dofs, hname)
        for k, v in res.items():
            for tree, ms in v.items():
                print(f"[{tree.name}] {k:46s} {stats(ms)}")
    if only:
        return
    # opening a tab in a loaded page (the card open on another tab, caches warm)
    order = [
        ("Phase and peaks", "phase.b"),
        ("Contributions", "contributions.lines"),
        ("Across speed", "speedmap.image"),
        ("Compare", "compare.curve0"),
    ]
    for tree, page, _proc, port, *_ in servers:
        page.goto(
            f"http://127.0.0.1:{port}/main?rounds={rounds}&atab=compare",
            timeout=300_000,
            wait_until="commit",
        )
        page.wait_for_function(JS_READY, arg="compare.curve0", timeout=300_000)
        wait_band_idle(page)
        for title, name in order:
            ms = page.evaluate(JS_TAB_OPEN, [title, name, 120_000])
            print(f"[{tree.name}] open tab {title!r:34s} {ms:7.0f} ms (first view of the tab)")


def vehicle_bench(servers, measure, n, rounds):
    """Page changes in vehicle scope (issue 31), printed like the others."""
    for _tree, page, _proc, port, *_ in servers:
        page.goto(
            f"http://127.0.0.1:{port}/main?scope=vehicle&rounds={rounds}",
            timeout=300_000,
            wait_until="commit",
        )
        page.wait_for_function(JS_READY, arg="wheels.lines", timeout=600_000)
        page.wait_for_function(JS_READY, arg="truncation.map", timeout=600_000)
        wait_band_idle(page, timeout=900_000)
    wheels = [[1, 2, 3] if k % 2 == 0 else [0, 1, 2, 3] for k in range(n)]  # FL off / on
    points = [str(p) for p in np.resize(["seat_fl", "bushing_rr", "strut_fl", "bushing_rl"], n)]
    steps = {
        "vehicle: wheel FL (mobility.truncated)": lambda: measure(
            "active", "ctl-case-wheels", wheels, "mobility.truncated"
        ),
        "vehicle: wheel FL (wheels.lines)": lambda: measure(
            "active", "ctl-case-wheels", wheels, "wheels.lines"
        ),
        "vehicle: wheel FL (truncation.map)": lambda: measure(
            "active", "ctl-case-wheels", wheels, "truncation.map"
        ),
        "vehicle: tracks (mobility.truncated)": lambda: measure(
            "active", "ctl-case-tracks", [k % 2 for k in range(1, n + 1)], "mobility.truncated"
        ),
        "vehicle: point (mobility.truncated)": lambda: measure(
            "select", "ctl-case-point", points, "mobility.truncated"
        ),
        "vehicle: modes N (mobility.truncated)": lambda: measure(
            "value",
            "ctl-case-n_modes",
            [10 * int(i) for i in np.resize(np.arange(2, 21), n)],
            "mobility.truncated",
        ),
        "vehicle: harmonic (mobility.truncated)": lambda: measure(
            "value",
            "ctl-case-harmonic",
            [int(h) for h in np.resize([2, 3, 4, 5, 6, 7, 1], n)],
            "mobility.truncated",
        ),
    }
    for k, step in steps.items():  # printed as measured
        for tree, ms in step().items():
            print(f"[{tree.name}] {k:46s} {stats(ms)}  (load {os.getloadavg()[0]:.1f})", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=10_000)
    ap.add_argument("--samples", type=int, default=20)
    ap.add_argument("--threads", type=int, default=4)
    ap.add_argument("--no-warm", action="store_true")
    ap.add_argument("--analysis", action="store_true", help="also the Analysis card's views")
    ap.add_argument("--only-analysis", action="store_true", help="only the Analysis card")
    ap.add_argument("--vehicle", action="store_true", help="also vehicle scope (issue 31)")
    ap.add_argument("--only-vehicle", action="store_true", help="only vehicle scope")
    ap.add_argument(
        "--vehicle-rounds",
        type=int,
        default=1_000,
        help="rounds of the car's band (vehicle scope's default: 1,000)",
    )
    ap.add_argument(
        "--tabs",
        default="",
        help="with --analysis: these tabs only, comma-separated (phase,contributions,speed,"
        "compare; no tab-opening figures)",
    )
    ap.add_argument(
        "--tree",
        action="append",
        type=Path,
        help="a source checkout to serve (repeat to compare side by side); default this one",
    )
    args = ap.parse_args()
    trees = [t.resolve() for t in (args.tree or [ROOT])]

    launch = {"args": ARGS}
    if Path(CHROMIUM).exists():
        launch["executable_path"] = CHROMIUM
    print(
        f"cores: {os.cpu_count()}, load average: {os.getloadavg()[0]:.1f}; "
        f"rounds R = {args.rounds:,}; --num-threads {args.threads}"
        f"{'' if args.no_warm else ' --warm'}; trees: {', '.join(map(str, trees))}"
    )
    with sync_playwright() as p:
        browser = p.chromium.launch(**launch)
        servers = []
        try:
            for tree in trees:
                page = browser.new_page(viewport={"width": 1600, "height": 1200})
                port = free_port()
                t0 = time.perf_counter()
                proc, ready = start_server(port, args.threads, not args.no_warm, tree)
                servers.append((tree, page, proc, port, ready, t0))
            for tree, page, _proc, port, ready, t0 in servers:
                t_ready = ready.get(timeout=900)
                if t_ready is None:
                    raise RuntimeError(f"server of {tree} did not start")
                t_req = time.perf_counter()
                page.goto(
                    f"http://127.0.0.1:{port}/main?rounds={args.rounds}",
                    timeout=300_000,
                    wait_until="commit",
                )
                page.wait_for_function(JS_READY, arg="mobility.truncated", timeout=300_000)
                t_plot = time.perf_counter()
                page.wait_for_function(JS_READY, arg="scatter.minmax", timeout=600_000)
                t_band = time.perf_counter()
                print(f"[{tree.name}] server start -> app running:          {t_ready - t0:6.1f} s")
                print(
                    f"[{tree.name}] server start -> first rendered plot:  {t_plot - t0:6.1f} s "
                    f"(page request -> plot {t_plot - t_req:.1f} s)"
                )
                print(f"[{tree.name}] server start -> scatter band shown:   {t_band - t0:6.1f} s")
                wait_band_idle(page)

            def measure(kind, cls, values, name):
                out = {tree: [] for tree, *_ in servers}
                for v in values:  # alternate: both trees see the same load
                    for tree, page, *_ in servers:
                        out[tree].append(page.evaluate(JS_MEASURE, [kind, cls, v, name, 120_000]))
                        wait_band_idle(page)  # the next sample starts from a settled page
                return out

            n = args.samples
            modes = [10 * int(i) for i in np.resize(np.arange(2, 21), n)]  # N = 20 ... 200
            if args.analysis or args.only_analysis:
                only = {t.strip() for t in args.tabs.split(",") if t.strip()}
                analysis_bench(servers, measure, modes, n, args.rounds, only)
            if args.vehicle or args.only_vehicle:
                vehicle_bench(servers, measure, n, args.vehicle_rounds)
            if args.only_analysis or args.only_vehicle:
                return
            res = {
                "modes N (mobility.truncated)": measure(
                    "value", "ctl-case-n_modes", modes, "mobility.truncated"
                ),
                "harmonic (mobility.truncated)": measure(
                    "value",
                    "ctl-case-harmonic",
                    [int(h) for h in np.resize([2, 3, 4, 5, 6, 7, 1], n)],
                    "mobility.truncated",
                ),
                "response DOF (mobility.truncated)": measure(
                    "active",
                    "ctl-case-dof",
                    [int(d) for d in np.resize([0, 1, 3, 4, 5, 2], n)],
                    "mobility.truncated",
                ),
            }
            for k, v in res.items():
                for tree, ms in v.items():
                    print(f"[{tree.name}] {k:36s} {stats(ms)}")
            # scatter band: a new seed forces a new band of R rounds; at the default
            # harmonic 1 (78 lines) and at harmonic 7 (633 lines, the largest)
            for h in (1, 7):
                band = {tree: [] for tree, *_ in servers}
                for _, page, *_ in servers:
                    page.evaluate(
                        JS_MEASURE, ["value", "ctl-case-harmonic", h, "mobility.truncated", 120_000]
                    )
                for seed in range(100 * h + 1, 100 * h + 6):  # never computed before
                    for tree, page, *_ in servers:
                        # the band of the previous change may start a little later: let it
                        # start and finish, so that its arrival is not taken for this one's
                        page.wait_for_timeout(300)
                        wait_band_idle(page)
                        band[tree].append(page.evaluate(JS_BAND, [seed]))
                label = f"scatter band R={args.rounds:,}, harmonic {h}"
                for tree, ms in band.items():
                    print(f"[{tree.name}] {label:36s} {stats(ms)}")
        except Exception:
            for tree, _, proc, *_ in servers:
                print(
                    f"[{tree}] server log (last lines):\n" + "".join(proc.log[-40:]),
                    file=sys.stderr,
                )
            raise
        finally:
            for _, _, proc, *_ in servers:
                proc.terminate()
                try:
                    proc.wait(timeout=60)
                except subprocess.TimeoutExpired:
                    proc.kill()
            browser.close()
    print(f"load average at the end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
