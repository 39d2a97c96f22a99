"""The records of a project, as the service hands them out: immutable, plain values.

A project (:class:`ProjectInfo`) lists which groups may open it and, per group, which
candidates it sees (:class:`GroupAccess`). Its candidates (:class:`Candidate`: a tire file as
uploaded with name, supplier, size, version and digest), targets (:class:`Target`), named
views (:class:`View`: the page's settings and pins as URL query text), notes (:class:`Note`)
and its audit log (:class:`AuditEntry`) are stored by :mod:`app.projects.storage` and filtered
for each user by :mod:`app.projects.access` before they leave the service.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "FULL_ONLY",
    "Audience",
    "AuditEntry",
    "Candidate",
    "GroupAccess",
    "ProjectInfo",
    "ProjectPage",
    "Note",
    "ResolvedView",
    "Target",
    "User",
    "View",
]

#: Who may read a note or an audit entry: ``None`` everyone who opens the project; a set of
#: supplier names: the groups that see all candidates, and those that see these suppliers'
#: candidates; :data:`FULL_ONLY`: only the groups that see all candidates. ``"*"`` is refused
#: as a supplier name, so no supplier group's set ever holds it.
Audience = frozenset[str] | None
FULL_ONLY: frozenset[str] = frozenset({"*"})


@dataclass(frozen=True)
class User:
    """A logged-in user and the deployment's groups it belongs to."""

    name: str
    groups: frozenset[str]


@dataclass(frozen=True)
class GroupAccess:
    """What one group sees of a project.

    Attributes
    ----------
    group : str
        Group name from the deployment's configuration.
    suppliers : frozenset of str or None
        ``None``: every candidate (and the project's administration: access, targets, any
        candidate's removal). A set: only the candidates whose supplier is in it (compared
        without case), plus the targets and what its members wrote themselves.
    """

    group: str
    suppliers: frozenset[str] | None


@dataclass(frozen=True)
class ProjectInfo:
    """A project's identity and access list (the first record of its database)."""

    id: str
    title: str
    created_by: str
    created_at: str
    access: tuple[GroupAccess, ...]


@dataclass(frozen=True)
class Candidate:
    """A tire file of the project, as uploaded.

    ``sha256`` (hex of the file's bytes) names the file in the data directory; ``digest`` is
    the key the dashboard gives the same upload (first 24 hex characters of SHA-256 over the
    bytes and the import settings, ``app.datasource``), so a view's candidates are found
    again. A removed candidate keeps its record (``removed_by``/``removed_at``): views that
    show it say so, the audit log keeps its name; its file is deleted.
    """

    id: int
    name: str
    supplier: str
    size: str
    version: str
    filename: str
    sha256: str
    digest: str
    n_bytes: int
    added_by: str
    added_at: str
    removed_by: str | None = None
    removed_at: str | None = None

    @property
    def removed(self) -> bool:
        return self.removed_at is not None


@dataclass(frozen=True)
class Target:
    """A target file of the project (bushing targets), as uploaded."""

    id: int
    name: str
    filename: str
    sha256: str
    n_bytes: int
    added_by: str
    added_at: str
    removed_by: str | None = None
    removed_at: str | None = None

    @property
    def removed(self) -> bool:
        return self.removed_at is not None


@dataclass(frozen=True)
class View:
    """A named view: the page's settings and pins as URL query text.

    ``candidates`` are the ids of the candidates the view shows (given when it was saved, and
    every candidate whose digest its query text contains): a user sees the view only when it
    may see all of them. Its id is ``<project id>-<12 random characters>``: the only thing
    its link carries.
    """

    id: str
    name: str
    query: str
    candidates: tuple[int, ...]
    saved_by: str
    saved_at: str


@dataclass(frozen=True)
class Note:
    """A short note; ``audience`` says who reads it (:data:`Audience`)."""

    id: int
    text: str
    audience: Audience
    written_by: str
    written_at: str


@dataclass(frozen=True)
class AuditEntry:
    """One line of the append-only audit log: who did what to which item, when."""

    seq: int
    at: str
    user: str
    action: str
    what: str
    candidates: tuple[int, ...]
    audience: Audience


@dataclass(frozen=True)
class ProjectPage:
    """What one user sees of an opened project (already filtered by the access rules)."""

    info: ProjectInfo
    candidates: tuple[Candidate, ...]
    removed: tuple[Candidate, ...]
    targets: tuple[Target, ...]
    views: tuple[View, ...]
    notes: tuple[Note, ...]
    full_access: bool


@dataclass(frozen=True)
class ResolvedView:
    """A view opened from its link: its project, its query, the candidates it lacks.

    ``missing`` names the view's candidates that were removed since it was saved (the view
    still opens, without them).
    """

    project: ProjectInfo
    view: View
    query: str
    missing: tuple[str, ...]
