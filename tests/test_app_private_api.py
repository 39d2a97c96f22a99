"""The app and its server use only public mechanisms of Panel, Bokeh, BokehJS and Tornado,
except in two isolated modules (``app/runtime/panel_private.py`` for the app,
``docker/server_private.py`` for the server stage of the image), whose private uses fail a
test here when they disappear.

Scanned: every module of ``app`` and of ``docker`` (the server: ``entrypoint.py``,
``fbs_server.py``, ``fbs_auth.py``), the browser tests and the dashboard benchmarks. Flagged:
an attribute ``x._name`` on anything but ``self``/``cls``, ``getattr(x, "_name")`` and
friends, imports of private names or modules of Panel/Bokeh, and ``._name`` inside the
JavaScript strings that run in the page.
"""

from __future__ import annotations

import ast
import inspect
import re
from pathlib import Path

import panel as pn
import pytest

ROOT = Path(__file__).resolve().parents[1]
ISOLATED = ROOT / "app" / "runtime" / "panel_private.py"
SERVER_ISOLATED = ROOT / "docker" / "server_private.py"
SCANNED = sorted(
    [p for p in (ROOT / "app").rglob("*.py") if p != ISOLATED]
    + [p for p in (ROOT / "docker").glob("*.py") if p != SERVER_ISOLATED]
    + list((ROOT / "tests" / "browser").glob("*.py"))
    + [ROOT / "bench" / n for n in ("bench_dashboard.py", "load_test.py", "load_clients.py")]
)
JS_PRIVATE = re.compile(r"\.\s*_[A-Za-z]\w*")
#: Documented names of the standard library that start with an underscore.
STDLIB_PUBLIC = {("os", "_exit")}


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def violations(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    # names bound to the project's own modules: their private names are the project's
    own_modules = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (
            node.level > 0 or (node.module or "").split(".")[0] in ("app", "fbs_core")
        ):
            own_modules |= {a.asname or a.name for a in node.names}
        elif isinstance(node, ast.Import):
            own_modules |= {
                a.asname or a.name for a in node.names if a.name.split(".")[0] in ("app",)
            }
    out = []
    for node in ast.walk(tree):
        where = f"{path.relative_to(ROOT)}:{getattr(node, 'lineno', '?')}"
        if isinstance(node, ast.Attribute) and _private(node.attr):
            own = isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")
            own |= (
                isinstance(node.value, ast.Call)
                and isinstance(node.value.func, ast.Name)
                and node.value.func.id == "super"
            )
            own |= isinstance(node.value, ast.Name) and node.value.id in own_modules
            own |= isinstance(node.value, ast.Name) and (node.value.id, node.attr) in STDLIB_PUBLIC
            if not own:
                out.append(f"{where} attribute .{node.attr}")
        elif isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Attribute) and t.attr == "__class__" for t in node.targets
        ):
            out.append(f"{where} assignment to __class__")
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            if node.func.id in ("getattr", "setattr", "hasattr", "delattr") and len(node.args) > 1:
                arg = node.args[1]
                if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                    if _private(arg.value):
                        out.append(f"{where} {node.func.id}(..., {arg.value!r})")
        elif isinstance(node, ast.ImportFrom) and node.module:
            parts = node.module.split(".")
            if parts[0] in ("panel", "bokeh", "tornado"):
                if any(_private(p) for p in parts) or parts[:2] == ["panel", "models"]:
                    out.append(f"{where} import from {node.module}")
                out += [f"{where} import {a.name}" for a in node.names if _private(a.name)]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            if "=>" in node.value or "function" in node.value or "Bokeh." in node.value:
                for m in JS_PRIVATE.findall(node.value):
                    out.append(f"{where} JavaScript {m.strip()}")
    return out


@pytest.mark.parametrize("path", SCANNED, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_private_attribute_of_panel_bokeh_or_bokehjs(path):
    assert violations(path) == []


def test_the_scan_finds_what_it_must():
    """The checker itself: each kind of private use is caught (it can fail)."""
    bad = ROOT / "tests" / "_private_sample.py"
    bad.write_text(
        "import panel as pn\n"
        "from panel.models.markup import HTML\n"
        "from panel.io.document import _cleanup_doc\n"
        "w = pn.widgets.IntSlider()\n"
        "w._debounce = 5\n"
        "ok = pn.state._unblocked(None)\n"
        "x = getattr(doc, '_pending_writes', None)\n"
        "JS = '() => [...Bokeh.documents[0]._all_models.values()]'\n"
        "self_ok = self._mine\n"
        "from . import figures\n"
        "own_ok = figures._LOCK\n"
        "provider.__class__ = Other\n"
    )
    try:
        found = violations(bad)
    finally:
        bad.unlink()
    joined = "\n".join(found)
    for what in (
        "import from panel.models.markup",
        "import _cleanup_doc",
        "attribute ._debounce",
        "attribute ._unblocked",
        "getattr(..., '_pending_writes')",
        "JavaScript ._all_models",
        "assignment to __class__",
    ):
        assert what in joined
    assert "_mine" not in joined and "_LOCK" not in joined


def test_the_isolated_private_use_still_exists_in_panel():
    """``app/runtime/panel_private.py`` sets ``Widget._debounce``: Panel must still have it and read
    it where it schedules a browser change (else the setting silently does nothing)."""
    from app.runtime.panel_private import DEBOUNCE_MS, respond_at_once

    assert isinstance(pn.widgets.IntSlider._debounce, int)
    from panel.reactive import Syncable

    assert "self._debounce" in inspect.getsource(Syncable)
    w = pn.widgets.EditableFloatSlider(start=0, end=1)
    respond_at_once(w)
    assert all(x._debounce == DEBOUNCE_MS for x in w.select(pn.widgets.Widget))


def test_the_server_scan_covers_docker():
    names = {p.name for p in SCANNED if p.parent.name == "docker"}
    assert {"entrypoint.py", "fbs_server.py", "fbs_auth.py"} <= names
    assert "server_private.py" not in names


def test_the_servers_isolated_private_uses_still_exist():
    """``docker/server_private.py``: each private name it uses is still there and used as
    relied on (else the server would silently lose its shutdown, its start-up proof or the
    client address of the login throttle)."""
    import tornado.httpserver
    from panel.io import document
    from panel.io.state import state

    assert callable(document._cleanup_doc)
    assert "_thread_pool" in vars(type(state)) or hasattr(state, "_thread_pool")
    src = inspect.getsource(tornado.httpserver._HTTPRequestContext.__init__)
    assert "self.address = address" in src
    src = inspect.getsource(tornado.httpserver.HTTPServer.handle_stream)
    assert "HTTP1ServerConnection(stream, self.conn_params, context)" in src


def test_tornado_refuses_a_frame_by_its_declared_size_before_reading_it():
    """``server_private.report_refused_websocket_frames`` relies on Tornado checking the
    length a websocket frame declares before it reads the payload, closing with 1009 via the
    protocol's ``close`` (which it wraps; ``mask_outgoing`` tells a server's protocol);
    ``bound_bokeh_messages`` wraps ``on_message`` of Panel's websocket handler."""
    import tornado.websocket
    from panel.io.server import WSHandler

    src = inspect.getsource(tornado.websocket.WebSocketProtocol13._receive_frame)
    check = src.index("if new_len > self.params.max_message_size:")
    assert src.index('self.close(1009, "message too big")') > check
    assert src.index("await self._read_bytes(payloadlen)") > check
    assert "self.mask_outgoing = mask_outgoing" in inspect.getsource(
        tornado.websocket.WebSocketProtocol13.__init__
    )
    assert inspect.iscoroutinefunction(WSHandler.on_message)


def test_the_accept_loop_the_server_takes_over_is_still_tornados():
    """``server_private.accept_connections`` replaces the accept handler Tornado's
    ``TCPServer.add_sockets`` registers per listening socket (kept in ``_sockets`` and
    ``_handlers``, whose removers ``stop()`` calls) and serves connections with
    ``_handle_connection``; Bokeh's server keeps its HTTP server in ``_http``."""
    import tornado.tcpserver
    from bokeh.server.server import BaseServer

    src = inspect.getsource(tornado.tcpserver.TCPServer.add_sockets)
    assert "self._sockets[sock.fileno()] = sock" in src
    assert "self._handlers[sock.fileno()] = add_accept_handler(" in src
    assert "self._handle_connection" in src
    assert "self._handlers.pop(fd)()" in inspect.getsource(tornado.tcpserver.TCPServer.stop)
    assert "self._http = http_server" in inspect.getsource(BaseServer.__init__)


def test_the_routes_whose_page_builds_are_bounded_are_still_panels():
    """``server_private.bound_page_builds`` wraps the coroutines of Panel's page, autoload
    and websocket routes (the per-app routes Bokeh builds its application's handlers from)."""
    from bokeh.server.urls import per_app_patterns
    from panel.io.server import AutoloadJsHandler, DocHandler, WSHandler

    assert {DocHandler, AutoloadJsHandler, WSHandler} <= {h for _, h in per_app_patterns}
    for method in (DocHandler.get, AutoloadJsHandler.get, WSHandler.prepare):
        # (a login decorator may wrap it: awaited all the same)
        assert inspect.iscoroutinefunction(inspect.unwrap(method)), method


def test_the_process_pools_worker_list_is_still_there():
    """``panel_private.pool_processes`` reads CPython's ``ProcessPoolExecutor._processes``:
    the report drawer's processes, ended when the server stops."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    from app.runtime.panel_private import pool_processes

    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        assert pool.submit(abs, -1).result(timeout=120) == 1
        procs = pool_processes(pool)
        assert len(procs) == 1 and procs[0].is_alive()


def test_the_app_script_lock_is_released_while_the_proof_steps_aside():
    """Bokeh runs app scripts under one process-wide re-entrant lock; the proof, stepping
    aside inside its script, releases it (``server_private.app_scripts_unlocked``) so a
    user's script runs meanwhile, and holds it again as before afterwards."""
    import sys
    import threading

    from bokeh.application.handlers import code_runner
    from panel.io import handlers

    sys.path.insert(0, str(ROOT / "docker"))
    from server_private import app_scripts_unlocked

    lock = code_runner._PROCESS_GLOBALS_LOCK
    # Bokeh's and Panel's script runners both take it
    assert "_hold_process_globals()" in inspect.getsource(code_runner.CodeRunner.run)
    assert "_hold_process_globals()" in inspect.getsource(handlers)
    ran = threading.Event()

    def other_script() -> None:
        with code_runner._hold_process_globals():
            ran.set()

    with code_runner._hold_process_globals(), code_runner._hold_process_globals():
        with app_scripts_unlocked():
            t = threading.Thread(target=other_script)
            t.start()
            assert ran.wait(60), "another thread's script could not run while this one waited"
            t.join(60)
        assert lock._is_owned()  # held again, twice: released twice below
    assert not lock._is_owned()
    with app_scripts_unlocked():  # a thread that does not hold it: nothing changes
        assert not lock._is_owned()
