"""Monte-Carlo noise scatter band (thesis section 5.2, figs. 5.9-5.11).

The band is computed off the event loop (a worker thread), so the page of this session stays
responsive and other sessions are not blocked; a progress bar shows while it runs, and a
result that arrives after the settings changed again is discarded.
"""

from __future__ import annotations

import asyncio
import time

import holoviews as hv
import panel as pn
import param
from panel.viewable import Viewer

from .. import compute
from ..state import CaseState, NoiseState
from .common import COLORS, CURVE_OPTS, FREQ, download_button, level_dim, name_source

CASE_KEYS = ["harmonic", "n_modes", "coupling", "models"]
#: Seconds between a control change and the start of the band computation.
DEBOUNCE_S = 0.15
NOISE_KEYS = ["noise", "target", "frequency_dependent", "rounds", "seed"]


class ScatterBandView(Viewer):
    """Min/max corridor, percentile band, unpolluted reference and one single round."""

    case = param.ClassSelector(class_=CaseState)
    noise = param.ClassSelector(class_=NoiseState)
    result = param.Parameter(default=None, doc="The current scatter-band result object.")
    busy = param.Boolean(default=False, doc="True while a band is being computed.")
    seconds = param.Number(default=None, allow_None=True, doc="Wall time of the last band.")

    def __init__(self, **params):
        super().__init__(**params)
        self._pending = None
        self.case.param.watch(self._schedule, CASE_KEYS)
        self.noise.param.watch(self._schedule, NOISE_KEYS)

    # -- computation -------------------------------------------------------------------
    def key(self) -> tuple:
        c, n = self.case, self.noise
        return (c.harmonic, c.n_modes, c.coupling, float(n.noise), n.target,
                bool(n.frequency_dependent), int(n.rounds), int(n.seed), c.models)

    def compute_now(self):
        """Compute (or fetch from the cache) the band of the current state, blocking."""
        t0 = time.perf_counter()
        key = self.key()
        res = compute.band(*key)
        self.param.update(result=res, seconds=time.perf_counter() - t0, busy=False)
        return res

    def _schedule(self, *events):
        if pn.state.curdoc is None or pn.state.curdoc.session_context is None:
            self.compute_now()  # no server (tests, notebooks): compute in place
            return
        pn.state.execute(self._compute_async, schedule=True)

    async def _compute_async(self):
        key = self.key()
        self._pending = key
        self.busy = True
        t0 = time.perf_counter()
        # debounce: let the quick plots of this change reach the browser first, and skip
        # bands that a further change (a dragged slider) has already superseded
        await asyncio.sleep(DEBOUNCE_S)
        if self._pending != key:
            return
        try:
            res = await asyncio.to_thread(compute.band, *key)
        except Exception as exc:  # show the core's message instead of a silent spinner
            if self._pending == key:
                self.busy = False
                if pn.state.notifications is not None:
                    pn.state.notifications.error(f"Scatter band failed: {exc}", duration=8000)
            raise
        if self._pending != key:  # settings changed while computing: a newer task is running
            return
        self.param.update(result=res, seconds=time.perf_counter() - t0, busy=False)

    def start(self):
        """Compute the first band after the page has loaded."""
        self._schedule()

    # -- data --------------------------------------------------------------------------
    def data(self) -> dict:
        """Band columns for the selected DOF (computes the band if there is none yet)."""
        res = self.result if self.result is not None else self.compute_now()
        return compute.band_data(res, self.case.dof, self.noise.percentile)

    def round_data(self) -> dict:
        res = self.result if self.result is not None else self.compute_now()
        return compute.single_round_data(res, self.noise.single_round, self.case.dof)

    # -- plot layers -------------------------------------------------------------------
    # own level dimension (ranges are linked by label and unit): the band's y range is not
    # tied to the coupled-response plot. Styles are set once on the DynamicMaps.
    @staticmethod
    def _dims(dof):
        return (level_dim(dof, "band_level", "Band level"),
                level_dim(dof, "band_level2", "Upper level"))

    def _area(self, result, dof, percentile, which):
        lvl, lvl2 = self._dims(dof)
        label = "min-max corridor" if which == "minmax" else "percentile band"
        if result is None:
            return hv.Area(([], [], []), FREQ, [lvl, lvl2], label=label)
        d = compute.band_data(result, dof, percentile)
        lo, hi = ("minimum_db", "maximum_db") if which == "minmax" else ("lower_db", "upper_db")
        return hv.Area((d["freq"], d[lo], d[hi]), FREQ, [lvl, lvl2], label=label)

    def _reference(self, result, dof):
        lvl, _ = self._dims(dof)
        if result is None:
            return hv.Curve(([], []), FREQ, lvl, label="unpolluted")
        d = compute.band_data(result, dof)
        return hv.Curve((d["freq"], d["reference_db"]), FREQ, lvl, label="unpolluted")

    def _round(self, result, dof, single_round):
        lvl, _ = self._dims(dof)
        if result is None:
            return hv.Curve(([], []), FREQ, lvl, label="single round")
        d = compute.single_round_data(result, single_round, dof)
        return hv.Curve((d["freq"], d["round_db"]), FREQ, lvl, label="single round")

    @param.depends("busy", "seconds", "result")
    def _status(self):
        if self.busy:
            return pn.pane.Markdown(
                f"Computing {self.noise.rounds:,} rounds ...", margin=(0, 10),
                css_classes=["scatter-status"])
        if self.seconds is None:
            return pn.pane.Markdown("", margin=(0, 10), css_classes=["scatter-status"])
        conv = compute.convergence_db(self.result)
        return pn.pane.Markdown(
            f"{self.result.rounds:,} rounds in {self.seconds:.2f} s &middot; largest edge change "
            f"in the last half of the rounds: {conv:.1f} dB", margin=(0, 10),
            css_classes=["scatter-status"])

    def __panel__(self):
        c, n = self.case, self.noise
        def res():
            return hv.streams.Params(self, ["result"])

        def dof():
            return hv.streams.Params(c, ["dof"])


        area_tips = [("Frequency", "$x{0.0} Hz"), ("Level", "$y{0.0} dB")]
        curve_tips = [("Frequency", "@freq{0.0} Hz"), ("Level", "@band_level{0.0} dB")]
        area = dict(responsive=True, min_height=320, framewise=True, tools=["hover"],
                    line_alpha=0)
        minmax = hv.DynamicMap(
            lambda result, dof, percentile: self._area(result, dof, percentile, "minmax"),
            streams=[res(), dof(), hv.streams.Params(n, ["percentile"])]).opts(
            color=COLORS["band"], alpha=0.35, hooks=[name_source("scatter.minmax")],
            hover_tooltips=[("", "min-max corridor"), *area_tips], **area)
        pct = hv.DynamicMap(
            lambda result, dof, percentile: self._area(result, dof, percentile, "pct"),
            streams=[res(), dof(), hv.streams.Params(n, ["percentile"])]).opts(
            color=COLORS["percentile"], alpha=0.45, hooks=[name_source("scatter.percentile")],
            hover_tooltips=[("", "central percentile band"), *area_tips], **area)
        ref = hv.DynamicMap(self._reference, streams=[res(), dof()]).opts(
            color=COLORS["reference"], hooks=[name_source("scatter.reference")],
            hover_tooltips=[("", "unpolluted"), *curve_tips], **CURVE_OPTS)
        single = hv.DynamicMap(self._round, streams=[
            res(), dof(), hv.streams.Params(n, ["single_round"])]).opts(
            color=COLORS["round"], line_width=1.5, hooks=[name_source("scatter.round")],
            hover_tooltips=[("", "single round"), *curve_tips],
            **{k: v for k, v in CURVE_OPTS.items() if k != "line_width"})
        # click on the plot: show the round with the highest level at that frequency
        tap = hv.streams.Tap(source=single, x=None, y=None)
        tap.add_subscriber(self._pick_peak_round)
        plot = (minmax * pct * ref * single).opts(
            hv.opts.Overlay(legend_position="bottom_left",
                            title="Click a frequency: the round with the highest level there"))
        progress = pn.indicators.Progress(
            active=True, bar_color="primary", width=160, height=12,
            visible=self.param.busy, css_classes=["scatter-progress"], margin=(12, 10))
        dl = download_button("scatter", self._csv_columns, self._meta, self._filename)
        return pn.Column(
            pn.Row(progress, self._status,
                   pn.layout.HSpacer(), dl),
            pn.pane.HoloViews(plot, sizing_mode="stretch_both", min_height=340),
            sizing_mode="stretch_both",
        )

    def _pick_peak_round(self, x=None, y=None):
        if x is None or self.result is None:
            return
        self.noise.single_round = compute.peak_round(self.result, x, self.case.dof, "max")

    def _filename(self) -> str:
        c, n = self.case, self.noise
        fd = "fdep" if n.frequency_dependent else "findep"
        return (f"scatter_band_h{c.harmonic}_{c.dof}_p{n.noise:g}_{n.target}_{fd}"
                f"_R{n.rounds}_seed{n.seed}.csv")

    def _meta(self) -> dict:
        c, n = self.case, self.noise
        lo = (100 - n.percentile) / 2
        return {
            "view": "Monte-Carlo scatter band (thesis 5.2)", "harmonic": c.harmonic,
            "N (retained tire modes)": c.n_modes, "response DOF": f"bushing:{c.dof}",
            "coupling": c.coupling, "noise_pct": n.noise, "noise target": n.target,
            "frequency dependent": n.frequency_dependent, "rounds": n.rounds,
            "seed": n.seed, "single round": n.single_round,
            "percentiles": f"{lo:g}-{100 - lo:g}", "unit": compute.level_unit(c.dof),
            "lower/upper": "min/max of |v_e| over the rounds; percentiles numpy 'linear'",
            "models": c.models.describe(),
        }

    def _csv_columns(self) -> dict:
        d, r = self.data(), self.round_data()
        return {"freq_Hz": d["freq"], "reference_dB": d["reference_db"],
                "minimum_dB": d["minimum_db"], "maximum_dB": d["maximum_db"],
                "lower_dB": d["lower_db"], "upper_dB": d["upper_db"],
                f"round_{self.noise.single_round}_dB": r["round_db"]}
