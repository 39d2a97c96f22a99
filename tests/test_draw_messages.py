"""A draw on a served page leaves as one Bokeh message (app.runtime.draw).

A Panel server in this process serves a small page; a Bokeh protocol client (the messages a
browser receives, read off the websocket) opens it and says the page is ready, as BokehJS
does. A draw asked for from another thread changes several properties of several models;
the client must receive all of them in one PATCH-DOC message (Bokeh alone sends one per
property, and each message builds the serializer's map of every model of the page), and its
replica of the document must hold the drawn values.
"""

from __future__ import annotations

import asyncio
import threading
import time

import numpy as np
import panel as pn
import pytest
from bokeh.document import Document
from bokeh.models import ColumnDataSource, Div
from bokeh.plotting import figure
from server_util import PageClient, in_own_loop, served_in_process

from app.runtime.draw import on_document

TIMEOUT = 60.0


class _Page:
    """What the served page's app made: its document and models (set by the app)."""

    def __init__(self) -> None:
        self.loaded = threading.Event()
        self.doc = None
        self.source = self.fig = self.div = None

    def app(self):
        self.source = ColumnDataSource({"x": np.arange(3.0), "y": np.zeros(3)})
        self.fig = figure(title="before", width=300, height=200)
        self.fig.line("x", "y", source=self.source)
        self.div = Div(text="before")
        self.doc = pn.state.curdoc
        pn.state.onload(self.loaded.set)  # Panel handled the page's ready event
        return pn.Column(pn.pane.Bokeh(self.fig), pn.pane.Bokeh(self.div))


async def _client(url: str, page: _Page, draw) -> tuple[list, Document]:
    """Open the page, say it is ready, ask for ``draw`` from a thread, and collect the
    PATCH-DOC messages that arrive until the drawn values are all in the replica."""
    client = await PageClient.open(url)
    pop = client.pop
    doc = await client.pull(TIMEOUT)
    await client.ready(doc)
    loaded = await asyncio.get_running_loop().run_in_executor(None, page.loaded.wait, TIMEOUT)
    assert loaded, "the page never loaded"
    threading.Thread(target=on_document, args=(page.doc, draw)).start()

    patches = []
    end = time.monotonic() + TIMEOUT
    while True:
        remaining = end - time.monotonic()
        assert remaining > 0, f"the draw never fully arrived ({len(patches)} patches)"
        msg = await asyncio.wait_for(pop(), remaining)
        if msg.msgtype != "PATCH-DOC":
            continue
        patches.append(msg)
        msg.apply_to_document(doc)
        div = doc.get_model_by_id(page.div.id)
        if div.text == "after":
            break
    client.close()
    return patches, doc


@pytest.fixture
def served_page():
    page = _Page()
    with served_in_process({"page": page.app}, TIMEOUT) as port:
        yield page, f"ws://127.0.0.1:{port}/page/ws"


def test_a_draw_reaches_the_page_as_one_message_holding_all_its_changes(served_page):
    page, url = served_page

    def draw():  # several properties of several models, as a view's redraw
        page.source.data = {"x": np.arange(4.0), "y": np.ones(4)}
        page.fig.title.text = "after"
        page.fig.x_range.start = -1.0
        page.div.text = "after"

    patches, replica = in_own_loop(
        asyncio.wait_for(_client(url, page, draw), 2 * TIMEOUT), 3 * TIMEOUT
    )
    assert len(patches) == 1, [len(p.content["events"]) for p in patches]
    assert len(patches[0].content["events"]) >= 4
    src = replica.get_model_by_id(page.source.id)
    np.testing.assert_array_equal(np.asarray(src.data["y"]), np.ones(4))
    assert replica.get_model_by_id(page.fig.title.id).text == "after"
    assert replica.get_model_by_id(page.fig.x_range.id).start == -1.0


def test_draws_asked_for_by_a_draw_join_its_message(served_page):
    # the view switch: one draw sets the page's view, and each view's restyle asks for a
    # draw of its own; they must reach the page in the first draw's one message (as separate
    # messages the page laid itself out again after each one)
    page, url = served_page

    def draw():
        page.source.data = {"x": np.arange(4.0), "y": np.ones(4)}
        on_document(page.doc, lambda: setattr(page.fig.title, "text", "after"))
        on_document(page.doc, lambda: setattr(page.fig.x_range, "start", -1.0))
        on_document(page.doc, lambda: setattr(page.div, "text", "after"))

    patches, replica = in_own_loop(
        asyncio.wait_for(_client(url, page, draw), 2 * TIMEOUT), 3 * TIMEOUT
    )
    assert len(patches) == 1, [len(p.content["events"]) for p in patches]
    assert replica.get_model_by_id(page.fig.title.id).text == "after"
    assert replica.get_model_by_id(page.fig.x_range.id).start == -1.0
