"""``panel serve`` of the dashboard, hardened for deployment (run by ``docker/entrypoint.py``).

The container's entrypoint validates the settings and then runs :func:`serve` in the server
process (PID 1 in the container). It is Panel's own ``panel serve`` command, with four
changes that ``panel serve`` offers no option for:

Secrets stay off the command line
    The cookie secret and the basic-auth users reach this process through a private,
    already unlinked file descriptor (see ``docker/entrypoint.py``) and are set in Panel's
    ``config`` here: neither ``ps``/``docker top`` (the command line) nor
    ``/proc/<pid>/environ`` of the server shows them, and child processes (the file-parser
    sandbox) do not inherit them.
A cheap health check
    ``/liveness`` answers from memory, without login: ``{"/liveness": true}``, and with
    ``?endpoint=/main`` whether that app built a page. The app is proved *once*, at start,
    before the server listens: one page is built and cleaned up, and a script that fails
    stops the server with the error (the container exits; a restart policy retries). No
    request, authenticated or not, makes the health check build a page (Panel's own
    ``--liveness`` built one on the event loop for every request; finding 2 of issue 20).
Throttled logins
    Wrong basic-auth logins are logged (client address, user name) and slowed per client:
    from the 4th failure within :data:`LOGIN_WINDOW_S` each answer is delayed (0.5 s,
    doubling, at most 8 s) without blocking the server, and from the ``max_failures``-th
    on the client gets ``429 Too Many Requests`` until its failures age out, without its
    password being checked. Passwords are compared in constant time.
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
import collections
import hmac
import json
import logging
import os
import signal
import sys
import threading
import time

log = logging.getLogger("tire_fbs.server")

#: Failures (per client) before wrong logins are slowed down.
LOGIN_FREE_FAILURES = 3
#: Delay of the first slowed answer in seconds; doubles per failure up to LOGIN_MAX_DELAY_S.
LOGIN_BASE_DELAY_S = 0.5
LOGIN_MAX_DELAY_S = 8.0
#: Seconds a failed login counts against its client.
LOGIN_WINDOW_S = 300.0
#: Default failures within the window after which a client is refused (429).
LOGIN_MAX_FAILURES = 10
#: Clients remembered at most (older entries are dropped first).
LOGIN_MAX_CLIENTS = 10_000
#: Seconds after SIGTERM after which the process ends, orderly or not.
SHUTDOWN_DEADLINE_S = 6.0
#: Seconds child processes get to end after SIGTERM before they are killed.
CHILD_GRACE_S = 1.0


# ---- login throttle ----------------------------------------------------------------------


class LoginThrottle:
    """Failed logins per client in a sliding window.

    Parameters
    ----------
    max_failures : int
        Failures within ``window_s`` after which the client is refused.
    window_s : float
        Seconds a failure counts.
    clock : callable
        Monotonic clock (seconds); replaceable in tests.
    """

    def __init__(
        self,
        max_failures: int = LOGIN_MAX_FAILURES,
        window_s: float = LOGIN_WINDOW_S,
        clock=time.monotonic,
    ) -> None:
        if max_failures < 1:
            raise ValueError(f"max_failures={max_failures}: must be >= 1")
        self.max_failures = max_failures
        self.window_s = window_s
        self.clock = clock
        self._failures: collections.OrderedDict[str, collections.deque] = collections.OrderedDict()
        self._lock = threading.Lock()

    def _recent(self, client: str, now: float) -> collections.deque:
        times = self._failures.get(client)
        if times is None:
            return collections.deque()
        while times and now - times[0] >= self.window_s:
            times.popleft()
        if not times:
            del self._failures[client]
        return times

    def retry_after(self, client: str) -> float:
        """Seconds until ``client`` may try again; 0 if it may now."""
        with self._lock:
            now = self.clock()
            times = self._recent(client, now)
            if len(times) < self.max_failures:
                return 0.0
            return max(times[-self.max_failures] + self.window_s - now, 0.0)

    def failed(self, client: str) -> int:
        """Count a failure of ``client``; the number of its failures in the window."""
        with self._lock:
            now = self.clock()
            times = self._recent(client, now)
            self._failures[client] = times
            self._failures.move_to_end(client)
            times.append(now)
            while len(self._failures) > LOGIN_MAX_CLIENTS:
                self._failures.popitem(last=False)
            return len(times)

    def succeeded(self, client: str) -> None:
        with self._lock:
            self._failures.pop(client, None)

    @staticmethod
    def delay(failures: int) -> float:
        """Seconds to hold the answer to the ``failures``-th failure."""
        if failures <= LOGIN_FREE_FAILURES:
            return 0.0
        delay = LOGIN_BASE_DELAY_S * 2.0 ** (failures - LOGIN_FREE_FAILURES - 1)
        return min(delay, LOGIN_MAX_DELAY_S)


def _printable(text: str, limit: int = 64) -> str:
    """A user-supplied string made safe for one log line."""
    return repr(text[:limit] + ("..." if len(text) > limit else ""))


def check_password(users, username: str, password: str) -> bool:
    """Constant-time check of ``username``/``password`` against ``users``.

    ``users`` is a mapping user -> password or the path of a JSON file holding one.
    """
    if isinstance(users, str):
        with open(users, encoding="utf-8") as f:
            users = json.load(f)
    expected = users.get(username) if isinstance(users, dict) else None
    # compare against something of the same kind also for an unknown user
    ok = hmac.compare_digest(
        (expected if isinstance(expected, str) else "\0" + password).encode("utf-8"),
        password.encode("utf-8"),
    )
    return ok and isinstance(expected, str)


def _login_handler_class(throttle: LoginThrottle):
    import tornado.escape
    from panel.auth import BasicLoginHandler
    from panel.config import config

    class ThrottledLoginHandler(BasicLoginHandler):
        """Panel's login form with per-client throttling and logging of failures."""

        def _validate(self, username, password):
            return check_password(config.basic_auth, username, password)

        async def post(self):
            client = self.request.remote_ip or "unknown"
            wait = throttle.retry_after(client)
            if wait > 0:
                log.warning(
                    "login refused: client %s has %d failed logins within %.0f s "
                    "(may try again in %.0f s)",
                    client,
                    throttle.max_failures,
                    throttle.window_s,
                    wait,
                )
                self.set_status(429)
                self.set_header("Retry-After", str(int(wait) + 1))
                self.finish("Too many failed logins: try again later.")
                return
            username = self.get_argument("username", "")
            if self._validate(username, self.get_argument("password", "")):
                throttle.succeeded(client)
                log.info("login: user %s from %s", _printable(username), client)
                self.set_current_user(username)
                self.redirect(self._next_url())
                return
            failures = throttle.failed(client)
            pause = throttle.delay(failures)
            log.warning(
                "failed login: user %s from %s (%d failures within %.0f s%s)",
                _printable(username),
                client,
                failures,
                throttle.window_s,
                f"; answer held {pause:.1f} s" if pause else "",
            )
            if pause:
                await asyncio.sleep(pause)  # holds this answer only, not the server
            error = "?error=" + tornado.escape.url_escape("Invalid username or password!")
            self.redirect(self.request.path + error)

        def _next_url(self):
            from panel.auth import _validate_next_url
            from panel.io.state import state

            return _validate_next_url(self.get_cookie("next_url", state.base_url))

    return ThrottledLoginHandler


def _throttled_provider_class(handler_class):
    from panel.auth import BasicAuthProvider

    class ThrottledBasicAuthProvider(BasicAuthProvider):
        @property
        def login_handler(self):
            handler_class._login_endpoint = self._login_endpoint
            handler_class._login_template = self._login_template
            return handler_class

    return ThrottledBasicAuthProvider


# ---- health check ------------------------------------------------------------------------


def _health_handler_class():
    from tornado import web

    class HealthHandler(web.RequestHandler):
        """``/liveness``: answered from memory, never builds a page."""

        def initialize(self, proved: dict[str, float]):
            self.proved = proved

        def get(self):
            self.set_header("Content-Type", "application/json")
            self.set_header("Cache-Control", "no-store")
            endpoint = self.get_argument("endpoint", default=None)
            if endpoint is None:
                self.write({self.request.path: True})
            elif endpoint in self.proved:
                self.write({endpoint: True})
            else:
                self.set_status(400)
                self.write({"error": "unknown endpoint", "endpoints": sorted(self.proved)})

        head = get

    return HealthHandler


def prove_applications(files: list[str], args: list[str]) -> dict[str, float]:
    """Build and clean up one page of each app; seconds per app path (e.g. ``/main``).

    Raises
    ------
    RuntimeError
        If an app script fails or builds an empty page (the message names the error).
    """
    from panel.command import serve as panel_serve
    from panel.io.document import _cleanup_doc
    from panel.io.session import generate_session

    apps = panel_serve.build_single_handler_applications(files, {f: args for f in files})
    proved = {}
    for path, app in apps.items():
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
        finally:
            _cleanup_doc(doc)
        proved[path] = time.perf_counter() - t0
        log.info("app %s builds a page (%.1f s); /liveness reports it", path, proved[path])
    return proved


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


def stop_children(grace_s: float = CHILD_GRACE_S) -> int:
    """SIGTERM every child process, SIGKILL those alive after ``grace_s``; their number."""
    pids = child_pids()
    for pid in pids:
        try:
            os.kill(pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
    deadline = time.monotonic() + grace_s
    alive = list(pids)
    while alive and time.monotonic() < deadline:
        alive = [p for p in alive if _alive(p)]
        if alive:
            time.sleep(0.02)
    for pid in alive:
        try:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
        except (ProcessLookupError, ChildProcessError):
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


def _cancel_queued_work() -> None:
    """Cancel work queued on Panel's thread pool (running work is abandoned at exit)."""
    from panel.io.state import state

    pool = getattr(state, "_thread_pool", None)
    if pool is not None:
        pool.shutdown(wait=False, cancel_futures=True)


def _on_stop_signal(signum: int, deadline_s: float) -> None:
    from tornado.ioloop import IOLoop

    log.info("%s: stopping the server", signal.Signals(signum).name)

    def watchdog():
        time.sleep(deadline_s)
        log.error("not stopped %.0f s after the signal: exiting now", deadline_s)
        exit_now(1)

    threading.Thread(target=watchdog, name="shutdown-watchdog", daemon=True).start()
    _cancel_queued_work()
    IOLoop.current().stop()


def _install_stop_signals(deadline_s: float) -> None:
    """Replace Bokeh's SIGTERM handler (it only stops the loop) by the prompt shutdown."""
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, _on_stop_signal, sig, deadline_s)


# ---- the command -------------------------------------------------------------------------


def _serve_class():
    from panel.auth import BasicAuthProvider
    from panel.command.serve import Serve

    class HardenedServe(Serve):
        """Panel's ``serve`` command with the changes listed in the module docstring."""

        login_max_failures = LOGIN_MAX_FAILURES
        shutdown_deadline_s = SHUTDOWN_DEADLINE_S

        def customize_kwargs(self, args, server_kwargs):
            # the level panel serve gave Bokeh's loggers (--log-level)
            log.setLevel(logging.getLogger("bokeh").getEffectiveLevel())
            if args.liveness:
                log.warning("--liveness ignored: the server has its own cheap /liveness")
                args.liveness = False
            kwargs = super().customize_kwargs(args, server_kwargs)
            provider = kwargs.get("auth_provider")
            if type(provider) is BasicAuthProvider:
                throttle = LoginThrottle(self.login_max_failures)
                handler = _login_handler_class(throttle)
                provider.__class__ = _throttled_provider_class(handler)
            proved = prove_applications(args.files, args.args or [])
            kwargs["extra_patterns"].append(
                (f"/{args.liveness_endpoint}", _health_handler_class(), {"proved": proved})
            )
            from tornado.ioloop import IOLoop

            IOLoop.current().add_callback(_install_stop_signals, self.shutdown_deadline_s)
            return kwargs

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
        ``login_max_failures`` (int), ``shutdown_deadline_s`` (float).
    """
    from panel.config import config

    if private.get("cookie_secret"):
        config.cookie_secret = private["cookie_secret"]
    if private.get("basic_auth"):
        config.basic_auth = private["basic_auth"]
    cls = _serve_class()
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
