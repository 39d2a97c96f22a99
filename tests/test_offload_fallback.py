"""A Dask cluster that cannot compute a heavy band costs the dashboard no waiting: the band is
computed in the process (issue 28, the Dask items).

- an unreachable scheduler is tried by one band at a time, and then left alone for a while
  (backoff): before, every heavy band waited 10 s for the connection, one after another
  under a global lock;
- a scheduler without workers, or one that goes away while the band runs, ends in the
  in-process band, not in a failure or a wait without end.

Truth: the number of connection attempts (a stand-in ``distributed.Client`` counts them),
and the in-process band of ``fbs_core.scatter_band`` for the fallback's numbers.
"""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from server_util import wait_for

import fbs_core
from app import compute
from app.runtime import offload
from fbs_core.campaign import SCHEDULER_ENV
from fbs_core.campaign.cluster import ClusterUnavailable, scatter_band_on

KEY = compute.band_key(1, None, "6dof", 10.0, "both", False, 150, 3)


@pytest.fixture(autouse=True)
def _clean(monkeypatch):
    monkeypatch.setenv(SCHEDULER_ENV, "tcp://127.0.0.1:9")
    monkeypatch.setenv(offload.MIN_ROUNDS_ENV, "100")
    offload.reset()
    yield
    offload.reset()


class _Refusing:
    """A stand-in for ``distributed.Client`` whose connection fails after ``delay_s``."""

    calls = 0
    delay_s = 0.0

    def __init__(self, *args, **kwargs):
        type(self).calls += 1
        time.sleep(self.delay_s)
        raise OSError("connection refused")


def test_an_unreachable_scheduler_is_left_alone_after_it_failed(monkeypatch):
    import distributed

    monkeypatch.setattr(distributed, "Client", _Refusing)
    _Refusing.calls = 0
    never = lambda: False  # noqa: E731
    for _ in range(5):  # five heavy bands in a row: computed here
        assert offload.band(KEY, never) is None
    assert _Refusing.calls == 1  # one attempt, then the backoff
    # after the backoff the scheduler is tried again, and the wait doubles
    until, wait = offload._backoff[offload.scheduler()]
    monkeypatch.setattr(offload.time, "monotonic", lambda: until + 0.1)
    assert offload.band(KEY, never) is None
    assert _Refusing.calls == 2 and offload._backoff[offload.scheduler()][1] == 2 * wait


def test_bands_do_not_wait_for_another_bands_connection(monkeypatch):
    import distributed

    monkeypatch.setattr(distributed, "Client", _Refusing)
    monkeypatch.setattr(_Refusing, "delay_s", 3.0)
    _Refusing.calls = 0
    t = threading.Thread(target=offload.band, args=(KEY, lambda: False))
    t.start()
    wait_for(lambda: _Refusing.calls == 1, 30, what="the first band connecting")
    t0 = time.monotonic()
    assert offload.band(KEY, lambda: False) is None  # at once, computed here
    waited = time.monotonic() - t0
    t.join(30)
    assert waited < 2.0 and _Refusing.calls == 1


@pytest.fixture(scope="module")
def empty_cluster():
    from distributed import Client, LocalCluster

    with (
        LocalCluster(n_workers=0, processes=False, dashboard_address="127.0.0.1:0") as cl,
        Client(cl, set_as_default=False) as client,
    ):
        yield client


def test_a_scheduler_without_workers_is_refused_before_any_work(empty_cluster):
    with pytest.raises(ClusterUnavailable, match="no workers"):
        scatter_band_on(empty_cluster, 1, 0.1, "both", 150, seed=3)


RELEASE = threading.Event()


def endless_block(*args, **kwargs):
    """A block that ends only when the test says (a worker in this process shares it)."""
    RELEASE.wait(600)


def test_a_cluster_that_loses_its_workers_mid_band_falls_back(monkeypatch):
    """The band's workers go away while it runs: the band is computed in the process, equal
    to fbs_core.scatter_band."""
    from distributed import Client, LocalCluster

    with LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address="127.0.0.1:0"
    ) as cl:
        monkeypatch.setenv(SCHEDULER_ENV, cl.scheduler_address)
        client = Client(cl, set_as_default=False)
        # a stand-in block that never ends, so the band is surely running when the worker
        # goes (the real block's numbers are checked by tests/test_app_offload.py)
        from fbs_core.campaign import work

        monkeypatch.setattr(work, "band_block", endless_block)
        out = {}

        def run():
            try:
                scatter_band_on(client, 1, 0.1, "both", 150, seed=3, stall_s=1.0)
                out["res"] = "finished"
            except ClusterUnavailable as e:
                out["res"] = str(e)

        t = threading.Thread(target=run)
        t.start()
        wait_for(
            lambda: client.processing() and any(client.processing().values()), 60, what="running"
        )
        for w in list(cl.workers.values()):
            client.sync(w.close)
        t.join(60)
        RELEASE.set()
        client.close()
    # ClusterUnavailable (a block lost with its worker, or no worker left), never a hang
    assert "lost its workers" in out["res"] or "failed the band" in out["res"], out


def test_the_fallback_band_is_the_in_process_band(monkeypatch):
    import distributed

    monkeypatch.setattr(distributed, "Client", _Refusing)
    from app.state import DashboardState
    from app.store import Results

    state = DashboardState()
    state.noise.param.update(rounds=150, seed=3)
    res = Results(state, background=True)
    band = res.band_now()
    want = fbs_core.scatter_band(
        1,
        noise=0.1,
        rounds=150,
        seed=3,
        n_modes=band.settings.n_modes,
        percentiles=compute.Q_LEVELS,
    )
    np.testing.assert_allclose(band.result.maximum, want.maximum, rtol=1e-12)
