"""Run the parsers (scipy MAT v5, h5py, the text formats) outside this process.

See :mod:`fbs_core.io._worker` for why: both libraries crash or hang on some
malformed files. A few long-lived worker interpreters (:data:`PARSERS`, ``FBS_PARSERS``)
are started on first use; each forks a child per file, so a crash, a hang (killed after
``timeout``) or a memory blow-up (``RLIMIT_AS``) ends in
:class:`~fbs_core.errors.DataFormatError` here.

Several files are parsed at once, one per worker; a caller waits for a free worker. A
caller may be cancelled while it waits or while its file is parsed (:func:`cancel_scope`:
a closed browser tab stops its parse): the worker and its child are then killed and
started again for the next file. Each worker leads a process group of its own with its
forked child, so a server stopping kills both (``os.killpg``), and a worker whose parent
died (its pipe closed) kills its child and ends.
"""

from __future__ import annotations

import atexit
import contextlib
import json
import os
import select
import signal
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any, overload

import numpy as np

from ..errors import DataFormatError
from ._worker import array_specs

__all__ = [
    "Cancelled",
    "DEFAULT_TIMEOUT",
    "MAX_RESULT_BYTES",
    "PARSERS",
    "cancel_scope",
    "parse_isolated",
]

#: Seconds a single file may take to parse.
DEFAULT_TIMEOUT = 30.0

#: Largest total size of the arrays one file may yield (256 MiB): far more than the
#: dashboard can show (a 12 x 6 mobility at 100,000 lines is 115 MB), far less than the
#: memory a hostile file could otherwise claim in the server process.
MAX_RESULT_BYTES = 256 << 20

#: Files parsed at once in the process (worker interpreters), unless ``FBS_PARSERS`` says.
PARSERS = 2
PARSERS_ENV = "FBS_PARSERS"
#: How much the parser processes lower their CPU priority (nice value): a parse gets the
#: cores the server's threads and the scatter bands (nice 10) leave.
PARSER_NICE = 15
#: Seconds between two looks at a caller's cancel flag.
CANCEL_POLL_S = 0.1

_U64 = struct.Struct("<Q")
_WORKER = Path(__file__).with_name("_worker.py")


class Cancelled(Exception):  # noqa: N818  (a signal, not an error of the input)
    """The caller's parse was cancelled (:func:`cancel_scope`) before it finished."""


_SCOPE = threading.local()


@contextlib.contextmanager
def cancel_scope(cancelled: threading.Event) -> Iterator[None]:
    """Parses started by this thread inside the block stop when ``cancelled`` is set:
    :func:`parse_isolated` then raises :class:`Cancelled` (while waiting for a worker, or
    with the worker killed while it parses)."""
    outer = getattr(_SCOPE, "event", None)
    _SCOPE.event = cancelled
    try:
        yield
    finally:
        _SCOPE.event = outer


def _cancelled() -> bool:
    event = getattr(_SCOPE, "event", None)
    return event is not None and event.is_set()


def parsers() -> int:
    """Worker interpreters of the process: :data:`PARSERS` or ``$FBS_PARSERS`` (1-16)."""
    raw = os.environ.get(PARSERS_ENV, "").strip()
    return int(raw) if raw.isdigit() and 1 <= int(raw) <= 16 else PARSERS


class _Worker:
    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.proc: subprocess.Popen[bytes] | None = None
        self.owner = os.getpid()

    def _start(self) -> subprocess.Popen[bytes]:
        if self.owner != os.getpid():
            # a forked copy of this process: the pipes belong to the parent, leave them
            self.proc, self.owner = None, os.getpid()
        if self.proc is None or self.proc.poll() is not None:
            self.proc = subprocess.Popen(
                [sys.executable, "-s", "-P", str(_WORKER), "--nice", str(PARSER_NICE)],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=subprocess.DEVNULL,
                cwd=tempfile.gettempdir(),
                start_new_session=True,  # its own process group, with its forked parser
            )
        return self.proc

    def stop(self) -> None:
        """Kill the worker and its forked parser (its process group)."""
        if self.owner != os.getpid():
            return
        proc = self.proc
        if proc is not None and proc.poll() is None:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                proc.kill()
            proc.wait()
        for pipe in (proc.stdin, proc.stdout) if proc is not None else ():
            if pipe is not None:
                with contextlib.suppress(OSError):
                    pipe.close()
        self.proc = None

    @overload
    def _read(self, fd: int, n: int, deadline: float, into: None = None) -> bytes: ...
    @overload
    def _read(self, fd: int, n: int, deadline: float, into: memoryview) -> None: ...
    def _read(
        self, fd: int, n: int, deadline: float, into: memoryview | None = None
    ) -> bytes | None:
        """``n`` bytes from the pipe, as bytes or straight into ``into``."""
        buf = bytearray()
        got = 0
        while got < n:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError
            if _cancelled():
                raise Cancelled
            ready, _, _ = select.select([fd], [], [], min(left, CANCEL_POLL_S))
            if ready:
                chunk = os.read(fd, min(n - got, 1 << 20))
                if not chunk:
                    raise EOFError
                if into is None:
                    buf += chunk
                else:
                    into[got : got + len(chunk)] = chunk
                got += len(chunk)
        return bytes(buf) if into is None else None

    def request(
        self, kind: str, raw: bytes, timeout: float, mem_bytes: int, limit: int
    ) -> tuple[int, bytes | tuple[dict[str, Any], list[np.ndarray]]]:
        """Send one file; returns ``(0, (meta, arrays))`` or ``(status, message bytes)``.

        The arrays are read from the pipe straight into arrays allocated here (one copy
        of the data in this process); a reply larger than ``limit`` or not matching its
        own header stops the worker instead of being read.
        """
        # the caller holds self.lock (_Pool.worker)
        proc = self._start()
        assert proc.stdin is not None and proc.stdout is not None  # both PIPE
        head = kind.ljust(8).encode() + b"".join(
            _U64.pack(v) for v in (int(timeout * 1000), int(mem_bytes), int(limit), len(raw))
        )
        try:
            proc.stdin.write(head)
            proc.stdin.write(raw)
            proc.stdin.flush()
            # the worker enforces ``timeout`` itself; allow for its start-up on top
            deadline = time.monotonic() + timeout + 60.0
            fd = proc.stdout.fileno()
            status, n = (_U64.unpack(self._read(fd, 8, deadline))[0] for _ in range(2))
            if status != 0:
                if n > 1 << 20:
                    raise ValueError("message too long")
                return status, self._read(fd, n, deadline)
            if n > limit + (64 << 20):
                raise ValueError(f"reply of {n} bytes")
            (hlen,) = _U64.unpack(self._read(fd, 8, deadline))
            if hlen > min(n, 64 << 20):
                raise ValueError("header too long")
            meta = json.loads(self._read(fd, hlen, deadline).decode())
            specs = array_specs(meta)
            sizes = [dt.itemsize * int(np.prod(shape, dtype=np.int64)) for dt, shape in specs]
            if 8 + hlen + sum(sizes) != n or sum(sizes) > limit:
                raise ValueError("reply does not match its header")
            arrays = []
            for (dt, shape), size in zip(specs, sizes, strict=True):
                a = np.empty(shape, dt)
                self._read(fd, size, deadline, a.reshape(-1).view(np.uint8).data)
                arrays.append(a)
            return 0, (meta, arrays)
        except Cancelled:
            self.stop()  # its parse is abandoned: the next file gets a fresh worker
            raise
        except (OSError, EOFError, TimeoutError):
            self.stop()
            return 2, b"the parser process stopped unexpectedly"
        except (ValueError, TypeError, KeyError, AttributeError, OverflowError) as e:
            self.stop()  # the stream is out of step: never reuse this worker
            return 2, f"unreadable parser reply ({e})".encode()


class _Pool:
    """The worker interpreters; a caller takes a free one or waits (cancellably)."""

    def __init__(self) -> None:
        self.workers: list[_Worker] = []
        self._cond = threading.Condition()

    @contextlib.contextmanager
    def worker(self) -> Iterator[_Worker]:
        with self._cond:
            if not self.workers:
                self.workers = [_Worker() for _ in range(parsers())]
            while True:
                free = next((w for w in self.workers if w.lock.acquire(blocking=False)), None)
                if free is not None:
                    break
                if _cancelled():
                    raise Cancelled
                self._cond.wait(CANCEL_POLL_S)
        try:
            yield free
        finally:
            free.lock.release()
            with self._cond:
                self._cond.notify()

    def stop(self) -> None:
        for w in self.workers:
            w.stop()

    def after_fork(self) -> None:
        # a forked child starts its own workers; the parent's stay the parent's
        self.workers = []
        self._cond = threading.Condition()


_pool = _Pool()
atexit.register(_pool.stop)
os.register_at_fork(after_in_child=_pool.after_fork)


def parse_isolated(
    kind: str,
    raw: bytes,
    what: str,
    *,
    timeout: float = DEFAULT_TIMEOUT,
    mem_bytes: int | None = None,
    max_result_bytes: int | None = None,
) -> tuple[dict[str, Any], list[np.ndarray]]:
    """Parse ``raw`` with handler ``kind`` ("mat5", "hdf5", "uff", "csv", "table") in the sandbox.

    Parameters
    ----------
    kind : {"mat5", "hdf5", "uff", "csv", "table"}
    raw : bytes
        File content.
    what : str
        How to name the file in messages, e.g. ``"MATLAB file 'chassis.mat'"``.
    timeout : float
        Seconds before the parser is killed.
    mem_bytes : int, optional
        Extra address space the parser may use; default ``1 GiB + 4 x len(raw)``.
    max_result_bytes : int, optional
        Largest total size of the arrays that may come back (default
        :data:`MAX_RESULT_BYTES`); the parsers check the sizes a file announces before
        reading its data, so a small compressed file cannot make the server allocate
        gigabytes.

    Returns
    -------
    meta : dict
        JSON-compatible description of the content.
    arrays : list of ndarray
        Numeric arrays referenced from ``meta`` by position.

    Raises
    ------
    DataFormatError
        If the file cannot be parsed, crashes the parser, takes too long or holds more
        numbers than allowed (the message names the limit that was hit).
    Cancelled
        When the caller's :func:`cancel_scope` was cancelled meanwhile.
    """
    if mem_bytes is None:
        mem_bytes = (1 << 30) + 4 * len(raw)
    limit = MAX_RESULT_BYTES if max_result_bytes is None else int(max_result_bytes)
    if _cancelled():
        raise Cancelled
    with _pool.worker() as worker:
        status, payload = worker.request(kind, raw, float(timeout), int(mem_bytes), limit)
    if status == 0:
        assert not isinstance(payload, bytes)
        return payload
    assert isinstance(payload, bytes)
    msg = payload.decode("utf-8", "replace")
    if status == 1:
        raise DataFormatError(f"{what} cannot be read: {msg}")
    if status == 4:
        raise DataFormatError(f"{what} is damaged or not what its name says (parser: {msg})")
    if status == 3:
        raise DataFormatError(
            f"{what} cannot be read: {msg}, the time limit for one file (it is too large or "
            "too deeply structured to read in that time)"
        )
    raise DataFormatError(
        f"{what} cannot be read: {msg}; the file is damaged, or its parsing needed more than "
        f"the {mem_bytes / 2**20:,.0f} MiB of memory one file may use"
    )
