"""Access control of the deployment (docker/entrypoint.py), tested without Docker.

The container's entrypoint turns ``FBS_*`` environment variables into a ``panel serve``
command line. Here it is run as a subprocess on a free loopback port with basic
authentication on, serving a small Panel script, and checked from outside like a browser
would be: without credentials there is no app content and no websocket; after logging in
through the login form the page and the websocket work. The settings parser is tested
directly (every refused value has a ``pytest.raises``).
"""

from __future__ import annotations

import asyncio
import http.cookiejar
import importlib.util
import json
import os
import re
import socket
import stat
import subprocess
import sys
import time
import urllib.error
import urllib.parse
import urllib.request
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SPEC = importlib.util.spec_from_file_location("fbs_entrypoint", ROOT / "docker" / "entrypoint.py")
entrypoint = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(entrypoint)
SettingError = entrypoint.SettingError

USER, PASSWORD = "reviewer", "Tyre:Chassis-2026"  # a ':' inside the password on purpose
SECRET = "-" + "s" * 39  # a leading "-" on purpose (token_urlsafe makes one in 64)

APP = """
import numpy as np
import panel as pn
from bokeh.plotting import figure

slider = pn.widgets.IntSlider(name="k", start=1, end=5, value=2)
fig = figure(height=200, width=300)
x = np.linspace(0.0, 1.0, 20)
line = fig.line(x, np.sin(2 * x))
slider.param.watch(lambda e: line.data_source.data.update(y=np.sin(e.new * x)), "value")
pn.Column("# confidential-model-marker", slider, fig).servable()
"""


# ---- the settings parser ------------------------------------------------------------------


def test_parse_users_accepts_commas_newlines_and_colons_in_passwords():
    users = entrypoint.parse_users("alice:pw:with:colons, bob:x\n carol:y ,")
    assert users == {"alice": "pw:with:colons", "bob": "x", "carol": "y"}


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("alice", "not of the form user:password"),
        (":pw", "not of the form user:password"),
        ("alice:", "not of the form user:password"),
        ("alice:a,alice:b", "'alice' is given twice"),
        (" , \n", "holds no user:password entry"),
    ],
)
def test_parse_users_rejects(text, match):
    with pytest.raises(SettingError, match=match):
        entrypoint.parse_users(text)


@pytest.fixture
def app_file(tmp_path):
    path = tmp_path / "fbsapp.py"
    path.write_text(APP)
    return path


def test_default_command(app_file):
    cmd, warnings = entrypoint.build_command({"FBS_APP": str(app_file)}, ["--dev-flag"])
    assert cmd[1:3] == ["serve", str(app_file)]
    joined = " ".join(cmd)
    assert "--address 0.0.0.0 --port 5006 --liveness --num-threads 4" in joined
    assert not any(a.startswith(("--basic-auth", "--cookie-secret")) for a in cmd)
    # uploads up to 150 MB fit one message (base64), beyond fbs_core's 100 MiB limit
    assert f"--websocket-max-message-size {200 * 1024 * 1024}" in joined
    assert cmd[-1] == "--dev-flag" and warnings == []


def _option(cmd: list[str], name: str) -> str:
    """The value of ``name=value`` on a command line (exactly one such argument)."""
    values = [a.split("=", 1)[1] for a in cmd if a.startswith(name + "=")]
    assert len(values) == 1 and name not in cmd, cmd
    return values[0]


def test_basic_auth_users_go_to_a_private_file_not_the_command_line(app_file):
    env = {
        "FBS_APP": str(app_file),
        "FBS_BASIC_AUTH": f"{USER}:{PASSWORD}",
        "FBS_COOKIE_SECRET": SECRET,
    }
    cmd, _ = entrypoint.build_command(env, [])
    assert PASSWORD not in " ".join(cmd)
    users_file = Path(_option(cmd, "--basic-auth"))
    assert json.loads(users_file.read_text()) == {USER: PASSWORD}
    assert stat.S_IMODE(users_file.stat().st_mode) == 0o600
    assert _option(cmd, "--cookie-secret") == SECRET
    assert SECRET not in entrypoint.masked(cmd)


def test_auth_without_secret_makes_a_random_one(app_file):
    env = {"FBS_APP": str(app_file), "FBS_BASIC_AUTH": "a:b"}
    cmd1, warnings = entrypoint.build_command(env, [])
    cmd2, _ = entrypoint.build_command(env, [])
    s1, s2 = (_option(c, "--cookie-secret") for c in (cmd1, cmd2))
    assert len(s1) >= entrypoint.MIN_SECRET_LEN and s1 != s2
    assert any("FBS_COOKIE_SECRET" in w for w in warnings)


@pytest.mark.parametrize(
    ("env", "match"),
    [
        ({"FBS_BASIC_AUTH": "a:b", "FBS_BASIC_AUTH_FILE": "/x.json"}, "not both"),
        ({"PANEL_BASIC_AUTH": "pw"}, "lower-cases"),
        ({"FBS_BASIC_AUTH": "a:b", "PANEL_OAUTH_PROVIDER": "github"}, "exclude each other"),
        ({"FBS_BASIC_AUTH": "a:b", "FBS_COOKIE_SECRET": "short"}, "at least 32 characters"),
        ({"FBS_COOKIE_SECRET": SECRET, "PANEL_COOKIE_SECRET": SECRET}, "not both"),
        ({"FBS_NUM_THREADS": "0"}, "FBS_NUM_THREADS='0': must be an integer >= 1"),
        ({"FBS_NUM_THREADS": "four"}, "must be an integer >= 1"),
        ({"FBS_PORT": "-1"}, "FBS_PORT"),
        ({"FBS_LOG_LEVEL": "loud"}, "allowed values are debug, info"),
        ({"FBS_USE_XHEADERS": "maybe"}, "FBS_USE_XHEADERS='maybe': allowed values"),
        ({"FBS_WEBSOCKET_MAX_MESSAGE_MB": "0"}, "FBS_WEBSOCKET_MAX_MESSAGE_MB"),
        ({"FBS_BASIC_AUTH_FILE": "/nonexistent/users.json"}, "cannot be read"),
        ({"FBS_APP": "/nonexistent/main.py"}, "does not exist"),
    ],
)
def test_refused_settings(app_file, env, match):
    env = {"FBS_APP": str(app_file), **env}
    with pytest.raises(SettingError, match=match):
        entrypoint.build_command(env, [])


@pytest.mark.parametrize("content", ['["alice", "pw"]', "{}", '{"alice": 3}', "not json"])
def test_refused_users_file(app_file, tmp_path, content):
    users = tmp_path / "users.json"
    users.write_text(content)
    with pytest.raises(SettingError, match="FBS_BASIC_AUTH_FILE"):
        entrypoint.build_command({"FBS_APP": str(app_file), "FBS_BASIC_AUTH_FILE": str(users)}, [])


# ---- the served app with authentication on -----------------------------------------------


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class _NoRedirect(urllib.request.HTTPRedirectHandler):
    def redirect_request(self, *args, **kwargs):
        return None


def _run_async(coro):
    """Run ``coro`` to completion on a fresh event loop in its own thread.

    ``asyncio.run`` refuses to start inside a running loop, and pytest-playwright's sync API
    leaves one running in a worker that has already run browser tests.
    """
    import concurrent.futures

    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as pool:
        return pool.submit(asyncio.run, coro).result()


def _get(opener, url):
    """(status, location header, body) without following redirects."""
    try:
        with opener.open(url, timeout=30) as r:
            return r.status, r.headers.get("Location"), r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.headers.get("Location"), e.read().decode()


async def _websocket_session(
    port: int, cookie: str | None, token: str | None = None
) -> tuple[str, str]:
    """Open the app's Bokeh websocket as bokehjs does, then pull the document.

    Returns the type of the server's first message and the pulled document's content.
    Bokeh messages are three frames: header, metadata, content.
    """
    from bokeh.util.token import generate_jwt_token, generate_session_id
    from tornado.httpclient import HTTPRequest
    from tornado.websocket import websocket_connect

    headers = {"Origin": f"http://127.0.0.1:{port}"}
    if cookie:
        headers["Cookie"] = cookie
    token = token or generate_jwt_token(generate_session_id(), signed=False)
    request = HTTPRequest(f"ws://127.0.0.1:{port}/fbsapp/ws", headers=headers)
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


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    folder = tmp_path_factory.mktemp("authapp")
    app = folder / "fbsapp.py"
    app.write_text(APP)
    port = _free_port()
    env = {
        **os.environ,
        "FBS_APP": str(app),
        "FBS_PORT": str(port),
        "FBS_ADDRESS": "127.0.0.1",
        "FBS_BASIC_AUTH": f"{USER}:{PASSWORD}",
        "FBS_COOKIE_SECRET": SECRET,
        "FBS_NUM_THREADS": "2",
        "BOKEH_ALLOW_WS_ORIGIN": f"127.0.0.1:{port}",
    }
    log = open(folder / "server.log", "w+")  # noqa: SIM115 (closed below)
    proc = subprocess.Popen(
        [sys.executable, str(ROOT / "docker" / "entrypoint.py")],
        env=env,
        stdout=log,
        stderr=subprocess.STDOUT,
    )
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 25
        while True:
            try:
                with urllib.request.urlopen(base + "/liveness", timeout=2) as r:
                    if r.status == 200:
                        break
            except OSError:
                pass
            if proc.poll() is not None or time.monotonic() > deadline:
                log.seek(0)
                pytest.fail(f"panel serve did not start:\n{log.read()}")
            time.sleep(0.2)
        yield base, port
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        log.close()


def test_without_credentials_no_app_content_and_no_websocket(server):
    base, port = server
    opener = urllib.request.build_opener(_NoRedirect)
    for path in ("/", "/fbsapp", "/fbsapp/autoload.js?bokeh-autoload-element=x"):
        status, location, body = _get(opener, base + path)
        assert status in (302, 401, 403), (path, status)
        assert "render_items" not in body and "confidential-model-marker" not in body
        if status == 302:
            assert "login" in location
    status, _, body = _get(urllib.request.build_opener(), base + "/fbsapp")  # follow
    assert status == 200 and 'name="password"' in body
    assert "render_items" not in body and "confidential-model-marker" not in body
    with pytest.raises(Exception, match="403"):
        _run_async(_websocket_session(port, cookie=None))
    # the health endpoint stays open (Docker's HEALTHCHECK), and tells nothing of the app
    status, _, body = _get(opener, base + "/liveness")
    assert status == 200 and json.loads(body) == {"/liveness": True}


def test_wrong_password_gets_no_session_cookie(server):
    base, _ = server
    jar = http.cookiejar.CookieJar()
    opener = urllib.request.build_opener(_NoRedirect, urllib.request.HTTPCookieProcessor(jar))
    data = urllib.parse.urlencode({"username": USER, "password": PASSWORD + "x"}).encode()
    try:
        opener.open(base + "/login", data=data, timeout=30)
    except urllib.error.HTTPError as e:
        assert e.code == 302 and "error" in e.headers["Location"]
    assert "user" not in {c.name for c in jar}
    status, location, body = _get(opener, base + "/fbsapp")
    assert status == 302 and "login" in location and "render_items" not in body


def test_with_credentials_the_app_and_its_websocket_work(server):
    base, port = server
    jar = http.cookiejar.CookieJar()
    opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor(jar))
    data = urllib.parse.urlencode({"username": USER, "password": PASSWORD}).encode()
    with opener.open(base + "/login", data=data, timeout=30) as r:
        assert r.status == 200
    assert "user" in {c.name for c in jar}
    status, _, body = _get(opener, base + "/fbsapp")
    # Panel's page carries a session token; the document itself comes over the websocket
    assert status == 200 and "render_items" in body
    token = re.search(r'"token":\s*"([^"]+)"', body).group(1)
    cookie = "; ".join(f"{c.name}={c.value}" for c in jar)
    first, document = _run_async(_websocket_session(port, cookie, token))
    assert first == "ACK"
    assert "confidential-model-marker" in document and "ColumnDataSource" in document
