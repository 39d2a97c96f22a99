"""Heavy scatter bands on a Dask cluster, when one is configured.

With ``FBS_DASK_SCHEDULER=tcp://host:8786`` in the server's environment, a band of at
least :func:`min_rounds` rounds (100,000 by default, ``FBS_OFFLOAD_MIN_ROUNDS`` to change
it) is computed by the cluster's workers instead of this process
(:func:`fbs_core.campaign.cluster.scatter_band_on`: the blocks of lines of a campaign), so
one user's large study leaves the server's cores to the other sessions. The page shows
the frequency lines of the finished blocks (from the futures) and the time left, as for a
band computed here; a newer request of the session or a closed page cancels
the futures (the session's :class:`~app.runtime.bands.Job` is asked every 0.1 s). The band is the
in-process one to the last bit (the subsystem arrays are computed here and shipped).

Without the variable nothing changes. Whenever the cluster cannot compute a band it is
computed here, as without the variable: the scheduler cannot be reached (the
connection is tried for :data:`CONNECT_TIMEOUT_S` by one band at a time, the others do
not wait for it; after a failure the scheduler is left alone for :data:`BACKOFF_S`
seconds, doubling up to :data:`MAX_BACKOFF_S`), it has no workers, or it or its workers
go away while the band runs (:class:`fbs_core.campaign.cluster.ClusterUnavailable`).

Results come back from the workers by unpickling: whoever can talk to the scheduler's
port can run code in this server. The scheduler is therefore joined as
:mod:`fbs_core.campaign.security` allows: ``tls://`` with the certificates of
``$FBS_DASK_TLS_DIR`` (mutual authentication), plain ``tcp://`` on the loopback interface
only, unless ``FBS_DASK_ALLOW_PLAIN=1`` says the network is private by other means. A
refused address is logged and backed off like an unreachable one: bands are computed here.
"""

from __future__ import annotations

import logging
import os
import threading
import time

from fbs_core.campaign import SCHEDULER_ENV
from fbs_core.campaign.cluster import ClusterUnavailable, scatter_band_on
from fbs_core.campaign.security import InsecureScheduler, connect

from .. import compute

__all__ = ["MIN_ROUNDS_ENV", "scheduler", "min_rounds", "wanted", "band", "client", "reset"]

MIN_ROUNDS_ENV = "FBS_OFFLOAD_MIN_ROUNDS"
DEFAULT_MIN_ROUNDS = 100_000

#: Seconds one connection attempt to the scheduler may take.
CONNECT_TIMEOUT_S = 3.0
#: Seconds the scheduler is left alone after it failed (doubling up to MAX_BACKOFF_S).
BACKOFF_S = 5.0
MAX_BACKOFF_S = 300.0

log = logging.getLogger(__name__)
_lock = threading.Lock()
_client = None
_client_addr = ""
#: (address, monotonic time before which it is not tried again, current backoff)
_backoff: dict[str, tuple[float, float]] = {}


class Unavailable(Exception):  # noqa: N818  (a state, not an error of the input)
    """The cluster is not to be used now (backing off, or another band is connecting)."""


def failed(addr: str, why: object) -> None:
    """The scheduler at ``addr`` failed: leave it alone for a while (doubling)."""
    _until, wait = _backoff.get(addr, (0.0, BACKOFF_S / 2))
    wait = min(MAX_BACKOFF_S, wait * 2)
    _backoff[addr] = (time.monotonic() + wait, wait)
    log.warning("Dask scheduler %s: %s; bands are computed here for %.0f s", addr, why, wait)


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
    """Whether the band of ``key`` (:func:`app.compute.band_key`) goes to the cluster.

    A car's band (vehicle scope: a key with its road and point) is computed in-process:
    the cluster's workers run the corner's band function; vehicle scope starts at fewer
    rounds instead (``app.state.VEHICLE_ROUNDS``)."""
    return bool(scheduler()) and not key.is_car and key.rounds >= min_rounds()


def client():
    """The server's one client of the configured scheduler (connected on first use).

    Raises
    ------
    Unavailable
        While the scheduler is backed off after a failure, or another band is connecting,
        or when its address is refused (plain TCP off the loopback, TLS without
        certificates: :func:`fbs_core.campaign.security.security_for`).
    OSError, TimeoutError
        When the connection fails (the scheduler is then backed off).
    """
    global _client, _client_addr
    addr = scheduler()
    if not _lock.acquire(blocking=False):  # another band is connecting: do not wait for it
        raise Unavailable(f"connecting to {addr}")
    try:
        until, _ = _backoff.get(addr, (0.0, 0.0))
        if time.monotonic() < until:
            raise Unavailable(f"{addr} failed recently")
        if _client is not None and _client_addr == addr and _client.status == "running":
            return _client
        if _client is not None:
            _close(_client)
            _client = None
        try:
            _client = connect(addr, f"{CONNECT_TIMEOUT_S}s", set_as_default=False)
        except InsecureScheduler as exc:  # refused before any connection is tried
            failed(addr, f"refused: {exc}")
            raise Unavailable(str(exc)) from None
        except (OSError, TimeoutError) as exc:
            failed(addr, f"unreachable ({exc})")
            raise
        _client_addr = addr
        _backoff.pop(addr, None)
        return _client
    finally:
        _lock.release()


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
        _backoff.clear()


def band(key: tuple, cancel, progress=None):
    """The band of ``key`` computed on the cluster and cached as the in-process one is.

    Returns None (compute it here instead) when the cluster cannot compute it (see the
    module); raises :class:`fbs_core.StudyCancelled` when ``cancel()`` turned True
    meanwhile.
    """
    addr = scheduler()
    t0 = time.perf_counter()
    try:
        c = client()
    except Unavailable as exc:
        log.info("Dask scheduler not used (%s): band computed here", exc)
        return None
    except (OSError, TimeoutError):
        return None  # backed off and logged by client()
    try:
        res = _on(c, key, cancel, progress)
    except ClusterUnavailable as exc:
        failed(addr, exc)
        return None
    compute.remember_band(key, res, time.perf_counter() - t0)
    return res


def _on(c, key: tuple, cancel, progress):
    harmonic, n_modes, coupling, noise_pct, target, fdep, rounds, seed, models, _ = key
    return scatter_band_on(
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
        **compute.models_kw(models),
    )
