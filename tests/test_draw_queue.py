"""The session's draw queue (app.runtime.draw.DrawQueue): draws in the order asked for, each
one written before the next starts, a failing draw does not stop the others, and a page
that ended keeps nothing alive through draws that never ran.

The served document is stood in for by the two things the queue uses of it: Bokeh's
``add_next_tick_callback`` and the session context's ``with_locked_document`` (whose
awaiting stands for the socket writes of the draw's patches).
"""

from __future__ import annotations

import asyncio
import gc
import inspect
import threading
import weakref

from bokeh.document import Document

from app.runtime import draw as draw_module
from app.runtime.draw import DrawQueue, on_document
from app.runtime.panel_private import panel_writes_pending


class _Context:
    def __init__(self, doc, log):
        self._doc, self.log = weakref.ref(doc), log

    async def with_locked_document(self, func):
        self.log.append("lock")
        try:  # as Bokeh's: an awaitable result is awaited inside the lock
            r = func(self._doc())
            if inspect.isawaitable(r):
                await r
        finally:
            await asyncio.sleep(0)  # the patches' writes: other tasks may run meanwhile
            self.log.append("written")


class _Doc:
    def __init__(self, log):
        self.session_context = _Context(self, log)
        self.ticks = []

    def add_next_tick_callback(self, cb):
        self.ticks.append(cb)


def _run(doc):
    """Run the scheduled callbacks on an event loop of their own, in a thread of their own
    (an earlier test may have left a loop running in this one)."""

    async def main():
        while doc.ticks:
            await doc.ticks.pop(0)()

    errors = []
    t = threading.Thread(target=lambda: _capture(errors, lambda: asyncio.run(main())))
    t.start()
    t.join(timeout=60)
    assert not t.is_alive() and errors == []


def _capture(errors, fn):
    try:
        fn()
    except Exception as e:  # reported by the test's thread
        errors.append(e)


def test_draws_run_in_order_each_written_before_the_next_and_failures_stay_alone():
    log = []
    doc = _Doc(log)

    def draw(name, fail=False):
        def fn():
            log.append(name)
            if fail:
                raise RuntimeError("broken view")

        return fn

    on_document(doc, draw("analysis"))
    on_document(doc, draw("mobility", fail=True))
    on_document(doc, draw("truncation"))
    assert len(doc.ticks) == 1  # one drain for all waiting draws
    _run(doc)
    assert log == [
        "lock", "analysis", "written",
        "lock", "mobility", "written",
        "lock", "truncation", "written",
    ]  # fmt: skip
    # a later draw starts a new drain
    on_document(doc, draw("eigen"))
    assert len(doc.ticks) == 1
    _run(doc)
    assert log[-3:] == ["lock", "eigen", "written"]


def test_no_server_draws_at_once():
    log = []
    on_document(None, lambda: log.append("drawn"))
    assert log == ["drawn"]


def test_an_ended_page_is_not_kept_alive_by_draws_that_never_ran():
    doc = _Doc([])

    class View:  # a view holds its document, as LiveView does
        def __init__(self, d):
            self.doc = d

        def apply(self):
            pass

    on_document(doc, View(doc).apply)
    ref = weakref.ref(doc)
    DrawQueue.discard(doc)
    doc.ticks.clear()  # the destroyed session's callbacks never run
    del doc
    gc.collect()
    assert ref() is None


def test_a_draw_waits_inside_the_lock_for_the_messages_panel_serialized_before_it(monkeypatch):
    """Panel writes some changes (a clicked dynamic tab's new views) from a task that polls
    the socket; a draw queued behind them must not overtake them (its patches would reach the
    page before the models they change: the phase tab's plots stayed empty)."""
    log = []
    doc = _Doc(log)
    pending = {"messages": 3}

    def panel_pending(d):
        assert d is doc
        return pending["messages"] > 0

    async def panel_writer():  # Panel's write task: one message per turn of the loop
        while pending["messages"]:
            await asyncio.sleep(0)
            pending["messages"] -= 1
            log.append("panel message written")

    monkeypatch.setattr(draw_module, "panel_writes_pending", panel_pending)
    on_document(doc, lambda: log.append("phase drawn"))
    drain = doc.ticks.pop(0)

    async def main():
        await asyncio.gather(drain(), panel_writer())

    errors: list = []
    t = threading.Thread(target=lambda: _capture(errors, lambda: asyncio.run(main())))
    t.start()
    t.join(timeout=60)
    assert not t.is_alive() and errors == []
    assert log == ["lock", *["panel message written"] * 3, "phase drawn", "written"]


def test_pending_panel_writes_are_read_from_panel_itself():
    """The predicate reads Panel's own record of queued, unwritten changes (it fails here
    if Panel renames or drops it)."""
    from panel.io import document as pdoc

    doc = Document()
    assert not panel_writes_pending(doc)
    pdoc._WRITE_BLOCK[doc] = True
    try:
        assert panel_writes_pending(doc)
    finally:
        del pdoc._WRITE_BLOCK[doc]
    pdoc._WRITE_EVENTS[doc] = [(["connection"], ["event"])]
    try:
        assert panel_writes_pending(doc)
    finally:
        del pdoc._WRITE_EVENTS[doc]
    assert not panel_writes_pending(doc)
