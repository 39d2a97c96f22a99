"""Waits of a session for work it shares with others end: a shared computation whose owner
raises reports the error to every waiter (it is not computed again by each), one whose
owner is stuck or gone is computed by the waiter itself after a deadline, never waited for
for ever (app.compute.shared_cache)."""

from __future__ import annotations

import threading

import pytest

from app import compute

WAIT_S = 120


def _run(fn, *args):
    """``fn(*args)`` on a thread; (thread, box with 'value' or 'error')."""
    box: dict = {}

    def go():
        try:
            box["value"] = fn(*args)
        except BaseException as e:  # the test reads it
            box["error"] = e

    t = threading.Thread(target=go, daemon=True)
    t.start()
    return t, box


def test_the_owners_error_reaches_every_waiter_and_is_computed_once():
    calls = []
    started, release = threading.Event(), threading.Event()

    @compute.shared_cache(maxsize=4)
    def work(x):
        calls.append(x)
        started.set()
        assert release.wait(WAIT_S)
        raise ValueError(f"bad input {x}")

    owner, b0 = _run(work, 1)
    assert started.wait(WAIT_S)
    waiters = [_run(work, 1) for _ in range(3)]
    # the waiters are waiting on the owner's entry before it fails
    deadline = threading.Event()
    for _ in range(200):
        if all(t.is_alive() for t, _ in waiters):
            break
        deadline.wait(0.01)
    release.set()
    for t, _ in [(owner, b0), *waiters]:
        t.join(WAIT_S)
        assert not t.is_alive()
    for _, box in [(owner, b0), *waiters]:
        assert isinstance(box.get("error"), ValueError) and "bad input 1" in str(box["error"])
    assert calls == [1]  # reported to every waiter, not computed again by each
    # the next call tries again
    release.set()
    with pytest.raises(ValueError):
        work(1)
    assert calls == [1, 1]


def test_a_stuck_owner_does_not_hold_a_waiter_for_ever():
    """The owner never finishes (a lost or wedged thread): the waiter computes the entry
    itself once the deadline has passed, and gets the right value."""
    stuck, release = threading.Event(), threading.Event()
    calls = []

    @compute.shared_cache(maxsize=4)
    def square(x):
        calls.append(threading.current_thread().name)
        if len(calls) == 1:  # the first caller wedges
            stuck.set()
            release.wait(WAIT_S)
        return x * x

    square.wait_s = 0.5
    owner, _ = _run(square, 7)
    assert stuck.wait(WAIT_S)
    t, box = _run(square, 7)
    t.join(WAIT_S / 4)
    try:
        assert not t.is_alive(), "the waiter still waits for a wedged owner"
        assert box == {"value": 49}
    finally:
        release.set()
        owner.join(WAIT_S)


def test_an_owner_thread_that_ended_without_finishing_is_not_waited_for():
    """The owner's thread is gone while the computation is marked as under way (a worker
    lost): the waiter does not wait out the deadline, it computes the entry."""

    @compute.shared_cache(maxsize=4)
    def double(x):
        return 2 * x

    double.wait_s = WAIT_S  # a long deadline: only the owner's end may free the waiter
    # a computation marked as under way by a thread that has ended without finishing it
    ghost = threading.Thread(target=lambda: None)
    ghost.start()
    ghost.join()
    entry = compute._Entry(False)
    entry.owner = ghost
    double.running[(5,)] = entry
    t, box = _run(double, 5)
    t.join(WAIT_S / 4)
    assert not t.is_alive() and box == {"value": 10}
    # the lost entry is gone: the next caller computes at once too
    assert double(6) == 12 and (5,) not in double.running
