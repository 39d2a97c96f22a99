"""The reading of uploaded files, off Panel's worker threads and bounded per session.

Reading an upload takes up to the sandbox's time limit (30 s) and used to run on the Panel
worker thread that handled the upload (``FBS_NUM_THREADS``, 4): four tabs uploading slow
files held every thread, and every other session's control changes waited
(p95 from 0.17 s to over 60 s). Here an upload is a job of :data:`UPLOADS`:

- a few threads of its own read the files, as many as the sandbox has parser processes
  (``fbs_core.io._sandbox.parsers()``), so Panel's threads answer the controls meanwhile;
- a session (its :class:`~app.datasource.DataSource`) has at most one job per slot
  (chassis, tire) waiting: a newer upload replaces the waiting one, and the jobs wait in
  arrival order across sessions, so one session's uploads do not starve another's;
- at most :data:`MAX_WAITING` jobs wait in all; beyond that an upload is refused at once
  with a message (``DataSource.error``) instead of queueing without bound;
- a closed tab cancels its jobs: a waiting one is dropped, a running one stops its parse
  (``fbs_core.io._sandbox.cancel_scope``: the parser process is killed);
- a job only reads: what the new models change (the session's pass, which may compute for
  many seconds) runs on a thread of its own (:func:`on_upload_thread`, used by
  :class:`app.store.Results`), so a long pass never holds a reading thread (every
  session's later uploads waited for it) nor the data source's lock.

A job runs with the session's document as Panel's current document, so what it changes
(the data source's models, error and summaries) reaches the page through the session's
own event loop, as the scatter bands do (:func:`app.runtime.bands.start`).
"""

from __future__ import annotations

import logging
import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import panel as pn

from fbs_core.io._sandbox import Cancelled, cancel_scope, parsers

__all__ = ["MAX_WAITING", "UPLOADS", "UploadJob", "UploadQueue", "on_upload_thread"]

log = logging.getLogger(__name__)

#: Uploads waiting at most in the process (beyond: refused at once with a message).
MAX_WAITING = 16

_local = threading.local()


def on_upload_thread() -> bool:
    """True while a job of an :class:`UploadQueue` runs on the calling thread."""
    return bool(getattr(_local, "reading", False))


@dataclass(eq=False)
class UploadJob:
    """One reading of an upload: whose (``owner``), which ``slot``, what to run."""

    owner: Any
    slot: str
    run: Callable[[], Any]
    refused: Callable[[str], Any]
    doc: Any = None
    cancelled: threading.Event = field(default_factory=threading.Event)
    done: threading.Event = field(default_factory=threading.Event)


class UploadQueue:
    """Jobs of all sessions, read by ``threads`` threads in arrival order (see the module).

    Parameters
    ----------
    threads : int, optional
        Reading threads (default: the sandbox's parser processes).
    max_waiting : int
        Jobs waiting at most.
    """

    def __init__(self, threads: int | None = None, max_waiting: int = MAX_WAITING) -> None:
        self.threads = threads
        self.max_waiting = max_waiting
        self._waiting: deque[UploadJob] = deque()
        self._running: set[UploadJob] = set()
        self._cond = threading.Condition()
        self._workers: list[threading.Thread] = []

    def submit(
        self,
        owner: Any,
        slot: str,
        run: Callable[[], Any],
        refused: Callable[[str], Any],
    ) -> UploadJob | None:
        """Queue ``run()`` for ``owner``'s ``slot``; None (and ``refused(message)``) when
        too many jobs wait. A job of the same owner and slot still waiting is replaced."""
        job: UploadJob | None = UploadJob(owner, slot, run, refused, doc=pn.state.curdoc)
        with self._cond:
            for old in [j for j in self._waiting if j.owner is owner and j.slot == slot]:
                self._waiting.remove(old)
                old.cancelled.set()
                old.done.set()
            if len(self._waiting) >= self.max_waiting:
                n = len(self._waiting)
                job = None
            else:
                assert job is not None
                self._waiting.append(job)
                self._start_workers()
                self._cond.notify()
        if job is None:
            refused(
                f"the server is reading {n} other uploads; nothing changed, try again in a minute"
            )
        return job

    def cancel(self, owner: Any) -> int:
        """Cancel every job of ``owner`` (a closed tab); the number cancelled."""
        with self._cond:
            mine = [j for j in self._waiting if j.owner is owner]
            for j in mine:
                self._waiting.remove(j)
                j.done.set()
            mine += [j for j in self._running if j.owner is owner]
            for j in mine:
                j.cancelled.set()
        return len(mine)

    @property
    def waiting(self) -> int:
        with self._cond:
            return len(self._waiting)

    @property
    def running(self) -> int:
        with self._cond:
            return len(self._running)

    def _start_workers(self) -> None:
        n = self.threads or parsers()
        while len(self._workers) < n:
            t = threading.Thread(target=self._work, name="fbs-upload", daemon=True)
            self._workers.append(t)
            t.start()

    def _work(self) -> None:
        while True:
            with self._cond:
                while not self._waiting:
                    self._cond.wait()
                job = self._waiting.popleft()
                self._running.add(job)
            try:
                self._run(job)
            finally:
                with self._cond:
                    self._running.discard(job)
                job.done.set()

    @staticmethod
    def _run(job: UploadJob) -> None:
        if job.cancelled.is_set():
            return
        pn.state.curdoc = job.doc  # what the job changes is drawn by its session's loop
        _local.reading = True
        try:
            with cancel_scope(job.cancelled):
                job.run()
        except Cancelled:
            log.info("an upload's reading was cancelled (its tab closed or a newer upload)")
        except Exception:  # a job's own failure must not end the reading thread
            log.exception("reading an upload failed")
        finally:
            _local.reading = False
            pn.state.curdoc = None


#: The process's upload queue.
UPLOADS = UploadQueue()
