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
import os
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
    form_token,
    get,
    login_post,
    process_tree,
    run_async,
    wait_for,
    websocket_session,
)

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docker"))
import fbs_auth  # noqa: E402
import fbs_server  # noqa: E402

USER, PASSWORD = "reviewer", "Tyre:Chassis-2026-pw"
OTHER_USER, OTHER_PASSWORD = "colleague", "Second-user-pw-2026"
SECRET = "cookie-" + "k" * 40
MAX_FAILURES = 5

# counts its page builds in COUNT_FILE and starts a child per page that lives as long as
# its parent (reads its stdin until EOF), like the sandbox worker; a page asked for with
# ?exit=1 raises SystemExit while it is built (what importing venv.__main__ did: issue 28)
APP = """
import os, subprocess, sys
from pathlib import Path
import panel as pn

count = Path(__file__).with_name("builds.txt")
count.write_text(str(int(count.read_text() or 0) + 1) if count.exists() else "1")
if pn.state.session_args.get("exit"):
    raise SystemExit(2)
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
            "FBS_BASIC_AUTH": f"{USER}:{PASSWORD},{OTHER_USER}:{OTHER_PASSWORD}",
            "FBS_COOKIE_SECRET": SECRET,
            "FBS_LOGIN_MAX_FAILURES": str(MAX_FAILURES),
            # clients told apart by X-Forwarded-For, as behind a reverse proxy: the tests
            # connect from 127.0.0.1, the trusted proxy
            "FBS_USE_XHEADERS": "true",
            "FBS_TRUSTED_PROXIES": "127.0.0.1",
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


def test_the_port_opens_before_the_app_is_proved(tmp_path):
    """Issue 33: the server listens within seconds; the app's proof (one page built, the
    server's warm-up) runs after, and ``/liveness?endpoint=`` says so until it is done."""
    gate = tmp_path / "gate"
    app = (
        "import pathlib, time\n"
        f"gate = pathlib.Path({str(gate)!r})\n"
        "t0 = time.monotonic()\n"
        "while not gate.exists() and time.monotonic() - t0 < 300:\n"
        "    time.sleep(0.05)\n"
        "import panel as pn\n"
        "pn.pane.Markdown('slow app').servable()\n"
    )
    srv = Server(tmp_path, app, {}, name="slowapp")
    try:
        srv.listening(120)  # with the proof held at its gate
        opener = urllib.request.build_opener(NoRedirect)
        status, _, body = get(opener, srv.base + "/liveness?endpoint=/slowapp")
        assert status == 503 and json.loads(body) == {"/slowapp": False}
        status, _, body = get(opener, srv.base + "/liveness?endpoint=/other")
        assert status == 400 and json.loads(body)["endpoints"] == ["/slowapp"]
        gate.write_text("open")
        srv.started(120)
        status, _, body = get(opener, srv.base + "/liveness?endpoint=/slowapp")
        assert status == 200 and json.loads(body) == {"/slowapp": True}
    finally:
        srv.stop()


def test_an_app_that_cannot_build_a_page_stops_the_server(tmp_path):
    srv = Server(tmp_path, "raise RuntimeError('broken-app-marker')\n", {})
    try:
        srv.proc.wait(120)
        assert srv.proc.returncode != 0
        assert "failed to build a page" in srv.log() and "broken-app-marker" in srv.log()
    finally:
        srv.stop()


def test_an_app_whose_page_fails_when_loaded_stops_the_server(tmp_path):
    """The proof loads its page as a browser would (Bokeh's "document ready"): a page whose
    on-load callback fails (the dashboard builds what is below its first screen there)
    stops the server with the error, as a script that fails does."""
    app = (
        "import panel as pn\n"
        "def fail():\n"
        "    raise RuntimeError('broken-onload-marker')\n"
        "pn.state.onload(fail)\n"
        "pn.pane.Markdown('a page').servable()\n"
    )
    srv = Server(tmp_path, app, {})
    try:
        srv.proc.wait(120)
        assert srv.proc.returncode != 0
        log = srv.log()
        assert "failed when its page was loaded" in log and "broken-onload-marker" in log
    finally:
        srv.stop()


def test_the_proof_reports_the_app_once_its_page_is_loaded(tmp_path):
    """``/liveness?endpoint=`` answers 200 only after the proof's page ran its on-load
    callbacks (held here at a gate: 503 meanwhile)."""
    gate, loaded = tmp_path / "gate", tmp_path / "loaded"
    app = (
        "import pathlib, time\n"
        "import panel as pn\n"
        "def load():\n"
        f"    gate = pathlib.Path({str(gate)!r})\n"
        "    t0 = time.monotonic()\n"
        "    while not gate.exists() and time.monotonic() - t0 < 300:\n"
        "        time.sleep(0.05)\n"
        f"    pathlib.Path({str(loaded)!r}).write_text('loaded')\n"
        "pn.state.onload(load)\n"
        "pn.pane.Markdown('a page').servable()\n"
    )
    srv = Server(tmp_path, app, {}, name="gatedapp")
    try:
        srv.listening(120)
        opener = urllib.request.build_opener(NoRedirect)
        # the script ran (the port is open, its proof started); its page is not loaded yet
        status, _, body = get(opener, srv.base + "/liveness?endpoint=/gatedapp")
        assert status == 503 and not loaded.exists()
        gate.write_text("open")
        srv.started(120)
        assert loaded.read_text() == "loaded"
    finally:
        srv.stop()


def test_the_apps_imports_are_loaded_before_the_port_opens(tmp_path):
    """Issue 33: the modules the app script imports, and the submodules it imports from a
    package, are imported on the server's main thread before it listens, so that the first
    page does not wait for them (the proof imports on a thread of its own, after the port
    is open); a name imported from a package that is not a module is left alone."""
    marker = (
        "import pathlib, threading\n"
        "pathlib.Path({0!r}).joinpath(__name__ + '.txt').write_text("
        "threading.current_thread().name)\n"
    )
    (tmp_path / "marker_mod.py").write_text(marker.format(str(tmp_path)))
    (tmp_path / "markerpkg").mkdir()
    (tmp_path / "markerpkg" / "__init__.py").write_text("def helper():\n    return 1\n")
    (tmp_path / "markerpkg" / "sub.py").write_text(marker.format(str(tmp_path)))
    app = (
        "import marker_mod\n"
        "from markerpkg import helper, sub\n"
        "import panel as pn\n"
        "pn.pane.Markdown('a page').servable()\n"
    )
    env = {"PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    srv = Server(tmp_path, app, env)
    try:
        srv.started(120)
        assert (tmp_path / "marker_mod.txt").read_text() == "MainThread"
        assert (tmp_path / "markerpkg.sub.txt").read_text() == "MainThread"
        log = srv.log()
        assert "the apps' imports preloaded" in log
        assert "preloading" not in log.replace("the apps' imports preloaded", "")
    finally:
        srv.stop()


def test_a_preloaded_modules_warm_up_runs_before_the_port_opens(tmp_path):
    """Issue 33: a module the script imports may define ``warm_before_serving()`` (the
    dashboard computes its default page's results there); the server calls it on its main
    thread after preloading and before its port opens; one that fails is logged, and the
    server goes on (the proof reports a broken app)."""
    (tmp_path / "warm_mod.py").write_text(
        "import os, pathlib, socket, threading\n"
        "def warm_before_serving():\n"
        "    with socket.socket() as s:\n"
        "        port_open = s.connect_ex(('127.0.0.1', int(os.environ['FBS_PORT']))) == 0\n"
        f"    pathlib.Path({str(tmp_path)!r}, 'warm.txt').write_text(\n"
        "        f'{threading.current_thread().name} port open: {port_open}')\n"
    )
    (tmp_path / "broken_warm.py").write_text(
        "def warm_before_serving():\n    raise RuntimeError('warm-marker')\n"
    )
    app = (
        "import warm_mod, broken_warm\nimport panel as pn\npn.pane.Markdown('a page').servable()\n"
    )
    env = {"PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    srv = Server(tmp_path, app, env)
    try:
        srv.started(120)
        assert (tmp_path / "warm.txt").read_text() == "MainThread port open: False"
        log = srv.log()
        assert "warm_mod.warm_before_serving (" in log
        assert "broken_warm.warm_before_serving failed: warm-marker" in log
        assert log.index("warm_mod.warm_before_serving (") < log.index("Bokeh app running")
    finally:
        srv.stop()


def test_script_imports_reads_the_top_level_imports(tmp_path):
    script = tmp_path / "s.py"
    script.write_text(
        "from __future__ import annotations\n"
        "import os, json as j\n"
        "from pathlib import Path\n"
        "from . import sibling\n"
        "import os\n"
        "def f():\n"
        "    import csv\n"
    )
    assert fbs_server.script_imports(str(script)) == ["os", "json", "pathlib"]
    assert fbs_server.script_submodules(str(script)) == ["pathlib.Path"]


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
    assert login_post(opener, server.base, USER, PASSWORD)[0] == 200
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


def _login_cookies(secret: str = SECRET, user: str = USER, password: str = PASSWORD) -> str:
    """Both login cookies as the server sets them, made here with the secret."""
    token = fbs_auth.login_token(secret, user, password)
    return f"user={_signed(secret, 'user', user)}; fbs_login={_signed(secret, 'fbs_login', token)}"


def _page_with_cookie(server, cookie: str):
    opener = urllib.request.build_opener(NoRedirect)
    return get(opener, server.base + "/fbsapp", headers={"Cookie": cookie})


def test_a_cookie_signed_with_another_secret_gives_no_access(server):
    # control: cookies signed with the server's secret are accepted (the forging is right)
    good = _login_cookies()
    status, _, body = _page_with_cookie(server, good)
    assert status == 200 and "render_items" in body
    token = re.search(r'"token":\s*"([^"]+)"', body).group(1)
    first, document = run_async(websocket_session(server.port, "fbsapp", good, token))
    assert first == "ACK" and "confidential-model-marker" in document

    wrong_secret = _login_cookies("x" * 40)
    # a signature made for one user, the value of another
    b64 = base64.b64encode(USER.encode()).decode()
    other = base64.b64encode(b"admin").decode()
    tampered = good.replace(f"{len(b64)}:{b64}", f"{len(other)}:{other}")
    assert tampered != good
    unsigned = f"user={USER}"
    # Panel's user cookie alone (a cookie of before issue 28): not a login here
    user_only = f"user={_signed(SECRET, 'user', USER)}"
    for cookie in (wrong_secret, tampered, unsigned, user_only):
        status, headers, body = _page_with_cookie(server, cookie)
        assert status == 302 and "login" in headers["Location"], cookie
        assert "render_items" not in body and "confidential-model-marker" not in body
        with pytest.raises(Exception, match="403"):
            run_async(websocket_session(server.port, "fbsapp", cookie))


def test_a_websocket_from_another_origin_is_refused(server):
    good = _login_cookies()
    _, _, body = _page_with_cookie(server, good)
    token = re.search(r'"token":\s*"([^"]+)"', body).group(1)
    with pytest.raises(Exception, match="403"):
        run_async(
            websocket_session(
                server.port, "fbsapp", good, token, origin="http://attacker.example:5006"
            )
        )


# ---- login flooding ----------------------------------------------------------------------


def _login(server, client_ip: str, username: str, password: str, header="X-Forwarded-For"):
    """(status, headers, seconds) of a login POST from ``client_ip`` (as the proxy says)."""
    opener = urllib.request.build_opener(NoRedirect)
    t0 = time.monotonic()
    status, headers, _ = login_post(
        opener, server.base, username, password, headers={header: client_ip}
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
    for k in range(fbs_auth.LOGIN_FREE_FAILURES + 1, MAX_FAILURES + 1):
        assert held[k - 1] >= fbs_auth.LoginThrottle.delay(k) * 0.95, held
    # now refused, even with the right password (which is not checked)
    status, headers, _ = _login(server, attacker, USER, PASSWORD)
    assert status == 429 and int(headers["Retry-After"]) > 0
    # another client is not locked out, nor another user of the same address (a NAT)
    status, headers, _ = _login(server, other, USER, PASSWORD)
    assert status == 302 and "error" not in headers["Location"]
    status, headers, _ = _login(server, attacker, OTHER_USER, OTHER_PASSWORD)
    assert status == 302 and "error" not in headers["Location"]
    log = server.log()
    assert f"failed login: user {USER!r} from {attacker} ({MAX_FAILURES} failures" in log
    assert f"login refused: client {attacker}, user {USER!r}" in log
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


def test_throttle_window_pairs_and_clients():
    clock = _Clock()
    throttle = fbs_auth.LoginThrottle(max_failures=3, window_s=60.0, clock=clock)
    assert throttle.failed("a", "u") == 1  # t = 1000
    clock.t += 5
    assert throttle.failed("a", "u") == 2  # t = 1005
    assert throttle.retry_after("a", "u") == 0.0
    clock.t += 5
    assert throttle.failed("a", "u") == 3  # t = 1010: locked until the first ages out (1060)
    assert throttle.retry_after("a", "u") == pytest.approx(50.0)
    # neither another client nor another user of the same client is locked
    assert throttle.retry_after("b", "u") == 0.0 and throttle.retry_after("a", "v") == 0.0
    clock.t += 50.0  # t = 1060: the first failure aged out
    assert throttle.retry_after("a", "u") == 0.0 and throttle.failed("a", "u") == 3
    throttle.succeeded("a", "u")
    assert throttle.failed("a", "u") == 1
    delays = [fbs_auth.LoginThrottle.delay(k) for k in range(1, 10)]
    assert delays == [0, 0, 0, 0.5, 1, 2, 4, 8, 8]
    with pytest.raises(ValueError, match="max_failures"):
        fbs_auth.LoginThrottle(max_failures=0)
    with pytest.raises(ValueError, match="global_failures"):
        fbs_auth.LoginThrottle(global_failures=0)


def test_throttle_across_all_clients_refuses_only_clients_that_failed():
    clock = _Clock()
    throttle = fbs_auth.LoginThrottle(
        max_failures=10, window_s=60.0, global_failures=20, clock=clock
    )
    # many addresses guessing, each below its own limit
    for k in range(20):
        for _ in range(fbs_auth.LOGIN_FREE_FAILURES):
            throttle.failed(f"10.0.0.{k}", f"user{k}")
    # a guessing address is refused at once, with any user name ...
    assert throttle.retry_after("10.0.0.3", "someone-else") > 0
    # ... a client without failures is not (a colleague behind the same NAT logs in)
    assert throttle.retry_after("10.0.1.1", "user3") == 0.0
    clock.t += 61  # the failures age out
    assert throttle.retry_after("10.0.0.3", "someone-else") == 0.0


def test_throttle_forgets_the_oldest_pairs_beyond_its_size(monkeypatch):
    monkeypatch.setattr(fbs_auth, "LOGIN_MAX_CLIENTS", 3)
    throttle = fbs_auth.LoginThrottle(max_failures=1)
    for client in "abcd":
        throttle.failed(client, "u")
    assert throttle.retry_after("a", "u") == 0.0  # dropped
    assert all(throttle.retry_after(c, "u") > 0 for c in "bcd")


class _Headers(dict):
    def get_list(self, name):
        v = self.get(name)
        return [] if v is None else [v]


@pytest.mark.parametrize(
    ("peer", "headers", "client"),
    [
        # directly connected: the headers are the client's own claim, never believed
        ("203.0.113.9", {"X-Forwarded-For": "10.1.1.1", "X-Real-Ip": "10.1.1.2"}, "203.0.113.9"),
        # from the trusted proxy: the address it appended (the last hop)
        ("127.0.0.1", {"X-Forwarded-For": "10.1.1.1"}, "10.1.1.1"),
        # a client's own X-Forwarded-For before the proxy's entry is not believed
        ("127.0.0.1", {"X-Forwarded-For": "6.6.6.6, 10.1.1.1"}, "10.1.1.1"),
        # two trusted proxies in a row: the first untrusted hop from the right
        ("127.0.0.1", {"X-Forwarded-For": "10.1.1.1, 172.18.0.5"}, "10.1.1.1"),
        # no X-Forwarded-For: X-Real-IP of the proxy
        ("127.0.0.1", {"X-Real-Ip": "10.1.1.3"}, "10.1.1.3"),
        # garbage where the proxy writes: the proxy itself
        ("127.0.0.1", {"X-Forwarded-For": "not-an-address"}, "127.0.0.1"),
        ("127.0.0.1", {}, "127.0.0.1"),
    ],
)
def test_client_address_believes_forwarding_headers_only_from_trusted_proxies(
    peer, headers, client
):
    proxies = fbs_auth.parse_networks("127.0.0.1, 172.18.0.0/16")
    assert fbs_auth.client_address(peer, _Headers(headers), proxies) == client


def test_trusted_proxies_are_checked():
    with pytest.raises(ValueError, match="'proxy.example'"):
        fbs_auth.parse_networks("10.0.0.1, proxy.example")


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


# ---- issue 28: what a request may not do ---------------------------------------------------


def _form_login(base: str, user: str, password: str) -> str:
    import http.cookiejar

    jar = http.cookiejar.CookieJar()
    opener = urllib.request.build_opener(NoRedirect, urllib.request.HTTPCookieProcessor(jar))
    assert login_post(opener, base, user, password)[0] == 302
    return "; ".join(f"{c.name}={c.value}" for c in jar)


def _logged_in(base: str, cookie: str) -> bool:
    status, _, body = get(
        urllib.request.build_opener(NoRedirect), base + "/fbsapp", headers={"Cookie": cookie}
    )
    return status == 200 and "render_items" in body


def test_a_page_that_raises_system_exit_does_not_end_the_server(server):
    cookie = _login_cookies()
    req = urllib.request.Request(server.base + "/fbsapp?exit=1", headers={"Cookie": cookie})
    log0 = len(server.log())
    try:  # the request itself gets no page (its handler ended): cut it short
        urllib.request.build_opener(NoRedirect).open(req, timeout=5).read()
    except OSError:
        pass
    wait_for(lambda: "SystemExit escaped" in server.log()[log0:], 60, what="the log line")
    assert server.alive(), server.log()[-2000:]
    assert _logged_in(server.base, cookie)  # and it serves the next page


def test_logout_revokes_the_login_cookie(server):
    cookie = _form_login(server.base, OTHER_USER, OTHER_PASSWORD)
    assert _logged_in(server.base, cookie)
    opener = urllib.request.build_opener(NoRedirect)
    token, csrf = form_token(server.base, "/logout", headers={"Cookie": cookie})
    data = urllib.parse.urlencode({"_csrf": token}).encode()
    status = get(
        opener, server.base + "/logout", data=data, headers={"Cookie": f"{cookie}; {csrf}"}
    )
    assert status[0] == 200
    # the same cookie, kept (stolen) after the logout, is no login any more
    assert not _logged_in(server.base, cookie)
    with pytest.raises(Exception, match="403"):
        run_async(websocket_session(server.port, "fbsapp", cookie))
    # a new login works
    assert _logged_in(server.base, _form_login(server.base, OTHER_USER, OTHER_PASSWORD))


@pytest.fixture(scope="module")
def direct_server(tmp_path_factory):
    """Behind a proxy that is not the tests' address: the tests connect directly, and the
    login comes from a users file that the tests change."""
    folder = tmp_path_factory.mktemp("direct")
    users = folder / "users.json"
    users.write_text(json.dumps({USER: PASSWORD, OTHER_USER: OTHER_PASSWORD}))
    srv = Server(
        folder,
        "import panel as pn\npn.Column('# confidential-model-marker').servable()\n",
        {
            "FBS_BASIC_AUTH_FILE": str(users),
            "FBS_COOKIE_SECRET": SECRET,
            "FBS_LOGIN_MAX_FAILURES": str(MAX_FAILURES),
            "FBS_USE_XHEADERS": "true",
            "FBS_TRUSTED_PROXIES": "10.255.0.1",
        },
    )
    srv.users = users
    try:
        yield srv.started()
    finally:
        srv.stop()


def test_a_direct_client_cannot_pick_its_address_with_forwarding_headers(direct_server):
    srv = direct_server
    statuses = []
    for k in range(MAX_FAILURES + 2):
        header = "X-Forwarded-For" if k % 2 else "X-Real-IP"
        statuses.append(_login(srv, f"10.77.0.{k}", USER, f"guess-{k}", header=header)[0])
    # every guess counted against the real address: refused after MAX_FAILURES
    assert statuses[:MAX_FAILURES] == [302] * MAX_FAILURES and statuses[-1] == 429, statuses
    assert "from 127.0.0.1" in srv.log() and "from 10.77.0." not in srv.log()


def _cookie_lines(headers) -> dict[str, set[str]]:
    """name -> attributes (lower case) of a response's Set-Cookie headers."""
    out = {}
    for v in headers.get_all("Set-Cookie") or []:
        name, _, rest = v.partition("=")
        out[name] = {a.strip().lower() for a in rest.split(";")[1:]}
    return out


def test_cookies_are_secure_when_a_trusted_proxy_says_https(server, direct_server):
    """Behind a TLS-terminating proxy (X-Forwarded-Proto: https from a trusted proxy) the
    login and form cookies are Secure; a direct client's header is ignored (the cookies stay
    usable over its plain HTTP)."""
    https = {"X-Forwarded-Proto": "https"}
    for srv, secure in ((server, True), (direct_server, False)):
        opener = urllib.request.build_opener(NoRedirect)
        status, headers, _ = login_post(opener, srv.base, OTHER_USER, OTHER_PASSWORD, https)
        assert status == 302
        got = _cookie_lines(headers)
        for name in ("user", "fbs_login"):
            assert {"httponly", "samesite=lax"} <= got[name], got
            assert ("secure" in got[name]) is secure, (srv.base, got)
        status, headers, _ = get(opener, srv.base + "/login", headers=https)
        assert ("secure" in _cookie_lines(headers)["fbs_csrf"]) is secure


def test_removing_a_user_or_changing_the_password_revokes_the_cookies(direct_server):
    srv = direct_server
    a = _form_login(srv.base, OTHER_USER, OTHER_PASSWORD)
    assert _logged_in(srv.base, a)
    # the password changed in the users file: the old cookie is no login
    srv.users.write_text(json.dumps({USER: PASSWORD, OTHER_USER: OTHER_PASSWORD + "-new"}))
    assert not _logged_in(srv.base, a)
    b = _form_login(srv.base, OTHER_USER, OTHER_PASSWORD + "-new")
    assert _logged_in(srv.base, b)
    # the user removed
    srv.users.write_text(json.dumps({USER: PASSWORD}))
    assert not _logged_in(srv.base, b)


# ---- issue 42: giant websocket messages ------------------------------------------------------


def _rss_mb(pid: int) -> float:
    for line in _read(f"/proc/{pid}/status").decode().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def _raw_websocket(server, cookie: str):
    """A websocket of the app opened by hand (a socket: frames of any declared size)."""
    import socket

    from bokeh.util.token import generate_jwt_token, generate_session_id

    token = generate_jwt_token(generate_session_id(), signed=False)
    key = base64.b64encode(os.urandom(16)).decode()
    s = socket.create_connection(("127.0.0.1", server.port), timeout=30)
    s.sendall(
        (
            f"GET /fbsapp/ws HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\n"
            "Upgrade: websocket\r\nConnection: Upgrade\r\n"
            f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
            f"Sec-WebSocket-Protocol: bokeh, {token}\r\n"
            f"Origin: http://127.0.0.1:{server.port}\r\nCookie: {cookie}\r\n\r\n"
        ).encode()
    )
    head = b""
    while b"\r\n\r\n" not in head:
        chunk = s.recv(4096)
        assert chunk, head
        head += chunk
    assert head.startswith(b"HTTP/1.1 101"), head[:200]
    return s


def _frame_header(opcode: int, length: int, mask: bytes) -> bytes:
    import struct

    return struct.pack("!BBQ", 0x80 | opcode, 0x80 | 127, length) + mask


def _send_until_closed(s, chunks, deadline_s: float) -> int:
    """Send ``chunks`` until the server closes the connection; bytes sent."""
    sent = 0
    t0 = time.monotonic()
    try:
        for chunk in chunks:
            s.sendall(chunk)
            sent += len(chunk)
            if time.monotonic() - t0 > deadline_s:
                break
    except OSError:  # closed by the server (reset or broken pipe)
        pass
    return sent


def _masked(payload: bytes, mask: bytes) -> bytes:
    import numpy as np

    m = np.frombuffer(mask * (len(payload) // 4), dtype=np.uint8)
    return (np.frombuffer(payload, dtype=np.uint8) ^ m).tobytes()


def test_a_frame_declaring_150_mb_is_refused_before_it_is_read(server):
    """A websocket frame whose header declares 150 MB (a fake upload above the largest a
    file may need) closes the connection before its payload is read: the server's memory
    does not grow by it (it took 0.98 -> 2.2 GB), the refusal is logged with the client's
    address, and another session works."""
    import threading

    cookie = _login_cookies()
    size, chunk = 150_000_000, 1 << 20
    mask = os.urandom(4)
    payload = _masked(b"a" * chunk, mask)
    rss0 = _rss_mb(server.proc.pid)
    peak = [rss0]
    stop = threading.Event()

    def sample():
        while not stop.wait(0.02):
            peak[0] = max(peak[0], _rss_mb(server.proc.pid))

    log0 = len(server.log())
    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    s = _raw_websocket(server, cookie)
    try:
        chunks = [_frame_header(0x1, size, mask)] + [payload] * (size // chunk)
        chunks.append(payload[: size % chunk])
        sent = _send_until_closed(s, chunks, 120)
        time.sleep(1.0)  # (the peak of what the server does with what it read)
    finally:
        s.close()
        stop.set()
        sampler.join()
    assert peak[0] - rss0 < 100, f"server memory {rss0:.0f} -> {peak[0]:.0f} MB"
    assert sent < 50_000_000, f"{sent:,} bytes of the frame were sent and read"
    mark = "websocket of 127.0.0.1 closed:"
    wait_for(lambda: mark in server.log()[log0:], 30, what="the log line")
    line = next(ln for ln in server.log()[log0:].splitlines() if mark in ln)
    assert "declared above the limit" in line, line
    _, document = run_async(websocket_session(server.port, "fbsapp", cookie))
    assert "confidential-model-marker" in document and server.alive()


def test_a_bokeh_message_of_many_buffers_is_bounded_in_all(server):
    """A Bokeh message is a header, metadata, content and the buffers its header announces,
    each a websocket message of its own: buffers each under the size limit but above it in
    all (4 x 50 MB) close the connection with a logged reason once their sum is above."""
    import json as _json

    cookie = _login_cookies()
    mask = os.urandom(4)

    def text(obj) -> bytes:
        raw = _json.dumps(obj).encode()
        raw += b" " * (-len(raw) % 4)
        return _frame_header(0x1, len(raw), mask) + _masked(raw, mask)

    buffer = 50_000_000
    block = _masked(b"\0" * (1 << 20), mask)
    chunks = [text({"msgid": "m1", "msgtype": "PATCH-DOC", "num_buffers": 4}), text({}), text({})]
    for k in range(4):
        chunks.append(text({"id": f"b{k}"}))
        chunks.append(_frame_header(0x2, buffer, mask))
        chunks += [block] * (buffer >> 20)
        chunks.append(_masked(b"\0" * (buffer - (buffer >> 20 << 20)), mask))
    log0 = len(server.log())
    s = _raw_websocket(server, cookie)
    try:
        _send_until_closed(s, chunks, 120)
    finally:
        s.close()
    wait_for(lambda: "a Bokeh message of more than" in server.log()[log0:], 60, what="the log")
    _, document = run_async(websocket_session(server.port, "fbsapp", cookie))
    assert "confidential-model-marker" in document and server.alive()


# ---- issue 42: connections held open (slowloris) ---------------------------------------------

#: The start of a request whose headers never end.
PARTIAL = b"GET /liveness HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: "


def _held(source: str, port: int, n: int) -> list:
    """``n`` connections from the loopback address ``source``, each with a partial head."""
    import socket

    out = []
    for _ in range(n):
        s = socket.socket()
        s.bind((source, 0))
        s.settimeout(30)
        s.connect(("127.0.0.1", port))
        try:
            s.sendall(PARTIAL)
        except OSError:  # refused and closed at once
            pass
        out.append(s)
    return out


def _answer(s, timeout_s: float) -> bytes | None:
    """What the server sent before closing ``s`` (b"" for a plain close), or None if the
    connection is still open after ``timeout_s``."""
    s.settimeout(timeout_s)
    data = b""
    try:
        while True:
            chunk = s.recv(4096)
            if not chunk:
                return data
            data += chunk
    except TimeoutError:
        return None
    except OSError:  # reset
        return data


def test_connections_that_never_finish_their_headers_are_capped_and_closed(tmp_path):
    """Slowloris: connections that never finish their headers stayed open for ever. Now a
    client holds at most FBS_MAX_CONNECTIONS_PER_CLIENT, all clients FBS_MAX_CONNECTIONS;
    beyond, a connection is answered 503 and closed at once (logged once per interval);
    and the server closes the held ones FBS_HEADER_TIMEOUT_S after they opened."""
    srv = Server(
        tmp_path,
        "import panel as pn\npn.pane.Markdown('a page').servable()\n",
        {
            "FBS_MAX_CONNECTIONS_PER_CLIENT": "20",
            "FBS_MAX_CONNECTIONS": "30",
            "FBS_HEADER_TIMEOUT_S": "8",
        },
    )
    held: list = []
    try:
        srv.started(120)
        log0 = len(srv.log())
        t0 = time.monotonic()
        a = _held("127.0.0.2", srv.port, 25)  # 5 above the cap of a client
        b = _held("127.0.0.3", srv.port, 15)  # 5 above the cap of all (30)
        held = a + b
        import select

        def closed():  # the connections the server closed so far
            return [k for k, s in enumerate(held) if select.select([s], [], [], 0)[0]]

        wait_for(lambda: len(closed()) >= 10, 6, what="10 refusals")
        refused = closed()
        answers = {k: _answer(held[k], 5) for k in refused}
        assert refused == [*range(20, 25), *range(35, 40)], answers
        assert all(answers[k].startswith(b"HTTP/1.1 503") for k in refused), answers
        # the held ones are closed by the server once their header deadline is over
        late = [_answer(s, 60) for k, s in enumerate(held) if k not in refused]
        assert all(x == b"" for x in late), late
        assert time.monotonic() - t0 < 8 + 30
        status, _, _ = get(urllib.request.build_opener(), srv.base + "/liveness")
        assert status == 200
        new = srv.log()[log0:]
        assert "Traceback" not in new
        per_client = new.count("connections refused: client 127.0.0.2 holds 20")
        in_all = new.count("connections refused: 30 open")
        assert per_client == 1 and in_all == 1, new[-3000:]
    finally:
        for s in held:
            s.close()
        srv.stop()


def test_out_of_file_descriptors_the_server_pauses_accepting_quietly(tmp_path):
    """Near the open-file limit ``accept()`` failed with EMFILE in a busy loop (90,424
    tracebacks in 25 s). The server's limit is lowered under it here (``prlimit``), then
    more connections come (from several addresses: no cap of a client is reached) than
    descriptors are left: a few log lines, no traceback, and once they close the server
    answers again."""
    import resource

    srv = Server(tmp_path, "import panel as pn\npn.pane.Markdown('a page').servable()\n", {})
    held: list = []
    try:
        srv.started(120)
        fds = len(os.listdir(f"/proc/{srv.proc.pid}/fd"))
        resource.prlimit(srv.proc.pid, resource.RLIMIT_NOFILE, (fds + 20, fds + 20))
        log0 = len(srv.log())
        for k in range(4):
            held += _held(f"127.0.0.{k + 2}", srv.port, 15)  # 60 > 20 descriptors left
        time.sleep(3.0)  # the attack goes on (what the log gets meanwhile is the point)
        new = srv.log()[log0:]
        assert "Traceback" not in new and new.count("\n") < 20, new[-3000:]
        assert "no file descriptor left" in new
        for s in held:
            s.close()
        wait_for(
            lambda: get(urllib.request.build_opener(), srv.base + "/liveness")[0] == 200,
            60,
            what="the server answering again",
        )
    finally:
        for s in held:
            s.close()
        srv.stop()


# ---- issue 42: page builds without a websocket ----------------------------------------------

#: A page that takes 0.3 s of the event loop to build (as a page of the dashboard does
#: more) and counts its builds.
SLOW_PAGE = """
import time
from pathlib import Path
import panel as pn

count = Path(__file__).with_name("builds.txt")
count.write_text(str(int(count.read_text() or 0) + 1) if count.exists() else "1")
time.sleep(0.3)
pn.pane.Markdown("# slow-page-marker").servable()
"""


def test_page_builds_are_bounded_per_user(tmp_path):
    """A logged-in user reloading the page in a loop (no websocket) built a page on the
    event loop each time. Now each login has a budget of event-loop time for page builds
    (FBS_PAGE_BUILD_BURST_S_PER_USER at once, FBS_PAGE_BUILD_SHARE_PER_USER per second):
    beyond, 429 with Retry-After and a page that reloads itself; another user still gets
    pages, and opening the pages one asks for (their websockets) gives the charge back;
    one log line per interval."""
    srv = Server(
        tmp_path,
        SLOW_PAGE,
        {
            "FBS_BASIC_AUTH": f"{USER}:{PASSWORD},{OTHER_USER}:{OTHER_PASSWORD}",
            "FBS_COOKIE_SECRET": SECRET,
            "FBS_PAGE_BUILD_SHARE_PER_USER": "0.1",
            "FBS_PAGE_BUILD_BURST_S_PER_USER": "1",
        },
    )
    try:
        srv.started(120)
        log0 = len(srv.log())
        cookie = _login_cookies()
        opener = urllib.request.build_opener(NoRedirect)
        builds0 = _builds(srv)
        statuses, retry, t0 = [], [], time.monotonic()
        while time.monotonic() - t0 < 6.0:
            status, headers, body = get(opener, srv.base + "/fbsapp", headers={"Cookie": cookie})
            statuses.append(status)
            if status == 429:
                retry.append(int(headers["Retry-After"]))
                assert "opens by itself" in body and "render_items" not in body
        secs = time.monotonic() - t0
        built = _builds(srv) - builds0
        # at most the burst (1 s) and 0.1 s per second of 0.3 s builds, and one more (the
        # build that spends the budget is charged after it)
        assert built <= (1 + 0.1 * secs) / 0.3 + 1, (built, statuses)
        assert 429 in statuses and min(retry) >= 1, statuses
        assert statuses.count(200) == built
        # another user is not held back, even opening pages in a row: opening a page (its
        # websocket) gives its charge back; the budget bounds pages built and never used
        other = _login_cookies(user=OTHER_USER, password=OTHER_PASSWORD)
        for _ in range(8):
            status, _, body = get(opener, srv.base + "/fbsapp", headers={"Cookie": other})
            token = re.search(r'"token":\s*"([^"]+)"', body)
            assert status == 200 and token, status
            _, document = run_async(websocket_session(srv.port, "fbsapp", other, token[1]))
            assert "slow-page-marker" in document
        new = srv.log()[log0:]
        assert new.count(f"page builds refused: 'user {USER}'") == 1, new[-3000:]
        assert "Traceback" not in new
    finally:
        srv.stop()


def test_page_build_budgets_per_user_and_in_all():
    """The budgets on their own (a clock of the test's): a user's burst, its refill, and the
    budget of all users refusing a user whose own budget is left."""
    import page_limits

    clock = _Clock()
    builds = page_limits.PageBuilds(
        user_share=0.2, user_burst_s=2.0, total_share=0.5, total_burst_s=3.0, clock=clock
    )
    assert builds.check("a") is None
    builds.charge("a", 1.5)
    assert builds.check("a") is None  # 0.5 s left
    builds.charge("a", 1.0)  # -0.5 s: refilled to above 0 in 2.5 s
    kind, wait = builds.check("a")
    assert kind == "user" and wait == pytest.approx(2.5, abs=0.01)
    assert builds.check("b") is None  # the total: 3 - 2.5 = 0.5 s left
    builds.charge("b", 1.0)  # total -0.5 s: above 0 again in 1 s
    kind, wait = builds.check("c")
    assert kind == "all" and wait == pytest.approx(1.0, abs=0.01)
    clock.t += 1.01
    assert builds.check("c") is None
    level = builds.users["a"].update(clock.t)
    assert builds.refund("a") == 1.5  # a's first page opened: its charge back
    assert builds.users["a"].level == pytest.approx(level + 1.5)
    assert builds.refund("a") == 1.0 and builds.refund("a") == 0.0  # nothing more pending
    status, retry, page = builds.wait_page("user", 2.2)
    assert (status, retry) == (429, 3) and 'content="3"' in page
    assert builds.wait_page("all", 0.2)[:2] == (503, 1)


def test_connection_limits_count_open_sockets_per_client_and_in_all():
    """The caps on their own: a closed socket no longer counts, a trusted proxy counts in
    the total only, the total stays below the open-file limit, and the refusals of one
    kind are logged once per interval with their count."""
    import socket

    import conn_limits

    clock = _Clock()
    quiet = conn_limits.QuietLog(10.0, clock=clock)
    proxies = fbs_auth.parse_networks("10.0.0.9")
    limits = conn_limits.ConnectionLimits(2, 4, exempt=proxies, fd_limit=10_000, quiet=quiet)
    assert conn_limits.ConnectionLimits(2, 4000, fd_limit=1000).total == 1000 - 256
    pairs = [socket.socketpair() for _ in range(8)]
    try:
        a, b, c, d, e, f, g, h = (p[0] for p in pairs)
        assert limits.admit(a, ("10.0.0.1", 1)) and limits.admit(b, ("10.0.0.1", 2))
        assert not limits.admit(c, ("10.0.0.1", 3)) and c.fileno() == -1  # refused, closed
        assert pairs[2][1].recv(100).startswith(b"HTTP/1.1 503")
        a.close()  # the server closed one: room again
        assert limits.admit(d, ("10.0.0.1", 4)) and limits.open_count("10.0.0.1") == 2
        assert limits.admit(e, ("10.0.0.9", 5)) and limits.admit(f, ("10.0.0.9", 6))
        assert limits.open_count() == 4
        assert not limits.admit(g, ("10.0.0.9", 7))  # the proxy: the total (4) is reached
        clock.t += 11
        assert not limits.admit(h, ("10.0.0.2", 8))
        assert limits.refused == 3
    finally:
        for p in pairs:
            p[0].close()
            p[1].close()
    assert quiet.note("k", "x") and not quiet.note("k", "x") and not quiet.note("k", "x")
    clock.t += 10
    assert quiet.note("k", "x")
