"""The results of the main views, each a pure function of one snapshot.

Coupled response (eq. 4.1), truncation error map (eq. 5.1), suggested modes (table 5.1),
eigenfrequency versus N (fig. 5.8), the tire's interpolation quality, the uncoupled
subsystems and the scatter band's curves (5.2). The numbers come from :mod:`app.compute`
(cached calls into the core); here they are put together with their description (CSV
header, file name, caption) from the same snapshot.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from fbs_core import FRF
from fbs_core.units import frf_unit, input_kind, output_kind
from fbs_core.vocabulary import EIGEN_SPEEDS, HARMONIC_CASES, magnitude_db

from .. import compute
from . import analysis_compute as ac
from .base import Result, Snapshot, csv_name
from .scope import file_parts, vehicle_meta

__all__ = [
    "band_result",
    "chassis_label",
    "eigen_result",
    "error_map_result",
    "first_order_result",
    "map_result",
    "residual_meta",
    "residual_work",
    "response_result",
    "suggested_result",
    "tire_meta",
    "tire_quality_result",
    "uncoupled_result",
]

#: The CSV header's word where residual compensation does not act.
NOT_COMPENSATED = "not applied here (plain truncation to N modes; it acts on the coupled response)"


def residual_meta(on: bool) -> str:
    """The CSV header's word on residual compensation."""
    if on:
        return (
            "on: the tire modes left out of N enter with their quasi-static part "
            "(upper residual flexibility, docs/tire-model.md)"
        )
    return "off: plain truncation to N modes"


def res_part(s: Snapshot) -> str:
    """``"res"`` in a file name when residual compensation is on."""
    return "res" if s.residual else ""


def tire_meta(s: Snapshot, harmonics=None) -> dict:
    """The tire's interpolation quality and speed coverage for a CSV header."""
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
        filename=csv_name(s, "tire_interpolation_quality"),
        caption=(
            f"Tire between its {q['n_points']} operating points "
            f"({q['speeds'][0]:g}-{q['speeds'][1]:g} km/h): leave-one-out error per "
            "harmonic band"
        ),
        draw={"quality": q, "warnings": warn},
    )


def response_result(s: Snapshot) -> Result:
    """The coupled bushing response v_e* with all modes and with N (eq. 4.1)."""
    d = compute.mobility_data(s.harmonic, s.n_modes, s.dof, s.coupling, s.models, s.residual)
    res = " + residual" if s.residual else ""
    out = [f"bushing:{s.dof}"]
    truncated = FRF(d["freq"], d["truncated"][:, None, None], out, ["patch"])
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
        filename=csv_name(
            s, "bushing_response", f"h{s.harmonic}", f"N{s.n_modes}", res_part(s), s.dof, s.coupling
        ),
        caption=(
            f"**Harmonic {s.harmonic}** &middot; bushing:{s.dof} &middot; N = {s.n_modes}"
            f"{res} &middot; {s.coupling} coupling"
        ),
        draw={"dof": s.dof, "truncated_label": f"N retained modes{res}"},
        core={
            "reference": FRF(d["freq"], d["reference"][:, None, None], out, ["patch"]),
            "truncated": truncated,
            # the peaks the phase view labels (the report's peak table)
            "peaks": ac.peaks(truncated, s.harmonic),
        },
    )


def _tables(s: Snapshot) -> tuple[dict, dict | None]:
    """The suggested N plain and with residuals (None: that one is not computed yet and
    not needed now: the error map shows the plain one)."""
    args = (s.threshold, s.f_max, s.coupling, s.map_dof, s.models)
    tab = compute.suggested_table(*args)
    ready = s.residual or compute.suggested_table_ready(*args, True)
    return tab, compute.suggested_table(*args, True) if ready else None


def error_map_result(s: Snapshot) -> Result:
    """The truncation error map (eq. 5.1) and the N it suggests."""
    d = compute.error_map_data(s.harmonic, s.coupling, s.map_dof, s.models, s.residual)
    what = f"bushing:{s.dof}" if s.map_dof else "max over 6 DOFs"
    if s.residual:
        what += ", with residuals"
    tab, tab_r = _tables(s)
    shown = tab_r if s.residual else tab
    assert shown is not None  # with residual on, its table is computed (_tables)
    return map_result(
        s,
        d,
        what=what,
        view="truncation error map (thesis eq. 5.1, figs. 5.3/5.6/5.7)",
        filename=csv_name(
            s, "truncation_map", f"h{s.harmonic}", s.map_dof or "maxdof", s.coupling, res_part(s)
        ),
        title=f"Harmonic {s.harmonic}, {what}",
        suggested_n=int(shown["n_modes"][list(shown["harmonic"]).index(s.harmonic)]),
        core_map=compute.error_map(s.harmonic, s.coupling, s.models, s.residual),
    )


def map_result(
    s: Snapshot,
    d: dict,
    *,
    what: str,
    view: str,
    filename: str,
    title: str,
    suggested_n: int,
    core_map: Any,
    scope_meta: dict | None = None,
) -> Result:
    """The Result of a truncation error map (eq. 5.1) ``d`` (``n_modes``, ``centre_freq``,
    ``error_pct``), a corner's or the car's: its CSV in long layout (one row per N and
    centre frequency), its header and what the view draws."""
    nn, ff = np.meshgrid(d["n_modes"], d["centre_freq"], indexing="ij")
    return Result(
        columns={
            "n_modes": nn.ravel(),
            "centre_freq_Hz": ff.ravel(),
            "error_pct": d["error_pct"].ravel(),
        },
        meta={
            "view": view,
            **(scope_meta or {}),
            "harmonic": s.harmonic,
            "coupling": s.coupling,
            "response DOF": what,
            "reference": "all tire modes",
            "residual compensation": residual_meta(s.residual),
            "layout": "long: one row per (N, centre freq)",
            "models": s.models.describe(),
            **tire_meta(s),
        },
        filename=filename,
        draw={
            "map": d,
            "title": title,
            "threshold": s.threshold,
            "f_max": s.f_max,
            "n_modes": s.n_modes,
            "suggested_n": suggested_n,
            "freq": compute.frequencies(s.harmonic),
        },
        core={"map": core_map},
    )


def suggested_result(s: Snapshot) -> Result:
    """The suggested N for every harmonic, plain and with residuals; while the column with
    residuals is being computed (:func:`residual_work`) it is NaN and the caption says so."""
    tab, tab_r = _tables(s)
    pending = tab_r is None
    if tab_r is None:
        nan = np.full(len(tab["harmonic"]), np.nan)
        tab_r = {**tab, "n_modes": nan, "eigenfrequency": nan, "result": None}
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
        filename=csv_name(
            s,
            "suggested_modes",
            s.map_dof or "maxdof",
            s.coupling,
            f"thr{s.threshold:g}",
            f"fmax{s.f_max:g}",
        ),
        caption=(
            f"Smallest N from which the error stays below **{s.threshold:g} %** up "
            f"to **{s.f_max:g} Hz** ({where}), plain and with residual compensation "
            f"(the error map and its dashed line: **{shown}**), and the highest "
            "eigenfrequency among those modes at 80 km/h."
            + (" The column with residuals is being computed ..." if pending else "")
        ),
        draw={"table": tab, "table_residual": tab_r, "residual": s.residual},
        core={"shown": (tab_r if s.residual else tab)["result"]},
    )


def residual_work(s: Snapshot) -> Callable[[], Iterator[None]] | None:
    """The column with residuals of :func:`suggested_result` when it is not computed yet:
    its seven residual error maps one by one, then the table (None: nothing to do)."""
    args = (s.threshold, s.f_max, s.coupling, s.map_dof, s.models)
    if s.residual or compute.suggested_table_ready(*args, True):
        return None

    def work() -> Iterator[None]:
        for h in HARMONIC_CASES:
            compute.error_map(h, s.coupling, s.models, True)
            yield
        compute.suggested_table(*args, True)

    return work


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
        filename=csv_name(s, "eigenfrequency_vs_modes"),
        draw={"curves": d, "n_modes": s.n_modes},
        core={"eigen": d["result"]},
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
            "residual compensation": NOT_COMPENSATED,
            "tire output": f"hub:{s.dof}",
            "chassis": f"spindle:{s.spindle_input} -> bushing:{s.dof}",
            "unit": (
                f"tire_*: {tire_unit} (free hub velocity per metre of road amplitude), "
                f"tire_*_dB: dB re 1 {tire_unit}; chassis: {chassis_unit}, chassis_dB: "
                f"dB re 1 {chassis_unit}"
            ),
            "models": s.models.describe(),
        },
        filename=csv_name(
            s, "uncoupled", f"h{s.harmonic}", f"N{s.n_modes}", s.dof, f"in{s.spindle_input}"
        ),
        draw={
            "dof": s.dof,
            "tire_title": f"Tire: free hub velocity hub:{s.dof} (figs. 4.6-4.7)",
            "chassis_title": f"Chassis: spindle:{s.spindle_input} -> bushing:{s.dof} "
            "(figs. 4.2-4.3)",
            "chassis_label": chassis_label(s.dof, s.spindle_input),
        },
    )


def band_result(s: Snapshot) -> Result | None:
    """The published band's curves at the selected DOF, percentile band and round.

    The header describes the band as it was computed (``band.settings``), whatever the
    controls say now: a band still computing for new settings never relabels old data.
    """
    band = s.band
    if band is None:
        return None
    b = band.settings
    res = band.result
    out = f"{b.point}:{s.dof}" if b.vehicle else f"bushing:{s.dof}"
    d = compute.band_data(res, out, s.percentile)
    k = min(s.single_round, res.rounds - 1)  # the round must exist in this band
    r = compute.single_round_data(res, k, out)
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
            "view": "Monte-Carlo scatter band (thesis 5.2)"
            + (" of the car (noise per wheel and on the body)" if b.vehicle else ""),
            **(vehicle_meta(b) if b.vehicle else {}),
            "harmonic": b.harmonic,
            "N (retained tire modes)": b.n_modes,
            "residual compensation": NOT_COMPENSATED,
            "response DOF": out,
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
        filename=csv_name(
            b,
            "vehicle_scatter_band" if b.vehicle else "scatter_band",
            f"h{b.harmonic}",
            f"N{b.n_modes}",
            *((b.point,) if b.vehicle else ()),
            s.dof,
            b.coupling,
            f"p{b.noise:g}",
            b.target,
            fd,
            f"R{b.rounds}",
            f"seed{b.seed}",
            *(file_parts(b) if b.vehicle else ()),
        ),
        draw={"band": d, "round": r, "dof": s.dof, "seconds": band.seconds},
        core={"band": res},
        snapshot=b.replace(dof=s.dof, percentile=s.percentile, single_round=k),
    )


def first_order_result(s: Snapshot) -> Result | None:
    """The first-order band of the published scatter band's settings (docs/corridor.md
    section 6), at the selected DOF, as the overlay of the scatter band view.

    Made of the band's own settings (harmonic, N, coupling, models, noise level and target:
    the rounds, seed and frequency dependence do not enter a linearisation), so overlay and
    band always describe the same noise. Its edges are ``|v| +- k std`` with ``k`` the
    Gaussian quantile of the central percentile band (90 % -> 1.645), beside the band's
    percentiles.
    """
    band = s.band
    if band is None or s.vehicle:  # the linearisation is the corner's (docs/corridor.md)
        return None
    from scipy.stats import norm

    b = band.settings
    fo = compute.first_order(b.harmonic, b.n_modes, b.coupling, b.noise, b.target, b.models)
    j = fo.dofs.index(f"bushing:{s.dof}")
    k = float(norm.ppf(0.5 + s.percentile / 200))
    low, high = fo.band(k)
    ref = np.abs(fo.reference[:, j])
    lo = (100 - s.percentile) / 2
    cols = {
        "freq_Hz": np.asarray(fo.freq, float),
        "reference_dB": magnitude_db(ref),
        "first_order_low_dB": magnitude_db(low[:, j]),
        "first_order_high_dB": magnitude_db(high[:, j]),
        "std": np.asarray(fo.std[:, j], float),
        "relative_std": np.asarray(fo.relative_std[:, j], float),
        "interface_condition": np.asarray(fo.condition, float),
    }
    return Result(
        columns=cols,
        meta={
            "view": "first-order band beside the Monte-Carlo scatter band (docs/corridor.md 6)",
            "harmonic": b.harmonic,
            "N (retained tire modes)": b.n_modes,
            "residual compensation": NOT_COMPENSATED,
            "response DOF": f"bushing:{s.dof}",
            "coupling": b.coupling,
            "noise_pct": b.noise,
            "noise target": b.target,
            "percentiles": f"{lo:g}-{100 - lo:g}",
            "k (Gaussian quantile)": round(k, 6),
            "first_order_low/high": "|v_e| -+ k std (linearised covariance of eqs. 5.2-5.4; "
            "the lower edge clipped at 0)",
            "std": "standard deviation of |v_e| to first order",
            "relative_std": "std / |v_e|: near 1 the linearisation fails (antiresonances)",
            "unit": compute.level_unit(s.dof),
            "models": b.models.describe(),
        },
        filename=csv_name(
            b,
            "first_order_band",
            f"h{b.harmonic}",
            f"N{b.n_modes}",
            s.dof,
            b.coupling,
            f"p{b.noise:g}",
            b.target,
            f"pct{s.percentile}",
        ),
        caption=(
            f"First-order band &middot; \u00b1{k:.3f} std ({lo:g}-{100 - lo:g} % of a "
            f"Gaussian |v|) &middot; noise {b.noise:g} % in {b.target}"
        ),
        draw={"dof": s.dof, "percentile": s.percentile, "k": k},
        core={"first_order": fo, "band": band.result},
        snapshot=b.replace(dof=s.dof, percentile=s.percentile, first_order=True),
    )
