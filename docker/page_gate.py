"""The server's proof steps aside while users' pages open (the first page).

The server proves its app once the port is open (``fbs_server.prove_in_background``): one
page built and loaded on a thread of its own. Python runs one thread at a time, so a page a
user opened meanwhile shared the interpreter with the proof: 2.6-2.8 s from its request to
its first plot instead of 1.65 s once the app was proved (``bench/bench_first_page.py``).

:class:`PageGate` knows the pages being opened: a page opens when its session starts
(Bokeh's session-created callbacks, before the app's script builds it) and is open when its
browser says it shows it (Bokeh's "document ready" event, sent once the first screen is
drawn) and the on-load callbacks the page registered have run (the dashboard builds what
is below the first screen there: a page requested the moment the previous one showed
shared the machine with that and with the proof), or when its session ends.

The proof steps aside at safe points only: before it builds a page, before it loads it, and
where the app's script says so. A thread that builds a page nobody waits for carries a
``step_aside`` attribute, a callable that returns once no page opens (and the proof's
document carries it too while its on-load callbacks run on Panel's worker threads); an app
calls it between the steps of its build, where it holds nothing another page may wait for (no lock,
no result half computed: ``app/runtime/pace.py``). Pausing anywhere else is not safe: paused
in the middle of a computation that a user's page waited for (the dashboard shares its
results between pages), the proof held that page back until its hold ran out (seen: 13 s).

Bounded, so that no client can hold the proof off for ever (a bare HTTP request makes a
session whose browser never says anything): a page holds the proof for at most ``hold_s``
seconds from its start, and the proof yields ``budget_s`` seconds in all, then runs beside
whatever opens.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import Any

log = logging.getLogger("tire_fbs.server")

#: Seconds one page opening holds the proof back at most, from its session's start.
PAGE_HOLD_S = 10.0
#: Seconds the proof steps aside for opening pages in all, at most.
PROOF_YIELD_BUDGET_S = 30.0


class PageGate:
    """The pages of users being opened; the proof's thread waits for them (bounded).

    Parameters
    ----------
    hold_s
        Seconds a page holds the proof at most from its start (a session whose browser
        never says it shows the page: a bare HTTP request, a tab closed at once).
    budget_s
        Seconds the proof waits in all, at most; beyond, it runs beside opening pages.
    """

    def __init__(self, hold_s: float = PAGE_HOLD_S, budget_s: float = PROOF_YIELD_BUDGET_S):
        self.hold_s = float(hold_s)
        self.budget_s = float(budget_s)
        self._cond = threading.Condition()
        self._opening: dict[str, float] = {}  # session id -> monotonic time it started
        self._retired = False
        self._waiters = 0
        self.waited_s = 0.0  # seconds the proof has waited so far

    # ---- pages -------------------------------------------------------------------------

    def opened(self, key: str) -> None:
        """A page's session started (its page is about to be built)."""
        with self._cond:
            if not self._retired:
                self._opening[key] = time.monotonic()
                log.info("a page opens while the proof runs (%d opening)", len(self._opening))

    def shown(self, key: str) -> None:
        """The page of ``key`` is shown (document ready) or its session ended."""
        with self._cond:
            if self._opening.pop(key, None) is not None:
                self._cond.notify_all()

    def opening(self) -> int:
        """How many pages are opening (an expired hold counts until a wait drops it)."""
        return len(self._opening)

    def waiting(self) -> bool:
        """Whether a thread waits in :meth:`wait` now."""
        return self._waiters > 0

    def retire(self) -> None:
        """The proof is over: pages are no longer tracked, nobody waits any more."""
        with self._cond:
            self._retired = True
            self._opening.clear()
            self._cond.notify_all()

    def watch_session(self, session_context: Any) -> None:
        """Session-created callback (``pn.state.on_session_created``; Panel runs it with the
        session's document current): the page of this session opens until its on-load
        callbacks have run (see :meth:`watch`) or the session ends."""
        import panel as pn

        self.watch(str(session_context.id), pn.state.curdoc)

    def watch(self, key: str, doc: Any) -> None:
        """The page of ``doc`` opens now, until its browser says it shows it ("document
        ready") and the on-load callbacks the page registered have run after it (the
        dashboard builds what is below its first screen there), or its session ends."""
        if self._retired or doc is None:
            return
        self.opened(key)

        def ready(_event: Any) -> None:  # after the page's own on-load callbacks
            import panel as pn
            from panel.io.state import set_curdoc

            with set_curdoc(doc):
                pn.state.onload(lambda: self.shown(key))

        doc.on_event("document_ready", ready)
        doc.on_session_destroyed(lambda _ctx: self.shown(key))

    # ---- the proof ---------------------------------------------------------------------

    def wait(self) -> bool:
        """Block while pages open (each at most ``hold_s`` from its start; in all at most
        ``budget_s``). False once the budget is spent or the gate retired: the caller
        need not ask again."""
        with self._cond:
            start = time.monotonic()
            announced = False
            while True:
                now = time.monotonic()
                for key, began in list(self._opening.items()):
                    if now - began >= self.hold_s:
                        del self._opening[key]
                left = self.budget_s - self.waited_s - (now - start)
                if not self._opening or left <= 0 or self._retired:
                    break
                if not announced:
                    log.info("the proof steps aside: %d page(s) opening", len(self._opening))
                    announced = True
                until = min(min(self._opening.values()) + self.hold_s - now, left)
                self._waiters += 1
                try:
                    self._cond.wait(until)
                finally:
                    self._waiters -= 1
            waited = time.monotonic() - start
            self.waited_s += waited
            if announced:
                log.info("the proof goes on (%.2f s aside)", waited)
            return not self._retired and self.waited_s < self.budget_s

    def _wait_unlocked(self) -> bool:
        """:meth:`wait`, with the app-script lock this thread may hold released meanwhile
        (it steps aside inside the app's script: ``server_private.app_scripts_unlocked``)."""
        from server_private import app_scripts_unlocked

        with app_scripts_unlocked():
            return self.wait()

    def run(self, work: Callable[[], Any]) -> Any:
        """``work()`` in this thread, which carries :meth:`wait` as its ``step_aside``
        (see the module's docstring); the gate is retired after it."""
        thread = threading.current_thread()
        thread.step_aside = self._wait_unlocked  # type: ignore[attr-defined]
        try:
            return work()
        finally:
            del thread.step_aside  # type: ignore[attr-defined]
            self.retire()
