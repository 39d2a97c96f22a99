"""The only module of the server stage that touches private Panel, Bokeh or Tornado API.

``docker/fbs_server.py`` and ``docker/fbs_auth.py`` use public mechanisms only (Bokeh's
``Serve.customize_kwargs``/``customize_server`` hooks and ``AuthProvider`` interface,
Tornado's ``RequestHandler``/``StaticFileHandler``, Panel's ``ComponentResourceHandler``
and templates); what has no public form is here, where ``tests/test_app_private_api.py``
checks that each private name still exists and does what is relied on (and its scan of
``docker/`` fails on a private use anywhere else).
"""

from __future__ import annotations

__all__ = ["cancel_queued_panel_work", "cleanup_document", "peer_address"]


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
