"""Panel changes a served page's models off the event loop only in the thread holding the
page's document lock (``app.runtime.panel_private.lock_held_only_by_its_thread``).

Panel 1.10 took a held lock, held by anyone, as leave to change models from its worker
threads: a worker's change raced the end of another locked callback and Bokeh refused it
("_pending_writes should be non-None when we have a document lock"). Truth: Bokeh's own
session runs a locked callback in an executor thread; the check is made there and from a
thread that does not hold the lock, while the lock is held.
"""

from __future__ import annotations

import asyncio
import threading
import types

from bokeh.document import Document
from bokeh.server.session import ServerSession
from panel.io.state import set_curdoc, state
from server_util import in_own_loop

from app.runtime.panel_private import lock_held_only_by_its_thread


def _served_document() -> tuple[Document, ServerSession]:
    doc = Document()
    session = ServerSession("s-lock-held", doc)
    context = types.SimpleNamespace(session=session)
    doc._session_context = lambda: context  # what Bokeh's server gives a served document
    return doc, session


def test_only_the_thread_running_the_locked_callback_counts_as_holding_the_lock():
    lock_held_only_by_its_thread()
    lock_held_only_by_its_thread()  # idempotent
    doc, session = _served_document()
    seen: dict[str, bool] = {}

    def other_thread() -> None:  # a Panel worker handling a browser change meanwhile
        with set_curdoc(doc):
            seen["other"] = state._document_lock_held

    def locked() -> None:  # Bokeh runs it in an executor thread, the lock held
        with set_curdoc(doc):
            seen["locked"] = state._document_lock_held
        t = threading.Thread(target=other_thread)
        t.start()
        t.join(60)

    async def main() -> None:
        await session.with_document_locked(locked)
        with set_curdoc(doc):  # after the callback: nobody holds it
            seen["after"] = state._document_lock_held

    in_own_loop(main(), 120)
    assert seen == {"locked": True, "other": False, "after": False}


def test_a_locked_callback_still_returns_its_result_and_its_coroutine_runs():
    lock_held_only_by_its_thread()
    doc, session = _served_document()

    async def later() -> str:
        await asyncio.sleep(0)
        return "drawn"

    async def main() -> tuple[int, str]:
        a = await session.with_document_locked(lambda x: x + 1, 41)
        b = await session.with_document_locked(later)
        return a, b

    assert in_own_loop(main(), 120) == (42, "drawn")
