"""The campaign browser's results: a campaign file's case table and one case's view.

Pure functions of an opened :class:`~fbs_core.campaign.CampaignResult` (no Panel, no
Bokeh), so the browser (:mod:`app.views.campaign`), the session's report and the tests
read the same numbers:

- :func:`case_rows`: the case table, one row per case (harmonic, noise, target,
  frequency dependence, truncation range, tire and chassis variants, coupling, rounds,
  seed, design, status);
- :func:`scatter_case_result`: a scatter case's band at one bushing DOF (reference,
  min/max, percentiles; thesis 5.2);
- :func:`truncation_case_result`: a truncation case's error map (eq. 5.1) with its
  suggested mode counts (table 5.1);
- :func:`variants_case_result`: a variants case's corridor over its nominal response and
  the per-band leaders of its Sobol' indices (docs/corridor.md).

Each view is a :class:`~app.results.Result` whose description carries the case's
provenance (campaign, seeds, case digest, where and with what it ran), the CSV header
included. The numbers are the file's: the band is :meth:`CampaignResult.band` (the stored
blocks joined), the map :meth:`CampaignResult.truncation`, the corridor
:meth:`CampaignResult.variants`; nothing is recomputed.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from fbs_core.campaign import CampaignError
from fbs_core.vocabulary import magnitude_db, percent

from .base import Result

__all__ = [
    "case_rows",
    "scatter_case_result",
    "truncation_case_result",
    "variants_case_result",
]


def _truncation_label(s: dict) -> str:
    n = s.get("n_modes")
    return f"N = {n[0]}..{n[-1]} ({len(n)})" if isinstance(n, list) and n else ""


def case_rows(result) -> dict[str, list]:
    """The case table of a :class:`~fbs_core.campaign.CampaignResult`, one row per case.

    Raises
    ------
    CampaignError
        For a case whose settings cannot be shown (naming the file and the case).
    """
    cols: dict[str, list] = {
        k: []
        for k in (
            "case",
            "kind",
            "harmonic",
            "noise_pct",
            "target",
            "freq_dependent",
            "truncation",
            "tire",
            "chassis",
            "coupling",
            "rounds",
            "seed",
            "design",
            "status",
        )
    }
    for c in result.cases:
        try:
            row = _case_row(c)
        except (KeyError, ValueError, TypeError, IndexError) as exc:
            raise CampaignError(
                f"{result.path}: case {c.name!r} cannot be shown ({type(exc).__name__}: {exc})"
            ) from None
        for k, v in row.items():
            cols[k].append(v)
    return cols


def _parameters_of(s: dict, model: str) -> str:
    """The varied parameters of a variants case that belong to ``model`` (comma list), and
    "base changed" when the case replaces the reference's base parameters."""
    from fbs_core.variants import PARAMETERS

    names = [n for n in s.get("parameters", ()) if n in PARAMETERS and PARAMETERS[n].model == model]
    text = ", ".join(names)
    if s.get(model):
        text = f"{text}; base changed" if text else "base changed"
    return text


def _variants_row(c) -> dict[str, Any]:
    """A variants case in the table's columns: its harmonics, the varied tire and
    chassis parameters, its design and size."""
    s = c.settings
    n_variants = c.n_lines - 1 if c.n_lines else 0  # the nominal models are one unit
    return {
        "case": c.name,
        "kind": c.kind,
        "harmonic": ", ".join(str(int(h)) for h in s["harmonics"]),
        "noise_pct": None,
        "target": "",
        "freq_dependent": None,
        "truncation": "",
        "tire": _parameters_of(s, "tire"),
        "chassis": _parameters_of(s, "chassis"),
        "coupling": str(s.get("coupling", "")),
        "rounds": None,
        "seed": str(s.get("seed", "")),
        "design": f"{s['design']} n={s['n']} ({n_variants} variants)",
        "status": "complete"
        if c.complete
        else f"partial ({c.lines_done}/{c.n_lines} variants and nominal)",
    }


def _case_row(c) -> dict[str, Any]:
    s = c.settings
    if c.kind == "variants":
        return _variants_row(c)
    band = c.kind == "scatter"
    return {
        "case": c.name,
        "kind": c.kind,
        "harmonic": int(s.get("harmonic", 0)),
        "noise_pct": round(percent(float(s["noise"])), 6) if band else None,
        "target": str(s["target"]) if band else "",
        "freq_dependent": bool(s["frequency_dependent"]) if band else None,
        "truncation": "" if band else _truncation_label(s),
        "tire": str(s.get("tire", "")),
        "chassis": str(s.get("chassis", "")),
        "coupling": str(s.get("coupling", "")),
        "rounds": int(s["rounds"]) if band else None,
        "seed": str(s.get("seed", "")) if band else "",
        "design": "",
        "status": "complete" if c.complete else f"partial ({c.lines_done}/{c.n_lines} lines)",
    }


def _provenance(result, name: str) -> dict[str, Any]:
    """Where a case comes from: file, campaign, seeds, digest, the runs that made it."""
    c = result.case(name)
    a = result.attrs
    meta: dict[str, Any] = {
        "campaign file": result.path.name,
        "campaign": a.get("campaign_name", ""),
        "campaign seed": a.get("campaign_seed", ""),
        "seeds": a.get("seeds", ""),
        "case": name,
        "case digest": result.case_attrs(name).get("digest", ""),
    }
    meta.update({f"case {k}": v for k, v in c.settings.items() if k != "kind"})
    if result.runs:
        r = result.runs[-1]
        versions = r.get("versions") or {}
        meta["last run"] = (
            f"{r.get('started')} {r.get('status')}, {r.get('workers')} worker(s) at "
            f"{r.get('scheduler')}"
        )
        if isinstance(versions, dict):
            meta["versions"] = ", ".join(f"{k} {v}" for k, v in sorted(versions.items()))
    return meta


def scatter_case_result(result, name: str, dof: str) -> Result:
    """The band of a scatter case at ``bushing:dof``, as stored (magnitudes and dB)."""
    band = result.band(name)
    j = band.dofs.index(f"bushing:{dof}")
    ref = np.abs(band.reference[:, j])
    cols = {
        "freq_Hz": np.asarray(band.freq),
        "reference": ref,
        "minimum": np.asarray(band.minimum[:, j]),
        "maximum": np.asarray(band.maximum[:, j]),
    }
    for k, q in enumerate(band.q):
        cols[f"p{q:g}"] = np.asarray(band.percentiles[k, :, j])
    db = {f"{k}_dB": magnitude_db(v) for k, v in cols.items() if k != "freq_Hz"}
    meta = {
        "view": "campaign scatter band (thesis 5.2)",
        "response DOF": f"bushing:{dof}",
        "columns": "magnitudes |v_e| and their levels in dB",
        **_provenance(result, name),
    }
    s = result.case(name).settings
    return Result(
        columns={**cols, **db},
        meta=meta,
        filename=f"{Path(result.path).stem}_{name}_{dof}.csv",
        caption=(
            f"**{name}** &middot; bushing:{dof} &middot; noise {percent(s['noise']):g} % in "
            f"{s['target']} &middot; {s['rounds']:,} rounds &middot; seed {s['seed']}"
        ),
        draw={"kind": "scatter", "dof": dof, "q": tuple(float(q) for q in band.q)},
    )


def variants_case_result(result, name: str, dof: str, harmonic: int | None = None) -> Result:
    """The corridor of a variants case at ``bushing:dof`` over its nominal response, and the
    per-band leaders of its Sobol' indices (a Saltelli design only; see
    docs/corridor.md).

    The numbers are those of :meth:`CampaignResult.variants`: the study as stored, its
    corridor at the case's percentiles and its sensitivity (:meth:`VariantStudy.corridor`,
    :meth:`VariantStudy.sensitivity`); ``harmonic`` None: the case's first harmonic.
    """
    study = result.variants(name)
    s = result.case(name).settings
    harmonics = [int(h) for h in s["harmonics"]]
    h = harmonics[0] if harmonic is None else int(harmonic)
    if h not in harmonics:
        raise CampaignError(
            f"case {name} has no harmonic {h}; computed: {', '.join(map(str, harmonics))}"
        )
    pct = tuple(float(q) for q in s["percentiles"])
    c = study.corridor(h, percentiles=pct)
    label = f"bushing:{dof}"
    j = c.dof_index(label)
    cols: dict[str, np.ndarray] = {
        "freq_Hz": np.asarray(c.freq),
        "nominal": np.abs(c.nominal[:, j]),
        "minimum": np.asarray(c.minimum[:, j]),
        "maximum": np.asarray(c.maximum[:, j]),
    }
    for k, q in enumerate(c.q):
        cols[f"p{q:g}"] = np.asarray(c.percentiles[k, :, j])
    db = {f"{k}_dB": magnitude_db(v) for k, v in cols.items() if k != "freq_Hz"}
    leaders: list[dict[str, Any]] = []
    if s["design"] == "saltelli":
        leaders = study.sensitivity(h).leaders(label)
        ranking = "; ".join(
            f"{r['band_low']:.0f}-{r['band_high']:.0f} Hz: {r['parameter']} "
            f"(S_T {r['total']:.2f}, then {r['second'] or '-'}, {r['std_db']:.1f} dB)"
            for r in leaders
        )
    else:
        ranking = f"none ({s['design']} design: Sobol' indices need a Saltelli design)"
    params = ", ".join(s["parameters"])
    pct_text = ", ".join(f"{q:g}" for q in c.q)
    meta = {
        "view": "campaign corridor of systematic errors (docs/corridor.md)",
        "response DOF": label,
        "harmonic": h,
        "parameters": params,
        "design": f"{s['design']} n={s['n']} ({c.n_variants} variants), seed {s['seed']}",
        "percentiles": pct_text,
        "columns": "magnitudes |v_e| over the variants (and the nominal models) and dB",
        "sensitivity leaders (total Sobol' index per band)": ranking,
        **_provenance(result, name),
    }
    return Result(
        columns={**cols, **db},
        meta=meta,
        filename=f"{Path(result.path).stem}_{name}_h{h}_{dof}.csv",
        caption=(
            f"**{name}** &middot; {result.path.name} &middot; harmonic {h} &middot; "
            f"{label} &middot; {c.n_variants} variants of {params} &middot; "
            f"percentiles {pct_text} %"
        ),
        draw={
            "kind": "variants",
            "dof": dof,
            "q": tuple(float(q) for q in c.q),
            "leaders": leaders,
        },
        core={"corridor": c},
    )


def truncation_case_result(result, name: str, dof: str | None) -> Result:
    """The error map of a truncation case (``dof`` None: max over the DOFs) and its
    suggested mode counts, as stored."""
    t = result.truncation(name)
    if t.error is None:
        raise CampaignError(f"case {name} was stored without its error map ([outputs])")
    if dof is None:
        err = np.max(t.error, axis=2)
        what = "max over DOFs"
    else:
        err = t.error[:, :, t.dofs.index(f"bushing:{dof}")]
        what = f"bushing:{dof}"
    nn, ff = np.meshgrid(t.n_modes, t.centres, indexing="ij")
    sugg = {}
    if t.suggested is not None:
        for i, th in enumerate(t.thresholds):
            for k, fm in enumerate(t.f_max):
                sugg[f"{percent(th):g} % up to {fm:g} Hz"] = int(t.suggested[i, k])
    meta = {
        "view": "campaign truncation error map (thesis eq. 5.1)",
        "response DOF": what,
        "layout": "long: one row per (N, centre freq)",
        "suggested N (max over DOFs)": "; ".join(f"{k}: {v}" for k, v in sugg.items()),
        **_provenance(result, name),
    }
    return Result(
        columns={
            "n_modes": nn.ravel(),
            "centre_freq_Hz": ff.ravel(),
            "error_pct": percent(err.ravel()),
        },
        meta=meta,
        filename=f"{Path(result.path).stem}_{name}_{dof or 'maxdof'}.csv",
        caption=f"**{name}** &middot; {what}",
        draw={
            "kind": "truncation",
            "error_pct": percent(err),
            "n_modes": np.asarray(t.n_modes),
            "centres": np.asarray(t.centres),
            "suggested": sugg,
        },
    )
