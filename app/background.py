"""Work the server does beside the sessions, at a lower CPU priority.

Interactive work (a control change and its plots) must win the two cores over work
nobody waits for: the modes next to the peak labels, the warm-up of the reference
studies. :func:`start` runs such work on a daemon thread whose CPU priority is lowered
(Linux: ``setpriority`` on a thread id applies to that thread only, see ``man 2
setpriority``); elsewhere the thread runs at the normal priority.
"""

from __future__ import annotations

import gc
import logging
import os
import threading
from collections.abc import Callable

from . import compute

__all__ = [
    "BACKGROUND_NICE",
    "freeze_long_lived",
    "lower_priority",
    "start",
    "warm_reference_studies",
]

log = logging.getLogger(__name__)

#: Nice value of background threads (0 normal .. 19 lowest).
BACKGROUND_NICE = 10


def lower_priority(nice: int = BACKGROUND_NICE) -> bool:
    """Lower the CPU priority of the calling thread to ``nice`` (a thread already lower
    stays so); False where the OS does not allow it (not Linux, or not permitted)."""
    try:
        tid = threading.get_native_id()
        if os.getpriority(os.PRIO_PROCESS, tid) < nice:  # never raises a priority
            os.setpriority(os.PRIO_PROCESS, tid, nice)
    except (AttributeError, OSError):
        return False
    return True


def start(work: Callable[[], object], name: str) -> threading.Thread:
    """Run ``work()`` on a daemon thread at :data:`BACKGROUND_NICE` (errors are logged)."""

    def run() -> None:
        compute.mark_background()  # sessions never wait for this thread's results
        lower_priority()
        try:
            work()
        except Exception:  # a background result is optional: log, never kill the server
            log.exception("background work %s failed", name)

    t = threading.Thread(target=run, name=name, daemon=True)
    t.start()
    return t


_warmed = threading.Event()
_warm_lock = threading.Lock()


def warm_reference_studies(coupling: str = "6dof") -> threading.Thread | None:
    """Once per process, in the background: the reference error maps of all seven
    harmonics (each holds the coupled responses of every N of the selector), so that the
    first change to another harmonic finds them computed. Returns the thread, or None if
    the warm-up was already started."""
    with _warm_lock:
        if _warmed.is_set():
            return None
        _warmed.set()

    def work() -> None:
        for h in range(1, 8):
            compute.error_map(h, coupling)
        freeze_long_lived()

    return start(work, "fbs-warm-reference")


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
