"""Scatter bands of all sessions: cancelled when superseded, computed in turns.

A band is the one computation of the dashboard that takes seconds (up to minutes for
200,000 rounds). A band that several sessions ask for at once is computed once for all of
them (:class:`SharedRun`). Four rules keep one session from starving the others:

- **one live band per session**: a new request of a session cancels its running band
  (:class:`Job`); the kernel stops at its next chunk of lines
  (``fbs_core.scatter_band(cancel=...)``), so a dragged slider leaves no queue behind;
- **turns**: the kernel asks before every chunk of lines (about 0.1 s of work), and a
  band's setup (the subsystem arrays: a tire synthesis for a new N or harmonic) runs in
  the turn of its first chunk; all running bands queue for the next chunk in arrival order
  (:class:`Turnstile`), so two sessions' bands advance chunk by chunk, alternately, and a
  short band waits for at most one chunk of a long one per turn;
- **no pool to fill**: each live band has its own thread (a session has at most one live
  band, a cancelled one ends at its next turn), so no session can occupy the workers
  others need;
- **interactive work first**: a band's thread lowers its own CPU priority (its nice value
  by :data:`BAND_NICE`, or ``FBS_BAND_NICE``; Linux, per thread; numba's worker threads,
  which the band's thread starts, inherit it), so the threads that answer control changes
  (Panel's workers, the event loop that sends the plots) get the cores whenever they need
  them, and a band takes what is left. Not before the kernels are compiled
  (:data:`KERNELS_WARM`): the first band of a process compiles them (tens of seconds of
  CPU without numba's cache), and at a low priority on a machine that other processes keep
  busy that took minutes, with every page waiting for its first band.

The numba kernels run one chunk at a time process-wide anyway (``fbs_core`` holds a lock
around the parallel kernel), so the turns cost no parallelism. A chunk lasts about 0.1 s
(``fbs_core.scatter_band(max_chunk_seconds=...)``: the lines of a chunk are sized by the
measured time per line), whatever the round count, so a turn is never long; the single
rounds a page draws and the band's reference run on the calling thread without that lock.
"""

from __future__ import annotations

import os
import threading
import time
from collections import deque
from collections.abc import Callable

import panel as pn

from fbs_core.errors import FBSError, StudyCancelled
from fbs_core.studies.scatter import EDGES_JUDGED_WITHIN_DB

from .. import compute
from ..results import vehicle_compute
from . import offload
from .draw import served
from .priority import BACKGROUND_NICE
from .priority import lower_priority as _lower

__all__ = [
    "BAND_NICE",
    "Job",
    "KERNELS_WARM",
    "SharedRun",
    "Turnstile",
    "TURNSTILE",
    "band_nice",
    "done_text",
    "lower_priority",
    "run",
    "served",
    "start",
]

#: How much a band's thread raises its nice value (lowers its CPU priority), unless
#: ``FBS_BAND_NICE`` says otherwise (0: bands run at the server's priority).
BAND_NICE = BACKGROUND_NICE
BAND_NICE_ENV = "FBS_BAND_NICE"


def band_nice() -> int:
    """:data:`BAND_NICE` or ``$FBS_BAND_NICE`` (an integer 0-19; anything else: the default)."""
    raw = os.environ.get(BAND_NICE_ENV, "").strip()
    if raw.isdigit() and int(raw) <= 19:
        return int(raw)
    return BAND_NICE


def lower_priority(by: int | None = None) -> int | None:
    """Raise the calling thread's nice value by ``by`` (default :func:`band_nice`), see
    :func:`app.runtime.priority.lower_priority`; its new value (None: unchanged)."""
    return _lower(band_nice() if by is None else by)


class Job:
    """One requested band: its cache key, a cancel flag the kernel checks, and its progress
    (lines done of the total, reported by the kernel after each chunk)."""

    def __init__(self, key: tuple, owner=None, on_progress=None) -> None:
        self.key = key
        self.owner = owner
        self._cancelled = threading.Event()
        self.started = time.perf_counter()
        self.done = 0
        self.total = 0
        #: ``on_progress(job)`` after each chunk (from the band's thread)
        self.on_progress = on_progress

    def report(self, done: int, total: int) -> None:
        """The kernel's progress callback: ``done`` of ``total`` lines."""
        self.done, self.total = int(done), int(total)
        if self.on_progress is not None and not self.cancelled:
            self.on_progress(self)

    @property
    def fraction(self) -> float:
        return self.done / self.total if self.total else 0.0

    def seconds_left(self) -> float | None:
        """Time left at the rate so far (None before the first chunk is done)."""
        if not self.done or not self.total:
            return None
        spent = time.perf_counter() - self.started
        return spent * (self.total - self.done) / self.done

    def cancel(self) -> None:
        self._cancelled.set()

    @property
    def cancelled(self) -> bool:
        return self._cancelled.is_set()


class Turnstile:
    """First come, first served turns for the chunks of all running bands."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._queue: deque[Job] = deque()
        self._holder: Job | None = None

    def next_turn(self, job: Job) -> bool:
        """Give up ``job``'s turn, queue for the next one and wait for it.

        Returns False (without a turn) when the job was cancelled meanwhile.
        """
        with self._cond:
            if self._holder is job:
                self._holder = None
            self._queue.append(job)
            self._cond.notify_all()
            while not (self._holder is None and self._queue[0] is job):
                if job.cancelled:
                    self._queue.remove(job)
                    self._cond.notify_all()
                    return False
                self._cond.wait(0.05)
            self._queue.popleft()
            self._holder = job
            return not job.cancelled

    def leave(self, job: Job) -> None:
        """``job`` is done: free its turn and its place in the queue."""
        with self._cond:
            if self._holder is job:
                self._holder = None
            if job in self._queue:
                self._queue.remove(job)
            self._cond.notify_all()

    @property
    def holder(self) -> Job | None:
        """The job whose turn it is (None between turns)."""
        with self._cond:
            return self._holder

    @property
    def waiting(self) -> int:
        with self._cond:
            return len(self._queue)


#: The process-wide turns of the band kernels.
TURNSTILE = Turnstile()

Done = Callable[[Job, object, object, float, object], None]


class SharedRun:
    """One band computation shared by every session that asks for the same band.

    Sessions of a review meeting often ask for the same band at once (the same link, the
    same harmonic): the first request computes it, later ones join and get its result.
    The run stops at its next chunk only when every joined job has been cancelled. It
    stands for its jobs in the :class:`Turnstile` (``key``, ``owner``, ``cancelled``).
    """

    def __init__(self, first: Job) -> None:
        self.key = first.key
        self.owner = first.owner
        self._jobs = [first]
        self._lock = threading.Lock()
        self.finished = threading.Event()
        self.result: object = None
        self.error: BaseException | None = None

    def add(self, job: Job) -> None:
        with self._lock:
            self._jobs.append(job)

    @property
    def jobs(self) -> list[Job]:
        with self._lock:
            return list(self._jobs)

    @property
    def cancelled(self) -> bool:
        """True once every job of the run has been cancelled."""
        return all(j.cancelled for j in self.jobs)

    def report(self, done: int, total: int) -> None:
        """The kernel's progress: passed on to every job still wanting the band."""
        for j in self.jobs:
            j.report(done, total)


#: Set once a band of this process has finished a chunk: the kernels are compiled, and
#: band threads may lower their priority from then on.
KERNELS_WARM = threading.Event()

_RUNS: dict[tuple, SharedRun] = {}
_RUNS_LOCK = threading.Lock()


def _join(job: Job) -> tuple[SharedRun, bool]:
    """The running computation of ``job``'s band, joined (or a new one): (run, computes)."""
    with _RUNS_LOCK:
        shared = _RUNS.get(job.key)
        if shared is None:
            shared = _RUNS[job.key] = SharedRun(job)
            return shared, True
        shared.add(job)
        return shared, False


def _compute(shared: SharedRun, turns: Turnstile) -> None:
    """Compute ``shared``'s band in this thread, chunk by chunk in turns."""
    try:
        res = None
        if offload.wanted(shared.key):  # heavy: on the Dask cluster
            res = offload.band(shared.key, lambda: shared.cancelled, shared.report)
        if res is None:
            # the band's setup (the tire synthesis of a new N or harmonic) is work like a
            # chunk: done in a turn of its own, so it does not share the cores with another
            # session's chunk; its first chunk follows in the same turn
            if not turns.next_turn(shared):
                raise StudyCancelled("every session cancelled the band")
            first = [True]

            def cancel() -> bool:
                if first:
                    first.clear()
                    return shared.cancelled
                return not turns.next_turn(shared)

            def progress(done: int, total: int) -> None:
                KERNELS_WARM.set()  # a chunk ran here: the kernels are compiled
                shared.report(done, total)

            if compute.is_car_key(shared.key):
                res = vehicle_compute.cached_band(shared.key, cancel=cancel, progress=progress)
            else:
                res = compute.band(*shared.key, cancel=cancel, progress=progress)
        shared.result = res
    except StudyCancelled:
        pass
    except Exception as exc:  # handed to every job's ``done``
        shared.error = exc
    finally:
        turns.leave(shared)
        with _RUNS_LOCK:
            if _RUNS.get(shared.key) is shared:
                del _RUNS[shared.key]
        shared.finished.set()


def run(job: Job, done: Done, context=None, turnstile: Turnstile | None = None) -> None:
    """Compute ``job``'s band here and call ``done(job, context, band, seconds, error)``.

    A band another session is computing already is not computed twice: the job joins that
    run (:class:`SharedRun`) and waits for its result. ``band`` is None when the job was
    cancelled (then ``done`` is not called) or failed (``error`` holds the core's message).
    """
    t0 = time.perf_counter()
    if job.cancelled:
        return
    turns = TURNSTILE if turnstile is None else turnstile
    res = compute.cached_band(job.key)
    while res is None:
        shared, computes = _join(job)
        if computes:
            _compute(shared, turns)
        else:
            while not shared.finished.wait(0.05):
                if job.cancelled:
                    return
        if job.cancelled:
            return
        error = shared.error
        if error is not None:
            # the page shows the message instead of a silent spinner
            done(job, context, None, time.perf_counter() - t0, error)
            if computes and not isinstance(error, FBSError):
                raise error
            return
        # None: the run stopped because everyone else cancelled it just before this job
        # joined; compute afresh
        res = shared.result
    done(job, context, res, time.perf_counter() - t0, None)


def start(
    job: Job, done: Done, context=None, turnstile: Turnstile | None = None
) -> threading.Thread:
    """:func:`run` on a thread of its own (daemon: it never holds up a shutdown).

    The thread works for the calling thread's session: Panel's current document is set in
    it, so what ``done`` publishes is drawn through that session's event loop. It runs at a
    lower CPU priority (:func:`lower_priority`) once the kernels are compiled
    (:data:`KERNELS_WARM`).
    """
    doc = pn.state.curdoc

    def work():
        pn.state.curdoc = doc
        if KERNELS_WARM.is_set():
            lower_priority()
        run(job, done, context, turnstile)

    t = threading.Thread(target=work, name="scatter-band", daemon=True)
    t.start()
    return t


def done_text(result, seconds: float, key: tuple, now: float | None = None) -> str:
    """The status line of a finished band ``result`` of settings ``key``, ``seconds``
    after it was asked for: its rounds, how long it took (or that it was computed before,
    and how long it took then), and how well the rounds fix its central 5-95 % band
    (:meth:`fbs_core.ScatterBand.percentile_confidence_db`: to halve it, four times the
    rounds)."""
    rec = compute.band_computed(key)
    now = time.monotonic() if now is None else now
    if rec is not None and rec.ready < now - seconds - 0.05:  # ready before it was asked
        took = "" if rec.seconds is None else f", in {rec.seconds:.2f} s"
        when = f"computed before{took}"
    else:
        when = f"in {seconds:.2f} s"
    conf = result.percentile_confidence_db()
    edges = (
        f"5-95 % band edges within ±{conf:.2f} dB (95 % confidence, lines within "
        f"{EDGES_JUDGED_WITHIN_DB:g} dB of the peak; four times the rounds halve it)"
        if conf == conf
        else "no line within the peak's range to judge the band by"
    )
    return f"{result.rounds:,} rounds {when} &middot; {edges}"
