"""One session's results: computed from its state, published as parameters.

:class:`Results` is the only place a session computes anything. It owns the session's
:class:`~app.state.DashboardState` (the controls and the data source) and publishes one
:class:`Result` per view as a parameter. Each result is declared once, next to the method
that computes it, with the state parameters it depends on::

    @param.depends("state.case.harmonic", "state.case.dof", watch=True, on_init=True)
    def _response(self):
        self._publish("response", lambda s: ...)

so that adding a published result is a parameter and a method, and adding a view of it is a
:class:`~app.views.live.LiveView` subclass that draws it.

Ordering: every result is computed and published under the session's one lock, and it
reads the state *inside* that lock. Control changes of one session arrive on several
worker threads in any order; whichever thread publishes last read the state last, so the
newest state always lands last (no tickets, no tokens).

Consistency: a :class:`Result` carries its data *and* their description (the settings it was
computed for, the CSV header, the file name, the caption) from one snapshot of the state,
so a view or an export can never pair data with another state's description.

The scatter band is the one long computation: it runs on its own thread
(:mod:`app.bands`), one live band per session (a newer request cancels the older one
between the kernel's chunks), and bands of all sessions take turns chunk by chunk.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import param

from fbs_core.units import frf_unit, input_kind, output_kind
from fbs_core.vocabulary import EIGEN_SPEEDS

from . import background, bands, compute
from .state import DashboardState

__all__ = ["Result", "Results", "Snapshot", "BandStatus", "progress_status"]


@dataclass(frozen=True, eq=False)
class Result:
    """What one view shows: data and their description, from one state.

    Attributes
    ----------
    columns : mapping of str to 1-D ndarray
        The data as exported (CSV columns, equal length).
    meta : mapping of str to object
        The CSV header: the settings these data were computed for.
    filename : str
        The CSV file name.
    caption : str
        One line for the page (``**bold**`` and ``&middot;`` allowed; escaped as text).
    draw : mapping
        Anything else the view needs to draw these data (curves in dB, axis labels,
        marker positions).
    """

    columns: Mapping[str, np.ndarray] = field(default_factory=dict)
    meta: Mapping[str, Any] = field(default_factory=dict)
    filename: str = "data.csv"
    caption: str = ""
    draw: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Snapshot:
    """The state of a session at one moment (plain values, read under the lock)."""

    harmonic: int
    n_modes: int
    dof: str
    coupling: str
    show_uncoupled: bool
    spindle_input: str
    models: Any
    noise: float
    target: str
    frequency_dependent: bool
    rounds: int
    seed: int
    single_round: int
    percentile: int
    threshold: float
    f_max: float
    map_mode: str
    residual: bool = False

    @classmethod
    def of(cls, state: DashboardState) -> Snapshot:
        c, n, t = state.case, state.noise, state.truncation
        return cls(
            harmonic=int(c.harmonic),
            n_modes=int(c.n_modes),
            dof=c.dof,
            coupling=c.coupling,
            show_uncoupled=bool(c.show_uncoupled),
            spindle_input=c.spindle_input,
            models=c.models,
            noise=float(n.noise),
            target=n.target,
            frequency_dependent=bool(n.frequency_dependent),
            rounds=int(n.rounds),
            seed=int(n.seed),
            single_round=int(n.single_round),
            percentile=int(n.percentile),
            threshold=float(t.threshold),
            f_max=float(t.f_max),
            map_mode=t.map_mode,
            residual=bool(c.residual),
        )

    @property
    def map_dof(self) -> str | None:
        """The DOF the error map and the suggestion judge (None: max over the 6 DOFs)."""
        return self.dof if self.map_mode == "selected DOF" else None

    def band_key(self) -> tuple:
        return compute.band_key(
            self.harmonic,
            self.n_modes,
            self.coupling,
            self.noise,
            self.target,
            self.frequency_dependent,
            self.rounds,
            self.seed,
            self.models,
        )


@dataclass(frozen=True, eq=False)
class Band:
    """A finished scatter band and the settings it was computed for."""

    result: Any  # fbs_core.ScatterBand
    settings: Snapshot
    seconds: float


@dataclass(frozen=True)
class BandStatus:
    """Whether a band is being computed, and the line the page shows about it.

    During a computation ``done`` of ``total`` frequency lines are done (0 of 0 before the
    kernel's first report) and ``seconds_left`` estimates the rest (None: not yet known).
    """

    busy: bool = False
    text: str = ""
    done: int = 0
    total: int = 0
    seconds_left: float | None = None

    @property
    def percent(self) -> int:
        return int(100 * self.done / self.total) if self.total else 0


def duration_text(seconds: float) -> str:
    """``"about 1 min 10 s"``, ``"about 8 s"``, ``"under a second"``."""
    if seconds < 1:
        return "under a second"
    s = int(round(seconds))
    return f"about {s // 60} min {s % 60} s" if s >= 60 else f"about {s} s"


def progress_status(rounds: int, done: int, total: int, seconds_left) -> BandStatus:
    """The status of a running band: done/total lines and the time left."""
    text = f"Computing {rounds:,} rounds ..."
    if total:
        text = (
            f"Computing {rounds:,} rounds: {int(100 * done / total)} % "
            f"({done} of {total} frequency lines)"
        )
        if seconds_left is not None:
            text += f", {duration_text(seconds_left)} left"
    return BandStatus(True, text, done, total, seconds_left)


class Results(param.Parameterized):
    """The published results of one browser session (see the module docstring)."""

    state = param.ClassSelector(class_=DashboardState, instantiate=False, constant=True)

    response = param.ClassSelector(class_=Result, doc="Coupled response v_e* (eq. 4.1).")
    error_map = param.ClassSelector(class_=Result, doc="Truncation error map (eq. 5.1).")
    suggested = param.ClassSelector(class_=Result, doc="Suggested modes (table 5.1).")
    eigen = param.ClassSelector(class_=Result, doc="Eigenfrequency vs N (fig. 5.8).")
    tire_quality = param.ClassSelector(
        class_=Result, doc="Leave-one-out interpolation error and speed coverage of the tire."
    )
    uncoupled = param.ClassSelector(
        class_=Result, allow_None=True, doc="Uncoupled tire and chassis (None until shown)."
    )
    band = param.ClassSelector(class_=Band, allow_None=True, doc="The latest scatter band.")
    band_curves = param.ClassSelector(
        class_=Result, allow_None=True, doc="The band's curves at the selected DOF."
    )
    band_status = param.ClassSelector(class_=BandStatus, doc="Band computation status.")
    pinned = param.Parameter(
        default=(),
        doc="The Analysis card's pinned baselines against the current state: a tuple of "
        "Result, one per pin (app.analysis_store; the report shows each).",
    )
    closed = param.Boolean(default=False, doc="The session has ended: nothing is drawn.")
    background = param.Boolean(
        default=None,
        allow_None=True,
        doc="Compute bands on a thread of their own (None: when the page is served).",
    )

    @property
    def threaded(self) -> bool:
        """Whether longer work goes to threads of its own: ``background``, or when it is
        None, whether the page is served (no server: tests, exports compute in place)."""
        return bands.served() if self.background is None else bool(self.background)

    def __init__(self, state: DashboardState | None = None, **params):
        self._lock = threading.RLock()
        self._band_job: bands.Job | None = None
        self._pending: set = set()  # residual tables being computed (see _residual_table)
        params["state"] = state if state is not None else DashboardState()
        params.setdefault("band_status", BandStatus())
        #: Publishers that run first on a change of the case, before this store's own (the
        #: Analysis card registers the one of the view it shows: what the user looks at is
        #: computed and drawn first; ``app.analysis_store``).
        self.first_publishers: list[Callable[[], None]] = []
        super().__init__(**params)

    # -- publishing ------------------------------------------------------------------------
    def _publish(self, name: str, make: Callable[[Snapshot], Any]) -> None:
        """Compute ``make(snapshot)`` from the current state and publish it as ``name``,
        all under the session's lock (the newest state lands last)."""
        with self._lock:
            if self.closed:
                return
            setattr(self, name, make(Snapshot.of(self.state)))

    @property
    def lock(self) -> threading.RLock:
        """The session's lock (publishers of other results of the session share it)."""
        return self._lock

    def snapshot(self) -> Snapshot:
        """The current state as plain values."""
        return Snapshot.of(self.state)

    # -- the results, each next to what it depends on -----------------------------------------
    # (param calls a class's watchers in the order of their definition: this one first)
    @param.depends(
        "state.case.harmonic",
        "state.case.n_modes",
        "state.case.dof",
        "state.case.coupling",
        "state.case.spindle_input",
        "state.case.models",
        watch=True,
    )
    def _first(self):
        for publish in list(self.first_publishers):
            publish()

    @param.depends(
        "state.case.harmonic",
        "state.case.n_modes",
        "state.case.dof",
        "state.case.coupling",
        "state.case.models",
        "state.case.residual",
        watch=True,
        on_init=True,
    )
    def _response(self):
        self._publish("response", response_result)

    @param.depends(
        "state.case.harmonic",
        "state.case.n_modes",
        "state.case.dof",
        "state.case.coupling",
        "state.case.models",
        "state.truncation.map_mode",
        "state.truncation.threshold",
        "state.truncation.f_max",
        "state.case.residual",
        watch=True,
        on_init=True,
    )
    def _error_map(self):
        self._publish("error_map", error_map_result)

    @param.depends(
        "state.case.coupling",
        "state.case.dof",
        "state.case.models",
        "state.truncation.map_mode",
        "state.truncation.threshold",
        "state.truncation.f_max",
        "state.case.residual",
        watch=True,
        on_init=True,
    )
    def _suggested(self):
        self._publish("suggested", lambda s: suggested_result(s, self._residual_table(s)))

    def _residual_table(self, s: Snapshot) -> dict | None:
        """The suggestion with residual compensation beside the plain one, or None while
        it is computed on a thread of its own (served pages: its seven residual maps must
        not delay the first page); the table is published again when it is ready."""
        args = (s.threshold, s.f_max, s.coupling, s.map_dof, s.models, True)
        later = self.threaded
        if s.residual or not later or compute.suggested_table_ready(*args):
            return compute.suggested_table(*args)
        with self._lock:
            if args in self._pending:
                return None
            self._pending.add(args)

        def work():
            try:
                compute.suggested_table(*args)
            finally:
                with self._lock:
                    self._pending.discard(args)
            self._suggested()  # publish again (with the column if the state still wants it)

        def start():  # at a lower priority: the page's own updates win the cores
            background.start(work, "residual-table")

        if bands.served():  # after the page is sent (its first build stays as fast)
            import panel as pn

            pn.state.onload(start)
        else:
            start()
        return None

    @param.depends("state.case.models", watch=True, on_init=True)
    def _tire_quality(self):
        self._publish("tire_quality", tire_quality_result)

    @param.depends("state.case.models", "state.case.n_modes", watch=True, on_init=True)
    def _eigen(self):
        self._publish("eigen", eigen_result)

    @param.depends(
        "state.case.show_uncoupled",
        "state.case.harmonic",
        "state.case.n_modes",
        "state.case.dof",
        "state.case.spindle_input",
        "state.case.models",
        watch=True,
        on_init=True,
    )
    def _uncoupled(self):
        self._publish(
            "uncoupled",
            lambda s: uncoupled_result(s) if s.show_uncoupled or self.uncoupled else None,
        )

    @param.depends(
        "band",
        "state.case.dof",
        "state.noise.percentile",
        "state.noise.single_round",
        watch=True,
        on_init=True,
    )
    def _band_curves(self):
        self._publish("band_curves", lambda s: band_result(self.band, s))

    # -- the scatter band: long, off the session's threads --------------------------------
    @param.depends(
        "state.case.harmonic",
        "state.case.n_modes",
        "state.case.coupling",
        "state.case.models",
        "state.noise.noise",
        "state.noise.target",
        "state.noise.frequency_dependent",
        "state.noise.rounds",
        "state.noise.seed",
        watch=True,
    )
    def request_band(self, *, wait: bool | None = None) -> None:
        """Compute the band of the current settings (cancelling one still running).

        ``wait=True`` computes it in the calling thread (no server: tests, exports, the
        warm-up); by default it runs in the background when the page is served.
        """
        with self._lock:
            if self.closed:
                return
            s = self.snapshot()
            key = s.band_key()
            running = self._band_job
            if running is not None and running.key == key:
                return  # already on its way
            if running is not None:
                running.cancel()
                self._band_job = None
            if self.band is not None and self.band.settings.band_key() == key:
                self.band_status = _done_status(self.band)  # back to the shown band
                return
            job = self._band_job = bands.Job(key, owner=self, on_progress=self._band_progress)
            self.band_status = progress_status(s.rounds, 0, 0, None)
        if wait is None:
            wait = not self.threaded
        if wait:
            bands.run(job, self._band_done, s)
        else:
            bands.start(job, self._band_done, s)

    #: Shortest interval between two progress updates of the page (s).
    PROGRESS_INTERVAL = 0.4

    def _band_progress(self, job: bands.Job) -> None:
        """The kernel finished a chunk of ``job``: publish done/total and the time left
        (at most every PROGRESS_INTERVAL seconds; short bands finish before the first)."""
        now = time.perf_counter()
        last = getattr(job, "published", job.started)
        if job.done < job.total and now - last < self.PROGRESS_INTERVAL:
            return
        job.published = now
        with self._lock:
            if job is not self._band_job or job.cancelled or self.closed:
                return
            rounds = job.key[6]
            self.band_status = progress_status(rounds, job.done, job.total, job.seconds_left())

    def cancel_band(self) -> None:
        """Stop the running band (the cancel button); the band on the page stays, marked as
        not of the current settings."""
        with self._lock:
            job = self._band_job
            if job is None:
                return
            job.cancel()
            self._band_job = None
            shown = "" if self.band is None else " The plot shows the band of earlier settings."
            self.band_status = BandStatus(
                False,
                f"Cancelled after {job.done} of {job.total} frequency lines.{shown} "
                "Change a noise setting to compute again.",
            )

    def _band_done(self, job: bands.Job, settings: Snapshot, res, seconds: float, error) -> None:
        with self._lock:
            if job is not self._band_job or job.cancelled or self.closed:
                return  # superseded: a newer job publishes
            self._band_job = None
            if error is not None:
                self.band_status = BandStatus(False, f"Scatter band failed: {error}")
                return
            self.band = Band(res, settings, seconds)
            self.band_status = _done_status(self.band)

    def band_now(self) -> Band | None:
        """The band of the current settings, computed here if needed (None if it failed)."""
        self.request_band(wait=True)
        return self.band

    def pick_peak_round(self, freq: float) -> None:
        """Show the round with the highest level at the line nearest ``freq`` (Hz)."""
        band = self.band
        if band is None:
            return
        self.state.noise.single_round = compute.peak_round(
            band.result, float(freq), self.state.case.dof, "max"
        )

    def close(self) -> None:
        """The session ended: cancel its band and publish nothing more."""
        with self._lock:
            self.closed = True
            if self._band_job is not None:
                self._band_job.cancel()
                self._band_job = None


def _done_status(band: Band) -> BandStatus:
    conv = compute.convergence_db(band.result)
    return BandStatus(
        False,
        f"{band.result.rounds:,} rounds in {band.seconds:.2f} s &middot; largest edge change "
        f"in the last half of the rounds: {conv:.1f} dB",
    )


# -- what each result holds -----------------------------------------------------------------
def residual_meta(on: bool) -> str:
    """The CSV header's word on residual compensation."""
    if on:
        return (
            "on: the tire modes left out of N enter with their quasi-static part "
            "(upper residual flexibility, docs/tire-model.md)"
        )
    return "off: plain truncation to N modes"


def tire_meta(s: Snapshot, harmonics=None) -> dict:
    """The tire's interpolation quality and speed coverage for a CSV header (issue 13)."""
    q = compute.tire_quality(s.models)
    ks = [s.harmonic] if harmonics is None else list(harmonics)
    idx = [list(q["harmonic"]).index(k) for k in ks]
    loo = "; ".join(
        f"h{k}: " + ("n/a" if not np.isfinite(q["loo_db"][i]) else f"{q['loo_db'][i]:.2f} dB")
        for k, i in zip(ks, idx, strict=True)
    )
    warn = [w for k, w in zip(q["harmonic"], _band_warnings(q), strict=True) if k in ks and w]
    return {
        "tire interpolation error (leave-one-out, worst)": loo,
        "tire speed range": (
            " | ".join(warn)
            if warn
            else f"covered: {q['speeds'][0]:g}-{q['speeds'][1]:g} km/h, "
            f"{q['n_points']} operating points"
        ),
    }


def _band_warnings(q: dict) -> list[str]:
    """One warning text (or "") per harmonic of ``compute.tire_quality``'s table."""
    texts = iter(q["warnings"])
    return [("" if ok else next(texts, "outside the stored speeds")) for ok in q["covered"]]


def tire_quality_result(s: Snapshot) -> Result:
    q = compute.tire_quality(s.models)
    warn = _band_warnings(q)
    return Result(
        columns={
            "harmonic": np.asarray(q["harmonic"]),
            "loo_error_dB": np.asarray(q["loo_db"]),
            "speeds_covered": np.asarray(q["covered"], float),
        },
        meta={
            "view": "tire interpolation quality (leave-one-out) and speed coverage",
            "method": q["method"],
            "operating points": f"{q['n_points']}, {q['speeds'][0]:g}-{q['speeds'][1]:g} km/h",
            "speed range warnings": " | ".join(w for w in warn if w) or "none",
            "models": s.models.describe(),
        },
        filename="tire_interpolation_quality.csv",
        caption=(
            f"Tire between its {q['n_points']} operating points "
            f"({q['speeds'][0]:g}-{q['speeds'][1]:g} km/h): leave-one-out error per "
            "harmonic band"
        ),
        draw={"quality": q, "warnings": warn, "harmonic": s.harmonic},
    )


def response_result(s: Snapshot) -> Result:
    d = compute.mobility_data(s.harmonic, s.n_modes, s.dof, s.coupling, s.models, s.residual)
    res = " + residual" if s.residual else ""
    return Result(
        columns={
            "freq_Hz": d["freq"],
            "reference_dB": d["reference_db"],
            "truncated_dB": d["truncated_db"],
            "reference": d["reference"],
            "truncated": d["truncated"],
        },
        meta={
            "view": "coupled bushing response v_e* (thesis eq. 4.1)",
            "harmonic": s.harmonic,
            "N (retained tire modes)": s.n_modes,
            "reference": "all tire modes",
            "residual compensation": residual_meta(s.residual),
            "response DOF": f"bushing:{s.dof}",
            "coupling": s.coupling,
            "unit": compute.level_unit(s.dof),
            "models": s.models.describe(),
            **tire_meta(s),
        },
        filename=(
            f"bushing_response_h{s.harmonic}_N{s.n_modes}{'_res' if s.residual else ''}"
            f"_{s.dof}_{s.coupling}.csv"
        ),
        caption=(
            f"**Harmonic {s.harmonic}** &middot; bushing:{s.dof} &middot; N = {s.n_modes}"
            f"{res} &middot; {s.coupling} coupling"
        ),
        draw={
            "dof": s.dof,
            "truncated_label": f"N retained modes{' + residual' if s.residual else ''}",
        },
    )


def _suggested_n(s: Snapshot) -> int:
    tab = compute.suggested_table(s.threshold, s.f_max, s.coupling, s.map_dof, s.models, s.residual)
    return int(tab["n_modes"][list(tab["harmonic"]).index(s.harmonic)])


def error_map_result(s: Snapshot) -> Result:
    d = compute.error_map_data(s.harmonic, s.coupling, s.map_dof, s.models, s.residual)
    what = f"bushing:{s.dof}" if s.map_dof else "max over 6 DOFs"
    if s.residual:
        what += ", with residuals"
    nn, ff = np.meshgrid(d["n_modes"], d["centre_freq"], indexing="ij")
    return Result(
        columns={
            "n_modes": nn.ravel(),
            "centre_freq_Hz": ff.ravel(),
            "error_pct": d["error_pct"].ravel(),
        },
        meta={
            "view": "truncation error map (thesis eq. 5.1, figs. 5.3/5.6/5.7)",
            "harmonic": s.harmonic,
            "coupling": s.coupling,
            "response DOF": what,
            "reference": "all tire modes",
            "residual compensation": residual_meta(s.residual),
            "layout": "long: one row per (N, centre freq)",
            "models": s.models.describe(),
            **tire_meta(s),
        },
        filename=(
            f"truncation_map_h{s.harmonic}_{s.map_dof or 'maxdof'}"
            f"{'_res' if s.residual else ''}.csv"
        ),
        draw={
            "map": d,
            "title": f"Harmonic {s.harmonic}, {what}",
            "threshold": s.threshold,
            "f_max": s.f_max,
            "n_modes": s.n_modes,
            "suggested_n": _suggested_n(s),
            "freq": compute.frequencies(s.harmonic),
        },
    )


def suggested_result(s: Snapshot, tab_r: dict | None = None) -> Result:
    """The suggested N for every harmonic, plain and (``tab_r``) with residuals; without
    ``tab_r`` (still being computed) that column is NaN and the caption says so."""
    tab = compute.suggested_table(s.threshold, s.f_max, s.coupling, s.map_dof, s.models)
    pending = tab_r is None
    if tab_r is None:
        nan = np.full(len(tab["harmonic"]), np.nan)
        tab_r = {**tab, "n_modes": nan, "eigenfrequency": nan}
    where = f"bushing:{s.dof}" if s.map_dof else s.map_mode
    shown = "with residuals" if s.residual else "plain"
    return Result(
        columns={
            "harmonic": tab["harmonic"],
            "f_low_Hz": tab["f_low"],
            "f_high_Hz": tab["f_high"],
            "n_modes": tab["n_modes"],
            "n_modes_residual": tab_r["n_modes"],
            "eigenfrequency_Hz": tab["eigenfrequency"],
            "eigenfrequency_residual_Hz": tab_r["eigenfrequency"],
        },
        meta={
            "view": "suggested number of modes (thesis table 5.1)",
            "threshold_pct": s.threshold,
            "f_max_Hz": s.f_max,
            "coupling": s.coupling,
            "response DOF": f"bushing:{s.dof}" if s.map_dof else "max over 6 DOFs",
            "eigenfrequency": "highest retained eigenfrequency at 80 km/h",
            "n_modes": "plain truncation to N modes",
            "n_modes_residual": "N modes + quasi-static part of the modes left out "
            "(residual compensation)",
            "shown in the error map": shown,
            "with residuals": "being computed (NaN)" if pending else "computed",
            "models": s.models.describe(),
            **tire_meta(s, harmonics=tab["harmonic"]),
        },
        filename=f"suggested_modes_thr{s.threshold:g}_fmax{s.f_max:g}.csv",
        caption=(
            f"Smallest N from which the error stays below **{s.threshold:g} %** up "
            f"to **{s.f_max:g} Hz** ({where}), plain and with residual compensation "
            f"(the error map and its dashed line: **{shown}**), and the highest "
            "eigenfrequency among those modes at 80 km/h."
            + (" The column with residuals is being computed ..." if pending else "")
        ),
        draw={"table": tab, "table_residual": tab_r, "residual": s.residual},
    )


def eigen_result(s: Snapshot) -> Result:
    d = compute.eigen_curves(s.models)
    return Result(
        columns={
            "n_modes": d["n_modes"],
            **{f"f_{v:g}kmh_Hz": d[f"f_{int(v)}"] for v in EIGEN_SPEEDS},
        },
        meta={
            "view": "highest retained eigenfrequency vs N (thesis fig. 5.8)",
            "models": s.models.describe(),
        },
        filename="eigenfrequency_vs_modes.csv",
        draw={"curves": d, "n_modes": s.n_modes},
    )


def chassis_label(dof: str, spindle_input: str) -> str:
    """Axis label of the chassis mobility from a spindle input to a bushing DOF."""
    out, inp = output_kind(f"bushing:{dof}"), input_kind(f"spindle:{spindle_input}")
    return f"Mobility (dB re 1 {frf_unit(out, inp, 'mobility')})"


def uncoupled_result(s: Snapshot) -> Result:
    d = compute.uncoupled_data(s.harmonic, s.n_modes, s.dof, s.spindle_input, s.models)
    # column name -> key of the computed data (units in the names, as every export)
    keys = {
        "freq_Hz": "freq",
        "tire_reference_dB": "tire_reference_db",
        "tire_truncated_dB": "tire_truncated_db",
        "chassis_dB": "chassis_db",
        "tire_reference": "tire_reference",
        "tire_truncated": "tire_truncated",
        "chassis": "chassis",
    }
    chassis_unit = frf_unit(
        output_kind(f"bushing:{s.dof}"), input_kind(f"spindle:{s.spindle_input}"), "mobility"
    )
    tire_unit = frf_unit(output_kind(f"hub:{s.dof}"), "road", "mobility")
    return Result(
        columns={name: d[k] for name, k in keys.items()},
        meta={
            "view": "uncoupled subsystems",
            "harmonic": s.harmonic,
            "N (retained tire modes)": s.n_modes,
            "tire output": f"hub:{s.dof}",
            "chassis": f"spindle:{s.spindle_input} -> bushing:{s.dof}",
            "unit": (
                f"tire_*: {tire_unit} (free hub velocity per metre of road amplitude), "
                f"tire_*_dB: dB re 1 {tire_unit}; chassis: {chassis_unit}, chassis_dB: "
                f"dB re 1 {chassis_unit}"
            ),
            "models": s.models.describe(),
        },
        filename=f"uncoupled_h{s.harmonic}_N{s.n_modes}_{s.dof}_in{s.spindle_input}.csv",
        draw={
            "dof": s.dof,
            "tire_title": f"Tire: free hub velocity hub:{s.dof} (figs. 4.6-4.7)",
            "chassis_title": f"Chassis: spindle:{s.spindle_input} -> bushing:{s.dof} "
            "(figs. 4.2-4.3)",
            "chassis_label": chassis_label(s.dof, s.spindle_input),
        },
    )


def band_result(band: Band | None, s: Snapshot) -> Result | None:
    """The band's curves at the selected DOF, percentile band and round.

    The header describes the band as it was computed (``band.settings``), whatever the
    controls say now: a band still computing for new settings never relabels old data.
    """
    if band is None:
        return None
    b = band.settings
    res = band.result
    d = compute.band_data(res, s.dof, s.percentile)
    k = min(s.single_round, res.rounds - 1)  # the round must exist in this band
    r = compute.single_round_data(res, k, s.dof)
    lo = (100 - s.percentile) / 2
    fd = "fdep" if b.frequency_dependent else "findep"
    return Result(
        columns={
            "freq_Hz": d["freq"],
            "reference_dB": d["reference_db"],
            "minimum_dB": d["minimum_db"],
            "maximum_dB": d["maximum_db"],
            "pct_low_dB": d["pct_low_db"],
            "pct_high_dB": d["pct_high_db"],
            f"round_{k}_dB": r["round_db"],
        },
        meta={
            "view": "Monte-Carlo scatter band (thesis 5.2)",
            "harmonic": b.harmonic,
            "N (retained tire modes)": b.n_modes,
            "response DOF": f"bushing:{s.dof}",
            "coupling": b.coupling,
            "noise_pct": b.noise,
            "noise target": b.target,
            "frequency dependent": b.frequency_dependent,
            "rounds": b.rounds,
            "seed": b.seed,
            "single round": k,
            "percentiles": f"{lo:g}-{100 - lo:g}",
            "unit": compute.level_unit(s.dof),
            "minimum/maximum": "min/max of |v_e| over the rounds",
            "pct_low/pct_high": "percentiles of |v_e| over the rounds (numpy 'linear')",
            "models": b.models.describe(),
        },
        filename=(
            f"scatter_band_h{b.harmonic}_{s.dof}_p{b.noise:g}_{b.target}_{fd}"
            f"_R{b.rounds}_seed{b.seed}.csv"
        ),
        draw={"band": d, "round": r, "dof": s.dof, "seconds": band.seconds},
    )
