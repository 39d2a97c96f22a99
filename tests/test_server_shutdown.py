"""The server ends promptly on SIGTERM, whatever work is running or queued (issue 20, 9).

``docker stop`` sends SIGTERM and kills the container 10 s later. The dashboard runs long
computations (Monte-Carlo bands) on worker threads, and Python waits at exit for every
worker thread of a ``concurrent.futures`` pool to finish its queue: after heavy use the
server took 36-39 s to exit. Here a served page queues a minute of work on the event
loop's executor (as the scatter band does, ``asyncio.to_thread``) and on Panel's thread
pool, and starts a child process (as the file-parser sandbox does); once that work runs,
SIGTERM must end the server within docker's grace period and leave no child behind.
"""

from __future__ import annotations

import signal
import subprocess
import time
import urllib.request

import pytest
from server_util import Server, get, running, wait_for

#: docker stop's default grace period (s).
DOCKER_STOP_GRACE_S = 10.0

APP = """
import asyncio, os, subprocess, sys, time
from pathlib import Path
import panel as pn

here = Path(__file__).parent

def busy(name):
    (here / f"busy-{name}-{os.getpid()}-{time.monotonic_ns()}").touch()
    end = time.monotonic() + 60
    while time.monotonic() < end:
        sum(range(10_000))

ctx = pn.state.curdoc.session_context
if ctx is not None and ctx.server_context is not None:  # a served page, not the start-up proof
    loop = asyncio.get_event_loop()
    for k in range(8):  # more than the executor's threads: some are queued
        loop.run_in_executor(None, busy, f"loop{k}")
        pn.state.execute(lambda k=k: busy(f"panel{k}"), schedule="thread")
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
    (here / "child.pid").write_text(str(child.pid))
pn.Column("# busy page", pn.widgets.IntSlider(name="k", value=2)).servable()
"""


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_stop_signal_ends_a_busy_server_promptly(tmp_path, sig):
    srv = Server(tmp_path, APP, {"FBS_NUM_THREADS": "2"}, name="busy").started()
    child = None
    try:
        opener = urllib.request.build_opener()
        status, _, body = get(opener, srv.base + "/busy")
        assert status == 200 and "render_items" in body
        pid_file = tmp_path / "child.pid"
        child = int(wait_for(pid_file.exists, 60, what="child started") and pid_file.read_text())
        wait_for(lambda: len(list(tmp_path.glob("busy-*"))) >= 2, 60, what="work running")
        t0 = time.monotonic()
        srv.proc.send_signal(sig)
        try:
            srv.proc.wait(DOCKER_STOP_GRACE_S)
        except subprocess.TimeoutExpired:
            pytest.fail(f"the server did not end within {DOCKER_STOP_GRACE_S:.0f} s of {sig!r}")
        print(f"{sig.name}: ended after {time.monotonic() - t0:.2f} s")
        wait_for(lambda: not running(child), 5, what="the child process ended")
        assert "stopping the server" in srv.log()
    finally:
        srv.stop()
        if child is not None and running(child):
            import os

            os.kill(child, signal.SIGKILL)


# a page starts a child in a process group of its own that forks a busy grandchild, as the
# file-parser sandbox does for a parse (issue 28: SIGTERM during a parse left the parser
# running for minutes, orphaned)
GROUP_APP = """
import subprocess, sys
from pathlib import Path
import panel as pn

here = Path(__file__).parent
CODE = '''
import os, sys, time
pid = os.fork()
if pid == 0:
    while True:
        sum(range(10_000))
open(sys.argv[1], "w").write(str(pid))
time.sleep(600)
'''
ctx = pn.state.curdoc.session_context
if ctx is not None and ctx.server_context is not None:  # a served page
    subprocess.Popen(
        [sys.executable, "-c", CODE, str(here / "grandchild.pid")], start_new_session=True
    )
pn.Column("# parsing page").servable()
"""


def test_stop_signal_ends_the_process_group_of_a_child(tmp_path):
    import os

    srv = Server(tmp_path, GROUP_APP, {}, name="group").started()
    grandchild = None
    try:
        status, _, body = get(urllib.request.build_opener(), srv.base + "/group")
        assert status == 200 and "render_items" in body
        pid_file = tmp_path / "grandchild.pid"
        wait_for(lambda: pid_file.exists() and pid_file.read_text(), 60, what="parser forked")
        grandchild = int(pid_file.read_text())
        assert running(grandchild)
        srv.proc.send_signal(signal.SIGTERM)
        srv.proc.wait(DOCKER_STOP_GRACE_S)
        wait_for(lambda: not running(grandchild), 5, what="the forked grandchild ended")
    finally:
        srv.stop()
        if grandchild is not None and running(grandchild):
            os.kill(grandchild, signal.SIGKILL)


# a page keeps the report process busy drawing PDF reports, as a tab asking for reports in a
# loop does; its processes carry a marker in their environment (inherited by every process
# the server starts after the page set it)
REPORT_APP = """
import os, threading
from pathlib import Path
import panel as pn

here = Path(__file__).parent
ctx = pn.state.curdoc.session_context
if ctx is not None and ctx.server_context is not None and not (here / "started").exists():
    (here / "started").touch()
    os.environ["FBS_TEST_REPORT_MARK"] = str(here)
    from app.report import ReportData
    from app.runtime import reports

    SETTINGS = dict(harmonic=1, n_modes=20, dof="z", coupling="6dof", threshold=20.0,
                    f_max=40.0, map_mode="selected DOF", noise=10.0, target="both",
                    frequency_dependent=False, rounds=300, seed=3, single_round=7,
                    percentile=90)

    # the loop outlives the page's session, whose end clears this module's globals
    def reports_in_a_loop(here=here, reports=reports, ReportData=ReportData, SETTINGS=SETTINGS):
        k = 0
        while True:
            try:
                reports.draw_apart("pdf", ReportData(settings=SETTINGS))
            except Exception as exc:  # the server stopping: no more reports
                (here / "ended").write_text(repr(exc))
                return
            k += 1
            (here / f"drawn-{k}").touch()

    threading.Thread(target=reports_in_a_loop, daemon=True).start()
pn.Column("# report page").servable()
"""


def _marked(mark: str) -> list[int]:
    """PIDs of the processes whose environment holds ``FBS_TEST_REPORT_MARK=mark``."""
    import os

    want = f"FBS_TEST_REPORT_MARK={mark}".encode()
    out = []
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/environ", "rb") as f:
                if want in f.read().split(b"\0"):
                    out.append(int(d))
        except OSError:
            continue
    return out


def test_stop_signal_while_a_report_is_drawn_leaves_no_report_process(tmp_path):
    """SIGTERM while the report process draws: the server ends it and starts no other
    (before: the pool broke when its process was stopped, and the report thread started a
    new process after the server had listed its children: an orphan)."""
    import os

    srv = Server(tmp_path, REPORT_APP, {}, name="reports").started()
    mark = str(tmp_path)
    try:
        status, _, body = get(urllib.request.build_opener(), srv.base + "/reports")
        assert status == 200 and "render_items" in body
        wait_for(lambda: list(tmp_path.glob("drawn-*")), 180, what="a report drawn")
        wait_for(lambda: _marked(mark), 30, what="the report process")  # drawing the next
        srv.proc.send_signal(signal.SIGTERM)
        srv.proc.wait(DOCKER_STOP_GRACE_S)
        left = []

        def none_left():
            left[:] = [p for p in _marked(mark) if running(p)]
            return not left

        wait_for(none_left, 10, what="no report process left")
    finally:
        srv.stop()
        for pid in _marked(mark):
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
