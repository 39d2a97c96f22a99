"""The deployed server under attack: health check, secrets, forged cookies, login flooding.

Issue 20, findings 2, 7 and 9. The server is started as in the container
(``docker/entrypoint.py``, basic authentication on) on a free loopback port, serving a small
Panel script that counts the pages it builds and starts a child process per page (as the
file-parser sandbox does), and is attacked from outside:

- ``/liveness?endpoint=...`` without login must not build a page: the app is proved once,
  at start, and a script that fails stops the server;
- the cookie secret and the passwords must not be readable from the command line or the
  environment of any process of the server (``ps``, ``docker top``, ``/proc``);
- a cookie not signed with the server's secret gives no access (checked against one signed
  with it, which does: the forging method is right);
- wrong logins are logged and slowed per client, then refused (HTTP 429), without locking
  out other clients.
"""

from __future__ import annotations

import base64
import json
import re
import sys
import time
import urllib.parse
import urllib.request
from pathlib import Path

import pytest
from server_util import (
    NoRedirect,
    Server,
    get,
    process_tree,
    run_async,
    wait_for,
    websocket_session,
)

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docker"))
import fbs_server  # noqa: E402

USER, PASSWORD = "reviewer", "Tyre:Chassis-2026-pw"
SECRET = "cookie-" + "k" * 40
MAX_FAILURES = 5

# counts its page builds in COUNT_FILE and starts a child per page that lives as long as
# its parent (reads its stdin until EOF), like the sandbox worker
APP = """
import os, subprocess, sys
from pathlib import Path
import panel as pn

count = Path(__file__).with_name("builds.txt")
count.write_text(str(int(count.read_text() or 0) + 1) if count.exists() else "1")
subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()"], stdin=subprocess.PIPE)
pn.Column("# confidential-model-marker", pn.widgets.IntSlider(name="k", value=2)).servable()
"""


def _builds(server: Server) -> int:
    path = server.folder / "builds.txt"
    return int(path.read_text()) if path.exists() else 0


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    srv = Server(
        tmp_path_factory.mktemp("secapp"),
        APP,
        {
            "FBS_BASIC_AUTH": f"{USER}:{PASSWORD}",
            "FBS_COOKIE_SECRET": SECRET,
            "FBS_LOGIN_MAX_FAILURES": str(MAX_FAILURES),
            # clients told apart by X-Real-IP, as behind a reverse proxy
            "FBS_USE_XHEADERS": "true",
        },
    )
    try:
        yield srv.started()
    finally:
        srv.stop()


# ---- health check ------------------------------------------------------------------------


def test_health_check_answers_without_login_and_builds_no_page(server):
    opener = urllib.request.build_opener(NoRedirect)
    assert _builds(server) == 1  # the proof at start
    for _ in range(20):
        status, _, body = get(opener, server.base + "/liveness?endpoint=/fbsapp")
        assert status == 200 and json.loads(body) == {"/fbsapp": True}
        status, _, body = get(opener, server.base + "/liveness")
        assert status == 200 and json.loads(body) == {"/liveness": True}
    assert _builds(server) == 1
    status, _, body = get(opener, server.base + "/liveness?endpoint=/nothing%3Cb%3E")
    assert status == 400 and "<b>" not in body and json.loads(body)["endpoints"] == ["/fbsapp"]


def test_an_app_that_cannot_build_a_page_stops_the_server(tmp_path):
    srv = Server(tmp_path, "raise RuntimeError('broken-app-marker')\n", {})
    try:
        srv.proc.wait(120)
        assert srv.proc.returncode != 0
        assert "failed to build a page" in srv.log() and "broken-app-marker" in srv.log()
    finally:
        srv.stop()


# ---- secrets -------------------------------------------------------------------------------


def _read(path: str) -> bytes:
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError:
        return b""


def test_secrets_are_not_on_any_command_line_or_environment(server):
    # a page load starts a child process (as an upload starts the parser sandbox)
    opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor())
    data = urllib.parse.urlencode({"username": USER, "password": PASSWORD}).encode()
    assert get(opener, server.base + "/login", data=data)[0] == 200
    builds = _builds(server)
    assert builds >= 2  # the proof at start and this page: a child each

    def tree():
        pids = process_tree(server.proc.pid)
        return pids if len(pids) > builds else None

    pids = wait_for(tree, 30, what="the children of the server")
    for pid in pids:
        for what in ("cmdline", "environ"):
            content = _read(f"/proc/{pid}/{what}")
            assert content, (pid, what)
            for secret in (SECRET, PASSWORD):
                assert secret.encode() not in content, f"{secret!r} in /proc/{pid}/{what}"


# ---- forged cookies ----------------------------------------------------------------------


def _signed(secret: str, name: str, value: str) -> str:
    from tornado.web import create_signed_value

    return create_signed_value(secret, name, value).decode()


def _page_with_cookie(server, cookie: str):
    opener = urllib.request.build_opener(NoRedirect)
    return get(opener, server.base + "/fbsapp", headers={"Cookie": cookie})


def test_a_cookie_signed_with_another_secret_gives_no_access(server):
    # control: a cookie signed with the server's secret is accepted (the forging is right)
    good = f"user={_signed(SECRET, 'user', USER)}"
    status, _, body = _page_with_cookie(server, good)
    assert status == 200 and "render_items" in body
    token = re.search(r'"token":\s*"([^"]+)"', body).group(1)
    first, document = run_async(websocket_session(server.port, "fbsapp", good, token))
    assert first == "ACK" and "confidential-model-marker" in document

    wrong_secret = f"user={_signed('x' * 40, 'user', USER)}"
    # a signature made for one user, the value of another
    b64 = base64.b64encode(USER.encode()).decode()
    other = base64.b64encode(b"admin").decode()
    tampered = good.replace(f"{len(b64)}:{b64}", f"{len(other)}:{other}")
    assert tampered != good
    unsigned = f"user={USER}"
    for cookie in (wrong_secret, tampered, unsigned):
        status, headers, body = _page_with_cookie(server, cookie)
        assert status == 302 and "login" in headers["Location"], cookie
        assert "render_items" not in body and "confidential-model-marker" not in body
        with pytest.raises(Exception, match="403"):
            run_async(websocket_session(server.port, "fbsapp", cookie))


def test_a_websocket_from_another_origin_is_refused(server):
    good = f"user={_signed(SECRET, 'user', USER)}"
    _, _, body = _page_with_cookie(server, good)
    token = re.search(r'"token":\s*"([^"]+)"', body).group(1)
    with pytest.raises(Exception, match="403"):
        run_async(
            websocket_session(
                server.port, "fbsapp", good, token, origin="http://attacker.example:5006"
            )
        )


# ---- login flooding ----------------------------------------------------------------------


def _login(server, client_ip: str, username: str, password: str):
    """(status, headers, seconds) of a login POST from ``client_ip``."""
    opener = urllib.request.build_opener(NoRedirect)
    data = urllib.parse.urlencode({"username": username, "password": password}).encode()
    t0 = time.monotonic()
    status, headers, _ = get(
        opener, server.base + "/login", data=data, headers={"X-Real-IP": client_ip}
    )
    return status, headers, time.monotonic() - t0


def test_wrong_logins_are_logged_slowed_and_then_refused(server):
    attacker, other = "10.9.8.7", "10.9.8.6"
    held = []
    for k in range(1, MAX_FAILURES + 1):
        status, headers, seconds = _login(server, attacker, USER, f"guess-{k}")
        assert status == 302 and "error" in headers["Location"]
        held.append(seconds)
    # the 4th and later wrong answers are held (0.5 s, 1 s, ...): a lower bound, safe on a
    # busy machine
    for k in range(fbs_server.LOGIN_FREE_FAILURES + 1, MAX_FAILURES + 1):
        assert held[k - 1] >= fbs_server.LoginThrottle.delay(k) * 0.95, held
    # now refused, even with the right password (which is not checked)
    status, headers, _ = _login(server, attacker, USER, PASSWORD)
    assert status == 429 and int(headers["Retry-After"]) > 0
    # another client is not locked out
    status, headers, _ = _login(server, other, USER, PASSWORD)
    assert status == 302 and "error" not in headers["Location"]
    log = server.log()
    assert f"failed login: user {USER!r} from {attacker} ({MAX_FAILURES} failures" in log
    assert f"login refused: client {attacker}" in log
    assert "guess-" not in log and PASSWORD not in log  # passwords are never logged


def test_a_user_name_cannot_forge_log_lines(server):
    _login(server, "10.9.8.5", "x\n2026-01-01 00:00:00,000 login: user 'admin'", "pw")
    lines = [ln for ln in server.log().splitlines() if "from 10.9.8.5" in ln]
    assert len(lines) == 1 and "x\\n2026" in lines[0]


# ---- the throttle and the password check on their own --------------------------------------


class _Clock:
    def __init__(self):
        self.t = 1000.0

    def __call__(self):
        return self.t


def test_throttle_window_and_clients():
    clock = _Clock()
    throttle = fbs_server.LoginThrottle(max_failures=3, window_s=60.0, clock=clock)
    assert throttle.failed("a") == 1  # t = 1000
    clock.t += 5
    assert throttle.failed("a") == 2  # t = 1005
    assert throttle.retry_after("a") == 0.0
    clock.t += 5
    assert throttle.failed("a") == 3  # t = 1010: locked until the first ages out (1060)
    assert throttle.retry_after("a") == pytest.approx(50.0)
    assert throttle.retry_after("b") == 0.0
    clock.t += 50.0  # t = 1060: the first failure aged out
    assert throttle.retry_after("a") == 0.0 and throttle.failed("a") == 3
    throttle.succeeded("a")
    assert throttle.failed("a") == 1
    delays = [fbs_server.LoginThrottle.delay(k) for k in range(1, 10)]
    assert delays == [0, 0, 0, 0.5, 1, 2, 4, 8, 8]
    with pytest.raises(ValueError, match="max_failures"):
        fbs_server.LoginThrottle(max_failures=0)


def test_throttle_forgets_the_oldest_clients_beyond_its_size(monkeypatch):
    monkeypatch.setattr(fbs_server, "LOGIN_MAX_CLIENTS", 3)
    throttle = fbs_server.LoginThrottle(max_failures=1)
    for client in "abcd":
        throttle.failed(client)
    assert throttle.retry_after("a") == 0.0  # dropped
    assert all(throttle.retry_after(c) > 0 for c in "bcd")


def test_check_password(tmp_path):
    users = {"alice": "pw-1", "bob": "p\u00e4ss"}
    path = tmp_path / "users.json"
    path.write_text(json.dumps(users))
    for source in (users, str(path)):
        assert fbs_server.check_password(source, "alice", "pw-1")
        assert fbs_server.check_password(source, "bob", "p\u00e4ss")
        assert not fbs_server.check_password(source, "alice", "pw-2")
        assert not fbs_server.check_password(source, "alice", "")
        assert not fbs_server.check_password(source, "carol", "pw-1")
        assert not fbs_server.check_password(source, "carol", "\0pw-1")
