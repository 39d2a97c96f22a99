"""The skeleton every view shares: a figure built once, redrawn from a published result.

A view is a :class:`LiveView` subclass that says which result of the session's
:class:`~app.store.Results` it shows and how to draw it::

    class EigenView(LiveView):
        key = "eigen"                                   # CSV name, css class

        def result(self):
            return self.store.eigen

        @param.depends("store.eigen", watch=True)
        def _changed(self):
            self.redraw()

        def _build(self):                              # Bokeh figures, once per session
            ...

        def _draw(self, r):                            # assign sources from ``r``
            ...

Drawing goes through the session's :class:`DrawQueue`: from any thread, the draws run one
after the other on the session's event loop under its document lock (Bokeh's
``with_locked_document``), each one's patches written to the page before the next draw, in
the order they were asked for. A redraw draws the result published *when it runs*, so
redraws may come from any thread in any order: the last one shows the newest result.
Redraws already waiting are not queued twice.
"""

from __future__ import annotations

import datetime as dt
import html
import io
import logging
import re
import threading
import weakref
from collections import deque
from functools import partial

import panel as pn
import param
from bokeh.document import without_document_lock
from panel.io.state import set_curdoc
from panel.viewable import Viewer

from .. import compute
from ..export import to_csv
from ..panel_private import html_model, html_text
from ..report.bokeh import TitleBlockModels, style_figure
from ..report.live import page_url, view_title
from ..store import Result, Results
from .plots import fit_range


def _plots_in(obj) -> list:
    """The Bokeh plots of ``obj``: itself if it is one, else those of its layout in order."""
    from bokeh.models import Plot

    if isinstance(obj, Plot):
        return [obj]
    return list(obj.select({"type": Plot})) if hasattr(obj, "select") else []


log = logging.getLogger(__name__)

__all__ = [
    "DrawQueue",
    "LiveText",
    "LiveView",
    "download_button",
    "export_meta",
    "inline_html",
    "on_document",
    "served_document",
]


def served_document():
    """The Bokeh document of the current served session (None: no server)."""
    doc = pn.state.curdoc
    return doc if doc is not None and doc.session_context is not None else None


def inline_html(text: str) -> str:
    """A caption's text as HTML: escaped, then ``**bold**`` and ``&middot;`` restored.

    Values in captions may come from users' files (DOF labels), hence the escaping.
    """
    out = html.escape(text, quote=False).replace("&amp;middot;", "&middot;")
    return re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", out)


def export_meta(meta, url: str | None = None, now: dt.datetime | None = None) -> dict:
    """A result's CSV header with the provenance every export carries: the core's version,
    the date of the export and the page URL that reproduces it."""
    now = now or dt.datetime.now(dt.UTC)
    url = page_url() if url is None else url
    return {
        **meta,
        "fbs_core version": compute.version(),
        "exported": now.strftime("%Y-%m-%d %H:%M UTC"),
        "page URL": url or "(not served: no page URL)",
    }


def download_button(key: str, result) -> pn.widgets.FileDownload:
    """A CSV download of ``result()``: its columns under its own header and file name."""

    def callback():
        r = result()
        if r is None:
            return io.StringIO("")
        btn.filename = r.filename
        return io.StringIO(to_csv(r.columns, export_meta(r.meta), key))

    first = result()
    btn = pn.widgets.FileDownload(
        callback=callback,
        filename=first.filename if first is not None else f"{key}.csv",
        label="CSV",
        button_type="light",
        width=90,
        embed=False,
        css_classes=[f"download-{key}"],
    )
    return btn


def on_document(doc, fn) -> None:
    """Run ``fn`` (changes of Bokeh models) where it may change the served document
    ``doc``: on the session's event loop under its lock, whichever thread asks (``doc``
    None: no server, at once), after the changes asked for before it (:class:`DrawQueue`)."""
    if doc is None or doc.session_context is None:
        fn()  # no server: tests, notebooks, exports
    else:
        DrawQueue.of(doc).add(fn)


class DrawQueue:
    """A served session's draws, run one after the other on its event loop.

    Each draw runs under the document lock (Bokeh's ``with_locked_document``) and its
    patches are written to the socket before the next draw starts. Scheduled as separate
    next-tick callbacks instead, every socket write of a draw (a data patch is seven
    websocket frames) waited for one turn of the event loop, in which the session's other
    waiting draws ran in full: the view drawn first (the Analysis card's shown view)
    reached the page only after the main views' draws (10-40 ms each). One queue per
    document, in the order the draws were asked for; a failing draw is logged and the
    next one runs.
    """

    _queues: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
    _queues_lock = threading.Lock()

    def __init__(self, doc) -> None:
        self._doc = weakref.ref(doc)
        self._fns: deque = deque()
        self._lock = threading.Lock()
        self._running = False

    @classmethod
    def of(cls, doc) -> DrawQueue:
        """The queue of document ``doc`` (made on first use)."""
        with cls._queues_lock:
            q = cls._queues.get(doc)
            if q is None:
                q = cls._queues[doc] = cls(doc)
            return q

    @classmethod
    def discard(cls, doc) -> None:
        """Drop the draws still waiting for ``doc`` (its session ended: a next-tick callback
        of a destroyed session may never run, and a waiting draw keeps its page alive)."""
        if doc is None:
            return
        with cls._queues_lock:
            q = cls._queues.pop(doc, None)
        if q is not None:
            q.clear()

    def clear(self) -> None:
        """Drop the draws waiting in this queue."""
        with self._lock:
            self._fns.clear()

    def add(self, fn) -> None:
        """Run ``fn`` after the draws already waiting (from any thread)."""
        with self._lock:
            self._fns.append(fn)
            if self._running:
                return
            self._running = True
        doc = self._doc()
        try:
            if doc is None:
                raise RuntimeError("document gone")
            doc.add_next_tick_callback(self._drain)  # thread-safe in Bokeh
        except Exception:
            with self._lock:  # the session is gone: nothing will draw
                self._fns.clear()
                self._running = False

    @without_document_lock
    async def _drain(self) -> None:
        while True:
            with self._lock:
                if not self._fns:
                    self._running = False
                    return
                fn = self._fns.popleft()
            doc = self._doc()
            if doc is None or doc.session_context is None:
                continue
            try:  # returns once the draw's patches are written (or the session ended)
                await doc.session_context.with_locked_document(partial(_run_on, fn))
            except Exception:
                log.exception("drawing on the page failed")


def _run_on(fn, doc) -> None:
    with set_curdoc(doc):  # Panel components changed by ``fn`` find their document
        fn()


class LiveText:
    """A caption or status line that changes with the results, set in place.

    Its model is Panel's own HTML model held in a Bokeh pane, and only its ``text``
    changes: one string property, one small patch (why not ``pn.pane.HTML`` or Bokeh's
    ``Div``, with the measurements: :mod:`app.panel_private`). Like every change of a
    Bokeh model, :attr:`text` is set where the document may change (a view's draw on the
    session's event loop, or no server at all). Text from users' files inside the HTML
    stays escaped (:func:`inline_html`).
    """

    def __init__(self, text: str = "", *, css_classes=(), styles=None, height=None) -> None:
        self._text = text
        self.model = html_model(
            text,
            css_classes=list(css_classes),
            styles=dict(styles or {}),
            sizing_mode="stretch_width",
            height=height,
            margin=(0, 10),
        )
        self._pane = pn.pane.Bokeh(self.model, sizing_mode="stretch_width", height=height)

    @property
    def text(self) -> str:
        """The HTML shown."""
        return self._text

    @text.setter
    def text(self, value: str) -> None:
        if value != self._text:  # an unchanged text sends nothing
            self._text = value
            self.model.text = html_text(value)

    def __panel__(self) -> pn.pane.Bokeh:
        return self._pane


class LiveView(Viewer):
    """Base of the plot views: build once, redraw the published result in place."""

    store = param.ClassSelector(class_=Results, doc="The session's results.")
    mode = param.Selector(
        default="normal",
        objects=["normal", "present"],
        doc="Type sizes: normal or presentation view (projector).",
    )

    #: Short name: CSV view key and download css class.
    key = "view"
    #: Text beside the download button when the view has no caption of its own.
    note = ""
    #: Smallest height of the plot row (px).
    min_height = 340

    def __init__(self, **params):
        super().__init__(**params)
        self._layout = None
        self._doc = None
        self._caption: LiveText | None = None
        self._pending = False
        self._guard = threading.Lock()
        self._figures: list = []
        self._titles: list[TitleBlockModels] = []
        self._fits: list[tuple] = []  # ranges to fit after a draw's data (_fit)

    # -- what a subclass provides ----------------------------------------------------------
    def result(self) -> Result | None:
        """The published result this view shows."""
        raise NotImplementedError

    def _build(self) -> list:
        """The view's Bokeh figures (called once)."""
        raise NotImplementedError

    def _draw(self, r: Result) -> None:
        """Assign the figures' sources and properties from ``r`` (only assignments)."""
        raise NotImplementedError

    def _controls(self) -> list:
        """Widgets shown in the view's header row."""
        return []

    # -- machinery ---------------------------------------------------------------------------
    def redraw(self) -> None:
        """Draw the newest published result, on the session's event loop when served.

        Each property set is its own patch (Bokeh's normal path). A view's draw is not held
        with ``pn.io.hold``: on the event loop Panel's hold writes the held events through
        its own queue of socket writes, and when two of a session's held patches meet a
        busy socket, the later one can stay in that queue until the session's next change
        (20 concurrent sessions, ``bench/load_test.py --client bokeh``: one change in 100
        never reached its session)."""
        if self._layout is None:
            return
        with self._guard:
            if self._pending:
                return
            self._pending = True
        self._on_document(self._apply)

    def _on_document(self, fn) -> None:
        """Run ``fn`` (changes of Bokeh models) where it may change the served document."""
        on_document(self._doc, fn)

    def _apply(self) -> None:
        with self._guard:
            self._pending = False
        if self.store.closed:
            return
        r = self.result()
        if r is None:
            return
        if self._caption is not None and r.caption:
            self._caption.text = f"<p>{inline_html(r.caption)}</p>"
        self._fits = []
        self._draw(r)
        for rng, values in self._fits:  # after the data: the page renders linked plots once
            fit_range(rng, values)
        self._draw_title()

    def _fit(self, rng, values) -> None:
        """Fit the range ``rng`` to ``values`` once the draw has set its data (ranges are
        shared by linked plots: set first, they made the page render every linked plot
        with the old data before the new arrived)."""
        self._fits.append((rng, values))

    # -- title block: what the plot shows, on the plot and in its saved PNG -----------------
    def _title_state(self):
        """The state snapshot the title describes (the band view: the band's own)."""
        return self.store.snapshot()

    def _draw_title(self) -> None:
        if not self._titles:
            return
        tb, stem = view_title(self.key, self._title_state(), page_url())
        for t in self._titles:
            t.update(tb, stem)

    @param.depends("mode", watch=True)
    def _restyle(self) -> None:
        # the view switch arrives on a worker thread of the server: Bokeh models change
        # only on the session's event loop (a RuntimeError of Bokeh otherwise)
        self._on_document(self._restyle_now)

    def _restyle_now(self) -> None:
        for fig in self._figures:
            style_figure(fig, self.mode, legend_side="below")
        for t in self._titles:
            t.style(self.mode)

    def _header(self) -> pn.Row:
        first: pn.pane.HTML | LiveText
        if self.note:
            first = pn.pane.HTML(
                f"<p>{inline_html(self.note)}</p>",
                margin=(0, 10),
                styles={"color": "#495057", "font-size": "0.9em"},
                sizing_mode="stretch_width",
            )
        else:
            first = self._caption = LiveText()
        return pn.Row(*self._controls(), first, download_button(self.key, self.result))

    def __panel__(self):
        if self._layout is None:
            self._doc = served_document()
            figures = self._build()
            # the plots to style; a view may build a layout of plots (its first one carries
            # the title block)
            per_object = [_plots_in(f) for f in figures]
            self._figures = [p for plots in per_object for p in plots]
            self._titles = [TitleBlockModels(plots[0]) for plots in per_object if plots]
            self._restyle_now()
            header = self._header()
            plots = [
                pn.pane.Bokeh(f, sizing_mode="stretch_both", min_height=self.min_height)
                for f in figures
            ]
            body = plots[0] if len(plots) == 1 else pn.Row(*plots, sizing_mode="stretch_both")
            self._layout = pn.Column(header, *self._extra(), body, sizing_mode="stretch_both")
            self._apply()
        return self._layout

    def _extra(self) -> list:
        """Rows between the header and the plot (e.g. a status line)."""
        return []
