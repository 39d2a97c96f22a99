"""Uploads are read off Panel's worker threads, bounded per session, stopped with their tab
(issue 28, finding 3), by parser processes that run side by side and end with the server.

The queue (:mod:`app.runtime.uploads`) is checked with jobs that wait on events (what runs, in
which order, what is refused or cancelled); the sandbox (:mod:`fbs_core.io._sandbox`) with
real files: a slow UFF (a few thousand datasets 58, made here as text) and small files.
"""

from __future__ import annotations

import threading
import time

import pytest
from server_util import process_tree, running, wait_for

from app.runtime.uploads import UploadQueue
from fbs_core.errors import DataFormatError
from fbs_core.io import _sandbox
from fbs_core.io._sandbox import Cancelled, cancel_scope, parse_isolated

# ---- the queue ------------------------------------------------------------------------------


class _Jobs:
    """Jobs that record when they run and wait until released."""

    def __init__(self):
        self.ran: list[str] = []
        self.release = threading.Event()
        self.refusals: list[str] = []

    def job(self, name):
        def run():
            self.ran.append(name)
            self.release.wait(30)

        return run

    def refused(self, message):
        self.refusals.append(message)


def test_one_waiting_reading_per_session_and_slot_in_arrival_order():
    q, j = UploadQueue(threads=1, max_waiting=3), _Jobs()
    a, b = object(), object()
    q.submit(a, "chassis", j.job("a1"), j.refused)
    wait_for(lambda: j.ran == ["a1"], 10, what="the first job running")
    replaced = q.submit(a, "chassis", j.job("a2"), j.refused)
    q.submit(b, "chassis", j.job("b1"), j.refused)
    q.submit(a, "chassis", j.job("a3"), j.refused)  # replaces a2, queued behind b1
    q.submit(a, "tire", j.job("a-tire"), j.refused)  # another slot: waits too
    assert replaced.cancelled.is_set() and q.waiting == 3
    # the queue is full: refused at once, with a message
    assert q.submit(b, "tire", j.job("b-tire"), j.refused) is None
    assert j.refusals and "reading 3 other uploads" in j.refusals[0]
    j.release.set()
    wait_for(lambda: q.waiting == 0 and q.running == 0, 30, what="the queue empty")
    assert j.ran == ["a1", "b1", "a3", "a-tire"]


def test_a_closed_tab_cancels_its_waiting_and_running_readings():
    q, j = UploadQueue(threads=1), _Jobs()
    a, b = object(), object()
    running_job = q.submit(a, "chassis", j.job("a1"), j.refused)
    wait_for(lambda: j.ran == ["a1"], 10, what="the first job running")
    waiting = q.submit(a, "tire", j.job("a2"), j.refused)
    other = q.submit(b, "chassis", j.job("b1"), j.refused)
    assert q.cancel(a) == 2
    assert running_job.cancelled.is_set() and waiting.cancelled.is_set()
    assert not other.cancelled.is_set()
    j.release.set()
    wait_for(lambda: other.done.is_set(), 30, what="the other session's reading")
    assert j.ran == ["a1", "b1"]


def test_a_failing_reading_does_not_stop_the_queue():
    q = UploadQueue(threads=1)
    ran = []

    def bad():
        raise RuntimeError("boom")

    q.submit(object(), "chassis", bad, print)
    job = q.submit(object(), "chassis", lambda: ran.append(1), print)
    wait_for(job.done.is_set, 30, what="the next reading")
    assert ran == [1]


# ---- the sandbox ------------------------------------------------------------------------------

RECORD = """    -1
    58
mobility {o}:z / {i}:z
tire-fbs test
03-Dec-26 10:50:18
NONE
NONE
    4         0    0         0 {o:>10s}         1   3 {i:>10s}         2   3
         6         3         1  1.00000e+00  1.00000e+00  0.00000e+00
        18    0    0    0 NONE                 Hz
        11    1    0    0 NONE                 m/s
        13    0    1    0 NONE                 N
         0    0    0    0 NONE                 NONE
   1.00000000000e-03   0.00000000000e+00   1.00000000000e-03   0.00000000000e+00
   1.00000000000e-03   0.00000000000e+00
    -1
"""


def slow_uff(n: int) -> bytes:
    """A valid UFF of ``n`` datasets 58 (three lines each): seconds to parse per 10,000."""
    return "".join(RECORD.format(o=f"n{k % 100}", i=f"m{k // 100}") for k in range(n)).encode()


def test_the_slow_file_is_valid():
    meta, arrays = parse_isolated("uff", slow_uff(300), "t")
    assert sum(a.size for a in arrays) >= 300 * 3


def test_parses_run_side_by_side_and_a_cancelled_one_ends_its_processes():
    assert _sandbox.parsers() >= 2
    slow = slow_uff(40_000)
    small = slow_uff(3)
    cancel = threading.Event()
    outcome = {}

    def long_parse():
        t0 = time.monotonic()
        try:
            with cancel_scope(cancel):
                parse_isolated("uff", slow, "slow.uff", timeout=120)
            outcome["long"] = "finished"
        except Cancelled:
            outcome["long"] = "cancelled"
        except DataFormatError as e:
            outcome["long"] = str(e)
        outcome["long_s"] = time.monotonic() - t0

    t = threading.Thread(target=long_parse)
    t.start()
    wait_for(lambda: any(w.lock.locked() for w in _sandbox._pool.workers), 30, what="busy")
    # another file is read while the slow one occupies a parser
    meta, arrays = parse_isolated("uff", small, "small.uff")
    assert arrays and "long" not in outcome
    busy = [w for w in _sandbox._pool.workers if w.lock.locked()]
    (worker,) = busy
    wait_for(lambda: len(process_tree(worker.proc.pid)) >= 2, 30, what="the forked parser")
    tree = process_tree(worker.proc.pid)
    cancel.set()
    t.join(60)
    assert outcome["long"] == "cancelled", outcome
    assert outcome["long_s"] < 60  # long before its 120 s limit
    wait_for(lambda: not any(running(p) for p in tree), 10, what="worker and parser ended")
    # the next file gets a fresh worker
    meta, arrays = parse_isolated("uff", small, "small.uff")
    assert arrays


def test_a_parse_waiting_for_a_parser_can_be_cancelled(monkeypatch):
    monkeypatch.setattr(_sandbox, "_pool", _sandbox._Pool())
    monkeypatch.setenv(_sandbox.PARSERS_ENV, "1")
    slow = slow_uff(40_000)
    first_cancel, second_cancel = threading.Event(), threading.Event()
    outcome = {}

    def parse(name, event):
        try:
            with cancel_scope(event):
                parse_isolated("uff", slow, name, timeout=120)
            outcome[name] = "finished"
        except Cancelled:
            outcome[name] = "cancelled"

    a = threading.Thread(target=parse, args=("a", first_cancel))
    a.start()
    wait_for(lambda: any(w.lock.locked() for w in _sandbox._pool.workers), 30, what="busy")
    b = threading.Thread(target=parse, args=("b", second_cancel))
    b.start()
    second_cancel.set()  # b waits for the only parser: cancelled while waiting
    b.join(30)
    assert outcome.get("b") == "cancelled" and "a" not in outcome
    first_cancel.set()
    a.join(60)
    assert outcome["a"] == "cancelled"
    _sandbox._pool.stop()


# ---- refusals that say which limit was hit ----------------------------------------------------


def test_a_deeply_nested_hdf5_file_names_the_nesting_limit():
    import io

    import h5py
    import numpy as np

    from fbs_core.io import load_frf

    b = io.BytesIO()
    with h5py.File(b, "w") as h:
        g = h
        for k in range(3000):
            g = g.create_group(f"g{k}")
        h.create_dataset("freq", data=np.arange(1.0, 4.0))
    with pytest.raises(DataFormatError, match="nested more than 64 levels deep"):
        load_frf(b.getvalue(), filename="nested.h5")


def test_a_timeout_names_the_time_limit():
    from fbs_core.io import load_frf

    with pytest.raises(DataFormatError, match="time limit for one file") as err:
        load_frf(slow_uff(20_000), filename="many.uff", timeout=0.5)
    assert "corrupt" not in str(err.value)


def test_a_csv_with_cr_line_ends_is_read():
    from fbs_core.io import load_frf

    text = (
        "# tire-fbs FRF\r# quantity: mobility\r"
        "freq [Hz],Re(a:z / b:z),Im(a:z / b:z)\r1,1e-3,0\r2,2e-3,1e-4\r"
    )
    frf = load_frf(text.encode(), filename="mac.csv").frf
    assert frf.shape == (2, 1, 1) and abs(frf.data[1, 0, 0] - (2e-3 + 1e-4j)) < 1e-15


def test_a_csv_wider_than_the_column_limit_is_refused_in_the_sandbox():
    from fbs_core.io import load_frf
    from fbs_core.io._textparse import MAX_COLUMNS

    cols = ["freq [Hz]"] + [f"Re(n{k}:z / s:z),Im(n{k}:z / s:z)" for k in range(MAX_COLUMNS // 2)]
    text = "# quantity: mobility\n" + ",".join(cols) + "\n" + "1" + ",0" * MAX_COLUMNS + "\n"
    with pytest.raises(DataFormatError, match="20,001 columns .* more than the 20,000"):
        load_frf(text.encode(), filename="wide.csv")
