"""The deployment's public base URL (``FBS_PUBLIC_URL``): the links a page hands out.

Behind a reverse proxy, a tunnel or a port mapping, the address in the browser's location
bar (``http://localhost:5006/main``) is not the address a recipient of a report, a CSV or
a saved plot can open. ``FBS_PUBLIC_URL`` names the address at which the server's root is
reached from outside (with ``FBS_PREFIX``: the address of the prefix), e.g.
``https://nvh.example.com/tire-fbs``; every link the page writes then starts with it and
keeps the page's path and query (``https://nvh.example.com/tire-fbs/main?h=4&N=60``).

No Panel here: the container's entrypoint checks the variable with :func:`check_public_url`
before the server starts (a wrong value stops it with a message naming the variable).
"""

from __future__ import annotations

import os
import urllib.parse
from collections.abc import Mapping

__all__ = ["PUBLIC_URL_ENV", "PublicURLError", "check_public_url", "public_base", "public_link"]

#: The environment variable holding the public base URL.
PUBLIC_URL_ENV = "FBS_PUBLIC_URL"
#: The environment variable of the server's URL prefix (``panel serve --prefix``).
PREFIX_ENV = "FBS_PREFIX"
_EXAMPLE = "e.g. https://nvh.example.com or https://nvh.example.com/tire-fbs"


class PublicURLError(ValueError):
    """A public base URL that links cannot start with."""


def check_public_url(value: str, name: str = PUBLIC_URL_ENV) -> str:
    """``value`` as a base for links (no trailing ``/``); ``""`` for an empty value.

    Raises
    ------
    PublicURLError
        Naming ``name`` and the value, when it is not an absolute http(s) address with a
        host, or carries a query, a fragment, user info, spaces, quotes or angle brackets.
    """
    raw = str(value or "").strip()
    if not raw:
        return ""
    bad = f"{name}={raw!r}"
    if any(c in raw for c in "\"'<> \t\n\\"):
        raise PublicURLError(f"{bad}: must not contain spaces, quotes or angle brackets")
    u = urllib.parse.urlsplit(raw)
    if u.scheme not in ("http", "https"):
        raise PublicURLError(f"{bad}: must start with http:// or https:// ({_EXAMPLE})")
    if not u.hostname:
        raise PublicURLError(f"{bad}: names no host ({_EXAMPLE})")
    if u.username is not None or u.password is not None:
        raise PublicURLError(f"{bad}: must not hold a user name or password")
    if u.query or u.fragment or raw.endswith(("?", "#")):
        raise PublicURLError(
            f"{bad}: must not hold a query (?) or fragment (#); the page adds its own"
        )
    try:
        u.port  # noqa: B018  (raises for a port that is not a number in 0-65535)
    except ValueError:
        raise PublicURLError(f"{bad}: the port is not a number in 0-65535") from None
    return raw.rstrip("/")


def public_base(env: Mapping[str, str] | None = None) -> str:
    """The checked ``FBS_PUBLIC_URL`` of ``env`` (default the process's), ``""`` if unset."""
    env = os.environ if env is None else env
    return check_public_url(env.get(PUBLIC_URL_ENV, ""))


def public_link(href: str, env: Mapping[str, str] | None = None) -> str:
    """``href`` (the page's address as the browser sees it) with its scheme, host and
    server prefix replaced by the public base URL; ``href`` itself when none is set.

    Examples
    --------
    >>> env = {"FBS_PUBLIC_URL": "https://nvh.example.com/fbs"}
    >>> public_link("http://localhost:5006/main?h=4", env)
    'https://nvh.example.com/fbs/main?h=4'
    >>> env["FBS_PREFIX"] = "tire-fbs"
    >>> public_link("http://127.0.0.1:5006/tire-fbs/main", env)
    'https://nvh.example.com/fbs/main'
    """
    env = os.environ if env is None else env
    base = public_base(env)
    if not base or not href:
        return href
    u = urllib.parse.urlsplit(href)
    path = u.path or "/"
    prefix = "/" + env.get(PREFIX_ENV, "").strip().strip("/")
    if prefix != "/" and (path == prefix or path.startswith(prefix + "/")):
        path = path[len(prefix) :] or "/"
    out = base + (path if path.startswith("/") else "/" + path)
    return out + ("?" + u.query if u.query else "")
