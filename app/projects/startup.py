"""The projects store at the server's start: on when groups are configured, checked, logged.

The server calls :func:`projects_at_start` once before it listens. Without ``FBS_GROUPS`` or
``FBS_ACCESS_FILE`` projects are off (``None``: nobody could open one). With them, a malformed
setting or an unwritable data directory raises a
:class:`~app.projects.errors.ProjectError` naming the problem (the server refuses to start),
projects that cannot be opened are logged with the reason and the others are served, and
group members that are not among the login users are logged (a likely typo).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable, Mapping

from .service import Projects

__all__ = ["projects_at_start"]

log = logging.getLogger("tire_fbs.projects")


def projects_at_start(
    environ: Mapping[str, str] | None = None, logins: Iterable[str] | None = None
) -> Projects | None:
    """The server's projects service, or ``None`` when no groups are configured.

    Parameters
    ----------
    environ : mapping, optional
        The environment (default ``os.environ``).
    logins : iterable of str, optional
        The login users (basic authentication), to name group members that cannot log in.
    """
    env = os.environ if environ is None else environ
    if not (env.get("FBS_GROUPS", "").strip() or env.get("FBS_ACCESS_FILE", "").strip()):
        log.info("projects off: no FBS_GROUPS or FBS_ACCESS_FILE")
        return None
    projects = Projects.from_env(env)
    for problem in projects.problems:
        log.error("project not served: %s: %s", problem.path, problem.message)
    if logins is not None:
        unknown = projects.access.unknown_users(logins)
        if unknown:
            log.warning("group members without a login: %s", ", ".join(unknown))
    n = len(projects.store.ids())
    log.info(
        "projects on: %d in %s, groups %s",
        n,
        projects.store.root,
        ", ".join(sorted(projects.access.groups)),
    )
    return projects
