"""The exceptions of the projects store: each names the project, item or setting at fault.

Every error is a :class:`ProjectError`; the page shows its text as it is. An operation that
raises has changed nothing (the files and records of a project are written in one step,
:mod:`app.projects.storage`).
"""

from __future__ import annotations

__all__ = [
    "AccessConfigError",
    "AccessDenied",
    "Conflict",
    "DiskFull",
    "NotFound",
    "ProjectError",
    "StorageError",
]


class ProjectError(Exception):
    """Any refusal of the projects store (bad input, access, storage)."""


class AccessConfigError(ProjectError, ValueError):
    """The deployment's groups setting (``FBS_GROUPS`` / ``FBS_ACCESS_FILE``) is malformed."""


class AccessDenied(ProjectError):
    """The user may not do this; the message names nothing the user may not see."""


class NotFound(ProjectError):
    """No such project, candidate, target or view (among those the user may see)."""


class Conflict(ProjectError, ValueError):
    """Bad input: a duplicate name or file, an empty or too long text, a file too large."""


class StorageError(ProjectError):
    """The data directory cannot be read or written, or a project's database is damaged."""


class DiskFull(StorageError):
    """The data volume is full; nothing was written."""
