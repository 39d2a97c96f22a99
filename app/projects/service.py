"""The projects service: what the page and the server call (docs/projects.md).

Every call names the user (a login name, or a :class:`~app.projects.records.User`) and goes
through the access policy (:mod:`app.projects.access`) before anything is read or written;
what the user may not see never leaves this module. Writes are atomic
(:mod:`app.projects.storage`); every addition, removal, opening, view and export is written
to the project's append-only audit log.

Errors are :class:`~app.projects.errors.ProjectError` subclasses whose text names the
problem and nothing the user may not see: :class:`AccessDenied`, :class:`NotFound`,
:class:`Conflict` (bad input), :class:`StorageError` / :class:`DiskFull`.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import re
import secrets
import sqlite3
from collections.abc import Iterable, Mapping
from pathlib import Path

from . import access as policy
from .config import AccessConfig, data_dir, load_access_config
from .errors import AccessDenied, Conflict, NotFound, ProjectError
from .records import (
    FULL_ONLY,
    Audience,
    AuditEntry,
    Candidate,
    GroupAccess,
    Note,
    ProjectInfo,
    ProjectPage,
    ResolvedView,
    Target,
    User,
)
from .storage import Problem, ProjectDB, ProjectStore, now_text

__all__ = ["MAX_QUERY_CHARS", "Projects", "upload_digest"]

#: Largest file kept (bytes): the limit of the files ``fbs_core.io`` reads (100 MiB), so
#: that a project holds no file the dashboard would refuse. Not imported from there: the
#: store starts without loading the numerical libraries.
DEFAULT_MAX_BYTES = 100 * 1024 * 1024
#: Longest text of a title, name, supplier, size, version or file name.
MAX_TEXT = 120
#: Longest note.
MAX_NOTE = 2000
#: Longest query text of a view (what a link carries).
MAX_QUERY_CHARS = 8000
_VIEW_ID = re.compile(r"([0-9a-f]{16})-([A-Za-z0-9_-]{12})")
_CANDIDATE_KEYS = {"name", "supplier", "size", "version"}


def upload_digest(data: bytes) -> str:
    """The key the dashboard gives an uploaded tire file (``app.datasource``): 24 hex
    characters of SHA-256 over the bytes and the (empty) import settings."""
    return _digests(data)[1]


def _digests(data: bytes) -> tuple[str, str]:
    """``(sha256 hex of the bytes, upload_digest)`` in one pass over the bytes."""
    h = hashlib.sha256(data)
    full = h.hexdigest()
    h.update(repr(sorted({}.items())).encode())
    return full, h.hexdigest()[:24]


def _text(value: object, what: str, required: bool = False, limit: int = MAX_TEXT) -> str:
    if not isinstance(value, str):
        raise Conflict(f"the {what} must be text, got {type(value).__name__}")
    s = " ".join(value.split())
    if required and not s:
        raise Conflict(f"the {what} must not be empty")
    if len(s) > limit:
        raise Conflict(f"the {what} is {len(s)} characters long; at most {limit}")
    return s


def _file(filename: object, data: object, what: str) -> tuple[str, bytes]:
    name = _text(filename, f"{what}'s file name", required=True)
    name = os.path.basename(name.replace("\\", "/")) or name
    if not isinstance(data, bytes | bytearray | memoryview):
        raise Conflict(f"the {what} file {name!r} must be bytes, got {type(data).__name__}")
    raw = bytes(data)
    if not raw:
        raise Conflict(f"the {what} file {name!r} is empty")
    if len(raw) > DEFAULT_MAX_BYTES:
        raise Conflict(
            f"the {what} file {name!r} has {len(raw) / 2**20:.1f} MiB; at most "
            f"{DEFAULT_MAX_BYTES / 2**20:.0f} MiB"
        )
    return name, raw


class Projects:
    """The projects of one data directory, for the users of one deployment.

    Parameters
    ----------
    root : path
        The data directory (``FBS_DATA_DIR``).
    access : AccessConfig
        The deployment's groups (``FBS_GROUPS`` / ``FBS_ACCESS_FILE``).
    scan : bool
        Check and clean every project now (at the server's start); the damaged ones are in
        :attr:`problems` and the others open.
    """

    def __init__(self, root: Path | str, access: AccessConfig, scan: bool = True) -> None:
        self.store = ProjectStore(root)
        self.access = access
        if scan:
            self.store.scan()

    @classmethod
    def from_env(cls, environ: Mapping[str, str] | None = None) -> Projects:
        """The service of ``FBS_DATA_DIR`` with the groups of ``FBS_GROUPS`` /
        ``FBS_ACCESS_FILE`` (errors name the setting)."""
        return cls(data_dir(environ), load_access_config(environ))

    @property
    def problems(self) -> tuple[Problem, ...]:
        """Projects that could not be opened at start, each with the reason."""
        return self.store.problems

    # ---- who -----------------------------------------------------------------------------------

    def user(self, user: str | User) -> User:
        """The user with its groups (a name is looked up in the deployment's groups)."""
        if isinstance(user, User):
            return user
        if not isinstance(user, str) or not user:
            raise AccessDenied("no user: log in to open projects")
        return self.access.user(user)

    def _open(self, user: User, pid: str) -> tuple[ProjectDB, ProjectInfo]:
        db = self.store.project(pid)
        info = db.info()
        if not policy.can_open(user, info):
            raise AccessDenied(f"project {pid}: you may not open it")
        return db, info

    def _admin(self, user: User, pid: str, what: str) -> tuple[ProjectDB, ProjectInfo]:
        db, info = self._open(user, pid)
        if not policy.may_administer(user, info):
            raise AccessDenied(f"{what}: only the groups that see all candidates may do this")
        return db, info

    @staticmethod
    def _shown_info(user: User, info: ProjectInfo) -> ProjectInfo:
        """The project as ``user`` sees it: a supplier's group sees its own access entries
        only (not which other suppliers take part)."""
        if policy.full_access(user, info):
            return info
        mine = tuple(a for a in info.access if a.group in user.groups)
        return ProjectInfo(info.id, info.title, info.created_by, info.created_at, mine)

    def _access(self, access: Mapping[str, Iterable[str] | None]) -> tuple[GroupAccess, ...]:
        if not isinstance(access, Mapping) or not access:
            raise Conflict("a project needs at least one group that may open it")
        out = []
        for group, suppliers in access.items():
            if group not in self.access.groups:
                raise Conflict(
                    f"group {group!r} is not among the deployment's groups "
                    f"({', '.join(sorted(self.access.groups)) or 'none set: FBS_GROUPS'})"
                )
            if suppliers is None:
                out.append(GroupAccess(group, None))
                continue
            if isinstance(suppliers, str):
                raise Conflict(f"group {group!r}: give its suppliers as a list, not one text")
            names = frozenset(_text(s, "supplier name", required=True) for s in suppliers)
            if "*" in names:
                raise Conflict(f"group {group!r}: '*' is not a supplier name")
            out.append(GroupAccess(group, names))
        return tuple(sorted(out, key=lambda a: a.group))

    # ---- projects ------------------------------------------------------------------------------

    def create_project(
        self, user: str | User, title: str, access: Mapping[str, Iterable[str] | None]
    ) -> ProjectInfo:
        """Create a project.

        Parameters
        ----------
        title : str
            E.g. ``"rear axle, summer tire sourcing 2027"``.
        access : mapping
            Group -> ``None`` (sees every candidate, administers) or the supplier names
            whose candidates it sees. The creator must be in a group with ``None``.
        """
        who = self.user(user)
        title = _text(title, "project title", required=True)
        entries = self._access(access)
        probe = ProjectInfo("", title, who.name, "", entries)
        if not policy.full_access(who, probe):
            raise AccessDenied(
                f"project {title!r}: list one of your groups "
                f"({', '.join(sorted(who.groups)) or 'none'}) as seeing all candidates"
            )
        db = self.store.create(title, who.name, entries, None)
        return db.info()

    def set_access(
        self, user: str | User, pid: str, access: Mapping[str, Iterable[str] | None]
    ) -> ProjectInfo:
        """Replace the project's access list (full-access groups only; the caller must keep
        full access, so that a project is never left without administrators)."""
        who = self.user(user)
        db, info = self._admin(who, pid, f"project {pid}: changing access")
        entries = self._access(access)
        after = ProjectInfo(info.id, info.title, info.created_by, info.created_at, entries)
        if not policy.full_access(who, after):
            raise Conflict(f"project {pid}: the new access list would shut you out")

        def body(conn: sqlite3.Connection) -> None:
            ProjectDB.put_access(conn, entries)
            text = "; ".join(
                f"{a.group}: {'all' if a.suppliers is None else ', '.join(sorted(a.suppliers))}"
                for a in entries
            )
            ProjectDB.write_audit(conn, now_text(), who.name, "access", text, (), FULL_ONLY)

        db.write(f"project {pid}: changing access", body)
        return db.info()

    def list_projects(self, user: str | User) -> tuple[ProjectInfo, ...]:
        """The projects ``user`` may open (a damaged one is left out: see :attr:`problems`)."""
        who = self.user(user)
        out = []
        for pid in self.store.ids():
            try:
                info = self.store.project(pid).info()
            except ProjectError:  # damaged since the start: reported by the next scan
                continue
            if policy.can_open(who, info):
                out.append(self._shown_info(who, info))
        return tuple(sorted(out, key=lambda i: (i.title.casefold(), i.id)))

    def open_project(self, user: str | User, pid: str) -> ProjectPage:
        """What ``user`` sees of project ``pid`` (audited as opened)."""
        who = self.user(user)
        db, _ = self._open(who, pid)
        info, candidates, targets, views, notes = db.snapshot()
        if not policy.can_open(who, info):  # access changed between the two reads
            raise AccessDenied(f"project {pid}: you may not open it")
        by_id = {c.id: c for c in candidates}
        visible = policy.visible_candidates(who, info, candidates)
        page = ProjectPage(
            info=self._shown_info(who, info),
            candidates=tuple(c for c in visible if not c.removed),
            removed=tuple(c for c in visible if c.removed),
            targets=tuple(t for t in targets if not t.removed),
            views=tuple(v for v in views if policy.view_visible(who, info, v, by_id)),
            notes=tuple(n for n in notes if policy.note_visible(who, info, n)),
            full_access=policy.full_access(who, info),
        )
        self._log(db, who, "opened", f"project {info.title!r}", (), None)
        return page

    def _log(
        self,
        db: ProjectDB,
        who: User,
        action: str,
        what: str,
        candidates: Iterable[int],
        audience: Audience,
    ) -> None:
        ids = tuple(candidates)

        def body(conn: sqlite3.Connection) -> None:
            ProjectDB.write_audit(conn, now_text(), who.name, action, what, ids, audience)

        db.write(f"project {db.id}: audit log", body)

    # ---- candidates and targets ----------------------------------------------------------------

    def add_candidate(
        self,
        user: str | User,
        pid: str,
        filename: str,
        data: bytes,
        meta: Mapping[str, str],
    ) -> Candidate:
        """Store a tire file as a candidate of project ``pid``.

        ``meta`` holds ``name`` (required, unique among the project's candidates),
        ``supplier``, ``size`` and ``version``. The file is kept as uploaded; the call
        returns once file and record are durable.
        """
        who = self.user(user)
        db, info = self._open(who, pid)
        unknown = sorted(set(meta) - _CANDIDATE_KEYS)
        if unknown:
            raise Conflict(
                f"candidate: unknown field {unknown[0]!r} (fields: name, supplier, size, version)"
            )
        name = _text(meta.get("name", ""), "candidate's name", required=True)
        supplier = _text(meta.get("supplier", ""), "candidate's supplier")
        size = _text(meta.get("size", ""), "candidate's size")
        version = _text(meta.get("version", ""), "candidate's version")
        if not policy.may_add_candidate(who, info, supplier):
            _, mine = policy.supplier_scope(who, info)
            raise AccessDenied(
                f"candidate {name!r}: you may add candidates of "
                f"{', '.join(sorted(mine or ())) or 'no supplier'} only"
            )
        fname, raw = _file(filename, data, f"candidate {name!r}")
        sha256, digest = _digests(raw)
        what = f"project {pid}: adding candidate {name!r}"

        def insert(conn: sqlite3.Connection, sha: str) -> Candidate:
            now = ProjectDB._info(conn)  # the access list as of this transaction
            if not policy.may_add_candidate(who, now, supplier):
                raise AccessDenied(f"{what}: your access to the project has changed")
            for other in ProjectDB._candidates(conn):
                if other.removed:
                    continue
                if other.sha256 == sha:
                    if policy.candidate_visible(who, now, other):
                        raise Conflict(f"{what}: the same file is candidate {other.name!r}")
                    raise Conflict(f"{what}: the project holds this file already")
                same_supplier = policy.supplier_key(other.supplier) == policy.supplier_key(supplier)
                if same_supplier and other.name.casefold() == name.casefold():
                    raise Conflict(
                        f"{what}: {supplier or 'no supplier'} has a candidate of that name"
                    )
            at = now_text()
            cur = conn.execute(
                "INSERT INTO candidates (name, supplier, size, version, filename, sha256, "
                "digest, n_bytes, added_by, added_at) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (name, supplier, size, version, fname, sha, digest, len(raw), who.name, at),
            )
            cid = int(cur.lastrowid or 0)
            ProjectDB.write_audit(conn, at, who.name, "added", f"candidate {name!r}", (cid,), None)
            return Candidate(
                cid, name, supplier, size, version, fname, sha, digest, len(raw), who.name, at
            )

        result: Candidate = db.add_file_record(what, raw, insert, sha256)
        return result

    def _candidate(self, who: User, db: ProjectDB, info: ProjectInfo, cid: int) -> Candidate:
        _, candidates, *_ = db.snapshot()
        for c in candidates:
            if c.id == cid and policy.candidate_visible(who, info, c):
                return c
        raise NotFound(f"project {db.id}: no candidate {cid}")

    def remove_candidate(self, user: str | User, pid: str, cid: int) -> Candidate:
        """Remove a candidate: its file is deleted, its record kept (views that show it
        say so; the audit log keeps its name)."""
        who = self.user(user)
        db, info = self._open(who, pid)
        c = self._candidate(who, db, info, cid)
        if c.removed:
            raise Conflict(f"project {pid}: candidate {c.name!r} was removed already")
        if not policy.may_remove_candidate(who, info, c):
            raise AccessDenied(f"project {pid}: you may not remove candidate {c.name!r}")
        at = now_text()

        def body(conn: sqlite3.Connection) -> None:
            n = conn.execute(
                "UPDATE candidates SET removed_by = ?, removed_at = ? "
                "WHERE id = ? AND removed_at IS NULL",
                (who.name, at, cid),
            ).rowcount
            if n != 1:
                raise Conflict(f"project {pid}: candidate {c.name!r} was removed already")
            ProjectDB.write_audit(
                conn, at, who.name, "removed", f"candidate {c.name!r}", (cid,), None
            )

        db.write(f"project {pid}: removing candidate {c.name!r}", body)
        db.remove_file_if_unused(c.sha256)
        return dataclasses.replace(c, removed_by=who.name, removed_at=at)

    def candidate_file(self, user: str | User, pid: str, cid: int) -> tuple[Candidate, bytes]:
        """A candidate's record and its file as uploaded (audited as exported)."""
        who = self.user(user)
        db, info = self._open(who, pid)
        c = self._candidate(who, db, info, cid)
        if c.removed:
            raise NotFound(f"project {pid}: candidate {c.name!r} was removed; its file is gone")
        data = db.read_file(c.sha256)
        self._log(db, who, "exported", f"file of candidate {c.name!r}", (cid,), None)
        return c, data

    def add_target(
        self, user: str | User, pid: str, filename: str, data: bytes, name: str
    ) -> Target:
        """Store a target file (full-access groups only; every group that opens the
        project sees the targets)."""
        who = self.user(user)
        name = _text(name, "target's name", required=True)
        db, _ = self._admin(who, pid, f"project {pid}: adding target {name!r}")
        fname, raw = _file(filename, data, f"target {name!r}")
        what = f"project {pid}: adding target {name!r}"

        def insert(conn: sqlite3.Connection, sha: str) -> Target:
            at = now_text()
            cur = conn.execute(
                "INSERT INTO targets (name, filename, sha256, n_bytes, added_by, added_at) "
                "VALUES (?, ?, ?, ?, ?, ?)",
                (name, fname, sha, len(raw), who.name, at),
            )
            ProjectDB.write_audit(conn, at, who.name, "added", f"target {name!r}", (), None)
            return Target(int(cur.lastrowid or 0), name, fname, sha, len(raw), who.name, at)

        try:
            result: Target = db.add_file_record(what, raw, insert)
        except Conflict:
            raise Conflict(f"{what}: the project has a target of that name") from None
        return result

    def _target(self, db: ProjectDB, tid: int) -> Target:
        for t in db.snapshot()[2]:
            if t.id == tid:
                return t
        raise NotFound(f"project {db.id}: no target {tid}")

    def remove_target(self, user: str | User, pid: str, tid: int) -> Target:
        who = self.user(user)
        db, _ = self._admin(who, pid, f"project {pid}: removing target {tid}")
        t = self._target(db, tid)
        at = now_text()

        def body(conn: sqlite3.Connection) -> None:
            n = conn.execute(
                "UPDATE targets SET removed_by = ?, removed_at = ? "
                "WHERE id = ? AND removed_at IS NULL",
                (who.name, at, tid),
            ).rowcount
            if n != 1:
                raise Conflict(f"project {pid}: target {t.name!r} was removed already")
            ProjectDB.write_audit(conn, at, who.name, "removed", f"target {t.name!r}", (), None)

        db.write(f"project {pid}: removing target {t.name!r}", body)
        db.remove_file_if_unused(t.sha256)
        return dataclasses.replace(t, removed_by=who.name, removed_at=at)

    def target_file(self, user: str | User, pid: str, tid: int) -> tuple[Target, bytes]:
        who = self.user(user)
        db, _ = self._open(who, pid)
        t = self._target(db, tid)
        if t.removed:
            raise NotFound(f"project {pid}: target {t.name!r} was removed; its file is gone")
        data = db.read_file(t.sha256)
        self._log(db, who, "exported", f"file of target {t.name!r}", (), None)
        return t, data

    # ---- views ---------------------------------------------------------------------------------

    def save_view(
        self,
        user: str | User,
        pid: str,
        name: str,
        query: str,
        candidates: Iterable[int | str] = (),
    ) -> str:
        """Save the page's settings and pins (URL query text) as a named view.

        ``candidates`` are the candidates the view shows, by id or digest; every candidate
        whose digest or SHA-256 the query text contains is added. Returns the view id, the
        only thing its link carries.
        """
        who = self.user(user)
        db, info = self._open(who, pid)
        name = _text(name, "view's name", required=True)
        if not isinstance(query, str):
            raise Conflict(f"view {name!r}: the query must be text, got {type(query).__name__}")
        query = query.strip().removeprefix("?")
        if len(query) > MAX_QUERY_CHARS:
            raise Conflict(
                f"view {name!r}: the query has {len(query)} characters; at most {MAX_QUERY_CHARS}"
            )
        if any(ord(ch) < 32 for ch in query):
            raise Conflict(f"view {name!r}: the query holds control characters")
        all_candidates = db.snapshot()[1]
        by_key: dict[int | str, Candidate] = {}
        for c in all_candidates:
            by_key[c.id] = c
            by_key[c.digest] = c
        refs: set[int] = set()
        for key in candidates:
            given = by_key.get(key)
            if given is None or not policy.candidate_visible(who, info, given):
                raise NotFound(f"view {name!r}: project {pid} has no candidate {key!r}")
            refs.add(given.id)
        for c in all_candidates:
            if c.digest in query or c.sha256 in query:
                refs.add(c.id)
        for cid in refs:
            if not policy.candidate_visible(who, info, by_key[cid]):
                raise NotFound(f"view {name!r}: the query names a candidate you may not see")
        view_id = f"{pid}-{secrets.token_urlsafe(9)}"
        ids = tuple(sorted(refs))

        def body(conn: sqlite3.Connection) -> None:
            at = now_text()
            conn.execute(
                "INSERT INTO views VALUES (?, ?, ?, ?, ?, ?)",
                (view_id, name, query, json.dumps(list(ids)), who.name, at),
            )
            ProjectDB.write_audit(conn, at, who.name, "saved view", f"view {name!r}", ids, None)

        db.write(f"project {pid}: saving view {name!r}", body)
        return view_id

    def resolve_view(self, user: str | User, view_id: str) -> ResolvedView:
        """The project and query text of a view's link, or AccessDenied / NotFound.

        A view of a project the user may not open, or showing a candidate it may not see,
        is refused without telling anything of it. A view whose candidates were removed
        since still opens; :attr:`ResolvedView.missing` names them.
        """
        who = self.user(user)
        m = _VIEW_ID.fullmatch(view_id) if isinstance(view_id, str) else None
        if m is None:
            raise NotFound(f"no view {str(view_id)[:40]!r}")
        pid = m.group(1)
        try:
            db, _ = self._open(who, pid)
        except (AccessDenied, NotFound):
            raise AccessDenied(
                f"view {view_id}: it belongs to a project you may not open (or to none)"
            ) from None
        info, candidates, _, views, _ = db.snapshot()
        by_id = {c.id: c for c in candidates}
        view = next((v for v in views if v.id == view_id), None)
        if view is None:
            raise NotFound(f"view {view_id}: no such view in this project")
        if not policy.view_visible(who, info, view, by_id):
            raise AccessDenied(f"view {view_id}: it shows a candidate you may not see")
        missing = tuple(by_id[c].name for c in view.candidates if by_id[c].removed)
        self._log(db, who, "viewed", f"view {view.name!r}", view.candidates, None)
        return ResolvedView(self._shown_info(who, info), view, view.query, missing)

    # ---- notes, exports, audit -----------------------------------------------------------------

    def add_note(self, user: str | User, pid: str, text: str, shared: bool = False) -> Note:
        """A short note. Read by the groups that see at least what its writer sees;
        ``shared`` (full-access groups only): by every group that opens the project."""
        who = self.user(user)
        db, info = self._open(who, pid)
        text = _text(text, "note", required=True, limit=MAX_NOTE)
        if shared and not policy.full_access(who, info):
            raise AccessDenied(f"project {pid}: only the groups that see all candidates share")
        audience: Audience = None if shared else policy.audience_of(who, info)
        at = now_text()

        def body(conn: sqlite3.Connection) -> int:
            cur = conn.execute(
                "INSERT INTO notes (text, audience, written_by, written_at) VALUES (?, ?, ?, ?)",
                (text, None if audience is None else json.dumps(sorted(audience)), who.name, at),
            )
            short = text if len(text) <= 60 else text[:57] + "..."
            ProjectDB.write_audit(conn, at, who.name, "noted", repr(short), (), audience)
            return int(cur.lastrowid or 0)

        nid: int = db.write(f"project {pid}: adding a note", body)
        return Note(nid, text, audience, who.name, at)

    def notes(self, user: str | User, pid: str) -> tuple[Note, ...]:
        who = self.user(user)
        db, _ = self._open(who, pid)
        info, *_, notes = db.snapshot()
        return tuple(n for n in notes if policy.note_visible(who, info, n))

    def record_export(
        self, user: str | User, pid: str, what: str, candidates: Iterable[int] = ()
    ) -> None:
        """Write an export (a report, a CSV) of project ``pid`` to its audit log."""
        who = self.user(user)
        db, info = self._open(who, pid)
        ids = tuple(candidates)
        by_id = {c.id: c for c in db.snapshot()[1]}
        for cid in ids:
            c = by_id.get(cid)
            if c is None or not policy.candidate_visible(who, info, c):
                raise NotFound(f"project {pid}: no candidate {cid}")
        self._log(db, who, "exported", _text(what, "export's description", True), ids, None)

    def audit(self, user: str | User, pid: str) -> tuple[AuditEntry, ...]:
        """The project's audit log as ``user`` may read it, oldest first."""
        who = self.user(user)
        db, _ = self._open(who, pid)
        info, candidates, entries = db.audit_entries()
        by_id = {c.id: c for c in candidates}

        def shown(e: AuditEntry) -> bool:
            if not policy.audience_visible(who, info, e.audience):
                return False
            return all(
                cid in by_id and policy.candidate_visible(who, info, by_id[cid])
                for cid in e.candidates
            )

        return tuple(e for e in entries if shown(e))

    def ranking(self, user: str | User, pid: str, ranking: Iterable[object]) -> tuple[object, ...]:
        """The verdict's ranking as ``user`` may see it (:func:`access.redact_ranking`)."""
        who = self.user(user)
        db, info = self._open(who, pid)
        return policy.redact_ranking(who, info, db.snapshot()[1], tuple(ranking))
