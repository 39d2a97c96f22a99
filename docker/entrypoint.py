"""Container entrypoint: deployment settings from environment variables -> ``panel serve``.

The image's exec-form ENTRYPOINT runs this script, which validates the ``FBS_*`` variables
and builds the arguments of ``panel serve``. It then replaces itself (``os.execve``, same
PID: the server is PID 1 and receives ``docker stop``'s SIGTERM) with a Python that runs
``panel serve`` in-process through ``docker/fbs_server.py`` (cheap ``/liveness``, throttled
logins, prompt shutdown). Secrets (the cookie secret, the basic-auth users) are handed over
in an unlinked temporary file whose descriptor the new process reads and closes; they are
removed from the new process's environment and are never on its command line, so ``ps``,
``docker top`` and ``/proc/<pid>/environ`` do not show them, and child processes do not
inherit them. Arguments given after the image name in ``docker run`` are appended to the
``panel serve`` arguments. ``--healthcheck`` instead probes the server's ``/liveness``
endpoint (the image's HEALTHCHECK); ``--print-command`` prints the arguments without
running the server.

Variables (all optional; the table with examples is in docs/deployment.md):

``BOKEH_ALLOW_WS_ORIGIN``
    Read by Bokeh itself: comma-separated ``host:port`` values that browsers may open the
    websocket from (the address in the browser's location bar). Image default
    ``localhost:5006,127.0.0.1:5006``.
``FBS_NUM_THREADS``
    Worker threads for session callbacks (``--num-threads``), integer >= 1, default 4.
``FBS_BASIC_AUTH``
    Turns on Panel's basic authentication (login form): ``user:password`` entries separated
    by commas or newlines. The users stay in the server's memory: never on a command line,
    in a file or in the server's environment.
``FBS_BASIC_AUTH_FILE``
    Same, from a mounted JSON file ``{"user": "password", ...}`` (e.g. a Docker secret).
``FBS_LOGIN_MAX_FAILURES``
    Failed logins of one client within 5 minutes after which it is refused (HTTP 429) until
    they age out, default 10; from the 4th failure on each answer is delayed.
``FBS_COOKIE_SECRET``, ``FBS_COOKIE_SECRET_FILE``
    Secret (>= 32 characters) that signs the login cookies, or the path of a file holding
    it (e.g. a Docker secret). With authentication on and no secret, a random one is made at
    start: logins then end when the container restarts. ``PANEL_COOKIE_SECRET`` is accepted
    as well.
``PANEL_OAUTH_PROVIDER``, ``PANEL_OAUTH_KEY``, ``PANEL_OAUTH_SECRET``, ...
    Read by Panel itself: OAuth login instead of basic authentication.
``FBS_PUBLIC_URL``
    The address at which recipients reach the server's root (with ``FBS_PREFIX``: the
    prefix), e.g. ``https://nvh.example.com/tire-fbs``: the links in reports, CSV headers
    and title blocks start with it instead of the browser's address. An absolute http(s)
    address without query or fragment; anything else stops the start with a message.
``FBS_PREFIX``
    URL prefix when served behind a reverse proxy under a sub-path (``--prefix``).
``FBS_USE_XHEADERS``
    ``true`` behind a TLS-terminating reverse proxy (``--use-xheaders``); needs
    ``FBS_TRUSTED_PROXIES``.
``FBS_TRUSTED_PROXIES``
    Addresses or networks (comma-separated) of the reverse proxies whose ``X-Forwarded-For``
    / ``X-Real-IP`` headers name the client (login throttling, logs); from anyone else
    these headers are ignored.
``FBS_WEBSOCKET_MAX_MESSAGE_MB``
    Largest websocket message in MiB (file uploads travel in one, base64-encoded), default
    135: a file up to fbs_core's limit of 100 MiB. A larger message is refused by the size
    its frame declares, before it is read, and its websocket closed (logged).
``FBS_MAX_CONNECTIONS``, ``FBS_MAX_CONNECTIONS_PER_CLIENT``
    Open connections the server keeps, in all (default 1000, and never more than the
    open-file limit minus 256) and per client address (default 64; a trusted reverse
    proxy counts in the total only); beyond, a connection gets a 503 and is closed.
``FBS_HEADER_TIMEOUT_S``, ``FBS_BODY_TIMEOUT_S``
    Seconds a request's headers (from the connection's start, or the previous request on
    it) and its body may take, default 10 and 30; then the connection is closed.
``FBS_PAGE_BUILD_SHARE``, ``FBS_PAGE_BUILD_SHARE_PER_USER``
    Share of the server's event loop that page builds may take, of all users (default
    0.5) and of one user (a login, or a client address without login; default 0.2);
    beyond, a page request gets 503 or 429 with ``Retry-After`` and a page that reloads
    itself. ``FBS_PAGE_BUILD_BURST_S`` and ``FBS_PAGE_BUILD_BURST_S_PER_USER``: seconds
    of page builds at once (default 8 and 4: several tabs opened together).
``FBS_LOG_LEVEL``
    ``debug``, ``info`` (default), ``warning``, ``error`` or ``critical``.
``FBS_APP``
    Path of the Panel script to serve; default the installed ``app/main.py``.
``FBS_PORT``, ``FBS_ADDRESS``
    Port and address the server listens on inside the container, default 5006 and 0.0.0.0
    (publish another host port with ``docker run -p HOSTPORT:5006`` instead).
``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS``, ``MKL_NUM_THREADS``
    Threads of the native libraries' pools in the server; default 1 each (the server's
    matrices are small and its cores are busy with sessions: :func:`server_environment`).
"""

from __future__ import annotations

import importlib.util
import json
import os
import secrets
import sys
import tempfile
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path

DEFAULT_PORT = 5006
LOG_LEVELS = ("debug", "info", "warning", "error", "critical")
TRUE = ("1", "true", "yes", "on")
FALSE = ("", "0", "false", "no", "off")
MIN_SECRET_LEN = 32
#: Variables holding secrets: read here, handed to the server privately, removed from the
#: server's environment.
#: Thread counts of native libraries' pools, one each unless set (:func:`server_environment`).
NATIVE_THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
SECRET_VARS = (
    "FBS_BASIC_AUTH",
    "FBS_COOKIE_SECRET",
    "PANEL_COOKIE_SECRET",
    "BOKEH_COOKIE_SECRET",
)
#: Internal option: the server stage, reading its private settings from a descriptor.
SERVE_FD = "--serve-fd"
HERE = Path(__file__).resolve().parent


class SettingError(ValueError):
    """A deployment environment variable has a value that cannot be used."""


@dataclass
class Launch:
    """What the server process gets: public arguments and private settings."""

    args: list[str]  # arguments of ``panel serve`` (no secrets)
    private: dict = field(default_factory=dict)  # cookie_secret, basic_auth
    options: dict = field(default_factory=dict)  # fbs_server.serve options
    warnings: list[str] = field(default_factory=list)


def _flag(env: dict[str, str], name: str) -> bool:
    value = env.get(name, "").strip().lower()
    if value in TRUE:
        return True
    if value in FALSE:
        return False
    raise SettingError(f"{name}={env[name]!r}: allowed values are {', '.join(TRUE + FALSE[1:])}")


#: Default largest websocket message in MiB: an upload of fbs_core's largest file (100 MiB)
#: base64-encoded (133.4 MiB) in a Bokeh message (see build_launch).
WEBSOCKET_MAX_MESSAGE_MB = 135


def _positive_int(env: dict[str, str], name: str, default: int | None) -> int | None:
    raw = env.get(name, "").strip()
    if not raw:
        return default
    try:
        value = int(raw)
    except ValueError:
        value = 0
    if value < 1:
        raise SettingError(f"{name}={raw!r}: must be an integer >= 1")
    return value


def _share(env: dict[str, str], name: str, default: float) -> float:
    """A fraction in (0, 1] from ``env[name]``; ``default`` when unset."""
    raw = env.get(name, "").strip()
    if not raw:
        return default
    try:
        value = float(raw)
    except ValueError:
        value = -1.0
    if not 0 < value <= 1:
        raise SettingError(f"{name}={raw!r}: must be a number in (0, 1], e.g. 0.5")
    return value


def _networks(env: dict[str, str], name: str) -> str:
    """Comma-separated IP addresses or networks, checked; "" when unset."""
    import ipaddress

    raw = env.get(name, "").strip()
    for entry in raw.replace(" ", ",").split(","):
        if entry.strip():
            try:
                ipaddress.ip_network(entry.strip(), strict=False)
            except ValueError:
                raise SettingError(
                    f"{name}: {entry.strip()!r} is not an IP address or network "
                    "(e.g. 172.18.0.2 or 10.0.0.0/8)"
                ) from None
    return raw


def parse_users(text: str, name: str = "FBS_BASIC_AUTH") -> dict[str, str]:
    """Parse ``user:password`` entries separated by commas or newlines.

    Raises
    ------
    SettingError
        If an entry has no ``:``, an empty user or password, or a user appears twice.
    """
    users: dict[str, str] = {}
    for entry in text.replace("\n", ",").split(","):
        entry = entry.strip()
        if not entry:
            continue
        user, sep, password = entry.partition(":")
        user = user.strip()
        if not sep or not user or not password:
            raise SettingError(
                f"{name}: entry {user or entry[:1] + '...'!r} is not of the form user:password"
            )
        if user in users:
            raise SettingError(f"{name}: user {user!r} is given twice")
        users[user] = password
    if not users:
        raise SettingError(f"{name} is set but holds no user:password entry")
    return users


def _check_users_file(path: str) -> None:
    try:
        with open(path, encoding="utf-8") as f:
            users = json.load(f)
    except OSError as exc:
        raise SettingError(f"FBS_BASIC_AUTH_FILE={path!r} cannot be read: {exc}") from exc
    except json.JSONDecodeError as exc:
        raise SettingError(f"FBS_BASIC_AUTH_FILE={path!r} is not JSON: {exc}") from exc
    if (
        not isinstance(users, dict)
        or not users
        or not all(isinstance(k, str) and isinstance(v, str) and k and v for k, v in users.items())
    ):
        raise SettingError(
            f'FBS_BASIC_AUTH_FILE={path!r} must hold a JSON object {{"user": "password", ...}}'
        )


def _cookie_secret(env: dict[str, str]) -> str:
    """The cookie secret from FBS_COOKIE_SECRET(_FILE) or PANEL_COOKIE_SECRET, or ""."""
    given = [n for n in ("FBS_COOKIE_SECRET", "FBS_COOKIE_SECRET_FILE", "PANEL_COOKIE_SECRET")]
    given = [n for n in given if env.get(n)]
    if len(given) > 1:
        raise SettingError(f"set one of {', '.join(given)}, not several")
    if env.get("FBS_COOKIE_SECRET_FILE"):
        path = env["FBS_COOKIE_SECRET_FILE"]
        try:
            with open(path, encoding="utf-8") as f:
                secret = f.read().strip()
        except OSError as exc:
            raise SettingError(f"FBS_COOKIE_SECRET_FILE={path!r} cannot be read: {exc}") from exc
        return secret
    return env.get("FBS_COOKIE_SECRET") or env.get("PANEL_COOKIE_SECRET") or ""


def default_app() -> str:
    """Path of the installed dashboard script ``app/main.py``."""
    spec = importlib.util.find_spec("app")
    if spec is None or not spec.submodule_search_locations:
        raise SettingError("the package 'app' is not installed; set FBS_APP to a Panel script")
    return str(Path(next(iter(spec.submodule_search_locations))) / "main.py")


def _check_public_url(env: dict[str, str]) -> None:
    """``FBS_PUBLIC_URL`` checked by the app's own rule (:mod:`app.public_url`)."""
    if not env.get("FBS_PUBLIC_URL", "").strip():
        return
    try:
        from app.public_url import PublicURLError, check_public_url
    except ImportError:
        raise SettingError("FBS_PUBLIC_URL needs the package 'app' (not installed)") from None
    try:
        check_public_url(env["FBS_PUBLIC_URL"])
    except PublicURLError as exc:
        raise SettingError(str(exc)) from None


def build_launch(env: dict[str, str], extra: list[str]) -> Launch:
    """Arguments of ``panel serve``, private settings and warnings, from the environment.

    Raises
    ------
    SettingError
        For a variable with a value that cannot be used (the message names it).
    """
    warnings: list[str] = []
    app = env.get("FBS_APP") or default_app()
    if not os.path.isfile(app):
        raise SettingError(f"FBS_APP: the Panel script {app!r} does not exist")
    port = _positive_int(env, "FBS_PORT", DEFAULT_PORT)
    address = env.get("FBS_ADDRESS", "0.0.0.0").strip() or "0.0.0.0"
    args = [app, "--address", address, "--port", str(port)]
    threads = _positive_int(env, "FBS_NUM_THREADS", 4)
    if env.get("PANEL_NUM_THREADS"):
        warnings.append("PANEL_NUM_THREADS is set and wins over FBS_NUM_THREADS")
    else:
        args += ["--num-threads", str(threads)]

    if "PANEL_BASIC_AUTH" in env:
        raise SettingError(
            "PANEL_BASIC_AUTH is not supported here (Panel lower-cases its value); "
            "use FBS_BASIC_AUTH or FBS_BASIC_AUTH_FILE"
        )
    if env.get("FBS_BASIC_AUTH") and env.get("FBS_BASIC_AUTH_FILE"):
        raise SettingError("set FBS_BASIC_AUTH or FBS_BASIC_AUTH_FILE, not both")
    private: dict = {}
    if env.get("FBS_BASIC_AUTH_FILE"):
        _check_users_file(env["FBS_BASIC_AUTH_FILE"])
        private["basic_auth"] = env["FBS_BASIC_AUTH_FILE"]
    elif env.get("FBS_BASIC_AUTH"):
        private["basic_auth"] = parse_users(env["FBS_BASIC_AUTH"])
    oauth = bool(env.get("PANEL_OAUTH_PROVIDER"))
    if private and oauth:
        raise SettingError(
            "basic authentication (FBS_BASIC_AUTH*) and PANEL_OAUTH_PROVIDER "
            "exclude each other: choose one"
        )
    options = {
        "login_max_failures": _positive_int(env, "FBS_LOGIN_MAX_FAILURES", 10),
        "trusted_proxies": _networks(env, "FBS_TRUSTED_PROXIES"),
        "max_connections": _positive_int(env, "FBS_MAX_CONNECTIONS", 1000),
        "max_connections_per_client": _positive_int(env, "FBS_MAX_CONNECTIONS_PER_CLIENT", 64),
        "header_timeout_s": _positive_int(env, "FBS_HEADER_TIMEOUT_S", 10),
        "body_timeout_s": _positive_int(env, "FBS_BODY_TIMEOUT_S", 30),
        "page_build_share": _share(env, "FBS_PAGE_BUILD_SHARE", 0.5),
        "page_build_share_per_user": _share(env, "FBS_PAGE_BUILD_SHARE_PER_USER", 0.2),
        "page_build_burst_s": _positive_int(env, "FBS_PAGE_BUILD_BURST_S", 8),
        "page_build_burst_s_per_user": _positive_int(env, "FBS_PAGE_BUILD_BURST_S_PER_USER", 4),
    }

    secret = _cookie_secret(env)
    if secret and len(secret) < MIN_SECRET_LEN:
        raise SettingError(
            f"the cookie secret must have at least {MIN_SECRET_LEN} characters "
            f"(has {len(secret)}); make one with "
            "python3 -c 'import secrets; print(secrets.token_urlsafe(32))'"
        )
    if not secret and (private or oauth):
        secret = secrets.token_urlsafe(32)
        warnings.append("no FBS_COOKIE_SECRET: made a random one, logins end at restart")
    if secret:
        private["cookie_secret"] = secret

    _check_public_url(env)
    prefix = env.get("FBS_PREFIX", "").strip("/")
    if prefix:
        args += [f"--prefix={prefix}"]
    if _flag(env, "FBS_USE_XHEADERS"):
        if not options["trusted_proxies"]:
            raise SettingError(
                "FBS_USE_XHEADERS=true needs FBS_TRUSTED_PROXIES: the address(es) or "
                "network(s) of the reverse proxy, e.g. 172.18.0.2 or 10.0.0.0/8 (forwarding "
                "headers from anyone else must not name the client)"
            )
        args += ["--use-xheaders"]
    # an uploaded file travels base64-encoded in one message: 135 MiB carries fbs_core's
    # largest file (100 MiB), which gets the app's clear answer; a larger message is refused
    # by the size its frame declares before any of it is read (read and decoded, a 147 MB
    # message takes the server from 0.98 to 2.2 GB), and its websocket is closed
    size = _positive_int(env, "FBS_WEBSOCKET_MAX_MESSAGE_MB", WEBSOCKET_MAX_MESSAGE_MB)
    args += ["--websocket-max-message-size", str(size * 1024 * 1024)]
    level = env.get("FBS_LOG_LEVEL", "info").strip().lower()
    if level not in LOG_LEVELS:
        raise SettingError(f"FBS_LOG_LEVEL={level!r}: allowed values are {', '.join(LOG_LEVELS)}")
    args += ["--log-level", level]
    for arg in extra:
        if arg.split("=", 1)[0] in ("--cookie-secret", "--basic-auth", "--oauth-secret"):
            raise SettingError(
                f"{arg.split('=', 1)[0]} on the command line is visible to every user of the "
                "host (ps, docker top): use FBS_COOKIE_SECRET(_FILE), FBS_BASIC_AUTH(_FILE) "
                "or PANEL_OAUTH_SECRET"
            )
    return Launch(args + list(extra), private, options, warnings)


def healthcheck(env: dict[str, str]) -> int:
    """Exit status 0 when ``/liveness`` answers 200 with all applications alive, else 1."""
    prefix = env.get("FBS_PREFIX", "").strip("/")
    port = _positive_int(env, "FBS_PORT", DEFAULT_PORT)
    url = f"http://127.0.0.1:{port}/{prefix + '/' if prefix else ''}liveness"
    try:
        with urllib.request.urlopen(url, timeout=4) as resp:
            ok = resp.status == 200 and all(json.load(resp).values())
    except Exception as exc:  # any failure means unhealthy
        print(f"unhealthy: {url}: {exc}", file=sys.stderr)
        return 1
    return 0 if ok else 1


def exec_server(launch: Launch, env: dict[str, str]) -> None:
    """Replace this process by the server stage; secrets travel in an unlinked file."""
    blob = json.dumps({"private": launch.private, "options": launch.options}).encode()
    with tempfile.TemporaryFile() as f:  # no name on disk; closed by the server once read
        f.write(blob)
        f.flush()
        fd = os.dup(f.fileno())
    os.lseek(fd, 0, os.SEEK_SET)
    os.set_inheritable(fd, True)
    argv = [sys.executable, str(Path(__file__).resolve()), SERVE_FD, str(fd), "--", *launch.args]
    os.execve(sys.executable, argv, server_environment(env))


def server_environment(env: dict[str, str]) -> dict[str, str]:
    """The server stage's environment: ``env`` without the secrets, and one thread per
    native thread pool (BLAS, OpenMP) unless ``env`` sets its own.

    The server's dense linear algebra is small (6x6 interface solves, the chassis' 264-DOF
    eigenproblem) and runs beside the event loop, the numba kernels' threads and other
    sessions' bands: OpenBLAS's threads, which spin while they wait for work, only fight
    them for the cores. On the 2-core machine with its cores busy the chassis' modal
    decomposition took 1.4-2.2 s with OpenBLAS's default of a thread per core, 0.08-0.12 s
    with one (``bench/bench_blas_threads.py``).
    """
    clean = {k: v for k, v in env.items() if k not in SECRET_VARS}
    for name in NATIVE_THREAD_VARS:
        clean.setdefault(name, "1")
    return clean


def run_server(argv: list[str]) -> int:
    """The server stage: ``--serve-fd FD -- ARGS`` (started by :func:`exec_server`)."""
    fd = int(argv[1])
    with os.fdopen(fd, "rb") as f:
        settings = json.loads(f.read() or b"{}")
    sys.path.insert(0, str(HERE))
    import fbs_server

    return fbs_server.serve(argv[3:], settings.get("private", {}), settings.get("options", {}))


def main(argv: list[str]) -> int:
    env = dict(os.environ)
    if argv[:1] == ["--healthcheck"]:
        return healthcheck(env)
    if argv[:1] == [SERVE_FD] and argv[2:3] == ["--"]:
        return run_server(argv)
    dry = argv[:1] == ["--print-command"]
    try:
        launch = build_launch(env, argv[1:] if dry else argv)
    except SettingError as exc:
        print(f"tire-fbs: configuration error: {exc}", file=sys.stderr)
        return 2
    for w in launch.warnings:
        print(f"tire-fbs: warning: {w}", file=sys.stderr)
    private = ", ".join(sorted(launch.private)) or "none"
    print(
        "tire-fbs: panel serve " + " ".join(launch.args) + f"  (private settings: {private})",
        file=sys.stderr,
        flush=True,
    )
    if dry:
        return 0
    exec_server(launch, env)
    return 0  # not reached


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
