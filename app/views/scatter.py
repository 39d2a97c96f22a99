"""Monte-Carlo noise scatter band (thesis section 5.2, figs. 5.9-5.11).

The band is computed by the session's :class:`~app.store.Results` off the session's threads
(:mod:`app.runtime.bands`); this view draws the published band and its status line, and a click on
the plot picks the round with the highest level at that frequency. With the state's
``noise.first_order`` on it overlays the first-order band of the same noise (the store's
``first_order`` row, computed only while shown; docs/corridor.md section 6).
"""

from __future__ import annotations

import numpy as np
import panel as pn
import param
from bokeh.core.properties import value
from bokeh.events import Tap
from bokeh.models import ColumnDataSource, HoverTool, LegendItem

from fbs_core.candidates import MAX_CANDIDATES

from ..results.base import made_of_same
from .common import (
    CANDIDATE_COLORS,
    COLORS,
    FREQ_LABEL,
    TARGET_COLOR,
    level_label,
    level_tooltips,
)
from .layout import font
from .live import LiveText, LiveView, downloads, inline_html
from .plots import add_band, add_line, frequency_range, new_figure, set_data

#: The overlay's legend (its band's quantile said once drawn).
FIRST_ORDER_LEGEND = "first-order band (linearised)"
#: What the other candidates' bands and the shown band must share to be drawn together.
BANDS_SAME = (
    "harmonic", "n_modes", "dof", "coupling", "percentile", "noise", "target",
    "frequency_dependent", "rounds", "seed", "scope",
)  # fmt: skip
#: What the car's bands add to :data:`BANDS_SAME` in vehicle scope.
CAR_SAME = ("point", "wheels", "tracks", "coherence")
#: The progress bar is hidden when idle (its box kept: no new layout of the page). The rule
#: follows the bar's own ``active`` class: the bar's ``styles`` are copied onto the inner
#: ``<progress>`` element once, when it is drawn, so a bar drawn idle stayed hidden for
#: good (no bar on a page whose first band was ready when it loaded).
IDLE_CSS = "progress:not(.active) { visibility: hidden; }"


class ScatterBandView(LiveView):
    """Min/max corridor, percentile band, unpolluted reference and one single round."""

    key = "scatter"
    result_name = "band_curves"
    also = ("band_status", "first_order", "review_bands")
    x_range = param.Parameter(
        default=None,
        doc="Frequency range shared with other views (linked zoom and pan); a new one if None.",
    )

    def __init__(self, **params):
        super().__init__(**params)
        # switched off, the overlay is hidden (the row is not published again for that)
        self.store.state.noise.param.watch(lambda _e: self.redraw(), "first_order")

    def _header(self):
        # The indicator and the status line keep their place and size: changing their
        # content does not make the browser lay out the page again (toggling visibility
        # did, and delayed every plot update sent with it).
        # Idle, the bar is hidden (an empty bar looked like a text field) but keeps its box.
        self._progress = pn.indicators.Progress(
            active=False,
            value=0,
            max=100,
            bar_color="primary",
            width=160,
            height=14,
            css_classes=["scatter-progress"],
            margin=(12, 10),
            stylesheets=[IDLE_CSS],
        )
        self._cancel = pn.widgets.Button(
            label="Cancel band",
            button_type="danger",
            button_style="outline",
            disabled=True,
            width=110,
            css_classes=["scatter-cancel"],
        )
        self._cancel.on_click(lambda _e: self.store.cancel_band())
        return pn.Row(
            self._progress,
            self._cancel,
            pn.layout.HSpacer(),
            *downloads(self.key, self.result),
        )

    def _extra(self):
        # its own line, two lines high: the text's length changes, its box does not
        self._status = LiveText(
            height=40,
            css_classes=["scatter-status"],
            styles={"font-size": font("0.85em"), "line-height": "1.3"},
        )
        return [self._status]

    def _build(self):
        if self.x_range is None:
            self.x_range = frequency_range()
        self._fig = fig = new_figure(
            x_label=FREQ_LABEL,
            y_label=level_label("z", "Band level"),
            x_range=self.x_range,
            name="scatter.figure",
        )
        self._minmax = add_band(
            fig, "scatter.minmax", color=COLORS["band"], alpha=0.35, legend="min-max corridor"
        )
        self._pct = add_band(
            fig,
            "scatter.percentile",
            color=COLORS["percentile"],
            alpha=0.45,
            legend="central percentile band",
        )
        self._ref = add_line(
            fig,
            "scatter.reference",
            color=COLORS["reference"],
            legend="unpolluted",
            tooltips=level_tooltips("unpolluted"),
        )
        self._round = add_line(
            fig,
            "scatter.round",
            color=COLORS["round"],
            width=1.5,
            legend="single round",
            tooltips=level_tooltips("single round"),
        )
        self._first = ColumnDataSource(
            {"freq": np.zeros(0), "low": np.zeros(0), "high": np.zeros(0)},
            name="scatter.first_order",
        )
        for edge in ("low", "high"):
            add_line(
                fig,
                f"scatter.first_order.{edge}",
                color=COLORS["first_order"],
                legend=FIRST_ORDER_LEGEND,
                tooltips=level_tooltips(f"first-order {edge} edge", column=edge),
                y=edge,
                dash="dashed",
                width=1.5,
                source=self._first,
            )
        for leg in fig.legend:  # hidden until the overlay is drawn
            for item in leg.items:
                if getattr(item.label, "value", None) == FIRST_ORDER_LEGEND:
                    item.visible = False
        # the review's other candidates: their central band's two edges in their colour (a
        # pair of lines per colour slot, made on first use; legend entries here from the start)
        self._cand: dict[int, ColumnDataSource] = {}
        self._cand_items = [
            LegendItem(label=value(f"candidate {k + 1}"), renderers=[], visible=False)
            for k in range(MAX_CANDIDATES)
        ]
        # the target at the shown DOF: what the band's upper edge is judged against
        self._target = ColumnDataSource(
            {"freq": np.zeros(0), "level": np.zeros(0), "name": []}, name="scatter.target"
        )
        target_line = fig.line(
            "freq", "level", source=self._target, line_color=TARGET_COLOR, line_width=2.6,
            line_dash="dotdash", visible=False,
        )  # fmt: skip
        self._target_item = LegendItem(
            label=value("target"), renderers=[target_line], visible=False
        )
        fig.legend[0].items = [*fig.legend[0].items, *self._cand_items, self._target_item]
        self._cand_tool = HoverTool(
            renderers=[], tooltips=level_tooltips("@name", "level"), mode="vline"
        )
        self._cand_tool.renderers = [target_line]
        fig.add_tools(self._cand_tool)
        fig.on_event(Tap, self._tapped)
        return [fig]

    def _cand_lines(self, slot: int) -> ColumnDataSource:
        """The source of a candidate's band edges (colour ``slot``), its lines made on first
        use: the upper edge solid, the lower dashed."""
        src = self._cand.get(slot)
        if src is not None:
            return src
        src = self._cand[slot] = ColumnDataSource(
            {"freq": np.zeros(0), "low": np.zeros(0), "high": np.zeros(0), "name": []},
            name=f"scatter.candidate{slot}",
        )
        lines = [
            self._fig.line(
                "freq", edge, source=src, line_color=CANDIDATE_COLORS[slot], line_width=1.6,
                line_dash=dash, visible=False,
            )
            for edge, dash in (("high", "solid"), ("low", "dashed"))
        ]  # fmt: skip
        self._cand_items[slot].renderers = lines
        self._cand_tool.renderers = [*self._cand_tool.renderers, *lines]
        return src

    def _draw_candidates(self, r) -> None:
        """The other candidates' bands when they are of the band ``r`` shows (its case,
        DOF, percentile band and noise settings)."""
        rb = self.store.review_bands
        fields: tuple[str, ...] = BANDS_SAME
        if r is not None and r.snapshot is not None and r.snapshot.vehicle:
            fields += CAR_SAME  # the car's road and point too
        ok = rb is not None and made_of_same(rb, r, fields)
        shown = set()
        for cv in rb.draw["curves"] if ok and rb is not None else []:
            n = len(cv["freq"])
            self._cand_lines(cv["slot"]).data = {
                "freq": cv["freq"],
                "low": cv["low"],
                "high": cv["high"],
                "name": [cv["name"]] * n,
            }
            label = f"{cv['name']}: central band"
            if getattr(self._cand_items[cv["slot"]].label, "value", None) != label:
                self._cand_items[cv["slot"]].label = value(label)
            shown.add(cv["slot"])
        for slot in self._cand:
            item, on = self._cand_items[slot], slot in shown
            if item.visible != on:
                item.visible = on
                for line in item.renderers:
                    line.visible = on
        y = rb.draw.get("target") if ok and rb is not None else None
        if y is not None and rb is not None:
            label = rb.draw["target_label"]
            self._target.data = {"freq": rb.draw["freq"], "level": y, "name": [label] * len(y)}
            if getattr(self._target_item.label, "value", None) != label:
                self._target_item.label = value(label)
        on = y is not None
        if self._target_item.visible != on:
            self._target_item.visible = on
            for line in self._target_item.renderers:
                line.visible = on

    def _overlay(self, r):
        """The published first-order result when it is shown and of the drawn band, DOF and
        percentile band (else None: the overlay is empty)."""
        fo = self.store.first_order
        if not self.store.state.noise.first_order or fo is None:
            return None
        same = fo.core["band"] is r.core["band"] and (fo.draw["dof"], fo.draw["percentile"]) == (
            r.draw["dof"],
            r.snapshot.percentile if r.snapshot is not None else None,
        )
        return fo if same else None

    def _draw_title(self, r):
        """The band's own settings (it may be older than the controls: the heading says
        so), the shown DOF, percentile band and round."""
        super()._draw_title(r)
        st, band = self.store.band_status, self.store.band
        stale = band is not None and band.settings.band_key() != self.store.snapshot().band_key()
        for t in self._titles:
            what = t.heading.text.split(" [")[0]
            if stale:
                what += " [shown: the previous settings' band" + (
                    ", the new one is computing]" if st.busy else "]"
                )
            if t.heading.text != what:
                t.heading.text = what

    def _tapped(self, event):
        if event.x is not None:
            self.store.pick_peak_round(event.x)

    def _apply(self):
        super()._apply()
        if self.store.closed:
            return
        st = self.store.band_status
        self._status.text = f"<p>{inline_html(st.text)}</p>" if st.text else ""
        value = (st.percent if st.total else -1) if st.busy else 0
        if self._progress.active != st.busy or self._progress.value != value:
            self._progress.param.update(active=st.busy, value=value)
        if self._cancel.disabled == st.busy:
            self._cancel.disabled = not st.busy

    def _draw(self, r):
        d, single = r.draw["band"], r.draw["round"]
        f = d["freq"]
        self._minmax.data = {"freq": f, "lower": d["minimum_db"], "upper": d["maximum_db"]}
        self._pct.data = {"freq": f, "lower": d["pct_low_db"], "upper": d["pct_high_db"]}
        self._ref.data = {"freq": f, "level": d["reference_db"]}
        self._round.data = {"freq": f, "level": single["round_db"]}
        fo = self._overlay(r)
        if fo is None:
            set_data(self._first, {"freq": [], "low": [], "high": []})
        else:
            c = fo.columns
            set_data(
                self._first,
                {
                    "freq": c["freq_Hz"],
                    "low": c["first_order_low_dB"],
                    "high": c["first_order_high_dB"],
                },
            )
        self._fig.yaxis.axis_label = level_label(r.draw["dof"], "Band level")
        labels = [
            f"min-max over {r.meta['rounds']:,} rounds",
            f"central band, percentiles {r.meta['percentiles']} %",
            "unpolluted",
            f"round #{r.meta['single round']} (click: highest round there)",
            FIRST_ORDER_LEGEND
            if fo is None
            else f"first order: |v| \u00b1 {fo.draw['k']:.3f} std (linearised, Gaussian "
            f"{r.meta['percentiles']} %)",
        ]
        for leg in self._fig.legend:
            for item, text in zip(leg.items, labels, strict=False):
                if getattr(item.label, "value", None) != text:
                    item.label = value(text)
            if len(leg.items) > len(labels) - 1:
                item = leg.items[len(labels) - 1]
                if item.visible != (fo is not None):
                    item.visible = fo is not None
        self._draw_candidates(r)
        self._fit(self.x_range, f)
