"""The two kinds of load-test session: a real browser page, and a Bokeh protocol client.

Both give the load test (``bench/load_test.py``) one interface:

- ``await open(url)``: start a fresh session (its own Bokeh session on the server) and wait
  until the document with its plots and sliders is there;
- ``await settle(timeout_s, quiet_s)``: wait until the plot data have not changed, and no
  computation has been reported in progress, for ``quiet_s``; the plot-data digest, or
  None on timeout;
- ``await slider_info(title)``: title, value, start, end, step of a slider (``#k``: the
  k-th slider in document order; else the first whose title contains ``title``);
- ``await change(title, value, timeout_s, quiet_s)``: set the slider the way a dragged
  slider does and return ``(first, settled)`` in ms: the time to the first change of the
  plot data and to the last one before they stay quiet for ``quiet_s`` (None if the plot
  data never changed);
- ``await plot_digest(timeout_s)``: the digest of the session's plot data now (what the
  isolation check compares, once the session has settled);
- ``errors``: what went wrong in the session (page errors, protocol errors);
- ``await close()``.

``BrowserSession`` is a playwright browser context with one page (the JavaScript that runs
in the page times its changes with ``performance.now()``). ``BokehSession`` speaks Bokeh's
websocket protocol directly (``ACK``, ``PULL-DOC``, ``PATCH-DOC``): it holds a replica of
the session's document, applies the server's patches to it and sends model changes like
BokehJS does, including the ``document_ready`` event after the document has arrived (which
starts the app's on-load work). It costs a fraction of a browser's CPU, so a load test on
one machine measures the server rather than the browsers; rendering is what it leaves out.
Applying every patch to a replica still costs CPU (50 sessions kept the clients' core
busy); ``RawSession`` keeps no replica: it opens the session as a browser does (the page,
its token, the websocket, document-ready), decodes only message headers and patch
contents, timestamps the patches that change plot data, and pulls the document once more
at the end for the isolation check.

Digests (a count and a weighted sum of the numbers in every ``ColumnDataSource``) are
compared only between sessions of the same kind.
"""

from __future__ import annotations

import asyncio
import contextlib
import importlib
import itertools
import json
import pkgutil
import re
import sys
import time
import urllib.parse
import urllib.request
from pathlib import Path

import numpy as np

# the page digest and the browser launch arguments are the Docker smoke test's
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docker"))
from smoke_test import DIGEST_JS, chromium_args  # noqa: E402, F401

# ---- browser -----------------------------------------------------------------------------

READY_JS = """() => window.Bokeh && Bokeh.documents.length > 0 &&
  [...Bokeh.documents[0].all_models].some(m => m.type === 'ColumnDataSource' &&
    Object.values(m.data instanceof Map ? Object.fromEntries(m.data) : m.data)
      .some(c => c && c.length > 0)) &&
  [...Bokeh.documents[0].all_models].some(m => m.type.endsWith('Slider'))"""

SLIDER_JS = """(title) => {
  const all = [...Bokeh.documents[0].all_models].filter(m => m.type.endsWith('Slider'));
  if (title.startsWith('#')) return all[parseInt(title.slice(1))];
  return all.find(m => !title || String(m.title).includes(title));
}"""

SLIDER_INFO_JS = f"""(title) => {{
  const m = ({SLIDER_JS})(title);
  return m ? {{title: m.title, value: m.value, start: m.start, end: m.end, step: m.step}} : null;
}}"""

#: Set the slider value and time the plot-data changes; returns [first, settled] in ms.
CHANGE_JS = f"""async ([title, value, timeout, quiet]) => {{
  const digest = {DIGEST_JS};
  const m = ({SLIDER_JS})(title);
  const before = digest();
  const t0 = performance.now();
  m.setv({{value: value, value_throttled: value}});
  let first = null, last = null, current = before;
  while (performance.now() - t0 < timeout) {{
    await new Promise(r => setTimeout(r, 25));
    const now = performance.now();
    const d = digest();
    if (d !== current) {{ current = d; last = now; if (first === null) first = now; }}
    if (last !== null && now - last > quiet) break;
  }}
  return first === null ? null : [first - t0, last - t0];
}}"""

#: True while the page reports a computation in progress (the scatter band's progress bar):
#: under load a band can take longer than any fixed quiet time.
#: Busy: a band computing (its progress bar active) or the page still adding what is below
#: its first screen (its main column marked ``page-building``, app/main.py).
BUSY_JS = """() => [...Bokeh.documents[0].all_models].some(m => m.css_classes && (
  (m.css_classes.includes('scatter-progress') && m.active === true)
  || m.css_classes.includes('page-building')))"""

SETTLE_JS = f"""async ([timeout, quiet]) => {{
  const digest = {DIGEST_JS};
  const busy = {BUSY_JS};
  const t0 = performance.now();
  let current = digest(), last = t0;
  while (performance.now() - t0 < timeout) {{
    await new Promise(r => setTimeout(r, 50));
    const d = digest();
    if (d !== current || busy()) {{ current = d; last = performance.now(); }}
    if (performance.now() - last > quiet) return current;
  }}
  return null;
}}"""


class BrowserSession:
    """One browser context with one page (its own cookies and Bokeh session)."""

    def __init__(self, browser):
        self._browser = browser
        self.context = self.page = None
        self.errors: list[str] = []

    async def open(self, url: str, timeout_s: float) -> None:
        self.context = await self._browser.new_context(viewport={"width": 1400, "height": 1000})
        self.page = await self.context.new_page()
        self.page.on(
            "pageerror",
            lambda exc: self.errors.append(
                f"page error: {exc}; stack: {' | '.join((exc.stack or '').splitlines()[:6])}"
            ),
        )
        ms = timeout_s * 1000
        await self.page.goto(url, timeout=ms)
        await self.page.wait_for_function(READY_JS, timeout=ms, polling=100)

    async def settle(self, timeout_s: float, quiet_s: float) -> str | None:
        return await self.page.evaluate(SETTLE_JS, [timeout_s * 1000, quiet_s * 1000])

    async def slider_info(self, title: str) -> dict | None:
        return await self.page.evaluate(SLIDER_INFO_JS, title)

    async def change(self, title: str, value, timeout_s: float, quiet_s: float):
        return await self.page.evaluate(CHANGE_JS, [title, value, timeout_s * 1000, quiet_s * 1000])

    async def plot_digest(self, timeout_s: float) -> str:
        return await self.page.evaluate(DIGEST_JS)

    async def close(self) -> None:
        if self.context is not None:
            await self.context.close()


# ---- Bokeh protocol client ---------------------------------------------------------------

_MODELS_LOADED = False


def _load_model_classes() -> None:
    """Import every Panel model module, so the document's custom models deserialize."""
    global _MODELS_LOADED
    if _MODELS_LOADED:
        return
    import panel  # noqa: F401  (registers Panel's models with Bokeh)
    import panel.models

    for info in pkgutil.iter_modules(panel.models.__path__):
        try:
            importlib.import_module(f"panel.models.{info.name}")
        except ImportError:  # optional extras (e.g. a model needing an absent package)
            pass
    _MODELS_LOADED = True


_APP_URLS: dict[str, str] = {}


def websocket_url(url: str, headers: dict | None = None) -> str:
    """The Bokeh websocket endpoint of an app URL (``http://h:p/app`` -> ``ws://h:p/app/ws``).

    A server root that redirects to its app (``panel serve`` of one script: ``/`` ->
    ``/main``) is followed first, as a browser would (sending ``headers``, e.g. a login
    cookie).
    """
    if url not in _APP_URLS and not urllib.parse.urlsplit(url).path.strip("/"):
        # only a server root is followed: a request of an app's page builds a page that
        # this client would never open (and spends the user's page-build budget)
        req = urllib.request.Request(url, headers=headers or {})
        with urllib.request.urlopen(req, timeout=60) as r:
            _APP_URLS[url] = r.geturl()
    parts = urllib.parse.urlsplit(_APP_URLS.get(url, url))
    scheme = {"http": "ws", "https": "wss"}.get(parts.scheme, parts.scheme)
    path = parts.path.rstrip("/") + "/ws"
    return urllib.parse.urlunsplit((scheme, parts.netloc, path, "", ""))


def column_digest(doc) -> str:
    """Count and weighted sum of the finite numbers of every ColumnDataSource of ``doc``."""
    from bokeh.models import ColumnDataSource

    out = []
    for m in doc.models:
        if not isinstance(m, ColumnDataSource):
            continue
        n, s = 0, 0.0
        for col in m.data.values():
            if isinstance(col, str) or not hasattr(col, "__len__"):
                continue
            n += len(col)
            try:
                v = np.asarray(col, dtype=float).ravel()
            except (TypeError, ValueError):  # lists of arrays of different shapes, strings
                v = np.concatenate(
                    [np.asarray(c, dtype=float).ravel() for c in col if not isinstance(c, str)]
                    or [np.zeros(0)]
                )
            v = v[np.isfinite(v)]
            s += float(np.sum(v * np.sqrt(np.arange(v.size) + 2.0) + v * v))
        out.append(f"{n}:{s:.9e}")
    return "|".join(sorted(out))


class BokehSession:
    """A Bokeh websocket client with a replica of its session's document.

    Two tasks share the work. The reader takes each message off the socket as soon as it
    arrives and notes the arrival time of every patch that touches a ColumnDataSource (the
    plot data); the applier applies the patches to the replica in order and keeps a digest
    of the plot data. Latencies are arrival times, so a client that is busy applying other
    sessions' patches does not count its own backlog as the server's.
    """

    def __init__(
        self, *, max_message_mb: int = 200, headers: dict | None = None, token: str | None = None
    ):
        _load_model_classes()
        self._max_bytes = max_message_mb * 2**20
        self._headers = dict(headers or {})  # e.g. Cookie (a login), Origin
        self._token = token  # of a session the server made for a page (else a new session)
        self.errors: list[str] = []
        self.doc = None
        self._ws = self._sock = None
        self._tasks: list[asyncio.Task] = []
        self._queue: asyncio.Queue = asyncio.Queue()
        self._digest = ""
        self._change_times: list[float] = []  # arrival of each patch of plot data
        self._patched_at = 0.0  # arrival of the last patch of any kind
        self._sources: set[str] = set()  # ids of the ColumnDataSources
        self._progress: list = []  # the progress bars of long computations (class name)
        self._building: list = []  # the page's column while it is being completed
        self._n_models = 0

    @property
    def digest(self) -> str:
        """Digest of the replica's plot data (:func:`column_digest`) after the last patch."""
        return self._digest

    async def open(self, url: str, timeout_s: float) -> None:
        from bokeh.client.websocket import WebSocketClientConnectionWrapper
        from bokeh.document import Document
        from bokeh.document.events import MessageSentEvent
        from bokeh.events import DocumentReady
        from bokeh.protocol import Protocol
        from bokeh.protocol.receiver import Receiver
        from bokeh.util.token import generate_jwt_token, generate_session_id
        from tornado.httpclient import HTTPRequest
        from tornado.websocket import websocket_connect

        self._protocol = Protocol()
        self._receiver = Receiver(self._protocol)
        token = self._token or generate_jwt_token(generate_session_id())
        self._ws = await asyncio.wait_for(
            websocket_connect(
                HTTPRequest(websocket_url(url, self._headers), headers=self._headers),
                subprotocols=["bokeh", token],
                max_message_size=self._max_bytes,
            ),
            timeout_s,
        )
        self._sock = WebSocketClientConnectionWrapper(self._ws)
        ack = await asyncio.wait_for(self._pop(), timeout_s)
        if ack is None or ack.msgtype != "ACK":
            raise RuntimeError(f"expected ACK from the server, got {ack and ack.msgtype}")
        await self._protocol.create("PULL-DOC-REQ").send(self._sock)
        reply = await asyncio.wait_for(self._pop(), timeout_s)
        while reply is not None and reply.msgtype == "PATCH-DOC":
            # a change of the session made before the reply (e.g. the progress of a band
            # started with the page): the document in the reply already holds it
            reply = await asyncio.wait_for(self._pop(), timeout_s)
        if reply is None or reply.msgtype != "PULL-DOC-REPLY":
            raise RuntimeError(
                f"expected PULL-DOC-REPLY, got {reply and reply.msgtype}: {reply and reply.content}"
            )
        self.doc = Document()
        reply.push_to_document(self.doc)
        self._index_models()
        self._digest = column_digest(self.doc)
        self._tasks = [asyncio.ensure_future(self._read()), asyncio.ensure_future(self._apply())]
        # what BokehJS sends once the page has rendered: starts the app's on-load work
        await self._send([MessageSentEvent(self.doc, "bokeh_event", DocumentReady())])

    def _index_models(self) -> None:
        from bokeh.models import ColumnDataSource

        self._n_models = len(self.doc.models)
        self._sources = {m.id for m in self.doc.models if isinstance(m, ColumnDataSource)}
        self._progress = [
            m
            for m in self.doc.models
            if "css_classes" in m.properties() and "scatter-progress" in m.css_classes
        ]
        self._building = [  # the page's main column while it adds the rest (app/main.py)
            m
            for m in self.doc.models
            if "css_classes" in m.properties() and "page-building" in m.css_classes
        ]

    async def _pop(self):
        while True:
            frag = await self._ws.read_message()
            if frag is None:
                return None
            msg = await self._receiver.consume(frag)
            if msg is not None:
                return msg

    async def _send(self, events) -> None:
        await self._protocol.create("PATCH-DOC", events).send(self._sock)

    async def send(self, events) -> None:
        """Send document events (e.g. ``ModelChangedEvent``) as one patch, as BokehJS does."""
        await self._send(events)

    async def _read(self) -> None:
        while True:
            msg = await self._pop()
            if msg is None:
                return
            if msg.msgtype == "ERROR":
                self.errors.append(f"server error: {msg.content.get('text')}")
            elif msg.msgtype == "PATCH-DOC":
                self._patched_at = time.perf_counter()
                if any(_event_model_id(e) in self._sources for e in msg.content["events"]):
                    self._change_times.append(time.perf_counter())
                self._queue.put_nowait(msg)

    async def _apply(self) -> None:
        while True:
            msg = await self._queue.get()
            try:
                msg.apply_to_document(self.doc, self)
                events = msg.content["events"]
                if len(self.doc.models) != self._n_models:
                    self._index_models()  # models came or went
                if any(_event_model_id(e) in self._sources for e in events):
                    self._digest = column_digest(self.doc)
            except Exception as exc:  # a patch the replica cannot apply is a finding
                self.errors.append(f"{type(exc).__name__} applying a server patch: {exc}")
            finally:
                self._queue.task_done()
            await asyncio.sleep(0)  # let the readers of other sessions in

    @property
    def _changed_at(self) -> float:
        return self._change_times[-1] if self._change_times else 0.0

    def _busy(self) -> bool:
        return any(getattr(m, "active", False) for m in self._progress) or any(
            "page-building" in m.css_classes for m in self._building
        )

    def _slider(self, title: str):
        sliders = [m for m in self.doc.models if type(m).__name__.endswith("Slider")]
        if title.startswith("#"):
            k = int(title[1:])
            return sliders[k] if k < len(sliders) else None
        return next((m for m in sliders if not title or title in str(m.title)), None)

    async def find(self, predicate, timeout_s: float):
        """The first model of the replica for which ``predicate(model)`` holds, once one does
        (a page builds what is below its first screen once it is shown: the upload widgets
        of the dashboard arrive after the first document); None after ``timeout_s``."""
        t0 = time.perf_counter()
        while True:
            m = next((m for m in self.doc.models if predicate(m)), None)
            if m is not None or time.perf_counter() - t0 > timeout_s:
                return m
            await asyncio.sleep(0.05)

    async def settle(self, timeout_s: float, quiet_s: float) -> str | None:
        t0 = time.perf_counter()
        last = max(t0, self._changed_at, self._patched_at)
        while time.perf_counter() - t0 < timeout_s:
            await asyncio.sleep(0.05)
            now = time.perf_counter()
            if self._busy() or not self._queue.empty():
                last = now
            # any message is activity: a page still building (the dashboard adds what is
            # below its first screen once shown) is not settled
            last = max(last, self._changed_at, self._patched_at)
            if now - last > quiet_s:
                return self._digest
        return None

    async def plot_digest(self, timeout_s: float) -> str:
        await asyncio.wait_for(self._queue.join(), timeout_s)
        return self._digest

    async def slider_info(self, title: str) -> dict | None:
        m = self._slider(title)
        if m is None:
            return None
        return {"title": m.title, "value": m.value, "start": m.start, "end": m.end, "step": m.step}

    async def change(self, title: str, value, timeout_s: float, quiet_s: float):
        from bokeh.document.events import ModelChangedEvent

        m = self._slider(title)
        n0, before = len(self._change_times), self._digest
        t0 = time.perf_counter()
        # the replica changes without an echo (setter=self); the server gets both
        # properties a released slider sets, in one patch, as BokehJS sends them
        events = []
        for attr in ("value", "value_throttled"):
            m.set_from_json(attr, value, setter=self)
            events.append(ModelChangedEvent(self.doc, m, attr, value))
        await self._send(events)
        while time.perf_counter() - t0 < timeout_s:
            await asyncio.sleep(0.01)
            if len(self._change_times) > n0 and time.perf_counter() - self._changed_at > quiet_s:
                break
        await self._queue.join()  # applied: the digest is that of the new state
        if len(self._change_times) == n0 or self._digest == before:
            return None
        return [(self._change_times[n0] - t0) * 1000, (self._changed_at - t0) * 1000]

    async def close(self) -> None:
        for task in self._tasks:
            task.cancel()
            try:
                await task
            except (asyncio.CancelledError, Exception):
                pass
        if self._ws is not None:
            self._ws.close()


def _event_model_id(event: dict) -> str | None:
    model = event.get("model")
    if isinstance(model, dict):
        return model.get("id")
    return None


# ---- raw protocol client -----------------------------------------------------------------

#: Patch events that change a data source's ``data`` in place (a ``ModelChanged`` of
#: ``data`` replaces it whole).
DATA_EVENTS = frozenset({"ColumnDataChanged", "ColumnsStreamed", "ColumnsPatched"})

#: The page's marks of work in progress (app/main.py, the scatter band): see ``BUSY_JS``.
BUILDING, PROGRESS = "page-building", "scatter-progress"


class RawMessage:
    """One Bokeh message as it came off the socket: its header decoded, the rest as text
    and bytes (buffers are ``(buffer header, payload)`` frame pairs, left undecoded)."""

    __slots__ = ("header_json", "header", "metadata_json", "content_json", "buffers")

    def __init__(self, header_json: str, metadata_json: str, content_json: str) -> None:
        self.header_json = header_json
        self.header = json.loads(header_json)
        self.metadata_json = metadata_json
        self.content_json = content_json
        self.buffers: list[tuple[str, bytes]] = []

    @property
    def msgtype(self) -> str:
        return self.header["msgtype"]

    @property
    def complete(self) -> bool:
        return len(self.buffers) >= self.header.get("num_buffers", 0)


class FrameAssembler:
    """Bokeh's wire format read frame by frame: a message is three text frames (header,
    metadata, content) and then, for each of the header's ``num_buffers``, a text frame
    (the buffer's id) and a binary frame (its bytes). Only the header is decoded here."""

    def __init__(self) -> None:
        self._texts: list[str] = []
        self._partial: RawMessage | None = None
        self._buffer_header: str | None = None

    def feed(self, frame: str | bytes) -> RawMessage | None:
        """Take the next frame; the message it completes, if any."""
        msg = self._partial
        if msg is None:
            if not isinstance(frame, str):
                raise ValueError("a binary frame where a message's text frame was due")
            self._texts.append(frame)
            if len(self._texts) < 3:
                return None
            msg = RawMessage(*self._texts)
            self._texts = []
        elif self._buffer_header is None:
            if not isinstance(frame, str):
                raise ValueError("a binary frame where a buffer header was due")
            self._buffer_header = frame
            return None
        else:
            if not isinstance(frame, bytes):
                raise ValueError("a text frame where a buffer's bytes were due")
            msg.buffers.append((self._buffer_header, frame))
            self._buffer_header = None
        self._partial = None if msg.complete else msg
        return msg if msg.complete else None


def _model_id(event: dict) -> str | None:
    model = event.get("model")
    return model.get("id") if isinstance(model, dict) else None


def _definitions(value, out: list[dict]) -> list[dict]:
    """The model definitions (``{"type": "object", ...}``) anywhere in decoded JSON."""
    stack = [value]
    while stack:
        v = stack.pop()
        if isinstance(v, dict):
            if v.get("type") == "object" and "id" in v:
                out.append(v)
            stack.extend(x for x in v.values() if isinstance(x, (dict, list)))
        elif isinstance(v, list):
            stack.extend(x for x in v if isinstance(x, (dict, list)))
    return out


class DocIndex:
    """What a raw client follows of its session's document, from the document's JSON and
    the patches: the ids of the data sources (every ``ColumnDataSource``, the plot data the
    Bokeh client digests), the sliders (their attributes, in document order) and the marks
    of work in progress (a column marked ``page-building``, an active ``scatter-progress``
    bar)."""

    def __init__(self) -> None:
        self.sources: set[str] = set()
        self.sliders: dict[str, dict] = {}  # id -> attributes (name under "__name__")
        self.classes: dict[str, list[str]] = {}  # id -> css_classes, of the marked models
        self.active: dict[str, bool] = {}  # id -> active, of the progress bars

    def add(self, value) -> None:
        """Learn the models defined anywhere in ``value`` (a document's or patch's JSON)."""
        for d in _definitions(value, []):
            name, mid, attrs = d.get("name", ""), d["id"], d.get("attributes") or {}
            if name == "ColumnDataSource":
                self.sources.add(mid)
            elif name.rsplit(".", 1)[-1].endswith("Slider"):
                self.sliders[mid] = {"__name__": name, "title": "", "step": 1, **attrs}
            classes = attrs.get("css_classes")
            if isinstance(classes, list) and (BUILDING in classes or PROGRESS in classes):
                self.classes[mid] = classes
                self.active.setdefault(mid, bool(attrs.get("active", False)))

    def patch(self, content_json: str) -> bool:
        """Follow a PATCH-DOC's content; True if it changes a data source's data."""
        events = json.loads(content_json)["events"]
        if '"object"' in content_json:  # new models (e.g. the page's lower half)
            self.add(events)
        data = False
        for e in events:
            kind, mid = e.get("kind"), _model_id(e)
            if mid is None:
                continue
            if kind in DATA_EVENTS or (kind == "ModelChanged" and e.get("attr") == "data"):
                data |= mid in self.sources
            elif kind == "ModelChanged":
                attr, new = e.get("attr"), e.get("new")
                if mid in self.sliders:
                    self.sliders[mid][attr] = new
                if attr == "css_classes" and isinstance(new, list):
                    self.classes[mid] = new
                elif attr == "active" and mid in self.classes:
                    self.active[mid] = bool(new)
        return data

    @property
    def busy(self) -> bool:
        """The page still building its lower half, or a band being computed."""
        return any(
            BUILDING in c or (PROGRESS in c and self.active.get(mid, False))
            for mid, c in self.classes.items()
        )

    def slider(self, title: str) -> tuple[str, dict] | None:
        """(id, attributes) of a slider: ``#k`` the k-th, else the first whose title
        contains ``title``."""
        items = list(self.sliders.items())
        if title.startswith("#"):
            k = int(title[1:])
            return items[k] if k < len(items) else None
        return next(((i, a) for i, a in items if not title or title in str(a["title"])), None)


def slider_patch(model_id: str, value) -> str:
    """The content of the PATCH-DOC a released slider sends (BokehJS: both properties)."""
    return json.dumps(
        {
            "events": [
                {"kind": "ModelChanged", "model": {"id": model_id}, "attr": attr, "new": value}
                for attr in ("value", "value_throttled")
            ]
        }
    )


#: The content of BokehJS's document-ready event (what Bokeh's own ``DocumentReady``
#: serializes to): the server then runs the page's on-load callbacks.
DOCUMENT_READY = json.dumps(
    {
        "events": [
            {
                "kind": "MessageSent",
                "msg_type": "bokeh_event",
                "msg_data": {"type": "event", "name": "document_ready", "values": {"type": "map"}},
            }
        ]
    }
)

#: The session token in a served page (``render_items`` of its embedding script).
TOKEN = re.compile(r'"token"\s*:\s*"([^"]+)"')


def to_document(msg: RawMessage):
    """A Bokeh ``Document`` from a raw ``PULL-DOC-REPLY`` (its buffers included)."""
    from bokeh.document import Document
    from bokeh.protocol import Protocol

    _load_model_classes()
    full = Protocol().assemble(msg.header_json, msg.metadata_json, msg.content_json)
    for buffer_header, payload in msg.buffers:
        full.assemble_buffer(json.loads(buffer_header), payload)
    doc = Document()
    full.push_to_document(doc)
    return doc


class RawSession:
    """A browser's session reduced to its messages: the page is fetched (its session token),
    the websocket opened with it, the document pulled as JSON, then BokehJS's
    document-ready and slider changes are sent as raw Bokeh messages. Of what arrives only
    headers and patch contents are decoded (never the buffers of the data): enough to
    timestamp the patches that change a data source, follow the sliders and the page's
    marks of work in progress. No replica: :meth:`digest` pulls the document once more and
    digests its plot data as the Bokeh client does (:func:`column_digest`), and checks that
    each slider this session set holds the value it set last."""

    def __init__(self, *, max_message_mb: int = 200, headers: dict | None = None):
        self._max_bytes = max_message_mb * 2**20
        self._headers = dict(headers or {})
        self.errors: list[str] = []
        self.index = DocIndex()
        self._ws = None
        self._reader: asyncio.Task | None = None
        self._send_lock = asyncio.Lock()
        self._msgids = itertools.count()
        self._data_times: list[float] = []  # arrival of each patch changing plot data
        self._data_arrived = asyncio.Event()
        self._patched_at = 0.0  # arrival of the last patch of any kind
        self._pulls: list[asyncio.Future] = []
        self._set: dict[str, object] = {}  # slider id -> the value this session set last
        self._closing = False

    async def _fetch_page(self, url: str, timeout_s: float) -> tuple[str, str]:
        from tornado.httpclient import AsyncHTTPClient, HTTPRequest

        client = AsyncHTTPClient(force_instance=True)
        try:
            r = await client.fetch(
                HTTPRequest(
                    url,
                    headers=self._headers,
                    follow_redirects=True,
                    connect_timeout=timeout_s,
                    request_timeout=timeout_s,
                )
            )
        finally:
            client.close()
        found = TOKEN.search(r.body.decode("utf-8", "replace"))
        if found is None:
            raise RuntimeError(f"no session token in the page {r.effective_url}")
        return r.effective_url, found.group(1)

    async def open(self, url: str, timeout_s: float) -> None:
        from tornado.httpclient import HTTPRequest
        from tornado.websocket import websocket_connect

        page_url, token = await self._fetch_page(url, timeout_s)
        parts = urllib.parse.urlsplit(page_url)
        scheme = {"http": "ws", "https": "wss"}.get(parts.scheme, parts.scheme)
        ws_url = urllib.parse.urlunsplit(
            (scheme, parts.netloc, parts.path.rstrip("/") + "/ws", "", "")
        )
        headers = {"Origin": f"{parts.scheme}://{parts.netloc}", **self._headers}
        # a browser waits for the handshake as long as it takes (tornado: 20 s); a server
        # building many pages answers it late
        request = HTTPRequest(
            ws_url, headers=headers, connect_timeout=timeout_s, request_timeout=timeout_s
        )
        self._ws = await asyncio.wait_for(
            websocket_connect(
                request,
                subprotocols=["bokeh", token],
                max_message_size=self._max_bytes,
            ),
            timeout_s,
        )
        frames = FrameAssembler()

        async def pop() -> RawMessage:
            while True:
                frame = await self._ws.read_message()
                if frame is None:
                    raise RuntimeError("the server closed the websocket")
                msg = frames.feed(frame)
                if msg is not None:
                    return msg

        ack = await asyncio.wait_for(pop(), timeout_s)
        if ack.msgtype != "ACK":
            raise RuntimeError(f"expected ACK from the server, got {ack.msgtype}")
        await self._send("PULL-DOC-REQ", "{}")
        reply = await asyncio.wait_for(pop(), timeout_s)
        while reply.msgtype == "PATCH-DOC":  # made before the reply, which holds it
            reply = await asyncio.wait_for(pop(), timeout_s)
        if reply.msgtype != "PULL-DOC-REPLY":
            raise RuntimeError(f"expected PULL-DOC-REPLY, got {reply.msgtype}")
        self.index.add(json.loads(reply.content_json)["doc"])
        self._reader = asyncio.ensure_future(self._read(frames))
        await self._send("PATCH-DOC", DOCUMENT_READY)  # the page is shown: on-load work

    async def _send(self, msgtype: str, content_json: str) -> None:
        header = json.dumps({"msgid": f"r{next(self._msgids)}", "msgtype": msgtype})
        async with self._send_lock:  # one message's three frames together
            for frame in (header, "{}", content_json):
                await self._ws.write_message(frame)

    async def _read(self, frames: FrameAssembler) -> None:
        try:
            while True:
                frame = await self._ws.read_message()
                if frame is None:
                    if not self._closing:
                        self.errors.append("the server closed the websocket")
                    return
                msg = frames.feed(frame)
                if msg is None:
                    continue
                kind = msg.msgtype
                if kind == "PATCH-DOC":
                    now = time.perf_counter()
                    self._patched_at = now
                    if self.index.patch(msg.content_json):
                        self._data_times.append(now)
                        self._data_arrived.set()
                elif kind == "PULL-DOC-REPLY" and self._pulls:
                    pulled = self._pulls.pop(0)
                    if not pulled.done():  # else the puller gave up waiting
                        pulled.set_result(msg)
                elif kind == "ERROR":
                    self.errors.append(f"server error: {json.loads(msg.content_json).get('text')}")
        except Exception as exc:  # a message this client cannot read is a finding
            self.errors.append(f"{type(exc).__name__} reading the server's messages: {exc}")

    async def settle(self, timeout_s: float, quiet_s: float) -> str | None:
        """Wait until no patch has arrived for ``quiet_s`` and the page marks no work in
        progress; the number of plot-data patches so far (None on timeout)."""
        t0 = time.perf_counter()
        last = max(t0, self._patched_at)
        while True:
            now = time.perf_counter()
            if self.index.busy:
                last = now
            last = max(last, self._patched_at)
            if now - last > quiet_s:
                return f"{len(self._data_times)} plot-data patches"
            if now - t0 > timeout_s:
                return None
            await asyncio.sleep(max(0.05, last + quiet_s - now + 0.001))

    async def slider_info(self, title: str) -> dict | None:
        found = self.index.slider(title)
        if found is None:
            return None
        a = found[1]
        return {k: a.get(k) for k in ("title", "value", "start", "end", "step")}

    async def change(self, title: str, value, timeout_s: float, quiet_s: float):
        found = self.index.slider(title)
        if found is None:
            raise LookupError(f"no slider {title!r}")
        mid, attrs = found
        n0 = len(self._data_times)
        t0 = time.perf_counter()
        self._data_arrived.clear()
        await self._send("PATCH-DOC", slider_patch(mid, value))
        attrs["value"] = attrs["value_throttled"] = value
        self._set[mid] = value
        end = t0 + timeout_s
        while True:
            now = time.perf_counter()
            if now >= end:
                break
            if len(self._data_times) > n0:
                wait = self._data_times[-1] + quiet_s - now
                if wait <= 0:
                    break
                await asyncio.sleep(min(wait + 0.001, end - now))
            else:
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(self._data_arrived.wait(), end - now)
        if len(self._data_times) == n0:
            return None
        return [(self._data_times[n0] - t0) * 1000, (self._data_times[-1] - t0) * 1000]

    async def plot_digest(self, timeout_s: float) -> str:
        """Pull the document again: the digest of its plot data (:func:`column_digest`);
        a slider of the server's document not holding what this session set is an error."""
        pulled = asyncio.get_running_loop().create_future()
        self._pulls.append(pulled)
        await self._send("PULL-DOC-REQ", "{}")
        doc = to_document(await asyncio.wait_for(pulled, timeout_s))
        for mid, value in self._set.items():
            model = doc.get_model_by_id(mid)
            held = getattr(model, "value", None)
            if held != value:
                self.errors.append(
                    f"the server's slider {mid} holds {held}, this session set {value} last"
                )
        return column_digest(doc)

    async def close(self) -> None:
        self._closing = True
        if self._ws is not None:
            self._ws.close()
        if self._reader is not None:
            self._reader.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await self._reader
