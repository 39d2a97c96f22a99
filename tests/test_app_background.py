"""Background work of the server (app/background.py): lower CPU priority, errors logged,
the reference studies warmed once per process."""

from __future__ import annotations

import os
import sys
import threading

import pytest

from app import background, compute


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="thread priorities: Linux")
def test_background_threads_run_at_a_lower_priority_and_the_caller_keeps_its_own():
    seen = {}

    def work():
        seen["nice"] = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())

    mine = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    background.start(work, "test-nice").join(60)
    assert seen["nice"] == max(mine, background.BACKGROUND_NICE)
    assert os.getpriority(os.PRIO_PROCESS, threading.get_native_id()) == mine


def test_a_failing_background_job_is_logged_not_raised(caplog):
    def work():
        raise RuntimeError("boom")

    background.start(work, "test-fail").join(60)
    assert any("test-fail" in r.getMessage() for r in caplog.records)


def test_the_reference_studies_are_warmed_once(monkeypatch):
    asked = []
    monkeypatch.setattr(compute, "error_map", lambda h, c: asked.append((h, c)))
    monkeypatch.setattr(background, "_warmed", threading.Event())
    t = background.warm_reference_studies()
    assert t is not None
    t.join(60)
    assert background.warm_reference_studies() is None  # once per process
    assert asked == [(h, "6dof") for h in range(1, 8)]


def test_a_session_never_waits_for_a_background_thread_computing_the_same_result():
    """Priority inversion: the warm-up (nice 10) computing a map a page asks for would make
    the page wait at a fraction of a core on a busy machine. The page's thread computes it
    itself; two sessions' threads still share one computation."""
    started, release = threading.Event(), threading.Event()
    calls = []

    @compute.shared_cache(maxsize=4)
    def slow(x):
        calls.append(threading.current_thread().name)
        if threading.current_thread().name == "test-bg":
            started.set()
            assert release.wait(120)
        return x * 2

    bg = background.start(lambda: slow(21), "test-bg")
    assert started.wait(60)
    assert slow(21) == 42  # returns while the background thread is still held
    assert calls == ["test-bg", threading.current_thread().name]
    release.set()
    bg.join(60)
