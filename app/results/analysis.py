"""The results of the Analysis card, each a pure function of one snapshot.

Contributions of the interface forces (eq. 4.1 term by term), the phase view and its peaks
(with the coupled modes nearby, computed in the background), the Campbell diagram, the
bushing level over speed and frequency, and the picked point. The coupled response in
the contributions and the phase view is the coupled-response view's own
(:func:`app.results.main.response_result`, residual compensation included).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence

import numpy as np

import fbs_core
from fbs_core import FRF
from fbs_core.analysis import delta_cursor, phase_deg
from fbs_core.errors import FBSError
from fbs_core.vocabulary import magnitude_db, percent

from .. import compute
from . import analysis_compute as ac
from .base import Result, Snapshot, csv_name
from .main import NOT_COMPENSATED, chassis_label, res_part, residual_meta, response_result

__all__ = [
    "campbell_result",
    "contributions_result",
    "nearest_order_line",
    "peak_modes_result",
    "peak_modes_work",
    "peak_text",
    "phase_result",
    "pick_result",
    "speed_map_ahead",
    "speed_map_result",
]


def pick_result(s: Snapshot) -> Result:
    speed = f"{s.picked_speed:g} km/h" if s.picked_speed > 0 else "none"
    freq = f"{s.picked_freq:g} Hz" if s.picked_freq > 0 else "none"
    return Result(
        columns={"speed_kmh": np.array([s.picked_speed]), "freq_Hz": np.array([s.picked_freq])},
        meta={"view": "picked point (0: none)", "picked speed": speed, "picked frequency": freq},
        filename="picked_point.csv",
        draw={
            "speed": s.picked_speed if s.picked_speed > 0 else None,
            "freq": s.picked_freq if s.picked_freq > 0 else None,
        },
    )


def _label(dof: str) -> str:
    return dof.replace(":", "_")


CONTRIBUTION_MODES = {
    "lines": "lines: the level of each term and of the total",
    "stacked": "stacked: each term's share of the total",
}


def contributions_result(s: Snapshot) -> Result:
    c = ac.contributions(s.harmonic, s.n_modes, s.coupling, s.models, s.residual)
    out = f"bushing:{s.dof}"
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
    res = " + residual" if s.residual else ""
    return Result(
        columns=cols,
        meta={
            "view": "contributions of the interface forces to the bushing response (eq. 4.1)",
            "harmonic": s.harmonic,
            "N (retained tire modes)": s.n_modes,
            "residual compensation": residual_meta(s.residual),
            "response DOF": out,
            "coupling": s.coupling,
            "terms": "term hub:d = Y_ej^E[bushing, spindle:d] g_d; the terms add up to total",
            "share": "Re(term conj(total)) / |total|^2 (shares add up to 1 at every line)",
            "shown as": CONTRIBUTION_MODES[s.contrib_mode],
            "unit": compute.level_unit(s.dof),
            "models": s.models.describe(),
        },
        filename=csv_name(
            s, "contributions", f"h{s.harmonic}", f"N{s.n_modes}", res_part(s), s.dof, s.coupling
        ),
        caption=(
            f"**Harmonic {s.harmonic}** &middot; {out} &middot; N = {s.n_modes}{res} &middot; "
            f"{s.coupling} &middot; at the highest level ({c.freq[i_peak]:.1f} Hz) the largest "
            f"term is **{c.interface[k_dom]}**"
        ),
        draw={"interface": tuple(c.interface), "mode": s.contrib_mode, "dof": s.dof},
        core={"contributions": c},
    )


def peak_text(p: dict, modes: Sequence = ()) -> str:
    """A peak's label: frequency, level, speed, and the coupled modes nearby if known."""
    text = f"{p['freq']:.1f} Hz, {p['level']:.1f} dB"
    if p.get("speed") is not None:
        text += f" @ {p['speed']:.0f} km/h"
    if modes:
        shown = (f"{m.freq:.1f} Hz ({percent(m.damping):.1f} %)" for m in modes)
        text += "\nmodes " + ", ".join(shown)
    return text


def _phase_frfs(s: Snapshot) -> dict[str, FRF]:
    """The FRFs of the phase view: ``{"all modes", "N modes"}`` of the coupled response
    (the coupled-response view's own) or of the tire's free hub velocity, ``{"chassis"}``
    for the chassis mobility."""
    if s.frf == "coupled":
        core = response_result(s).core
        return {"all modes": core["reference"], "N modes": core["truncated"]}
    return ac.uncoupled_frfs(s.harmonic, s.n_modes, s.dof, s.frf, s.spindle_input, s.models)


def _peaks(s: Snapshot, frfs: dict[str, FRF]) -> list[dict]:
    frf = frfs["chassis" if s.frf == "chassis" else "N modes"]
    return [
        {"freq": p.freq, "level": p.level_db, "speed": p.speed_kmh, "line": p.line}
        for p in ac.peaks(frf, s.harmonic)
    ]


PHASE_WHAT = {
    "coupled": "coupled bushing response v_e* at bushing:{dof} (eq. 4.1)",
    "tire": "tire free hub velocity Y_ja F_a at hub:{dof}",
    "chassis": "chassis mobility spindle:{spindle} -> bushing:{dof}",
}


def _case_meta(s: Snapshot) -> dict:
    """The case a phase-view result is of (CSV header lines)."""
    return {
        "harmonic": s.harmonic,
        "N (retained tire modes)": s.n_modes,
        "response DOF": f"bushing:{s.dof}",
        "coupling": s.coupling,
        "residual compensation": (
            residual_meta(s.residual) if s.frf == "coupled" else NOT_COMPENSATED
        ),
    }


def phase_result(s: Snapshot) -> Result:
    frfs = _phase_frfs(s)
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
    peaks = _peaks(s, frfs)
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
    what = PHASE_WHAT[s.frf].format(dof=s.dof, spindle=s.spindle_input)
    if s.frf == "chassis":
        unit = chassis_label(s.dof, s.spindle_input)
    else:
        unit = f"Level ({compute.level_unit(s.dof)})"
    res = " + residual" if s.residual and s.frf == "coupled" else ""
    meta = {
        "view": f"phase view ({s.phase_mode}): {what}",
        **_case_meta(s),
        "phase": "degrees, unwrapped along frequency",
        "frequency axis": "logarithmic" if s.log_freq else "linear",
        "unit": unit,
        **{
            f"peak {i + 1}": peak_text(p).replace("\n", "; ")
            for i, p in enumerate(sorted(peaks, key=lambda p: p["freq"]))
        },
        **meta_c,
        "models": s.models.describe(),
    }
    parts = [f"h{s.harmonic}", f"N{s.n_modes}", "res" if res else "", s.dof, s.coupling]
    if s.frf == "chassis":
        parts = [f"h{s.harmonic}", f"in{s.spindle_input}", s.dof]
    return Result(
        columns=cols,
        meta=meta,
        filename=csv_name(s, f"phase_{s.frf}", *parts),
        caption=(
            f"**{what}** &middot; harmonic {s.harmonic} &middot; N = {s.n_modes}{res}"
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
            "y_label": unit,
        },
    )


def _peak_modes(s: Snapshot, peaks: list[dict], known_only: bool) -> list:
    """The coupled modes near each peak (None for a peak whose modes are not known yet
    when ``known_only``); none for the uncoupled FRFs."""
    if s.frf != "coupled":
        return [() for _ in peaks]
    return [
        ac.peak_modes(p["freq"], p["speed"], s.coupling, s.models, known_only=known_only)
        for p in peaks
    ]


def peak_modes_result(s: Snapshot) -> Result:
    """The phase view's peak labels with the coupled modes nearby that are known (the
    others are computed in the background: :func:`peak_modes_work`)."""
    frfs = _phase_frfs(s)
    peaks = _peaks(s, frfs)
    modes = _peak_modes(s, peaks, known_only=True)
    labels = tuple(peak_text(p, m or ()) for p, m in zip(peaks, modes, strict=True))
    waiting = sum(m is None for m in modes)
    return Result(
        columns={
            "freq_Hz_of_peak": np.array([p["freq"] for p in peaks], float),
            "level_dB_of_peak": np.array([p["level"] for p in peaks], float),
        },
        meta={
            "view": "peaks of the phase view and the coupled modes nearby",
            "FRF": PHASE_WHAT[s.frf].format(dof=s.dof, spindle=s.spindle_input),
            **_case_meta(s),
            **{f"peak {i + 1}": t.replace("\n", "; ") for i, t in enumerate(labels)},
            "coupled modes": f"{waiting} peak(s) still being solved" if waiting else "known",
            "models": s.models.describe(),
        },
        filename=csv_name(
            s,
            f"peaks_{s.frf}",
            f"h{s.harmonic}",
            f"N{s.n_modes}",
            res_part(s) if s.frf == "coupled" else "",
            s.dof,
            s.coupling,
        ),
        draw={"labels": labels, "waiting": waiting},
    )


def peak_modes_work(s: Snapshot) -> Callable[[], Iterator[None]] | None:
    """The coupled modes of the peaks whose modes are not known yet, one peak per step
    (an eigenvalue solve of the assembled tire + chassis, 0.3-1 s each); None: none."""
    peaks = _peaks(s, _phase_frfs(s))
    todo = [p for p, m in zip(peaks, _peak_modes(s, peaks, True), strict=True) if m is None]
    if not todo:
        return None

    def work() -> Iterator[None]:
        for p in todo:
            ac.peak_modes(p["freq"], p["speed"], s.coupling, s.models)
            yield

    return work


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


def campbell_result(s: Snapshot) -> Result:
    cb = ac.campbell(s.models)
    hs = [fbs_core.harmonic(int(k)) for k in cb.harmonic]
    cols: dict[str, np.ndarray] = {"speed_kmh": np.asarray(cb.speeds, float)}
    # the modal model's tracked branches carry no direction of travel: they pass between
    # waves at the veerings (docs/modes.md: 1 of 14 follows its wave), so their slope says
    # nothing known about forward or backward; the waves are the Modes tab's diagram
    for j, br in enumerate(cb.branch):
        cols[f"branch{int(br)}_Hz"] = cb.freq[:, j]
    for k, hk in enumerate(cb.harmonic):
        cols[f"order_line_h{int(hk)}_Hz"] = cb.lines[:, k]
    branches = {
        "modes": {
            "xs": [np.asarray(cb.speeds, float)] * cb.branch.size,
            "ys": [cb.freq[:, j] for j in range(cb.branch.size)],
            "branch": [int(b) for b in cb.branch],
        }
    }
    return Result(
        columns=cols,
        meta={
            "view": "Campbell diagram: tire eigenfrequencies vs speed, order lines f = v / lambda",
            "direction of travel": "not shown: the modal model's branches are tracked for "
            "the interpolation and pass between forward and backward waves at the veerings "
            "(docs/modes.md); the Modes tab's Campbell diagram of the belt waves has them",
            "branches": f"{cb.branch.size} vibration modes below 450 Hz somewhere in the range",
            "wavelengths_m": ", ".join(
                f"h{int(k)}: {w:g}" for k, w in zip(cb.harmonic, cb.wavelength, strict=True)
            ),
            "chosen harmonic (thick line)": f"h{s.harmonic}",
            "models": s.models.describe(),
        },
        filename=csv_name(s, "campbell"),
        caption=(
            f"{cb.branch.size} tire modes below 450 Hz (no direction of travel: waves are "
            "in the **Modes** tab) &middot; order lines of the seven cases &middot; "
            "**click**: pick speed and frequency"
        ),
        draw={
            "branches": branches,
            "speeds": np.asarray(cb.speeds, float),
            "lines": cb.lines,
            "in_band": cb.in_band,
            "harmonic": [int(k) for k in cb.harmonic],
            "wavelength": [float(w) for w in cb.wavelength],
            "speed_range": [tuple(map(float, h.speed_range)) for h in hs],
            "current": s.harmonic,
            "report_plot": {
                "kind": "lines",
                "x": np.asarray(cb.speeds, float),
                "groups": {
                    **(
                        {"tire modes (tracked branches)": branches["modes"]["ys"]}
                        if branches["modes"]["ys"]
                        else {}
                    ),
                    "order lines of the other cases": [
                        cb.lines[:, i] for i, k in enumerate(cb.harmonic) if int(k) != s.harmonic
                    ],
                    f"order line of harmonic {s.harmonic}": [
                        cb.lines[:, i] for i, k in enumerate(cb.harmonic) if int(k) == s.harmonic
                    ],
                },
                "muted": "order lines of the other cases",
                "highlight": f"order line of harmonic {s.harmonic}",
                "y_max": 450.0,
                "x_label": "Vehicle speed (km/h)",
                "y_label": "Frequency (Hz)",
            },
        },
    )


def speed_map_result(s: Snapshot) -> Result:
    sm = ac.speed_map(s.harmonic, s.n_modes, s.coupling, s.models)
    out = f"bushing:{s.dof}"
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
            "harmonic": s.harmonic,
            "wavelength_m": sm.wavelength,
            "N (retained tire modes)": s.n_modes,
            "residual compensation": NOT_COMPENSATED,
            "response DOF": out,
            "coupling": s.coupling,
            "layout": "long: one row per (speed, frequency)",
            "unit": compute.level_unit(s.dof),
            "models": s.models.describe(),
        },
        filename=csv_name(s, "speed_map", f"h{s.harmonic}", f"N{s.n_modes}", s.dof, s.coupling),
        caption=(
            f"**Harmonic {s.harmonic}** (wavelength {sm.wavelength:g} m) &middot; {out} "
            f"&middot; N = {s.n_modes} &middot; dashed: the harmonic line f = v / lambda "
            "&middot; **click**: pick speed and frequency"
        ),
        draw={
            "speeds": np.asarray(sm.speeds, float),
            "freq": np.asarray(sm.freq, float),
            "level": lv,
            "line_freq": np.asarray(sm.line_freq, float),
            "dof": s.dof,
            "report_plot": {
                "kind": "image",
                "x": np.asarray(sm.speeds, float),
                "y": np.asarray(sm.freq, float),
                "z": lv,
                "line": (np.asarray(sm.speeds, float), np.asarray(sm.line_freq, float)),
                "x_label": "Vehicle speed (km/h)",
                "y_label": "Frequency (Hz)",
                "z_label": f"Level at {out} ({compute.level_unit(s.dof)})",
            },
        },
    )


def speed_map_ahead(
    old: Snapshot, new: Snapshot, counts: Sequence[int]
) -> Callable[[], object] | None:
    """After a step of the N slider on the speed tab, the speed map of the next count in
    the same direction (``counts``: the slider's steps), computed ahead; None otherwise.

    A new N is a new speed map (the tire synthesised at 21 speeds: 40-300 ms by harmonic
    and N), and the slider moves a step at a time: the next step then finds its map in the
    cache, or computed in part (a session asking for it waits for it instead of computing
    it a second time beside it). A jump to a far count or a change of anything else
    computes nothing ahead.
    """
    same = (old.harmonic, old.coupling, old.models) == (new.harmonic, new.coupling, new.models)
    if not same or old.n_modes == new.n_modes:
        return None
    counts = list(counts)
    if old.n_modes not in counts or new.n_modes not in counts:
        return None
    i, step = counts.index(new.n_modes), 1 if new.n_modes > old.n_modes else -1
    if not 0 <= i + step < len(counts):
        return None
    n = counts[i + step]
    return lambda: ac.speed_map(new.harmonic, n, new.coupling, new.models)
