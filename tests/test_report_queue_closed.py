"""Reports queued by a tab that closed, and reports once the server stops.

A served report waits for the one report thread. A tab closed before its turn left its
report queued: it then ran on a page whose names Bokeh had cleared (``NameError: name
'report_data' is not defined``), and, as nobody awaited it any more, asyncio logged "Future
exception was never retrieved". Here the session's close is Bokeh's own: the document's
session-destroyed callbacks, called as the server calls them.
"""

from __future__ import annotations

import asyncio
import gc
import logging
import subprocess
import sys
import threading

import pytest
from bokeh.document import Document
from server_util import in_own_loop

from app.runtime import reports


def _close(doc: Document) -> None:
    """What Bokeh's server does when a session is discarded."""
    for cb in list(doc.session_destroyed_callbacks):
        cb(None)


def test_a_report_queued_by_a_closed_tab_never_runs():
    gate, started, ran = threading.Event(), threading.Event(), []

    def first_report():
        started.set()
        gate.wait(60)
        return "a"

    async def main():
        doc_a, doc_b = Document(), Document()
        first = reports.submit_for_session(doc_a, first_report)
        assert await asyncio.to_thread(started.wait, 60)
        second = reports.submit_for_session(doc_b, lambda: ran.append("b") or "b")
        third = reports.submit_for_session(doc_a, lambda: ran.append("a2") or "a2")
        _close(doc_b)  # the tab closes while its report waits for its turn
        gate.set()
        assert await first == "a"
        assert await third == "a2"  # the open tab's next report runs
        with pytest.raises(asyncio.CancelledError):
            await second
        with pytest.raises(reports.ReportsStopped, match="closed"):
            reports.submit_for_session(doc_b, lambda: ran.append("late"))

    in_own_loop(main(), 300)
    assert ran == ["a2"]


def test_a_report_failing_after_its_tab_closed_is_not_an_unretrieved_error(caplog):
    started, gate = threading.Event(), threading.Event()

    def report():
        started.set()
        gate.wait(60)
        raise NameError("name 'report_data' is not defined")  # the page's names cleared

    async def main():
        doc = Document()
        fut = reports.submit_for_session(doc, report)  # nobody awaits it: the tab closed
        assert await asyncio.to_thread(started.wait, 60)
        _close(doc)
        gate.set()
        for _ in range(600):
            if fut.done():
                break
            await asyncio.sleep(0.05)
        assert fut.done()
        del fut
        gc.collect()

    with caplog.at_level(logging.DEBUG):
        in_own_loop(main(), 300)
        gc.collect()
    assert not [r for r in caplog.records if "never retrieved" in r.getMessage()]
    assert any("NameError" in r.getMessage() for r in caplog.records)


def test_once_stopped_no_report_process_is_started():
    """In a process of its own (stopping is for good): queued reports are cancelled, a
    report asked for afterwards raises ReportsStopped and starts no process."""
    code = """
import multiprocessing, threading
from app.runtime import reports
gate = threading.Event()
held = reports.REPORTS.submit(gate.wait, 60)
queued = reports.REPORTS.submit(lambda: "ran")
assert reports.stop() == 0
gate.set()
assert queued.cancelled(), "a queued report still ran"
try:
    reports.draw_apart("html", None)
except reports.ReportsStopped as e:
    print("refused:", e)
assert multiprocessing.active_children() == [], multiprocessing.active_children()
print("ok")
"""
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=False
    )
    assert out.returncode == 0, out.stderr
    assert "refused: the server is stopping" in out.stdout and "ok" in out.stdout
