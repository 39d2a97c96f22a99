"""The only module of the app that touches a private attribute of Panel, Bokeh or BokehJS.

``tests/test_app_private_api.py`` greps every other app module (and the browser tests and
benchmarks) for private attributes, and fails here when Panel drops what is used.

Panel waits ``Widget._debounce`` ms (50) after a browser-side widget change before it
handles it, to merge bursts; Panel has no public setting for it. The views here update in
a few milliseconds and a newer state always lands last, so the wait only adds to every
control's latency (50 -> 5 ms is 45 ms off each change, measured by
``bench/bench_dashboard.py``).
"""

from __future__ import annotations

import panel as pn

__all__ = ["DEBOUNCE_MS", "respond_at_once"]

#: Milliseconds Panel waits after a browser-side widget change before handling it.
DEBOUNCE_MS = 5


def respond_at_once(widget: pn.widgets.Widget, ms: int = DEBOUNCE_MS) -> None:
    """Shorten Panel's wait after a change of ``widget`` (and of its sub-widgets)."""
    # composite widgets (DiscreteSlider, Editable*Slider) receive the change on a sub-widget
    for w in widget.select(pn.widgets.Widget):
        w._debounce = ms
