"""The load test's raw protocol client reads Bokeh's messages as Bokeh writes them.

``bench/load_clients.py``'s ``RawSession`` keeps no replica of its session's document: it
takes messages off the websocket frame by frame (``FrameAssembler``: header, metadata and
content, then a buffer header and a binary payload per buffer), decodes only the patch
contents (``DocIndex``) and writes its own slider changes and document-ready event. Here
the frames are made by Bokeh's own protocol from a small document and its changes, so the
client is checked against the serializer a server uses: a data patch whose arrays travel as
binary buffers is recognised as a change of the plot data and the buffers are skipped
without losing the message after them; a patch of another model is not a data change; a
data source that arrives later in a patch is followed too; the page's marks of work in
progress are followed; and what the client sends is what Bokeh applies to a document.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from bokeh.document import Document
from bokeh.document.events import MessageSentEvent, ModelChangedEvent
from bokeh.events import DocumentReady
from bokeh.models import Column, ColumnDataSource, Div, Slider
from bokeh.plotting import figure
from bokeh.protocol import Protocol

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
from load_clients import (  # noqa: E402
    DOCUMENT_READY,
    DocIndex,
    FrameAssembler,
    column_digest,
    slider_patch,
    to_document,
)


def _frames(msg) -> list:
    """A message's websocket frames, in the order Bokeh writes them (Message.send)."""
    out = [msg.header_json, msg.metadata_json, msg.content_json]
    for buffer in msg.buffers:
        out += [json.dumps(buffer.ref), buffer.to_bytes()]
    return out


def _page():
    """A page like the dashboard's: a plot with its data source, a slider, and the main
    column marked as still building; the document records its own changes."""
    doc = Document()
    source = ColumnDataSource({"x": np.arange(5.0), "y": np.zeros(5)})
    fig = figure()
    fig.line("x", "y", source=source)
    slider = Slider(title="Harmonic case", start=1, end=7, value=1)  # step: the default
    note = Div(text="before")
    column = Column(fig, slider, note, css_classes=["page-building"])
    doc.add_root(column)
    events: list = []
    doc.on_change(events.append)
    return doc, source, slider, note, column, events


def _read(frames: list) -> list:
    """The messages a frame sequence makes, fed one frame at a time."""
    assembler = FrameAssembler()
    return [m for m in (assembler.feed(f) for f in frames) if m is not None]


def test_the_pulled_document_names_its_sources_sliders_and_marks():
    doc, source, slider, _, column, _ = _page()
    msg = Protocol().create("PULL-DOC-REPLY", "req1", doc)
    assert msg.header["num_buffers"] > 0  # the arrays travel as binary frames
    (raw,) = _read(_frames(msg))
    assert raw.msgtype == "PULL-DOC-REPLY" and len(raw.buffers) == msg.header["num_buffers"]

    index = DocIndex()
    index.add(json.loads(raw.content_json)["doc"])
    assert index.sources == {source.id}
    found = index.slider("Harmonic")
    assert found is not None and found[0] == slider.id
    assert {k: found[1][k] for k in ("value", "start", "end", "step")} == {
        "value": 1,
        "start": 1,
        "end": 7,
        "step": 1,
    }
    assert index.slider("#0") == found and index.slider("Coherence") is None
    assert index.busy  # the main column is marked page-building
    # the document rebuilt from the raw frames, buffers included, has the same plot data
    assert column_digest(to_document(raw)) == column_digest(doc)
    assert column.id in index.classes


def test_data_patches_are_recognised_and_their_buffers_skipped():
    doc, source, _, note, column, events = _page()
    pulled = Protocol().create("PULL-DOC-REPLY", "r", doc).content_json  # before the patches
    source.data = {"x": np.arange(6.0), "y": np.ones(6)}  # ColumnDataChanged, 2 buffers
    note.text = "after"  # a patch of another model
    source.stream({"x": np.array([7.0]), "y": np.array([1.0])})  # ColumnsStreamed
    source.patch({"y": [(0, 5.0)]})  # ColumnsPatched, no buffers
    # a whole new data mapping as a ModelChanged of ``data``
    events.append(ModelChangedEvent(doc, source, "data", {"x": np.arange(3.0)}))
    # the page's lower half: a new plot with a new source, then a change of its data
    later = ColumnDataSource({"a": np.arange(4.0)})
    fig = figure()
    fig.scatter("a", "a", source=later)
    column.children.append(fig)
    later.data["a"] = np.arange(4.0) + 1
    messages = [Protocol().create("PATCH-DOC", [e]) for e in events]
    assert messages[0].header["num_buffers"] == 2

    raws = _read([f for m in messages for f in _frames(m)])
    assert [r.msgtype for r in raws] == ["PATCH-DOC"] * len(messages)
    index = DocIndex()
    index.add(json.loads(pulled)["doc"])
    assert later.id not in index.sources  # not in the document pulled before
    data = [index.patch(r.content_json) for r in raws]
    assert data == [True, False, True, True, True, False, True]
    assert later.id in index.sources


def test_the_marks_of_work_in_progress_are_followed():
    doc, _, _, _, column, events = _page()
    index = DocIndex()
    index.add(json.loads(Protocol().create("PULL-DOC-REPLY", "r", doc).content_json)["doc"])
    assert index.busy
    bar = Div(text="", css_classes=["scatter-progress"])
    column.children.append(bar)
    column.css_classes = []  # the page is complete
    patches = [Protocol().create("PATCH-DOC", [e]).content_json for e in events]
    index.patch(patches[0])
    assert index.busy  # still building
    index.patch(patches[1])
    assert not index.busy  # built; the bar is there but not active
    index.patch(json.dumps({"events": [_changed(bar.id, "active", True)]}))
    assert index.busy
    index.patch(json.dumps({"events": [_changed(bar.id, "active", False)]}))
    assert not index.busy


def _changed(model_id: str, attr: str, new) -> dict:
    return {"kind": "ModelChanged", "model": {"id": model_id}, "attr": attr, "new": new}


def test_a_slider_change_from_the_server_is_followed():
    doc, _, slider, _, _, _ = _page()
    index = DocIndex()
    index.add(json.loads(Protocol().create("PULL-DOC-REPLY", "r", doc).content_json)["doc"])
    index.patch(json.dumps({"events": [_changed(slider.id, "value", 5)]}))
    assert index.slider("Harmonic")[1]["value"] == 5


def _applied(doc, content_json: str) -> None:
    header = json.dumps({"msgid": "c1", "msgtype": "PATCH-DOC"})
    Protocol().assemble(header, "{}", content_json).apply_to_document(doc, None)


def test_what_the_client_sends_is_what_bokeh_applies():
    doc, _, slider, _, _, _ = _page()
    _applied(doc, slider_patch(slider.id, 4))
    assert (slider.value, slider.value_throttled) == (4, 4)

    ready: list = []
    doc.on_event(DocumentReady, ready.append)
    _applied(doc, DOCUMENT_READY)
    assert len(ready) == 1
    # the same event as Bokeh's own client sends (load_clients.BokehSession)
    own = Protocol().create("PATCH-DOC", [MessageSentEvent(doc, "bokeh_event", DocumentReady())])
    assert json.loads(own.content_json) == json.loads(DOCUMENT_READY)


def test_frames_out_of_order_are_refused():
    assembler = FrameAssembler()
    with pytest.raises(ValueError):
        assembler.feed(b"\x00")  # bytes where a header is due
    doc, source, *_, events = _page()
    source.data = {"x": np.arange(2.0), "y": np.ones(2)}
    frames = _frames(Protocol().create("PATCH-DOC", events))
    assembler = FrameAssembler()
    for f in frames[:4]:  # header, metadata, content, first buffer header
        assert assembler.feed(f) is None
    with pytest.raises(ValueError):
        assembler.feed(frames[3])  # a second text frame where the buffer's bytes are due
