"""Backup and restore of the projects of a data directory, while the server runs.

A backup is a directory laid out like the data directory (``projects/<id>/project.sqlite3``
and ``projects/<id>/files/<sha256>``) plus ``backup.json`` (when, which projects, what was
skipped). Each project's database is copied with SQLite's online backup API (a consistent
snapshot; writers go on meanwhile), then the files its snapshot names are copied and their
SHA-256 checked. A file removed by a writer between the two steps makes the project's copy
start again (at most :data:`ATTEMPTS` times), so a backed-up project is always complete.

A restore checks every project of the backup first (``PRAGMA integrity_check``, each named
file present with its digest), copies it beside the live ones under a temporary name and
renames it into place: a running server sees the old project or the restored one, never a
mix. An existing project is replaced only when asked (``replace=True``).

Command line: ``python -m app.projects.backup backup|verify|restore BACKUP_DIR [--data DIR]
[--project ID ...] [--replace]`` (also ``scripts/projects_backup.py``; docs/projects.md).
"""

from __future__ import annotations

import argparse
import contextlib
import fcntl
import hashlib
import json
import os
import secrets
import shutil
import sqlite3
import sys
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from .config import data_dir
from .errors import ProjectError, StorageError
from .storage import (
    DB_NAME,
    FILES,
    HOOKS,
    PROJECTS,
    ProjectStore,
    fsync_dir,
    is_project_id,
    now_text,
)

__all__ = ["ATTEMPTS", "BackupReport", "backup", "main", "restore", "verify"]

#: Attempts to copy one project whose files changed during its copy.
ATTEMPTS = 5
MANIFEST = "backup.json"


@dataclass(frozen=True)
class BackupReport:
    """What a backup or restore did: the projects copied and those skipped, with why."""

    copied: tuple[str, ...]
    skipped: tuple[tuple[str, str], ...]


def _copy_file(src: Path, dst: Path, sha: str) -> None:
    tmp = dst.with_name(f".tmp-{secrets.token_hex(6)}")
    h = hashlib.sha256()
    with open(src, "rb") as fin, open(tmp, "wb") as fout:
        while chunk := fin.read(1 << 20):
            h.update(chunk)
            fout.write(chunk)
        fout.flush()
        os.fsync(fout.fileno())
    if h.hexdigest() != sha:
        tmp.unlink()
        raise StorageError(f"file {src} does not have its digest: the data directory is damaged")
    os.replace(tmp, dst)


def _referenced(db: Path) -> set[str]:
    conn = sqlite3.connect(db)
    try:
        return {
            r[0]
            for r in conn.execute(
                "SELECT sha256 FROM candidates WHERE removed_at IS NULL "
                "UNION SELECT sha256 FROM targets WHERE removed_at IS NULL"
            )
        }
    finally:
        conn.close()


def _integrity(db: Path) -> str:
    conn = sqlite3.connect(db)
    try:
        rows = [r[0] for r in conn.execute("PRAGMA integrity_check")]
    except sqlite3.DatabaseError as exc:
        return str(exc)
    finally:
        conn.close()
    return "ok" if rows == ["ok"] else "; ".join(rows[:3])


def _backup_project(src: Path, dest: Path) -> None:
    """Copy project directory ``src`` to ``dest`` (complete, or raise)."""
    pid = src.name
    for _attempt in range(ATTEMPTS):
        shutil.rmtree(dest, ignore_errors=True)
        (dest / FILES).mkdir(parents=True)
        source = sqlite3.connect(src / DB_NAME, timeout=30.0)
        target = sqlite3.connect(dest / DB_NAME)
        try:
            source.backup(target)
        except sqlite3.DatabaseError as exc:
            raise StorageError(f"project {pid}: its database cannot be read ({exc})") from None
        finally:
            target.close()
            source.close()
        HOOKS.checkpoint("backup-db-copied")
        try:
            for sha in sorted(_referenced(dest / DB_NAME)):
                _copy_file(src / FILES / sha, dest / FILES / sha, sha)
        except FileNotFoundError:
            continue  # a file removed after the snapshot: take a new snapshot
        result = _integrity(dest / DB_NAME)
        if result != "ok":
            raise StorageError(f"project {pid}: its copy fails the integrity check ({result})")
        fsync_dir(dest / FILES)
        return
    raise StorageError(f"project {pid}: its files kept changing during {ATTEMPTS} copies")


def backup(data: Path | str, dest: Path | str, projects: Iterable[str] = ()) -> BackupReport:
    """Back up the projects of data directory ``data`` into new directory ``dest``.

    Parameters
    ----------
    projects : iterable of str
        Ids of the projects to copy (default: all). A damaged project is skipped and named
        in the report and in ``backup.json``.
    """
    root, out = Path(data), Path(dest)
    if out.exists() and any(out.iterdir()):
        raise ProjectError(f"backup directory {out} is not empty")
    wanted = set(projects)
    sources = (
        sorted(p for p in (root / PROJECTS).iterdir() if is_project_id(p.name) and p.is_dir())
        if (root / PROJECTS).is_dir()
        else []
    )
    unknown = wanted - {p.name for p in sources}
    if unknown:
        raise ProjectError(f"no project {sorted(unknown)[0]!r} in {root}")
    (out / PROJECTS).mkdir(parents=True, exist_ok=True)
    copied, skipped = [], []
    for src in sources:
        if wanted and src.name not in wanted:
            continue
        partial = out / PROJECTS / f".partial-{src.name}"
        try:
            _backup_project(src, partial)
        except (StorageError, OSError) as exc:
            shutil.rmtree(partial, ignore_errors=True)
            skipped.append((src.name, str(exc)))
            continue
        os.rename(partial, out / PROJECTS / src.name)
        copied.append(src.name)
    fsync_dir(out / PROJECTS)
    manifest = {"created_at": now_text(), "projects": copied, "skipped": skipped}
    (out / MANIFEST).write_text(json.dumps(manifest, indent=1) + "\n", encoding="utf-8")
    return BackupReport(tuple(copied), tuple((a, b) for a, b in skipped))


def verify(backup_dir: Path | str) -> dict[str, str]:
    """Each project of a backup -> ``"ok"`` or what is wrong with its copy."""
    out: dict[str, str] = {}
    base = Path(backup_dir) / PROJECTS
    if not base.is_dir():
        raise ProjectError(f"{backup_dir} is not a backup of projects (no {PROJECTS}/ in it)")
    for p in sorted(base.iterdir()):
        if not is_project_id(p.name):
            continue
        result = _integrity(p / DB_NAME) if (p / DB_NAME).is_file() else "no database"
        if result == "ok":
            for sha in sorted(_referenced(p / DB_NAME)):
                f = p / FILES / sha
                if not f.is_file():
                    result = f"file {sha} is missing"
                    break
                if hashlib.sha256(f.read_bytes()).hexdigest() != sha:
                    result = f"file {sha} does not have its digest"
                    break
        out[p.name] = result
    return out


def restore(
    backup_dir: Path | str,
    data: Path | str,
    projects: Iterable[str] = (),
    replace: bool = False,
) -> BackupReport:
    """Restore the projects of a backup into data directory ``data`` (module notes).

    Every chosen project is verified before anything is changed; a project that exists in
    ``data`` is replaced only with ``replace=True``.
    """
    checks = verify(backup_dir)
    wanted = set(projects) or set(checks)
    unknown = wanted - set(checks)
    if unknown:
        raise ProjectError(f"the backup holds no project {sorted(unknown)[0]!r}")
    bad = {p: r for p, r in checks.items() if p in wanted and r != "ok"}
    if bad:
        pid, why = sorted(bad.items())[0]
        raise ProjectError(f"project {pid} of the backup is damaged ({why}); nothing restored")
    store = ProjectStore(data)
    store.ensure()
    live = store.projects
    existing = sorted(p for p in wanted if (live / p).exists())
    if existing and not replace:
        raise ProjectError(
            f"project {existing[0]} exists in {data}; restore with replace to overwrite it"
        )
    copied = []
    for pid in sorted(wanted):
        new = live / f".new-{pid}"
        shutil.rmtree(new, ignore_errors=True)
        new.mkdir()
        lock = os.open(new / ".creating", os.O_WRONLY | os.O_CREAT, 0o640)
        try:
            fcntl.flock(lock, fcntl.LOCK_EX)
            src = Path(backup_dir) / PROJECTS / pid
            (new / FILES).mkdir()
            shutil.copy2(src / DB_NAME, new / DB_NAME)
            for f in (src / FILES).iterdir():
                if not f.name.startswith("."):
                    _copy_file(f, new / FILES / f.name, f.name)
            with open(new / DB_NAME, "rb") as fh:
                os.fsync(fh.fileno())
            fsync_dir(new / FILES)
            fsync_dir(new)
            old = live / f".old-{pid}-{secrets.token_hex(4)}"
            if (live / pid).exists():
                os.rename(live / pid, old)
            os.rename(new, live / pid)
            fsync_dir(live)
            with contextlib.suppress(FileNotFoundError):
                (live / pid / ".creating").unlink()
            shutil.rmtree(old, ignore_errors=True)
        finally:
            os.close(lock)
        copied.append(pid)
    return BackupReport(tuple(copied), ())


def main(argv: list[str] | None = None) -> int:
    """The command line (exit status 0 all copied, 1 a project skipped or damaged, 2 refused)."""
    ap = argparse.ArgumentParser(
        prog="projects_backup",
        description="Back up, verify and restore the projects of a data directory.",
    )
    sub = ap.add_subparsers(dest="command", required=True)
    for name in ("backup", "verify", "restore"):
        p = sub.add_parser(name)
        p.add_argument("backup_dir", type=Path)
        if name != "verify":
            p.add_argument("--data", type=Path, default=None, help="data directory")
            p.add_argument("--project", action="append", default=[], help="project id")
        if name == "restore":
            p.add_argument("--replace", action="store_true", help="overwrite existing projects")
    args = ap.parse_args(argv)
    data = getattr(args, "data", None) or data_dir()
    try:
        if args.command == "backup":
            report = backup(data, args.backup_dir, args.project)
            for pid in report.copied:
                print(f"backed up {pid}")
            for pid, why in report.skipped:
                print(f"SKIPPED {pid}: {why}", file=sys.stderr)
            print(f"{len(report.copied)} projects in {args.backup_dir}")
            return 1 if report.skipped else 0
        if args.command == "verify":
            checks = verify(args.backup_dir)
            for pid, result in checks.items():
                print(f"{pid}: {result}")
            return 0 if all(r == "ok" for r in checks.values()) else 1
        report = restore(args.backup_dir, data, args.project, replace=args.replace)
        for pid in report.copied:
            print(f"restored {pid}")
        return 0
    except ProjectError as exc:
        print(f"refused: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
