"""Reports drawn apart: one at a time on the report thread, in a process of their own.

Drawing a report (matplotlib, the PDF writer) holds the interpreter for seconds, in C code
too. A served click waits on the session's event loop for :data:`REPORTS` (one thread:
the sessions asking wait for their turn without holding one of Panel's worker threads;
issue 28, finding 7: four tabs asking for PDF reports in a loop took every worker, another
session's p95 went from 0.1 to 2.2 s), and that thread has the file drawn by the report
process (:func:`draw_apart`, at a lower priority). What a report shows is
:mod:`app.report`'s; the buttons are :func:`app.page.chrome.report_buttons`.
"""

from __future__ import annotations

import copyreg
import logging
import multiprocessing
import os
import threading
import types
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from ..report import ReportData, build_html, build_pdf

__all__ = ["REPORT_THREADS", "REPORT_NICE", "REPORTS", "draw", "draw_apart"]

#: Reports drawn at once in the server. Drawing holds the interpreter, so more threads
#: would only slow every session.
REPORT_THREADS = 1
#: The report thread: a served click's report is made here while the click waits.
REPORTS = ThreadPoolExecutor(REPORT_THREADS, thread_name_prefix="fbs-report")
#: How much the report process lowers its CPU priority (nice value).
REPORT_NICE = 10

log = logging.getLogger(__name__)
_drawer: list[ProcessPoolExecutor] = []
_drawer_lock = threading.Lock()


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
    (logged) or the process broke twice."""
    for _ in range(2):
        with _drawer_lock:
            if not _drawer:
                ctx = multiprocessing.get_context("spawn")  # the server has threads: no fork
                _drawer.append(ProcessPoolExecutor(1, ctx, initializer=_lower_priority))
            pool = _drawer[0]
        try:
            return pool.submit(draw, kind, data).result()
        except BrokenProcessPool:
            with _drawer_lock:
                if _drawer and _drawer[0] is pool:
                    _drawer.clear()
        except (TypeError, AttributeError) as exc:  # not picklable: a section of a new view
            log.warning("report drawn in the server process (%s)", exc)
            break
    return draw(kind, data)
