"""Drawing on a served page: the session's draw queue and where Bokeh models may change.

Bokeh models of a served document change only on the session's event loop with the
document lock held; control changes, bands and background work publish their results on
other threads. :func:`on_document` runs a change where it may happen: at once without a
server (tests, exports), else in the session's :class:`DrawQueue`, which runs the draws one
after the other on the event loop, each under the document lock (Bokeh's
``with_locked_document``) and each one's patches written to the page before the next draw,
in the order they were asked for. A draw that fails is logged and the next one runs; the
queue of a session that ended is dropped (:meth:`DrawQueue.discard`).
"""

from __future__ import annotations

import asyncio
import logging
import threading
import time
import weakref
from collections import deque
from functools import partial

import panel as pn
from bokeh.document import without_document_lock
from panel.io.state import set_curdoc

from . import collector
from .panel_private import panel_writes_pending

__all__ = ["DrawQueue", "on_document", "served", "served_document"]

log = logging.getLogger(__name__)


def served() -> bool:
    """True inside a served browser session (else: tests, notebooks, the warm-up)."""
    doc = pn.state.curdoc
    return doc is not None and doc.session_context is not None


def served_document():
    """The Bokeh document of the current served session (None: no server)."""
    doc = pn.state.curdoc
    return doc if doc is not None and doc.session_context is not None else None


#: The document whose draw this thread is running (a draw's own requests join it).
_drawing = threading.local()


def on_document(doc, fn) -> None:
    """Run ``fn`` (changes of Bokeh models) where it may change the served document
    ``doc``: on the session's event loop under its lock, whichever thread asks (``doc``
    None: no server, at once), after the changes asked for before it (:class:`DrawQueue`).

    Asked for by a draw of ``doc`` itself, ``fn`` runs at once, inside that draw: its
    changes leave in the draw's one message. (The view switch restyles a dozen figures,
    each through its own view: as separate draws they reached the browser as a dozen
    messages, and the page laid itself out again after each one, ~0.4 s apiece.)
    """
    if doc is None or doc.session_context is None:
        fn()  # no server: tests, notebooks, exports
    elif getattr(_drawing, "doc", None) is doc:
        fn()
    else:
        DrawQueue.of(doc).add(fn)


class DrawQueue:
    """A served session's draws, run one after the other on its event loop.

    Each draw runs under the document lock (Bokeh's ``with_locked_document``) and its
    patches are written to the socket before the next draw starts. Scheduled as separate
    next-tick callbacks instead, every socket write of a draw (a data patch is seven
    websocket frames) waited for one turn of the event loop, in which the session's other
    waiting draws ran in full: the view drawn first (the Analysis card's shown view)
    reached the page only after the main views' draws (10-40 ms each). One queue per
    document, in the order the draws were asked for; a failing draw is logged and the
    next one runs.
    """

    _queues: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
    _queues_lock = threading.Lock()

    def __init__(self, doc) -> None:
        self._doc = weakref.ref(doc)
        self._fns: deque = deque()
        self._lock = threading.Lock()
        self._running = False

    @classmethod
    def of(cls, doc) -> DrawQueue:
        """The queue of document ``doc`` (made on first use)."""
        with cls._queues_lock:
            q = cls._queues.get(doc)
            if q is None:
                q = cls._queues[doc] = cls(doc)
            return q

    @classmethod
    def discard(cls, doc) -> None:
        """Drop the draws still waiting for ``doc`` (its session ended: a next-tick callback
        of a destroyed session may never run, and a waiting draw keeps its page alive)."""
        if doc is None:
            return
        with cls._queues_lock:
            q = cls._queues.pop(doc, None)
        if q is not None:
            q.clear()

    def clear(self) -> None:
        """Drop the draws waiting in this queue."""
        with self._lock:
            self._fns.clear()

    def add(self, fn) -> None:
        """Run ``fn`` after the draws already waiting (from any thread)."""
        collector.touch()  # not quiet: the next full collection waits
        with self._lock:
            self._fns.append(fn)
            if self._running:
                return
            self._running = True
        doc = self._doc()
        try:
            if doc is None:
                raise RuntimeError("document gone")
            doc.add_next_tick_callback(self._drain)  # thread-safe in Bokeh
        except Exception:
            with self._lock:  # the session is gone: nothing will draw
                self._fns.clear()
                self._running = False

    @without_document_lock
    async def _drain(self) -> None:
        while True:
            with self._lock:
                if not self._fns:
                    self._running = False
                    return
                fn = self._fns.popleft()
            doc = self._doc()
            if doc is None or doc.session_context is None:
                continue
            try:  # returns once the draw's patches are written (or the session ended)
                await doc.session_context.with_locked_document(partial(_draw_locked, fn))
            except Exception:
                log.exception("drawing on the page failed")


#: Longest wait of a draw for Panel's pending messages (s): a safeguard only; they are
#: written as soon as the socket is free (tens of ms under load).
PANEL_WRITES_WAIT = 10.0


async def _after_panel_writes(doc) -> None:
    """Wait until the messages Panel serialized for ``doc`` earlier are written, so that a
    draw's patches never reach the page before the models they change
    (:mod:`app.runtime.panel_private`)."""
    end = time.monotonic() + PANEL_WRITES_WAIT
    while panel_writes_pending(doc) and doc.session_context is not None:
        if time.monotonic() > end:
            log.warning("Panel's messages to a page waited more than %g s", PANEL_WRITES_WAIT)
            return
        await asyncio.sleep(0.002)


async def _draw_locked(fn, doc) -> None:
    """``fn`` under the document lock, once the messages Panel serialized before it are
    written (waiting inside the lock: no change of Panel's can be serialized in between)."""
    await _after_panel_writes(doc)
    _run_on(fn, doc)


def _run_on(fn, doc) -> None:
    # Panel components changed by ``fn`` find their document; the draw's changes leave as
    # one PATCH-DOC message (Panel's ``unlocked``: the document held during the draw, its
    # events serialized together). Bokeh alone sends one message per property set, each
    # building the serializer's map of the page's ~750 models: a quarter of the server's
    # CPU with 20 sessions changing (``bench/load_test.py``, profiled; tested by
    # ``tests/test_draw_messages.py``).
    outer = getattr(_drawing, "doc", None)
    _drawing.doc = doc
    try:
        with set_curdoc(doc), pn.io.unlocked():
            fn()
    finally:
        _drawing.doc = outer
