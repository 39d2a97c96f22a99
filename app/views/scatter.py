"""Monte-Carlo noise scatter band (thesis section 5.2, figs. 5.9-5.11).

The band is computed off the event loop (a worker thread), so the page of this session stays
responsive and other sessions are not blocked; a progress bar shows while it runs, and a
result that arrives after the settings changed again is discarded.
"""

from __future__ import annotations

import asyncio
import time

import numpy as np
import panel as pn
import param
from bokeh.events import Tap
from panel.viewable import Viewer

from .. import compute
from ..state import CaseState, NoiseState
from .common import (
    COLORS,
    FREQ_LABEL,
    download_button,
    level_label,
    level_tooltips,
    live_text,
)
from .plots import Pusher, add_band, add_line, fit_range, frequency_range, new_figure

CASE_KEYS = ["harmonic", "n_modes", "coupling", "models"]
#: Seconds between a control change and the start of the band computation.
DEBOUNCE_S = 0.05
NOISE_KEYS = ["noise", "target", "frequency_dependent", "rounds", "seed"]


class ScatterBandView(Viewer):
    """Min/max corridor, percentile band, unpolluted reference and one single round."""

    case = param.ClassSelector(class_=CaseState)
    noise = param.ClassSelector(class_=NoiseState)
    result = param.Parameter(default=None, doc="The current scatter-band result object.")
    busy = param.Boolean(default=False, doc="True while a band is being computed.")
    seconds = param.Number(default=None, allow_None=True, doc="Wall time of the last band.")
    x_range = param.Parameter(
        default=None,
        doc="Frequency range shared with other views (linked zoom and pan); a new one if None.",
    )

    def __init__(self, **params):
        super().__init__(**params)
        self._pending = None
        self._layout = None
        self._push = Pusher()
        self.case.param.watch(self._schedule, CASE_KEYS)
        self.noise.param.watch(self._schedule, NOISE_KEYS)

    # -- computation -------------------------------------------------------------------
    def key(self) -> tuple:
        c, n = self.case, self.noise
        return (
            c.harmonic,
            c.n_modes,
            c.coupling,
            float(n.noise),
            n.target,
            bool(n.frequency_dependent),
            int(n.rounds),
            int(n.seed),
            c.models,
        )

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
        # Panel runs this coroutine on the event loop *without* the document lock (so the
        # session stays responsive while the band computes); every change of state that
        # reaches the Bokeh document is therefore handed back as a locked next-tick
        # callback (``_locked``) instead of being made here directly.
        key = self.key()
        self._pending = key
        self._locked(self.param.update, busy=True)
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
                self._locked(self._failed, f"Scatter band failed: {exc}")
            raise
        if self._pending != key:  # settings changed while computing: a newer task is running
            return
        self._locked(self._finish, key, res, time.perf_counter() - t0)

    @staticmethod
    def _locked(fn, *args, **kwargs):
        """Run ``fn`` on the event loop under the session's document lock."""
        pn.state.execute(lambda: fn(*args, **kwargs), schedule=True)

    def _finish(self, key, res, seconds):
        if self._pending == key:  # not overtaken while waiting for the lock
            self.param.update(result=res, seconds=seconds, busy=False)

    def _failed(self, message):
        self.busy = False
        if pn.state.notifications is not None:
            pn.state.notifications.error(message, duration=8000)

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

    def _status_text(self) -> str:
        if self.busy:
            return f"Computing {self.noise.rounds:,} rounds ..."
        if self.seconds is None or self.result is None:
            return ""
        conv = compute.convergence_db(self.result)
        return (
            f"{self.result.rounds:,} rounds in {self.seconds:.2f} s &middot; largest edge "
            f"change in the last half of the rounds: {conv:.1f} dB"
        )

    # -- plot ----------------------------------------------------------------------------
    def _build(self):
        if self.x_range is None:
            self.x_range = frequency_range()
        fig = new_figure(
            x_label=FREQ_LABEL,
            y_label=level_label(self.case.dof, "Band level"),
            x_range=self.x_range,
            name="scatter.figure",
            title="Click a frequency: the round with the highest level there",
        )
        self._fig = fig
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
        # click on the plot: show the round with the highest level at that frequency
        fig.on_event(Tap, lambda event: self._pick_peak_round(event.x, event.y))
        self._apply(*self._plot_state())()
        self.param.watch(self._changed, ["result"])
        self.case.param.watch(self._changed, ["dof"])
        self.noise.param.watch(self._changed, ["percentile", "single_round"])
        return fig

    def _plot_state(self) -> tuple:
        res, dof, n = self.result, self.case.dof, self.noise
        if res is None:
            return None, None, dof
        return (
            compute.band_data(res, dof, n.percentile),
            compute.single_round_data(res, n.single_round, dof),
            dof,
        )

    def _apply(self, band, single, dof):
        empty = np.zeros(0)

        def update():
            if band is None:
                for src in (self._minmax, self._pct):
                    src.data = {"freq": empty, "lower": empty, "upper": empty}
                for src in (self._ref, self._round):
                    src.data = {"freq": empty, "level": empty}
                return
            f = band["freq"]
            fit_range(self.x_range, f)
            self._minmax.data = {
                "freq": f,
                "lower": band["minimum_db"],
                "upper": band["maximum_db"],
            }
            self._pct.data = {"freq": f, "lower": band["lower_db"], "upper": band["upper_db"]}
            self._ref.data = {"freq": f, "level": band["reference_db"]}
            self._round.data = {"freq": f, "level": single["round_db"]}
            self._fig.yaxis[0].axis_label = level_label(dof, "Band level")

        return update

    def _changed(self, *events):
        self._push(lambda: self._apply(*self._plot_state()))

    def __panel__(self):
        if self._layout is not None:
            return self._layout
        # The indicator and the status line keep their place and size: changing their
        # content does not make the browser lay out the page again (toggling visibility
        # did, and delayed every plot update sent with it by 100-200 ms).
        progress = pn.indicators.Progress(
            active=self.busy,
            value=-1 if self.busy else 0,
            max=100,
            bar_color="primary",
            width=160,
            height=12,
            css_classes=["scatter-progress"],
            margin=(12, 10),
        )
        # its own line, two lines high: the text's length changes, its box does not
        status = live_text(
            self._status_text,
            [(self, ["busy", "seconds", "result"])],
            height=40,
            css_classes=["scatter-status"],
            styles={"font-size": "0.85em", "line-height": "1.3"},
        )
        self.param.watch(
            lambda _: progress.param.update(active=self.busy, value=-1 if self.busy else 0), "busy"
        )
        dl = download_button("scatter", self._csv_columns, self._meta, self._filename)
        self._layout = pn.Column(
            pn.Row(progress, dl),
            status,
            pn.pane.Bokeh(self._build(), sizing_mode="stretch_both", min_height=340),
            sizing_mode="stretch_both",
        )
        return self._layout

    def _pick_peak_round(self, x=None, y=None):
        if x is None or self.result is None:
            return
        self.noise.single_round = compute.peak_round(self.result, x, self.case.dof, "max")

    def _filename(self) -> str:
        c, n = self.case, self.noise
        fd = "fdep" if n.frequency_dependent else "findep"
        return (
            f"scatter_band_h{c.harmonic}_{c.dof}_p{n.noise:g}_{n.target}_{fd}"
            f"_R{n.rounds}_seed{n.seed}.csv"
        )

    def _meta(self) -> dict:
        c, n = self.case, self.noise
        lo = (100 - n.percentile) / 2
        return {
            "view": "Monte-Carlo scatter band (thesis 5.2)",
            "harmonic": c.harmonic,
            "N (retained tire modes)": c.n_modes,
            "response DOF": f"bushing:{c.dof}",
            "coupling": c.coupling,
            "noise_pct": n.noise,
            "noise target": n.target,
            "frequency dependent": n.frequency_dependent,
            "rounds": n.rounds,
            "seed": n.seed,
            "single round": n.single_round,
            "percentiles": f"{lo:g}-{100 - lo:g}",
            "unit": compute.level_unit(c.dof),
            "lower/upper": "min/max of |v_e| over the rounds; percentiles numpy 'linear'",
            "models": c.models.describe(),
        }

    def _csv_columns(self) -> dict:
        d, r = self.data(), self.round_data()
        return {
            "freq_Hz": d["freq"],
            "reference_dB": d["reference_db"],
            "minimum_dB": d["minimum_db"],
            "maximum_dB": d["maximum_db"],
            "lower_dB": d["lower_db"],
            "upper_dB": d["upper_db"],
            f"round_{self.noise.single_round}_dB": r["round_db"],
        }
