"""CPU priority of the server's own threads (Linux, per thread).

Interactive work (a control change and its plots, on Panel's worker threads and the
event loop) must win the two cores over work nobody waits for. ``setpriority`` with a
thread id acts on that thread alone (``man 2 setpriority``), and threads it starts later
(numba's workers of a band) inherit it; elsewhere, or when refused, nothing changes.
"""

from __future__ import annotations

import os
import sys
import threading

__all__ = ["BACKGROUND_NICE", "lower_priority", "nice"]

#: How much background threads (and, by default, band threads) raise their nice value.
BACKGROUND_NICE = 10


def nice() -> int | None:
    """The calling thread's nice value (None where threads have none of their own)."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        return os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    except OSError:
        return None


def lower_priority(by: int = BACKGROUND_NICE) -> int | None:
    """Raise the calling thread's nice value by ``by`` (at most to 19); its new value.

    Relative, so a server started with ``nice`` keeps the difference. Linux only (the id
    of ``setpriority`` names the thread there; elsewhere it would name the process): None
    elsewhere or when refused (e.g. a sandbox without the right to renice).
    """
    now = nice()
    if now is None:
        return None
    tid = threading.get_native_id()
    try:
        os.setpriority(os.PRIO_PROCESS, tid, min(19, now + by))
        return os.getpriority(os.PRIO_PROCESS, tid)
    except OSError:
        return None
