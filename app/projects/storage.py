"""Where projects live: one SQLite database per project, its files beside it.

Layout of the data directory (``FBS_DATA_DIR``)::

    projects/<id>/project.sqlite3   the project's records (WAL mode, synchronous=FULL)
    projects/<id>/files/<sha256>    its tire and target files as uploaded, named by the
                                    SHA-256 (hex) of their bytes
    projects/.new-<id>/             a project being created (renamed to <id> when complete)

One database per project, so that a damaged one is reported at start and the others open
(:meth:`ProjectStore.scan` runs ``PRAGMA quick_check`` on each), writers to different projects
never wait for each other, and a project is backed up, restored or deleted as one directory.

How a file and its record are written so that a killed server loses nothing it acknowledged
and lists nothing half written (:meth:`ProjectDB.add_file_record`):

1. the bytes go to ``files/.tmp-<random>`` (held under ``flock`` while written), are
   ``fsync``-ed;
2. in one ``BEGIN IMMEDIATE`` transaction the temporary file is renamed to its digest (the
   directory ``fsync``-ed) and the record inserted; ``COMMIT`` (WAL, ``synchronous=FULL``:
   durable when it returns) is the acknowledgement.

Killed before the commit, the transaction is rolled back by SQLite and the file is an orphan:
:meth:`ProjectDB.clean` (at start, under the write lock) deletes every file no record names
and every temporary file whose writer is gone (its ``flock`` is free). Two writers of one
project take turns on the write lock (busy timeout :data:`BUSY_TIMEOUT_S`, then retries), so
both land. A full disk (``ENOSPC``, or SQLite's "database or disk is full") raises
:class:`~app.projects.errors.DiskFull` after removing what was begun.

:data:`HOOKS` lets the fault tests block at a named point (``checkpoint``) or fail a write
(``write``); in the server both are no-ops / ``os.write``.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import json
import logging
import os
import re
import secrets
import shutil
import sqlite3
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from .errors import Conflict, DiskFull, NotFound, StorageError
from .records import (
    FULL_ONLY,
    Audience,
    AuditEntry,
    Candidate,
    GroupAccess,
    Note,
    ProjectInfo,
    Target,
    View,
)

__all__ = [
    "BUSY_TIMEOUT_S",
    "DB_NAME",
    "HOOKS",
    "SCHEMA_VERSION",
    "Hooks",
    "Problem",
    "ProjectDB",
    "ProjectStore",
    "fsync_dir",
    "is_project_id",
    "now_text",
    "sha256_hex",
]

log = logging.getLogger("tire_fbs.projects")

SCHEMA_VERSION = 1
DB_NAME = "project.sqlite3"
FILES = "files"
PROJECTS = "projects"
#: Seconds a writer waits for another writer of the same project before retrying.
BUSY_TIMEOUT_S = 30.0
#: Attempts of a write transaction that found the project busy.
BUSY_ATTEMPTS = 4
_CHUNK = 1 << 20
_ID = re.compile(r"[0-9a-f]{16}")
_SHA = re.compile(r"[0-9a-f]{64}")

_SCHEMA = """
CREATE TABLE project (
    id TEXT PRIMARY KEY, title TEXT NOT NULL, created_by TEXT NOT NULL,
    created_at TEXT NOT NULL);
CREATE TABLE access (grp TEXT PRIMARY KEY, suppliers TEXT);
CREATE TABLE candidates (
    id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT NOT NULL, supplier TEXT NOT NULL,
    size TEXT NOT NULL, version TEXT NOT NULL, filename TEXT NOT NULL, sha256 TEXT NOT NULL,
    digest TEXT NOT NULL, n_bytes INTEGER NOT NULL, added_by TEXT NOT NULL,
    added_at TEXT NOT NULL, removed_by TEXT, removed_at TEXT);
CREATE UNIQUE INDEX candidates_name
    ON candidates (supplier COLLATE NOCASE, name COLLATE NOCASE) WHERE removed_at IS NULL;
CREATE UNIQUE INDEX candidates_file ON candidates (sha256) WHERE removed_at IS NULL;
CREATE TABLE targets (
    id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT NOT NULL, filename TEXT NOT NULL,
    sha256 TEXT NOT NULL, n_bytes INTEGER NOT NULL, added_by TEXT NOT NULL,
    added_at TEXT NOT NULL, removed_by TEXT, removed_at TEXT);
CREATE UNIQUE INDEX targets_name ON targets (name COLLATE NOCASE) WHERE removed_at IS NULL;
CREATE TABLE views (
    id TEXT PRIMARY KEY, name TEXT NOT NULL, query TEXT NOT NULL, candidates TEXT NOT NULL,
    saved_by TEXT NOT NULL, saved_at TEXT NOT NULL);
CREATE TABLE notes (
    id INTEGER PRIMARY KEY AUTOINCREMENT, text TEXT NOT NULL, audience TEXT,
    written_by TEXT NOT NULL, written_at TEXT NOT NULL);
CREATE TABLE audit (
    seq INTEGER PRIMARY KEY AUTOINCREMENT, at TEXT NOT NULL, user TEXT NOT NULL,
    action TEXT NOT NULL, what TEXT NOT NULL, candidates TEXT NOT NULL, audience TEXT);
CREATE TRIGGER audit_no_update BEFORE UPDATE ON audit
    BEGIN SELECT RAISE(ABORT, 'the audit log is append-only'); END;
CREATE TRIGGER audit_no_delete BEFORE DELETE ON audit
    BEGIN SELECT RAISE(ABORT, 'the audit log is append-only'); END;
"""


@dataclass
class Hooks:
    """Points where the fault tests step in (no-ops in the server).

    ``checkpoint(point)`` is called at ``"file-partial"`` (first chunk of a file written),
    ``"file-written"`` (temporary file complete and fsync-ed), ``"file-renamed"`` (file under
    its digest, record not yet written), ``"record-written"`` (record inserted, not yet
    committed) and ``"committed"`` (durable, not yet acknowledged to the caller).
    ``write(fd, data)`` writes bytes like :func:`os.write`.
    """

    checkpoint: Callable[[str], None] = field(default=lambda point: None)
    write: Callable[[int, memoryview], int] = field(default=os.write)


#: The hooks in use (see :class:`Hooks`).
HOOKS = Hooks()


def now_text() -> str:
    """The current UTC time as ISO text with milliseconds (``2027-03-01T09:30:00.123Z``)."""
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3] + "Z"


def sha256_hex(data: bytes) -> str:
    """SHA-256 of ``data``, hex: the name of a file in a project's ``files`` directory."""
    import hashlib

    return hashlib.sha256(data).hexdigest()


def is_project_id(text: str) -> bool:
    """Whether ``text`` has the form of a project id (16 lower-case hex characters)."""
    return bool(_ID.fullmatch(text))


def fsync_dir(path: Path) -> None:
    """Make a rename or removal in directory ``path`` durable."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _full(exc: BaseException) -> bool:
    if isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT):
        return True
    return isinstance(exc, sqlite3.OperationalError) and "full" in str(exc)


def _storage_error(exc: BaseException, what: str) -> StorageError:
    if _full(exc):
        return DiskFull(f"{what}: the data volume is full; nothing was saved")
    if isinstance(exc, sqlite3.DatabaseError):
        return StorageError(f"{what}: the project's database failed ({exc})")
    text = getattr(exc, "strerror", None) or str(exc)
    return StorageError(f"{what}: {text}")


def _audience_text(audience: Audience) -> str | None:
    return None if audience is None else json.dumps(sorted(audience))


def _audience(text: str | None) -> Audience:
    return None if text is None else frozenset(json.loads(text))


def _try_lock(path: Path) -> bool:
    """Whether nobody holds ``path``'s flock (then it was taken and released again)."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except FileNotFoundError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except OSError:
        return False
    finally:
        os.close(fd)


class _Staged:
    """A file written to a temporary name and fsync-ed, held under flock until closed."""

    def __init__(self, files: Path, data: bytes) -> None:
        self.tmp = files / f".tmp-{secrets.token_hex(8)}"
        self.fd = os.open(self.tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o640)
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX)
            view = memoryview(data)
            pos = 0
            while pos < len(view):
                pos += HOOKS.write(self.fd, view[pos : pos + _CHUNK])
                if pos < len(view):
                    HOOKS.checkpoint("file-partial")
            os.fsync(self.fd)
        except BaseException:
            self.discard()
            raise
        HOOKS.checkpoint("file-written")

    def discard(self) -> None:
        with contextlib.suppress(OSError):
            self.tmp.unlink()
        self.close()

    def close(self) -> None:
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1


class ProjectDB:
    """The records and files of one project (no access checks: see the service).

    Every call opens its own connection, so any thread or process may use the project and
    a restore that swaps the directory is seen by the next call.
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self.db = path / DB_NAME
        self.files = path / FILES
        self.id = path.name

    # ---- connections -------------------------------------------------------------------------

    def connect(self) -> sqlite3.Connection:
        if not self.db.is_file():
            raise StorageError(f"project {self.id}: its database {self.db} is missing")
        conn = sqlite3.connect(self.db, timeout=BUSY_TIMEOUT_S, isolation_level=None)
        try:
            conn.execute("PRAGMA synchronous=FULL")
            version = conn.execute("PRAGMA user_version").fetchone()[0]
        except sqlite3.DatabaseError as exc:
            conn.close()
            raise StorageError(f"project {self.id}: its database is damaged ({exc})") from None
        if version != SCHEMA_VERSION:
            conn.close()
            raise StorageError(
                f"project {self.id}: database version {version}, this server reads "
                f"version {SCHEMA_VERSION}"
            )
        return conn

    @contextlib.contextmanager
    def reading(self) -> Iterator[sqlite3.Connection]:
        """A connection in one read transaction (a consistent snapshot of the project)."""
        conn = self.connect()
        try:
            conn.execute("BEGIN")
            yield conn
            conn.execute("COMMIT")
        except sqlite3.DatabaseError as exc:
            raise _storage_error(exc, f"project {self.id}") from None
        finally:
            conn.close()

    def write(self, what: str, body: Callable[[sqlite3.Connection], Any]) -> Any:
        """Run ``body(conn)`` in one ``BEGIN IMMEDIATE`` transaction and commit it.

        A project busy beyond the busy timeout is tried again (:data:`BUSY_ATTEMPTS`); on any
        error the transaction is rolled back and the error raised as a ProjectError.
        """
        for attempt in range(BUSY_ATTEMPTS):
            conn = self.connect()
            try:
                conn.execute("BEGIN IMMEDIATE")
                try:
                    result = body(conn)
                    HOOKS.checkpoint("record-written")
                    conn.execute("COMMIT")
                except BaseException:
                    if conn.in_transaction:
                        conn.execute("ROLLBACK")
                    raise
                HOOKS.checkpoint("committed")
                return result
            except sqlite3.OperationalError as exc:
                if "locked" in str(exc) or "busy" in str(exc):
                    if attempt + 1 < BUSY_ATTEMPTS:
                        log.warning("project %s busy (%s), trying again", self.id, what)
                        continue
                    raise StorageError(
                        f"{what}: project {self.id} stayed busy with other writers; try again"
                    ) from None
                raise _storage_error(exc, what) from None
            except sqlite3.IntegrityError as exc:
                raise Conflict(f"{what}: {exc}") from None
            except (sqlite3.DatabaseError, OSError) as exc:
                raise _storage_error(exc, what) from None
            finally:
                conn.close()
        raise AssertionError("unreachable")

    # ---- creation ----------------------------------------------------------------------------

    @staticmethod
    def create(
        root: Path, title: str, user: str, access: Sequence[GroupAccess], audience: Audience
    ) -> ProjectDB:
        """Create a project under ``root/projects`` in one step (complete, or not there)."""
        projects = root / PROJECTS
        pid = secrets.token_hex(8)
        new = projects / f".new-{pid}"
        lock_fd = -1
        try:
            projects.mkdir(parents=True, exist_ok=True)
            new.mkdir()
            lock_fd = os.open(new / ".creating", os.O_WRONLY | os.O_CREAT, 0o640)
            fcntl.flock(lock_fd, fcntl.LOCK_EX)
            (new / FILES).mkdir()
            conn = sqlite3.connect(new / DB_NAME, isolation_level=None)
            try:
                conn.execute("PRAGMA journal_mode=WAL")
                conn.execute("PRAGMA synchronous=FULL")
                conn.executescript(_SCHEMA)  # a new file in a directory not yet listed
                conn.execute("BEGIN IMMEDIATE")
                at = now_text()
                conn.execute("INSERT INTO project VALUES (?, ?, ?, ?)", (pid, title, user, at))
                ProjectDB.put_access(conn, access)
                ProjectDB.write_audit(conn, at, user, "created", f"project {title!r}", (), audience)
                conn.execute(f"PRAGMA user_version={SCHEMA_VERSION}")
                conn.execute("COMMIT")
                conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
            finally:
                conn.close()
            HOOKS.checkpoint("project-written")
            fsync_dir(new / FILES)
            fsync_dir(new)
            final = projects / pid
            os.rename(new, final)
            fsync_dir(projects)
            (final / ".creating").unlink()
        except (OSError, sqlite3.DatabaseError) as exc:
            shutil.rmtree(new, ignore_errors=True)
            raise _storage_error(exc, f"creating project {title!r}") from None
        finally:
            if lock_fd >= 0:
                os.close(lock_fd)
        return ProjectDB(final)

    @staticmethod
    def put_access(conn: sqlite3.Connection, access: Sequence[GroupAccess]) -> None:
        conn.execute("DELETE FROM access")
        for a in access:
            suppliers = None if a.suppliers is None else json.dumps(sorted(a.suppliers))
            conn.execute("INSERT INTO access VALUES (?, ?)", (a.group, suppliers))

    # ---- reading -----------------------------------------------------------------------------

    @staticmethod
    def _info(conn: sqlite3.Connection) -> ProjectInfo:
        row = conn.execute("SELECT id, title, created_by, created_at FROM project").fetchone()
        if row is None:
            raise StorageError("the project's database has no project record")
        access = tuple(
            GroupAccess(g, None if s is None else frozenset(json.loads(s)))
            for g, s in conn.execute("SELECT grp, suppliers FROM access ORDER BY grp")
        )
        return ProjectInfo(row[0], row[1], row[2], row[3], access)

    def info(self) -> ProjectInfo:
        with self.reading() as conn:
            return self._info(conn)

    @staticmethod
    def _candidates(conn: sqlite3.Connection) -> tuple[Candidate, ...]:
        rows = conn.execute(
            "SELECT id, name, supplier, size, version, filename, sha256, digest, n_bytes, "
            "added_by, added_at, removed_by, removed_at FROM candidates ORDER BY id"
        )
        return tuple(Candidate(*r) for r in rows)

    @staticmethod
    def _targets(conn: sqlite3.Connection) -> tuple[Target, ...]:
        rows = conn.execute(
            "SELECT id, name, filename, sha256, n_bytes, added_by, added_at, removed_by, "
            "removed_at FROM targets ORDER BY id"
        )
        return tuple(Target(*r) for r in rows)

    @staticmethod
    def _views(conn: sqlite3.Connection) -> tuple[View, ...]:
        rows = conn.execute(
            "SELECT id, name, query, candidates, saved_by, saved_at FROM views ORDER BY saved_at"
        )
        return tuple(View(i, n, q, tuple(json.loads(c)), b, a) for i, n, q, c, b, a in rows)

    @staticmethod
    def _notes(conn: sqlite3.Connection) -> tuple[Note, ...]:
        rows = conn.execute(
            "SELECT id, text, audience, written_by, written_at FROM notes ORDER BY id"
        )
        return tuple(Note(i, t, _audience(a), b, w) for i, t, a, b, w in rows)

    @staticmethod
    def _audit_entries(conn: sqlite3.Connection) -> tuple[AuditEntry, ...]:
        rows = conn.execute(
            "SELECT seq, at, user, action, what, candidates, audience FROM audit ORDER BY seq"
        )
        return tuple(
            AuditEntry(s, at, u, ac, w, tuple(json.loads(c)), _audience(au))
            for s, at, u, ac, w, c, au in rows
        )

    def snapshot(
        self,
    ) -> tuple[
        ProjectInfo,
        tuple[Candidate, ...],
        tuple[Target, ...],
        tuple[View, ...],
        tuple[Note, ...],
    ]:
        """Everything but the audit log, read in one transaction."""
        with self.reading() as conn:
            return (
                self._info(conn),
                self._candidates(conn),
                self._targets(conn),
                self._views(conn),
                self._notes(conn),
            )

    def audit_entries(self) -> tuple[ProjectInfo, tuple[Candidate, ...], tuple[AuditEntry, ...]]:
        with self.reading() as conn:
            return self._info(conn), self._candidates(conn), self._audit_entries(conn)

    def read_file(self, sha256: str) -> bytes:
        if not _SHA.fullmatch(sha256):
            raise NotFound(f"project {self.id}: no file {sha256!r}")
        try:
            return (self.files / sha256).read_bytes()
        except OSError as exc:
            raise StorageError(f"project {self.id}: file {sha256} cannot be read: {exc}") from None

    # ---- writing -----------------------------------------------------------------------------

    @staticmethod
    def write_audit(
        conn: sqlite3.Connection,
        at: str,
        user: str,
        action: str,
        what: str,
        candidates: Sequence[int],
        audience: Audience,
    ) -> None:
        conn.execute(
            "INSERT INTO audit (at, user, action, what, candidates, audience) "
            "VALUES (?, ?, ?, ?, ?, ?)",
            (at, user, action, what, json.dumps(list(candidates)), _audience_text(audience)),
        )

    def add_file_record(
        self,
        what: str,
        data: bytes,
        insert: Callable[[sqlite3.Connection, str], Any],
        sha256: str | None = None,
    ) -> Any:
        """Store ``data`` under its digest and its record in one step (module notes).

        ``insert(conn, sha256)`` inserts the record (and its audit line) inside the write
        transaction and returns what the caller gets back; ``sha256`` is the digest of
        ``data`` when the caller has it already.
        """
        sha = sha256 or sha256_hex(data)
        final = self.files / sha
        try:
            staged = _Staged(self.files, data)
        except OSError as exc:
            raise _storage_error(exc, what) from None
        ours = False  # the final file is this call's (it did not exist before the rename)
        try:

            def body(conn: sqlite3.Connection) -> Any:
                nonlocal ours
                existed = final.exists()
                os.replace(staged.tmp, final)
                ours = not existed
                fsync_dir(self.files)
                HOOKS.checkpoint("file-renamed")
                return insert(conn, sha)

            try:
                return self.write(what, body)
            except BaseException:
                if ours:
                    with contextlib.suppress(OSError):
                        final.unlink()
                raise
        finally:
            staged.discard()

    def remove_file_if_unused(self, sha256: str) -> None:
        """Delete a file no active candidate or target names any more (after its commit).

        A crash before this leaves an orphan that :meth:`clean` deletes at the next start.
        """

        def used(conn: sqlite3.Connection) -> bool:
            n = conn.execute(
                "SELECT (SELECT count(*) FROM candidates WHERE sha256 = ? AND removed_at IS NULL)"
                " + (SELECT count(*) FROM targets WHERE sha256 = ? AND removed_at IS NULL)",
                (sha256, sha256),
            ).fetchone()[0]
            if not n:
                with contextlib.suppress(FileNotFoundError):
                    (self.files / sha256).unlink()
            return bool(n)

        with contextlib.suppress(StorageError):
            self.write("removing an unused file", used)

    def clean(self) -> tuple[str, ...]:
        """Delete orphan files and dead writers' temporary files (under the write lock).

        Returns the names deleted.
        """

        def body(conn: sqlite3.Connection) -> tuple[str, ...]:
            used = {
                r[0]
                for r in conn.execute(
                    "SELECT sha256 FROM candidates WHERE removed_at IS NULL "
                    "UNION SELECT sha256 FROM targets WHERE removed_at IS NULL"
                )
            }
            gone: list[str] = []
            for p in sorted(self.files.iterdir()):
                if p.name.startswith(".tmp-"):
                    if _try_lock(p):
                        p.unlink(missing_ok=True)
                        gone.append(p.name)
                elif p.name not in used:
                    p.unlink(missing_ok=True)
                    gone.append(p.name)
            if gone:
                fsync_dir(self.files)
            return tuple(gone)

        stale = self.path / ".creating"
        if stale.exists() and _try_lock(stale):
            stale.unlink(missing_ok=True)
        result: tuple[str, ...] = self.write(f"cleaning project {self.id}", body)
        return result

    def check(self) -> ProjectInfo:
        """``PRAGMA quick_check`` and the project record; StorageError naming the fault."""
        try:
            conn = self.connect()
        except StorageError:
            raise
        try:
            rows = [r[0] for r in conn.execute("PRAGMA quick_check")]
            if rows != ["ok"]:
                raise StorageError(f"project {self.id}: database damaged ({'; '.join(rows[:3])})")
            if not self.files.is_dir():
                raise StorageError(f"project {self.id}: its files directory is missing")
            return self._info(conn)
        except sqlite3.DatabaseError as exc:
            raise StorageError(f"project {self.id}: database damaged ({exc})") from None
        finally:
            conn.close()


@dataclass(frozen=True)
class Problem:
    """A project directory that could not be opened at start, and why."""

    path: str
    message: str


class ProjectStore:
    """All projects of a data directory.

    :meth:`scan` (at start) checks every project, cleans orphans, removes unfinished
    creations and reports the damaged ones (:attr:`problems`); the others open.
    """

    def __init__(self, root: Path | str) -> None:
        self.root = Path(root)
        self.projects = self.root / PROJECTS
        self.problems: tuple[Problem, ...] = ()
        self._broken: set[str] = set()

    def ensure(self) -> None:
        try:
            self.projects.mkdir(parents=True, exist_ok=True)
            probe = self.projects / f".probe-{secrets.token_hex(4)}"
            probe.write_bytes(b"")
            probe.unlink()
        except OSError as exc:
            raise StorageError(
                f"data directory {self.root} cannot be written ({exc.strerror or exc}); "
                "set FBS_DATA_DIR to a writable directory (the container's data volume)"
            ) from None

    def scan(self) -> tuple[Problem, ...]:
        """Check and clean every project; the problems found (also logged)."""
        self.ensure()
        problems: list[Problem] = []
        broken: set[str] = set()
        for p in sorted(self.projects.iterdir()):
            if p.name.startswith(".new-"):
                if _try_lock(p / ".creating") or not (p / ".creating").exists():
                    shutil.rmtree(p, ignore_errors=True)
                    problems.append(Problem(str(p), "an unfinished project creation; removed"))
                continue
            if p.name.startswith(".old-"):
                problems.append(Problem(str(p), "left by an interrupted restore; left alone"))
                continue
            if p.name.startswith("."):
                continue
            if not p.is_dir() or not is_project_id(p.name):
                problems.append(Problem(str(p), "not a project directory; left alone"))
                continue
            db = ProjectDB(p)
            try:
                db.check()
                gone = db.clean()
                if gone:
                    log.info("project %s: %d orphan files removed", p.name, len(gone))
            except StorageError as exc:
                broken.add(p.name)
                problems.append(Problem(str(p), str(exc)))
        for problem in problems:
            log.error("projects: %s: %s", problem.path, problem.message)
        self.problems = tuple(problems)
        self._broken = broken
        return self.problems

    def ids(self) -> tuple[str, ...]:
        """Ids of the projects that opened at the last scan (and any created since)."""
        if not self.projects.is_dir():
            return ()
        return tuple(
            p.name
            for p in sorted(self.projects.iterdir())
            if is_project_id(p.name)
            and p.is_dir()
            and (p.name not in self._broken or self._recovered(p.name))
        )

    def _recovered(self, pid: str) -> bool:
        """Whether a project damaged at the last scan checks out now (restored since)."""
        try:
            ProjectDB(self.projects / pid).check()
        except StorageError:
            return False
        self._broken.discard(pid)
        return True

    def project(self, pid: str) -> ProjectDB:
        """The project ``pid`` (NotFound for an unknown or damaged one)."""
        if not is_project_id(pid) or not (self.projects / pid).is_dir():
            raise NotFound(f"no project {pid!r}")
        if pid in self._broken and not self._recovered(pid):
            raise NotFound(f"no project {pid!r}")
        return ProjectDB(self.projects / pid)

    def create(
        self, title: str, user: str, access: Sequence[GroupAccess], audience: Audience = FULL_ONLY
    ) -> ProjectDB:
        self.ensure()
        return ProjectDB.create(self.root, title, user, access, audience)
