"""Sessions do not change each other's pages through Panel's process-wide busy flag.

Panel sets ``pn.state.busy`` while it handles a browser change of any widget of any session
and mirrors it into the busy indicator of every template ever served; with the template's
default spinner every change of every session set every open page's spinner twice (an
eighth of the server's CPU with 20 sessions changing, ``bench/load_test.py`` profiled).
"""

from __future__ import annotations

import panel as pn
from bokeh.document import Document
from panel.io.state import set_curdoc
from panel.util import edit_readonly

from app.main import create_app


def test_the_busy_flag_of_the_process_changes_no_page():
    docs, events = [], []
    for _ in range(2):
        doc = Document()
        with set_curdoc(doc):
            page = create_app()
            page.server_doc(doc)
        assert page.busy_indicator is None
        doc.on_change(events.append)
        docs.append((doc, page))
    for value in (True, False):
        with edit_readonly(pn.state):
            pn.state.busy = value
    assert events == [], [type(e).__name__ for e in events]
