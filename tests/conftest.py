"""Session-wide hooks of the test suite."""

from __future__ import annotations

import os
import sys
import threading

#: Longest wait for a left-over server thread to stop at the end of the session (s).
STOP_WAIT_S = 30.0

_status: list[int] = []


def pytest_sessionfinish(session, exitstatus):
    """Stop the Panel server threads still running when the session ends, and name them.

    A page served in the test process runs on a thread that is not a daemon
    (``pn.serve(threaded=True)``, ``tests/server_util.served_in_process``); one left running
    kept the interpreter from exiting after the summary (the whole suite had passed, and the
    run waited until CI's time was up).
    """
    _status.append(int(exitstatus))
    if "panel" not in sys.modules:
        return
    from panel.io.threads import StoppableThread

    for t in [t for t in threading.enumerate() if isinstance(t, StoppableThread)]:
        if not t.is_alive():
            continue
        sys.stderr.write(f"\nstopping a Panel server thread left running: {t.name}\n")
        stopper = threading.Thread(target=t.stop, name=f"stop-{t.name}", daemon=True)
        stopper.start()
        stopper.join(STOP_WAIT_S)


def pytest_unconfigure(config):
    """After the summary: a Panel server thread that would not stop keeps the process alive
    for ever (it is not a daemon); name it and end the process with the session's status."""
    if "panel" not in sys.modules or not _status:
        return
    from panel.io.threads import StoppableThread

    left = [t for t in threading.enumerate() if isinstance(t, StoppableThread) and t.is_alive()]
    if left:
        names = ", ".join(sorted(t.name for t in left))
        sys.stderr.write(f"\nPanel server threads still running after the tests: {names}\n")
        sys.stderr.flush()
        sys.stdout.flush()
        os._exit(_status[-1])
