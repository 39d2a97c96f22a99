"""The main controls change the page in place: no Bokeh model is added or dropped.

A pane re-rendered by a control (Panel's ``pn.pane.HTML``/``Markdown`` given a new object)
sends new models (its stylesheets), and the served document then walks its whole model
graph (~750 models) on the event loop: ~45 ms per session and change, which held back
every session's first plot update when 20 sessions moved the harmonic slider together
(``bench/load_test.py``: p95 1.6-1.9 s; the line under the harmonic slider was such a
pane). Views, captions and status lines change the properties of the models they have.
"""

from __future__ import annotations

import pytest
from bokeh.document import Document
from panel.io.state import set_curdoc

from app.main import create_app


@pytest.fixture(scope="module")
def page_doc():
    doc = Document()
    with set_curdoc(doc):
        page = create_app()
        page.server_doc(doc)
    return page, doc


def _changes(page):
    c, t = page.state.case, page.state.truncation
    return [
        ("harmonic", c, (3, 5)),
        ("n_modes", c, tuple(c.param.n_modes.objects[1:3])),
        ("dof", c, ("x", "rz")),
        ("coupling", c, tuple(c.param.coupling.objects[1:2])),
        ("residual", c, (True, False)),
        ("threshold", t, (20.0, 30.0)),
        ("map_mode", t, tuple(t.param.map_mode.objects[1:2])),
    ]


@pytest.mark.parametrize("k", range(7))
def test_a_control_change_keeps_the_page_models(page_doc, k):
    page, doc = page_doc
    name, obj, values = _changes(page)[k]
    before = {m.id for m in doc.models}
    with set_curdoc(doc):
        for v in values:
            setattr(obj, name, v)
    after = {m.id for m in doc.models}
    added = sorted(type(doc.get_model_by_id(i)).__name__ for i in after - before)
    assert not added and before <= after, f"{name}: new models {added}, {len(before - after)} gone"
