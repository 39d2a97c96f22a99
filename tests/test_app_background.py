"""Background work of the server (app/runtime/background.py): one thread per worker whatever
the number of tasks, a newer task of a key replaces the waiting one, long tasks take turns
step by step, the lower CPU priority, errors logged, the reference studies warmed once."""

from __future__ import annotations

import os
import sys
import threading

import pytest

from app import compute
from app.runtime import background, collector
from app.runtime.background import Worker

WAIT_S = 120


def _nice() -> int:
    return os.getpriority(os.PRIO_PROCESS, threading.get_native_id())


def _blocked(worker: Worker) -> threading.Event:
    """Occupy ``worker`` until the returned event is set."""
    started, release = threading.Event(), threading.Event()

    def hold():
        started.set()
        assert release.wait(WAIT_S)

    worker.submit(("holder",), hold)
    assert started.wait(WAIT_S)
    return release


def _threads(name: str) -> int:
    return sum(t.name == name and t.is_alive() for t in threading.enumerate())


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="thread priorities: Linux")
def test_background_work_runs_at_a_lower_priority_and_the_caller_keeps_its_own():
    seen = {}
    w = Worker("test-nice", nice=background.BACKGROUND_NICE, background=True)
    mine = _nice()
    w.submit(("s", "nice"), lambda: seen.update(nice=_nice()))
    assert w.idle(WAIT_S)
    assert seen["nice"] == min(19, mine + background.BACKGROUND_NICE)
    assert _nice() == mine


def test_a_newer_task_of_a_key_replaces_the_waiting_one_and_one_thread_runs_them_all():
    """Four sessions flipping a setting 25 times each: one thread, and per session only the
    last task runs (the superseded ones are dropped while they wait)."""
    w = Worker("test-supersede")
    release = _blocked(w)
    ran = []
    for step in range(25):
        for session in range(4):
            w.submit(("session", session, "peaks"), lambda s=session, k=step: ran.append((s, k)))
    assert w.waiting == 4 and _threads("test-supersede") == 1
    release.set()
    assert w.idle(WAIT_S)
    assert sorted(ran) == [(s, 24) for s in range(4)]


def test_long_tasks_of_several_sessions_take_turns_step_by_step():
    w = Worker("test-turns")
    release = _blocked(w)
    order = []

    def steps(name, n):
        for k in range(n):
            order.append((name, k))
            yield

    w.submit(("a",), lambda: steps("a", 4))
    w.submit(("b",), lambda: steps("b", 2))
    release.set()
    assert w.idle(WAIT_S)
    assert order == [("a", 0), ("b", 0), ("a", 1), ("b", 1), ("a", 2), ("a", 3)]


def test_the_queue_is_bounded_and_a_closed_sessions_tasks_are_dropped(monkeypatch):
    monkeypatch.setattr(background, "MAX_WAITING", 5)
    w = Worker("test-bound")
    release = _blocked(w)
    ran = []
    for k in range(8):
        w.submit((f"s{k}", "x"), lambda k=k: ran.append(k))
    assert w.waiting == 5 and w.dropped == 3  # the three oldest
    w.cancel("s7")  # the newest one's session closed
    release.set()
    assert w.idle(WAIT_S)
    assert ran == [3, 4, 5, 6]


def test_a_failing_task_is_logged_not_raised_and_the_worker_goes_on(caplog):
    w = Worker("test-fail")
    done = []

    def boom():
        raise RuntimeError("boom")

    w.submit(("s", "fail"), boom)
    w.submit(("s", "next"), lambda: done.append(1))
    assert w.idle(WAIT_S)
    assert done == [1]
    assert any("test-fail" in r.getMessage() for r in caplog.records)


def test_the_reference_studies_are_warmed_once(monkeypatch):
    """Once per process, each harmonic's map and the freeze after a quiet moment (issue 33)."""
    asked = []
    monkeypatch.setattr(compute, "error_map", lambda h, c: asked.append((h, c)))
    monkeypatch.setattr(collector, "wait_quiet", lambda: asked.append("quiet"))
    monkeypatch.setattr(background, "freeze_long_lived", lambda: asked.append("freeze"))
    monkeypatch.setattr(background, "_warmed", threading.Event())
    t = background.warm_reference_studies()
    assert t is not None
    t.join(60)
    assert background.warm_reference_studies() is None  # once per process
    maps = [x for h in range(1, 8) for x in ("quiet", (h, "6dof"))]
    assert asked == [*maps, "quiet", "freeze"]  # the full collection in a quiet moment too


def test_a_session_never_waits_for_a_background_thread_computing_the_same_result():
    """Priority inversion: background work (nice 10) computing a map a page asks for would
    make the page wait at a fraction of a core on a busy machine. The page's thread
    computes it itself; two sessions' threads still share one computation."""
    started, release = threading.Event(), threading.Event()
    calls = []

    @compute.shared_cache(maxsize=4)
    def slow(x):
        calls.append(threading.current_thread().name)
        if threading.current_thread().name == "test-bg":
            started.set()
            assert release.wait(120)
        return x * 2

    w = Worker("test-bg", background=True)
    w.submit(("s", "slow"), lambda: slow(21))
    assert started.wait(60)
    assert slow(21) == 42  # returns while the background thread is still held
    assert calls == ["test-bg", threading.current_thread().name]
    release.set()
    assert w.idle(60)
