"""Access control of the deployment (docker/entrypoint.py), tested without Docker.

The container's entrypoint turns ``FBS_*`` environment variables into a ``panel serve``
command line. Here it is run as a subprocess on a free loopback port with basic
authentication on, serving a small Panel script, and checked from outside like a browser
would be: without credentials there is no app content and no websocket; after logging in
through the login form the page and the websocket work. The settings parser is tested
directly (every refused value has a ``pytest.raises``).
"""

from __future__ import annotations

import http.cookiejar
import importlib.util
import json
import re
import sys
import urllib.error
import urllib.parse
import urllib.request
from pathlib import Path

import pytest
from server_util import NoRedirect, Server, get, login_post, run_async, websocket_session

ROOT = Path(__file__).resolve().parents[1]
SPEC = importlib.util.spec_from_file_location("fbs_entrypoint", ROOT / "docker" / "entrypoint.py")
entrypoint = importlib.util.module_from_spec(SPEC)
sys.modules[SPEC.name] = entrypoint  # (its dataclass looks the module up)
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
    launch = entrypoint.build_launch({"FBS_APP": str(app_file)}, ["--dev-flag"])
    args = launch.args
    assert args[0] == str(app_file)
    joined = " ".join(args)
    assert "--address 0.0.0.0 --port 5006 --num-threads 4" in joined
    # the server's own /liveness, not Panel's (which built a page per request)
    assert "--liveness" not in args
    assert not any(a.startswith(("--basic-auth", "--cookie-secret")) for a in args)
    # fbs_core's largest file (100 MiB) fits one message base64-encoded with Bokeh's
    # envelope; the 147 MB fake upload does not (refused by its declared size)
    limit = int(args[args.index("--websocket-max-message-size") + 1])
    assert 4 * -(-(100 << 20) // 3) + 4096 <= limit < 147_000_000
    assert args[-1] == "--dev-flag" and launch.warnings == [] and launch.private == {}


def test_the_server_gets_one_native_thread_per_pool_and_no_secret():
    env = {"FBS_BASIC_AUTH": "a:b", "FBS_COOKIE_SECRET": "s" * 40, "PATH": "/bin"}
    out = entrypoint.server_environment(env)
    assert not set(entrypoint.SECRET_VARS) & set(out) and out["PATH"] == "/bin"
    assert all(out[v] == "1" for v in entrypoint.NATIVE_THREAD_VARS)
    # a count the deployment sets is kept
    out = entrypoint.server_environment({"OPENBLAS_NUM_THREADS": "2"})
    assert out["OPENBLAS_NUM_THREADS"] == "2" and out["OMP_NUM_THREADS"] == "1"


def test_basic_auth_users_and_secret_stay_off_the_command_line(app_file):
    env = {
        "FBS_APP": str(app_file),
        "FBS_BASIC_AUTH": f"{USER}:{PASSWORD}",
        "FBS_COOKIE_SECRET": SECRET,
    }
    launch = entrypoint.build_launch(env, [])
    joined = " ".join(launch.args)
    assert PASSWORD not in joined and SECRET not in joined and USER not in joined
    assert launch.private == {"basic_auth": {USER: PASSWORD}, "cookie_secret": SECRET}


def test_cookie_secret_from_a_file(app_file, tmp_path):
    secret_file = tmp_path / "cookie_secret"
    secret_file.write_text(SECRET + "\n")
    env = {"FBS_APP": str(app_file), "FBS_COOKIE_SECRET_FILE": str(secret_file)}
    assert entrypoint.build_launch(env, []).private == {"cookie_secret": SECRET}


def test_auth_without_secret_makes_a_random_one(app_file):
    env = {"FBS_APP": str(app_file), "FBS_BASIC_AUTH": "a:b"}
    first = entrypoint.build_launch(env, [])
    second = entrypoint.build_launch(env, [])
    s1, s2 = first.private["cookie_secret"], second.private["cookie_secret"]
    assert len(s1) >= entrypoint.MIN_SECRET_LEN and s1 != s2
    assert any("FBS_COOKIE_SECRET" in w for w in first.warnings)


@pytest.mark.parametrize(
    ("env", "match"),
    [
        ({"FBS_BASIC_AUTH": "a:b", "FBS_BASIC_AUTH_FILE": "/x.json"}, "not both"),
        ({"PANEL_BASIC_AUTH": "pw"}, "lower-cases"),
        ({"FBS_BASIC_AUTH": "a:b", "PANEL_OAUTH_PROVIDER": "github"}, "exclude each other"),
        ({"FBS_BASIC_AUTH": "a:b", "FBS_COOKIE_SECRET": "short"}, "at least 32 characters"),
        ({"FBS_COOKIE_SECRET": SECRET, "PANEL_COOKIE_SECRET": SECRET}, "not several"),
        ({"FBS_COOKIE_SECRET_FILE": "/nonexistent/secret"}, "cannot be read"),
        ({"FBS_LOGIN_MAX_FAILURES": "0"}, "FBS_LOGIN_MAX_FAILURES"),
        ({"FBS_NUM_THREADS": "0"}, "FBS_NUM_THREADS='0': must be an integer >= 1"),
        ({"FBS_NUM_THREADS": "four"}, "must be an integer >= 1"),
        ({"FBS_PORT": "-1"}, "FBS_PORT"),
        ({"FBS_LOG_LEVEL": "loud"}, "allowed values are debug, info"),
        ({"FBS_USE_XHEADERS": "maybe"}, "FBS_USE_XHEADERS='maybe': allowed values"),
        ({"FBS_USE_XHEADERS": "true"}, "needs FBS_TRUSTED_PROXIES"),
        ({"FBS_TRUSTED_PROXIES": "10.0.0.1,proxy.local"}, "'proxy.local' is not an IP address"),
        ({"FBS_WEBSOCKET_MAX_MESSAGE_MB": "0"}, "FBS_WEBSOCKET_MAX_MESSAGE_MB"),
        ({"FBS_BASIC_AUTH_FILE": "/nonexistent/users.json"}, "cannot be read"),
        ({"FBS_APP": "/nonexistent/main.py"}, "does not exist"),
    ],
)
def test_refused_settings(app_file, env, match):
    env = {"FBS_APP": str(app_file), **env}
    with pytest.raises(SettingError, match=match):
        entrypoint.build_launch(env, [])


@pytest.mark.parametrize("content", ['["alice", "pw"]', "{}", '{"alice": 3}', "not json"])
def test_refused_users_file(app_file, tmp_path, content):
    users = tmp_path / "users.json"
    users.write_text(content)
    with pytest.raises(SettingError, match="FBS_BASIC_AUTH_FILE"):
        entrypoint.build_launch({"FBS_APP": str(app_file), "FBS_BASIC_AUTH_FILE": str(users)}, [])


@pytest.mark.parametrize("arg", ["--cookie-secret=" + SECRET, "--basic-auth", "--oauth-secret=x"])
def test_secrets_as_extra_arguments_are_refused(app_file, arg):
    with pytest.raises(SettingError, match="visible to every user"):
        entrypoint.build_launch({"FBS_APP": str(app_file)}, [arg])


# ---- the served app with authentication on -----------------------------------------------


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    srv = Server(
        tmp_path_factory.mktemp("authapp"),
        APP,
        {"FBS_BASIC_AUTH": f"{USER}:{PASSWORD}", "FBS_COOKIE_SECRET": SECRET},
    )
    try:
        yield srv.started()
    finally:
        srv.stop()


def test_without_credentials_no_app_content_and_no_websocket(server):
    base, port = server.base, server.port
    opener = urllib.request.build_opener(NoRedirect)
    for path in ("/", "/fbsapp", "/fbsapp/autoload.js?bokeh-autoload-element=x"):
        status, headers, body = get(opener, base + path)
        assert status in (302, 401, 403), (path, status)
        assert "render_items" not in body and "confidential-model-marker" not in body
        if status == 302:
            assert "login" in headers["Location"]
    status, _, body = get(urllib.request.build_opener(), base + "/fbsapp")  # follow
    assert status == 200 and 'name="password"' in body
    assert "render_items" not in body and "confidential-model-marker" not in body
    with pytest.raises(Exception, match="403"):
        run_async(websocket_session(port, "fbsapp", cookie=None))
    # the health endpoint stays open (Docker's HEALTHCHECK), and tells nothing of the app
    status, _, body = get(opener, base + "/liveness")
    assert status == 200 and json.loads(body) == {"/liveness": True}


def test_wrong_password_gets_no_session_cookie(server):
    base = server.base
    jar = http.cookiejar.CookieJar()
    opener = urllib.request.build_opener(NoRedirect, urllib.request.HTTPCookieProcessor(jar))
    status, headers, _ = login_post(opener, base, USER, PASSWORD + "x")
    assert status == 302 and "error" in headers["Location"]
    assert "user" not in {c.name for c in jar}
    status, headers, body = get(opener, base + "/fbsapp")
    assert status == 302 and "login" in headers["Location"] and "render_items" not in body


def test_with_credentials_the_app_and_its_websocket_work(server):
    base, port = server.base, server.port
    jar = http.cookiejar.CookieJar()
    opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor(jar))
    status, _, _ = login_post(opener, base, USER, PASSWORD)  # the redirect followed
    assert status == 200
    assert "user" in {c.name for c in jar}
    status, _, body = get(opener, base + "/fbsapp")
    # Panel's page carries a session token; the document itself comes over the websocket
    assert status == 200 and "render_items" in body
    token = re.search(r'"token":\s*"([^"]+)"', body).group(1)
    cookie = "; ".join(f"{c.name}={c.value}" for c in jar)
    first, document = run_async(websocket_session(port, "fbsapp", cookie, token))
    assert first == "ACK"
    assert "confidential-model-marker" in document and "ColumnDataSource" in document


# ---- cookies and forms: SameSite, HttpOnly, Secure, CSRF, logout by POST --------------------


def _set_cookies(headers) -> dict[str, str]:
    """name -> the whole Set-Cookie line, of a response's headers."""
    return {v.split("=", 1)[0]: v for v in headers.get_all("Set-Cookie") or []}


def _attrs(line: str) -> set[str]:
    return {a.strip().lower() for a in line.split(";")[1:]}


def _logged_in(cookie: str, base: str) -> bool:
    status, _, body = get(
        urllib.request.build_opener(NoRedirect), base + "/fbsapp", headers={"Cookie": cookie}
    )
    return status == 200 and "render_items" in body


def _jar_login(base):
    jar = http.cookiejar.CookieJar()
    opener = urllib.request.build_opener(NoRedirect, urllib.request.HTTPCookieProcessor(jar))
    status, headers, _ = login_post(opener, base, USER, PASSWORD)
    assert status == 302
    return headers, "; ".join(f"{c.name}={c.value}" for c in jar)


def test_login_cookies_are_httponly_and_samesite_and_not_secure_over_plain_http(server):
    headers, _ = _jar_login(server.base)
    cookies = _set_cookies(headers)
    for name in ("user", "fbs_login"):
        a = _attrs(cookies[name])
        assert "httponly" in a and "samesite=lax" in a, cookies[name]
        assert "secure" not in a, cookies[name]  # plain http here: a Secure cookie is dropped


def test_the_login_form_carries_a_csrf_token_and_a_post_without_it_is_refused(server):
    from server_util import form_token

    base = server.base
    status, headers, body = get(urllib.request.build_opener(NoRedirect), base + "/login")
    assert status == 200 and 'name="_csrf"' in body
    csrf = _set_cookies(headers)["fbs_csrf"]
    assert {"httponly", "samesite=strict"} <= _attrs(csrf)
    token, cookie = form_token(base)
    opener = urllib.request.build_opener(NoRedirect)
    for data, cookie_header, why in (
        ({"username": USER, "password": PASSWORD}, cookie, "no token in the form"),
        ({"username": USER, "password": PASSWORD, "_csrf": token}, "", "no token cookie"),
        ({"username": USER, "password": PASSWORD, "_csrf": token + "x"}, cookie, "another token"),
    ):
        status, headers, body = get(
            opener, base + "/login", data=urllib.parse.urlencode(data).encode(),
            headers={"Cookie": cookie_header},
        )  # fmt: skip
        assert status == 403, (why, status)
        assert "user" not in _set_cookies(headers) and "fbs_login" not in _set_cookies(headers)
        assert "reload" in body.lower()


def test_get_logout_changes_nothing_and_post_logout_needs_the_token(server):
    from server_util import form_token

    base = server.base
    _, cookie = _jar_login(base)
    assert _logged_in(cookie, base)
    # a cross-site link (GET) only shows a confirmation form
    status, headers, body = get(urllib.request.build_opener(NoRedirect), base + "/logout",
                                headers={"Cookie": cookie})  # fmt: skip
    assert status == 200 and 'method="post"' in body and 'name="_csrf"' in body
    assert "fbs_login" not in _set_cookies(headers) and _logged_in(cookie, base)
    # a cross-site form (POST without the token) is refused
    opener = urllib.request.build_opener(NoRedirect)
    status, _, _ = get(opener, base + "/logout", data=b"", headers={"Cookie": cookie})
    assert status == 403 and _logged_in(cookie, base)
    # the confirmation form's POST logs out
    token, csrf_cookie = form_token(base, "/logout", headers={"Cookie": cookie})
    status, _, _ = get(
        opener, base + "/logout", data=urllib.parse.urlencode({"_csrf": token}).encode(),
        headers={"Cookie": f"{cookie}; {csrf_cookie}"},
    )  # fmt: skip
    assert status == 200 and not _logged_in(cookie, base)
