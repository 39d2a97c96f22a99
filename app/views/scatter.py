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

CASE_KEYS = ["harmonic", "n_modes", "coupling"]
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
                bool(n.frequency_dependent), int(n.rounds), int(n.seed))

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
        res = await asyncio.to_thread(compute.band, *key)
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
    def _bands(self, result, dof, percentile):
        # own level dimension: the band's y range is not linked to the coupled-response plot
        lvl, lvl2 = level_dim(dof, "band_level"), level_dim(dof, "band_level2", "Upper level")
        if result is None:
            e = ([], [], [])
            return (hv.Area(e, FREQ, [lvl, lvl2], label="min-max corridor").opts(
                        hooks=[name_source("scatter.minmax")])
                    * hv.Area(e, FREQ, [lvl, lvl2], label="percentile band").opts(
                        hooks=[name_source("scatter.percentile")])
                    * hv.Curve(([], []), FREQ, lvl, label="unpolluted").opts(
                        hooks=[name_source("scatter.reference")]))
        d = compute.band_data(result, dof, percentile)
        return (
            hv.Area((d["freq"], d["minimum_db"], d["maximum_db"]), FREQ, [lvl, lvl2],
                    label="min-max corridor").opts(
                color=COLORS["band"], alpha=0.35, line_alpha=0,
                hooks=[name_source("scatter.minmax")],
                hover_tooltips=[("min-max corridor", ""), ("Frequency", "$x{0.0} Hz"),
                                ("Level", "$y{0.0} dB")])
            * hv.Area((d["freq"], d["lower_db"], d["upper_db"]), FREQ, [lvl, lvl2],
                      label="percentile band").opts(
                color=COLORS["percentile"], alpha=0.45, line_alpha=0,
                hooks=[name_source("scatter.percentile")],
                hover_tooltips=[(f"central {percentile} % band", ""),
                                ("Frequency", "$x{0.0} Hz"), ("Level", "$y{0.0} dB")])
            * hv.Curve((d["freq"], d["reference_db"]), FREQ, lvl, label="unpolluted").opts(
                color=COLORS["reference"], hooks=[name_source("scatter.reference")],
                hover_tooltips=[("Frequency", "@freq{0.0} Hz"), ("Level", "@band_level{0.0} dB")])
        )

    def _round(self, result, dof, single_round):
        lvl = level_dim(dof, "band_level")
        if result is None:
            return hv.Curve(([], []), FREQ, lvl, label="single round").opts(
                hooks=[name_source("scatter.round")])
        d = compute.single_round_data(result, single_round, dof)
        return hv.Curve((d["freq"], d["round_db"]), FREQ, lvl,
                        label="single round").opts(
            color=COLORS["round"], line_width=1.5, hooks=[name_source("scatter.round")],
            hover_tooltips=[("Round", str(single_round)), ("Frequency", "@freq{0.0} Hz"),
                            ("Level", "@band_level{0.0} dB")])

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
        bands = hv.DynamicMap(self._bands, streams=[
            hv.streams.Params(self, ["result"]), hv.streams.Params(c, ["dof"]),
            hv.streams.Params(n, ["percentile"])])
        single = hv.DynamicMap(self._round, streams=[
            hv.streams.Params(self, ["result"]), hv.streams.Params(c, ["dof"]),
            hv.streams.Params(n, ["single_round"])])
        # click on the plot: show the round with the highest level at that frequency
        tap = hv.streams.Tap(source=single, x=None, y=None)
        tap.add_subscriber(self._pick_peak_round)
        plot = (bands * single).opts(
            hv.opts.Curve(**CURVE_OPTS), hv.opts.Area(responsive=True, min_height=320,
                                                      framewise=True, tools=["hover"]),
            hv.opts.Overlay(legend_position="bottom_left",
                            title="Scatter band: noise in the subsystem FRFs"))
        progress = pn.indicators.Progress(
            active=True, bar_color="primary", width=160, height=12,
            visible=self.param.busy, css_classes=["scatter-progress"], margin=(12, 10))
        dl = download_button("scatter", self._csv_columns, self._meta, self._filename)
        return pn.Column(
            pn.Row(pn.pane.Markdown("Click a frequency to draw the round with the highest "
                                    "level there (figs. 5.10-5.11).", margin=(0, 10)),
                   progress, self._status,
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
        }

    def _csv_columns(self) -> dict:
        d, r = self.data(), self.round_data()
        return {"freq_Hz": d["freq"], "reference_dB": d["reference_db"],
                "minimum_dB": d["minimum_db"], "maximum_dB": d["maximum_db"],
                "lower_dB": d["lower_db"], "upper_dB": d["upper_db"],
                f"round_{self.noise.single_round}_dB": r["round_db"]}
