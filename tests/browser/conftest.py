"""Real-browser harness: `panel serve app/main.py` in a subprocess, chromium via playwright.

Chromium: Debian's /usr/bin/chromium when present (playwright cannot download its own browser
on the CI machines), else the one `playwright install chromium` put in its cache.
"""

from __future__ import annotations

import os
import queue
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from playwright.sync_api import TimeoutError as PlaywrightTimeoutError

ROOT = Path(__file__).resolve().parents[2]
SYSTEM_CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
    "--disable-sync",
]
#: Script served; overridable for debugging the harness itself.
ARTIFACTS = Path(__file__).parent / "artifacts"
APP_SCRIPT = os.environ.get("FBS_DASHBOARD_SCRIPT", str(ROOT / "app" / "main.py"))
#: The checkout the server runs from (its working directory, first on its path): another
#: commit's tree shows that a test fails there (the tests themselves run from this one).
SERVER_ROOT = Path(os.environ.get("FBS_DASHBOARD_ROOT", str(ROOT)))
#: Names of the ColumnDataSources that every page shows (set by the views' hooks).
SOURCES = [
    "mobility.reference",
    "mobility.truncated",
    "truncation.map",
    "scatter.minmax",
    "scatter.percentile",
    "scatter.reference",
    "scatter.round",
    "eigen.f_20",
    "eigen.f_80",
    "eigen.f_120",
]


def chromium_launch_args() -> dict:
    """Launch arguments for playwright's chromium (system browser first)."""
    args = {"args": list(CHROMIUM_ARGS)}
    if Path(SYSTEM_CHROMIUM).exists():
        args["executable_path"] = SYSTEM_CHROMIUM
    return args


@pytest.fixture(scope="session")
def browser_type_launch_args(browser_type_launch_args):
    return {**browser_type_launch_args, **chromium_launch_args()}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class DashboardServer:
    """`panel serve` of the dashboard in a subprocess; ready when it logs its URL."""

    def __init__(self, script: str = APP_SCRIPT, num_threads: int = 2, timeout: float = 120):
        self.port = free_port()
        name = Path(script).stem
        self.url = f"http://127.0.0.1:{self.port}/{name}"
        cmd = [
            sys.executable,
            "-m",
            "panel",
            "serve",
            script,
            "--port",
            str(self.port),
            "--address",
            "127.0.0.1",
            "--num-threads",
            str(num_threads),
            "--allow-websocket-origin",
            f"127.0.0.1:{self.port}",
            # as scripts/serve.sh and the image: uploads up to 150 MB fit one message
            "--websocket-max-message-size",
            str(200 * 1024 * 1024),
        ]
        self.proc = subprocess.Popen(
            cmd,
            cwd=SERVER_ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            # bands at the server's own priority: the deployment's nice +10 orders the
            # server's threads, but against the busy processes of a loaded test machine a
            # band (and every first page, which waits for one) took minutes
            env={**os.environ, "PYTHONUNBUFFERED": "1", "FBS_BAND_NICE": "0"},
        )
        self.log: list[str] = []
        ready: queue.Queue = queue.Queue()

        def pump():
            for line in self.proc.stdout:
                self.log.append(line)
                if "Bokeh app running at" in line:
                    ready.put(True)
            ready.put(False)

        threading.Thread(target=pump, daemon=True).start()
        try:
            ok = ready.get(timeout=timeout)
        except queue.Empty:
            ok = False
        if not ok:
            self.stop()
            raise RuntimeError("panel serve did not start:\n" + "".join(self.log[-40:]))

    def errors(self) -> list[str]:
        """Server log lines that report an exception."""
        # a failed session callback is logged by Panel as a warning, not an error
        return [
            ln
            for ln in self.log
            if "Traceback" in ln or "ERROR" in ln or "failed with following error" in ln
        ]

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()


@pytest.fixture(scope="session")
def dashboard():
    server = DashboardServer()
    yield server
    server.stop()
    # the whole log, for a failure seen only in the server (an error in a callback)
    ARTIFACTS.mkdir(exist_ok=True)
    (ARTIFACTS / "dashboard_server.log").write_text("".join(server.log))


# -- helpers reading the Bokeh document ----------------------------------------------------
JS_SOURCE = """
(name) => {
  const doc = Bokeh.documents[0];
  const ms = [...doc.all_models].filter(
      m => m.name === name && m.type === 'ColumnDataSource');
  if (ms.length !== 1) return null;
  const out = {};
  for (const [k, v] of Object.entries(ms[0].data)) {
    if (k === 'image') out[k] = Array.from(v[0]);
    else out[k] = Array.from(v, x => (typeof x === 'number' ? x : Number(x)));
  }
  return out;
}
"""

JS_FINGERPRINT = """
(name) => {
  const doc = Bokeh.documents[0];
  const ms = [...doc.all_models].filter(
      m => m.name === name && m.type === 'ColumnDataSource');
  if (ms.length !== 1) return null;
  let s = '';
  for (const [k, v] of Object.entries(ms[0].data)) {
    const a = k === 'image' ? v[0] : v;
    let t = 0, n = 0;
    for (const x of a) { if (Number.isFinite(x)) { t += x * (1 + (n % 7)); } n++; }
    s += k + ':' + n + ':' + t.toPrecision(12) + ';';
  }
  return s;
}
"""


def source(page, name: str) -> dict | None:
    """The data of the named ColumnDataSource as lists (None if absent or ambiguous)."""
    return page.evaluate(JS_SOURCE, name)


def fingerprint(page, name: str) -> str | None:
    """A short summary of a source's data that changes when the data change."""
    return page.evaluate(JS_FINGERPRINT, name)


def open_dashboard(page, url: str, timeout=180_000):
    """Navigate and wait until every view holds data (the first page of a fresh server also
    loads the reference models and builds the truncation maps: generous timeout)."""
    page.goto(url, timeout=timeout, wait_until="commit")
    wait_loaded(page, timeout=timeout)


JS_SOURCES_SEEN = """(names) => Object.fromEntries(names.map(n => [n,
    [...Bokeh.documents[0].all_models].filter(m => m.name === n && m.type === 'ColumnDataSource')
      .map(m => { const k = Object.keys(m.data)[0];
                  return k === undefined ? -1 : m.data[k].length; })
  ]))"""


def wait_loaded(page, names=SOURCES, timeout=90_000):
    """Wait until the Bokeh document exists and every named source holds data.

    On a timeout the error says what the page held: per name, the length of each source
    of that name, and the page's query."""
    page.wait_for_function("() => window.Bokeh && Bokeh.documents.length > 0", timeout=timeout)
    try:
        page.wait_for_function(
            """(names) => names.every(n => {
                 const ms = [...Bokeh.documents[0].all_models].filter(
                     m => m.name === n && m.type === 'ColumnDataSource');
                 if (ms.length !== 1) return false;
                 const d = ms[0].data; const k = Object.keys(d)[0];
                 return k !== undefined && d[k].length > 0;
               })""",
            arg=list(names),
            timeout=timeout,
        )
    except PlaywrightTimeoutError:
        seen = page.evaluate(JS_SOURCES_SEEN, list(names))
        query = page.evaluate("() => window.location.search")
        ARTIFACTS.mkdir(exist_ok=True)
        shot_path = ARTIFACTS / "wait_loaded_timeout.png"
        page.screenshot(path=str(shot_path))
        raise AssertionError(
            f"sources not loaded in {timeout / 1000:g} s: {seen} (lengths of the sources of "
            f"each name; the page's query {query}; screenshot {shot_path})"
        ) from None


def wait_changed(page, name: str, before: str, timeout=30_000):
    """Wait until the fingerprint of a source differs from ``before``."""
    page.wait_for_function(
        f"([name, before]) => ({JS_FINGERPRINT})(name) !== before",
        arg=[name, before],
        timeout=timeout,
    )


def wait_band_idle(page, timeout=120_000):
    """Wait until no scatter band is being computed (its progress bar is hidden)."""
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].filter(m => m.css_classes && "
        "m.css_classes.includes('scatter-progress')).every(m => m.active === false)",
        timeout=timeout,
        polling=50,
    )


def set_model_value(page, css_class: str, value, model_type: str | None = None):
    """Set ``value`` of the widget model carrying ``css_class`` (as a user's drag would)."""
    page.evaluate(
        """([cls, value, type]) => {
             const ms = [...Bokeh.documents[0].all_models].filter(
                 m => m.css_classes && m.css_classes.includes(cls) && 'value' in m
                      && (type === null || m.type === type));
             if (ms.length !== 1) throw new Error(`${ms.length} widget models for ${cls}`);
             ms[0].value = value;
           }""",
        [css_class, value, model_type],
    )


def model_value(page, css_class: str, model_type: str | None = None):
    return page.evaluate(
        """([cls, type]) => [...Bokeh.documents[0].all_models].filter(
             m => m.css_classes && m.css_classes.includes(cls) && 'value' in m
                  && (type === null || m.type === type))[0].value""",
        [css_class, model_type],
    )


JS_TABLE = """
(cls) => {
  const ms = [...Bokeh.documents[0].all_models].filter(
      m => m.css_classes && m.css_classes.includes(cls) && m.source);
  if (ms.length !== 1) return null;
  const out = {};
  for (const [k, v] of Object.entries(ms[0].source.data)) out[k] = Array.from(v, String);
  return JSON.stringify(out);
}
"""


def table_json(page, css_class: str) -> str | None:
    """The data of the table widget carrying ``css_class`` as a JSON string."""
    return page.evaluate(JS_TABLE, css_class)


def color_high(page) -> float:
    """Upper colour limit of the (only) colour mapper on the page: the error map's cap."""
    return page.evaluate(
        """() => [...Bokeh.documents[0].all_models].filter(
             m => m.type === 'LinearColorMapper').map(m => m.high)[0]"""
    )


@pytest.fixture(scope="module")
def shared_page(browser, dashboard):
    """One page for a sequence of control changes (a page load costs seconds)."""
    context = browser.new_context(viewport={"width": 1600, "height": 1200}, accept_downloads=True)
    page = context.new_page()
    page.errors = []
    page.on("console", lambda m: m.type == "error" and page.errors.append(m.text))
    page.on("pageerror", lambda e: page.errors.append(str(e)))
    open_dashboard(page, dashboard.url + "?rounds=1000")
    yield page
    context.close()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """A failed browser test reports the server's log: a timeout in the page is often
    explained there (an exception in a callback, a computation that never ended)."""
    outcome = yield
    report = outcome.get_result()
    server = item.funcargs.get("dashboard") if hasattr(item, "funcargs") else None
    if report.failed and isinstance(server, DashboardServer):
        report.sections.append(("dashboard server log (last 80 lines)", "".join(server.log[-80:])))
        # every traceback whole (the last lines alone cut off where it began)
        starts = [i for i, ln in enumerate(server.log) if "Traceback" in ln]
        if starts:
            whole = "".join("".join(server.log[i : i + 60]) for i in starts[-4:])
            report.sections.append(("dashboard server tracebacks (last 4)", whole))
