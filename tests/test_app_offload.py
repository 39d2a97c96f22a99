"""The dashboard's heavy bands on a Dask cluster (``FBS_DASK_SCHEDULER``): computed by the
workers, equal to the in-process band, with progress from the futures, cancelled by a newer
request or a closed page.

Truth: ``fbs_core.scatter_band`` called directly in this process, and what the scheduler
itself reports (its task stream: which worker ran which task; the tasks it still holds).
"""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

import fbs_core
from app import compute
from app.runtime import offload
from app.state import DashboardState
from app.store import Results
from fbs_core.campaign import SCHEDULER_ENV
from fbs_core.campaign.cluster import DEFAULT_TASK_ROUND_LINES, line_blocks

WAIT_S = 300.0


def _wait(cond, what: str, timeout: float = WAIT_S) -> None:
    t0 = time.monotonic()
    while not cond():
        if time.monotonic() - t0 > timeout:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.02)


@pytest.fixture(scope="module")
def cluster():
    from distributed import Client, LocalCluster

    with (
        LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cl,
        Client(cl) as client,
    ):
        client.wait_for_workers(2)
        yield client
    offload.reset()


@pytest.fixture
def on_cluster(cluster, monkeypatch):
    monkeypatch.setenv(SCHEDULER_ENV, cluster.scheduler.address)
    yield cluster
    offload.reset()


def _tasks_on_scheduler(client) -> int:
    return client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks))


def _results(**noise) -> Results:
    state = DashboardState()
    state.noise.param.update(**noise)
    return Results(state, background=True)


def test_only_heavy_bands_go_to_a_configured_cluster(monkeypatch):
    key = compute.band_key(1, None, "6dof", 10.0, "both", False, 200_000, 1)
    monkeypatch.delenv(SCHEDULER_ENV, raising=False)
    monkeypatch.delenv(offload.MIN_ROUNDS_ENV, raising=False)
    assert not offload.wanted(key)  # no scheduler: nothing changes
    monkeypatch.setenv(SCHEDULER_ENV, "tcp://127.0.0.1:8786")
    assert offload.wanted(key)
    assert offload.wanted(compute.band_key(1, None, "6dof", 10.0, "both", False, 100_000, 1))
    assert not offload.wanted(compute.band_key(1, None, "6dof", 10.0, "both", False, 99_999, 1))


def test_unreachable_scheduler_computes_the_band_here(monkeypatch):
    import socket

    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    monkeypatch.setenv(SCHEDULER_ENV, f"tcp://127.0.0.1:{port}")
    monkeypatch.setenv(offload.MIN_ROUNDS_ENV, "100")
    monkeypatch.setattr(offload, "client", _refused)
    res = _results(rounds=150, seed=3)
    band = res.band_now()
    assert band is not None and band.result.rounds == 150
    offload.reset()


def _refused():
    raise OSError("connection refused")


def test_offloaded_band_runs_on_the_workers_equals_the_in_process_band_and_shows_progress(
    on_cluster, monkeypatch
):
    from distributed import get_task_stream

    monkeypatch.setenv(offload.MIN_ROUNDS_ENV, "2000")
    rounds, seed = 3000, 4242
    res = _results(rounds=rounds, seed=seed, frequency_dependent=True)
    res.state.case.harmonic = 2
    seen = []  # (done, total) lines of the progress the page shows
    res.param.watch(lambda e: seen.append((e.new.done, e.new.total)), "band_status")
    workers = set(on_cluster.scheduler_info()["workers"])
    with get_task_stream(on_cluster) as ts:
        res.request_band()
        _wait(lambda: res.band is not None and not res.band_status.busy, "the band")
    ran = [t for t in ts.data if t["key"].startswith("band_block")]
    n_blocks = len(line_blocks(rounds, 100, DEFAULT_TASK_ROUND_LINES))
    assert len(ran) == n_blocks and {t["worker"] for t in ran} <= workers
    # progress from the futures: lines of finished blocks, up to all 100 lines
    done = [d for d, t in seen if t == 100]
    assert done and done[-1] == 100 and done == sorted(done)
    s = res.band.settings
    assert (s.harmonic, s.rounds, s.seed, s.frequency_dependent) == (2, rounds, seed, True)
    direct = fbs_core.scatter_band(
        2,
        noise=s.noise / 100,
        target=s.target,
        rounds=rounds,
        frequency_dependent=True,
        seed=seed,
        n_modes=s.n_modes,
        coupling=s.coupling,
        percentiles=compute.Q_LEVELS,
    )
    b = res.band.result
    for k in ("minimum", "maximum", "percentiles", "reference"):
        np.testing.assert_allclose(getattr(b, k), getattr(direct, k), rtol=1e-12, atol=0)
    np.testing.assert_array_equal(b.argmax_round, direct.argmax_round)
    np.testing.assert_allclose(b.convergence.maximum, direct.convergence.maximum, rtol=1e-12)
    r = int(direct.argmax_round[50, 2])  # a round regenerates as the in-process one does
    np.testing.assert_allclose(b.round(r), direct.round(r), rtol=1e-12, atol=0)
    assert res.band_curves.meta["rounds"] == rounds  # drawn and exported like any band
    _wait(lambda: _tasks_on_scheduler(on_cluster) == 0, "the futures to be released")


def _blocks_started(res: Results) -> bool:
    return res.band_status.total == 633  # the cluster's first report: 0 of 633 lines


def test_a_closed_page_cancels_its_futures_on_the_cluster(on_cluster, monkeypatch):
    from distributed import get_task_stream

    monkeypatch.delenv(offload.MIN_ROUNDS_ENV, raising=False)  # the default: 100,000
    res = _results(rounds=100_000, seed=77)
    res.state.case.harmonic = 7  # 633 lines: 32 blocks of about 1.6 s each
    n_blocks = len(line_blocks(100_000, 633, DEFAULT_TASK_ROUND_LINES))
    with get_task_stream(on_cluster) as ts:
        res.request_band()
        _wait(lambda: _blocks_started(res), "the blocks to be submitted")
        _wait(lambda: any(on_cluster.processing().values()), "the workers to start")
        res.close()
        _wait(lambda: _tasks_on_scheduler(on_cluster) == 0, "the futures to be cancelled")
    done = [t for t in ts.data if t["key"].startswith("band_block")]
    assert len(done) < n_blocks // 2  # stopped, not run to the end
    assert res.band is None


def test_a_newer_request_cancels_the_running_offloaded_band(on_cluster, monkeypatch):
    monkeypatch.delenv(offload.MIN_ROUNDS_ENV, raising=False)
    res = _results(rounds=100_000, seed=78)
    res.state.case.harmonic = 7
    finished = threading.Event()
    res.param.watch(lambda e: finished.set(), "band")
    res.request_band()
    _wait(lambda: _blocks_started(res), "the blocks to be submitted")
    _wait(lambda: any(on_cluster.processing().values()), "the workers to start")
    res.state.noise.rounds = 500  # a light band: computed here
    _wait(lambda: res.band is not None and not res.band_status.busy, "the new band")
    assert res.band.result.rounds == 500 and res.band.settings.harmonic == 7
    _wait(lambda: _tasks_on_scheduler(on_cluster) == 0, "the old futures to be cancelled")
