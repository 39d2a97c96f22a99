"""Attack suite against the running dashboard: prints what it tried and what happened.

Issue 20. An outsider and a logged-in user attack the dashboard over HTTP and the Bokeh
websocket protocol (``bench/load_clients.py``'s protocol client: no browser needed):

1. unauthenticated endpoints: the app, its autoload script and metadata, static files,
   ``/liveness`` (what it costs the server: time per request, memory growth), path
   traversal, the websocket without a login;
2. forged cookies: signed with a wrong secret, tampered, unsigned (and, when the suite
   started the server and knows its secret, a correctly signed one as the control);
3. cross-origin websockets with a valid login;
4. bad URL values (out of range, wrong type, huge, markup), alone and before valid ones;
5. hostile files through the upload widgets: wide / tall / gzip-compressed CSV, truncated
   and garbage UFF, MAT and HDF5 decompression bombs, pickles under other names, markup in
   file names; time to the answer, the answer, and the server's memory;
6. one session flooding the compute (200,000-round bands at harmonic 7 with
   frequency-dependent noise, a new one every second) while another session's control
   changes (N, harmonic with a new seed, response DOF, in turn) are timed: p50/p95 of the
   time to its first plot update and to its settled plots, side by side with the same
   changes without the flood;
7. a login flood: 200 wrong logins at once from one client;
8. SIGTERM after all this: how long the server takes to end (only with ``--serve``);
9. connections that never finish their headers (slowloris, 3,500 from 50 loopback
   addresses), 2 and 4 loops of page requests that never open their websocket, each while
   another session's changes are timed (alone vs under attack, side by side), and one
   websocket frame declaring 147 MB (the server's memory, and a session after it).

Every line is ``[ok]``, ``[FINDING]`` (a property the deployment promises does not hold) or
``[info]``; the exit status is 1 if there was a finding.

Usage::

    python bench/attack_suite.py                       # starts its own server (entrypoint,
                                                       # basic auth with random credentials)
    python bench/attack_suite.py --only flood --flood-changes 20
    python bench/attack_suite.py --url http://127.0.0.1:5006 --user u --password p
    python bench/attack_suite.py --big                 # the issue's file sizes (100 MiB CSV)

``--url`` attacks a running server (the SIGTERM check is left out, memory is not read); the
login flood then locks the given user's address out for 5 minutes, so it runs last.
"""

from __future__ import annotations

import argparse
import asyncio
import base64
import concurrent.futures
import gzip
import html
import io
import json
import os
import pickle
import re
import secrets
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from load_clients import BokehSession  # noqa: E402

SECTIONS = (
    "endpoints",
    "cookies",
    "origin",
    "url",
    "files",
    "flood",
    "uploads",
    "reports",
    "bodies",
    "logins",
    "slowloris",
    "reloads",
    "giant",
    "sigterm",
)


# ---- reporting -----------------------------------------------------------------------------


class Report:
    def __init__(self):
        self.findings: list[str] = []

    def section(self, title: str) -> None:
        print(f"\n== {title}", flush=True)

    def line(self, tried: str, happened: str, ok: bool | None) -> None:
        tag = "info" if ok is None else ("ok" if ok else "FINDING")
        print(f"  [{tag:7s}] {tried}\n            -> {happened}", flush=True)
        if ok is False:
            self.findings.append(f"{tried}: {happened}")


# ---- the server ----------------------------------------------------------------------------


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class LocalServer:
    """The container's entrypoint on a loopback port, basic auth with random credentials."""

    def __init__(self, threads: int, campaign_dir: str | None = None):
        self.port = free_port()
        self.user = "attack-suite"
        self.password = secrets.token_urlsafe(12)
        self.secret = secrets.token_urlsafe(32)
        self.log_file = tempfile.NamedTemporaryFile("w+", suffix=".log", delete=False)
        env = {
            **os.environ,
            "FBS_PORT": str(self.port),
            "FBS_ADDRESS": "127.0.0.1",
            "FBS_NUM_THREADS": str(threads),
            "FBS_BASIC_AUTH": f"{self.user}:{self.password}",
            "FBS_COOKIE_SECRET": self.secret,
            "FBS_USE_XHEADERS": "true",  # the login flood comes from a made-up address,
            "FBS_TRUSTED_PROXIES": "127.0.0.1",  # as a reverse proxy on this machine says
            **({"FBS_CAMPAIGN_DIR": campaign_dir} if campaign_dir else {}),
            "BOKEH_ALLOW_WS_ORIGIN": f"127.0.0.1:{self.port}",
        }
        self.proc = subprocess.Popen(
            [sys.executable, str(ROOT / "docker" / "entrypoint.py")],
            env=env,
            stdout=self.log_file,
            stderr=subprocess.STDOUT,
        )
        self.base = f"http://127.0.0.1:{self.port}"
        t0 = time.monotonic()
        while time.monotonic() - t0 < 180:
            if self.proc.poll() is not None:
                raise RuntimeError(f"the server exited:\n{self.log()}")
            try:
                with urllib.request.urlopen(self.base + "/liveness", timeout=2):
                    break
            except OSError:
                time.sleep(0.3)
        else:
            raise RuntimeError("the server did not start within 180 s")
        self.start_s = time.monotonic() - t0

    def log(self) -> str:
        self.log_file.flush()
        return Path(self.log_file.name).read_text()

    def rss_mb(self, children: bool = False) -> float | None:
        """Resident memory of the server process (and its children: the sandbox) in MB."""
        total = 0
        for pid in _tree(self.proc.pid) if children else [self.proc.pid]:
            try:
                for line in Path(f"/proc/{pid}/status").read_text().splitlines():
                    if line.startswith("VmRSS:"):
                        total += int(line.split()[1])
            except OSError:
                continue
        return total / 1024

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        os.unlink(self.log_file.name)


def _tree(pid: int) -> list[int]:
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        try:
            for tid in os.listdir(f"/proc/{p}/task"):
                todo += [int(c) for c in Path(f"/proc/{p}/task/{tid}/children").read_text().split()]
        except OSError:
            continue
    return out


class MemoryPeak:
    """Samples the server's memory every 50 ms while in the ``with`` block.

    ``start``/``peak``/``end``: the server process; ``tree_peak``: with its children (the
    file-parser sandbox, which has its own memory limit).
    """

    def __init__(self, server):
        self.server = server
        self.peak = self.start = self.tree_peak = None

    def __enter__(self):
        if self.server is None:
            return self
        self.start = self.peak = self.server.rss_mb()
        self.tree_peak = self.server.rss_mb(children=True)
        self._stop = threading.Event()

        def sample():
            while not self._stop.wait(0.05):
                self.peak = max(self.peak, self.server.rss_mb())
                self.tree_peak = max(self.tree_peak, self.server.rss_mb(children=True))

        self._thread = threading.Thread(target=sample, daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc):
        if self.server is not None:
            self._stop.set()
            self._thread.join()
            self.end = self.server.rss_mb()

    def text(self) -> str:
        if self.server is None:
            return "memory not read (--url)"
        return (
            f"server process {self.start:.0f} -> peak {self.peak:.0f} -> {self.end:.0f} MB "
            f"(with children peak {self.tree_peak:.0f} MB)"
        )


# ---- HTTP helpers ----------------------------------------------------------------------------


class _NoRedirect(urllib.request.HTTPRedirectHandler):
    def redirect_request(self, *args, **kwargs):
        return None


def fetch(url: str, *, data=None, headers=None, timeout=60):
    """(status, headers, body bytes, seconds) without following redirects."""
    opener = urllib.request.build_opener(_NoRedirect)
    req = urllib.request.Request(url, data=data, headers=headers or {})
    t0 = time.perf_counter()
    try:
        with opener.open(req, timeout=timeout) as r:
            return r.status, r.headers, r.read(), time.perf_counter() - t0
    except urllib.error.HTTPError as e:
        return e.code, e.headers, e.read(), time.perf_counter() - t0
    except OSError as e:
        return None, {}, str(e).encode(), time.perf_counter() - t0


def login_form(base: str, user: str, password: str, headers=None) -> tuple[bytes, dict]:
    """``(body, headers)`` of a login POST as a browser sends it: the login form fetched
    first for its CSRF token (hidden field ``_csrf`` and cookie ``fbs_csrf``)."""
    import re

    status, h, body, _ = fetch(base + "/login", headers=headers)
    m = re.search(rb'name="_csrf" value="([^"]+)"', body or b"")
    token = m.group(1).decode() if m else ""
    cookie = "; ".join(
        v.split(";", 1)[0] for v in (h.get_all("Set-Cookie") or []) if v.startswith("fbs_csrf=")
    ) if status else ""  # fmt: skip
    form = {"username": user, "password": password, "_csrf": token}
    return urllib.parse.urlencode(form).encode(), {**(headers or {}), "Cookie": cookie}


def login(base: str, user: str, password: str) -> str | None:
    """The login cookie header value, or None."""
    jar = urllib.request.HTTPCookieProcessor()
    # the answer's redirect is not followed: it would build a page never opened
    opener = urllib.request.build_opener(jar, _NoRedirect)
    data, headers = login_form(base, user, password)
    try:
        req = urllib.request.Request(base + "/login", data=data, headers=headers)
        opener.open(req, timeout=60).read()
    except urllib.error.HTTPError as e:
        if e.code not in (301, 302, 303):
            return None
    cookies = {c.name: c.value for c in jar.cookiejar}
    if "user" not in cookies:
        return None
    return "; ".join(f"{k}={v}" for k, v in cookies.items())


def app_path(base: str, cookie: str | None) -> str:
    """The app's path (``/main``): where ``/`` redirects to after login."""
    if cookie:
        status, headers, _, _ = fetch(base + "/", headers={"Cookie": cookie})
        if status == 302 and headers.get("Location", "").startswith("/"):
            loc = headers["Location"].split("?")[0]
            if "login" not in loc:
                return loc.rstrip("/")
    return "/main"


async def ws_status(base: str, app: str, cookie: str | None, origin: str | None = None) -> str:
    """Open the app's websocket; 'ACK' if the server accepted it, else the error."""
    from bokeh.util.token import generate_jwt_token, generate_session_id
    from tornado.httpclient import HTTPRequest
    from tornado.websocket import websocket_connect

    headers = {"Origin": origin or base}
    if cookie:
        headers["Cookie"] = cookie
    token = generate_jwt_token(generate_session_id(), signed=False)
    url = base.replace("http", "ws", 1) + app + "/ws"
    try:
        conn = await asyncio.wait_for(
            websocket_connect(HTTPRequest(url, headers=headers), subprotocols=["bokeh", token]),
            30,
        )
    except Exception as exc:
        return f"refused ({exc})"
    try:
        msg = await asyncio.wait_for(conn.read_message(), 30)
        return json.loads(msg).get("msgtype", "?") if msg else "closed"
    finally:
        conn.close()


def run(coro):
    return asyncio.run(coro)


# ---- 1. unauthenticated endpoints ------------------------------------------------------------


def attack_endpoints(rep: Report, base: str, app: str, server) -> None:
    rep.section("1. unauthenticated endpoints (no cookie)")
    for path in (
        "/",
        app,
        f"{app}/autoload.js?bokeh-autoload-element=x",
        f"{app}/metadata",
        "/admin",
        "/logout",
        "/static/js/bokeh.min.js",
        "/static/../../../../etc/passwd",
        "/%2e%2e/%2e%2e/etc/passwd",
        "/liveness",
        f"/liveness?endpoint={app}",
        "/liveness?endpoint=/nothing",
    ):
        status, headers, body, secs = fetch(base + path)
        text = body[:200_000].decode("utf-8", "replace")
        leaks = [m for m in ("render_items", "docs_json", "root:x:", "Harmonic") if m in text]
        where = headers.get("Location", "") if status == 302 else ""
        happened = f"HTTP {status}{' -> ' + where if where else ''}, {len(body)} bytes"
        if leaks:
            happened += f", body contains {leaks}"
        if path.startswith("/static/js"):
            ok = status == 200 and not leaks  # public library code
        elif path.startswith("/liveness"):
            ok = status in (200, 400) and len(body) < 200 and not leaks
        elif path == "/logout":
            ok = not leaks
        else:
            ok = status in (302, 401, 403, 404) and not leaks
        rep.line(f"GET {path}", happened, ok)
    # the health check's cost: it must not build a page per request
    n = 200
    with MemoryPeak(server) as mem:
        times = [fetch(f"{base}/liveness?endpoint={app}")[3] for _ in range(n)]
    med = float(np.median(times)) * 1000
    grew = None if server is None else mem.end - mem.start
    ok = med < 50 and (grew is None or grew < 30)
    rep.line(
        f"{n} x GET /liveness?endpoint={app} without login",
        f"median {med:.1f} ms, max {max(times) * 1000:.1f} ms; {mem.text()}",
        ok,
    )
    ws = run(ws_status(base, app, None))
    rep.line("websocket of the app without a login cookie", ws, not ws.startswith("ACK"))


# ---- 2. forged cookies -------------------------------------------------------------------------


def attack_cookies(rep: Report, base: str, app: str, user: str, secret: str | None) -> None:
    from tornado.web import create_signed_value

    rep.section("2. forged cookies")
    forged = {
        "signed with a wrong secret": create_signed_value("w" * 43, "user", user).decode(),
        "unsigned user name": user,
        "garbage": "2|1:0|10:1700000000|4:user|8:YWRtaW4=|" + "0" * 64,
    }
    if secret:
        good = create_signed_value(secret, "user", user).decode()
        b64 = base64.b64encode(user.encode()).decode()
        admin = base64.b64encode(b"admin").decode()
        forged["valid signature, other user name"] = good.replace(
            f"{len(b64)}:{b64}", f"{len(admin)}:{admin}"
        )
        forged["expired (signed 60 days ago)"] = create_signed_value(
            secret, "user", user, clock=lambda: time.time() - 60 * 86400
        ).decode()
    for what, value in forged.items():
        cookie = f"user={value}"
        status, headers, body, _ = fetch(base + app, headers={"Cookie": cookie})
        ws = run(ws_status(base, app, cookie))
        leaked = b"render_items" in body
        rep.line(
            f"cookie {what}",
            f"page: HTTP {status} {headers.get('Location', '')}"
            f"{' WITH APP CONTENT' if leaked else ''}; websocket: {ws}",
            status != 200 and not leaked and not ws.startswith("ACK"),
        )
    if secret:
        cookie = f"user={create_signed_value(secret, 'user', user).decode()}"
        status, _, body, _ = fetch(base + app, headers={"Cookie": cookie})
        rep.line(
            "control: cookie signed with the server's secret (the forging method works)",
            f"page: HTTP {status}, app content {b'render_items' in body}",
            None,
        )


# ---- 3. cross-origin websockets ----------------------------------------------------------------


def attack_origin(rep: Report, base: str, app: str, cookie: str) -> None:
    rep.section("3. cross-origin websockets (with a valid login cookie)")
    for origin in (base, "http://attacker.example", "null", base.replace("127.0.0.1", "localhost")):
        ws = run(ws_status(base, app, cookie, origin=origin))
        expected = origin == base
        rep.line(
            f"websocket with Origin: {origin}",
            ws,
            ws.startswith("ACK") == expected,
        )


# ---- 4. bad URL values -------------------------------------------------------------------------

MARKUP = "<script>alert(1)</script>"

#: The sidebar controls' titles (the campaign card has a "Harmonic" and a "Noise (%)"
#: filter, which a match by part of the title picked when FBS_CAMPAIGN_DIR is set).
CONTROL_TITLES = {
    "Harmonic": "Harmonic case",
    "Rounds": "Rounds R",
    "Seed": "Seed",
    "Noise": "Noise level p (%)",
}


def _is(m, title: str) -> bool:
    """Whether model ``m`` is the control called ``title`` (a key of CONTROL_TITLES)."""
    return str(m.title) == CONTROL_TITLES.get(title, title)


def _value(sess: BokehSession, title: str):
    for m in sess.doc.models:
        if "title" in m.properties() and "value" in m.properties() and _is(m, title):
            try:
                return m.value
            except Exception:
                return None
    return None


def _doc_text(sess: BokehSession) -> str:
    parts = []
    for m in sess.doc.models:
        for prop in ("text", "object", "title", "value", "label"):
            if prop in m.properties():
                try:
                    v = getattr(m, prop)
                except Exception:  # a property without a value (e.g. an empty FileInput)
                    continue
                if isinstance(v, str):
                    parts.append(v)
    return "\n".join(parts)


async def _open(base: str, path: str, cookie: str | None, timeout_s: float = 120):
    """A session as a browser opens it: the page (with its URL query), then its websocket."""
    headers = {"Cookie": cookie} if cookie else {}
    t0 = time.monotonic()
    while True:
        status, answer, body, _ = await asyncio.to_thread(
            fetch, base + path, headers=headers, timeout=timeout_s
        )
        if status not in (429, 503) or time.monotonic() - t0 > timeout_s:
            break
        # the page-build budget is spent: wait as the page that reloads itself does
        await asyncio.sleep(float(answer.get("Retry-After", 1)))
    match = re.search(rb'"token":\s*"([^"]+)"', body)
    if status != 200 or match is None:
        raise RuntimeError(f"the page answered HTTP {status} without a session token")
    sess = BokehSession(headers=headers, token=match.group(1).decode())
    await sess.open(base + path.split("?")[0], timeout_s)
    return sess


def attack_url(rep: Report, base: str, app: str, cookie: str, server) -> None:
    rep.section("4. bad URL values (a session each; the values the page then shows)")
    cases = [
        ("h=99", {"Harmonic": (1, 7)}),
        ("h=-1", {"Harmonic": (1, 7)}),
        ("h=abc", {"Harmonic": (1, 7)}),
        ("rounds=1000000000000", {"Rounds": (1, 200_000)}),
        ("rounds=-5", {"Rounds": (1, 200_000)}),
        ("noise=1e308", {}),
        ("noise=nan", {}),
        ("seed=99999999999999999999999", {"Seed": (0, 2**63 - 1)}),
        ("N=7", {}),
        (f"dof={urllib.parse.quote(MARKUP)}", {}),
        ("h=abc&N=100&h=3", {"Harmonic": (3, 3)}),
        ("rounds=bad&h=5&N=100", {"Harmonic": (5, 5)}),
        ("h=2&" + "x=" + "A" * 20_000, {"Harmonic": (2, 2)}),
    ]

    async def one(query, expect):
        log0 = len(server.log()) if server else 0
        t0 = time.perf_counter()
        try:
            sess = await _open(base, f"{app}?{query}", cookie)
        except Exception as exc:
            return f"session did not open: {type(exc).__name__}: {str(exc)[:120]}", None
        try:
            await sess.settle(60, 1.0)
            values = {t: _value(sess, t) for t in ("Harmonic", "Rounds", "Seed", "Noise")}
            text = _doc_text(sess)
            errors = list(sess.errors)
        finally:
            await sess.close()
        secs = time.perf_counter() - t0
        tb = server and "Traceback" in server.log()[log0:]
        ok = not errors and not tb and MARKUP not in text
        for title, (lo, hi) in expect.items():
            v = values.get(title)
            ok = ok and v is not None and lo <= v <= hi
        shown = ", ".join(f"{k}={v!r}" for k, v in values.items() if v is not None)
        extra = []
        if errors:
            extra.append(f"session errors {errors[:2]}")
        if tb:
            extra.append("TRACEBACK in the server log")
        if MARKUP in text:
            extra.append("the markup is reflected into the page")
        return f"{secs:.1f} s; {shown}{'; ' + '; '.join(extra) if extra else ''}", ok

    for query, expect in cases:
        happened, ok = run(one(query, expect))
        rep.line(f"{app}?{query[:70]}{'...' if len(query) > 70 else ''}", happened, ok)


# ---- 5. hostile files --------------------------------------------------------------------------


def _csv(n_freq: int, n_out: int, name_len: int = 1) -> bytes:
    head = "# tire-fbs FRF\n# quantity: mobility\n# units: m/(N s)\n# layout: re-im\n"
    cols = ["freq [Hz]"]
    for o in range(n_out):
        node = f"n{o:0{name_len}d}:z"
        cols += [f"Re({node} / spindle:z)", f"Im({node} / spindle:z)"]
    row = ",".join(["1.0e-3"] * (2 * n_out))
    body = "\n".join(f"{1.0 + k * 0.5},{row}" for k in range(n_freq))
    return (head + ",".join(cols) + "\n" + body + "\n").encode()


def _uff() -> bytes:
    from fbs_core.frf import FRF
    from fbs_core.io import save_frf

    freq = np.arange(1.0, 201.0)
    data = np.ones((freq.size, 2, 2)) * (1 + 1j)
    frf = FRF(freq, data, ["a:z", "b:z"], ["a:z", "b:z"], quantity="mobility")
    return save_frf(frf, format="uff")


def _mat_bomb(zeros_mb: int) -> bytes:
    import scipy.io

    buf = io.BytesIO()
    z = np.zeros((zeros_mb * 2**20) // 16, dtype=complex)
    scipy.io.savemat(buf, {"freq": np.arange(1.0, 3.0), "H": z}, do_compression=True)
    return buf.getvalue()


def _h5_bomb(zeros_mb: int) -> bytes:
    import h5py

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "bomb.h5"
        n = (zeros_mb * 2**20) // 8
        with h5py.File(path, "w") as h:
            h.create_dataset("freq", data=np.arange(1.0, 3.0))
            ds = h.create_dataset("H", shape=(n,), dtype="f8", chunks=(2**20,), compression="gzip")
            ds.attrs["quantity"] = "mobility"
        return path.read_bytes()


class _Evil:
    def __reduce__(self):
        return (print, ("pickle executed on the server",))


def hostile_files(big: bool) -> list[tuple[str, str, str, bytes]]:
    """(what, widget 'chassis'|'tire', file name, content)."""
    uff = _uff()
    pkl = pickle.dumps({"H": _Evil()})
    wide = 50_000 if big else 20_000
    tall = 3_000_000 if big else 300_000
    files = [
        ("wide CSV", "chassis", "wide.csv", _csv(3, wide, 5)),
        ("tall CSV", "chassis", "tall.csv", _csv(tall, 1)),
        ("gzip-compressed CSV", "chassis", "chassis.csv", gzip.compress(_csv(20_000, 12) * 1)),
        ("truncated UFF", "chassis", "chassis.uff", uff[: int(len(uff) * 0.6)]),
        (
            "garbage UFF",
            "chassis",
            "chassis.uff",
            b"    -1\n    58\n" + os.urandom(200_000) + b"\n    -1\n",
        ),
        ("MAT v5 bomb (300 MB of zeros)", "chassis", "chassis.mat", _mat_bomb(300)),
        ("HDF5 bomb (300 MB of zeros)", "chassis", "chassis.h5", _h5_bomb(300)),
        ("pickle named .mat", "chassis", "chassis.mat", pkl),
        ("pickle named .h5", "tire", "tire.h5", pkl),
        ("pickle named .csv", "chassis", "chassis.csv", pkl),
        ("empty file", "chassis", "chassis.uff", b""),
        (
            "markup and a formula in the file name",
            "chassis",
            "=HYPERLINK(1)[x](http://attacker.example)![i](http://attacker.example/i.png).csv",
            b"not a csv",
        ),
    ]
    return files


async def _upload_widget(sess: BokehSession, which: str, timeout_s: float = 120):
    """The page's upload widget ``which`` ("chassis", "tire"), once the page holds it (the
    dashboard builds its data card once the page is shown); None if it never comes."""
    return await sess.find(
        lambda m: (
            type(m).__name__ == "FileInput"
            and f"upload-{which}" in (getattr(m, "css_classes", None) or [])
        ),
        timeout_s,
    )


def _alerts(sess: BokehSession) -> tuple[str, str]:
    """(error text if visible, summary text)."""
    err = summ = ""
    for m in sess.doc.models:
        css = getattr(m, "css_classes", None) or []
        if "upload-error" in css and getattr(m, "visible", True):
            err = str(getattr(m, "text", "") or getattr(m, "object", ""))
        if "upload-summary" in css:
            summ = str(getattr(m, "text", "") or getattr(m, "object", ""))
    return err, summ


async def _upload(sess: BokehSession, widget, name: str, content: bytes) -> None:
    from bokeh.document.events import ModelChangedEvent

    events = []
    for attr, value in (
        ("filename", name),
        ("mime_type", "application/octet-stream"),
        ("value", base64.b64encode(content).decode()),
    ):
        widget.set_from_json(attr, value, setter=sess)
        events.append(ModelChangedEvent(sess.doc, widget, attr, value))
    await sess._send(events)


def attack_files(rep: Report, base: str, app: str, cookie: str, server, big: bool) -> None:
    rep.section("5. hostile files through the upload widgets (a session each)")
    print("  (making the files ...)", flush=True)
    files = hostile_files(big)

    async def one(what, which, name, content):
        sess = await _open(base, app, cookie)
        try:
            await sess.settle(60, 0.5)
            widget = await _upload_widget(sess, which)
            if widget is None:
                return "no upload widget found in the page", False
            err0, summ0 = _alerts(sess)
            log0 = len(server.log()) if server else 0
            wait_s = 300 if content else 15  # an empty file: nothing may happen at all
            t0 = time.perf_counter()
            with MemoryPeak(server) as mem:
                await _upload(sess, widget, name, content)
                answer = None
                while time.perf_counter() - t0 < wait_s:
                    await asyncio.sleep(0.1)
                    err, summ = _alerts(sess)
                    if err != err0 or summ != summ0:
                        await sess.settle(10, 0.3)
                        answer = _alerts(sess)
                        break
            secs = time.perf_counter() - t0
        finally:
            await sess.close()
        if answer is None:
            return f"no answer within {wait_s} s; {mem.text()}", None if not content else False
        err, summ = (html.unescape(t) for t in answer)
        text = re.sub(r"<[^>]+>", " ", err or summ)
        text = re.sub(r"\s+", " ", text).strip()
        markup = [t for t in ("<a ", "<img", "<script") if t in err]
        tb = server is not None and "Traceback" in server.log()[log0:]
        executed = server is not None and "pickle executed" in server.log()[log0:]
        ok = bool(err) and not markup and not tb and not executed
        if server is not None:
            ok = ok and (mem.peak - mem.start) < max(200, 20 * len(content) / 2**20)
        happened = f"{secs:.1f} s; {'refused' if err else 'ACCEPTED'}: {text[:150]!r}; {mem.text()}"
        if markup:
            happened += f"; the alert renders {markup} from the file name"
        if tb:
            happened += "; TRACEBACK in the server log"
        if executed:
            happened += "; THE PICKLE RAN"
        return happened, ok

    for what, which, name, content in files:
        happened, ok = run(one(what, which, name, content))
        rep.line(
            f"{what}: {len(content) / 2**20:.2f} MB as {which} file {name[:40]!r}", happened, ok
        )


# ---- 6. compute flood --------------------------------------------------------------------------


async def _set(sess: BokehSession, title: str, value) -> bool:
    """Set the first model titled ``title`` (a spinner, select, ...) as BokehJS would."""
    from bokeh.document.events import ModelChangedEvent

    for m in sess.doc.models:
        if "title" in m.properties() and "value" in m.properties() and _is(m, title):
            events = []
            for attr in ("value", "value_throttled"):
                if attr in m.properties():
                    m.set_from_json(attr, value, setter=sess)
                    events.append(ModelChangedEvent(sess.doc, m, attr, value))
            await sess._send(events)
            return True
    return False


def _pct(values: list[float], q: float) -> float:
    return float(np.percentile(values, q)) if values else float("nan")


def _model(sess: BokehSession, title: str):
    for m in sess.doc.models:
        if "title" in m.properties() and "value" in m.properties() and _is(m, title):
            return m
    raise LookupError(f"no control titled {title!r} in the page")


def _has(sess: BokehSession, title: str) -> bool:
    try:
        _model(sess, title)
    except LookupError:
        return False
    return True


def _n_slider(sess: BokehSession):
    """The "Retained tire modes N" slider (a discrete slider: its value is the index)."""
    for m in sess.doc.models:
        if type(m).__name__ == "Slider" and m.start == 0 and m.end == 39:
            return m
    raise LookupError("no N slider in the page")


def _dof_buttons(sess: BokehSession):
    """The "Response DOF at the bushing" buttons of the controls (``active`` is the index of
    the DOF); not the campaign card's, which have the same labels."""
    for m in sess.doc.models:
        if (
            type(m).__name__ == "RadioButtonGroup"
            and list(m.labels) == DOF_LABELS
            and "ctl-case-dof" in (getattr(m, "css_classes", None) or [])
        ):
            return m
    raise LookupError("no response DOF buttons in the page")


DOF_LABELS = ["x", "y", "z", "rx", "ry", "rz"]


async def _timed_change(
    sess: BokehSession, changes: dict, timeout_s: float, quiet_s: float = 0.3, raw=()
):
    """Send control changes in one patch, as BokehJS does; (first, settled) in ms.

    ``changes`` maps control titles to values; ``raw`` adds ``(model, attribute, value)``
    changes (controls without a title). ``first``: the first plot-data update;
    ``settled``: the last one before the plots stay quiet for ``quiet_s`` with no
    computation in progress (the scatter band's progress bar off). Both are ``timeout_s``
    if nothing came in time.
    """
    from bokeh.document.events import ModelChangedEvent

    targets = []
    for title, value in changes.items():
        m = _model(sess, title)
        for attr in ("value", "value_throttled"):
            if attr in m.properties():
                targets.append((m, attr, value))
    targets += list(raw)
    events = []
    for m, attr, value in targets:
        m.set_from_json(attr, value, setter=sess)
        events.append(ModelChangedEvent(sess.doc, m, attr, value))
    n0 = len(sess._change_times)
    t0 = time.perf_counter()
    await sess._send(events)
    first = None
    while time.perf_counter() - t0 < timeout_s:
        await asyncio.sleep(0.02)
        if first is None and len(sess._change_times) > n0:
            first = sess._change_times[n0] - t0
        quiet = time.perf_counter() - sess._changed_at > quiet_s
        if first is not None and quiet and not sess._busy():
            return first * 1000, (sess._changed_at - t0) * 1000
    return (timeout_s * 1000 if first is None else first * 1000), timeout_s * 1000


#: The victim's changes in turn: N, the harmonic with a new seed (a band to compute, not
#: a cache hit), the response DOF.
KINDS = ("N", "harmonic", "DOF")


async def _timed_changes(sess: BokehSession, n: int, timeout_s: float, seed0: int):
    """Victim: ``n`` changes of N, harmonic (+ seed) and DOF in turn; (kinds, first, settled)."""
    kinds, first, settled = [], [], []
    current = _value(sess, "Harmonic") or 1
    n_slider, dof = _n_slider(sess), _dof_buttons(sess)
    for k in range(n):
        kind = KINDS[k % 3]
        if kind == "N":  # 50 -> 100 -> 150 -> 50 (indexes 4, 9, 14)
            idx = {4: 9, 9: 14}.get(int(n_slider.value), 4)
            raw = [(n_slider, a, idx) for a in ("value", "value_throttled")]
            f, s = await _timed_change(sess, {}, timeout_s, raw=raw)
        elif kind == "harmonic":
            current = current % 7 + 1
            changes = {"Harmonic": current}
            if _has(sess, "Seed"):  # (a typed field the page may build later)
                changes["Seed"] = seed0 + k
            f, s = await _timed_change(sess, changes, timeout_s)
        else:  # z -> x -> y -> z
            idx = {2: 0, 0: 1}.get(int(dof.active), 2)
            f, s = await _timed_change(sess, {}, timeout_s, raw=[(dof, "active", idx)])
        kinds.append(kind)
        first.append(f)
        settled.append(s)
    return kinds, first, settled


def attack_flood(rep: Report, base: str, app: str, cookie: str, args) -> None:
    rep.section(
        f"6. one session floods the compute ({args.flood_rounds:,}-round bands, "
        f"{args.flood_query}, a new one every {args.flood_every:.0f} s), another "
        f"({args.victim_rounds:,}-round bands) changes N, the harmonic (and the seed) and the "
        f"DOF in turn, {args.flood_changes} times"
    )

    async def main():
        victim = await _open(base, f"{app}?rounds={args.victim_rounds}", cookie)
        await victim.settle(120, 1.0)
        for h in range(2, 9):  # every harmonic once: its truncation map is cached
            await _timed_change(victim, {"Harmonic": (h - 1) % 7 + 1}, 120)
        base_changes = await _timed_changes(victim, args.flood_changes, args.flood_timeout, 10_000)
        query = f"rounds={args.flood_rounds}" + (f"&{args.flood_query}" if args.flood_query else "")
        hostile = await _open(base, f"{app}?{query}", cookie)
        stop = asyncio.Event()
        sent = 0

        async def flood():
            nonlocal sent
            while not stop.is_set():
                await _set(hostile, "Seed", 50_000 + sent)
                sent += 1
                try:
                    await asyncio.wait_for(stop.wait(), args.flood_every)
                except TimeoutError:
                    pass

        task = asyncio.ensure_future(flood())
        await asyncio.sleep(args.flood_every * 6)  # six bands requested before the victim moves
        t0 = time.perf_counter()
        flood_changes = await _timed_changes(victim, args.flood_changes, args.flood_timeout, 20_000)
        secs = time.perf_counter() - t0
        stop.set()
        await task
        errors = victim.errors + hostile.errors
        await hostile.close()
        await victim.close()
        return base_changes, flood_changes, sent, secs, errors

    (kinds, b1, b2), (_, f1, f2), sent, secs, errors = run(main())

    def stats(v):
        return f"p50 {_pct(v, 50):.0f} / p95 {_pct(v, 95):.0f} / max {max(v):.0f} ms"

    def by_kind(v):
        return "; ".join(
            f"{kind} " + " ".join(f"{x:.0f}" for x, k in zip(v, kinds, strict=True) if k == kind)
            for kind in KINDS
        )

    rep.line(
        "victim alone: change -> first plot update; -> settled plots",
        f"{stats(b1)}; {stats(b2)}",
        None,
    )
    rep.line(
        f"victim under the flood ({sent} hostile bands requested in {secs:.0f} s): first update",
        stats(f1),
        _pct(f1, 95) < 1000,
    )
    rep.line("  first update by kind of change (ms)", by_kind(f1), None)
    rep.line(
        "victim under the flood: settled plots (its own scatter band included)",
        stats(f2),
        _pct(f2, 95) < 1000,
    )
    rep.line("  settled by kind of change (ms)", by_kind(f2), None)
    if errors:
        rep.line("session errors during the flood", str(errors[:3]), False)


# ---- 6b. starvation: slow uploads, report floods, body floods -----------------------------


def _stats(v: list[float]) -> str:
    return f"p50 {_pct(v, 50):.0f} / p95 {_pct(v, 95):.0f} / max {max(v):.0f} ms"


def _attack_process(name: str, base: str, app: str, cookie: str, args, stop_flag, out) -> None:
    """Run the attack ``name`` in this (spawned) process until ``stop_flag`` is set; put its
    one-line description into ``out``. A process of its own: the hostile clients' work
    (encoding megabytes of uploads, decoding reports) must not delay the victim's client,
    whose timings are the measurement."""

    async def main():
        stop = asyncio.Event()

        async def watch():
            while not stop_flag.is_set():
                await asyncio.sleep(0.1)
            stop.set()

        watcher = asyncio.ensure_future(watch())
        try:
            return await ATTACKS[name](base, app, cookie, args, stop)
        finally:
            watcher.cancel()

    try:
        out.put(asyncio.run(main()))
    except Exception as exc:  # noqa: BLE001 (said in the report)
        out.put(f"the attack failed: {type(exc).__name__}: {exc}")


def _cpu_s(pid: int) -> float:
    """CPU seconds (user + system) of process ``pid`` and its children that ended."""
    try:
        f = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return float("nan")
    return sum(int(x) for x in f[11:15]) / os.sysconf("SC_CLK_TCK")


def side_by_side(
    rep: Report, base: str, app: str, cookie: str, args, title: str, name: str, server=None
):
    """The victim's control changes alone, then while the attack ``name`` (of
    :data:`ATTACKS`) runs in a process of its own (one run). With the suite's own server,
    also the server's CPU time in each phase (its share of the wall time)."""
    import multiprocessing

    rep.section(title)
    ctx = multiprocessing.get_context("spawn")
    stop_flag, out = ctx.Event(), ctx.Queue()

    async def main():
        victim = await _open(base, f"{app}?rounds={args.victim_rounds}", cookie)
        await victim.settle(120, 1.0)
        for h in range(2, 9):  # every harmonic once: its truncation map is cached
            await _timed_change(victim, {"Harmonic": (h - 1) % 7 + 1}, 120)
        c0, w0 = _cpu(), time.perf_counter()
        alone = await _timed_changes(victim, args.flood_changes, args.flood_timeout, 30_000)
        cpu_alone = (_cpu() - c0) / (time.perf_counter() - w0)
        proc = ctx.Process(
            target=_attack_process, args=(name, base, app, cookie, args, stop_flag, out)
        )
        proc.start()
        await asyncio.sleep(args.attack_warmup)  # the attack under way before the victim moves
        t0, c0 = time.perf_counter(), _cpu()
        under = await _timed_changes(victim, args.flood_changes, args.flood_timeout, 40_000)
        secs = time.perf_counter() - t0
        cpu_under = (_cpu() - c0) / secs
        stop_flag.set()
        what = await asyncio.to_thread(out.get, True, 300)
        await asyncio.to_thread(proc.join, 60)
        errors = list(victim.errors)
        await victim.close()
        return alone, under, secs, what, errors, cpu_alone, cpu_under

    def _cpu() -> float:
        if server is None:
            return float("nan")
        return sum(_cpu_s(p) for p in _tree(server.proc.pid))

    (kinds, a1, a2), (_, u1, u2), secs, what, errors, cpu_a, cpu_u = run(main())
    if server is not None:
        rep.line(
            "server CPU (with its parser and report processes), share of one core",
            f"victim alone {100 * cpu_a:.0f} %, under attack {100 * cpu_u:.0f} %",
            None,
        )
    rep.line(
        "victim alone: change -> first plot update; -> settled plots",
        f"{_stats(a1)}; {_stats(a2)}",
        None,
    )
    rep.line(
        f"victim under attack ({what}; {secs:.0f} s): first update", _stats(u1), _pct(u1, 95) < 1000
    )
    by_kind = "; ".join(
        f"{k} " + " ".join(f"{x:.0f}" for x, kk in zip(u1, kinds, strict=True) if kk == k)
        for k in KINDS
    )
    rep.line("  first update by kind of change (ms)", by_kind, None)
    rep.line("victim under attack: settled plots (its own band included)", _stats(u2), None)
    if errors:
        rep.line("victim session errors", str(errors[:3]), False)


RECORD_58 = """    -1
    58
mobility {o}:z / {i}:z
tire-fbs attack suite
03-Dec-26 10:50:18
NONE
NONE
    4         0    0         0 {o:>10s}         1   3 {i:>10s}         2   3
         6         3         1  1.00000e+00  1.00000e+00  0.00000e+00
        18    0    0    0 NONE                 Hz
        11    1    0    0 NONE                 m/s
        13    0    1    0 NONE                 N
         0    0    0    0 NONE                 NONE
   1.00000000000e-03   0.00000000000e+00   1.00000000000e-03   0.00000000000e+00
   1.00000000000e-03   0.00000000000e+00
    -1
"""


def slow_uff(n: int) -> bytes:
    """A valid UFF of ``n`` datasets 58: the parser needs seconds per 10,000 (the issue's
    slow file was an HDF5 file of 3,000 nested groups, now refused in seconds)."""
    return "".join(RECORD_58.format(o=f"n{k % 100}", i=f"m{k // 100}") for k in range(n)).encode()


def nested_h5(depth: int) -> bytes:
    """A valid HDF5 file of ``depth`` nested groups (the issue's slow file: h5py's visit took
    minutes; now refused in seconds, naming the nesting limit)."""
    import h5py

    b = io.BytesIO()
    with h5py.File(b, "w") as h:
        g = h
        for k in range(depth):
            g = g.create_group(f"g{k}")
        h.create_dataset("freq", data=np.arange(1.0, 4.0))
    return b.getvalue()


def _upload_file(args) -> tuple[bytes, str, str]:
    if args.upload_file == "nested":
        return nested_h5(3000), "slow{}.h5", "an HDF5 file of 3,000 nested groups"
    what = f"a valid UFF of {args.upload_records:,} datasets 58"
    return slow_uff(args.upload_records), "slow{}.uff", what


async def _uploads_attack(base, app, cookie, args, stop) -> str:
    content, name, _ = _upload_file(args)
    tabs = [await _open(base, app, cookie) for _ in range(args.attack_tabs)]
    sent = 0
    try:
        while not stop.is_set():
            for sess in tabs:
                widget = await _upload_widget(sess, "chassis")
                await _upload(sess, widget, name.format(sent), content)
                sent += 1
            try:
                await asyncio.wait_for(stop.wait(), args.upload_every)
            except TimeoutError:
                pass
    finally:
        for sess in tabs:
            await sess.close()  # closed tabs: their readings are cancelled
    return f"{args.attack_tabs} tabs sent {sent} uploads of {len(content) / 2**20:.1f} MB"


def attack_uploads(rep: Report, base: str, app: str, cookie: str, args, server=None) -> None:
    what = _upload_file(args)[2]
    side_by_side(
        rep,
        base,
        app,
        cookie,
        args,
        f"6b. {args.attack_tabs} tabs upload {what} every {args.upload_every:.0f} s while "
        "another session changes N, harmonic, DOF",
        "uploads",
        server,
    )


def _report_button(sess, kind: str = "pdf"):
    for m in sess.doc.models:
        if (
            f"report-{kind}" in (getattr(m, "css_classes", None) or [])
            and "clicks" in m.properties()
        ):
            return m
    raise LookupError(f"no report-{kind} download in the page")


async def _reports_attack(base, app, cookie, args, stop) -> str:
    from bokeh.document.events import ModelChangedEvent

    tabs = [await _open(base, app, cookie) for _ in range(args.attack_tabs)]
    done = 0

    async def loop(sess):
        nonlocal done
        btn = _report_button(sess)
        while not stop.is_set():
            data0 = btn.data
            clicks = int(btn.clicks or 0) + 1
            btn.set_from_json("clicks", clicks, setter=sess)
            await sess.send([ModelChangedEvent(sess.doc, btn, "clicks", clicks)])
            t0 = time.perf_counter()
            while btn.data == data0 and time.perf_counter() - t0 < 120 and not stop.is_set():
                await asyncio.sleep(0.1)
            done += btn.data != data0

    try:
        await asyncio.gather(*(loop(sess) for sess in tabs))
    finally:
        for sess in tabs:
            await sess.close()
    return f"{args.attack_tabs} tabs asked for PDF reports in a loop, {done} delivered"


def attack_reports(rep: Report, base: str, app: str, cookie: str, args, server=None) -> None:
    side_by_side(
        rep,
        base,
        app,
        cookie,
        args,
        f"6c. {args.attack_tabs} tabs ask for PDF reports in a loop while another session "
        "changes N, harmonic, DOF",
        "reports",
        server,
    )


async def _bodies_attack(base, app, cookie, args, stop) -> str:
    port = int(urllib.parse.urlparse(base).port or 80)
    size = args.body_mb << 20

    def one_body(stop: threading.Event) -> str:
        chunk = b"x" * (1 << 20)
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=30) as s:
                s.sendall(
                    b"POST /login HTTP/1.1\r\nHost: x\r\n"
                    b"Content-Type: application/x-www-form-urlencoded\r\n"
                    + f"Content-Length: {size}\r\n\r\n".encode()
                )
                sent = 0
                while sent < size and not stop.is_set():
                    s.sendall(chunk)
                    sent += len(chunk)
                return s.recv(64).split(b"\r\n")[0].decode("latin-1")
        except OSError as exc:  # the server closed the connection: the body was refused
            return f"closed ({type(exc).__name__})"

    flag = threading.Event()
    answers: Counter = Counter()

    def flood():
        while not flag.is_set():
            answers[one_body(flag)] += 1

    threads = [threading.Thread(target=flood, daemon=True) for _ in range(args.body_connections)]
    for t in threads:
        t.start()
    await stop.wait()
    flag.set()
    for t in threads:
        await asyncio.to_thread(t.join, 30)
    return (
        f"{args.body_connections} unauthenticated connections posting {args.body_mb} MB "
        f"bodies in a loop: {dict(answers.most_common(3))}"
    )


def attack_bodies(rep: Report, base: str, app: str, cookie: str, args, server=None) -> None:
    side_by_side(
        rep,
        base,
        app,
        cookie,
        args,
        f"6d. unauthenticated body flood ({args.body_connections} connections, "
        f"{args.body_mb} MB bodies) while a logged-in session changes N, harmonic, DOF",
        "bodies",
        server,
    )


# ---- 9. connections held open, page builds without a websocket, giant messages ---------------

#: The start of a request whose headers never end (slowloris).
PARTIAL_HEAD = b"GET /liveness HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: "


async def _slowloris_attack(base, app, cookie, args, stop) -> str:
    """Up to ``--slow-connections`` connections (from 50 loopback addresses) that never
    finish their headers, topped up as the server closes them, until ``stop``."""
    import resource
    import select

    port = int(urllib.parse.urlparse(base).port or 80)
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    try:
        resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))
    except (ValueError, OSError):
        hard = soft
    n = max(1, min(args.slow_connections, hard - 200))
    flag = threading.Event()
    held: dict[int, socket.socket] = {}
    counts = Counter()
    most = 0

    def run() -> None:
        nonlocal most
        poll = select.poll()
        k = 0
        t0 = time.monotonic()
        while not flag.is_set() and time.monotonic() - t0 < args.slow_seconds:
            while len(held) < n and not flag.is_set():
                s = socket.socket()
                try:
                    s.bind((f"127.0.0.{2 + k % 50}", 0))
                    k += 1
                    s.settimeout(5)
                    s.connect(("127.0.0.1", port))
                    s.sendall(PARTIAL_HEAD)
                except OSError:
                    s.close()
                    counts["connect failed"] += 1
                    break
                held[s.fileno()] = s
                poll.register(s, select.POLLIN | select.POLLHUP)
            most = max(most, len(held))
            for fd, _ in poll.poll(200):
                s = held.pop(fd)
                poll.unregister(fd)
                try:
                    data = s.recv(64)
                except OSError:
                    data = b""
                counts["refused 503" if data.startswith(b"HTTP/1.1 503") else "closed"] += 1
                s.close()
            flag.wait(0.5)  # a slowloris, not a connection flood: top up twice a second
        for s in held.values():
            s.close()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    while thread.is_alive() and not stop.is_set():
        await asyncio.sleep(0.2)
    flag.set()
    await asyncio.to_thread(thread.join, 30)
    return f"{n} connections that never finish their headers: at most {most} held; {dict(counts)}"


def attack_slowloris(rep: Report, base: str, app: str, cookie: str, args, server=None) -> None:
    fds = ""
    if server is not None:
        fds = f" (server file descriptors before: {len(os.listdir(f'/proc/{server.proc.pid}/fd'))})"
    side_by_side(
        rep,
        base,
        app,
        cookie,
        args,
        f"9a. slowloris: {args.slow_connections} connections that never finish their headers "
        f"while a logged-in session changes N, harmonic, DOF{fds}",
        "slowloris",
        server,
    )
    if server is not None:
        t0 = time.perf_counter()
        status = fetch(base + "/liveness", timeout=30)[0]
        rep.line(
            "after the attack: server file descriptors; /liveness",
            f"{len(os.listdir(f'/proc/{server.proc.pid}/fd'))}; HTTP {status} in "
            f"{(time.perf_counter() - t0) * 1000:.0f} ms",
            status == 200,
        )


async def _reloads_attack(base, app, cookie, args, stop) -> str:
    """``--reload-loops`` loops of ``GET app`` with the login, never opening the websocket."""
    counts = Counter()

    async def loop() -> None:
        while not stop.is_set():
            status = (
                await asyncio.to_thread(fetch, base + app, headers={"Cookie": cookie}, timeout=60)
            )[0]
            counts[status] += 1
            if status != 200:  # refused: what a browser's reload would do after Retry-After
                await asyncio.sleep(0.2)

    await asyncio.gather(*(loop() for _ in range(args.reload_loops)))
    return f"{args.reload_loops} loops of GET {app} without a websocket: answers {dict(counts)}"


def attack_reloads(rep: Report, base: str, app: str, cookie: str, args, server=None) -> None:
    import copy

    for loops in (2, 4):
        a = copy.copy(args)
        a.reload_loops = loops
        side_by_side(
            rep,
            base,
            app,
            cookie,
            a,
            f"9b. {loops} loops of GET {app} by a logged-in user (pages built, never opened) "
            "while another session changes N, harmonic, DOF",
            "reloads",
            server,
        )


def attack_giant(rep: Report, base: str, app: str, cookie: str, server=None, mb: int = 147):
    """One websocket frame declaring ``mb`` MB (a fake upload), sent until the server closes
    the connection: bytes it took, its memory, and whether a session opens after."""
    import struct

    rep.section(f"9c. one websocket message declaring {mb} MB (a fake upload)")
    from bokeh.util.token import generate_jwt_token, generate_session_id

    port = int(urllib.parse.urlparse(base).port or 80)
    token = generate_jwt_token(generate_session_id(), signed=False)
    key = base64.b64encode(os.urandom(16)).decode()
    size, chunk = mb * 1_000_000, 1 << 20
    mask = os.urandom(4)
    block = np.frombuffer(b"a" * chunk, np.uint8) ^ np.frombuffer(mask * (chunk // 4), np.uint8)
    block = block.tobytes()
    sent = 0
    with MemoryPeak(server) as mem:
        t0 = time.perf_counter()
        with socket.create_connection(("127.0.0.1", port), timeout=30) as s:
            s.sendall(
                (
                    f"GET {app}/ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
                    "Upgrade: websocket\r\nConnection: Upgrade\r\n"
                    f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
                    f"Sec-WebSocket-Protocol: bokeh, {token}\r\nOrigin: {base}\r\n"
                    f"Cookie: {cookie}\r\n\r\n"
                ).encode()
            )
            head = s.recv(4096)
            if not head.startswith(b"HTTP/1.1 101"):
                rep.line("websocket handshake", head[:80].decode("latin-1"), False)
                return
            try:
                s.sendall(struct.pack("!BBQ", 0x81, 0x80 | 127, size) + mask)
                while sent < size:
                    s.sendall(block[: min(chunk, size - sent)])
                    sent += min(chunk, size - sent)
            except OSError:
                pass
        secs = time.perf_counter() - t0
        time.sleep(1.0)  # what the server does with what it read
    closed = sent < size
    grew = None if server is None else mem.peak - mem.start
    rep.line(
        f"a frame declaring {mb} MB, sent until the server closes the connection",
        f"{sent / 1e6:.1f} MB sent in {secs:.1f} s "
        f"({'closed by the server' if closed else 'ALL READ'}); {mem.text()}",
        closed and (grew is None or grew < 100),
    )
    ws = run(ws_status(base, app, cookie))
    rep.line("then another session of the same user", ws, ws.startswith("ACK"))


#: The starvation attacks, each run in a process of its own by :func:`side_by_side`.
ATTACKS = {
    "uploads": _uploads_attack,
    "reports": _reports_attack,
    "bodies": _bodies_attack,
    "slowloris": _slowloris_attack,
    "reloads": _reloads_attack,
}


# ---- 7. login flood ----------------------------------------------------------------------------


def attack_logins(rep: Report, base: str, user: str, password: str | None, server) -> None:
    rep.section("7. login flood: 200 wrong logins at once from one client")
    client = "203.0.113.7"  # honoured only behind --use-xheaders (the suite's own server)
    log0 = len(server.log()) if server else 0

    def attempt(k):
        data, headers = login_form(base, user, f"wrong-{k}", {"X-Real-IP": client})
        return fetch(base + "/login", data=data, headers=headers, timeout=120)

    t0 = time.perf_counter()
    with concurrent.futures.ThreadPoolExecutor(20) as pool:
        results = list(pool.map(attempt, range(200)))
    secs = time.perf_counter() - t0
    statuses = Counter(r[0] for r in results)
    held = sorted(r[3] for r in results)
    rep.line(
        "200 wrong passwords, 20 at a time",
        f"{secs:.1f} s in all; answers {dict(statuses)}; median answer "
        f"{held[len(held) // 2]:.2f} s, slowest {held[-1]:.2f} s",
        statuses.get(429, 0) > 0,
    )
    if password:
        data, headers = login_form(base, user, password, {"X-Real-IP": client})
        status = fetch(base + "/login", data=data, headers=headers)[0]
        rep.line(
            "then the right password from the same client",
            f"HTTP {status} ({'refused while locked' if status == 429 else 'let in'})",
            status == 429,
        )
    if server is not None:
        new = server.log()[log0:]
        failed = new.count("failed login:")
        refused = new.count("login refused:")
        rep.line(
            "the server log",
            f"{failed} 'failed login' lines, {refused} 'login refused' lines",
            failed > 0,
        )


# ---- 8. SIGTERM --------------------------------------------------------------------------------


def attack_sigterm(rep: Report, server) -> None:
    rep.section("8. SIGTERM after all this (docker stop waits 10 s, then kills)")
    tree = _tree(server.proc.pid)
    t0 = time.perf_counter()
    server.proc.send_signal(signal.SIGTERM)
    try:
        server.proc.wait(60)
        secs = time.perf_counter() - t0
        left = [p for p in tree[1:] if Path(f"/proc/{p}").exists()]
        rep.line(
            f"SIGTERM to the server ({len(tree) - 1} child processes)",
            f"ended after {secs:.1f} s, exit status {server.proc.returncode}, "
            f"{len(left)} children left",
            secs < 10 and not left,
        )
    except subprocess.TimeoutExpired:
        rep.line("SIGTERM to the server", "still running after 60 s (killed)", False)


# ---- main --------------------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    import faulthandler

    faulthandler.register(signal.SIGUSR1, all_threads=True)  # kill -USR1: where it waits
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--url", help="attack a running server instead of starting one")
    ap.add_argument("--user", default=None)
    ap.add_argument("--password", default=None)
    ap.add_argument("--threads", type=int, default=4, help="FBS_NUM_THREADS of its own server")
    ap.add_argument("--only", nargs="+", choices=SECTIONS, help="run only these sections")
    ap.add_argument("--big", action="store_true", help="the issue's file sizes (slow)")
    ap.add_argument("--flood-rounds", type=int, default=200_000)
    ap.add_argument("--flood-every", type=float, default=1.0, help="s between hostile bands")
    ap.add_argument(
        "--flood-query",
        default="h=7&fdep=true",
        help="URL settings of the hostile session besides rounds (default: harmonic 7, "
        "frequency-dependent noise)",
    )
    ap.add_argument("--flood-changes", type=int, default=10)
    ap.add_argument("--victim-rounds", type=int, default=1_000, help="rounds of the victim's band")
    ap.add_argument("--flood-timeout", type=float, default=30.0, help="s per victim change")
    ap.add_argument("--campaign-dir", help="FBS_CAMPAIGN_DIR of its own server")
    ap.add_argument("--attack-tabs", type=int, default=4, help="hostile tabs (uploads, reports)")
    ap.add_argument("--attack-warmup", type=float, default=6.0, help="s of attack before timing")
    ap.add_argument("--upload-file", choices=("nested", "uff"), default="nested")
    ap.add_argument("--upload-records", type=int, default=40_000, help="datasets of the slow UFF")
    ap.add_argument("--upload-every", type=float, default=2.0, help="s between a tab's uploads")
    ap.add_argument("--body-mb", type=int, default=90)
    ap.add_argument("--body-connections", type=int, default=2)
    ap.add_argument("--slow-connections", type=int, default=3500, help="slowloris sockets")
    ap.add_argument("--slow-seconds", type=float, default=300, help="slowloris at most (s)")
    ap.add_argument("--giant-mb", type=int, default=147, help="declared websocket message")
    args = ap.parse_args(argv)
    sections = set(args.only or SECTIONS)
    rep = Report()
    server = None
    if args.url:
        base, user, password, secret = args.url.rstrip("/"), args.user, args.password, None
    else:
        print("starting the server (docker/entrypoint.py, basic auth, random credentials) ...")
        server = LocalServer(args.threads, args.campaign_dir)
        base, user = server.base, server.user
        password, secret = server.password, server.secret
        print(f"server up in {server.start_s:.1f} s at {base} (pid {server.proc.pid})")
    try:
        cookie = login(base, user, password) if user and password else None
        app = app_path(base, cookie)
        print(f"app {app}; logged in: {cookie is not None}; machine: {os.cpu_count()} cores")
        if "endpoints" in sections:
            attack_endpoints(rep, base, app, server)
        if "cookies" in sections:
            attack_cookies(rep, base, app, user or "admin", secret)
        if cookie and "origin" in sections:
            attack_origin(rep, base, app, cookie)
        if "url" in sections:
            attack_url(rep, base, app, cookie, server)
        if "files" in sections:
            attack_files(rep, base, app, cookie, server, args.big)
        if "flood" in sections:
            attack_flood(rep, base, app, cookie, args)
        if "uploads" in sections:
            attack_uploads(rep, base, app, cookie, args, server)
        if "reports" in sections:
            attack_reports(rep, base, app, cookie, args, server)
        if "bodies" in sections:
            attack_bodies(rep, base, app, cookie, args, server)
        if cookie and "slowloris" in sections:
            attack_slowloris(rep, base, app, cookie, args, server)
        if cookie and "reloads" in sections:
            attack_reloads(rep, base, app, cookie, args, server)
        if cookie and "giant" in sections:
            attack_giant(rep, base, app, cookie, server, args.giant_mb)
        if "logins" in sections:
            attack_logins(rep, base, user or "admin", password, server)
        if server is not None and "sigterm" in sections:
            attack_sigterm(rep, server)
    finally:
        if server is not None:
            server.stop()
    print(f"\n{len(rep.findings)} finding(s)")
    for f in rep.findings:
        print(f"  - {f}")
    return 1 if rep.findings else 0


if __name__ == "__main__":
    sys.exit(main())
