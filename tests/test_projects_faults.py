"""The projects store under faults: a writer killed mid-way, two writers at once, a full
disk, damaged projects at start.

A writer runs in a process of its own (``tests/projects_child.py``) and stops at a named
storage checkpoint until this test kills it with SIGKILL (no sleeps: it waits for the
child's ``AT <point>`` line). Reopening the data directory must then show every item the
child acknowledged, bit for bit, and nothing half written: no record without its file, no
file without its record, no temporary file.
"""

from __future__ import annotations

import errno
import hashlib
import os
import queue
import signal
import sqlite3
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from app.projects import DiskFull, NotFound, Projects, parse_groups
from app.projects.storage import HOOKS, Hooks, ProjectDB

sys.path.insert(0, str(Path(__file__).parent))
from projects_child import GROUPS, payload  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CHILD = Path(__file__).parent / "projects_child.py"
DEADLINE_S = 120.0
SIZE = 3 * (1 << 20) + 123  # several chunks: a kill can land between two of them


class Child:
    """A writer process and the lines it prints."""

    def __init__(self, data, pid, op, tag, n, stop_at=0, stop_point="-", announce=""):
        env = dict(os.environ, PYTHONPATH=str(ROOT), ANNOUNCE=announce)
        args = [str(data), pid, "alice", op, tag, str(n), str(SIZE), str(stop_at), stop_point]
        self.proc = subprocess.Popen(
            [sys.executable, str(CHILD), *args],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        self.lines: queue.Queue[str | None] = queue.Queue()
        self.acks: list[tuple[int, str]] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            self.lines.put(line.strip())
        self.lines.put(None)

    def expect(self, prefix: str) -> str:
        """Wait for a line starting with ``prefix`` (collecting ACKs on the way)."""
        while True:
            try:
                line = self.lines.get(timeout=DEADLINE_S)
            except queue.Empty:
                self.kill()
                raise AssertionError(f"no {prefix!r} line within {DEADLINE_S} s") from None
            if line is None:
                err = self.proc.stderr.read()
                raise AssertionError(f"child ended before {prefix!r}: {err}")
            if line.startswith("ACK"):
                _, i, ident = line.split()
                self.acks.append((int(i), ident))
            if line.startswith(prefix):
                return line

    def go(self) -> None:
        self.proc.stdin.write("go\n")
        self.proc.stdin.flush()

    def kill(self) -> None:
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(timeout=DEADLINE_S)

    def finish(self) -> None:
        self.expect("DONE")
        assert self.proc.wait(timeout=DEADLINE_S) == 0


@pytest.fixture()
def project(tmp_path):
    p = Projects(tmp_path, parse_groups(GROUPS))
    return tmp_path, p.create_project("alice", "rear axle", {"oem": None}).id


def _files(data: Path, pid: str) -> set[str]:
    return {f.name for f in (data / "projects" / pid / "files").iterdir()}


def _check_consistent(data: Path, pid: str) -> Projects:
    """Reopen as at a server's start; every listed candidate's file is its bytes, and the
    files directory holds exactly the listed candidates' files."""
    p = Projects(data, parse_groups(GROUPS))
    assert p.problems == ()
    page = p.open_project("alice", pid)
    for c in page.candidates:
        tag, i = c.name.rsplit("-", 1)
        _, data_bytes = p.candidate_file("alice", pid, c.id)
        assert data_bytes == payload(tag, int(i), SIZE)
        assert c.sha256 == hashlib.sha256(data_bytes).hexdigest()
    assert _files(data, pid) == {c.sha256 for c in page.candidates}
    conn = sqlite3.connect(data / "projects" / pid / "project.sqlite3")
    assert conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    conn.close()
    return p


@pytest.mark.parametrize(
    "point", ["file-partial", "file-written", "file-renamed", "record-written", "committed"]
)
def test_a_writer_killed_during_an_upload_loses_nothing_acknowledged(project, point):
    data, pid = project
    child = Child(data, pid, "candidate", "A", n=3, stop_at=3, stop_point=point)
    child.expect("AT")
    # what the killed upload left behind before the restart's clean-up
    left = _files(data, pid)
    child.kill()
    assert [i for i, _ in child.acks] == [1, 2]
    third = hashlib.sha256(payload("A", 3, SIZE)).hexdigest()
    if point in ("file-partial", "file-written"):
        assert any(n.startswith(".tmp-") for n in left)
    if point in ("file-renamed", "record-written"):
        assert third in left  # the file is there, its record is not committed
    p = _check_consistent(data, pid)
    names = [c.name for c in p.open_project("alice", pid).candidates]
    # committed before the kill: durable though not acknowledged; else not listed at all
    assert names == (["A-1", "A-2", "A-3"] if point == "committed" else ["A-1", "A-2"])
    assert [int(cid) for _, cid in child.acks] == [
        c.id for c in p.open_project("alice", pid).candidates[:2]
    ]


@pytest.mark.parametrize("point", ["record-written", "committed"])
def test_a_writer_killed_during_a_record_write_loses_nothing_acknowledged(project, point):
    data, pid = project
    child = Child(data, pid, "view", "V", n=3, stop_at=3, stop_point=point)
    child.expect("AT")
    child.kill()
    p = _check_consistent(data, pid)
    views = p.open_project("alice", pid).views
    assert [v.name for v in views] == (
        ["V-1", "V-2", "V-3"] if point == "committed" else ["V-1", "V-2"]
    )
    for _, vid in child.acks:
        assert p.resolve_view("bob", vid).query.startswith("view=V-")


def test_a_project_creation_killed_half_way_is_removed_and_reported(project):
    data, pid = project
    child = Child(data, pid, "project", "P", n=2, stop_at=2, stop_point="project-written")
    child.expect("AT")
    child.kill()
    unfinished = [d.name for d in (data / "projects").iterdir() if d.name.startswith(".new-")]
    assert len(unfinished) == 1
    p = Projects(data, parse_groups(GROUPS))
    assert [pr.message for pr in p.problems] == ["an unfinished project creation; removed"]
    titles = sorted(i.title for i in p.list_projects("alice"))
    assert titles == ["P-1", "rear axle"]
    assert not any(d.name.startswith(".new-") for d in (data / "projects").iterdir())


def test_two_writers_adding_to_one_project_at_once_both_land(project):
    data, pid = project
    # A holds the project's write lock (record inserted, not committed) while B has its
    # file staged and goes for the lock; then both run free, 4 additions each
    a = Child(data, pid, "candidate", "A", n=4, stop_at=1, stop_point="record-written")
    a.expect("AT record-written")
    b = Child(data, pid, "candidate", "B", n=4, announce="file-written")
    b.expect("AT file-written")
    a.go()
    a.finish()
    b.finish()
    assert len(a.acks) == len(b.acks) == 4
    p = _check_consistent(data, pid)
    names = sorted(c.name for c in p.open_project("alice", pid).candidates)
    assert names == sorted([f"A-{i}" for i in range(1, 5)] + [f"B-{i}" for i in range(1, 5)])


@pytest.fixture()
def hooks():
    saved = Hooks(HOOKS.checkpoint, HOOKS.write)
    yield HOOKS
    HOOKS.checkpoint, HOOKS.write = saved.checkpoint, saved.write


def test_a_full_disk_during_an_upload_writes_nothing(project, hooks):
    data, pid = project
    p = Projects(data, parse_groups(GROUPS))
    p.add_candidate("alice", pid, "a.h5", payload("A", 1, SIZE), {"name": "A-1"})
    written = []

    def full_after_one_chunk(fd: int, chunk: memoryview) -> int:
        if written:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        written.append(len(chunk))
        return os.write(fd, chunk)

    hooks.write = full_after_one_chunk
    with pytest.raises(DiskFull, match="the data volume is full; nothing was saved"):
        p.add_candidate("alice", pid, "b.h5", payload("A", 2, SIZE), {"name": "A-2"})
    assert written  # the failure came mid-file
    hooks.write = os.write
    # no temporary file, no record, before any clean-up
    assert _files(data, pid) == {hashlib.sha256(payload("A", 1, SIZE)).hexdigest()}
    assert [c.name for c in p.open_project("alice", pid).candidates] == ["A-1"]
    _check_consistent(data, pid)
    # and the next upload, with space again, lands
    p.add_candidate("alice", pid, "b.h5", payload("A", 2, SIZE), {"name": "A-2"})
    _check_consistent(data, pid)


def test_a_full_database_writes_nothing(project, monkeypatch):
    """SQLite's own "database or disk is full" (its page limit reached) during the commit
    of a candidate: the renamed file is taken back, the record rolled back."""
    data, pid = project
    p = Projects(data, parse_groups(GROUPS))
    connect = ProjectDB.connect

    def limited(self: ProjectDB) -> sqlite3.Connection:
        conn = connect(self)
        pages = conn.execute("PRAGMA page_count").fetchone()[0]
        conn.execute(f"PRAGMA max_page_count={pages}")
        return conn

    monkeypatch.setattr(ProjectDB, "connect", limited)
    acked = []
    with pytest.raises(DiskFull, match="full"):
        for i in range(1, 400):
            name = f"A-{i}"
            p.add_candidate("alice", pid, f"{name}.h5", payload("A", i, 64), {"name": name})
            acked.append(name)
    monkeypatch.setattr(ProjectDB, "connect", connect)
    names = [c.name for c in p.open_project("alice", pid).candidates]
    assert names == acked
    files = _files(data, pid)
    assert files == {
        hashlib.sha256(payload("A", i, 64)).hexdigest() for i in range(1, len(acked) + 1)
    }


def test_damaged_projects_at_start_are_reported_and_the_others_open(tmp_path):
    p = Projects(tmp_path, parse_groups(GROUPS))
    ids = [p.create_project("alice", f"project {k}", {"oem": None}).id for k in range(4)]
    for pid in ids:
        p.add_candidate("alice", pid, "a.h5", payload(pid, 1, 5000), {"name": f"tire {pid}"})
    from app.projects.backup import backup, restore

    backup(tmp_path, tmp_path / "backup", [ids[0]])
    root = tmp_path / "projects"
    # 0: garbage over the header; 1: cut to its first page; 2: database file missing
    db0 = root / ids[0] / "project.sqlite3"
    with open(db0, "r+b") as f:
        f.write(b"this is not a database at all" * 4)
    db1 = root / ids[1] / "project.sqlite3"
    conn = sqlite3.connect(db1)
    conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    conn.close()
    with open(db1, "r+b") as f:
        f.truncate(4096)
    (root / ids[2] / "project.sqlite3").unlink()
    (root / "stray.txt").write_text("not a project")

    again = Projects(tmp_path, parse_groups(GROUPS))
    problems = {Path(pr.path).name: pr.message for pr in again.problems}
    assert set(problems) == {ids[0], ids[1], ids[2], "stray.txt"}
    assert "damaged" in problems[ids[0]] and "damaged" in problems[ids[1]]
    assert "missing" in problems[ids[2]]
    assert [i.id for i in again.list_projects("alice")] == [ids[3]]
    assert [c.name for c in again.open_project("alice", ids[3]).candidates] == [f"tire {ids[3]}"]
    for pid in ids[:3]:
        with pytest.raises(NotFound):
            again.open_project("alice", pid)
    # the damaged project restored from its backup opens again, without a restart
    restore(tmp_path / "backup", tmp_path, [ids[0]], replace=True)
    assert sorted(i.id for i in again.list_projects("alice")) == sorted([ids[0], ids[3]])
    assert [c.name for c in again.open_project("alice", ids[0]).candidates] == [f"tire {ids[0]}"]
