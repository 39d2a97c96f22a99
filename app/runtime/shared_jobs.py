"""Long work that sessions wait for, computed once for all of them, its end told to each.

The belt waves' Campbell diagram of a tire (one dense solve per operating point) is the
same for every session showing that tire. Computed as a background task of the session
that asked first, it ran at a low priority behind the other sessions' work, the sessions
that asked later were told nothing when it ended, a task dropped from the full queue was
never asked for again (the row's inputs had not changed), and the page said "solving the
tire..." for as long as the session lived. A :class:`SharedJobs` instead:

- runs each job (a key, and ``work(progress)``) on a thread of its own at the server's
  priority, at most ``threads`` jobs at once (the others are queued and say so);
- tells every waiter (a *listener*, one per session and row, replaced when the session asks
  again) how the job moves: its progress (at most every :attr:`SharedJobs.interval`
  seconds), its end, its failure. Listeners run on the notifier's threads, never on the
  job's: a session whose lock is busy delays its own news, not the computation;
- has deadlines: after ``deadline_s`` a job still running is *late*, and its waiters are
  told why (how far it got, that the machine is busy); a job whose thread ended without
  finishing it (lost) is started again ``retries`` times, then reported as failed;
- keeps a failure for ``failed_ttl`` seconds (every waiter sees the message); a request
  after that tries again.

Nothing here computes a result: the work comes from the caller (:mod:`app.results.modes_compute`).
"""

from __future__ import annotations

import logging
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import dataclass, replace
from typing import Any

__all__ = ["JobStatus", "SharedJobs"]

log = logging.getLogger(__name__)

#: ``progress(done, total)`` as the work moves on.
Progress = Callable[[int, int], None]
#: ``listener(status)``: told how a job moves.
Listener = Callable[["JobStatus"], None]


@dataclass(frozen=True)
class JobStatus:
    """Where a shared job stands.

    Attributes
    ----------
    state : str
        ``"queued"``, ``"running"``, ``"done"`` or ``"failed"``.
    done, total : int
        Progress (steps of the work; 0 / 0 before the first).
    seconds : float
        Since the job was asked for (s).
    late : bool
        Running longer than the deadline.
    attempt : int
        1 for the first run, 2 after the first was lost, ...
    message : str
        What the failure was, or why it takes long.
    value : object
        The result once done.
    """

    state: str
    done: int = 0
    total: int = 0
    seconds: float = 0.0
    late: bool = False
    attempt: int = 1
    message: str = ""
    value: Any = None

    @property
    def finished(self) -> bool:
        return self.state in ("done", "failed")

    def describe(self, what: str) -> str:
        """One sentence for the page: ``what`` is under way (how far, how long) or failed."""
        if self.state == "failed":
            return f"{what} failed: {self.message}"
        if self.state == "done":
            return f"{what}: done"
        where = f", {self.done} of {self.total}" if self.total else ""
        head = "waiting for another computation to end" if self.state == "queued" else what
        text = f"{head} ({self.seconds:.0f} s so far{where})"
        if self.attempt > 1:
            text += f"; started again (attempt {self.attempt}: the previous run was lost)"
        if self.late:
            text += f"; {self.message}"
        return text


def _me() -> threading.Thread:
    return threading.current_thread()


class _Job:
    def __init__(self, key: Hashable, work: Callable[[Progress], Any]) -> None:
        self.key = key
        self.work = work
        self.asked = time.monotonic()
        self.status = JobStatus("queued")
        self.listeners: dict[Hashable, Listener] = {}
        self.thread: threading.Thread | None = None
        self.told = 0.0  # when the listeners were last told of progress
        self.finished_at = 0.0


class SharedJobs:
    """Jobs shared by the sessions that wait for them (see the module).

    Parameters
    ----------
    name : str
        Prefix of the threads' names.
    threads : int
        Jobs running at once.
    deadline_s : float
        After this a running job is late: its waiters are told why.
    retries : int
        Runs started again after a lost one.
    failed_ttl : float
        How long a failure is kept (s) before a request tries again.
    interval : float
        Shortest interval between two progress notes to the listeners (s).
    """

    def __init__(
        self,
        name: str,
        threads: int = 1,
        deadline_s: float = 60.0,
        retries: int = 1,
        failed_ttl: float = 30.0,
        interval: float = 1.0,
    ) -> None:
        self.name = name
        self.deadline_s = deadline_s
        self.retries = retries
        self.failed_ttl = failed_ttl
        self.interval = interval
        self._slots = threading.Semaphore(threads)
        self._lock = threading.Lock()
        self._jobs: dict[Hashable, _Job] = {}
        self._notes: OrderedDict[tuple[Hashable, Hashable], tuple[Listener, JobStatus]] = (
            OrderedDict()
        )
        self._notes_cond = threading.Condition()
        self._notifiers: list[threading.Thread] = []
        self._watchdog: threading.Thread | None = None

    # -- asking ----------------------------------------------------------------------------
    def status(self, key: Hashable) -> JobStatus | None:
        """Where the job of ``key`` stands (None: never asked for, or its failure has
        expired); a look-up, nothing is started."""
        with self._lock:
            job = self._jobs.get(key)
            if job is None or self._expired(job):
                return None
            return self._now(job)

    def request(
        self,
        key: Hashable,
        work: Callable[[Progress], Any],
        listener_key: Hashable | None = None,
        listener: Listener | None = None,
    ) -> JobStatus:
        """Ask for the job of ``key`` (started unless under way, done, or failed within
        ``failed_ttl``); ``listener`` (replacing the one of ``listener_key``) is told how
        it moves until it ends."""
        with self._lock:
            job = self._jobs.get(key)
            if job is None or self._expired(job):
                job = self._jobs[key] = _Job(key, work)
                self._start(job)
            elif not job.status.finished and job.thread is not None and not job.thread.is_alive():
                self._lost(job)
            if listener is not None and not job.status.finished:
                job.listeners[listener_key] = listener
            self._ensure_watchdog()
            return self._now(job)

    def run_here(self, key: Hashable, work: Callable[[Progress], Any], timeout: float) -> JobStatus:
        """The job's status once it ended, or late after ``timeout`` seconds, for a caller
        that has no page to be told on (tests, exports): computed here unless it is
        already under way."""
        done = threading.Event()
        st = self.request(key, work, ("run_here", threading.get_ident()), lambda s: done.set())
        if st.finished:
            return st
        done.wait(timeout)
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            now = self.status(key)
            if now is None or now.finished:
                return now if now is not None else st
            done.clear()
            done.wait(min(1.0, max(t_end - time.monotonic(), 0.01)))
        now = self.status(key)
        return now if now is not None else st

    def forget(self, key: Hashable) -> None:
        """Drop what is known of ``key`` (tests; a running job ends unseen)."""
        with self._lock:
            self._jobs.pop(key, None)

    def cancel_listeners(self, owner: object) -> None:
        """Stop telling ``owner``'s listeners (keys ``(owner, ...)``: a closed session)."""
        with self._lock:
            for job in self._jobs.values():
                for k in [k for k in job.listeners if isinstance(k, tuple) and k[:1] == (owner,)]:
                    del job.listeners[k]

    # -- running ---------------------------------------------------------------------------
    def _start(self, job: _Job) -> None:
        t = threading.Thread(target=self._run, args=(job,), name=f"{self.name}-job", daemon=True)
        job.thread = t
        t.start()

    def _lost(self, job: _Job) -> None:
        """The job's thread ended without finishing it (lock held)."""
        if job.status.attempt <= self.retries:
            log.warning("shared job %r was lost; starting it again", job.key)
            job.status = JobStatus("queued", attempt=job.status.attempt + 1)
            self._start(job)
        else:
            self._finish(
                job,
                replace(
                    job.status,
                    state="failed",
                    message=f"the computation stopped unexpectedly {job.status.attempt} times",
                ),
            )

    def _run(self, job: _Job) -> None:
        with self._slots:
            with self._lock:
                if (
                    self._jobs.get(job.key) is not job
                    or job.thread is not threading.current_thread()
                ):
                    return
                job.status = replace(job.status, state="running")

            def progress(done: int, total: int) -> None:
                with self._lock:
                    if job.thread is _me():
                        job.status = replace(job.status, done=int(done), total=int(total))

            try:
                value = job.work(progress)
            except Exception as e:  # reported to every waiter; never ends the server
                log.exception("shared job %r failed", job.key)
                msg = str(e) or type(e).__name__
                with self._lock:
                    if job.thread is _me():
                        self._finish(job, replace(job.status, state="failed", message=msg))
                return
            except BaseException:  # the thread ends unfinished: the watchdog finds it lost
                log.exception("shared job %r stopped its thread", job.key)
                return
            with self._lock:
                if job.thread is _me():
                    self._finish(job, replace(job.status, state="done", value=value))

    def _finish(self, job: _Job, status: JobStatus) -> None:
        """The job ended (lock held): every listener told, then forgotten."""
        job.status = status
        job.finished_at = time.monotonic()
        now = self._now(job)
        for lk, listener in job.listeners.items():
            self._note(job.key, lk, listener, now)
        job.listeners.clear()

    def _expired(self, job: _Job) -> bool:
        return job.status.state == "failed" and time.monotonic() - job.finished_at > self.failed_ttl

    def _now(self, job: _Job) -> JobStatus:
        end = job.finished_at if job.status.finished else time.monotonic()
        seconds = end - job.asked
        late = not job.status.finished and seconds > self.deadline_s
        msg = job.status.message
        if late and not msg:
            msg = (
                f"longer than the {self.deadline_s:.0f} s it takes on an idle core: the "
                "server is busy with other work; it goes on and the view updates when done"
            )
        return replace(job.status, seconds=seconds, late=late, message=msg)

    # -- the watchdog: progress notes, deadlines, lost threads -----------------------------
    def _ensure_watchdog(self) -> None:
        if self._watchdog is None or not self._watchdog.is_alive():
            self._watchdog = threading.Thread(
                target=self._watch, name=f"{self.name}-watchdog", daemon=True
            )
            self._watchdog.start()

    def _watch(self) -> None:
        while True:
            time.sleep(min(0.25, self.interval / 2))
            with self._lock:
                if not any(not j.status.finished for j in self._jobs.values()):
                    self._watchdog = None
                    return
                t = time.monotonic()
                for job in list(self._jobs.values()):
                    if job.status.finished:
                        continue
                    if job.thread is not None and not job.thread.is_alive():
                        self._lost(job)
                        if job.status.finished:
                            continue
                    if t - job.told >= self.interval:
                        job.told = t
                        now = self._now(job)
                        for lk, listener in job.listeners.items():
                            self._note(job.key, lk, listener, now)

    # -- the notifier: listeners run off the jobs' and the watchdog's threads -----------------
    def _note(self, key: Hashable, lk: Hashable, listener: Listener, status: JobStatus) -> None:
        with self._notes_cond:
            self._notes[(key, lk)] = (listener, status)  # a newer note replaces a waiting one
            self._notes.move_to_end((key, lk))
            while len(self._notifiers) < 2:
                t = threading.Thread(target=self._tell, name=f"{self.name}-notify", daemon=True)
                self._notifiers.append(t)
                t.start()
            self._notes_cond.notify()

    def _tell(self) -> None:
        while True:
            with self._notes_cond:
                self._notes_cond.wait_for(lambda: bool(self._notes))
                _, (listener, status) = self._notes.popitem(last=False)
            try:
                listener(status)
            except Exception:  # one session's failure must not silence the others
                log.exception("telling a waiter of a shared job failed")
