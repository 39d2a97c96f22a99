"""Heavy scatter bands on a Dask cluster, when one is configured.

With ``FBS_DASK_SCHEDULER=tcp://host:8786`` in the server's environment, a band of at
least :func:`min_rounds` rounds (100,000 by default, ``FBS_OFFLOAD_MIN_ROUNDS`` to change
it) is computed by the cluster's workers instead of this process
(:func:`fbs_core.campaign.cluster.scatter_band_on`: the blocks of lines of a campaign), so
one user's large study leaves the server's cores to the other sessions. The page shows
the frequency lines of the finished blocks (from the futures) and the time left, as for a
band computed here; a newer request of the session or a closed page cancels
the futures (the session's :class:`~app.bands.Job` is asked every 0.1 s). The band is the
in-process one to the last bit (the subsystem arrays are computed here and shipped).

Without the variable nothing changes. When the scheduler cannot be reached, the band is
computed here as before (and the next heavy band tries the scheduler again).
"""

from __future__ import annotations

import logging
import os
import threading

from fbs_core.campaign import SCHEDULER_ENV
from fbs_core.campaign.cluster import scatter_band_on

from . import compute

__all__ = ["MIN_ROUNDS_ENV", "scheduler", "min_rounds", "wanted", "band", "client", "reset"]

MIN_ROUNDS_ENV = "FBS_OFFLOAD_MIN_ROUNDS"
DEFAULT_MIN_ROUNDS = 100_000

log = logging.getLogger(__name__)
_lock = threading.Lock()
_client = None
_client_addr = ""


def scheduler() -> str:
    """The configured scheduler address (``$FBS_DASK_SCHEDULER``), "" when none."""
    return os.environ.get(SCHEDULER_ENV, "").strip()


def min_rounds() -> int:
    """Bands of at least this many rounds go to the cluster."""
    raw = os.environ.get(MIN_ROUNDS_ENV, "").strip()
    try:
        return max(1, int(raw)) if raw else DEFAULT_MIN_ROUNDS
    except ValueError:
        log.warning("%s=%r is not an integer: using %d", MIN_ROUNDS_ENV, raw, DEFAULT_MIN_ROUNDS)
        return DEFAULT_MIN_ROUNDS


def wanted(key: tuple) -> bool:
    """Whether the band of ``key`` (:func:`app.compute.band_key`) goes to the cluster."""
    return bool(scheduler()) and int(key[6]) >= min_rounds()


def client():
    """The server's one client of the configured scheduler (connected on first use)."""
    global _client, _client_addr
    from distributed import Client

    addr = scheduler()
    with _lock:
        if _client is not None and _client_addr == addr and _client.status == "running":
            return _client
        if _client is not None:
            _close(_client)
        _client = Client(addr, timeout="10s", set_as_default=False)
        _client_addr = addr
        return _client


def _close(c) -> None:
    try:
        c.close(timeout=2)
    except Exception:  # already gone
        pass


def reset() -> None:
    """Close the server's client (tests; the next heavy band connects again)."""
    global _client
    with _lock:
        if _client is not None:
            _close(_client)
        _client = None


def band(key: tuple, cancel, progress=None):
    """The band of ``key`` computed on the cluster and cached as the in-process one is.

    Returns None (compute it here instead) when the scheduler cannot be reached; raises
    :class:`fbs_core.StudyCancelled` when ``cancel()`` turned True meanwhile.
    """
    harmonic, n_modes, coupling, noise_pct, target, fdep, rounds, seed, models = key
    try:
        c = client()
    except (OSError, TimeoutError) as exc:
        log.warning("Dask scheduler %s unreachable (%s): band computed here", scheduler(), exc)
        return None
    res = scatter_band_on(
        c,
        harmonic,
        noise_pct / 100.0,
        target,
        rounds,
        fdep,
        seed,
        n_modes=n_modes,
        coupling=coupling,
        percentiles=compute.Q_LEVELS,
        progress=progress,
        cancel=cancel,
        **compute._models_kw(models),
    )
    compute.remember_band(key, res)
    return res
