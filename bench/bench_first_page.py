"""The first page, side by side: server start -> listening, page request -> first plot (issue 33).

Starts the server of each ``--tree`` (source checkouts of the project; default this one),
``--starts`` times, one server at a time and the trees alternated (each start sees the
machine to itself, as a user's start would; the trees take turns, so that a shared
machine's load falls on all alike), through ``docker/entrypoint.py`` as
``scripts/serve.sh`` does (``--panel``: plain ``panel serve app/main.py`` as
``bench_dashboard.py`` does); with Panel's ``--warm`` (the page run once before the port
opens) as the tree's own ``scripts/serve.sh`` passes it (``--warm serve-sh``, the default:
before issue 33 it passed ``--warm``), always (``yes``) or never (``no``). For each start
it prints:

- server start -> the port accepts a connection (a browser could connect);
- with ``--first proved``: server start -> the app proved (``/liveness`` answers 200:
  the server's own page of the app is built and loaded), and the first page requested only
  then (default ``--first listening``: requested as soon as the port accepts, while the
  server proves the app);
- then ``--samples`` fresh browser pages (chromium, playwright) one after the other, each
  requested until the coupled response's plot (``mobility.truncated``) holds data in the
  page, and closed again; the first of them is "the first page" of that start.

At the end, per tree, the medians over the starts (start -> listening, -> proved, first
page, later pages) and the ratios of the trees' medians.

``bench_dashboard.py`` prints a "page request -> plot" for its first page too, but its
trees' first pages are opened one after the other and each waits for its band, so the
second tree's figure there includes the first tree's page and band: use this benchmark to
compare first pages.

The server's CPU seconds from request to plot (all its threads, from ``/proc``) are printed
beside: less sensitive to the machine's load than the wall time. The load average
(``os.getloadavg``) is printed with every figure: on a shared machine only the ratios of
one run count.

Usage::

    .venv/bin/python bench/bench_first_page.py [--starts 3] [--samples 5] [--tree /tmp/old --tree .]
    .venv/bin/python bench/bench_first_page.py --first proved --tree /tmp/old --tree .
"""

from __future__ import annotations

import argparse
import os
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

import numpy as np
from playwright.sync_api import sync_playwright

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_dashboard import ARGS, CHROMIUM, JS_READY, free_port  # noqa: E402


def load() -> str:
    a, b, c = os.getloadavg()
    return f"load {a:.1f} {b:.1f} {c:.1f}"


def warmed(tree: Path, how: str) -> bool:
    """Whether the server of ``tree`` gets Panel's ``--warm`` (``how``: yes, no, serve-sh)."""
    if how == "serve-sh":
        script = (tree / "scripts" / "serve.sh").read_text()
        return "entrypoint.py --warm" in script
    return how == "yes"


def start(
    tree: Path, port: int, panel: bool, threads: int, warm: bool
) -> tuple[subprocess.Popen, dict]:
    """Start a server of ``tree`` on ``port``; returns the process and a dict the pump fills
    with the time of "Bokeh app running"."""
    extra = ["--warm"] if warm else []
    if panel:
        cmd = [sys.executable, "-m", "panel", "serve", "app/main.py", *extra]
        cmd += ["--port", str(port), "--address", "127.0.0.1", "--num-threads", str(threads)]
        env = {**os.environ}
    else:
        cmd = [sys.executable, "docker/entrypoint.py", *extra]
        env = {
            **os.environ,
            "FBS_APP": "app/main.py",
            "FBS_PORT": str(port),
            "FBS_ADDRESS": "127.0.0.1",
            "FBS_NUM_THREADS": str(threads),
        }
    env["PYTHONUNBUFFERED"] = "1"
    env["PYTHONPATH"] = os.pathsep.join([str(tree), env.get("PYTHONPATH", "")])
    proc = subprocess.Popen(
        cmd, cwd=tree, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    )
    marks: dict = {"log": []}

    def pump() -> None:
        assert proc.stdout is not None
        for line in proc.stdout:
            marks["log"].append(line)
            if "Bokeh app running" in line and "running" not in marks:
                marks["running"] = time.perf_counter()

    threading.Thread(target=pump, daemon=True).start()
    return proc, marks


def cpu_s(pid: int) -> float:
    """CPU seconds (user + system, all threads) the process used so far (Linux)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def proved(port: int) -> bool:
    """Whether the server's ``/liveness`` answers 200 for the app (its proof is done)."""
    try:
        with urllib.request.urlopen(
            f"http://127.0.0.1:{port}/liveness?endpoint=/main", timeout=2
        ) as r:
            return r.status == 200
    except OSError:
        return False


def listening(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(0.2)
        return s.connect_ex(("127.0.0.1", port)) == 0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tree", action="append", type=Path, help="a source checkout (repeat)")
    ap.add_argument("--samples", type=int, default=5, help="pages per start")
    ap.add_argument("--starts", type=int, default=3, help="server starts per tree")
    ap.add_argument("--threads", type=int, default=4)
    ap.add_argument("--panel", action="store_true", help="plain `panel serve`")
    ap.add_argument(
        "--warm",
        choices=["yes", "no", "serve-sh"],
        default="serve-sh",
        help="Panel's --warm before listening: as the tree's scripts/serve.sh starts it "
        "(default: the README's start command), always (yes) or never (no)",
    )
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per step")
    ap.add_argument(
        "--first",
        choices=["listening", "proved"],
        default="listening",
        help="request the first page once the port accepts (default) or once /liveness is 200",
    )
    args = ap.parse_args()
    trees = [t.resolve() for t in (args.tree or [ROOT])]
    names = [
        f"{t.name}#{i}" if [u.name for u in trees].count(t.name) > 1 else t.name
        for i, t in enumerate(trees)
    ]
    how = "panel serve" if args.panel else "docker/entrypoint.py"
    warm = [warmed(t, args.warm) for t in trees]
    print(f"cores {os.cpu_count()}; {how}; --num-threads {args.threads}; {load()}")
    for name, w in zip(names, warm, strict=True):
        print(f"[{name}] {'with' if w else 'without'} --warm")
    launch: dict = {"args": ARGS}
    if Path(CHROMIUM).exists():
        launch["executable_path"] = CHROMIUM
    figures: dict[str, dict[str, list[float]]] = {
        name: {"listening": [], "proved": [], "first": [], "later": [], "cpu": []} for name in names
    }
    with sync_playwright() as p:
        browser = p.chromium.launch(**launch)
        try:
            for r in range(args.starts):
                order = list(zip(names, trees, warm, strict=True))
                if r % 2:  # alternate which tree starts first
                    order.reverse()
                for name, tree, w in order:
                    one_start(browser, name, tree, w, args, figures[name])
        finally:
            browser.close()
    print("per tree (medians over the starts; 'later': the pages after each start's first):")
    for name in names:
        f = {k: np.asarray(v) for k, v in figures[name].items()}

        def med(a: np.ndarray) -> str:
            return f"{np.median(a):6.2f} s (max {a.max():5.2f})" if a.size else "     -"

        print(
            f"[{name}] start -> listening {med(f['listening'])}; proved {med(f['proved'])}; "
            f"first page {med(f['first'])}; later pages {med(f['later'])} (n={f['later'].size}); "
            f"server CPU per page {np.median(f['cpu']):5.2f} s"
        )
    if len(names) > 1:
        base = figures[names[0]]
        for name in names[1:]:
            print(
                f"ratio {name} / {names[0]} (medians): first page "
                f"{np.median(figures[name]['first']) / np.median(base['first']):.2f}, "
                f"start -> listening "
                f"{np.median(figures[name]['listening']) / np.median(base['listening']):.2f}"
            )


def one_start(browser, name: str, tree: Path, warm: bool, args, fig: dict) -> None:
    """Start the server of ``tree`` alone, note start -> listening (and -> proved), open
    ``args.samples`` pages one after the other, each until its first plot; stop it."""
    port = free_port()
    t0 = time.perf_counter()
    proc, marks = start(tree, port, args.panel, args.threads, warm)
    try:
        while not listening(port):  # polled every 50 ms
            if proc.poll() is not None or time.perf_counter() - t0 > args.timeout:
                print("".join(marks["log"][-30:]))
                raise RuntimeError(f"server of {name} did not listen")
            time.sleep(0.05)
        fig["listening"].append(time.perf_counter() - t0)
        print(f"[{name}] start -> listening      {fig['listening'][-1]:7.1f} s   ({load()})")
        if args.first == "proved" and not args.panel:
            while not proved(port):
                if proc.poll() is not None or time.perf_counter() - t0 > args.timeout:
                    print("".join(marks["log"][-30:]))
                    raise RuntimeError(f"server of {name} was not proved")
                time.sleep(0.05)
            fig["proved"].append(time.perf_counter() - t0)
            print(f"[{name}] start -> proved (/liveness 200) {fig['proved'][-1]:7.1f} s")
        for k in range(args.samples):
            page = browser.new_page(viewport={"width": 1600, "height": 1200})
            c = cpu_s(proc.pid)
            t = time.perf_counter()
            page.goto(
                f"http://127.0.0.1:{port}/main", timeout=args.timeout * 1e3, wait_until="commit"
            )
            page.wait_for_function(
                JS_READY, arg="mobility.truncated", timeout=args.timeout * 1e3, polling=20
            )
            dt = time.perf_counter() - t
            fig["first" if k == 0 else "later"].append(dt)
            fig["cpu"].append(cpu_s(proc.pid) - c)
            print(
                f"[{name}] page {k + 1}: request -> first plot {dt:6.2f} s, "
                f"server CPU {fig['cpu'][-1]:5.2f} s   ({load()})"
            )
            page.close()
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


if __name__ == "__main__":
    main()
