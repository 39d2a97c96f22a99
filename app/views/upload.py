"""Bring your own data: upload a chassis FRF file or a modal tire model for this session.

The files go to the session's :class:`~app.datasource.DataSource` (read with
:mod:`fbs_core.io`, checked, never written anywhere); the page shows what was read
(quantity, DOFs, frequency range, operating points) or why the file was refused. A refused
file changes nothing; "Use reference data" goes back to the shipped models.

The reading runs on the upload queue's threads (:mod:`app.runtime.uploads`), never on the Panel
worker thread that received the file: a slow file holds no thread the other sessions'
controls need, a session has one reading per kind of file waiting, and a closed tab stops
its reading.
"""

from __future__ import annotations

import html

import panel as pn
import param
from panel.viewable import Viewer

from ..datasource import CHASSIS_ACCEPT, GEOMETRY_ACCEPT, TIRE_ACCEPT, DataSource
from ..runtime.bands import served
from ..runtime.uploads import UPLOADS

HELP = (
    "Chassis FRF: UFF 58 (.uff/.unv), MATLAB (.mat), CSV or HDF5 (.h5), layouts in "
    "docs/file-formats.md; it must hold the six spindle DOFs (outputs and inputs) and the "
    "six bushing outputs. Name the spindle and bushing nodes (a node name, or a UFF node "
    "number). A measured set (sensors and impacts around the knuckle): upload its geometry "
    "first (UFF 15/2411, CSV or HDF5 table, docs/vpt.md); the chassis file is then "
    "transformed to the virtual point named as the spindle node, with its consistency "
    "per channel. Modal tire model: the project's .h5 format or MATLAB .mat. Uploads stay "
    "in this browser session."
)


#: Colours of the alert boxes (Bootstrap's): background, text, border.
ALERT_STYLES = {
    "success": ("#d1e7dd", "#0f5132", "#badbcc"),
    "secondary": ("#e2e3e5", "#41464b", "#d3d6d8"),
    "danger": ("#f8d7da", "#842029", "#f5c2c7"),
}


def _text(value: str) -> str:
    """User text (file names, messages quoting them) as HTML text: never markup."""
    return html.escape(str(value), quote=True)


def _alert(body: str, kind: str, css: str, visible: bool = True) -> pn.pane.HTML:
    """An alert box around ``body`` (HTML whose user text is escaped with :func:`_text`).

    Not a Markdown pane: a file name like ``[x](http://...)`` or ``![](http://...)`` must
    stay text, never a live link or an external image.
    """
    bg, fg, border = ALERT_STYLES[kind]
    return pn.pane.HTML(
        f'<div class="alert alert-{kind}" role="alert">{body}</div>',
        styles={
            "background": bg,
            "color": fg,
            "border": f"1px solid {border}",
            "border-radius": "6px",
            "padding": "2px 12px",
        },
        visible=visible,
        margin=(4, 5),
        css_classes=[css],
        sizing_mode="stretch_width",
    )


def _uploaded(widget: pn.widgets.FileInput, events) -> tuple[bytes, str] | None:
    """The file a browser upload gave ``widget`` (its bytes and name), or None when the
    events are not an upload (the input cleared). An empty file is ``b""``: Panel gives its
    value as None. The input is then cleared here without telling the browser, so that the
    same file uploaded again (an empty one too) is an upload again."""
    value, name = widget.value, widget.filename
    if value is None and not name:
        return None
    if isinstance(value, list) or isinstance(name, list):  # (single-file inputs only)
        return None
    with param.parameterized.discard_events(widget):
        widget.param.update(value=None, filename=None)
    return (b"" if value is None else bytes(value)), str(name or "upload")


def queue_read(owner, slot: str, job, refused) -> bool:
    """Run ``job`` (a file's reading) on the upload queue (:mod:`app.runtime.uploads`), or
    at once without a server (a notebook or a test: no other sessions); False when the
    queue refused it (``refused(message)`` was called)."""
    if not served():
        job()
        return True
    return UPLOADS.submit(owner, slot, job, refused) is not None


class UploadView(Viewer):
    """File inputs for a chassis FRF and a tire model, the import summary or the error."""

    data = param.ClassSelector(class_=DataSource, doc="The session's data source.")

    def __init__(self, **params):
        super().__init__(**params)
        ds = self.data
        W = pn.widgets
        self.chassis_file = W.FileInput(
            accept=CHASSIS_ACCEPT, multiple=False, css_classes=["upload-chassis"], width=260
        )
        self.tire_file = W.FileInput(
            accept=TIRE_ACCEPT, multiple=False, css_classes=["upload-tire"], width=260
        )
        self.geometry_file = W.FileInput(
            accept=GEOMETRY_ACCEPT, multiple=False, css_classes=["upload-geometry"], width=260
        )
        self.spindle = W.TextInput.from_param(
            ds.param.spindle, name="Spindle node", width=120, css_classes=["upload-spindle"]
        )
        self.bushing = W.TextInput.from_param(
            ds.param.bushing, name="Bushing node", width=120, css_classes=["upload-bushing"]
        )
        self.quantity = W.Select.from_param(
            ds.param.quantity,
            name="Quantity (if the file does not say)",
            width=250,
            css_classes=["upload-quantity"],
        )
        self.interpolate = W.Checkbox.from_param(
            ds.param.interpolate,
            name="Interpolate onto the analysis grid (linear Re/Im)",
            css_classes=["upload-interpolate"],
        )
        self.reread = W.Button(
            name="Read chassis again", button_type="light", width=150, css_classes=["upload-reread"]
        )
        self.reset = W.Button(
            name="Use reference data",
            button_type="warning",
            width=160,
            css_classes=["upload-reset"],
        )
        # the file name too: Panel gives an empty file's value as None (no value event when
        # the last one was None), and the upload was ignored with the earlier error on screen
        self.chassis_file.param.watch(self._on_chassis, ["value", "filename"])
        self.tire_file.param.watch(self._on_tire, ["value", "filename"])
        self.geometry_file.param.watch(self._on_geometry, ["value", "filename"])
        self.reread.on_click(lambda _: self._run("chassis", ds.load_chassis))
        # a new node name or the interpolation choice re-reads the chassis file at once;
        # this also settles a click on "Read chassis again" that overtook the change
        # (Panel hands both to its worker threads, in either order)
        ds.param.watch(
            lambda *_: self._run("chassis", ds.reread_if_changed),
            ["spindle", "bushing", "interpolate", "quantity"],
        )
        self.reset.on_click(lambda _: self._reset())
        doc = pn.state.curdoc
        if doc is not None and doc.session_context is not None:  # served: a tab to close
            doc.on_session_destroyed(lambda _ctx, owner=ds: UPLOADS.cancel(owner))

    # -- actions (each a call into the data source; errors land in ``data.error``) --------
    def _run(self, slot: str, fn, *args):
        """Read on the upload queue (see the module); ``slot``: "chassis" or "tire"."""

        def job():
            try:
                fn(*args)
            finally:
                self._busy(False)

        self._busy(True)
        self.data.error = ""  # the earlier file's error is stale: this one is being read
        if not queue_read(self.data, slot, job, self._refused):
            self._busy(False)

    def _refused(self, message: str) -> None:
        self.data.error = message

    def _reset(self):
        UPLOADS.cancel(self.data)
        self.data.reset()

    def _busy(self, on: bool):
        for w in (self.chassis_file, self.tire_file, self.geometry_file, self.reread, self.reset):
            w.disabled = on

    # an empty file is read too (as b""): the page says it is empty instead of ignoring it
    def _on_chassis(self, *events):
        got = _uploaded(self.chassis_file, events)
        if got is not None:
            self._run("chassis", self.data.load_chassis, *got)

    def _on_geometry(self, *events):
        got = _uploaded(self.geometry_file, events)
        if got is not None:
            self._run("chassis", self.data.load_geometry, *got)

    def _on_tire(self, *events):
        got = _uploaded(self.tire_file, events)
        if got is not None:
            self._run("tire", self.data.load_tire, *got)

    # -- display -----------------------------------------------------------------------
    @param.depends(
        "data.models", "data.tire_summary", "data.chassis_summary", "data.geometry_summary"
    )
    def _summary(self):
        ds = self.data
        parts = [f"<b>In use: {_text(ds.describe())}</b>"]
        if ds.geometry_summary:
            parts.append(f"Measured set:<pre>{_text(ds.geometry_summary)}</pre>")
        for title, text in (("Chassis", ds.chassis_summary), ("Tire", ds.tire_summary)):
            if text and (
                (title == "Chassis" and ds.models.chassis is not None)
                or (title == "Tire" and ds.models.tire is not None)
            ):
                parts.append(f"{title}:<pre>{_text(text)}</pre>")
        kind = "success" if not ds.models.is_reference else "secondary"
        return _alert("".join(parts), kind, "upload-summary")

    @param.depends("data.error")
    def _error(self):
        return _alert(
            f"<b>File refused, nothing changed.</b> {_text(self.data.error)}",
            "danger",
            "upload-error",
            visible=bool(self.data.error),
        )

    @param.depends("data.vpt")
    def _consistency(self):
        from .vpt_consistency import consistency_plot

        return consistency_plot(self.data.vpt)

    def __panel__(self):
        label = pn.pane.Markdown
        return pn.Column(
            label(HELP, margin=(0, 10), styles={"color": "#495057", "font-size": "0.9em"}),
            # the inputs wrap onto a second line where the card is narrower than all of
            # them (1280 px: the geometry input made the row overflow the page)
            pn.FlexBox(
                pn.Column(
                    label("**Chassis FRF**", margin=(0, 5)),
                    self.chassis_file,
                    pn.Row(self.spindle, self.bushing),
                    self.quantity,
                    self.interpolate,
                    self.reread,
                ),
                pn.Column(
                    label("**Knuckle geometry** (measured set)", margin=(0, 5)),
                    self.geometry_file,
                ),
                pn.Column(label("**Modal tire model**", margin=(0, 5)), self.tire_file),
                pn.Column(label("&nbsp;", margin=(0, 5)), self.reset),
                flex_wrap="wrap",
                sizing_mode="stretch_width",
            ),
            self._error,
            self._summary,
            self._consistency,
            sizing_mode="stretch_width",
        )
