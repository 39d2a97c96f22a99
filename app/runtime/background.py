"""Work the server does beside the sessions: bounded, superseded work dropped, low priority.

What nobody waits for (the coupled modes next to the phase view's peak labels, the
suggested N with residual compensation, the reference studies warmed once per process)
and what is computed ahead (the speed map of the next step of the N slider) runs on a
fixed number of threads of the process, whatever the number of sessions and of their
changes (four tabs flipping the phase view's DOF and N started one thread per
change; 437 MB more memory and another session's p95 319 -> 733 ms):

- :data:`BACKGROUND`: one thread at a lower CPU priority (:data:`~app.runtime.priority.
  BACKGROUND_NICE`), marked so that a session needing a result it is computing computes
  it itself instead of waiting at a fraction of a core (:func:`app.compute.shared_cache`);
- :data:`AHEAD`: one thread at the server's priority for work computed ahead, which a
  session asking for the same result waits for (it shares the computation).

Each task has a key (the session and the kind of work): a newer task of the same key
replaces the one still waiting (a dragged slider leaves one task, not one per step), and
a task that is a generator runs one step per turn, the tasks of all sessions in turn, so a
session's long work (eight eigenvalue solves, seven error maps) delays another session's by
at most one step. At most :data:`MAX_WAITING` tasks wait; beyond that the oldest is
dropped (its session asks again on its next change). Errors are logged, never raised.
"""

from __future__ import annotations

import gc
import logging
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterator
from typing import Any

from .. import compute
from . import collector
from .priority import BACKGROUND_NICE, lower_priority

__all__ = [
    "AHEAD",
    "BACKGROUND",
    "MAX_WAITING",
    "Worker",
    "freeze_long_lived",
    "warm_reference_studies",
]

log = logging.getLogger(__name__)

#: Tasks that may wait per worker (the oldest beyond it is dropped).
MAX_WAITING = 256


class Worker:
    """One thread of the process that runs keyed tasks in turn (see the module docstring).

    Parameters
    ----------
    name : str
        The thread's name.
    nice : int
        How much the thread lowers its CPU priority (0: the server's own).
    background : bool
        Mark the thread as background work (sessions never wait for its results).
    """

    def __init__(self, name: str, nice: int = 0, background: bool = False) -> None:
        self.name = name
        self.nice = nice
        self.background = background
        self._tasks: OrderedDict[Hashable, Callable[[], Any] | Iterator[Any]] = OrderedDict()
        self._cond = threading.Condition()
        self._thread: threading.Thread | None = None
        self._busy = False
        self.dropped = 0  # tasks dropped because the queue was full

    def submit(self, key: Hashable, work: Callable[[], Any]) -> None:
        """Run ``work()`` on the worker's thread; a task of ``key`` still waiting is
        replaced (a generator's later steps included)."""
        with self._cond:
            self._tasks.pop(key, None)
            self._tasks[key] = work
            while len(self._tasks) > MAX_WAITING:
                self._tasks.popitem(last=False)
                self.dropped += 1
            if self._thread is None or not self._thread.is_alive():
                self._thread = threading.Thread(target=self._run, name=self.name, daemon=True)
                self._thread.start()
            self._cond.notify()

    def cancel(self, owner: object) -> None:
        """Drop the waiting tasks whose key starts with ``owner`` (a closed session)."""
        with self._cond:
            for key in [k for k in self._tasks if isinstance(k, tuple) and k[:1] == (owner,)]:
                del self._tasks[key]

    @property
    def waiting(self) -> int:
        with self._cond:
            return len(self._tasks)

    def idle(self, timeout: float | None = None) -> bool:
        """Wait until no task waits or runs (tests); False on timeout."""
        with self._cond:
            return self._cond.wait_for(lambda: not self._tasks and not self._busy, timeout)

    def _run(self) -> None:
        if self.background:
            compute.mark_background()  # sessions never wait for this thread's results
        if self.nice:
            lower_priority(self.nice)
        while True:
            with self._cond:
                self._busy = False
                self._cond.notify_all()
                self._cond.wait_for(lambda: bool(self._tasks))
                key, task = self._tasks.popitem(last=False)
                self._busy = True
            try:
                if not isinstance(task, Iterator):
                    task = task()
                if isinstance(task, Iterator) and next(task, StopIteration) is not StopIteration:
                    with self._cond:  # a next step: after the other keys' tasks
                        if key not in self._tasks:  # not replaced meanwhile
                            self._tasks[key] = task
            except Exception:  # a background result is optional: log, never kill the server
                log.exception("background work %r of %s failed", key, self.name)


#: Work nobody waits for, at a lower priority.
BACKGROUND = Worker("fbs-background", nice=BACKGROUND_NICE, background=True)
#: Work computed ahead, at the server's priority (a session asking for it waits for it).
AHEAD = Worker("fbs-ahead")

_warmed = threading.Event()
_warm_lock = threading.Lock()


def warm_reference_studies(coupling: str = "6dof") -> threading.Thread | None:
    """Once per process, on a thread of its own at a lower priority: the reference error
    maps of all seven harmonics (each holds the coupled responses of every N of the
    selector), so that the first change to another harmonic finds them computed; then the
    long-lived objects are frozen (:func:`freeze_long_lived`). Each map, and the freeze,
    waits for a quiet moment (:func:`app.runtime.collector.wait_quiet`): started by the
    first page, the warm-up ran beside that page and the next ones opened.
    Returns the thread, or None if the warm-up was already started."""
    with _warm_lock:
        if _warmed.is_set():
            return None
        _warmed.set()

    def work() -> None:
        compute.mark_background()
        lower_priority(BACKGROUND_NICE)
        try:
            for h in range(1, 8):
                collector.wait_quiet()
                compute.error_map(h, coupling)
            # a full collection holds the interpreter (0.24 s seen while a page opened)
            collector.wait_quiet()
            freeze_long_lived()
        except Exception:  # optional: log, never kill the server
            log.exception("warming the reference studies failed")

    t = threading.Thread(target=work, name="fbs-warm-reference", daemon=True)
    t.start()
    return t


def freeze_long_lived() -> int:
    """Leave what the process holds now out of the garbage collector's full collections;
    the number of objects frozen.

    A full collection walks every tracked object with all threads stopped: the imported
    libraries, compiled kernels, reference models and shared result caches of a warm
    server are some 400,000 objects, about 0.3 s of every full collection (more on a busy
    machine), and full collections come with sessions opening and closing. After the
    warm-up these objects live as long as the process, so they are collected first and
    then frozen (``gc.freeze``); objects made later, sessions' among them, are collected
    as before. What the first page holds at that moment is frozen with them (one page's
    objects, once per process)."""
    gc.collect()
    gc.freeze()
    return gc.get_freeze_count()
