"""Full collections at quiet moments (app.runtime.collector), decided on a fake clock."""

from __future__ import annotations

import gc
import weakref

from app.runtime.collector import (
    BUSY_SHARE,
    PERIOD,
    QUIET,
    THAW_EVERY,
    IdleCollector,
    wait_quiet,
)


class _Clock:
    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


def _collector():
    calls: list[str] = []
    clock = _Clock()
    c = IdleCollector(
        collect=lambda: calls.append("collect"),
        collect_young=lambda: calls.append("young"),
        freeze=lambda: calls.append("freeze"),
        unfreeze=lambda: calls.append("unfreeze"),
        clock=clock,
    )
    return c, clock, calls


def test_nothing_happens_before_activity_or_while_it_goes_on():
    c, clock, calls = _collector()
    clock.t += 10
    assert not c.step() and calls == []  # never active: nothing to collect
    c.touch()
    for _ in range(20):  # a draw every QUIET/2 s: never quiet
        clock.t += QUIET / 2
        assert not c.step()
        c.touch()
    assert calls == []


def test_one_collection_and_freeze_once_quiet_then_none_until_new_activity():
    c, clock, calls = _collector()
    c.touch()
    clock.t += QUIET
    assert c.step() and calls == ["young", "freeze"]
    clock.t += 100
    assert not c.step() and calls == ["young", "freeze"]  # nothing happened since
    c.touch()
    clock.t += QUIET
    assert c.step() and calls == ["young", "freeze"] * 2


def test_an_ended_session_is_thawed_before_the_next_quiet_collection():
    c, clock, calls = _collector()
    c.session_ended()
    assert not c.step()  # not quiet yet
    clock.t += QUIET
    assert c.step() and calls == ["unfreeze", "collect", "freeze"]
    c.touch()
    clock.t += QUIET
    assert c.step() and calls[3:] == ["young", "freeze"]  # thawed once only


def test_frozen_objects_are_thawed_at_least_every_thaw_every_seconds_of_activity():
    c, clock, calls = _collector()
    clock.t += THAW_EVERY
    c.touch()
    clock.t += QUIET
    assert c.step() and calls == ["unfreeze", "collect", "freeze"]
    c.touch()
    clock.t += QUIET
    assert c.step() and calls[3:] == ["young", "freeze"]


def test_no_collection_while_the_process_computes_without_drawing():
    # a page being built or a band computed asks for no draw for a while: the process's
    # CPU time says it is not quiet
    calls: list[str] = []
    clock, cpu = _Clock(), [0.0]
    c = IdleCollector(
        collect=lambda: calls.append("collect"),
        collect_young=lambda: calls.append("young"),
        freeze=lambda: calls.append("freeze"),
        unfreeze=lambda: None,
        clock=clock,
        cpu=lambda: cpu[0],
    )
    c.touch()
    for _ in range(30):  # 3 s without a draw, a core busy
        clock.t += 0.1
        cpu[0] += 0.1
        assert not c.step()
    for _ in range(int(QUIET / 0.1) - 1):  # the work ends: quiet, but not for QUIET s yet
        clock.t += 0.1
        cpu[0] += 0.1 * BUSY_SHARE / 4
        assert not c.step()
    clock.t += 0.2
    assert c.step() and calls == ["young", "freeze"]


class _Cycle:
    def __init__(self) -> None:
        self.me = self


def test_a_thawed_quiet_collection_frees_cycles_that_were_frozen():
    # with the real gc: a cycle frozen by one quiet collection is freed by the thawed one
    clock = _Clock()
    c = IdleCollector(clock=clock)
    try:
        obj = _Cycle()
        ref = weakref.ref(obj)
        c.touch()
        clock.t += QUIET
        assert c.step()
        del obj
        gc.collect()
        assert ref() is not None, "frozen: a full collection leaves it"
        c.session_ended()
        clock.t += QUIET
        assert c.step()
        assert ref() is None, "thawed and collected"
    finally:
        gc.unfreeze()  # leave the test process as it was


def test_the_counts_of_what_outlived_the_sessions_are_logged_after_a_thawed_collection(caplog):
    c, clock, calls = _collector()
    alive = [3]
    c.alive["pages"] = lambda: alive[0]
    caplog.set_level("INFO", logger="app.runtime.collector")
    c.touch()
    clock.t += QUIET
    assert c.step() and "alive" not in caplog.text  # not thawed: nothing was freed
    c.session_ended()
    alive[0] = 0  # counted after the collection, which freed the ended session
    clock.t += QUIET
    assert c.step() and calls[-3:] == ["unfreeze", "collect", "freeze"]
    assert "alive: pages 0" in caplog.text


def test_live_holds_the_stores_not_yet_freed():
    from app.state import DashboardState
    from app.store import LIVE, Results

    state = DashboardState()
    state.noise.rounds = 30
    n0 = len(LIVE)
    r = Results(state)
    assert len(LIVE) == n0 + 1 and r in LIVE
    r.close()
    del r, state  # (the state's watchers hold its store)
    gc.collect()
    assert len(LIVE) == n0


def test_one_ended_session_among_many_open_waits_for_more_or_for_thaw_every():
    """A thawed collection walks every object (2.2 s with 50 pages open): one ended session
    among many open ones does not make it due; a quarter of them does, or THAW_EVERY."""
    c, clock, calls = _collector()
    for _ in range(8):
        c.session_started()
    c.session_ended()  # 1 ended, 7 open
    clock.t += QUIET
    assert c.step() and calls == ["young", "freeze"]  # not thawed
    c.session_ended()  # 2 ended since the last thaw, 6 open: a quarter
    clock.t += QUIET
    assert c.step() and calls[-3:] == ["unfreeze", "collect", "freeze"]
    c.session_ended()  # 1 ended since, 5 open: waits ...
    clock.t += QUIET
    assert c.step() and calls[-3:] != ["unfreeze", "collect", "freeze"]
    c.touch()  # ... until THAW_EVERY after the last thaw
    clock.t += THAW_EVERY
    assert c.step() and calls[-3:] == ["unfreeze", "collect", "freeze"]


def test_work_computed_ahead_waits_for_a_quiet_moment():
    """Issue 33: the warm-up's steps wait until no draw was asked for and no session started
    or ended during QUIET seconds, and a step runs once that is so (after a collection too)."""
    c, clock, _ = _collector()
    assert c.quiet()  # nothing ever happened
    slept: list[float] = []

    def sleep(dt: float) -> None:  # the fake clock moves as the poll sleeps
        slept.append(dt)
        clock.t += dt

    for mark in (c.touch, c.session_started, c.session_ended):
        mark()
        assert not c.quiet()
        clock.t += QUIET / 2
        assert not c.quiet()
        slept.clear()
        wait_quiet(c, sleep)
        assert c.quiet() and 0 < sum(slept) <= QUIET / 2 + PERIOD
    c.touch()
    for _ in range(3):  # a page drawing every QUIET / 2 s holds the work back
        clock.t += QUIET / 2
        assert not c.quiet()
        c.touch()
    clock.t += QUIET
    assert c.step() and c.quiet()  # the quiet collection does not make it busy again
