"""The server's proof steps aside while users' pages open (issue 33: the first page).

``docker/page_gate.py`` (the gate: pages opening, bounded waits), its use by the server's
proof (a real server: the proof waits at a safe point of the app until the user's page says
it is shown), and the app's safe points (``app/runtime/pace.py``): a page of a user is built
while the proof waits at any of them (paused inside a computation the pages share, the proof
held a user's page back until its hold ran out: 13 s).
"""

from __future__ import annotations

import asyncio
import json
import sys
import threading
import time
import urllib.request

import panel  # noqa: F401 (a page's replica holds Panel's models)
from server_util import ROOT, NoRedirect, PageClient, Server, get, in_own_loop, wait_for

sys.path.insert(0, str(ROOT / "docker"))
from page_gate import PageGate  # noqa: E402


def _waiter(gate: PageGate) -> tuple[threading.Thread, dict]:
    out: dict = {}

    def run() -> None:
        t0 = time.monotonic()
        out["again"] = gate.wait()
        out["waited"] = time.monotonic() - t0

    t = threading.Thread(target=run, daemon=True)
    t.start()
    return t, out


def test_nothing_opening_no_wait():
    gate = PageGate()
    assert gate.wait() is True and gate.waited_s < 1


def test_the_proof_waits_until_the_page_is_shown():
    gate = PageGate(hold_s=600, budget_s=600)
    gate.opened("a")
    gate.opened("b")
    t, out = _waiter(gate)
    wait_for(gate.waiting, 30, what="the proof waiting")
    gate.shown("a")  # one of two pages shown: still waiting
    wait_for(lambda: gate.opening() == 1, 30)
    assert t.is_alive() and gate.waiting()
    gate.shown("b")
    t.join(30)
    assert not t.is_alive() and out["again"] is True
    assert gate.opening() == 0 and not gate.waiting()


def test_a_page_that_is_never_shown_holds_the_proof_for_hold_s_only():
    gate = PageGate(hold_s=0.3, budget_s=600)
    t0 = time.monotonic()
    gate.opened("bare http request")
    t, out = _waiter(gate)
    t.join(60)
    assert not t.is_alive() and out["again"] is True
    assert time.monotonic() - t0 >= 0.3 and gate.opening() == 0


def test_the_proof_yields_its_budget_at_most():
    gate = PageGate(hold_s=600, budget_s=0.3)
    gate.opened("x")
    t, out = _waiter(gate)
    t.join(60)
    assert not t.is_alive() and out["again"] is False  # spent: no need to ask again
    assert out["waited"] >= 0.3
    t0 = time.monotonic()
    assert gate.wait() is False and time.monotonic() - t0 < 1  # runs beside pages now


def test_retiring_the_gate_frees_a_waiter_and_ends_tracking():
    gate = PageGate(hold_s=600, budget_s=600)
    gate.opened("x")
    t, out = _waiter(gate)
    wait_for(gate.waiting, 30, what="the proof waiting")
    gate.retire()
    t.join(30)
    assert not t.is_alive() and out["again"] is False
    gate.opened("later")  # sessions after the proof are not tracked
    assert gate.opening() == 0


def test_a_session_opens_until_document_ready_or_its_end():
    from bokeh.document import Document
    from bokeh.events import DocumentReady
    from panel.io.state import set_curdoc

    class Context:  # what watch_session reads of Bokeh's session context
        def __init__(self, key):
            self.id = key

    gate = PageGate()
    shown, closed = Document(), Document()
    for key, doc in (("shown", shown), ("closed", closed)):
        with set_curdoc(doc):  # as Panel runs session-created callbacks
            gate.watch_session(Context(key))
    assert gate.opening() == 2
    # shown, then its on-load callbacks (here, outside a server, at once; with a server
    # after the page's own: test_the_server_proof_steps_aside_for_a_page_opened_meanwhile)
    shown.callbacks.trigger_event(DocumentReady())
    wait_for(lambda: gate.opening() == 1, 30, what="the shown page's on-load callbacks")
    for callback in closed.session_destroyed_callbacks:
        callback(None)
    assert gate.opening() == 0


def test_the_server_proof_steps_aside_for_a_page_opened_meanwhile(tmp_path):
    """A real server: its proof builds the app's page; a user's page opens meanwhile; the
    proof, at the app's next safe point, waits until that page is shown and its own on-load
    work done, then goes on and the app is reported proved. Bokeh runs one app script at a
    time (a process-wide lock): the user's page is built once the proof, busy in its
    script, reaches that safe point, where it lets the user's script run."""
    notes, gate_file = tmp_path / "notes.txt", tmp_path / "gate"
    onload_gate = tmp_path / "onload-gate"
    app = (
        "import pathlib, threading, time\n"
        "import panel as pn\n"
        f"notes = pathlib.Path({str(notes)!r})\n"
        "def note(s):\n"
        "    with notes.open('a') as f:\n"
        "        f.write(s + '\\n')\n"
        "thread = threading.current_thread()\n"
        "if thread.name == 'fbs-prove-apps':\n"
        "    note('proof builds')\n"
        f"    gate = pathlib.Path({str(gate_file)!r})\n"
        "    t0 = time.monotonic()\n"
        "    while not gate.exists() and time.monotonic() - t0 < 300:\n"
        "        time.sleep(0.02)\n"
        "    step = getattr(thread, 'step_aside', None)\n"
        "    note(f'proof at a safe point ({step is not None})')\n"
        "    if step is not None:\n"
        "        step()\n"
        "    note('proof goes on')\n"
        "else:\n"
        "    note('page builds')\n"
        "    def below():  # the page's own on-load work (the dashboard: below the screen)\n"
        "        note('page on-load starts')\n"
        f"        more = pathlib.Path({str(onload_gate)!r})\n"
        "        t0 = time.monotonic()\n"
        "        while not more.exists() and time.monotonic() - t0 < 300:\n"
        "            time.sleep(0.02)\n"
        "        note('page on-load ends')\n"
        "    pn.state.onload(below)\n"
        "pn.pane.Markdown('a page').servable()\n"
    )
    srv = Server(tmp_path, app, {}, name="gateapp")

    def while_the_page_opens() -> None:
        assert "page builds" in notes.read_text()
        # the proof reached its safe point while the page opens: it waits there
        wait_for(lambda: "the proof steps aside: 1 page(s) opening" in srv.log(), 60)
        assert "proof at a safe point (True)" in notes.read_text()
        assert "proof goes on" not in notes.read_text()
        opener = urllib.request.build_opener(NoRedirect)
        status, _, body = get(opener, srv.base + "/liveness?endpoint=/gateapp")
        assert status == 503 and json.loads(body) == {"/gateapp": False}

    async def user() -> None:
        client = await PageClient.open(f"ws://127.0.0.1:{srv.port}/gateapp/ws")
        try:
            loop = asyncio.get_running_loop()
            pull = asyncio.ensure_future(client.pull(120))  # a user's page is requested
            # the server knows the page opens; the proof, busy in its script, goes on to
            # its next safe point
            await loop.run_in_executor(
                None, lambda: wait_for(lambda: "a page opens while the proof" in srv.log(), 60)
            )
            assert "page builds" not in notes.read_text()
            gate_file.write_text("open")
            doc = await pull  # the user's page opened (built, sent)
            await loop.run_in_executor(None, while_the_page_opens)
            await client.ready(doc)  # the browser shows the page: its on-load work starts
            await loop.run_in_executor(
                None, lambda: wait_for(lambda: "page on-load starts" in notes.read_text(), 60)
            )
            onload_gate.write_text("open")
            await loop.run_in_executor(
                None, lambda: wait_for(lambda: "proof goes on" in notes.read_text(), 60)
            )
            # the page stayed first until its own on-load work was done
            lines = notes.read_text().splitlines()
            assert lines.index("page on-load ends") < lines.index("proof goes on")
        finally:
            client.close()

    try:
        srv.listening(120)
        wait_for(lambda: notes.exists() and "proof builds" in notes.read_text(), 120)
        in_own_loop(user(), 300)
        srv.started(120)
        assert "the proof goes on (" in srv.log()
    finally:
        srv.stop()


def test_a_users_page_is_built_while_the_proof_waits_at_any_safe_point():
    """The dashboard's own safe points (``step_aside`` in ``app/main.py``): with the proof
    held at any of them, a user's page is built to the end (it never waits for the proof).
    The results the pages share are computed afresh by each proof (the caches emptied), so
    a safe point inside such a computation would hold the user's page."""
    from app.compute import clear_shared_caches
    from app.main import create_app
    from app.state import DashboardState

    def small() -> DashboardState:
        state = DashboardState()
        state.noise.rounds = 200
        return state

    class Stop(Exception):
        """Ends a held proof once released (the rest of its build is of no interest)."""

    def proof(step_aside) -> threading.Thread:
        def build() -> None:
            threading.current_thread().step_aside = step_aside  # type: ignore[attr-defined]
            try:
                create_app(small())
            except Stop:
                pass

        t = threading.Thread(target=build, daemon=True)
        t.start()
        return t

    calls: list[int] = []  # the safe points a proof passes
    clear_shared_caches()
    counting = proof(lambda: calls.append(1))
    counting.join(300)
    assert not counting.is_alive() and len(calls) >= 5
    for stop_at in range(1, len(calls) + 1):
        held, release = threading.Event(), threading.Event()
        passed: list[int] = []

        def step_aside(stop_at=stop_at, held=held, release=release, passed=passed) -> None:
            passed.append(1)
            if len(passed) == stop_at:
                held.set()
                assert release.wait(300)
                raise Stop

        clear_shared_caches()
        proving = proof(step_aside)
        wait_for(
            lambda held=held, proving=proving: held.is_set() or not proving.is_alive(),
            300,
            what="the proof held",
        )
        assert held.is_set(), f"the proof passed {len(passed)} safe points, not {len(calls)}"
        user: dict = {}
        building = threading.Thread(target=lambda u=user: u.update(page=create_app(small())))
        building.daemon = True
        building.start()
        building.join(120)
        try:
            assert not building.is_alive(), (
                f"a user's page waited for the proof held at its safe point {stop_at}"
            )
            assert user["page"].main.objects
            assert proving.is_alive()  # still held
        finally:
            release.set()
        proving.join(300)
        assert not proving.is_alive()
