"""Projects on the server: candidates, targets, views and notes kept per project, with
access per group and an audit log (docs/projects.md).

:class:`Projects` is the service the page and the server call; :mod:`.access` the pure
access policy; :mod:`.storage` the atomic SQLite-and-files storage; :mod:`.config` the
deployment's groups and data directory.
"""

from __future__ import annotations

from .access import (
    ANOTHER_CANDIDATE,
    can_open,
    candidate_visible,
    redact_ranking,
    visible_candidates,
)
from .config import AccessConfig, data_dir, load_access_config, parse_access_file, parse_groups
from .errors import (
    AccessConfigError,
    AccessDenied,
    Conflict,
    DiskFull,
    NotFound,
    ProjectError,
    StorageError,
)
from .records import (
    AuditEntry,
    Candidate,
    GroupAccess,
    Note,
    ProjectInfo,
    ProjectPage,
    ResolvedView,
    Target,
    User,
    View,
)
from .service import Projects, upload_digest
from .startup import projects_at_start

__all__ = [
    "ANOTHER_CANDIDATE",
    "AccessConfig",
    "AccessConfigError",
    "AccessDenied",
    "AuditEntry",
    "Candidate",
    "Conflict",
    "DiskFull",
    "GroupAccess",
    "Note",
    "NotFound",
    "ProjectError",
    "ProjectInfo",
    "ProjectPage",
    "Projects",
    "ResolvedView",
    "StorageError",
    "Target",
    "User",
    "View",
    "can_open",
    "candidate_visible",
    "data_dir",
    "load_access_config",
    "parse_access_file",
    "parse_groups",
    "projects_at_start",
    "redact_ranking",
    "upload_digest",
    "visible_candidates",
]
