"""``panel serve`` of the dashboard, hardened for deployment (run by ``docker/entrypoint.py``).

The container's entrypoint validates the settings and then runs :func:`serve` in the server
process (PID 1 in the container). It is Panel's own ``panel serve`` command, with the
changes that ``panel serve`` offers no option for:

Secrets stay off the command line
    The cookie secret and the basic-auth users reach this process through a private,
    already unlinked file descriptor (see ``docker/entrypoint.py``) and are set in Panel's
    ``config`` here: neither ``ps``/``docker top`` (the command line) nor
    ``/proc/<pid>/environ`` of the server shows them, and child processes (the file-parser
    sandbox) do not inherit them.
A cheap health check
    ``/liveness`` answers from memory, without login: ``{"/liveness": true}``, and with
    ``?endpoint=/main`` whether that app built a page (503 ``{"/main": false}`` while the
    proof still runs). The app is proved *once*, right after the port is open, on a thread
    of its own: one page is built, loaded as a browser would load it (Bokeh's "document
    ready" event: the page's on-load callbacks run, e.g. the part of the dashboard built
    after the first screen) and cleaned up, which also warms the server (reference models
    loaded, kernels compiled, the first page's results cached); a script or an on-load
    callback that fails stops the server with the error (the container exits; a restart
    policy retries).
    The port opens within seconds of the start (23.6 s when a warm-up and the
    proof ran before listening); a page requested meanwhile is served, computing what it
    needs beside the proof. No request, authenticated or not, makes the health check build
    a page (Panel's own ``--liveness`` built one on the event loop for every request).
Throttled logins, revocable cookies
    Wrong basic-auth logins are logged and slowed, then refused, per (client address, user
    name); a login cookie stops working on logout, when its user is removed or the
    password changed (``docker/fbs_auth.py``).
Only the app's own routes are open to code paths of the request
    Panel's component-resource route (``/components/<module>/...``) imported the module the
    URL named before any check, without login (``venv.__main__`` ended the process).
    Here it is behind the login and serves only modules of Panel that are already loaded
    (:func:`allowed_component_module`), so a URL never imports anything. An
    exception that escapes any request handler or callback (even ``SystemExit``) is logged
    and the server goes on (:class:`Supervised`).
Small HTTP bodies, large websocket messages
    Every HTTP request body is limited to :data:`HTTP_MAX_BODY_BYTES` (the login form is the
    only body the app takes; uploads travel over the websocket), so no request can make the
    event loop read and parse megabytes; the read buffer of a connection is
    as large as the largest websocket message, so a file upload up to that size reaches the
    app and gets its refusal instead of a closed connection. A larger
    websocket message is refused by the size its frame declares, before any of it is read,
    and a Bokeh message whose frames (content and buffers) add up to more is refused as
    its frames arrive; either closes that websocket with a log line naming the client
    (:func:`bound_websocket_messages`: read and decoded, a 147 MB message takes the
    server from 0.98 to 2.2 GB).
Connections bounded
    A request's headers and body must arrive within deadlines, and open connections are
    capped per client and in all; a connection beyond a cap gets a 503 and is closed, and
    ``accept()`` out of file descriptors pauses accepting instead of spinning, each logged
    once per interval (:mod:`conn_limits`: unbounded, 3,500 connections that never finish
    their headers stay open for ever and slow ``/liveness`` to 4.6-6 s). Page builds
    never used (page requests without their websocket) draw on budgets of event-loop time
    per user and in all (:mod:`page_limits`).
Prompt shutdown
    On SIGTERM or SIGINT the server stops listening and exits within seconds, whatever
    computations are running or queued: queued work is cancelled, worker threads are not
    waited for (Python would otherwise finish every queued scatter band first: 36-39 s
    after heavy use, longer than ``docker stop`` waits), and child processes are
    terminated. A watchdog ends the process if the orderly part hangs.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import os
import re
import signal
import sys
import threading
import time

from conn_limits import (
    BODY_TIMEOUT_S,
    HEADER_TIMEOUT_S,
    MAX_CONNECTIONS,
    MAX_CONNECTIONS_PER_CLIENT,
    ConnectionLimits,
    QuietLog,
)
from fbs_auth import (  # noqa: F401  (re-exported: the server's login in one import)
    LOGIN_FREE_FAILURES,
    LOGIN_MAX_FAILURES,
    GuardedBasicAuth,
    LoginThrottle,
    check_password,
    client_address,
    parse_networks,
)
from page_gate import PageGate
from page_limits import TOTAL_BURST_S, TOTAL_SHARE, USER_BURST_S, USER_SHARE, PageBuilds
from server_private import (
    accept_connections,
    bound_bokeh_messages,
    bound_page_builds,
    cancel_queued_panel_work,
    cleanup_document,
    peer_address,
    report_refused_websocket_frames,
)

log = logging.getLogger("tire_fbs.server")
#: The app's loggers, logged at the level panel serve gives Bokeh's (``--log-level``).
APP_LOGGERS = ("app", "tire-fbs")

#: Seconds after SIGTERM after which the process ends, orderly or not.
SHUTDOWN_DEADLINE_S = 6.0
#: Seconds child processes get to end after SIGTERM before they are killed.
CHILD_GRACE_S = 1.0
#: Largest body of an HTTP request (the login form: a user name and a password).
HTTP_MAX_BODY_BYTES = 16 * 1024
#: Room in a connection's read buffer beyond the largest websocket message (frame headers).
READ_BUFFER_SLACK = 1 << 20
#: Seconds the proof waits for a page's on-load callbacks (a failing one is reported at once).
ONLOAD_TIMEOUT_S = 300.0
#: Packages whose loaded modules Panel's component-resource route may serve files of.
COMPONENT_PACKAGES = ("panel",)


# ---- component resources -------------------------------------------------------------------


def allowed_component_module(name: str) -> bool:
    """Whether Panel's component-resource route may serve files of module ``name``: a module
    of :data:`COMPONENT_PACKAGES` that is loaded already (the route then imports nothing)."""
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*", name):
        return False
    return name.split(".")[0] in COMPONENT_PACKAGES and name in sys.modules


def _component_handler_class():
    from panel.io.server import AuthenticatedStaticFileHandler, ComponentResourceHandler
    from tornado.web import HTTPError

    class GuardedComponentHandler(AuthenticatedStaticFileHandler, ComponentResourceHandler):
        """Panel's ``/components/<module>/<class>/<attribute>/<file>`` behind the login, for
        loaded modules of Panel only (checked before the route would import the module)."""

        def parse_url_path(self, path: str) -> str:
            module = path.split("/", 1)[0]
            if not allowed_component_module(module):
                raise HTTPError(404, "Module not found")
            return super().parse_url_path(path)

    return ComponentResourceHandler, GuardedComponentHandler


def guard_component_route(patterns: list) -> int:
    """Replace Panel's component-resource route in ``patterns``; the number replaced."""
    original, guarded = _component_handler_class()
    n = 0
    for i, pattern in enumerate(patterns):
        if isinstance(pattern, tuple) and len(pattern) >= 2 and pattern[1] is original:
            patterns[i] = (pattern[0], guarded, *pattern[2:])
            n += 1
    return n


# ---- websocket messages ------------------------------------------------------------------


def _websocket_refused(handler, reason: str | None) -> None:
    """Log a websocket closed for the size of what its client sent (who, and why)."""
    request = getattr(handler, "request", None)
    who = peer_address(request) if request is not None else "unknown"
    log.warning(
        "websocket of %s closed: %s (FBS_WEBSOCKET_MAX_MESSAGE_MB)",
        who,
        reason if reason and reason != "message too big" else "a frame declared above the limit",
    )


def bound_websocket_messages(max_bytes: int) -> None:
    """Refuse a websocket message above ``max_bytes`` by the size its frame declares,
    before any of it is read (Tornado's check, logged here), and a Bokeh message whose
    frames add up to more (:func:`server_private.bound_bokeh_messages`)."""
    report_refused_websocket_frames(_websocket_refused)
    bound_bokeh_messages(int(max_bytes), _websocket_refused)


# ---- page builds ---------------------------------------------------------------------------


def limit_page_builds(builds: PageBuilds, by_login: bool, proxies, quiet: QuietLog) -> None:
    """Page builds draw on ``builds``' budgets (:mod:`page_limits`), owned by the login
    (``by_login``) or else by the client address; refusals logged once per interval."""

    def key_of(handler) -> str:
        if by_login:
            user = handler.current_user
            return "user " + (user.decode() if isinstance(user, bytes) else str(user))
        request = handler.request
        return "client " + client_address(peer_address(request), request.headers, proxies)

    def refused(handler, key: str, kind: str, wait_s: float) -> None:
        quiet.note(
            f"pages {kind}",
            f"page builds refused: {key[:80]!r} "
            f"({'its budget' if kind == 'user' else 'the budget of all users'} spent, "
            f"retry in {wait_s:.0f} s)",
        )

    bound_page_builds(builds, key_of, refused)


# ---- health check ------------------------------------------------------------------------


def _health_handler_class():
    from tornado import web

    class HealthHandler(web.RequestHandler):
        """``/liveness``: answered from memory, never builds a page."""

        def initialize(self, proved: dict[str, float], paths: list[str]):
            self.proved = proved  # filled by the proof's thread
            self.paths = paths

        def get(self):
            self.set_header("Content-Type", "application/json")
            self.set_header("Cache-Control", "no-store")
            endpoint = self.get_argument("endpoint", default=None)
            if endpoint is None:
                self.write({self.request.path: True})
            elif endpoint in self.proved:
                self.write({endpoint: True})
            elif endpoint in self.paths:  # its proof still runs
                self.set_status(503)
                self.write({endpoint: False})
            else:
                self.set_status(400)
                self.write({"error": "unknown endpoint", "endpoints": sorted(self.paths)})

        head = get

    return HealthHandler


def applications(files: list[str], args: list[str]) -> dict:
    """The apps of ``panel serve FILES`` by path (e.g. ``/main``); no script is run."""
    from panel.command import serve as panel_serve

    return panel_serve.build_single_handler_applications(files, {f: args for f in files})


def _top_level_imports(path: str) -> list:
    import ast
    from pathlib import Path

    tree = ast.parse(Path(path).read_text(encoding="utf-8"), filename=path)
    return [n for n in tree.body if isinstance(n, ast.Import | ast.ImportFrom)]


def script_imports(path: str) -> list[str]:
    """The modules a script imports at its top level, in order (read, not run)."""
    import ast

    names: list[str] = []
    for node in _top_level_imports(path):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif node.module and node.level == 0:
            names.append(node.module)
    return list(dict.fromkeys(n for n in names if n != "__future__"))


def script_submodules(path: str) -> list[str]:
    """``X.a`` of each top-level ``from X import a`` of a script: the names that may be
    submodules of a package ``X`` (read, not run; :func:`preload_imports` imports those
    that are)."""
    import ast

    names: list[str] = []
    for node in _top_level_imports(path):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names += [f"{node.module}.{a.name}" for a in node.names if a.name != "*"]
    return list(dict.fromkeys(n for n in names if not n.startswith("__future__.")))


def _is_submodule(name: str) -> bool:
    """Whether ``name`` (``X.a``) names a module of the imported package ``X``."""
    import importlib.util

    parent = sys.modules.get(name.rpartition(".")[0])
    if parent is None or not hasattr(parent, "__path__"):
        return False
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):
        return False


def preload_imports(files: list[str]) -> float:
    """Import the modules the app scripts ``files`` import at their top level, and the
    submodules they import names of; seconds.

    Run before the port opens (1.5-2 s for the dashboard: its libraries, the reference
    models' code and what its pages import on first use, ``app/runtime/libraries.py``), so
    that the first page requested does not wait for them. A module that fails
    to import is left to the proof, which reports the script's error. Then a preloaded
    module's ``warm_before_serving()``, if it has one, is called: what the app's first
    page computes, computed before the port opens (the dashboard's default results).
    """
    import importlib

    t0 = time.perf_counter()
    loaded = []
    for path in files:
        subs = [n for n in script_submodules(path) if n not in sys.modules]
        for name in script_imports(path) + subs:
            if name in subs and not _is_submodule(name):
                continue  # a function or class of the package, or the package failed
            try:
                loaded.append(importlib.import_module(name))
            except Exception as exc:  # noqa: BLE001 (the proof reports the script's error)
                log.warning("preloading %s for %s failed: %s", name, path, exc)
    dt = time.perf_counter() - t0
    log.info("the apps' imports preloaded (%.1f s)", dt)
    for module in loaded:
        warm = getattr(module, "warm_before_serving", None)
        if callable(warm):
            t1 = time.perf_counter()
            try:
                warm()
            except Exception as exc:  # noqa: BLE001 (the proof reports the script's error)
                log.warning("%s.warm_before_serving failed: %s", module.__name__, exc)
            log.info("%s.warm_before_serving (%.1f s)", module.__name__, time.perf_counter() - t1)
    return time.perf_counter() - t0


def prove_applications(apps: dict, proved: dict[str, float] | None = None) -> dict[str, float]:
    """Build, load (:func:`load_as_browser`) and clean up one page of each app of
    :func:`applications`; seconds per app path, entered in ``proved`` (a new dict by
    default) as each app is proved. Before it builds a page and before it loads it, it
    steps aside (the ``step_aside`` of its thread, if any: :mod:`page_gate`).

    Raises
    ------
    RuntimeError
        If an app script fails, builds an empty page or fails when loaded (the message
        names the error).
    """
    from panel.io.session import generate_session

    proved = {} if proved is None else proved
    for path, app in apps.items():
        step_aside()
        t0 = time.perf_counter()
        # a session context as in a served session: .servable() adds the page's roots
        doc = generate_session(app).document
        try:
            failed = [h for h in app.handlers if getattr(h, "failed", False)]
            if failed:
                h = failed[0]
                raise RuntimeError(
                    f"the app {path} failed to build a page: {h.error}\n{h.error_detail or ''}"
                )
            if not doc.roots:
                raise RuntimeError(f"the app {path} built an empty page")
            step_aside()
            # the page's on-load callbacks step aside too (on Panel's worker threads)
            doc.step_aside = getattr(threading.current_thread(), "step_aside", None)
            load_as_browser(doc, path)
        finally:
            cleanup_document(doc)
        proved[path] = time.perf_counter() - t0
        log.info("app %s builds a page (%.1f s); /liveness reports it", path, proved[path])
    return proved


def step_aside() -> None:
    """Wait while users' pages open, if this thread is asked to (:mod:`page_gate`)."""
    wait = getattr(threading.current_thread(), "step_aside", None)
    if wait is not None:
        wait()


def load_as_browser(doc, path: str, timeout_s: float = ONLOAD_TIMEOUT_S) -> None:
    """Send ``doc`` Bokeh's "document ready" event, as a browser does once it shows the
    page, and wait until the page's on-load callbacks (``pn.state.onload``) have run.

    Panel runs them on its worker threads (``--num-threads``) and hands an exception of
    one of them to ``pn.config.exception_handler`` with the page's document current; the
    handler is chained for the wait, so a failure ends the wait at once.

    Raises
    ------
    RuntimeError
        If an on-load callback fails, or they have not all run within ``timeout_s``.
    """
    import panel as pn
    from bokeh.events import DocumentReady
    from panel.io.state import set_curdoc

    done = threading.Event()
    errors: list[BaseException] = []
    previous = pn.config.exception_handler

    def handler(exc: BaseException) -> None:
        if pn.state.curdoc is doc:
            errors.append(exc)
            done.set()
        elif previous is not None:
            previous(exc)
        else:
            raise exc

    pn.config.exception_handler = handler
    try:
        with set_curdoc(doc):
            pn.state.onload(done.set)  # after the page's own callbacks, in their order
        doc.callbacks.trigger_event(DocumentReady())
        if not done.wait(timeout_s):
            raise RuntimeError(
                f"the app {path} built a page whose on-load callbacks did not finish "
                f"within {timeout_s:g} s"
            )
    finally:
        if pn.config.exception_handler is handler:
            pn.config.exception_handler = previous
    if errors:
        exc = errors[0]
        raise RuntimeError(
            f"the app {path} failed when its page was loaded: {type(exc).__name__}: {exc}"
        ) from exc


def prove_in_background(apps: dict, proved: dict[str, float], gate: PageGate) -> threading.Thread:
    """:func:`prove_applications` on a thread of its own, once the server listens; an app
    that cannot build a page stops the server (as a failed start would). The proof steps
    aside while users' pages open (``gate``, :class:`page_gate.PageGate`)."""

    def work() -> None:
        try:
            gate.run(lambda: prove_applications(apps, proved))
        except Exception as exc:  # noqa: BLE001 (any failure of the app: stop with it)
            log.error("the server stopped: %s", exc)
            print(f"tire-fbs: the server stopped: {exc}", file=sys.stderr, flush=True)
            exit_now(1)

    t = threading.Thread(target=work, name="fbs-prove-apps", daemon=True)
    t.start()
    return t


# ---- shutdown ----------------------------------------------------------------------------


def child_pids() -> list[int]:
    """PIDs of this process's children (all threads), from /proc; [] where unavailable."""
    pids: set[int] = set()
    try:
        tasks = os.listdir("/proc/self/task")
    except OSError:
        tasks = []
    for tid in tasks:
        try:
            with open(f"/proc/self/task/{tid}/children") as f:
                pids.update(int(p) for p in f.read().split())
        except OSError:
            continue
    return sorted(pids)


def _alive(pid: int) -> bool:
    try:
        done, _ = os.waitpid(pid, os.WNOHANG)
    except ChildProcessError:
        return False  # reaped elsewhere (e.g. by subprocess)
    return done == 0


def _signal_tree(pid: int, sig: int) -> None:
    """``sig`` to child ``pid``, and to its whole process group when it leads one (the
    file-parser sandbox does: its forked parsers end with it)."""
    try:
        if os.getpgid(pid) == pid:
            os.killpg(pid, sig)
        else:
            os.kill(pid, sig)
    except (ProcessLookupError, PermissionError):
        pass


def stop_children(grace_s: float = CHILD_GRACE_S) -> int:
    """SIGTERM every child process (and the process group it leads), SIGKILL those alive
    after ``grace_s``; their number."""
    pids = child_pids()
    for pid in pids:
        _signal_tree(pid, signal.SIGTERM)
    deadline = time.monotonic() + grace_s
    alive = list(pids)
    while alive and time.monotonic() < deadline:
        alive = [p for p in alive if _alive(p)]
        if alive:
            time.sleep(0.02)
    for pid in pids:  # the groups of those that ended too: a grandchild may linger
        _signal_tree(pid, signal.SIGKILL)
    for pid in alive:
        try:
            os.waitpid(pid, 0)
        except ChildProcessError:
            pass
    return len(pids)


def exit_now(status: int) -> None:
    """End the process now: children stopped, logs flushed, worker threads not waited for."""
    n = stop_children()
    if n:
        log.info("stopped %d child process(es)", n)
    busy = [t.name for t in threading.enumerate() if t.is_alive() and not t.daemon]
    if len(busy) > 1:
        log.info("exiting without waiting for %d worker thread(s)", len(busy) - 1)
    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:  # noqa: S110 (a closed stream: nothing to flush)
            pass
    os._exit(status)


#: Set by the stop signal: the event loop's end is then the server's.
STOPPING = threading.Event()


def _on_stop_signal(signum: int, deadline_s: float) -> None:
    from tornado.ioloop import IOLoop

    log.info("%s: stopping the server", signal.Signals(signum).name)

    def watchdog():
        time.sleep(deadline_s)
        log.error("not stopped %.0f s after the signal: exiting now", deadline_s)
        exit_now(1)

    threading.Thread(target=watchdog, name="shutdown-watchdog", daemon=True).start()
    STOPPING.set()
    cancel_queued_panel_work()
    stop_reports()
    IOLoop.current().stop()


def stop_reports() -> None:
    """End the app's report drawing (queued reports cancelled, the report process ended, no
    new one started): a report process started after :func:`stop_children` listed the
    children would outlive the server. Only when the app has loaded it."""
    reports = sys.modules.get("app.runtime.reports")
    if reports is not None:
        n = reports.stop()
        if n:
            log.info("stopped %d report process(es)", n)


def _install_stop_signals(deadline_s: float) -> None:
    """Replace Bokeh's SIGTERM handler (it only stops the loop) by the prompt shutdown."""
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, _on_stop_signal, sig, deadline_s)


# ---- the command -------------------------------------------------------------------------


class Supervised:
    """Runs the Bokeh server's event loop until the stop signal, whatever a request raises.

    An exception that escapes a request handler or a callback ends Tornado's event loop
    when it is not an ``Exception`` (``SystemExit``, ``KeyboardInterrupt``): asyncio re-raises
    those out of the loop, and ``panel serve`` would then end. Here it is logged and the
    loop started again; only the stop signal (:func:`_on_stop_signal`) ends the server.
    What ``customize_server`` returns to ``bokeh serve``: it only calls
    :meth:`run_until_shutdown`.
    """

    def __init__(self, server) -> None:
        self.server = server
        self.escaped = 0

    def run_until_shutdown(self) -> None:
        self.server.start()
        loop = self.server.io_loop
        while not STOPPING.is_set():
            try:
                loop.start()
            except BaseException as exc:  # noqa: BLE001 (the point: nothing ends the server)
                if STOPPING.is_set():
                    break
                self.escaped += 1
                log.error(
                    "%s escaped a request handler and would have ended the server; it goes on",
                    type(exc).__name__,
                    exc_info=exc,
                )
                continue
            break
        self.server.stop()


def _serve_class():
    from panel.auth import BasicAuthProvider
    from panel.command.serve import Serve
    from panel.config import config

    class HardenedServe(Serve):
        """Panel's ``serve`` command with the changes listed in the module docstring."""

        login_max_failures = LOGIN_MAX_FAILURES
        shutdown_deadline_s = SHUTDOWN_DEADLINE_S
        trusted_proxies = ""
        http_max_body_bytes = HTTP_MAX_BODY_BYTES
        max_connections = MAX_CONNECTIONS
        max_connections_per_client = MAX_CONNECTIONS_PER_CLIENT
        header_timeout_s = HEADER_TIMEOUT_S
        body_timeout_s = BODY_TIMEOUT_S
        page_build_share = TOTAL_SHARE
        page_build_burst_s = TOTAL_BURST_S
        page_build_share_per_user = USER_SHARE
        page_build_burst_s_per_user = USER_BURST_S
        users: dict | str | None = None  # the basic-auth users (set by serve)
        limits: ConnectionLimits | None = None

        def customize_kwargs(self, args, server_kwargs):
            # the level panel serve gave Bokeh's loggers (--log-level)
            level = logging.getLogger("bokeh").getEffectiveLevel()
            log.setLevel(level)
            for name in APP_LOGGERS:  # the app's own lines (a page's session ended, ...)
                logging.getLogger(name).setLevel(level)
            if args.liveness:
                log.warning("--liveness ignored: the server has its own cheap /liveness")
                args.liveness = False
            kwargs = super().customize_kwargs(args, server_kwargs)
            provider = kwargs.get("auth_provider")
            proxies = parse_networks(self.trusted_proxies)
            if type(provider) is BasicAuthProvider and self.users:
                login = GuardedBasicAuth(
                    provider,
                    self.users,
                    config.cookie_secret,
                    LoginThrottle(self.login_max_failures),
                    proxies,
                    config.oauth_expiry,
                )
                kwargs["auth_provider"] = login.provider()
            if guard_component_route(kwargs["extra_patterns"]) != 1:
                raise RuntimeError("Panel's component-resource route was not found to guard")
            ws_max = getattr(args, "websocket_max_message_size", None) or 20 * 1024 * 1024
            bound_websocket_messages(ws_max)
            kwargs["http_server_kwargs"] = {
                **(kwargs.get("http_server_kwargs") or {}),
                "max_body_size": int(self.http_max_body_bytes),
                "max_buffer_size": int(ws_max) + READ_BUFFER_SLACK,
                # the deadline of a request's headers too (Tornado's header_timeout)
                "idle_connection_timeout": float(self.header_timeout_s),
                "body_timeout": float(self.body_timeout_s),
            }
            self.limits = ConnectionLimits(
                int(self.max_connections_per_client),
                int(self.max_connections),
                exempt=proxies,
            )
            builds = PageBuilds(
                float(self.page_build_share_per_user),
                float(self.page_build_burst_s_per_user),
                float(self.page_build_share),
                float(self.page_build_burst_s),
            )
            by_login = bool(config.basic_auth) or bool(config.oauth_provider)
            limit_page_builds(builds, by_login, proxies, self.limits.quiet)
            log.info(
                "page builds: %.0f %% of the event loop per %s, %.0f %% in all",
                100 * builds.user_share,
                "login" if by_login else "client",
                100 * builds.total.rate,
            )
            log.info(
                "connections: at most %d per client, %d in all; headers within %g s, "
                "bodies within %g s",
                self.limits.per_client,
                self.limits.total,
                float(self.header_timeout_s),
                float(self.body_timeout_s),
            )
            apps = applications(args.files, args.args or [])
            preload_imports(args.files)  # before the port opens: no page waits for them
            proved: dict[str, float] = {}
            kwargs["extra_patterns"].append(
                (
                    f"/{args.liveness_endpoint}",
                    _health_handler_class(),
                    {"proved": proved, "paths": sorted(apps)},
                )
            )
            from tornado.ioloop import IOLoop

            IOLoop.current().add_callback(_install_stop_signals, self.shutdown_deadline_s)
            # once the loop runs (the port is open): the proof, which warms the server and
            # steps aside while a user's page opens (both are work for the one interpreter)
            from panel.io.state import state

            gate = PageGate()
            state.on_session_created(gate.watch_session)
            IOLoop.current().add_callback(prove_in_background, apps, proved, gate)
            return kwargs

        def customize_server(self, server):
            server = super().customize_server(server)
            if self.limits is not None and accept_connections(server, self.limits) < 1:
                raise RuntimeError("the server's listening socket was not found to guard")
            return Supervised(server)

    return HardenedServe


def serve(argv: list[str], private: dict, options: dict | None = None) -> int:
    """Run ``panel serve ARGV`` with the private settings; ends the process.

    Parameters
    ----------
    argv : list of str
        Arguments of ``panel serve`` (no secrets among them).
    private : dict
        ``cookie_secret`` (str) and ``basic_auth`` (dict user -> password, or the path of
        a JSON file), each optional.
    options : dict, optional
        ``login_max_failures`` (int), ``shutdown_deadline_s`` (float), ``trusted_proxies``
        (str: addresses or networks, :func:`fbs_auth.parse_networks`),
        ``http_max_body_bytes`` (int), ``max_connections``, ``max_connections_per_client``
        (int), ``header_timeout_s``, ``body_timeout_s`` (float): :mod:`conn_limits`.
    """
    from panel.config import config

    if private.get("cookie_secret"):
        config.cookie_secret = private["cookie_secret"]
    if private.get("basic_auth"):
        config.basic_auth = private["basic_auth"]
    cls = _serve_class()
    cls.users = private.get("basic_auth")
    for key, value in (options or {}).items():
        setattr(cls, key, value)
    parser = argparse.ArgumentParser(prog="panel serve")
    command = cls(parser=parser)
    args = parser.parse_args(argv)
    try:
        ret = command.invoke(args)
    except Exception as exc:
        log.error("the server stopped: %s", exc)
        print(f"tire-fbs: the server stopped: {exc}", file=sys.stderr)
        exit_now(1)
    exit_now(1 if ret is False else 0)
    return 0  # not reached
