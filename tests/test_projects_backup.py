"""Backup and restore of projects while writers are at work (scripts/projects_backup.py)."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from app.projects import Projects, parse_groups
from app.projects import backup as backups
from app.projects.storage import HOOKS

sys.path.insert(0, str(Path(__file__).parent))
from projects_child import GROUPS, payload  # noqa: E402
from test_projects_faults import SIZE, Child  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "projects_backup.py"


def _script(*args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(
        [sys.executable, str(SCRIPT), *args], capture_output=True, text=True, env=env, timeout=300
    )


def _names(p: Projects, pid: str) -> list[str]:
    return [c.name for c in p.open_project("alice", pid).candidates]


def test_a_backup_taken_during_a_write_restores_what_was_acknowledged(tmp_path):
    data, saved, fresh = tmp_path / "data", tmp_path / "backup", tmp_path / "fresh"
    live = Projects(data, parse_groups(GROUPS))
    pid = live.create_project("alice", "rear axle", {"oem": None}).id
    other = live.create_project("alice", "front axle", {"oem": None}).id
    live.add_note("alice", other, "kept too")
    # a writer holds the project's write lock in the middle of its third upload
    child = Child(data, pid, "candidate", "A", n=4, stop_at=3, stop_point="record-written")
    child.expect("AT record-written")
    out = _script("backup", str(saved), "--data", str(data))
    assert out.returncode == 0, out.stderr
    assert f"backed up {pid}" in out.stdout and f"backed up {other}" in out.stdout
    child.go()
    child.finish()
    assert _names(live, pid) == ["A-1", "A-2", "A-3", "A-4"]

    out = _script("verify", str(saved))
    assert out.returncode == 0 and out.stdout.count(": ok") == 2, out.stdout
    out = _script("restore", str(saved), "--data", str(fresh))
    assert out.returncode == 0, out.stderr
    restored = Projects(fresh, parse_groups(GROUPS))
    assert restored.problems == ()
    assert _names(restored, pid) == ["A-1", "A-2"]  # the snapshot: acknowledged, complete
    for c in restored.open_project("alice", pid).candidates:
        tag, i = c.name.split("-")
        assert restored.candidate_file("alice", pid, c.id)[1] == payload(tag, int(i), SIZE)
    assert [n.text for n in restored.notes("alice", other)] == ["kept too"]

    # into the live directory: refused without --replace, then swapped in under the server
    out = _script("restore", str(saved), "--data", str(data), "--project", pid)
    assert out.returncode == 2 and "exists" in out.stderr
    assert _names(live, pid) == ["A-1", "A-2", "A-3", "A-4"]
    out = _script("restore", str(saved), "--data", str(data), "--project", pid, "--replace")
    assert out.returncode == 0, out.stderr
    assert _names(live, pid) == ["A-1", "A-2"]  # the running service sees the restored one
    files = {f.name for f in (data / "projects" / pid / "files").iterdir()}
    assert files == {hashlib.sha256(payload("A", i, SIZE)).hexdigest() for i in (1, 2)}
    assert Projects(data, parse_groups(GROUPS)).problems == ()


def test_a_file_removed_during_the_backup_makes_it_start_again(tmp_path):
    p = Projects(tmp_path / "data", parse_groups(GROUPS))
    pid = p.create_project("alice", "rear axle", {"oem": None}).id
    a = p.add_candidate("alice", pid, "a.h5", payload("A", 1, 5000), {"name": "A-1"})
    p.add_candidate("alice", pid, "b.h5", payload("A", 2, 5000), {"name": "A-2"})
    copies = []

    def remove_once(point: str) -> None:
        if point == "backup-db-copied":
            copies.append(point)
            if len(copies) == 1:
                p.remove_candidate("bob", pid, a.id)  # after the snapshot named its file

    before = HOOKS.checkpoint
    HOOKS.checkpoint = remove_once
    try:
        report = backups.backup(tmp_path / "data", tmp_path / "backup")
    finally:
        HOOKS.checkpoint = before
    assert len(copies) == 2 and report.copied == (pid,)
    assert backups.verify(tmp_path / "backup") == {pid: "ok"}
    backups.restore(tmp_path / "backup", tmp_path / "fresh")
    restored = Projects(tmp_path / "fresh", parse_groups(GROUPS))
    page = restored.open_project("alice", pid)
    assert [c.name for c in page.candidates] == ["A-2"]
    assert [c.name for c in page.removed] == ["A-1"]


def test_a_damaged_backup_is_refused_and_nothing_is_restored(tmp_path):
    p = Projects(tmp_path / "data", parse_groups(GROUPS))
    pid = p.create_project("alice", "rear axle", {"oem": None}).id
    c = p.add_candidate("alice", pid, "a.h5", payload("A", 1, 5000), {"name": "A-1"})
    backups.backup(tmp_path / "data", tmp_path / "backup")
    with pytest.raises(Exception, match="not empty"):
        backups.backup(tmp_path / "data", tmp_path / "backup")
    f = tmp_path / "backup" / "projects" / pid / "files" / c.sha256
    f.write_bytes(b"flipped" + f.read_bytes()[7:])
    assert backups.verify(tmp_path / "backup") == {pid: f"file {c.sha256} does not have its digest"}
    out = _script("restore", str(tmp_path / "backup"), "--data", str(tmp_path / "fresh"))
    assert out.returncode == 2 and "damaged" in out.stderr
    assert not (tmp_path / "fresh" / "projects" / pid).exists()
