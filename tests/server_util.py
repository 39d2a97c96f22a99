"""Start the deployment's server (``docker/entrypoint.py``) on a free port and talk to it.

Shared by ``tests/test_auth.py`` and ``tests/test_server_*.py``: the server runs as a
subprocess exactly as in the container (the entrypoint with ``FBS_*`` variables), serving a
small Panel script, and is checked from outside like a browser or an attacker would.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import json
import os
import socket
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENTRYPOINT = ROOT / "docker" / "entrypoint.py"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def in_own_loop(coro, timeout_s: float):
    """Run ``coro`` on an event loop of its own, in a thread of its own (an earlier test may
    have left a loop running in this one); its result, or its exception raised here."""
    out: dict = {}

    def run() -> None:
        try:
            out["value"] = asyncio.run(coro)
        except BaseException as e:  # re-raised in the test's thread
            out["error"] = e

    t = threading.Thread(target=run)
    t.start()
    t.join(timeout_s)
    assert not t.is_alive(), "the client never finished"
    if "error" in out:
        raise out["error"]
    return out["value"]


class PageClient:
    """A served page's websocket read as BokehJS reads it (raw Bokeh protocol messages):
    :meth:`pull` the document, say it is :meth:`ready`, :meth:`pop` what arrives."""

    @classmethod
    async def open(cls, url: str) -> PageClient:
        from bokeh.client.websocket import WebSocketClientConnectionWrapper
        from bokeh.protocol import Protocol
        from bokeh.protocol.receiver import Receiver
        from bokeh.util.token import generate_jwt_token, generate_session_id
        from tornado.httpclient import HTTPRequest
        from tornado.websocket import websocket_connect

        self = cls()
        self.protocol, self.receiver = Protocol(), Receiver(Protocol())
        self.ws = await websocket_connect(
            HTTPRequest(url), subprotocols=["bokeh", generate_jwt_token(generate_session_id())]
        )
        self.sock = WebSocketClientConnectionWrapper(self.ws)
        return self

    async def pop(self):
        """The next whole message from the server."""
        while True:
            frag = await self.ws.read_message()
            assert frag is not None, "the server closed the websocket"
            msg = await self.receiver.consume(frag)
            if msg is not None:
                return msg

    async def pull(self, timeout_s: float):
        """The page's document, as the server sends it on connection (a replica)."""
        from bokeh.document import Document

        assert (await asyncio.wait_for(self.pop(), timeout_s)).msgtype == "ACK"
        await self.protocol.create("PULL-DOC-REQ").send(self.sock)
        reply = await asyncio.wait_for(self.pop(), timeout_s)
        while reply.msgtype == "PATCH-DOC":
            reply = await asyncio.wait_for(self.pop(), timeout_s)
        doc = Document()
        reply.push_to_document(doc)
        return doc

    async def ready(self, doc) -> None:
        """Say the page is shown (BokehJS's document-ready event): its on-load work starts."""
        from bokeh.document.events import MessageSentEvent
        from bokeh.events import DocumentReady

        event = MessageSentEvent(doc, "bokeh_event", DocumentReady())
        await self.protocol.create("PATCH-DOC", [event]).send(self.sock)

    def close(self) -> None:
        self.ws.close()


@contextlib.contextmanager
def served_in_process(apps: dict, timeout_s: float):
    """A Panel server in this process (its own thread) serving ``apps`` (``{name: function
    building a page}``) on a free loopback port, once it listens; yields the port."""
    import panel as pn

    port = free_port()
    server = pn.serve(
        apps,
        port=port,
        address="127.0.0.1",
        websocket_origin=[f"127.0.0.1:{port}"],
        threaded=True,
        show=False,
        start=True,
    )
    try:
        wait_for(lambda: _accepts(port), timeout_s, what="the in-process server listening")
        yield port
    finally:
        server.stop()


def _accepts(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=1).close()
        return True
    except OSError:
        return False


def wait_for(condition, timeout_s: float, interval_s: float = 0.05, what: str = "condition"):
    """Poll ``condition()`` until it returns a true value (returned) or the time is up."""
    deadline = time.monotonic() + timeout_s
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() > deadline:
            raise TimeoutError(f"{what} not reached within {timeout_s:.0f} s")
        time.sleep(interval_s)


class Server:
    """The entrypoint serving ``app_text`` as ``/<name>`` on 127.0.0.1, log in ``folder``
    (``app_text`` None: the dashboard itself, ``app/main.py`` as ``/main``)."""

    def __init__(
        self, folder: Path, app_text: str | None, env: dict[str, str], name: str = "fbsapp"
    ):
        self.folder = Path(folder)
        if app_text is None:
            self.app, name = ROOT / "app" / "main.py", "main"
        else:
            self.app = self.folder / f"{name}.py"
            self.app.write_text(app_text)
        self.name = name
        self.port = free_port()
        self.base = f"http://127.0.0.1:{self.port}"
        full_env = {
            **os.environ,
            "FBS_APP": str(self.app),
            "FBS_PORT": str(self.port),
            "FBS_ADDRESS": "127.0.0.1",
            "FBS_NUM_THREADS": "2",
            "BOKEH_ALLOW_WS_ORIGIN": f"127.0.0.1:{self.port}",
            **env,
        }
        self.log_path = self.folder / f"server-{self.port}.log"
        self._log = open(self.log_path, "w")  # noqa: SIM115 (closed in stop)
        self.proc = subprocess.Popen(
            [sys.executable, str(ENTRYPOINT)],
            env=full_env,
            stdout=self._log,
            stderr=subprocess.STDOUT,
        )

    def log(self) -> str:
        return self.log_path.read_text()

    def alive(self) -> bool:
        return self.proc.poll() is None

    def listening(self, timeout_s: float = 60) -> Server:
        """Wait until ``/liveness`` answers (the port is open: the app's proof may still
        run); raises with the log if the server ends first."""
        wait_for(lambda: self._answers("/liveness"), timeout_s, 0.1, "server listening")
        return self

    def started(self, timeout_s: float = 120) -> Server:
        """Wait until ``/liveness?endpoint=/<name>`` answers: the app built its page (the
        server's proof, which runs once the port is open); raises with the log if the
        server ends first."""
        wait_for(
            lambda: self._answers(f"/liveness?endpoint=/{self.name}"),
            timeout_s,
            0.1,
            "server start",
        )
        return self

    def _answers(self, path: str) -> bool:
        if self.proc.poll() is not None:
            raise RuntimeError(f"the server exited ({self.proc.returncode}):\n{self.log()}")
        try:
            with urllib.request.urlopen(self.base + path, timeout=2) as r:
                return r.status == 200
        except OSError:
            return False

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(15)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._log.close()


class NoRedirect(urllib.request.HTTPRedirectHandler):
    def redirect_request(self, *args, **kwargs):
        return None


def get(opener, url, data=None, headers=None):
    """(status, headers, body) of a request, without following redirects by default."""
    req = urllib.request.Request(url, data=data, headers=headers or {})
    try:
        with opener.open(req, timeout=60) as r:
            return r.status, r.headers, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.headers, e.read().decode()


def form_token(base: str, path: str = "/login", headers=None) -> tuple[str, str]:
    """``(token, cookie header)`` of a form of the server (the login form, the logout
    confirmation) as a browser gets it: its hidden CSRF field and the cookie that goes with
    it."""
    import http.cookiejar
    import re

    jar = http.cookiejar.CookieJar()
    opener = urllib.request.build_opener(NoRedirect, urllib.request.HTTPCookieProcessor(jar))
    status, _, body = get(opener, base + path, headers=headers)
    m = re.search(r'name="_csrf" value="([^"]+)"', body)
    assert status == 200 and m, (status, body[:300])
    return m.group(1), "; ".join(f"{c.name}={c.value}" for c in jar)


def login_post(opener, base: str, user: str, password: str, headers=None):
    """(status, headers, body) of the login form's POST as a browser sends it: the form
    fetched first for its CSRF token (hidden field and cookie). The token's cookie goes
    with the POST only, not with the redirects ``opener`` may follow (its own cookies do)."""
    import urllib.parse

    token, cookie = form_token(base, headers=headers)
    data = urllib.parse.urlencode({"username": user, "password": password, "_csrf": token})
    req = urllib.request.Request(base + "/login", data=data.encode(), headers=headers or {})
    req.add_unredirected_header("Cookie", cookie)
    try:
        with opener.open(req, timeout=60) as r:
            return r.status, r.headers, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.headers, e.read().decode()


def run_async(coro):
    """Run ``coro`` to completion on a fresh event loop in its own thread.

    ``asyncio.run`` refuses to start inside a running loop, and pytest-playwright's sync API
    leaves one running in a worker that has already run browser tests.
    """
    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as pool:
        return pool.submit(asyncio.run, coro).result()


async def websocket_session(
    port: int,
    app: str,
    cookie: str | None,
    token: str | None = None,
    origin: str | None = None,
) -> tuple[str, str]:
    """Open the app's Bokeh websocket as bokehjs does, then pull the document.

    Returns the type of the server's first message and the pulled document's content.
    Bokeh messages are three frames: header, metadata, content.
    """
    from bokeh.util.token import generate_jwt_token, generate_session_id
    from tornado.httpclient import HTTPRequest
    from tornado.websocket import websocket_connect

    headers = {"Origin": origin or f"http://127.0.0.1:{port}"}
    if cookie:
        headers["Cookie"] = cookie
    token = token or generate_jwt_token(generate_session_id(), signed=False)
    request = HTTPRequest(f"ws://127.0.0.1:{port}/{app}/ws", headers=headers)
    conn = await websocket_connect(request, subprotocols=["bokeh", token])

    async def frames(n):
        return [await asyncio.wait_for(conn.read_message(), 20) for _ in range(n)]

    try:
        first = json.loads((await frames(3))[0])["msgtype"]
        for frame in (json.dumps({"msgid": "t1", "msgtype": "PULL-DOC-REQ"}), "{}", "{}"):
            await conn.write_message(frame)
        while True:
            header, _, content = await frames(3)
            if json.loads(header)["msgtype"] == "PULL-DOC-REPLY":
                return first, content
    finally:
        conn.close()


def process_tree(pid: int) -> list[int]:
    """``pid`` and all its descendants (from /proc)."""
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        try:
            for tid in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{tid}/children") as f:
                    todo += [int(c) for c in f.read().split()]
        except OSError:
            continue
    return out


def running(pid: int) -> bool:
    """True while ``pid`` exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            state = f.read().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"
