"""The only module of the app that touches a private attribute of Panel, Bokeh or BokehJS.

``tests/test_app_private_api.py`` greps every other app module (and the browser tests and
benchmarks) for private attributes, and fails here when Panel drops what is used.

Panel waits ``Widget._debounce`` ms (50) after a browser-side widget change before it
handles it, to merge bursts; Panel has no public setting for it. The views here update in
a few milliseconds and a newer state always lands last, so the wait only adds to every
control's latency (50 -> 5 ms is 45 ms off each change, measured by
``bench/bench_dashboard.py``).

Captions and status lines (``app.views.live.LiveText``) are Panel's own HTML model
(``panel.models.HTML``, Panel-internal: what ``pn.pane.HTML`` renders) whose ``text`` is
set in place. The documented alternatives measured slower: setting ``pn.pane.HTML.object``
re-sends every property of the model (new stylesheet models each time: the served document
recomputes its model graph and serializes them; 8-21 % of the server's CPU time with 20
sessions changing, ``bench/load_test.py``), and Bokeh's ``Div`` makes the browser re-lay
out the whole page on every text change (~36 ms each in the page, against 0.2-0.6 ms for
Panel's HTML model). The text is sent escaped once, as the pane sends it (the page decodes
it once); ``tests/test_app_views.py`` fails if the pane's convention changes.

Panel writes some of a page's changes later than it schedules them: when a layout changes
(e.g. a dynamic tab's views are rendered when the tab is clicked) while the page's socket is
busy writing, Panel queues the change events and writes them from a task that polls the
socket's write lock every 10 ms (``panel.io.document.schedule_write_events``; Panel records
such a page in ``_WRITE_BLOCK`` and its queued batches in ``_WRITE_EVENTS``). A draw of the
app's own (:class:`app.runtime.draw.DrawQueue`) queues on that lock and could overtake those
changes: the page would see a draw's patches before the layout change that holds the models
they change (the phase view's plots stayed empty after a click on its tab).
:func:`panel_writes_pending` tells the draw queue to wait until Panel's queue is written.
"""

from __future__ import annotations

import html
import threading

import panel as pn

__all__ = [
    "DEBOUNCE_MS",
    "browser_change_pending",
    "html_model",
    "html_text",
    "lock_held_only_by_its_thread",
    "panel_writes_pending",
    "pool_processes",
    "resend_value",
    "respond_at_once",
]

#: Milliseconds Panel waits after a browser-side widget change before handling it.
DEBOUNCE_MS = 5


def respond_at_once(widget: pn.widgets.Widget, ms: int = DEBOUNCE_MS) -> None:
    """Shorten Panel's wait after a change of ``widget`` (and of its sub-widgets)."""
    # composite widgets (DiscreteSlider, Editable*Slider) receive the change on a sub-widget
    for w in widget.select(pn.widgets.Widget):
        w._debounce = ms


def html_text(html_source: str) -> str:
    """The ``text`` property of Panel's HTML model that shows ``html_source``."""
    return html.escape(html_source)


def html_model(html_source: str = "", **props):
    """Panel's HTML model (what ``pn.pane.HTML`` renders) showing ``html_source``."""
    from panel.models import HTML

    return HTML(text=html_text(html_source), disable_math=True, **props)


def panel_writes_pending(doc) -> bool:
    """Whether Panel holds changes for ``doc``'s page that it queued but has not written
    yet (see the module docstring)."""
    from panel.io import document as pdoc

    return doc in pdoc._WRITE_BLOCK or bool(pdoc._WRITE_EVENTS.get(doc))


def pool_processes(pool) -> list:
    """The worker processes of a ``concurrent.futures.ProcessPoolExecutor`` (CPython keeps
    them in ``_processes``; the executor has no public list). The report drawer's are ended
    and reaped when the server stops, also one started after the server listed its children.
    """
    return list((getattr(pool, "_processes", None) or {}).values())


def resend_value(widget: pn.widgets.Widget, doc) -> None:
    """Send the browser of ``doc`` the properties of ``widget``'s models that show its
    value (a slider's ``value``, a button group's ``active``...), even when the server's
    copy already holds them: a message the server wrote earlier may have crossed the
    browser's own change (:mod:`app.views.bind`). Runs where ``doc`` may change."""
    props = widget._process_param_change({"value": widget.value})
    for model, _ in list(widget._models.values()):
        if model.document is not doc:
            continue
        for attr in props:
            if attr in model.properties():
                value = getattr(model, attr)
                doc.callbacks.notify_change(model, attr, value, value)


def browser_change_pending(widget: pn.widgets.Widget) -> bool:
    """Whether Panel holds a change of ``widget`` from the browser that it has not yet
    handed to the widget (waiting for its debounce or for a free worker thread)."""
    return bool(widget._events)


_LOCKED_HERE = threading.local()


def lock_held_only_by_its_thread() -> None:
    """Let Panel change a served page's models off the event loop only in the thread that
    holds the page's document lock.

    Panel 1.10 handles a browser's widget change on its worker threads (``--num-threads``)
    and changes the models at once when ``state._document_lock_held``: the session's lock
    is held, by anyone. When another callback held it (a draw, a settle) the change raced
    that callback's end, and Bokeh refused it ("_pending_writes should be non-None when we
    have a document lock"; seen with the notification of a refused typed value and with
    the design's restyling when the car's wheels card appeared). Here the lock counts only
    in the thread running a locked callback (Bokeh's ``ServerSession.with_document_locked``
    runs the callback in an executor thread); elsewhere Panel schedules the change on the
    page's event loop, under the lock, as it does for any other thread. Idempotent.
    """
    from bokeh.server import session as bokeh_session
    from panel.io.state import state

    cls = bokeh_session.ServerSession
    if getattr(cls.with_document_locked, "_fbs_marks_thread", False):
        return
    inner = cls.with_document_locked.__wrapped__

    def with_document_locked(self, func, *args, **kwargs):
        _LOCKED_HERE.depth = getattr(_LOCKED_HERE, "depth", 0) + 1
        try:
            return inner(self, func, *args, **kwargs)
        finally:
            _LOCKED_HERE.depth -= 1

    wrapped = bokeh_session._needs_document_lock(with_document_locked)
    wrapped._fbs_marks_thread = True
    cls.with_document_locked = wrapped

    held = type(state)._document_lock_held

    def lock_held_here(self) -> bool:
        return getattr(_LOCKED_HERE, "depth", 0) > 0 and held.fget(self)

    type(state)._document_lock_held = property(lock_held_here, doc=held.__doc__)  # type: ignore[method-assign,assignment]
