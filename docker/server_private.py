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
    "app_scripts_unlocked",
    "cancel_queued_panel_work",
    "cleanup_document",
    "peer_address",
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
