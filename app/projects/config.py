"""The deployment's groups and data directory, from the environment.

Users log in as today (``FBS_BASIC_AUTH`` / ``FBS_BASIC_AUTH_FILE`` or OAuth, see
docs/deployment.md); which groups they belong to is set by one of

``FBS_GROUPS``
    ``group:user,user;group:user`` (``;`` or a new line between groups), e.g.
    ``oem:alice,bob;supplier_x:carol``.
``FBS_ACCESS_FILE``
    The path of a TOML file with a ``[groups]`` table of lists::

        [groups]
        oem = ["alice", "bob"]
        supplier_x = ["carol"]

A malformed setting raises :class:`~app.projects.errors.AccessConfigError` naming the entry;
the server refuses to start with it. ``FBS_DATA_DIR`` is where projects are stored
(default :data:`DEFAULT_DATA_DIR`, the container's data volume).
"""

from __future__ import annotations

import os
import re
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from .errors import AccessConfigError
from .records import User

__all__ = [
    "DEFAULT_DATA_DIR",
    "AccessConfig",
    "data_dir",
    "load_access_config",
    "parse_access_file",
    "parse_groups",
]

#: Where projects are stored when ``FBS_DATA_DIR`` is not set: the container's data volume.
DEFAULT_DATA_DIR = "/data"

_GROUP = re.compile(r"[A-Za-z0-9_.-]{1,64}")
_BAD_USER_CHARS = set(",;:\n\r\t\0")


@dataclass(frozen=True)
class AccessConfig:
    """Groups of the deployment: group name -> its users."""

    groups: Mapping[str, frozenset[str]]

    def user(self, name: str) -> User:
        """The user ``name`` with the groups it belongs to (none for an unknown name)."""
        return User(name, frozenset(g for g, users in self.groups.items() if name in users))

    def unknown_users(self, logins: Iterable[str]) -> tuple[str, ...]:
        """Users named in groups that are not among ``logins`` (a likely typo)."""
        known = set(logins)
        return tuple(sorted({u for us in self.groups.values() for u in us} - known))


def _group_name(name: str, where: str) -> str:
    if not _GROUP.fullmatch(name):
        raise AccessConfigError(
            f"{where}: group name {name!r} must be 1-64 letters, digits, '_', '.' or '-'"
        )
    return name


def _user_name(name: str, where: str) -> str:
    if not name or len(name) > 128 or _BAD_USER_CHARS & set(name) or name != name.strip():
        raise AccessConfigError(
            f"{where}: user name {name!r} must be 1-128 characters without , ; : or spaces "
            "around it"
        )
    return name


def parse_groups(text: str, source: str = "FBS_GROUPS") -> AccessConfig:
    """Groups from ``group:user,user;group:user`` text (``;`` or new lines between groups).

    Raises
    ------
    AccessConfigError
        For an entry without ``:``, a bad group or user name, a group given twice or one
        without users, naming the entry.
    """
    groups: dict[str, frozenset[str]] = {}
    for i, raw in enumerate(re.split(r"[;\n]", text), start=1):
        entry = raw.strip()
        if not entry:
            continue
        where = f"{source} entry {i} ({entry[:60]!r})"
        if ":" not in entry:
            raise AccessConfigError(f"{where}: expected group:user,user")
        group, users_text = entry.split(":", 1)
        group = _group_name(group.strip(), where)
        if group in groups:
            raise AccessConfigError(f"{where}: group {group!r} is given twice")
        users = [u.strip() for u in users_text.split(",") if u.strip()]
        if not users:
            raise AccessConfigError(f"{where}: group {group!r} has no users")
        groups[group] = frozenset(_user_name(u, where) for u in users)
    return AccessConfig(groups)


def parse_access_file(path: str | os.PathLike[str]) -> AccessConfig:
    """Groups from a TOML file with a ``[groups]`` table of user lists.

    Raises
    ------
    AccessConfigError
        When the file cannot be read, is not TOML, has no ``[groups]`` table, or holds a bad
        group or user name (naming the file and the key).
    """
    where = f"access file {os.fspath(path)!r}"
    try:
        with open(path, "rb") as f:
            doc = tomllib.load(f)
    except OSError as exc:
        raise AccessConfigError(f"{where} cannot be read: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise AccessConfigError(f"{where} is not valid TOML: {exc}") from None
    table = doc.get("groups")
    if not isinstance(table, dict):
        raise AccessConfigError(f'{where}: needs a [groups] table (oem = ["alice", "bob"])')
    unknown = sorted(set(doc) - {"groups"})
    if unknown:
        raise AccessConfigError(f"{where}: unknown table or key {unknown[0]!r}")
    groups: dict[str, frozenset[str]] = {}
    for group, users in table.items():
        key = f"{where}, groups.{group}"
        _group_name(group, key)
        if not isinstance(users, list) or not users or not all(isinstance(u, str) for u in users):
            raise AccessConfigError(f"{key}: must be a non-empty list of user names")
        groups[group] = frozenset(_user_name(u, key) for u in users)
    return AccessConfig(groups)


def load_access_config(environ: Mapping[str, str] | None = None) -> AccessConfig:
    """The groups of the deployment from ``FBS_GROUPS`` or ``FBS_ACCESS_FILE`` (not both).

    Neither set: no groups, so nobody opens any project (projects are off).
    """
    env = os.environ if environ is None else environ
    text, path = env.get("FBS_GROUPS", "").strip(), env.get("FBS_ACCESS_FILE", "").strip()
    if text and path:
        raise AccessConfigError("set FBS_GROUPS or FBS_ACCESS_FILE, not both")
    if path:
        return parse_access_file(path)
    return parse_groups(text)


def data_dir(environ: Mapping[str, str] | None = None) -> Path:
    """The data directory: ``FBS_DATA_DIR`` or :data:`DEFAULT_DATA_DIR`."""
    env = os.environ if environ is None else environ
    return Path(env.get("FBS_DATA_DIR", "").strip() or DEFAULT_DATA_DIR)
