"""The Modes and Selection tabs of the Analysis card.

Modes: the participation ranking of the tire modes for the harmonic, the bushing DOF and
the band (bars of the chosen measure, the picked mode highlighted), the picked mode's shape
animated in the page (the belt's centre line in the wheel plane, the rim, one crest of the
dominant ring order, and the width shape across at that crest), and the Campbell diagram
of the belt waves (its readable default: the branches in the harmonic's band of the
orders that carry its response; every branch on demand). A click on a bar or on a branch
picks that mode (``mode`` / ``mv`` in the URL) and its shape is drawn.

The animation runs in the browser: the server sends the frames of one period once, and a
script of the page shows them one after the other (the sources it writes are not synced
back to the server: no traffic while the shape moves).

Selection: the modes the case needs chosen by importance beside table 5.1's lowest N, and
the truncation of the chassis side (the largest eq. 5.1 error over the judged centres per
number of chassis modes, with the threshold and the count needed).
"""

from __future__ import annotations

import numpy as np
import panel as pn
from bokeh.events import Tap
from bokeh.models import (
    Arrow,
    ColumnDataSource,
    CustomJS,
    DataTable,
    FixedTicker,
    HoverTool,
    NormalHead,
    Span,
    TableColumn,
    Title,
)

from .analysis_speed import SPEED_LABEL
from .layout import plot_rows
from .live import LiveView
from .plots import new_figure, same_columns

__all__ = [
    "ChassisTruncationView",
    "ModeShapeView",
    "ParticipationView",
    "SelectedModesView",
    "WavesView",
    "modes_tab",
    "selection_tab",
]

BAR_COLOR = "#adb5bd"
PICKED_COLOR = "#c2255c"
#: One period of the shape's animation in the page (ms).
PERIOD_MS = 1600

#: The page's script that shows the frames of one period one after the other. It runs
#: whenever the server sends new frames (and once when the page is ready); the sources it
#: writes are not synced back to the server (``syncable=False``).
ANIMATE_JS = """
const key = "_fbsModeShape_" + frames.id;
if (window[key]) { clearInterval(window[key]); window[key] = null; }
const d = frames.data;
const n = d.x ? d.x.length : 0;
if (!n) {
  ring.data = {x: [], z: []}; rim.data = {x: [], z: []};
  crest.data = {x: [], z: []}; section.data = {y: [], r: []};
  return;
}
let k = 0;
function show() {
  ring.data = {x: d.x[k], z: d.z[k]};
  rim.data = {x: d.rim_x[k], z: d.rim_z[k]};
  crest.data = {x: [d.cx[k]], z: [d.cz[k]]};
  section.data = {y: d.sec_y[k], r: d.sec[k]};
  k = (k + 1) % n;
}
show();
window[key] = setInterval(show, period / n);
"""


#: Columns of text (compared as text).
TEXT_COLUMNS = ("label", "freq", "color", "name", "pairs", "top")


def set_data(src: ColumnDataSource, data: dict) -> None:
    """Assign ``data`` unless the source holds them already (no patch for the same data;
    :func:`app.views.plots.set_data` with the text columns compared as text)."""
    old = src.data
    if old.keys() == data.keys():
        text = [k for k in data if k in TEXT_COLUMNS]
        nums = [k for k in data if k not in TEXT_COLUMNS]
        if all(list(old[k]) == list(data[k]) for k in text) and same_columns(
            {k: old[k] for k in nums}, {k: data[k] for k in nums}
        ):
            return
    src.data = data


def _src(name: str, columns: tuple[str, ...], syncable: bool = True) -> ColumnDataSource:
    return ColumnDataSource({c: [] for c in columns}, name=name, syncable=syncable)


class ParticipationView(LiveView):
    """Bars of the chosen measure for the ranked tire modes; a click picks a mode."""

    key = "participation"
    result_name = "participation"
    also = ("mode_shape",)
    css_height = plot_rows(1.15)  # its own height: the tab's views stand one below the other

    def _controls(self):
        a = self.store.state.analysis
        return [pn.widgets.Select.from_param(a.param.mode_rank, name="", width=120)]

    def _build(self):
        self._fig = fig = new_figure(
            x_label="Tire mode (stored pair), ranked",
            y_label="Measure (%)",
            name="participation.figure",
            min_height=280,
        )
        self._bars = _src(
            "participation.bars",
            ("x", "value", "label", "mode", "freq", "speed", "share", "loo", "color"),
        )
        r = fig.vbar(x="x", top="value", width=0.8, source=self._bars, fill_color="color",
                     line_color="color")  # fmt: skip
        fig.add_tools(
            HoverTool(
                renderers=[r],
                tooltips=[
                    ("mode", "@mode"),
                    ("eigenfrequency", "@freq"),
                    ("where excited", "@speed{0.0} km/h"),
                    ("leave-one-out", "@loo{0.0} %"),
                    ("share", "@share{0.0} %"),
                ],
            )
        )
        fig.xaxis.ticker = FixedTicker(ticks=[])
        # labels across the axis: a bar's slot needs one line of type, not the label's
        # length (20 labels along the axis ran together at 1280 px in the presentation view)
        fig.xaxis.major_label_orientation = "vertical"
        fig.xgrid.visible = False
        fig.y_range.start = 0
        # the tread's first-order states (no vibration, not ranked): said under the bars
        self._unranked = Title(
            text="", align="left", text_font_style="italic", text_font_size="11px",
            name="participation.unranked",
        )  # fmt: skip
        fig.add_layout(self._unranked, "below")
        fig.on_event(Tap, self._tapped)
        return [fig]

    def _tapped(self, event):
        if event.x is not None:
            self.store.pick_mode_bar(float(event.x))

    def _draw(self, r):
        d = r.draw
        if not d.get("ready"):
            set_data(self._bars, {k: [] for k in self._bars.data})
            self._unranked.text = ""
            return
        if self._unranked.text != d.get("unranked", ""):
            self._unranked.text = d.get("unranked", "")
        shape = self.store.mode_shape
        picked = shape.draw.get("mode") if shape is not None else None
        n = len(d["mode"])
        set_data(
            self._bars,
            {
                "x": np.arange(n, dtype=float),
                "value": d["value"],
                "label": d["label"],
                "mode": np.asarray(d["mode"], float),
                "freq": d["freq"],
                "speed": d["speed"],
                "share": d["share"],
                "loo": d["loo"],
                "color": [PICKED_COLOR if m == picked else BAR_COLOR for m in d["mode"]],
            },
        )
        ticks = list(range(n))
        if list(self._fig.xaxis.ticker.ticks) != ticks:
            self._fig.xaxis.ticker = FixedTicker(ticks=ticks)
        self._fig.xaxis.major_label_overrides = {i: lab for i, lab in enumerate(d["label"])}
        self._fig.yaxis.axis_label = d["y_label"]


class ModeShapeView(LiveView):
    """The picked mode's belt over one period, animated in the page."""

    key = "modeshape"
    result_name = "mode_shape"
    css_height = plot_rows(1.15)  # its own height: the tab's views stand one below the other

    def _build(self):
        self._plane = fig = new_figure(
            x_label="x forward (m)", y_label="z up (m)", name="modeshape.figure", min_height=280
        )
        fig.match_aspect = True
        self._frames = _src(
            "modeshape.frames", ("x", "z", "rim_x", "rim_z", "cx", "cz", "sec", "sec_y")
        )
        self._rest = _src("modeshape.rest", ("x", "z"))
        self._ring = _src("modeshape.ring", ("x", "z"), syncable=False)
        self._rim = _src("modeshape.rim", ("x", "z"), syncable=False)
        self._crest = _src("modeshape.crest", ("x", "z"), syncable=False)
        self._section = _src("modeshape.section", ("y", "r"), syncable=False)
        fig.line("x", "z", source=self._rest, line_color="#adb5bd", line_dash="dashed")
        # the frames of one period, not drawn themselves (the page's script shows them)
        fig.multi_line("x", "z", source=self._frames, visible=False)
        fig.line("x", "z", source=self._ring, line_color="#1971c2", line_width=2.5)
        fig.line("x", "z", source=self._rim, line_color="#495057", line_width=1.5)
        fig.scatter("x", "z", source=self._crest, size=11, color="#c2255c", marker="circle")
        self._spin = Arrow(
            end=NormalHead(size=9, fill_color="#495057", line_color="#495057"),
            x_start=0.0, y_start=0.0, x_end=0.0, y_end=0.0, line_color="#495057",
            visible=False,
        )  # fmt: skip
        fig.add_layout(self._spin)
        self._across = sec = new_figure(
            x_label="across the width, y (m)",
            y_label="radial displacement (drawn)",
            name="modeshape.section_figure",
            min_height=280,
        )
        sec.line("y", "r", source=self._section, line_color="#1971c2", line_width=2.5)
        sec.add_layout(Span(location=0, dimension="width", line_color="#adb5bd"))
        anim = CustomJS(
            args={
                "frames": self._frames,
                "ring": self._ring,
                "rim": self._rim,
                "crest": self._crest,
                "section": self._section,
                "period": PERIOD_MS,
            },
            code=ANIMATE_JS,
        )
        self._frames.js_on_change("data", anim)
        if self._doc is not None:  # frames sent with the page: start when it is ready
            self._doc.js_on_event("document_ready", anim)
        return [fig, sec]

    def _draw(self, r):
        d = r.draw
        # a first-order pair has no shape: its plot says what it is instead
        note = d.get("title", "") if d.get("kind") else ""
        if self._plane.title.text != note:
            self._plane.title.text = note
        if not d.get("ready"):
            set_data(self._frames, {k: [] for k in self._frames.data})
            set_data(self._rest, {"x": [], "z": []})
            self._spin.visible = False
            return
        set_data(self._rest, {"x": d["rest_x"], "z": d["rest_z"]})
        set_data(
            self._frames,
            {
                "x": d["frames_x"],
                "z": d["frames_z"],
                "rim_x": d["rim_x"],
                "rim_z": d["rim_z"],
                "cx": d["crest_x"],
                "cz": d["crest_z"],
                "sec": d["section"],
                "sec_y": [d["section_y"]] * len(d["section"]),
            },
        )
        radius = float(np.max(np.hypot(d["rest_x"], d["rest_z"])))
        # the spin: the top of the wheel moves forward (theta grows from front to patch)
        self._spin.update(
            x_start=-0.35 * radius, y_start=1.2 * radius, x_end=0.35 * radius,
            y_end=1.2 * radius, visible=True,
        )  # fmt: skip


class WavesView(LiveView):
    """The Campbell diagram of the belt waves; a click on a branch picks its mode."""

    key = "waves"
    result_name = "waves"
    also = ("mode_shape",)
    css_height = plot_rows(1.15)  # its own height: the tab's views stand one below the other

    def _controls(self):
        a = self.store.state.analysis
        return [pn.widgets.Checkbox.from_param(a.param.waves_all, name="all branches", width=110)]

    def _build(self):
        self._fig = fig = new_figure(
            x_label=SPEED_LABEL, y_label="Frequency (Hz)", name="waves.figure", min_height=280
        )
        self._branches = _src("waves.branches", ("xs", "ys", "label", "color", "width"))
        r = fig.multi_line("xs", "ys", source=self._branches, line_color="color",
                           line_width="width")  # fmt: skip
        fig.add_tools(HoverTool(renderers=[r], tooltips=[("branch", "@label")]))
        self._veer = _src("waves.veering", ("x", "y"))
        fig.scatter("x", "y", source=self._veer, marker="circle", size=6, fill_alpha=0,
                    line_color="#495057")  # fmt: skip
        self._line = _src("waves.order_line", ("v", "f"))
        fig.line("v", "f", source=self._line, line_color="#2b2b2b", line_dash="dashed",
                 line_width=2)  # fmt: skip
        self._picked = _src("waves.picked", ("x", "y"))
        fig.scatter("x", "y", source=self._picked, marker="star", size=16, color=PICKED_COLOR)
        fig.on_event(Tap, self._tapped)
        return [fig]

    def _tapped(self, event):
        if event.x is not None and event.y is not None:
            self.store.pick_wave(float(event.x), float(event.y))

    def _draw(self, r):
        d = r.draw
        if not d.get("ready"):
            for src in (self._branches, self._veer, self._line, self._picked):
                set_data(src, {k: [] for k in src.data})
            return
        set_data(
            self._branches,
            {k: d[k] for k in ("xs", "ys", "label", "color", "width")},
        )
        set_data(self._veer, {"x": d["veer_x"], "y": d["veer_y"]})
        set_data(self._line, {"v": d["line_v"], "f": d["line_f"]})
        shape = self.store.mode_shape
        sd = shape.draw if shape is not None else {}
        if sd.get("ready"):
            t = shape.core["shape"]
            set_data(self._picked, {"x": [t.speed_kmh], "y": [t.freq]})
        else:
            set_data(self._picked, {"x": [], "y": []})


class SelectedModesView(LiveView):
    """The selected modes beside table 5.1's lowest N, as a table."""

    key = "selected"
    result_name = "selected_modes"
    css_height = "calc(140px + 7.5em)"  # its own height: the views stand one below the other

    def _build(self):
        self._table_src = _src("selected.table", ("name", "n_modes", "n_first", "top", "pairs"))
        self._table = DataTable(
            source=self._table_src,
            columns=[
                TableColumn(field="name", title="ordering", width=230),
                TableColumn(field="n_modes", title="modes (table 5.1 rule)", width=130),
                TableColumn(field="n_first", title="smallest meeting it", width=120),
                TableColumn(field="top", title="highest kept (Hz)", width=110),
                TableColumn(field="pairs", title="stored pairs kept", width=360),
            ],
            index_position=None,
            sizing_mode="stretch_width",
            height=140,
            name="selected.datatable",
        )
        return [self._table]

    def _draw(self, r):
        d = r.draw
        if "names" not in d:
            set_data(self._table_src, {k: [] for k in self._table_src.data})
            return
        set_data(
            self._table_src,
            {
                "name": d["names"],
                "n_modes": d["n_modes"],
                "n_first": d["n_first"],
                "top": [f"{t:.1f}" for t in d["top"]],
                "pairs": d["pairs"],
            },
        )


class ChassisTruncationView(LiveView):
    """Largest eq. 5.1 error per number of chassis modes, the threshold and the count."""

    key = "chassistrunc"
    result_name = "chassis_truncation"
    css_height = plot_rows(1)  # its own height: the tab's views stand one below the other

    def _build(self):
        self._fig = fig = new_figure(
            x_label="Chassis modes kept N",
            y_label="Largest error (%)",
            name="chassistrunc.figure",
            min_height=280,
            y_axis_type="log",
        )
        self._curve = _src("chassistrunc.curve", ("n", "err"))
        r = fig.line("n", "err", source=self._curve, line_color="#1971c2", line_width=2)
        fig.scatter("n", "err", source=self._curve, size=4, color="#1971c2")
        fig.add_tools(HoverTool(renderers=[r], tooltips=[("N", "@n"), ("error", "@err{0.0} %")]))
        self._thr = Span(location=20.0, dimension="width", line_color="#e03131", line_dash="dashed")
        self._sug = Span(location=0.0, dimension="height", line_color="#2b8a3e", line_width=2)
        fig.add_layout(self._thr)
        fig.add_layout(self._sug)
        return [fig]

    def _draw(self, r):
        d = r.draw
        if not d.get("ready"):
            set_data(self._curve, {"n": [], "err": []})
            return
        err = np.maximum(np.asarray(d["worst"], float), 1e-6)
        set_data(self._curve, {"n": d["n_modes"], "err": err})
        self._thr.location = float(d["threshold"])
        self._sug.location = float(d["suggested"])


def modes_tab(results, mode: str = "normal", views: list | None = None) -> pn.Column:
    """The "Modes" tab: the two ways to pick a mode side by side (the ranking's bars, the
    branches of the waves' Campbell diagram), the picked mode's shape below them at the
    tab's full width (its two plots side by side need it: at half a card's width their
    title lines were cut). In the type sizes of ``mode``; the views are appended to
    ``views`` (they follow the page's view switch)."""
    bars, waves, shape = (
        ParticipationView(store=results, mode=mode),
        WavesView(store=results, mode=mode),
        ModeShapeView(store=results, mode=mode),
    )
    if views is not None:
        views.extend([bars, waves, shape])
    return pn.Column(
        pn.Row(bars, waves, sizing_mode="stretch_width"),
        shape,
        sizing_mode="stretch_width",
    )


def selection_tab(results, mode: str = "normal", views: list | None = None) -> pn.Column:
    """The "Selected modes" tab: the selections beside table 5.1, the chassis side (in the
    type sizes of ``mode``; the views are appended to ``views``)."""
    table = SelectedModesView(store=results, mode=mode)
    chassis = ChassisTruncationView(store=results, mode=mode)
    if views is not None:
        views.extend([table, chassis])
    return pn.Column(table, chassis, sizing_mode="stretch_width")
