"""The only module of the server stage that touches private Panel, Bokeh or Tornado API.

``docker/fbs_server.py`` and ``docker/fbs_auth.py`` use public mechanisms only (Bokeh's
``Serve.customize_kwargs``/``customize_server`` hooks and ``AuthProvider`` interface,
Tornado's ``RequestHandler``/``StaticFileHandler``, Panel's ``ComponentResourceHandler``
and templates); what has no public form is here, where ``tests/test_app_private_api.py``
checks that each private name still exists and does what is relied on (and its scan of
``docker/`` fails on a private use anywhere else).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

__all__ = [
    "accept_connections",
    "app_scripts_unlocked",
    "bound_bokeh_messages",
    "bound_page_builds",
    "cancel_queued_panel_work",
    "cleanup_document",
    "peer_address",
    "report_refused_websocket_frames",
]


@contextlib.contextmanager
def app_scripts_unlocked() -> Iterator[None]:
    """Let other threads run app scripts while this one waits inside its own.

    Bokeh runs every app script under one process-wide re-entrant lock
    (``code_runner._PROCESS_GLOBALS_LOCK``: a script patches the process's working
    directory, ``sys.path``, ``sys.argv`` and the current document). The server's start-up
    proof builds a page on a thread of its own and steps aside inside the app's script
    while users' pages open; holding the lock there would hold every user's page build,
    and the event loop that runs it, back until the proof goes on. The lock is released as
    many times as this thread holds it and taken again as before (the ``Condition``
    protocol of the re-entrant lock); a user's script restores what it patched before the
    proof takes the lock back. A thread that does not hold it is left as it is.
    """
    try:
        from bokeh.application.handlers.code_runner import _PROCESS_GLOBALS_LOCK as lock
    except ImportError:  # a Bokeh without the lock: nothing to release
        yield
        return
    if not lock._is_owned():
        yield
        return
    saved = lock._release_save()
    try:
        yield
    finally:
        lock._acquire_restore(saved)


def cleanup_document(doc) -> None:
    """Free a document built without a browser session (the start-up proof of the app):
    Panel's own clean-up of a destroyed session's document (``_cleanup_doc``)."""
    from panel.io.document import _cleanup_doc

    _cleanup_doc(doc)


def cancel_queued_panel_work() -> None:
    """Cancel the callbacks queued on Panel's worker threads (``--num-threads``); running
    ones are abandoned at exit. Panel keeps its pool in ``state._thread_pool``."""
    from panel.io.state import state

    pool = getattr(state, "_thread_pool", None)
    if pool is not None:
        pool.shutdown(wait=False, cancel_futures=True)


def peer_address(request) -> str:
    """The address of the connection's other end, also when Tornado's ``xheaders`` has
    replaced ``request.remote_ip`` by what the request's headers claim.

    Tornado keeps the socket's address in the connection's ``context.address`` (documented
    as an opaque application-defined object).
    """
    context = getattr(getattr(request, "connection", None), "context", None)
    address = getattr(context, "address", None)
    if isinstance(address, tuple) and address and isinstance(address[0], str):
        return address[0]
    return str(request.remote_ip or "unknown")


def report_refused_websocket_frames(report) -> None:
    """Call ``report(handler, reason)`` when Tornado refuses a websocket frame for its size.

    Tornado checks the length a frame declares in its header against the handler's
    ``max_message_size`` before it reads the payload, and then closes the connection with
    code 1009 ("message too big") without a log line (``WebSocketProtocol13._receive_frame``
    calls the protocol's ``close(1009, ...)``); this wraps that ``close`` of the server's
    protocol class so that the refusal is logged with the client's address.
    """
    from tornado.websocket import WebSocketProtocol13

    if getattr(WebSocketProtocol13.close, "fbs_reports", False):
        return
    original = WebSocketProtocol13.close

    def close(self, code=None, reason=None):
        if code == 1009 and not self.mask_outgoing:  # (a server does not mask)
            try:
                report(self.handler, reason)
            except Exception:  # noqa: BLE001, S110 (a log line must not break the close)
                pass
        return original(self, code, reason)

    close.fbs_reports = True  # type: ignore[attr-defined]
    WebSocketProtocol13.close = close  # type: ignore[method-assign]


def bound_bokeh_messages(max_bytes: int, refused) -> None:
    """Close a websocket whose Bokeh message (header, metadata, content and the buffers
    its header announces, each a websocket message of its own) exceeds ``max_bytes``
    in all; ``refused(handler, text)`` is called first (the log line).

    Tornado bounds each websocket message by its declared size; a Bokeh message may have
    any number of buffers, so many messages under that size, each kept in memory until
    the Bokeh message is whole, would add up. Panel's websocket handler (``panel.io.server.
    WSHandler``, the ``/ws`` route of every app) gets this count in front of its
    ``on_message``; a fragment's size is counted before Bokeh decodes it, plus 64 bytes
    per fragment (so that empty buffers cannot pile up either).
    """
    import json

    from panel.io.server import WSHandler

    if getattr(WSHandler.on_message, "fbs_bounded", False):
        return
    original = WSHandler.on_message

    async def on_message(self, fragment):
        if getattr(self, "fbs_refused", False):
            return None  # closing: nothing more of this connection is read
        left = getattr(self, "fbs_frames_left", 0)
        if left <= 0:  # a Bokeh message begins: its header says how many buffers follow
            count = 0
            try:
                header = json.loads(fragment) if len(fragment) < 65536 else {}
                count = max(0, int(header.get("num_buffers", 0) or 0))
            except (ValueError, TypeError, AttributeError):
                count = 0  # Bokeh refuses it with its own protocol error
            left, size = 3 + 2 * count, 0
        else:
            size = getattr(self, "fbs_message_bytes", 0)
        size += len(fragment) + 64
        self.fbs_frames_left, self.fbs_message_bytes = left - 1, size
        if size > max_bytes:
            self.fbs_refused = True
            refused(self, f"a Bokeh message of more than {size:,} bytes (limit {max_bytes:,})")
            self.close(1009, "message too big")
            return None
        return await original(self, fragment)

    on_message.fbs_bounded = True  # type: ignore[attr-defined]
    WSHandler.on_message = on_message  # type: ignore[method-assign]


def accept_connections(bokeh_server, limits) -> int:
    """Put the server's own accept loop (``conn_limits.accept_loop``: connection caps, a
    pause instead of a busy loop when file descriptors run out) in front of the Bokeh
    server's HTTP server; the number of listening sockets it took over.

    Tornado's ``TCPServer`` accepts in a handler it registers per listening socket
    (``_sockets``, ``_handlers``: the remover ``stop()`` calls) and serves each connection
    with ``_handle_connection``; an ``accept()`` that fails with EMFILE escapes its handler,
    and the event loop calls it again at once (the busy loop). Bokeh keeps its HTTP server
    in ``Server._http``. Called before the event loop runs.
    """
    from conn_limits import accept_loop
    from tornado.ioloop import IOLoop

    http = bokeh_server._http
    io_loop = bokeh_server.io_loop

    def take_over(sock) -> None:
        def ready(_fd, _events) -> None:
            accept_loop(sock, http._handle_connection, limits, pause)

        def resume() -> None:
            if sock.fileno() != -1:  # not closed by a stop meanwhile
                io_loop.add_handler(sock, ready, IOLoop.READ)

        def pause(seconds: float) -> None:
            io_loop.remove_handler(sock)
            io_loop.call_later(seconds, resume)

        io_loop.add_handler(sock, ready, IOLoop.READ)
        http._handlers[sock.fileno()] = lambda: io_loop.remove_handler(sock)

    n = 0
    for fd, sock in list(http._sockets.items()):
        http._handlers.pop(fd)()  # Tornado's accept handler
        take_over(sock)
        n += 1
    return n


def bound_page_builds(builds, key_of, refused) -> None:
    """Put the page-build budgets (``page_limits.PageBuilds``) in front of the routes that
    build a page for an HTTP request: Panel's page (``DocHandler.get``) and autoload
    (``AutoloadJsHandler.get``) routes; the websocket route (``WSHandler.prepare``) gives
    the charge back when it opens a session built by such a request (the page is in use;
    Bokeh's ``ApplicationContext.get_session`` tells).

    ``key_of(handler)`` names the budget's owner (a login or a client address);
    ``refused(handler, key, kind, wait_s)`` is called for a refused request, which gets
    the status, ``Retry-After`` and light page of ``builds.wait_page``. A request without a
    login is left to the route (which sends it to the login). A build is charged the time
    its handler took.
    """
    import time

    from bokeh.util.token import get_session_id
    from panel.io.server import AutoloadJsHandler, DocHandler, WSHandler

    def refuse(handler, key: str, refusal) -> None:
        status, retry, page = builds.wait_page(*refusal)
        refused(handler, key, *refusal)
        handler.set_status(status)
        handler.set_header("Retry-After", str(retry))
        handler.set_header("Cache-Control", "no-store")
        handler.set_header("Content-Type", "text/html; charset=utf-8")
        handler.finish(page)

    for cls in (DocHandler, AutoloadJsHandler):
        if getattr(cls.get, "fbs_bounded", False):
            continue

        async def get(self, *args, _original=cls.get, **kwargs):
            if self.current_user is None:
                return await _original(self, *args, **kwargs)
            key = key_of(self)
            refusal = builds.check(key)
            if refusal is not None:
                return refuse(self, key, refusal)
            t0 = time.perf_counter()
            try:
                return await _original(self, *args, **kwargs)
            finally:
                builds.charge(key, time.perf_counter() - t0)

        get.fbs_bounded = True  # type: ignore[attr-defined]
        cls.get = get  # type: ignore[method-assign]

    if getattr(WSHandler.prepare, "fbs_bounded", False):
        return
    original_prepare = WSHandler.prepare

    async def prepare(self):
        await original_prepare(self)
        if self.current_user is None or self.get_status() != 200:
            return  # refused by Panel already
        header = self.request.headers.get("Sec-WebSocket-Protocol", "")
        protocols = [p.strip() for p in header.split(",")]
        try:
            self.application_context.get_session(get_session_id(protocols[1]))
        except Exception:  # noqa: BLE001 (no such session, or a token Bokeh refuses)
            return
        builds.refund(key_of(self))

    prepare.fbs_bounded = True  # type: ignore[attr-defined]
    WSHandler.prepare = prepare  # type: ignore[method-assign]
