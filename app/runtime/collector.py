"""Full garbage collections when the server is quiet, not in the middle of a change.

CPython's full collection walks every tracked object with all threads stopped, and the
open sessions are most of them: with 50 sessions open one took 0.6-1.2 s, and the
collections that the pages' openings had made due ran during the next changes (the server's
log of the collections beside ``bench/load_test.py --sessions 50``: 1148 ms 1.4 s after the
sessions started changing, 565 ms four seconds later: those rounds' first updates took
1.2-1.5 s). The long-lived objects of the warm-up are frozen once
(:func:`app.runtime.background.freeze_long_lived`); this collector does the same for the
open sessions, at a quiet moment:

- every draw asked for marks activity (:func:`touch`); once nothing was asked for during
  :data:`QUIET` seconds after some activity, and the process used less than
  :data:`BUSY_SHARE` of a core meanwhile (a page being built or a band computed draws
  nothing for a while), the collector collects the young generations and freezes what is
  alive (``gc.freeze``), so the collections that come with the next changes walk only what
  was made since (a full collection there walked the 50 pages just opened: 1.4 s, at the
  quiet moment when 50 sessions started changing: ``bench/load_test.py --sessions 50``);
- a session that ended is frozen with the rest: once the sessions ended since the last
  thaw are :data:`THAW_SHARE` of the open ones, the next quiet collection thaws everything
  (``gc.unfreeze``) first and then frees their cycles (a thawed collection walks every
  object: with 50 pages open it took 2.2 s, and one warm-up session ending made it due
  just when 50 sessions started changing: ``bench/load_test.py --sessions 50``); and at
  least every :data:`THAW_EVERY` seconds a quiet collection thaws first, so that cycles
  dropped by the open sessions, or left by ended ones, are not kept for longer than that.

The decision is :meth:`IdleCollector.step`, a pure function of the clock and what happened
(tested without threads); :func:`start` runs it on a daemon thread.
"""

from __future__ import annotations

import gc
import logging
import threading
import time
from collections import deque
from collections.abc import Callable

__all__ = [
    "BUSY_SHARE",
    "QUIET",
    "THAW_EVERY",
    "IdleCollector",
    "THAW_SHARE",
    "count_alive",
    "session_ended",
    "session_started",
    "start",
    "touch",
    "wait_quiet",
]

log = logging.getLogger(__name__)

#: Seconds without a draw after which the server counts as quiet.
QUIET = 0.5
#: Longest time (s) between two thawed collections while there is activity.
THAW_EVERY = 120.0
#: Ended sessions, as a share of the open ones, whose objects are worth a thawed collection
#: (it walks every object: 2.2 s with 50 pages open; one ended session among 50 open pages
#: waits for more, or for THAW_EVERY).
THAW_SHARE = 0.25
#: Share of a core the process may use during the quiet seconds (its CPU time, all threads).
BUSY_SHARE = 0.2
#: How often the collector's thread looks (s).
PERIOD = 0.1


def _collect_young() -> int:
    """Collect the two young generations (not the oldest, which holds the open pages)."""
    return gc.collect(1)


class IdleCollector:
    """When to collect and freeze, and when to thaw first (see the module docstring)."""

    def __init__(
        self,
        collect: Callable[[], object] = gc.collect,
        collect_young: Callable[[], object] = _collect_young,
        freeze: Callable[[], None] = gc.freeze,
        unfreeze: Callable[[], None] = gc.unfreeze,
        clock: Callable[[], float] = time.monotonic,
        cpu: Callable[[], float] | None = None,
    ) -> None:
        self._collect, self._freeze, self._unfreeze, self._clock = (
            collect,
            freeze,
            unfreeze,
            clock,
        )
        self._collect_young = collect_young
        self._cpu = cpu  # the process's CPU seconds (None: not looked at)
        self._samples: deque[tuple[float, float]] = deque()
        self._lock = threading.Lock()
        self._last_activity: float | None = None  # None: nothing since the last collection
        self._last_touch = -float("inf")  # the last activity of all (never reset)
        self._open = 0  # sessions started and not ended
        self._ended = 0  # sessions ended since the last thaw
        self._thawed_at = clock()
        self.collections = 0
        #: Counts of objects logged after each thawed collection, by name (:func:`count_alive`).
        self.alive: dict[str, Callable[[], int]] = {}

    def touch(self) -> None:
        """Something happened (a draw was asked for)."""
        now = self._clock()
        with self._lock:
            self._last_activity = self._last_touch = now

    def quiet(self) -> bool:
        """Whether nothing happened (no draw asked for, no session started or ended) during
        the last :data:`QUIET` seconds."""
        now = self._clock()
        with self._lock:
            return now - self._last_touch >= QUIET

    def session_started(self) -> None:
        """A session started (its page counts as open until :meth:`session_ended`)."""
        now = self._clock()
        with self._lock:
            self._open += 1
            self._last_touch = now

    def session_ended(self) -> None:
        """A session ended: its objects are to be freed by a thawed quiet collection, once
        the ended sessions are :data:`THAW_SHARE` of the open ones (or :data:`THAW_EVERY`
        seconds after the last thaw)."""
        now = self._clock()
        with self._lock:
            self._open = max(0, self._open - 1)
            self._ended += 1
            self._last_activity = self._last_touch = now

    def step(self) -> bool:
        """Collect (thawing first when due) if the server is quiet after activity; True if
        it did."""
        now = self._clock()
        if not self._cpu_quiet(now):
            return False
        with self._lock:
            if self._last_activity is None or now - self._last_activity < QUIET:
                return False
            thaw = (
                self._ended >= THAW_SHARE * max(self._open, 1)
                or now - self._thawed_at >= THAW_EVERY
            )
            self._last_activity = None
            if thaw:
                self._ended = 0
        t0 = time.perf_counter()
        if thaw:  # a full collection: it frees what ended sessions and dropped results left
            self._unfreeze()
            self._thawed_at = now
            self._collect()
        else:  # the young generations only: the rest is frozen without a walk
            self._collect_young()
        self._freeze()
        self.collections += 1
        ms = 1000 * (time.perf_counter() - t0)
        if thaw and self.alive:  # what outlived the ended sessions (bench/load_test.py)
            counts = ", ".join(f"{name} {count()}" for name, count in self.alive.items())
            log.info("quiet full collection (thawed): %.0f ms; alive: %s", ms, counts)
        else:
            log.debug("quiet %s collection: %.0f ms", "full (thawed)" if thaw else "young", ms)
        return True

    def _cpu_quiet(self, now: float) -> bool:
        """Whether the process used less than :data:`BUSY_SHARE` of a core over the last
        :data:`QUIET` seconds (True when CPU time is not looked at)."""
        if self._cpu is None:
            return True
        cpu = self._cpu()
        self._samples.append((now, cpu))
        while len(self._samples) > 1 and self._samples[1][0] <= now - QUIET:
            self._samples.popleft()  # keep one sample at or before the window's start
        t0, c0 = self._samples[0]
        if now - t0 < QUIET:
            return False  # not looked at long enough yet
        return (cpu - c0) / (now - t0) < BUSY_SHARE


COLLECTOR = IdleCollector(cpu=time.process_time)
_started = threading.Event()


def touch() -> None:
    """Mark activity (cheap: called for every draw)."""
    COLLECTOR.touch()


def session_started() -> None:
    """A session started (see :meth:`IdleCollector.session_started`)."""
    COLLECTOR.session_started()


def session_ended() -> None:
    """A session ended (see :meth:`IdleCollector.session_ended`)."""
    COLLECTOR.session_ended()


def wait_quiet(
    collector: IdleCollector | None = None, sleep: Callable[[float], None] = time.sleep
) -> None:
    """Return once the server is quiet (:meth:`IdleCollector.quiet`; polled every
    :data:`PERIOD` s): work computed ahead, which nobody waits for, starts its next step
    then rather than beside a page being opened or changed."""
    c = COLLECTOR if collector is None else collector
    while not c.quiet():
        sleep(PERIOD)


def count_alive(name: str, count: Callable[[], int]) -> None:
    """Log ``count()`` as ``name`` after every thawed quiet collection: what outlives the
    ended sessions (e.g. the open pages; ``bench/load_test.py`` reads it once every session
    of a level has closed)."""
    COLLECTOR.alive[name] = count


def start() -> threading.Thread | None:
    """Run the collector on a daemon thread, once per process (None if already running)."""
    if _started.is_set():
        return None
    _started.set()

    def loop() -> None:
        while True:
            time.sleep(PERIOD)
            try:
                COLLECTOR.step()
            except Exception:  # never kill the server for a collection
                log.exception("quiet collection failed")

    t = threading.Thread(target=loop, name="fbs-collector", daemon=True)
    t.start()
    return t
