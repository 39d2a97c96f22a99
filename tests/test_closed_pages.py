"""A write to a page that has closed is logged as a line, every other loop error as before."""

from __future__ import annotations

import asyncio
import logging
import threading

from tornado.websocket import WebSocketClosedError

from app.runtime.closed_pages import quiet_closed_page_writes


def test_only_closed_page_writes_are_quieted(caplog):
    loop = asyncio.new_event_loop()
    seen = []
    loop.set_exception_handler(lambda _loop, context: seen.append(context))
    try:
        assert quiet_closed_page_writes(loop)
        assert not quiet_closed_page_writes(loop)  # once per loop
        with caplog.at_level(logging.INFO, logger="tire-fbs"):
            loop.call_exception_handler(
                {
                    "message": "Task exception was never retrieved",
                    "exception": WebSocketClosedError(),
                }
            )
        assert seen == [] and "a page closed" in caplog.text
        other = {"message": "Task exception was never retrieved", "exception": ValueError("x")}
        loop.call_exception_handler(other)
        assert seen == [other]  # a real error still reaches the handler that was there
    finally:
        loop.close()


def test_a_task_failing_on_a_closed_page_leaves_no_traceback(caplog):
    """The report asyncio makes for a failed write task nobody awaited (Panel's writes of
    widget updates to a page that closed meanwhile)."""

    async def write_to_closed_page():
        raise WebSocketClosedError()

    async def scenario():
        quiet_closed_page_writes()
        task = asyncio.ensure_future(write_to_closed_page())
        await asyncio.sleep(0)
        await asyncio.sleep(0)
        assert task.done()
        del task  # dropped unawaited: asyncio reports it now
        import gc

        gc.collect()

    def run() -> None:  # a loop of its own (the test process may be inside one already)
        asyncio.run(scenario())

    import gc

    gc.collect()  # futures other tests dropped are reported now, not inside this scenario
    with caplog.at_level(logging.DEBUG):
        t = threading.Thread(target=run)
        t.start()
        t.join()
    assert "a page closed" in caplog.text
    # Only reports about this task count: the collection inside the scenario may also meet
    # futures of other tests' loops, and asyncio reports those wherever they are collected.
    ours = [
        r
        for r in caplog.records
        if "WebSocketClosedError" in r.getMessage()
        or (r.exc_info and isinstance(r.exc_info[1], WebSocketClosedError))
        or "write_to_closed_page" in r.getMessage()
    ]
    assert ours == [], [r.getMessage() for r in ours]
    assert not any(
        "never retrieved" in r.getMessage() and "WebSocketClosedError" in r.getMessage()
        for r in caplog.records
    )
