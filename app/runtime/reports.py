"""Reports drawn apart: one at a time on the report thread, in a process of their own.

Drawing a report (matplotlib, the PDF writer) holds the interpreter for seconds, in C code
too. A served click waits on the session's event loop for :data:`REPORTS` (one thread:
the sessions asking wait for their turn without holding one of Panel's worker threads;
four tabs asking for PDF reports in a loop took every worker, another
session's p95 went from 0.1 to 2.2 s), and that thread has the file drawn by the report
process (:func:`draw_apart`, at a lower priority). What a report shows is
:mod:`app.report`'s; the buttons are :func:`app.page.chrome.report_buttons`.
"""

from __future__ import annotations

import asyncio
import copyreg
import logging
import multiprocessing
import os
import threading
import types
import weakref
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from ..report import ReportData, build_html, build_pdf
from .panel_private import pool_processes

__all__ = [
    "REPORT_THREADS",
    "REPORT_NICE",
    "REPORTS",
    "ReportsStopped",
    "draw",
    "draw_apart",
    "stop",
    "submit_for_session",
]

#: Reports drawn at once in the server. Drawing holds the interpreter, so more threads
#: would only slow every session.
REPORT_THREADS = 1
#: The report thread: a served click's report is made here while the click waits.
REPORTS = ThreadPoolExecutor(REPORT_THREADS, thread_name_prefix="fbs-report")
#: How much the report process lowers its CPU priority (nice value).
REPORT_NICE = 10

log = logging.getLogger(__name__)
_drawer: list[ProcessPoolExecutor] = []
#: Held while the report process is started or stopped: no process is started once
#: :func:`stop` has run.
_drawer_lock = threading.Lock()
_stopping = threading.Event()
#: How long (s) :func:`stop` waits for a report process to end on SIGTERM before SIGKILL.
STOP_GRACE_S = 1.0


class ReportsStopped(RuntimeError):
    """The server is stopping, or the session that asked has closed: no report is drawn."""


def _mapping(d: dict[str, Any]) -> types.MappingProxyType[str, Any]:
    return types.MappingProxyType(d)


# report data's settings are a read-only mapping: sent to the report process as a dict
copyreg.pickle(types.MappingProxyType, lambda m: (_mapping, (dict(m),)))


def _lower_priority() -> None:
    try:
        os.nice(REPORT_NICE)
    except OSError:
        pass


def draw(kind: str, data: ReportData) -> tuple[str, str | bytes]:
    """``(file name, content)`` of the ``kind`` ("html" or "pdf") report of ``data``."""
    return (build_html if kind == "html" else build_pdf)(data)


def draw_apart(kind: str, data: ReportData) -> tuple[str, str | bytes]:
    """:func:`draw` in the report process: in a process of its own, at a lower priority, it
    takes nothing from the sessions' threads. Drawn here when the data cannot be sent
    (logged) or the process broke twice.

    Raises
    ------
    ReportsStopped
        Once the server is stopping (:func:`stop`): no report process is started then.
    """
    for _ in range(2):
        with _drawer_lock:  # the process starts (in submit) under the lock: stop() waits
            if _stopping.is_set():
                raise ReportsStopped("the server is stopping; no report is drawn")
            if not _drawer:
                ctx = multiprocessing.get_context("spawn")  # the server has threads: no fork
                _drawer.append(ProcessPoolExecutor(1, ctx, initializer=_lower_priority))
            pool = _drawer[0]
            future = pool.submit(draw, kind, data)
        try:
            return future.result()
        except BrokenProcessPool:
            with _drawer_lock:
                if _drawer and _drawer[0] is pool:
                    _drawer.clear()
        except (TypeError, AttributeError) as exc:  # not picklable: a section of a new view
            log.warning("report drawn in the server process (%s)", exc)
            break
    if _stopping.is_set():
        raise ReportsStopped("the server is stopping; no report is drawn")
    return draw(kind, data)


def stop(grace_s: float = STOP_GRACE_S) -> int:
    """Stop drawing reports, for the server's shutdown: queued reports are cancelled, no
    report process is started from now on, and the running one is ended (SIGTERM, SIGKILL
    after ``grace_s``) and reaped. Returns the number of report processes ended.

    The server's stop signal lists its child processes to end them; a report process
    started after that list (a queued report's turn, or a new process for a broken one)
    outlived the server before.
    """
    _stopping.set()
    REPORTS.shutdown(wait=False, cancel_futures=True)
    with _drawer_lock:
        pools, _drawer[:] = list(_drawer), []
    procs = []
    for pool in pools:
        procs += pool_processes(pool)
        pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(grace_s)
        if p.is_alive():
            p.kill()
            p.join(grace_s)
    return len(procs)


class _Session:
    """The reports a session has queued; cancelled together when the session closes."""

    def __init__(self) -> None:
        self.closed = threading.Event()
        self.queued: set[Future[Any]] = set()
        self.lock = threading.Lock()

    def destroyed(self, session_context: Any) -> None:
        self.closed.set()
        with self.lock:
            queued, self.queued = self.queued, set()
        for f in queued:
            f.cancel()  # only those not started yet; a running one finds closed set


_sessions: weakref.WeakKeyDictionary[Any, _Session] = weakref.WeakKeyDictionary()
_sessions_lock = threading.Lock()


def _session(doc: Any) -> _Session:
    with _sessions_lock:
        s = _sessions.get(doc)
        if s is None:
            s = _sessions[doc] = _Session()
            doc.on_session_destroyed(s.destroyed)
    return s


def _retrieved(f: asyncio.Future[Any]) -> None:
    """Read the outcome of a report nobody may await any more (its tab closed): not
    "Future exception was never retrieved" in the server log."""
    if f.cancelled():
        return
    exc = f.exception()
    if isinstance(exc, ReportsStopped):
        log.info("%s", exc)
    elif exc is not None:
        log.debug("a report ended with %s: %s", type(exc).__name__, exc)


def submit_for_session[T](doc: Any, fn: Callable[[], T]) -> asyncio.Future[T]:
    """``fn()`` on the report thread for the session of Bokeh document ``doc``, as an
    asyncio future of the running loop.

    When the session closes before its turn, the work is cancelled and never runs (its
    page is gone: the app's names are no longer there to run it, the report would be
    thrown away). A report that fails or is cancelled is read out (logged, not "never
    retrieved").

    Raises
    ------
    ReportsStopped
        In the returned future, when the session closed or the server is stopping.
    """
    s = _session(doc)

    def run() -> T:
        if s.closed.is_set():
            raise ReportsStopped("the page that asked for this report has closed")
        if _stopping.is_set():
            raise ReportsStopped("the server is stopping; no report is drawn")
        return fn()

    if s.closed.is_set() or _stopping.is_set():
        raise ReportsStopped("the page has closed or the server is stopping")
    cf = REPORTS.submit(run)
    with s.lock:
        s.queued.add(cf)
    cf.add_done_callback(lambda f: s.queued.discard(f))
    af = asyncio.wrap_future(cf)
    af.add_done_callback(_retrieved)
    return af
