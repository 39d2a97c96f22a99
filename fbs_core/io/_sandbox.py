"""Run the binary parsers (scipy MAT v5, h5py) outside this process.

See :mod:`fbs_core.io._worker` for why: both libraries crash or hang on some
malformed files. One long-lived worker interpreter is started on first use; it
forks a child per file, so a crash, a hang (killed after ``timeout``) or a memory
blow-up (``RLIMIT_AS``) ends in :class:`~fbs_core.errors.DataFormatError` here.
"""

from __future__ import annotations

import atexit
import os
import select
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from ..errors import DataFormatError
from ._worker import decode

__all__ = ["parse_isolated", "DEFAULT_TIMEOUT"]

#: Seconds a single file may take to parse.
DEFAULT_TIMEOUT = 30.0

_U64 = struct.Struct("<Q")
_WORKER = Path(__file__).with_name("_worker.py")


class _Worker:
    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.proc: subprocess.Popen | None = None
        self.owner = os.getpid()

    def _start(self) -> subprocess.Popen:
        if self.owner != os.getpid():
            # a forked copy of this process: the pipes belong to the parent, leave them
            self.proc, self.owner = None, os.getpid()
        if self.proc is None or self.proc.poll() is not None:
            self.proc = subprocess.Popen(
                [sys.executable, "-s", "-P", str(_WORKER)],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=subprocess.DEVNULL,
                cwd=tempfile.gettempdir(),
            )
        return self.proc

    def stop(self) -> None:
        if self.owner != os.getpid():
            return
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        self.proc = None

    def _read(self, fd: int, n: int, deadline: float) -> bytes:
        buf = bytearray()
        while len(buf) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError
            ready, _, _ = select.select([fd], [], [], left)
            if ready:
                chunk = os.read(fd, min(n - len(buf), 1 << 20))
                if not chunk:
                    raise EOFError
                buf += chunk
        return bytes(buf)

    def request(self, kind: str, raw: bytes, timeout: float, mem_bytes: int) -> tuple[int, bytes]:
        with self.lock:
            proc = self._start()
            head = kind.ljust(8).encode() + b"".join(
                _U64.pack(v) for v in (int(timeout * 1000), int(mem_bytes), len(raw))
            )
            try:
                proc.stdin.write(head + raw)
                proc.stdin.flush()
                # the worker enforces ``timeout`` itself; allow for its start-up on top
                deadline = time.monotonic() + timeout + 60.0
                fd = proc.stdout.fileno()
                status, n = (_U64.unpack(self._read(fd, 8, deadline))[0] for _ in range(2))
                return status, self._read(fd, n, deadline)
            except (OSError, EOFError, TimeoutError):
                self.stop()
                return 2, b"the parser process stopped unexpectedly"


_worker = _Worker()
atexit.register(_worker.stop)


def _after_fork() -> None:
    # a forked child gets a fresh lock and its own worker; the parent's stays its own
    _worker.lock = threading.Lock()
    _worker.proc, _worker.owner = None, os.getpid()


os.register_at_fork(after_in_child=_after_fork)


def parse_isolated(
    kind: str,
    raw: bytes,
    what: str,
    *,
    timeout: float = DEFAULT_TIMEOUT,
    mem_bytes: int | None = None,
) -> tuple[dict, list[np.ndarray]]:
    """Parse ``raw`` with handler ``kind`` ("mat5" or "hdf5") in the sandbox.

    Parameters
    ----------
    kind : {"mat5", "hdf5"}
    raw : bytes
        File content.
    what : str
        How to name the file in messages, e.g. ``"MATLAB file 'chassis.mat'"``.
    timeout : float
        Seconds before the parser is killed.
    mem_bytes : int, optional
        Extra address space the parser may use; default ``max(1 GiB, 20 x len(raw))``.

    Returns
    -------
    meta : dict
        JSON-compatible description of the content.
    arrays : list of ndarray
        Numeric arrays referenced from ``meta`` by position.

    Raises
    ------
    DataFormatError
        If the file cannot be parsed, crashes the parser or takes too long.
    """
    if mem_bytes is None:
        mem_bytes = max(1 << 30, 20 * len(raw))
    status, payload = _worker.request(kind, bytes(raw), float(timeout), int(mem_bytes))
    if status == 0:
        try:
            return decode(payload)
        except Exception as e:  # a compromised parser could send anything
            raise DataFormatError(f"{what}: unreadable parser reply ({e})") from None
    msg = payload.decode("utf-8", "replace")
    if status == 1:
        raise DataFormatError(f"{what} cannot be read: {msg}")
    if status == 4:
        raise DataFormatError(f"{what} is damaged or not what its name says (parser: {msg})")
    raise DataFormatError(f"{what} cannot be read: {msg}; the file is probably corrupt")
