"""Safe points of a page's build, where a build nobody waits for steps aside.

The server proves the app once its port is open by building a page on a thread of its own
(``docker/fbs_server.py``); a user's page opened meanwhile shared the one Python
interpreter with it (2.6-2.8 s to the first plot instead of 1.65 s). Such a
thread carries a ``step_aside`` attribute, a callable that returns once no user's page is
opening (``docker/page_gate.py``), and so does its document while its on-load callbacks
run (on Panel's worker threads). :func:`step_aside` calls it where the build holds
nothing another page may wait for: between the steps of :func:`app.main.create_app`, never
inside a computation whose result the pages share (paused there, it held a user's page
back). Elsewhere, and in every user's page, it does nothing.
"""

from __future__ import annotations

import threading

import panel as pn

__all__ = ["step_aside"]


def step_aside() -> None:
    """Let users' opening pages go first, if this thread builds a page nobody waits for
    (its ``step_aside``), or loads one (the ``step_aside`` of the current document: the
    page's on-load callbacks run on Panel's worker threads)."""
    wait = getattr(threading.current_thread(), "step_aside", None)
    if wait is None:
        wait = getattr(pn.state.curdoc, "step_aside", None)
    if wait is not None:
        wait()
