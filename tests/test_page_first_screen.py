"""A served page sends its first screen first, the rest once the browser shows it (issue 33).

A page of ~1,000 Bokeh models took 2.5 s from request to its first plot, most of it building,
sending and rendering what is below the first screen. The dashboard is served here by a Panel
server in this process; a Bokeh protocol client (what a browser receives, read off the
websocket) opens it: the document it pulls holds the first screen (the coupled response and
the error map with their data) and none of the views below it; once the client says the page
is ready, as BokehJS does, the rest arrives and the replica holds every view.
"""

from __future__ import annotations

import asyncio
import time

import pytest
from bokeh.document import Document
from bokeh.model import Model
from bokeh.models import ColumnDataSource
from server_util import PageClient, in_own_loop, served_in_process

from app.main import BUILDING, create_app

TIMEOUT = 120.0
FIRST_SCREEN = {"mobility.figure", "truncation.figure"}
BELOW = {"eigen.figure", "scatter.figure", "wheels.figure"}


def _names(doc: Document) -> set[str]:
    return {m.name for m in doc.models if getattr(m, "name", None)}


def _dressing(doc: Document, name: str) -> list[tuple]:
    """From the model named ``name`` up to the page's root: each model's type, margin and
    stylesheets (what the page's design gave it)."""
    parents = {}
    for m in doc.models:
        for c in getattr(m, "children", None) or []:
            child = c[0] if isinstance(c, tuple) else c  # (grid children: model, row, col)
            if isinstance(child, Model):  # (some models' children are names, not models)
                parents[child.id] = m
    out, x = [], next(m for m in doc.models if getattr(m, "name", None) == name)
    while x is not None:
        sheets = tuple(getattr(s, "url", None) or "inline" for s in x.stylesheets)
        out.append((type(x).__name__, tuple(x.margin or ()), sheets))
        x = parents.get(x.id)
    return out


def _building(doc: Document) -> bool:
    """Whether the page marks itself as still adding what is below its first screen."""
    return any(BUILDING in (getattr(m, "css_classes", None) or []) for m in doc.models)


def _has_data(doc: Document, name: str) -> bool:
    src = [m for m in doc.models if isinstance(m, ColumnDataSource) and m.name == name]
    return bool(src) and any(len(v) for v in src[0].data.values())


async def _client(url: str) -> tuple[Document, set[str], bool]:
    """Pull the page as a browser does; return the replica after the page said it is ready
    and every view arrived, the model names of the first document, and whether the first
    document held the coupled response's data."""
    client = await PageClient.open(url)
    pop = client.pop

    try:
        doc = await client.pull(TIMEOUT)
        first, first_data = _names(doc), _has_data(doc, "mobility.truncated")
        assert _building(doc), "the first document is not marked as building"
        await client.ready(doc)
        end = time.monotonic() + TIMEOUT
        while not BELOW <= _names(doc):
            remaining = end - time.monotonic()
            assert remaining > 0, f"the rest of the page never arrived: {_names(doc)}"
            msg = await asyncio.wait_for(pop(), remaining)
            if msg.msgtype == "PATCH-DOC":
                msg.apply_to_document(doc)
        while _building(doc):  # the mark goes in the message that adds the rest
            remaining = end - time.monotonic()
            assert remaining > 0, "the page stayed marked as building"
            msg = await asyncio.wait_for(pop(), remaining)
            if msg.msgtype == "PATCH-DOC":
                msg.apply_to_document(doc)
        return doc, first, first_data
    finally:
        client.close()


@pytest.fixture
def served_dashboard():
    with served_in_process({"main": create_app}, TIMEOUT) as port:
        yield f"ws://127.0.0.1:{port}/main/ws"


def test_the_first_screen_comes_first_and_the_rest_once_the_page_is_shown(served_dashboard):
    doc, first, first_data = in_own_loop(
        asyncio.wait_for(_client(served_dashboard), 2 * TIMEOUT), 3 * TIMEOUT
    )
    assert FIRST_SCREEN <= first, first
    assert first_data, "the first document has no coupled response to show"
    assert not (BELOW & first), BELOW & first
    # the whole page once shown: every view of the first screen kept, the rest added
    assert FIRST_SCREEN | BELOW <= _names(doc)
    # dressed by the page's design as the first screen is (inset in their cards, the same
    # stylesheets); the views built later once had their own design: no inset, plots
    # outside their cards at 1280x720 (tests/browser/test_layout.py)
    first = _dressing(doc, "mobility.figure")
    for name in ("eigen.figure", "scatter.figure"):
        assert _dressing(doc, name) == first, name
