"""A session's results store and its scatter bands: an export always describes its own
data, a superseded band is cancelled, bands of several sessions take turns, a closed page
computes and draws nothing more.

Truth: ``fbs_core.scatter_band`` called directly, the grids of the harmonics, and the order
in which the kernel's chunks actually ran (recorded by the turnstile).
"""

from __future__ import annotations

import os
import threading
import time

import numpy as np
import pytest

import fbs_core
from app import compute
from app.export import read_csv, to_csv
from app.runtime import bands
from app.state import DashboardState
from app.store import Results

WAIT_S = 300.0


def _wait(cond, what: str, timeout: float = WAIT_S) -> None:
    t0 = time.monotonic()
    while not cond():
        if time.monotonic() - t0 > timeout:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.01)


def _results(**noise) -> Results:
    state = DashboardState()
    state.noise.param.update(**{"rounds": 200, **noise})
    return Results(state, background=True)


def test_an_export_during_a_band_describes_the_band_it_holds(monkeypatch):
    """Click CSV while a band for new settings computes: the file holds the previous band
    under the previous band's settings, never old data under the new settings."""
    res = _results()
    res.request_band()
    _wait(lambda: res.band is not None and not res.band_status.busy, "the first band")
    assert res.band_curves.meta["harmonic"] == 1
    gate = threading.Event()
    real = compute.band

    def slow_band(*args, **kw):
        if args[0] == 7:
            assert gate.wait(WAIT_S)
        return real(*args, **kw)

    monkeypatch.setattr(compute, "band", slow_band)
    res.state.case.harmonic = 7  # a band for harmonic 7 starts and waits
    assert res.band_status.busy
    meta, cols = read_csv(to_csv(res.band_curves.columns, res.band_curves.meta, "scatter"))
    assert meta["harmonic"] == "1" and meta["rounds"] == "200"
    np.testing.assert_allclose(cols["freq_Hz"], fbs_core.harmonic(1).frequencies())
    gate.set()
    _wait(lambda: not res.band_status.busy, "the harmonic-7 band")
    meta, cols = read_csv(to_csv(res.band_curves.columns, res.band_curves.meta, "scatter"))
    assert meta["harmonic"] == "7"
    np.testing.assert_allclose(cols["freq_Hz"], fbs_core.harmonic(7).frequencies())
    want = fbs_core.scatter_band(
        7, noise=0.1, rounds=200, n_modes=50, percentiles=compute.Q_LEVELS, seed=0
    )
    j = want.dofs.index("bushing:z")
    np.testing.assert_allclose(cols["maximum_dB"], 20 * np.log10(want.maximum[:, j]), rtol=1e-12)


class Recorder(bands.Turnstile):
    """The process' turnstile, recording whose chunk ran when."""

    def __init__(self):
        super().__init__()
        self.turns: list[tuple] = []

    def next_turn(self, job):
        ok = super().next_turn(job)
        if ok:
            self.turns.append(job.key)
        return ok


@pytest.fixture
def turns(monkeypatch):
    rec = Recorder()
    monkeypatch.setattr(bands, "TURNSTILE", rec)
    return rec


def _live_band_threads() -> int:
    return sum(t.name == "scatter-band" and t.is_alive() for t in threading.enumerate())


def test_a_newer_request_cancels_the_running_band_and_nothing_queues(turns):
    res = _results(rounds=150_000, seed=11)
    res.state.case.harmonic = 7
    res.request_band()
    _wait(lambda: len(turns.turns) >= 2, "the long band to run")
    # six more requests in a row, as a dragged slider or an impatient user sends them
    for seed in range(12, 18):
        res.state.noise.seed = seed
    res.state.noise.rounds = 300
    _wait(lambda: res.band is not None and not res.band_status.busy, "the last band")
    assert res.band.settings.seed == 17 and res.band.result.rounds == 300
    _wait(lambda: _live_band_threads() == 0, "every band thread to end")
    long_key = compute.band_key(7, 50, "6dof", 10.0, "both", False, 150_000, 11)
    # the long band stopped after a few chunks instead of running its ~100
    assert 2 <= turns.turns.count(long_key) < 20
    ran = {k.seed for k in turns.turns}
    assert ran <= {11, 12, 13, 14, 15, 16, 17}


def test_bands_of_two_sessions_take_turns_chunk_by_chunk(turns):
    hog = _results(rounds=150_000, seed=21)
    hog.state.case.harmonic = 7
    hog.request_band()
    _wait(lambda: len(turns.turns) >= 2, "the long band to run")
    small = _results(rounds=2_000, seed=22)
    done_at = []  # how many chunks had started when the small band was published
    small.param.watch(lambda e: done_at.append(len(turns.turns)), "band")
    small.request_band()
    _wait(lambda: small.band is not None and not small.band_status.busy, "the small band")
    # the small band finished while the long one still runs: it waited for at most one
    # chunk of the long band per chunk of its own
    assert hog.band_status.busy and hog.band is None
    order = [k.seed for k in turns.turns[: done_at[0]]]
    first_small = order.index(22)
    assert order[first_small + 1 :].count(21) <= order.count(22)
    hog.close()
    _wait(lambda: _live_band_threads() == 0, "the long band to stop")
    assert hog.band is None  # a closed session publishes nothing


def test_turns_alternate_between_waiting_bands():
    t = bands.Turnstile()
    a, b = bands.Job("a"), bands.Job("b")
    order = []

    def work(job, n):
        for _ in range(n):
            assert t.next_turn(job)
            order.append(job.key)
            time.sleep(0.002)  # a chunk of work
        t.leave(job)

    assert t.next_turn(a)  # a holds the turn; b arrives and queues
    tb = threading.Thread(target=work, args=(b, 3))
    tb.start()
    _wait(lambda: t.waiting == 1, "b to queue")
    work(a, 3)
    tb.join(WAIT_S)
    assert order == ["b", "a", "b", "a", "b", "a"] or order == ["a", "b", "a", "b", "a", "b"]


def test_a_page_closed_during_a_band_draws_nothing_more(turns):
    from app.main import create_app

    res = _results(rounds=100_000, seed=31)
    app = create_app(results=res)  # no server: the first band computed in place
    res.state.case.harmonic = 6  # with background=True this one runs on its thread
    _wait(lambda: len(turns.turns) >= 1, "the band to start")
    before = res.band_curves
    res.close()  # the session ends
    _wait(lambda: _live_band_threads() == 0, "the band to stop")
    assert res.band_curves is before
    res.state.case.harmonic = 2  # a late event of the closed page
    assert res.band_curves is before and res.response.meta["harmonic"] == 6
    assert app is not None


def _nice() -> int:
    return os.getpriority(os.PRIO_PROCESS, threading.get_native_id())


def test_a_band_runs_at_a_lower_cpu_priority_than_the_controls(monkeypatch):
    """The band's thread (and so the numba threads it starts) yields the cores to the
    threads that answer control changes: its nice value is BAND_NICE above theirs."""
    monkeypatch.delenv(bands.BAND_NICE_ENV, raising=False)
    seen = []
    real = compute.band

    def band(*args, **kw):
        seen.append((threading.current_thread().name, _nice()))
        return real(*args, **kw)

    monkeypatch.setattr(compute, "band", band)
    monkeypatch.setattr(bands, "KERNELS_WARM", threading.Event())
    res = _results(seed=40)
    mine = _nice()
    # the first band of a process compiles the kernels: at the server's own priority (on a
    # machine other processes keep busy, a low priority made it take minutes)
    res.request_band()
    _wait(lambda: res.band is not None and not res.band_status.busy, "the first band")
    assert seen == [("scatter-band", mine)] and bands.KERNELS_WARM.is_set()
    res.state.noise.seed = 41  # background: on the band's own thread, at a lower priority
    _wait(lambda: res.band.settings.seed == 41 and not res.band_status.busy, "the band")
    assert seen[-1] == ("scatter-band", min(19, mine + bands.BAND_NICE))
    assert _nice() == mine  # the caller's thread (a Panel worker when served) is untouched
    monkeypatch.setenv(bands.BAND_NICE_ENV, "0")  # the deployment's switch
    res.state.noise.seed = 42
    _wait(lambda: res.band.settings.seed == 42 and not res.band_status.busy, "the band")
    assert seen[-1] == ("scatter-band", mine)


def test_a_dof_change_does_not_wait_for_another_sessions_band():
    """Another session's band holds the parallel kernel (a chunk is running): this session's
    DOF change redraws its band (a regenerated single round) all the same."""
    from fbs_core.studies import scatter

    res = _results(seed=51)
    res.request_band()
    _wait(lambda: res.band is not None and not res.band_status.busy, "the band")
    done = threading.Event()

    def change():
        res.state.case.dof = "x"
        done.set()

    with scatter._LOCK:  # a chunk of another session's band is running
        threading.Thread(target=change, daemon=True).start()
        finished = done.wait(120)  # liveness, not speed: with the lock needed it never ends
    assert finished, "the DOF change waited for another session's band"
    assert res.band_curves.meta["response DOF"] == "bushing:x"
    want = fbs_core.scatter_band(
        1, noise=0.1, rounds=200, n_modes=50, percentiles=compute.Q_LEVELS, seed=51
    )
    j = want.dofs.index("bushing:x")
    k = [c for c in res.band_curves.columns if c.startswith("round_")][0]
    np.testing.assert_allclose(
        res.band_curves.columns[k], 20 * np.log10(np.abs(want.round(0)[:, j])), rtol=1e-12
    )


def test_a_bands_setup_runs_in_its_turn(turns, monkeypatch):
    """The subsystem arrays of a new band (a tire synthesis) are computed in the band's turn,
    not beside another session's chunk."""
    from collections import OrderedDict

    from fbs_core.studies import _models, scatter

    monkeypatch.setattr(scatter, "_INPUTS", OrderedDict())  # nothing cached: a synthesis
    holders = []
    real = _models.tire_arrays

    def tire_arrays(*args, **kw):
        holders.append(turns.holder)
        return real(*args, **kw)

    chunks = []

    def counted(kernel):
        def chunk(*args):
            chunks.append(turns.holder)
            return kernel(*args)

        return chunk

    monkeypatch.setattr(_models, "tire_arrays", tire_arrays)
    # a chunk of lines runs one of the two parallel kernels: the fused rounds and statistics
    # (as many lines as threads or more), or the rounds shared by the threads (fewer)
    for name in ("noisy_band_stats", "noisy_block_run"):
        monkeypatch.setattr(
            scatter._noise_kernels, name, counted(getattr(scatter._noise_kernels, name))
        )
    res = _results(seed=61, rounds=5_000)
    res.request_band()
    _wait(lambda: res.band is not None and not res.band_status.busy, "the band")
    assert len(holders) == 1 and holders[0] is not None and holders[0].owner is res
    # every chunk ran in a turn of its own band, the first in the setup's turn: one turn
    # per chunk, the setup's included
    assert chunks and all(h is not None and h.owner is res for h in chunks)
    assert turns.turns.count(res.snapshot().band_key()) == len(chunks)


def test_sessions_asking_for_the_same_band_share_one_computation(turns, monkeypatch):
    """Three sessions ask for the same missing band at once (a meeting opening one link):
    the core computes it once, all three show it, and a session that leaves (cancels)
    does not stop it for the others. Truth: ``fbs_core.scatter_band`` called directly."""
    calls = []
    real = compute.band
    gate = threading.Event()

    def band(*args, **kw):
        calls.append(args)
        gate.wait(WAIT_S)  # all three sessions ask before the computation goes on
        return real(*args, **kw)

    monkeypatch.setattr(compute, "band", band)
    sessions = [_results(seed=71, rounds=3_000) for _ in range(3)]
    for res in sessions:
        res.request_band()
    # all three asked: three computations (each its own) or one run with three jobs
    _wait(lambda: len(calls) == 3 or len(_run_jobs()) == 3, "all three sessions to ask")
    sessions[0].cancel_band()  # one leaves the meeting before the band is done
    gate.set()
    for res in sessions[1:]:
        _wait(lambda r=res: r.band is not None and not r.band_status.busy, "the shared band")
    assert len(calls) == 1  # computed once
    assert sessions[1].band.result is sessions[2].band.result
    assert sessions[0].band is None  # the cancelled session shows nothing of it
    want = fbs_core.scatter_band(
        1, noise=0.1, rounds=3_000, n_modes=50, percentiles=compute.Q_LEVELS, seed=71
    )
    np.testing.assert_array_equal(sessions[1].band.result.maximum, want.maximum)
    _wait(lambda: _live_band_threads() == 0 and not bands._RUNS, "the band threads to end")


def _run_jobs() -> list:
    return [j for run in list(getattr(bands, "_RUNS", {}).values()) for j in run.jobs]


def test_a_shared_band_stops_once_every_session_cancelled_it(turns):
    sessions = [_results(seed=81, rounds=150_000) for _ in range(2)]
    for res in sessions:
        res.state.case.harmonic = 7
        res.request_band()
    key = compute.band_key(7, 50, "6dof", 10.0, "both", False, 150_000, 81)
    _wait(lambda: turns.turns.count(key) >= 2, "the long band to run")
    sessions[0].cancel_band()
    n = turns.turns.count(key)
    _wait(lambda: turns.turns.count(key) >= n + 2, "the band to go on for the other session")
    sessions[1].cancel_band()
    _wait(lambda: _live_band_threads() == 0 and not bands._RUNS, "the band to stop")
    assert turns.turns.count(key) < 40  # stopped after a few chunks of its ~100
    assert all(res.band is None for res in sessions)
