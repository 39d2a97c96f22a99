"""Back up, verify and restore the dashboard's projects (works while the server runs).

Usage (from the repository root, or in the container with ``docker exec``)::

    python scripts/projects_backup.py backup  BACKUP_DIR [--data DIR] [--project ID ...]
    python scripts/projects_backup.py verify  BACKUP_DIR
    python scripts/projects_backup.py restore BACKUP_DIR [--data DIR] [--project ID ...]
                                                         [--replace]

``--data`` defaults to ``FBS_DATA_DIR`` (else ``/data``). A backup copies each project's
database with SQLite's online backup API and then the files it names (digests checked); a
restore verifies the backup first and swaps each project in with one rename
(docs/projects.md, "Backup and restore"). Exit status 0 when everything was copied, 1 when
a project was skipped or damaged, 2 for a refused command.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if (ROOT / "app" / "projects").is_dir() and str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from app.projects import backup as store  # noqa: E402
from app.projects.config import data_dir  # noqa: E402
from app.projects.errors import ProjectError  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
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
            report = store.backup(data, args.backup_dir, args.project)
            for pid in report.copied:
                print(f"backed up {pid}")
            for pid, why in report.skipped:
                print(f"SKIPPED {pid}: {why}", file=sys.stderr)
            print(f"{len(report.copied)} projects in {args.backup_dir}")
            return 1 if report.skipped else 0
        if args.command == "verify":
            checks = store.verify(args.backup_dir)
            for pid, result in checks.items():
                print(f"{pid}: {result}")
            return 0 if all(r == "ok" for r in checks.values()) else 1
        report = store.restore(args.backup_dir, data, args.project, replace=args.replace)
        for pid in report.copied:
            print(f"restored {pid}")
        return 0
    except ProjectError as exc:
        print(f"refused: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
