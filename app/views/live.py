"""The skeleton every view shares: a figure built once, redrawn from a published result.

A view is a :class:`LiveView` subclass that says which published result of the session's
:class:`~app.store.Results` it shows and how to draw it::

    class EigenView(LiveView):
        key = "eigen"                                   # CSV name, css class
        result_name = "eigen"                           # the row of app.store.TABLE

        def _build(self):                              # Bokeh figures, once per session
            ...

        def _draw(self, r):                            # assign sources from ``r``
            ...

The view is redrawn when its result is published; its title block and its file names are
those of the result's own snapshot. It computes nothing: the numbers, the CSV and the
description are the result's.

Drawing goes through the session's :class:`~app.runtime.draw.DrawQueue`: from any thread,
the draws run one
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

import panel as pn
import param
from panel.viewable import Viewer

from .. import compute
from ..export import dated, export_columns, to_csv, to_uff
from ..page.bokeh import TitleBlockModels, style_figure
from ..page.titles import page_url, view_title
from ..results import Result
from ..runtime.draw import on_document, served_document
from ..runtime.panel_private import html_model, html_text
from ..store import Results
from .layout import CAPTION_ROW_CSS, font, sized
from .plots import fit_range


def _plots_in(obj) -> list:
    """The Bokeh plots of ``obj``: itself if it is one, else those of its layout in the
    layout's order (``select`` walks the model graph in no set order: the phase view's
    title block once landed on its lower plot)."""
    from bokeh.models import Plot

    if isinstance(obj, Plot):
        return [obj]
    children = getattr(obj, "children", None)
    if children is None:
        return list(obj.select({"type": Plot})) if hasattr(obj, "select") else []
    out = []
    for child in children:  # a grid's children are (model, row, column)
        out += _plots_in(child[0] if isinstance(child, tuple) else child)
    return out


log = logging.getLogger(__name__)

__all__ = [
    "LiveText",
    "LiveView",
    "download_button",
    "downloads",
    "uff_button",
    "export_meta",
    "inline_html",
]


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


#: Views whose data are functions of frequency: a UFF download beside the CSV one.
UFF_VIEWS = ("mobility", "scatter", "uncoupled", "contributions", "phase")


def download_button(key: str, result) -> pn.widgets.FileDownload:
    """A CSV download of ``result()``: its columns under its own header, a file name with
    the date (:func:`app.export.dated`)."""

    def callback():
        r = result()
        if r is None:
            return io.StringIO("")
        btn.filename = dated(r.filename)
        cols, meta = export_columns(r)
        return io.StringIO(to_csv(cols, export_meta(meta), key))

    first = result()
    btn = pn.widgets.FileDownload(
        callback=callback,
        filename=dated(first.filename) if first is not None else f"{key}.csv",
        label="CSV",
        button_type="light",
        width=90,
        embed=False,
        css_classes=[f"download-{key}"],
    )
    return btn


def uff_button(key: str, result) -> pn.widgets.FileDownload:
    """A UFF (dataset 58) download of ``result()`` beside its CSV download: its FRFs and
    complex curves over frequency, the case of its snapshot in the ID lines, the node map
    in ID line 5 (:func:`app.export.to_uff`)."""

    def callback():
        r = result()
        if r is None:
            return io.BytesIO(b"")
        btn.filename = dated(r.filename.rsplit(".", 1)[0] + ".uff")
        meta = export_meta({})
        return io.BytesIO(to_uff(r, {k: meta[k] for k in ("exported", "fbs_core version")}))

    first = result()
    btn = pn.widgets.FileDownload(
        callback=callback,
        filename=dated(first.filename.rsplit(".", 1)[0] + ".uff")
        if first is not None
        else f"{key}.uff",
        label="UFF",
        button_type="light",
        width=90,
        embed=False,
        css_classes=[f"download-uff-{key}"],
    )
    return btn


def downloads(key: str, result) -> list[pn.widgets.FileDownload]:
    """The downloads of a view: CSV, and UFF for the views over frequency."""
    out = [download_button(key, result)]
    if key in UFF_VIEWS:
        out.append(uff_button(key, result))
    return out


class LiveText:
    """A caption or status line that changes with the results, set in place.

    Its model is Panel's own HTML model held in a Bokeh pane, and only its ``text``
    changes: one string property, one small patch (why not ``pn.pane.HTML`` or Bokeh's
    ``Div``, with the measurements: :mod:`app.panel_private`). Like every change of a
    Bokeh model, :attr:`text` is set where the document may change (a view's draw on the
    session's event loop, or no server at all). Text from users' files inside the HTML
    stays escaped (:func:`inline_html`).
    """

    def __init__(
        self, text: str = "", *, css_classes=(), styles=None, height=None, margin=(0, 10)
    ) -> None:
        self._text = text
        self.model = html_model(
            text,
            css_classes=list(css_classes),
            styles=dict(styles or {}),
            sizing_mode="stretch_width",
            height=height,
            margin=margin,
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
    #: The published result shown (a row of :data:`app.store.TABLE`).
    result_name = ""
    #: Other published values whose change redraws the view.
    also: tuple[str, ...] = ()
    #: Text beside the download button when the view has no caption of its own.
    note = ""
    #: CSS height of the view (None: it fills the card it is put in; see
    #: app/views/layout.py).
    css_height: str | None = None

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
        self._title_pending = False
        if self.result_name:
            self.store.param.watch(lambda _e: self.redraw(), [self.result_name, *self.also])
            # a change the result does not depend on still changes the link it carries
            self.store.param.watch(lambda _e: self.retitle(), "published")

    # -- what a subclass provides ----------------------------------------------------------
    def result(self) -> Result | None:
        """The published result this view shows."""
        return getattr(self.store, self.result_name)

    def _build(self) -> list:
        """The view's Bokeh figures (called once)."""
        raise NotImplementedError

    def _draw(self, r: Result) -> None:
        """Assign the figures' sources and properties from ``r`` (only assignments)."""
        raise NotImplementedError

    def _controls(self) -> list:
        """Widgets shown in the view's header row."""
        return []

    def _messages(self) -> list:
        """Messages of the header's controls, under them (e.g. of a typed number)."""
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
        """Run ``fn`` (changes of Bokeh models) where it may change the served document:
        the one current when the view was built, else the one its figures belong to (a view
        built where no document was current would otherwise change served models off the
        session's event loop)."""
        if self._doc is None and self._figures:
            self._doc = self._figures[0].document
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
        self._draw_title(r)

    def _fit(self, rng, values) -> None:
        """Fit the range ``rng`` to ``values`` once the draw has set its data (ranges are
        shared by linked plots: set first, they made the page render every linked plot
        with the old data before the new arrived)."""
        self._fits.append((rng, values))

    # -- title block: what the plot shows, on the plot and in its saved PNG -----------------
    def retitle(self) -> None:
        """Draw the title block again (the published state changed)."""
        if self._layout is None or not self._titles:
            return
        with self._guard:
            if self._title_pending:
                return
            self._title_pending = True

        def again() -> None:
            with self._guard:
                self._title_pending = False
            r = None if self.store.closed else self.result()
            if r is not None:
                self._draw_title(r)

        self._on_document(again)

    def _draw_title(self, r: Result) -> None:
        """The title block of ``r``'s own snapshot (the band's: the settings it was
        computed for), with the link of the published state when ``r`` is of its values
        (:meth:`app.store.Results.link_snapshot`): never the page's URL of the moment,
        which may already or still name another state."""
        if not self._titles or r.snapshot is None:
            return
        link = self.store.link_snapshot(self.result_name, r)
        tb, stem = view_title(self.key, r.snapshot, link=link)
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

    def _header(self) -> pn.viewable.Viewable:
        first: pn.pane.HTML | LiveText
        if self.note:
            first = pn.pane.HTML(
                f"<p>{inline_html(self.note)}</p>",
                margin=(0, 10),
                styles={"color": "#495057", "font-size": font("0.9em")},
                sizing_mode="stretch_width",
            )
        else:
            first = self._caption = LiveText()
        controls = self._controls()
        download = downloads(self.key, self.result)
        if controls:  # the controls on lines of their own (wrapped), the caption below them
            return pn.Column(
                pn.FlexBox(
                    *controls,
                    *download,
                    flex_wrap="wrap",
                    align_items="flex-end",
                    sizing_mode="stretch_width",
                ),
                *self._messages(),
                first,
                sizing_mode="stretch_width",
            )
        # a caption and a CSV button only repeat the title block: not on the projector
        return pn.Row(first, *download, stylesheets=[CAPTION_ROW_CSS])

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
            plots = [pn.pane.Bokeh(f, sizing_mode="stretch_both") for f in figures]
            body = plots[0] if len(plots) == 1 else pn.Row(*plots, sizing_mode="stretch_both")
            parts = (header, *self._extra(), body)
            if self.css_height is None:  # the card around it gives the height
                self._layout = pn.Column(*parts, sizing_mode="stretch_both")
            else:
                self._layout = sized(*parts, height=self.css_height)
            self._apply()
        return self._layout

    def _extra(self) -> list:
        """Rows between the header and the plot (e.g. a status line)."""
        return []
