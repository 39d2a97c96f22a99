"""Back up, verify and restore the dashboard's projects (works while the server runs).

Usage (from the repository root; in the container ``python -m app.projects.backup`` is the
same command)::

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

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if (ROOT / "app" / "projects").is_dir() and str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from app.projects.backup import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
