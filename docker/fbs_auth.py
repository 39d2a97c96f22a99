"""The login of the deployed server: throttled basic authentication with revocable cookies.

Used by ``docker/fbs_server.py`` when basic authentication is on (``FBS_BASIC_AUTH*``). It
wraps the provider ``panel serve`` builds (:class:`panel.auth.BasicAuthProvider`) in a
provider of Bokeh's public :class:`~bokeh.server.auth_provider.AuthProvider` interface
that adds:

Throttled logins
    Failures are counted per *(client address, user name)*: from the 4th within
    :data:`LOGIN_WINDOW_S` each answer is held (0.5 s, doubling up to 8 s, without blocking
    the server), from the ``max_failures``-th on that user is refused from that address
    (HTTP 429) until the failures age out, without the password being checked. An attacker
    guessing one user's password therefore locks out neither the other users of the same
    address (a NAT, a corporate proxy) nor that user elsewhere. Across all clients, once
    more than :data:`LOGIN_GLOBAL_FAILURES` failures fall in the window (many addresses
    guessing at once), a client that has failed :data:`LOGIN_FREE_FAILURES` times already is
    refused at once; a client without failures still gets in with the right password.
The client address is the connection's peer
    ``X-Forwarded-For`` / ``X-Real-IP`` are believed only from the reverse proxies listed in
    ``FBS_TRUSTED_PROXIES`` (addresses or networks): from them the client is the nearest
    address in ``X-Forwarded-For`` that is not a trusted proxy (the one the proxy itself
    appended), else ``X-Real-IP``. A client that connects directly cannot pick its address.
Revocable login cookies
    Besides Panel's ``user`` cookie a login sets ``fbs_login`` (signed with the cookie
    secret): the user, when it was issued, a random id and a digest of the user's password.
    A request is logged in only when both are valid and the user still exists with the same
    password (the users file is re-read when it changes), and the id was not logged out: a
    cookie stops working on logout, when its user is removed from the users file, or when
    the password is changed (across restarts and processes, since the digest is derived
    from the password and the secret), and after ``PANEL_OAUTH_EXPIRY`` days (1).
Cookie attributes
    Every cookie set here is ``HttpOnly``; the login cookies are ``SameSite=Lax`` (a link
    from elsewhere opens the dashboard logged in, a cross-site form or script request
    carries no login), the form token's cookie ``SameSite=Strict``. ``Secure`` when the
    request came over HTTPS: a TLS connection, or ``X-Forwarded-Proto: https`` from a
    trusted proxy (``FBS_TRUSTED_PROXIES``; from anyone else the header is ignored).
Forms with a CSRF token
    The login form and the logout confirmation carry a random token in a hidden field and
    in the ``fbs_csrf`` cookie (double submit); a POST whose field does not match its cookie
    is refused (HTTP 403) before the password is looked at. ``GET /logout`` changes nothing
    (a cross-site link cannot log a user out): it shows a confirmation form whose POST
    logs out.
"""

from __future__ import annotations

import asyncio
import collections
import hashlib
import hmac
import ipaddress
import json
import logging
import os
import secrets
import threading
import time
from collections.abc import Iterable

log = logging.getLogger("tire_fbs.server")

#: Failures (per client and user) before wrong logins are slowed down.
LOGIN_FREE_FAILURES = 3
#: Delay of the first slowed answer in seconds; doubles per failure up to LOGIN_MAX_DELAY_S.
LOGIN_BASE_DELAY_S = 0.5
LOGIN_MAX_DELAY_S = 8.0
#: Seconds a failed login counts.
LOGIN_WINDOW_S = 300.0
#: Default failures of one user from one client within the window before it is refused (429).
LOGIN_MAX_FAILURES = 10
#: Failures of all clients within the window after which clients with failures are refused.
LOGIN_GLOBAL_FAILURES = 200
#: (client, user) pairs remembered at most (older entries are dropped first).
LOGIN_MAX_CLIENTS = 10_000
#: Logged-out cookie ids remembered at most (each until its cookie would have expired).
MAX_REVOKED = 100_000
#: Name of the revocable login cookie.
LOGIN_COOKIE = "fbs_login"
#: Name of the cookie holding the forms' CSRF token (double submit with the field ``_csrf``).
CSRF_COOKIE = "fbs_csrf"
#: SameSite of the login cookies and of the CSRF cookie.
LOGIN_SAMESITE = "Lax"
CSRF_SAMESITE = "Strict"


# ---- client address ------------------------------------------------------------------------


def parse_networks(text: str) -> tuple[ipaddress.IPv4Network | ipaddress.IPv6Network, ...]:
    """Addresses or networks separated by commas (``127.0.0.1, 10.0.0.0/8, ::1``).

    Raises
    ------
    ValueError
        For an entry that is not an IP address or network (naming it).
    """
    out = []
    for entry in text.replace(" ", ",").split(","):
        entry = entry.strip()
        if not entry:
            continue
        try:
            out.append(ipaddress.ip_network(entry, strict=False))
        except ValueError:
            raise ValueError(
                f"{entry!r} is not an IP address or network (e.g. 172.18.0.2 or 10.0.0.0/8)"
            ) from None
    return tuple(out)


def _ip(text: str):
    try:
        return ipaddress.ip_address(text.strip().strip("[]"))
    except ValueError:
        return None


def _trusted(address: str, proxies) -> bool:
    ip = _ip(address)
    return ip is not None and any(ip in net for net in proxies)


def client_address(peer: str, headers, proxies: Iterable) -> str:
    """The client a request comes from, for throttling and logs.

    Parameters
    ----------
    peer : str
        Address of the connection's other end.
    headers : tornado.httputil.HTTPHeaders
        The request's headers.
    proxies : sequence of ip networks
        Reverse proxies whose forwarding headers are believed (:func:`parse_networks`).
    """
    proxies = tuple(proxies)
    if not proxies or not _trusted(peer, proxies):
        return peer
    hops = [h.strip() for v in headers.get_list("X-Forwarded-For") for h in v.split(",")]
    for hop in reversed([h for h in hops if h]):
        if _ip(hop) is None:
            return peer  # a hop the proxy did not write: nothing behind it is believed
        if not _trusted(hop, proxies):
            return str(_ip(hop))
    real = _ip(headers.get("X-Real-Ip", ""))
    if real is not None and not _trusted(str(real), proxies):
        return str(real)
    return peer


# ---- throttle --------------------------------------------------------------------------------


class _Windows:
    """Failure times per key within a sliding window: at most LOGIN_MAX_CLIENTS keys (the
    oldest go first), the last ``keep`` times of each."""

    def __init__(self, window_s: float, keep: int) -> None:
        self.window_s = window_s
        self.keep = keep
        self._times: collections.OrderedDict[object, collections.deque] = collections.OrderedDict()

    def recent(self, key, now: float) -> collections.deque:
        times = self._times.get(key)
        if times is None:
            return collections.deque()
        while times and now - times[0] >= self.window_s:
            times.popleft()
        if not times:
            del self._times[key]
        return times

    def add(self, key, now: float) -> int:
        times = self.recent(key, now)
        if times.maxlen is None:
            times = collections.deque(times, maxlen=self.keep)
        self._times[key] = times
        self._times.move_to_end(key)
        times.append(now)
        while len(self._times) > LOGIN_MAX_CLIENTS:
            self._times.popitem(last=False)
        return len(times)

    def drop(self, key) -> None:
        self._times.pop(key, None)


class LoginThrottle:
    """Failed logins per (client, user) in a sliding window, and across all clients.

    Parameters
    ----------
    max_failures : int
        Failures of one user from one client within ``window_s`` after which that pair is
        refused.
    window_s : float
        Seconds a failure counts.
    global_failures : int
        Failures of all clients within ``window_s`` after which any client that has failed
        :data:`LOGIN_FREE_FAILURES` times (with any user names) is refused.
    clock : callable
        Monotonic clock (seconds); replaceable in tests.
    """

    def __init__(
        self,
        max_failures: int = LOGIN_MAX_FAILURES,
        window_s: float = LOGIN_WINDOW_S,
        global_failures: int = LOGIN_GLOBAL_FAILURES,
        clock=time.monotonic,
    ) -> None:
        if max_failures < 1:
            raise ValueError(f"max_failures={max_failures}: must be >= 1")
        if global_failures < 1:
            raise ValueError(f"global_failures={global_failures}: must be >= 1")
        self.max_failures = max_failures
        self.window_s = window_s
        self.global_failures = global_failures
        self.clock = clock
        self._pairs = _Windows(window_s, max_failures)
        self._clients = _Windows(window_s, LOGIN_FREE_FAILURES)
        self._all = _Windows(window_s, global_failures)
        self._lock = threading.Lock()

    def retry_after(self, client: str, user: str) -> float:
        """Seconds until ``user`` may try again from ``client``; 0 if now."""
        with self._lock:
            now = self.clock()
            times = self._pairs.recent((client, user), now)
            if len(times) >= self.max_failures:
                return max(times[-self.max_failures] + self.window_s - now, 0.0)
            everyone = self._all.recent(None, now)
            if len(everyone) >= self.global_failures:
                if len(self._clients.recent(client, now)) >= LOGIN_FREE_FAILURES:
                    return max(everyone[-self.global_failures] + self.window_s - now, 1.0)
            return 0.0

    def failed(self, client: str, user: str) -> int:
        """Count a failure of ``user`` from ``client``; that pair's failures in the window."""
        with self._lock:
            now = self.clock()
            self._clients.add(client, now)
            self._all.add(None, now)
            return self._pairs.add((client, user), now)

    def succeeded(self, client: str, user: str) -> None:
        with self._lock:
            self._pairs.drop((client, user))

    @staticmethod
    def delay(failures: int) -> float:
        """Seconds to hold the answer to the ``failures``-th failure."""
        if failures <= LOGIN_FREE_FAILURES:
            return 0.0
        delay = LOGIN_BASE_DELAY_S * 2.0 ** (failures - LOGIN_FREE_FAILURES - 1)
        return min(delay, LOGIN_MAX_DELAY_S)


def printable(text: str, limit: int = 64) -> str:
    """A user-supplied string made safe for one log line."""
    return repr(text[:limit] + ("..." if len(text) > limit else ""))


# ---- users and their cookies -------------------------------------------------------------------


class Users:
    """The basic-auth users: a dict, or a JSON file re-read when it changes.

    Parameters
    ----------
    source : dict or str
        user -> password, or the path of a JSON file holding that object.
    """

    def __init__(self, source) -> None:
        self.source = source
        self._stamp: tuple[int, int] | None = None
        self._users: dict[str, str] = dict(source) if isinstance(source, dict) else {}
        self._lock = threading.Lock()

    def current(self) -> dict[str, str]:
        """user -> password now (an unreadable file: no users, nobody is let in)."""
        if isinstance(self.source, dict):
            return self._users
        with self._lock:
            try:
                st = os.stat(self.source)
                stamp = (st.st_mtime_ns, st.st_size)
                if stamp != self._stamp:
                    with open(self.source, encoding="utf-8") as f:
                        users = json.load(f)
                    ok = isinstance(users, dict)
                    self._users = (
                        {k: v for k, v in users.items() if isinstance(v, str)} if ok else {}
                    )
                    self._stamp = stamp
            except (OSError, ValueError) as exc:
                log.error("users file %s cannot be read (%s): nobody is let in", self.source, exc)
                self._users, self._stamp = {}, None
            return self._users

    def check(self, username: str, password: str) -> bool:
        """Constant-time check of ``username``/``password``."""
        expected = self.current().get(username)
        ok = hmac.compare_digest(
            (expected if isinstance(expected, str) else "\0" + password).encode("utf-8"),
            password.encode("utf-8"),
        )
        return ok and isinstance(expected, str)


def check_password(users, username: str, password: str) -> bool:
    """Constant-time check against ``users`` (a dict or the path of a JSON file)."""
    return Users(users).check(username, password)


def password_digest(secret: str, user: str, password: str) -> str:
    """A digest of the user's password bound to the cookie secret (stored in the cookie)."""
    msg = b"fbs-login\0" + user.encode("utf-8") + b"\0" + password.encode("utf-8")
    return hmac.new(secret.encode("utf-8"), msg, hashlib.sha256).hexdigest()[:32]


def login_token(secret: str, user: str, password: str, issued: float | None = None) -> str:
    """The value of the :data:`LOGIN_COOKIE` cookie (before signing)."""
    return json.dumps(
        {
            "u": user,
            "t": int(time.time() if issued is None else issued),
            "n": secrets.token_hex(12),
            "g": password_digest(secret, user, password),
        },
        separators=(",", ":"),
    )


class Revoked:
    """Ids of logged-out cookies, each kept until its cookie would have expired."""

    def __init__(self) -> None:
        self._ids: collections.OrderedDict[str, float] = collections.OrderedDict()
        self._lock = threading.Lock()

    def add(self, token_id: str, until: float) -> None:
        with self._lock:
            self._ids[token_id] = until
            self._ids.move_to_end(token_id)
            now = time.time()
            while self._ids and (
                len(self._ids) > MAX_REVOKED or next(iter(self._ids.values())) < now
            ):
                self._ids.popitem(last=False)

    def __contains__(self, token_id: str) -> bool:
        with self._lock:
            return token_id in self._ids


# ---- the provider ------------------------------------------------------------------------------


def _login_handlers(auth: GuardedBasicAuth):
    import tornado.escape
    from panel.config import config
    from panel.io.resources import BASIC_LOGIN_TEMPLATE, CDN_DIST, LOGOUT_TEMPLATE
    from panel.io.state import state
    from tornado.web import RequestHandler

    def safe_next(url: str | None) -> str:
        """A same-site path to go to after the login, else the site's root."""
        url = url or ""
        if not url.startswith("/") or url.startswith("//") or "\\" in url or "\n" in url:
            return state.base_url or "/"
        return url

    def refuse_form(handler: RequestHandler, form: str) -> bool:
        """Answer 403 and return True when the POST's CSRF field does not match its cookie."""
        if auth.csrf_ok(handler):
            return False
        log.warning("%s refused: no valid form token, from %s", form, auth.client(handler.request))
        handler.set_status(403)
        handler.finish(
            f"<!DOCTYPE html><title>Form expired</title><p>The {form} form expired or was "
            f'sent from another site. <a href=".{tornado.escape.xhtml_escape(auth.login_url)}">'
            "Reload the login page</a> and try again.</p>"
        )
        return True

    class LoginHandler(RequestHandler):
        """Panel's login form with throttling, logging of failures, revocable cookies and
        a CSRF token."""

        def get(self):
            self.set_cookie(
                "next_url", safe_next(self.get_argument("next", "")), **auth.cookie_attrs(self)
            )
            page = BASIC_LOGIN_TEMPLATE.render(
                login_endpoint=auth.login_url,
                errormessage=self.get_argument("error", ""),
                PANEL_CDN=CDN_DIST,
            )
            self.write(with_token(page, auth.csrf_token(self)))

        async def post(self):
            if refuse_form(self, "login"):
                return
            client = auth.client(self.request)
            username = self.get_argument("username", "")
            wait = auth.throttle.retry_after(client, username)
            if wait > 0:
                log.warning(
                    "login refused: client %s, user %s, too many failed logins within %.0f s "
                    "(may try again in %.0f s)",
                    client,
                    printable(username),
                    auth.throttle.window_s,
                    wait,
                )
                self.set_status(429)
                self.set_header("Retry-After", str(int(wait) + 1))
                self.finish("Too many failed logins: try again later.")
                return
            password = self.get_argument("password", "")
            if auth.users.check(username, password):
                auth.throttle.succeeded(client, username)
                log.info("login: user %s from %s", printable(username), client)
                auth.set_login_cookies(self, username, password)
                self.redirect(safe_next(self.get_cookie("next_url")))
                return
            failures = auth.throttle.failed(client, username)
            pause = auth.throttle.delay(failures)
            log.warning(
                "failed login: user %s from %s (%d failures within %.0f s%s)",
                printable(username),
                client,
                failures,
                auth.throttle.window_s,
                f"; answer held {pause:.1f} s" if pause else "",
            )
            if pause:
                await asyncio.sleep(pause)  # holds this answer only, not the server
            error = "?error=" + tornado.escape.url_escape("Invalid username or password!")
            self.redirect(self.request.path + error)

    class LogoutHandler(RequestHandler):
        """``GET``: a confirmation form (nothing changes); ``POST`` with the form's token: the
        login ends, the cookie's id is revoked, the cookies are cleared."""

        def get(self):
            self.write(
                LOGOUT_CONFIRM.format(
                    action=tornado.escape.xhtml_escape("." + auth.logout_url),
                    token=tornado.escape.xhtml_escape(auth.csrf_token(self)),
                )
            )

        def post(self):
            if refuse_form(self, "logout"):
                return
            token = auth.token(self)
            if token is not None:
                auth.revoked.add(token["n"], token["t"] + auth.max_age_s)
                log.info("logout: user %s", printable(token["u"]))
            for name in ("user", "id_token", LOGIN_COOKIE, "next_url", CSRF_COOKIE):
                self.clear_cookie(name, path=config.cookie_path)
            self.write(LOGOUT_TEMPLATE.render(PANEL_CDN=CDN_DIST, LOGIN_ENDPOINT=auth.login_url))

    def with_token(page: str, token: str) -> str:
        """The login page with the CSRF token as a hidden field of its form."""
        field = f'<input type="hidden" name="_csrf" value="{tornado.escape.xhtml_escape(token)}">'
        head, sep, tail = page.partition("</form>")
        if not sep:
            raise RuntimeError("Panel's login page has no form to carry the CSRF token")
        return head + field + sep + tail

    return LoginHandler, LogoutHandler


#: The logout confirmation (``GET /logout``): its POST carries the CSRF token.
LOGOUT_CONFIRM = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>Log out</title>
<style>body{{font-family:sans-serif;margin:4em auto;max-width:24em}}
button{{padding:.5em 1.5em}}</style></head>
<body><form class="logout-form" action="{action}" method="post">
<p>Log out of the dashboard?</p>
<input type="hidden" name="_csrf" value="{token}">
<button type="submit">Log out</button></form></body></html>
"""


def _provider_base():
    from bokeh.server.auth_provider import AuthProvider

    return AuthProvider


class GuardedBasicAuth:
    """What the login handlers and the provider share (see the module docstring).

    Parameters
    ----------
    inner : panel.auth.BasicAuthProvider
        The provider ``panel serve`` built (its login URL, its guest endpoints, its user
        bookkeeping).
    users : dict or str
        user -> password, or the path of the JSON users file.
    secret : str
        The cookie secret.
    throttle : LoginThrottle
    proxies : sequence of ip networks
        Trusted reverse proxies (:func:`client_address`).
    max_age_days : float
        Life of a login cookie.
    """

    def __init__(self, inner, users, secret, throttle, proxies=(), max_age_days: float = 1.0):
        self.inner = inner
        self.users = Users(users)
        self.secret = secret
        self.throttle = throttle
        self.proxies = tuple(proxies)
        self.max_age_days = max_age_days
        self.max_age_s = max_age_days * 86400.0
        self.revoked = Revoked()
        self.login_url = inner.login_url
        self.logout_url = inner.logout_url
        self.login_handler, self.logout_handler = _login_handlers(self)

    def client(self, request) -> str:
        from server_private import peer_address

        return client_address(peer_address(request), request.headers, self.proxies)

    def is_https(self, request) -> bool:
        """Whether the request came over HTTPS: ``X-Forwarded-Proto`` of a trusted proxy,
        else the connection itself (TLS)."""
        from server_private import peer_address
        from tornado.iostream import SSLIOStream

        if _trusted(peer_address(request), self.proxies):
            proto = request.headers.get("X-Forwarded-Proto", "").split(",")[0].strip().lower()
            if proto:
                return proto == "https"
        stream = getattr(request.connection, "stream", None)
        return isinstance(stream, SSLIOStream)

    def cookie_attrs(self, handler, samesite: str = LOGIN_SAMESITE) -> dict:
        """The attributes of a cookie set for ``handler``'s request (module docstring)."""
        from panel.config import config

        return {
            "httponly": True,
            "samesite": samesite,
            "secure": self.is_https(handler.request),
            "path": config.cookie_path,
        }

    def csrf_token(self, handler) -> str:
        """The CSRF token of the request's browser (its cookie's, else a new one, set)."""
        token = handler.get_cookie(CSRF_COOKIE, "")
        if not (32 <= len(token) <= 128 and token.replace("-", "").replace("_", "").isalnum()):
            token = secrets.token_urlsafe(32)
            handler.set_cookie(CSRF_COOKIE, token, **self.cookie_attrs(handler, CSRF_SAMESITE))
        return token

    def csrf_ok(self, handler) -> bool:
        """Whether a POST's ``_csrf`` field matches its ``fbs_csrf`` cookie."""
        cookie = handler.get_cookie(CSRF_COOKIE, "")
        field = handler.get_body_argument("_csrf", "")
        return bool(cookie) and hmac.compare_digest(cookie.encode(), field.encode())

    def set_login_cookies(self, handler, user: str, password: str) -> None:
        handler.clear_cookie("is_guest")
        kw = {"expires_days": self.max_age_days, **self.cookie_attrs(handler)}
        handler.set_secure_cookie("user", user, **kw)
        handler.set_secure_cookie(LOGIN_COOKIE, login_token(self.secret, user, password), **kw)

    def token(self, handler) -> dict | None:
        """The valid login token of a request (see the module docstring), else None."""
        raw = handler.get_secure_cookie(LOGIN_COOKIE, max_age_days=self.max_age_days)
        if not raw:
            return None
        try:
            token = json.loads(raw)
            user, issued, tid, digest = token["u"], token["t"], token["n"], token["g"]
        except (ValueError, KeyError, TypeError):
            return None
        if not (isinstance(user, str) and isinstance(tid, str) and isinstance(digest, str)):
            return None
        password = self.users.current().get(user)
        if password is None or tid in self.revoked:
            return None
        if not hmac.compare_digest(digest, password_digest(self.secret, user, password)):
            return None
        if not isinstance(issued, int) or time.time() - issued > self.max_age_s:
            return None
        return token

    def get_user(self, handler):
        token = self.token(handler)
        if token is None:
            return None
        user = self.inner.get_user(handler)  # Panel's "user" cookie and its bookkeeping
        return user if user == token["u"] else None

    def provider(self):
        """A Bokeh :class:`~bokeh.server.auth_provider.AuthProvider` of this login."""
        base = _provider_base()
        shared = self

        class GuardedProvider(base):  # type: ignore[misc, valid-type]
            @property
            def get_user(self):
                return shared.get_user

            @property
            def login_url(self):
                return shared.login_url

            @property
            def login_handler(self):
                return shared.login_handler

            @property
            def logout_url(self):
                return shared.logout_url

            @property
            def logout_handler(self):
                return shared.logout_handler

        return GuardedProvider()
