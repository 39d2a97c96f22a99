"""Writes to a page that has just closed are not server errors.

A browser tab closed (or reloaded) while the server is still sending it patches makes
Tornado's write fail with ``WebSocketClosedError``. Panel's own writes of widget updates
are tasks that it cancels when the session ends; a task that had failed already is then
reported by asyncio at garbage collection as "Task exception was never retrieved", with
two tracebacks, in the server log where operators look for real errors. That exception,
and only that one, is logged here as one informational line; everything else goes to the
handler that was there before (asyncio's default).
"""

from __future__ import annotations

import asyncio
import logging
import weakref

__all__ = ["is_closed_page_write", "quiet_closed_page_writes"]

log = logging.getLogger("tire-fbs")
_done: weakref.WeakSet = weakref.WeakSet()


def is_closed_page_write(context: dict) -> bool:
    """True for asyncio's report of a write to a websocket that had closed."""
    from tornado.iostream import StreamClosedError
    from tornado.websocket import WebSocketClosedError

    return isinstance(context.get("exception"), (WebSocketClosedError, StreamClosedError))


def quiet_closed_page_writes(loop: asyncio.AbstractEventLoop | None = None) -> bool:
    """Install the handler on ``loop`` (default: the running loop), once per loop.

    Returns False when there is no running loop (no server: tests, notebooks) or the
    handler is there already.
    """
    if loop is None:
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:
            return False
    if loop in _done:
        return False
    before = loop.get_exception_handler()

    def handler(loop: asyncio.AbstractEventLoop, context: dict) -> None:
        if is_closed_page_write(context):
            log.info("a page closed while the server was writing to it")
            return
        if before is not None:
            before(loop, context)
        else:
            loop.default_exception_handler(context)

    loop.set_exception_handler(handler)
    _done.add(loop)
    return True
