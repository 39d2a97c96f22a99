"""The main views' results in vehicle scope, each a pure function of one snapshot.

The whole car: the reference vehicle with the session's tire on all four wheels, a harmonic
road on both tracks (the rear wheels a wheelbase later; the right track in phase, in
anti-phase or partially coherent with the left), the response at one of the car's points
(:mod:`app.results.vehicle_compute`, cached calls into :mod:`fbs_core.vehicle`). The same columns
and views as the corner's (:mod:`app.results.main`), with the scope, the wheels driven,
the track relation and the response point in every description; and the contribution of
each wheel's road to the response (:func:`wheels_result`).

A partially coherent road has two uncorrelated track components (in phase and in
anti-phase, docs/vehicle-model.md); its level is ``sqrt(sum_c |v_c|^2)`` and the complex
columns are given per component. The truncation map and the scatter band compare complex
responses: they need a coherent road (a coherence gives the core's message instead).
"""

from __future__ import annotations

import numpy as np

from fbs_core import FRF
from fbs_core import harmonic as _h
from fbs_core.vehicle import WHEELS
from fbs_core.vocabulary import HARMONIC_CASES, fraction, magnitude_db, percent

from .. import compute
from . import vehicle_compute as vc
from .base import Result, Snapshot, csv_name
from .main import map_result, res_part, residual_meta, tire_meta
from .scope import file_parts, tracks_text, vehicle_caption, vehicle_meta, wheels_text

__all__ = ["error_map_result", "response_result", "suggested_result", "wheels_result"]


def _level_and_components(resp, out: str) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The level at ``out`` and its complex value per track component."""
    r = resp.response
    e = list(r.outputs).index(out)
    comps = {c.removeprefix("road_"): r.data[:, e, k] for k, c in enumerate(r.inputs)}
    return resp.level[:, e], comps


def _core_frf(freq, level, comps: dict, out: str) -> FRF:
    """The report's response: the complex value for one track component, the level for
    two (their phases are unrelated); one input ``road``."""
    data = next(iter(comps.values())) if len(comps) == 1 else level.astype(complex)
    return FRF(freq, data[:, None, None], [out], ["road"])


def response_result(s: Snapshot) -> Result:
    """The car's response at the point's DOF with all modes and with N (eq. 4.1, four
    hubs as one interface)."""
    args = (s.harmonic, None, s.coupling, s.point, s.road, s.wheels, s.models)
    ref = vc.response(*args)
    tr = vc.response(*args[:1], s.n_modes, *args[2:], s.residual)
    out = s.output
    lref, cref = _level_and_components(ref, out)
    ltr, ctr = _level_and_components(tr, out)
    freq = np.asarray(ref.freq, float)
    res = " + residual" if s.residual else ""
    cols = {"freq_Hz": freq, "reference_dB": magnitude_db(lref), "truncated_dB": magnitude_db(ltr)}
    for c in cref:
        cols[f"reference_{c}"] = cref[c]
        cols[f"truncated_{c}"] = ctr[c]
    return Result(
        columns=cols,
        meta={
            "view": "coupled response of the car v_e* (thesis eq. 4.1, the four hubs as one "
            "interface)",
            **vehicle_meta(s),
            "harmonic": s.harmonic,
            "N (retained tire modes)": s.n_modes,
            "reference": "all tire modes",
            "residual compensation": residual_meta(s.residual),
            "response DOF": out,
            "coupling": s.coupling,
            "level": "root of the summed squares of the uncorrelated track components "
            "(in_phase, anti_phase); complex columns per component",
            "unit": compute.level_unit(s.dof),
            "models": s.models.describe(),
            **tire_meta(s),
        },
        filename=csv_name(
            s,
            "vehicle_response",
            f"h{s.harmonic}",
            f"N{s.n_modes}",
            res_part(s),
            s.point,
            s.dof,
            s.coupling,
            *file_parts(s),
        ),
        caption=(
            f"**Harmonic {s.harmonic}** &middot; {out} &middot; N = {s.n_modes}{res} &middot; "
            f"{s.coupling} coupling &middot; {vehicle_caption(s)}"
        ),
        draw={"dof": s.dof, "truncated_label": f"N retained modes{res}"},
        core={
            "reference": _core_frf(freq, lref, cref, out),
            "truncated": _core_frf(freq, ltr, ctr, out),
        },
    )


def _map(s: Snapshot, harmonic: int, residual: bool):
    return vc.truncation_map(harmonic, s.coupling, s.point, s.road, s.wheels, s.models, residual)


def _map_ready(s: Snapshot, harmonic: int, residual: bool) -> bool:
    return vc.truncation_map_ready(
        harmonic, s.coupling, s.point, s.road, s.wheels, s.models, residual
    )


def _map_dof(s: Snapshot) -> str | None:
    return s.output if s.map_mode == "selected DOF" else None


def _suggested(s: Snapshot, residual: bool) -> np.ndarray:
    """Suggested N per harmonic from the maps computed so far (NaN: not computed yet)."""
    out = np.full(len(HARMONIC_CASES), np.nan)
    for i, h in enumerate(HARMONIC_CASES):
        if h == s.harmonic or _map_ready(s, h, residual):
            m = _map(s, h, residual)
            out[i] = m.suggest(fraction(s.threshold), s.f_max, _map_dof(s))
    return out


def error_map_result(s: Snapshot) -> Result:
    """The truncation error map of the car (eq. 5.1) and the N it suggests."""
    m = _map(s, s.harmonic, s.residual)
    dof = _map_dof(s)
    err = m.max_error if dof is None else m.dof_error(dof)
    d = {
        "n_modes": np.asarray(m.n_modes),
        "centre_freq": np.asarray(m.centres, float),
        "error_pct": percent(np.asarray(err, float)),
    }
    what = dof or f"max over the 6 DOFs of {s.point}"
    if s.residual:
        what += ", with residuals"
    return map_result(
        s,
        d,
        what=what,
        view="truncation error map of the car (thesis eq. 5.1, figs. 5.3/5.6/5.7)",
        scope_meta=vehicle_meta(s),
        filename=csv_name(
            s,
            "vehicle_truncation_map",
            f"h{s.harmonic}",
            s.point,
            s.dof if dof else "maxdof",
            s.coupling,
            res_part(s),
            *file_parts(s),
        ),
        title=f"Harmonic {s.harmonic}, {what} (vehicle, wheels {wheels_text(s.wheels)}, "
        f"tracks {tracks_text(s)})",
        suggested_n=int(_suggested(s, s.residual)[list(HARMONIC_CASES).index(s.harmonic)]),
        core_map=m,
    )


def suggested_result(s: Snapshot) -> Result:
    """The suggested N of the car per harmonic (table 5.1) from the maps computed so far:
    a harmonic's entry appears once its map is (the shown harmonic's always is)."""
    plain, resid = _suggested(s, False), _suggested(s, True)
    h = np.asarray(HARMONIC_CASES)
    lo = np.array([_h(int(k)).freq_range[0] for k in h])
    hi = np.array([_h(int(k)).freq_range[1] for k in h])
    where = s.output if _map_dof(s) else f"max over the 6 DOFs of {s.point}"
    shown = "with residuals" if s.residual else "plain"
    nan = np.full(h.size, np.nan)
    tab = {"harmonic": h, "f_low": lo, "f_high": hi, "n_modes": plain, "eigenfrequency": nan}
    tab_r = {**tab, "n_modes": resid}
    return Result(
        columns={
            "harmonic": h,
            "f_low_Hz": lo,
            "f_high_Hz": hi,
            "n_modes": plain,
            "n_modes_residual": resid,
        },
        meta={
            "view": "suggested number of modes of the car (thesis table 5.1)",
            **vehicle_meta(s),
            "threshold_pct": s.threshold,
            "f_max_Hz": s.f_max,
            "coupling": s.coupling,
            "response DOF": where,
            "n_modes": "plain truncation to N modes (NaN: that harmonic's map not computed yet)",
            "n_modes_residual": "with residual compensation (NaN: not computed yet)",
            "shown in the error map": shown,
            "models": s.models.describe(),
        },
        filename=csv_name(
            s,
            "vehicle_suggested_modes",
            s.point,
            s.dof if _map_dof(s) else "maxdof",
            s.coupling,
            f"thr{s.threshold:g}",
            f"fmax{s.f_max:g}",
            *file_parts(s),
        ),
        caption=(
            f"Vehicle scope: smallest N from which the error at {where} stays below "
            f"**{s.threshold:g} %** up to **{s.f_max:g} Hz** (the error map: **{shown}**), for "
            "each harmonic whose car map is computed (each costs seconds: visit a harmonic "
            f"to add it) &middot; {vehicle_caption(s)}"
        ),
        draw={"table": tab, "table_residual": tab_r, "residual": s.residual},
        core={},
    )


def wheels_result(s: Snapshot) -> Result:
    """The contribution of each wheel's road to the response at the point (N modes, as
    the coupled-response view's truncated curve): ``by_wheel`` of the core, per track
    component; a wheel's level is the root of its components' summed squares."""
    resp = vc.response(
        s.harmonic, s.n_modes, s.coupling, s.point, s.road, s.wheels, s.models, s.residual
    )
    out = s.output
    level, _ = _level_and_components(resp, out)
    freq = np.asarray(resp.freq, float)
    cols: dict[str, np.ndarray] = {"freq_Hz": freq, "total_dB": magnitude_db(level)}
    e = list(resp.outputs).index(out)
    per = {w: np.zeros(freq.size) for w in WHEELS}
    for comp in resp.components:
        bw = resp.by_wheel(comp)
        for k, w in enumerate(WHEELS):
            v = bw.data[:, e, k]
            cols[f"{w}_{comp.removeprefix('road_')}"] = v
            per[w] = per[w] + np.abs(v) ** 2
    on = [w for w in WHEELS if w in s.wheels]
    for w in on:  # an off wheel contributes exact zeros: no level (20 log10 0), no column
        cols[f"{w}_dB"] = magnitude_db(np.sqrt(per[w]))
    peak = int(np.argmax(level)) if level.size else 0
    top = max(on, key=lambda w: per[w][peak]) if on and level[peak] > 0 else None
    res = " + residual" if s.residual else ""
    return Result(
        columns=cols,
        meta={
            "view": "contribution of each wheel's road to the car's response (eq. 4.1, "
            "fbs_core.vehicle VehicleResponse.by_wheel)",
            **vehicle_meta(s),
            "harmonic": s.harmonic,
            "N (retained tire modes)": s.n_modes,
            "residual compensation": residual_meta(s.residual),
            "response DOF": out,
            "coupling": s.coupling,
            "terms": "<wheel>_<component>: complex contribution of that wheel's road to the "
            "component; the four add up to the response",
            "<wheel>_dB": "level of the wheel's contribution (root of the summed squares of "
            "its components), for the driven wheels only (an off wheel's terms are zero: "
            "no level)",
            "unit": compute.level_unit(s.dof),
            "models": s.models.describe(),
        },
        filename=csv_name(
            s,
            "wheel_contributions",
            f"h{s.harmonic}",
            f"N{s.n_modes}",
            res_part(s),
            s.point,
            s.dof,
            s.coupling,
            *file_parts(s),
        ),
        caption=(
            f"**Harmonic {s.harmonic}** &middot; {out} &middot; N = {s.n_modes}{res} &middot; "
            f"{vehicle_caption(s)}"
            + (
                f" &middot; at the highest level ({freq[peak]:.1f} Hz) the largest "
                f"contribution is the **{top.upper()}** wheel's"
                if top
                else " &middot; no wheel driven"
            )
        ),
        draw={"dof": s.dof, "wheels": tuple(s.wheels)},
        core={"by_wheel": resp},
    )
