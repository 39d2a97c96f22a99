"""The Analysis card's results of one session (issue 18), published like :mod:`app.store`.

:class:`AnalysisResults` sits beside the session's :class:`~app.store.Results` (it reads the
same state, under the same session lock, so the newest state lands last here too) and
publishes one :class:`~app.store.Result` per analysis view. Each result is computed only
while its tab is shown (``state.analysis.tab``): a collapsed card or another tab costs
nothing, and showing a tab computes its result from the current state (cached in
:mod:`app.analysis_compute` per harmonic, N, coupling and models).

The coupled modes near the peaks (an eigenvalue solve of the assembled tire + chassis per
peak, 0.3-1 s each) are computed after the phase result is published, on a thread of their
own, and published as :attr:`AnalysisResults.peak_modes` for the phase result they belong
to: the peak labels show at once and gain their modes when these arrive.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import param

from fbs_core.analysis import add_pin, delta_cursor, phase_deg, pin_state, remove_pin
from fbs_core.errors import FBSError
from fbs_core.vocabulary import magnitude_db, percent

from . import analysis_compute as ac
from . import background, compute
from .analysis_pins import build_pin, compare_result, pin_result, pin_settings
from .analysis_state import check_pin_name, decode_pins, encode_pins
from .store import Result, Results, Snapshot, chassis_label

__all__ = ["AnalysisResults", "AnalysisSnapshot"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class AnalysisSnapshot:
    """The session's state and the Analysis card's settings at one moment."""

    base: Snapshot
    tab: str
    frf: str
    phase_mode: str
    log_freq: bool
    cursor1: float
    cursor2: float
    picked_speed: float
    picked_freq: float
    contrib_mode: str

    @classmethod
    def of(cls, state) -> AnalysisSnapshot:
        a = state.analysis
        return cls(
            base=Snapshot.of(state),
            tab=a.tab,
            frf=a.frf,
            phase_mode=a.phase_mode,
            log_freq=bool(a.log_freq),
            cursor1=float(a.cursor1),
            cursor2=float(a.cursor2),
            picked_speed=float(a.picked_speed),
            picked_freq=float(a.picked_freq),
            contrib_mode=a.contrib_mode,
        )


class AnalysisResults(param.Parameterized):
    """The published results of the Analysis card of one session."""

    store = param.ClassSelector(class_=Results, constant=True, doc="The session's results.")

    contributions = param.ClassSelector(class_=Result, allow_None=True)
    phase = param.ClassSelector(class_=Result, allow_None=True)
    peak_modes = param.Parameter(
        default=None, doc="(phase result, labels with the coupled modes nearby) or None."
    )
    campbell = param.ClassSelector(class_=Result, allow_None=True)
    speed_map = param.ClassSelector(class_=Result, allow_None=True)
    pick = param.ClassSelector(class_=Result, doc="The picked speed and frequency.")
    pins = param.Parameter(default=(), doc="The pinned baselines (tuple of app.analysis_pins.Pin).")
    compare = param.ClassSelector(class_=Result, allow_None=True)
    message = param.String(default="", doc="The last pin action's problem ('' if none).")

    #: Results published ahead of the main views when their tab is shown, and re-published
    #: only when what they are made of changed (:meth:`_inputs`).
    SHOWN_FIRST = {
        "contributions": "contributions",
        "phase": "phase",
        "speed": "speed_map",
        "compare": "compare",
    }

    def __init__(self, **params):
        self._made: dict[str, tuple] = {}  # the inputs of each result published (_inputs)
        super().__init__(**params)
        self.store.first_publishers.append(self._publish_shown)

    def _publish_shown(self) -> None:
        """Publish the shown tab's result now, ahead of the main views' results (the store
        calls this first on a change of the case); its own watcher later finds it current."""
        name = self.SHOWN_FIRST.get(self.state.analysis.tab)
        if name is not None:
            getattr(self, f"_{name}")()  # the result's own publisher

    @property
    def state(self):
        return self.store.state

    def _publish(self, name: str, tab: str | None, make: Callable[[AnalysisSnapshot], Any]) -> bool:
        """Publish ``make(snapshot)`` as ``name`` under the session's lock, but only while
        ``tab`` is shown (None: always); whether it was published."""
        with self.store.lock:
            if self.store.closed:
                return False
            s = AnalysisSnapshot.of(self.state)
            if tab is not None and s.tab != tab:
                return False
            inputs = self._inputs(name, s)
            if name in self.SHOWN_FIRST.values():
                made = self._made.get(name)
                if made is not None and _same(made, inputs) and getattr(self, name) is not None:
                    return False  # published for these very inputs already (ahead of the others)
            setattr(self, name, make(s))
            self._made[name] = inputs
            return True

    def _inputs(self, name: str, s: AnalysisSnapshot) -> tuple:
        """What result ``name`` is made of: the snapshot, and for the comparison also the
        pins, the pin compared to and the current band (in the cache when computed)."""
        if name == "compare":
            band = compute.cached_band(s.base.band_key())
            return (s, self.pins, self.state.analysis.compare_to, band)
        return (s,)

    # -- results -----------------------------------------------------------------------------
    @param.depends(
        "store.state.analysis.picked_speed",
        "store.state.analysis.picked_freq",
        watch=True,
        on_init=True,
    )
    def _pick(self):
        self._publish("pick", None, pick_result)

    @param.depends(
        "store.state.analysis.tab",
        "store.state.analysis.contrib_mode",
        "store.state.case.harmonic",
        "store.state.case.n_modes",
        "store.state.case.dof",
        "store.state.case.coupling",
        "store.state.case.models",
        watch=True,
        on_init=True,
    )
    def _contributions(self):
        self._publish("contributions", "contributions", contributions_result)

    @param.depends(
        "store.state.analysis.tab",
        "store.state.analysis.frf",
        "store.state.analysis.phase_mode",
        "store.state.analysis.log_freq",
        "store.state.analysis.cursor1",
        "store.state.analysis.cursor2",
        "store.state.case.harmonic",
        "store.state.case.n_modes",
        "store.state.case.dof",
        "store.state.case.coupling",
        "store.state.case.spindle_input",
        "store.state.case.models",
        watch=True,
        on_init=True,
    )
    def _phase(self):
        if not self._publish("phase", "phase", phase_result):
            return
        r = self.phase
        if r is not None and r.draw.get("modes_wanted") and not self.store.closed:
            self._find_modes(r)

    @param.depends("store.state.analysis.tab", "store.state.case.models", watch=True, on_init=True)
    def _campbell(self):
        self._publish("campbell", "speed", campbell_result)

    @param.depends(
        "store.state.analysis.tab",
        "store.state.case.harmonic",
        "store.state.case.n_modes",
        "store.state.case.dof",
        "store.state.case.coupling",
        "store.state.case.models",
        watch=True,
        on_init=True,
    )
    def _speed_map(self):
        before = self._made.get("speed_map")
        if self._publish("speed_map", "speed", speed_map_result) and not self.store.closed:
            if before is not None:
                self._prefetch_speed_map(before[0].base, self._made["speed_map"][0].base)

    #: The prefetch thread last started (tests join it).
    prefetch_thread: threading.Thread | None = None

    def _prefetch_speed_map(self, old: Snapshot, new: Snapshot) -> None:
        """After a step of the N slider on the speed tab, the speed map of the next count in
        the same direction, computed ahead on a thread of its own (served pages only).

        A new N is a new speed map (the tire synthesised at 21 speeds: 40-300 ms by harmonic
        and N), and the slider moves a step at a time: the next step then finds its map in
        the cache, or computed in part (a session asking for it waits for this thread
        instead of computing it a second time beside it). A jump to a far count, a change
        of harmonic or of anything else computes nothing ahead; the thread does nothing
        once the session has moved on.
        """
        same = (old.harmonic, old.coupling, old.models) == (new.harmonic, new.coupling, new.models)
        if not self.store.threaded or not same or old.n_modes == new.n_modes:
            return
        counts = list(self.state.case.param.n_modes.objects)
        if old.n_modes not in counts or new.n_modes not in counts:
            return
        i, step = counts.index(new.n_modes), 1 if new.n_modes > old.n_modes else -1
        if not 0 <= i + step < len(counts):
            return
        n = counts[i + step]

        def work() -> None:
            c = self.state.case
            if self.store.closed or self.state.analysis.tab != "speed" or c.n_modes != new.n_modes:
                return
            try:
                ac.speed_map(new.harmonic, n, new.coupling, new.models)
            except Exception:  # optional work: the session computes it itself when asked
                log.exception("computing the speed map of N = %d ahead failed", n)

        t = threading.Thread(target=work, name="fbs-prefetch", daemon=True)
        self.prefetch_thread = t
        t.start()

    @param.depends("store.state.analysis.pins", watch=True, on_init=True)
    def _sync_pins(self):
        """Build the pins the URL / the state lists (keeping those already built)."""
        with self.store.lock:
            if self.store.closed:
                return
            try:
                wanted = decode_pins(self.state.analysis.pins)
            except FBSError as e:
                self.message = str(e)
                return
            have = {p.settings: p for p in self.pins}
            current = Snapshot.of(self.state)
            self.pins = tuple(have.get(ps) or build_pin(ps, current) for ps in wanted)

    @param.depends(
        "store.state.analysis.tab",
        "store.state.analysis.compare_to",
        "pins",
        "store.band",
        "store.state.case.harmonic",
        "store.state.case.n_modes",
        "store.state.case.dof",
        "store.state.case.coupling",
        "store.state.case.models",
        "store.state.noise.percentile",
        "store.state.truncation.map_mode",
        watch=True,
        on_init=True,
    )
    def _compare(self):
        self._publish(
            "compare",
            "compare",
            lambda s: compare_result(s.base, self.pins, self.state.analysis.compare_to),
        )

    @param.depends(
        "pins",
        "store.state.case.harmonic",
        "store.state.case.n_modes",
        "store.state.case.dof",
        "store.state.case.coupling",
        "store.state.case.models",
        watch=True,
        on_init=True,
    )
    def _pinned(self):
        """Each pin against the current state, published in the session's store (where the
        report finds every published result), whichever tab is shown."""
        with self.store.lock:
            if self.store.closed:
                return
            s = Snapshot.of(self.state)
            out = tuple(r for r in (pin_result(s, p) for p in self.pins) if r is not None)
            if out or self.store.pinned:
                self.store.pinned = out

    def pin(self, name: str) -> None:
        """Pin the current state as ``name`` (up to four; a taken name is refused)."""
        with self.store.lock:
            try:
                name = check_pin_name(name)
                ps = pin_settings(name, Snapshot.of(self.state))
                add_pin(self.pins, pin_state(name, {}))  # the core's rules: unique, at most 4
            except FBSError as e:
                self.message = str(e)
                return
            self.message = ""
            self.state.analysis.pins = encode_pins([p.settings for p in self.pins] + [ps])

    def unpin(self, name: str) -> None:
        """Remove the pin named ``name``."""
        with self.store.lock:
            try:
                remove_pin([p.data or pin_state(p.name, {}) for p in self.pins], name)
            except FBSError as e:
                self.message = str(e)
                return
            self.message = ""
            a = self.state.analysis
            a.pins = encode_pins([p.settings for p in self.pins if p.name != name])
            if a.compare_to == name:
                a.compare_to = ""

    # -- the modes near the peaks: after the labels, off the session's threads ----------------
    def _find_modes(self, r: Result) -> None:
        peaks = r.draw["peaks"]
        s: Snapshot = r.draw["snapshot"]

        def work():
            labels = []
            for p in peaks:
                if self.phase is not r or self.store.closed:
                    return  # superseded: a newer phase result asks for its own
                modes = ac.peak_modes(p["freq"], p["speed"], s.coupling, s.models)
                labels.append(peak_text(p, modes))
            with self.store.lock:
                if self.phase is r and not self.store.closed:
                    self.peak_modes = (r, tuple(labels))

        later = self.store.threaded
        if later:  # a thread of its own at a lower priority: the plots win the cores
            background.start(work, "fbs-peak-modes")
        else:
            work()

    # -- actions from the views ----------------------------------------------------------------
    def pick_point(self, speed_kmh: float | None, freq: float | None) -> None:
        """Pick a speed (km/h) and a frequency (Hz) for the other views (None: unchanged)."""
        a = self.state.analysis
        upd = {}
        if speed_kmh is not None and np.isfinite(speed_kmh):
            upd["picked_speed"] = float(np.clip(round(speed_kmh, 2), 0.0, 300.0))
        if freq is not None and np.isfinite(freq):
            upd["picked_freq"] = float(np.clip(round(freq, 2), 0.0, 1000.0))
        if upd:
            a.param.update(**upd)

    def pick_campbell(self, speed_kmh: float, freq: float, tol: float = 0.03) -> None:
        """A click in the Campbell diagram: pick the point; if it lies on the order line of
        a harmonic case inside that case's speed range (within ``tol`` relative frequency),
        also choose that harmonic (its bushing response is the other views' subject)."""
        self.pick_point(speed_kmh, freq)
        r = self.campbell
        if r is None:
            return
        k = nearest_order_line(r.draw["wavelength"], r.draw["speed_range"], speed_kmh, freq, tol)
        if k is not None:
            self.state.case.harmonic = k


# -- helpers ----------------------------------------------------------------------------------
def _same(a: tuple, b: tuple) -> bool:
    """Inputs equal: snapshots and names by value, anything else (pins, bands) by identity."""
    if len(a) != len(b):
        return False
    for x, y in zip(a, b, strict=True):
        if x is y:
            continue
        if isinstance(x, tuple) and isinstance(y, tuple):
            if len(x) != len(y) or any(p is not q for p, q in zip(x, y, strict=True)):
                return False
        elif not (isinstance(x, AnalysisSnapshot | str) and type(x) is type(y) and x == y):
            return False
    return True


def nearest_order_line(wavelength, speed_range, speed_kmh: float, freq: float, tol: float):
    """The harmonic case whose line ``f = v / lambda`` passes within ``tol`` (relative) of
    ``(speed_kmh, freq)`` inside its speed range, or None."""
    best, err = None, tol
    for k, (lam, (lo, hi)) in enumerate(zip(wavelength, speed_range, strict=True), start=1):
        if not lo - 1e-9 <= speed_kmh <= hi + 1e-9:
            continue
        f_line = speed_kmh / 3.6 / lam
        e = abs(freq - f_line) / f_line
        if e <= err:
            best, err = k, e
    return best


def pick_result(s: AnalysisSnapshot) -> Result:
    return Result(
        columns={"speed_kmh": np.array([s.picked_speed]), "freq_Hz": np.array([s.picked_freq])},
        meta={"view": "picked point (0: none)"},
        filename="picked_point.csv",
        draw={
            "speed": s.picked_speed if s.picked_speed > 0 else None,
            "freq": s.picked_freq if s.picked_freq > 0 else None,
        },
    )


def _label(dof: str) -> str:
    return dof.replace(":", "_")


def contributions_result(s: AnalysisSnapshot) -> Result:
    b = s.base
    c = ac.contributions(b.harmonic, b.n_modes, b.coupling, b.models)
    out = f"bushing:{b.dof}"
    terms = c.at(out).data[:, 0, :]  # (n_f, n_j)
    total = terms.sum(-1)
    shares = c.shares(out)
    cols: dict[str, np.ndarray] = {"freq_Hz": np.asarray(c.freq, float)}
    cols["total"] = total
    cols["total_dB"] = magnitude_db(total)
    for k, j in enumerate(c.interface):
        cols[f"{_label(j)}"] = terms[:, k]
        cols[f"{_label(j)}_dB"] = magnitude_db(terms[:, k])
        cols[f"{_label(j)}_share"] = shares[:, k]
    i_peak = int(np.argmax(np.abs(total)))
    k_dom = int(np.argmax(np.abs(terms[i_peak])))
    return Result(
        columns=cols,
        meta={
            "view": "contributions of the interface forces to the bushing response (eq. 4.1)",
            "harmonic": b.harmonic,
            "N (retained tire modes)": b.n_modes,
            "response DOF": out,
            "coupling": b.coupling,
            "terms": "term hub:d = Y_ej^E[bushing, spindle:d] g_d; the terms add up to total",
            "share": "Re(term conj(total)) / |total|^2 (shares add up to 1 at every line)",
            "unit": compute.level_unit(b.dof),
            "models": b.models.describe(),
        },
        filename=f"contributions_h{b.harmonic}_N{b.n_modes}_{b.dof}_{b.coupling}.csv",
        caption=(
            f"**Harmonic {b.harmonic}** &middot; {out} &middot; N = {b.n_modes} &middot; "
            f"{b.coupling} &middot; at the highest level ({c.freq[i_peak]:.1f} Hz) the largest "
            f"term is **{c.interface[k_dom]}**"
        ),
        draw={
            "interface": tuple(c.interface),
            "mode": s.contrib_mode,
            "dof": b.dof,
        },
    )


def peak_text(p: dict, modes=()) -> str:
    """A peak's label: frequency, level, speed, and the coupled modes nearby if known."""
    text = f"{p['freq']:.1f} Hz, {p['level']:.1f} dB"
    if p.get("speed") is not None:
        text += f" @ {p['speed']:.0f} km/h"
    if modes:
        shown = (f"{m.freq:.1f} Hz ({percent(m.damping):.1f} %)" for m in modes)
        text += "\nmodes " + ", ".join(shown)
    return text


def phase_result(s: AnalysisSnapshot) -> Result:
    b = s.base
    frfs = ac.phase_frfs(b.harmonic, b.n_modes, b.dof, b.coupling, s.frf, b.spindle_input, b.models)
    freq = np.asarray(next(iter(frfs.values())).freq, float)
    cols: dict[str, np.ndarray] = {"freq_Hz": freq}
    curves = {}
    for name, frf in frfs.items():
        h = frf.data[:, 0, 0]
        key = name.replace(" ", "_")
        lv, ph = magnitude_db(h), phase_deg(h)
        cols[f"{key}"] = h
        cols[f"{key}_dB"] = lv
        cols[f"{key}_phase_deg"] = ph
        curves[name] = {"level": lv, "phase": ph, "re": h.real, "im": h.imag}
    main = "chassis" if s.frf == "chassis" else "N modes"
    frf = frfs[main]
    plist = ac.peaks(frf, b.harmonic)
    peaks = [
        {"freq": p.freq, "level": p.level_db, "speed": p.speed_kmh, "line": p.line} for p in plist
    ]
    cursors = None
    meta_c = {}
    if s.cursor1 > 0 and s.cursor2 > 0:
        try:
            d = delta_cursor(frf, s.cursor1, s.cursor2)
            cursors = {"f1": d.f1, "f2": d.f2, "l1": d.level1, "l2": d.level2}
            meta_c = {
                "cursors": f"f1 = {d.f1:g} Hz ({d.level1:.2f} dB), f2 = {d.f2:g} Hz "
                f"({d.level2:.2f} dB): df = {d.df:g} Hz, dL = {d.d_db:.2f} dB, "
                f"f2/f1 = {d.ratio:.4g} ({main})"
            }
        except FBSError as e:
            meta_c = {"cursors": str(e)}
    what = {
        "coupled": f"coupled bushing response v_e* at bushing:{b.dof} (eq. 4.1)",
        "tire": f"tire free hub velocity Y_ja F_a at hub:{b.dof}",
        "chassis": f"chassis mobility spindle:{b.spindle_input} -> bushing:{b.dof}",
    }[s.frf]
    if s.frf == "chassis":
        unit = chassis_label(b.dof, b.spindle_input)
    else:
        unit = f"Level ({compute.level_unit(b.dof)})"
    meta = {
        "view": f"phase view ({s.phase_mode}): {what}",
        "harmonic": b.harmonic,
        "N (retained tire modes)": b.n_modes,
        "response DOF": f"bushing:{b.dof}",
        "coupling": b.coupling,
        "phase": "degrees, unwrapped along frequency",
        "unit": unit,
        **{
            f"peak {i + 1}": peak_text(p).replace("\n", "; ")
            for i, p in enumerate(sorted(peaks, key=lambda p: p["freq"]))
        },
        **meta_c,
        "models": b.models.describe(),
    }
    return Result(
        columns=cols,
        meta=meta,
        filename=f"phase_{s.frf}_h{b.harmonic}_N{b.n_modes}_{b.dof}_{b.coupling}.csv",
        caption=(
            f"**{what}** &middot; harmonic {b.harmonic} &middot; N = {b.n_modes}"
            + (f" &middot; {meta_c['cursors']}" if meta_c else "")
        ),
        draw={
            "curves": curves,
            "freq": freq,
            "mode": s.phase_mode,
            "log": s.log_freq,
            "peaks": peaks,
            "labels": tuple(peak_text(p) for p in peaks),
            "cursors": cursors,
            "c1": s.cursor1,
            "c2": s.cursor2,
            "modes_wanted": s.frf == "coupled" and bool(peaks),
            "snapshot": b,
            "y_label": unit,
        },
    )


DIRECTION_CODE = {"forward": 1.0, "backward": -1.0, "standing": 0.0}


def campbell_result(s: AnalysisSnapshot) -> Result:
    b = s.base
    cb = ac.campbell(b.models)
    import fbs_core

    hs = [fbs_core.harmonic(int(k)) for k in cb.harmonic]
    cols: dict[str, np.ndarray] = {"speed_kmh": np.asarray(cb.speeds, float)}
    for j, br in enumerate(cb.branch):
        cols[f"branch{int(br)}_{cb.direction[j]}_Hz"] = cb.freq[:, j]
    for k, hk in enumerate(cb.harmonic):
        cols[f"order_line_h{int(hk)}_Hz"] = cb.lines[:, k]
    branches = {}
    for d in ("forward", "backward", "standing"):
        idx = [j for j in range(cb.branch.size) if cb.direction[j] == d]
        branches[d] = {
            "xs": [np.asarray(cb.speeds, float)] * len(idx),
            "ys": [cb.freq[:, j] for j in idx],
            "branch": [int(cb.branch[j]) for j in idx],
        }
    return Result(
        columns=cols,
        meta={
            "view": "Campbell diagram: tire eigenfrequencies vs speed, order lines f = v / lambda",
            "direction": f"{cb.method} criterion (fbs_core.analysis.campbell)",
            "branches": f"{cb.branch.size} vibration modes below 450 Hz somewhere in the range",
            "wavelengths_m": ", ".join(
                f"h{int(k)}: {w:g}" for k, w in zip(cb.harmonic, cb.wavelength, strict=True)
            ),
            "models": b.models.describe(),
        },
        filename="campbell.csv",
        caption=(
            f"{cb.branch.size} tire modes below 450 Hz &middot; forward / backward by the "
            f"{cb.method} of each branch &middot; order lines of the seven cases (solid inside "
            "their speed range) &middot; **click**: pick speed and frequency (on an order line: "
            "that harmonic)"
        ),
        draw={
            "branches": branches,
            "speeds": np.asarray(cb.speeds, float),
            "lines": cb.lines,
            "in_band": cb.in_band,
            "harmonic": [int(k) for k in cb.harmonic],
            "wavelength": [float(w) for w in cb.wavelength],
            "speed_range": [tuple(map(float, h.speed_range)) for h in hs],
            "current": b.harmonic,
        },
    )


def speed_map_result(s: AnalysisSnapshot) -> Result:
    b = s.base
    sm = ac.speed_map(b.harmonic, b.n_modes, b.coupling, b.models)
    out = f"bushing:{b.dof}"
    lv = sm.level_db(out)  # (n_v, n_f)
    vv, ff = np.meshgrid(sm.speeds, sm.freq, indexing="ij")
    resp = sm.response[:, :, list(sm.outputs).index(out)]
    return Result(
        columns={
            "speed_kmh": vv.ravel(),
            "freq_Hz": ff.ravel(),
            "level_dB": lv.ravel(),
            "response": resp.ravel(),
        },
        meta={
            "view": "bushing level vs speed and frequency (eq. 4.1 at fixed speeds)",
            "harmonic": b.harmonic,
            "wavelength_m": sm.wavelength,
            "N (retained tire modes)": b.n_modes,
            "response DOF": out,
            "coupling": b.coupling,
            "layout": "long: one row per (speed, frequency)",
            "unit": compute.level_unit(b.dof),
            "models": b.models.describe(),
        },
        filename=f"speed_map_h{b.harmonic}_N{b.n_modes}_{b.dof}_{b.coupling}.csv",
        caption=(
            f"**Harmonic {b.harmonic}** (wavelength {sm.wavelength:g} m) &middot; {out} "
            f"&middot; N = {b.n_modes} &middot; dashed: the harmonic line f = v / lambda "
            "&middot; **click**: pick speed and frequency"
        ),
        draw={
            "speeds": np.asarray(sm.speeds, float),
            "freq": np.asarray(sm.freq, float),
            "level": lv,
            "line_freq": np.asarray(sm.line_freq, float),
            "dof": b.dof,
        },
    )
