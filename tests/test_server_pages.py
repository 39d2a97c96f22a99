"""A page built and cleaned up outside a browser session leaves nothing behind.

Issue 20, finding 2: Panel's ``--liveness`` check built the whole page in a Bokeh document
without a browser session for every request and cleaned it up, yet the page's results,
states, views and data sources stayed alive after garbage collection; the server grew
from 423 to 1073 MB over ~250 requests. What held them: Panel's registry of JavaScript
callbacks (``panel.links.Callback.registry``, a weak-key dictionary filled by the controls'
editable sliders) whose values reach their own keys through the sliders' watchers, so no
entry ever goes; Panel drops those watchers only for the components of a served session.
The page now drops them itself with the document's session-destroyed callbacks
(``app.main.close_page``). The figure (server memory over many page builds) is printed by
``bench/bench_pages.py``.
"""

from __future__ import annotations

import gc
import weakref
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def results_made(monkeypatch):
    """Weak references to every :class:`app.store.Results` created during the test."""
    from app.store import Results

    made: list[weakref.ref] = []
    init = Results.__init__

    def tracked(self, *args, **kwargs):
        init(self, *args, **kwargs)
        made.append(weakref.ref(self))

    monkeypatch.setattr(Results, "__init__", tracked)
    return made


def _end_session(doc) -> None:
    """What Panel's liveness check and the server do with a document whose session
    ended: Panel's clean-up (the document's session-destroyed callbacks, then Panel's own
    clean-up of the served components it knows of)."""
    from panel.io.document import _cleanup_doc

    _cleanup_doc(doc)


def test_a_page_built_by_the_app_handler_without_a_session_is_freed(results_made):
    """As Panel's ``--liveness`` check did: the app script run into a new document."""
    from panel.command.serve import build_single_handler_applications

    apps = build_single_handler_applications([str(ROOT / "app" / "main.py")], {})
    doc = apps["/main"].create_document()
    assert len(results_made) == 1 and results_made[0]() is not None
    _end_session(doc)
    del doc
    gc.collect()
    assert results_made[0]() is None, "the page's results outlive its document"


def test_a_page_ends_even_when_bokeh_cleared_its_script_namespace_first(results_made, caplog):
    """Bokeh may clear the app script's module namespace before the session-destroyed
    callbacks run (seen under load: "name 'close_page' is not defined"); the page's end uses
    no global name of the script, so it still closes the page and logs that it ended."""
    from panel.command.serve import build_single_handler_applications

    apps = build_single_handler_applications([str(ROOT / "app" / "main.py")], {})
    doc = apps["/main"].create_document()
    script = str(ROOT / "app" / "main.py")
    callbacks = [
        cb
        for cb in doc.session_destroyed_callbacks
        if getattr(getattr(cb, "__code__", None), "co_filename", None) == script
    ]  # the page's own (not Panel's)
    assert len(callbacks) == 1
    for cb in callbacks:
        cb.__globals__.clear()  # the script's module (a fresh one per document)
    with caplog.at_level("INFO", logger="app.main"):
        for cb in callbacks:
            cb(None)
    assert results_made[0]().closed
    assert "a page's session ended" in caplog.text


def test_a_page_of_create_app_in_a_document_is_freed_with_it(results_made):
    """``create_app`` in a document of its own (a warm-up, a test): freed with it."""
    from bokeh.document import Document
    from panel.io.state import set_curdoc

    from app.main import create_app

    doc = Document()
    with set_curdoc(doc):
        page = create_app()
    state = weakref.ref(page.state.case)
    data = weakref.ref(page.state.data)
    assert results_made[0]() is page.results
    del page
    _end_session(doc)
    del doc
    gc.collect()
    assert results_made[0]() is None, "the page's results outlive its document"
    assert state() is None, "the page's case state outlives its document"
    assert data() is None, "the page's data source outlives its document"
