"""What a session is busy with, for the page's busy indicator.

A pass of the store can compute for many seconds (the first switch to the whole car: the
car's transfer per wheel, 20-50 s), and so can a report (30 s); the page said nothing
meanwhile. Work that may take long is an *activity* of its session (an owner with a
``working`` text parameter, :class:`app.store.Results`): :meth:`Activities.begin` when it
starts, :meth:`Activities.update` as it moves to another part, :meth:`Activities.end`.
One thread of the process (``fbs-activity``, only while an activity runs) writes the
owner's ``working`` once an activity has lasted :data:`SHOW_AFTER_S` (what is being done
and for how long, refreshed every second) and clears it when the last one ends; short work
never shows it (a slider step's pass is 0.1 s).
"""

from __future__ import annotations

import itertools
import logging
import threading
import time
from typing import Any

__all__ = ["ACTIVITIES", "Activities", "SHOW_AFTER_S"]

log = logging.getLogger(__name__)

#: An activity shorter than this is never shown (s).
SHOW_AFTER_S = 0.6


class Activities:
    """The activities of all sessions (see the module)."""

    def __init__(self, show_after_s: float = SHOW_AFTER_S, tick_s: float = 0.25) -> None:
        self.show_after_s = show_after_s
        self.tick_s = tick_s
        self._lock = threading.Lock()
        self._running: dict[int, tuple[Any, str, float]] = {}  # token -> owner, text, start
        self._shown: dict[int, Any] = {}  # id(owner) -> owner whose text is shown
        self._ids = itertools.count(1)
        self._thread: threading.Thread | None = None

    def begin(self, owner: Any, text: str) -> int:
        """An activity of ``owner`` starts; its token."""
        with self._lock:
            token = next(self._ids)
            self._running[token] = (owner, text, time.monotonic())
            if self._thread is None or not self._thread.is_alive():
                self._thread = threading.Thread(
                    target=self._watch, name="fbs-activity", daemon=True
                )
                self._thread.start()
            return token

    def update(self, token: int, text: str) -> None:
        """The activity moved on to ``text``."""
        with self._lock:
            if token in self._running:
                owner, _, t0 = self._running[token]
                self._running[token] = (owner, text, t0)

    def end(self, token: int) -> None:
        """The activity ended; its owner's text is cleared now if nothing else runs."""
        with self._lock:
            found = self._running.pop(token, None)
            if found is None:
                return
            owner = found[0]
            if any(o is owner for o, _, _ in self._running.values()):
                return
            shown = self._shown.pop(id(owner), None) is not None
        if shown:
            self._write(owner, "")

    def _watch(self) -> None:
        while True:
            time.sleep(self.tick_s)
            now = time.monotonic()
            writes: dict[int, tuple[Any, str]] = {}
            with self._lock:
                if not self._running:
                    self._thread = None
                    return
                for owner, text, t0 in sorted(self._running.values(), key=lambda r: -r[2]):
                    if now - t0 >= self.show_after_s:  # the oldest activity of an owner wins
                        writes[id(owner)] = (owner, f"{text} ({now - t0:.0f} s)")
                for k, (owner, _) in writes.items():
                    self._shown[k] = owner
            for owner, text in writes.values():
                self._write(owner, text)

    @staticmethod
    def _write(owner: Any, text: str) -> None:
        try:
            if getattr(owner, "working", None) != text:
                owner.working = text
        except Exception:  # a closed page: nothing to show it on
            log.debug("could not show an activity", exc_info=True)


#: The process's activities.
ACTIVITIES = Activities()
