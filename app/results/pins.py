"""Pinned baselines of the Compare tab: what a pin holds and the comparison.

A pin is the session's snapshot at one moment, named (up to four,
:data:`fbs_core.analysis.MAX_PINS`). In the URL (``pins=``) it travels as the settings that
change its numbers (:class:`~app.state.pins.PinSettings`: the case, residual
compensation included, the noise study, the models); in the session it keeps its whole
:class:`~app.results.base.Snapshot` and its data as a :class:`fbs_core.analysis.PinnedState`
(the coupled response with N and all modes at its DOF, made by the coupled-response view's
own :func:`~app.results.main.response_result`; the scatter band's edges when its band was
computed; its provenance: models, fbs_core version, time). A pin made by a click and one
restored from a link are the same; a pin of uploaded data can only be restored where the
same upload is loaded (its models key is a digest of the bytes).

The comparison (:func:`compare_result`) overlays the current coupled response (the
coupled-response view's) and the pins', gives their difference in dB
(:func:`fbs_core.analysis.db_difference`, current minus pin, only on the same frequency grid:
another harmonic has no difference curve), the band edges of each, and the error map of
the current state minus the chosen pin's (:func:`fbs_core.analysis.
truncation_map_difference`, same harmonic only; each map with its own residual setting) at
the current map DOF. The map's colours span the 95th percentile of the cells that differ
(:func:`difference_scale`): a few cells at low N, where eq. 5.1 errors run to hundreds of
times the response, differ by tens of thousands of percentage points and would set a range
in which every other cell is white; the cells beyond are drawn in the end colours and
counted in the map's title, the colour bar's end labels say ``>=`` / ``<=``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from fbs_core import FRF
from fbs_core.analysis import PinnedState, db_difference, pin_state, truncation_map_difference
from fbs_core.errors import FBSError
from fbs_core.vocabulary import magnitude_db, percent

from .. import compute
from ..datasource import REFERENCE, candidate_models
from ..report.titles import NOISE_WHERE
from ..state.pins import PinSettings, decode_pins
from .base import Band, Result, Snapshot, csv_name
from .main import res_part, response_result

__all__ = [
    "Pin",
    "build_pins",
    "compare_result",
    "difference_scale",
    "pin_settings",
    "pinned_result",
]

#: Share of the differing cells whose colour the difference map's range covers: the rest
#: (the largest differences) are clipped to the end colours and said so.
SCALE_QUANTILE = 0.95
#: Cells whose difference is below this (percentage points) are the same in both maps.
SAME_PP = 1e-9


@dataclass(frozen=True, eq=False)
class Pin:
    """A pinned baseline: its settings (as in the URL), the whole snapshot it describes and
    its data (None, with the reason in ``note``, if its models are not loaded here)."""

    settings: PinSettings
    snapshot: Snapshot | None
    data: PinnedState | None
    note: str = ""

    @property
    def name(self) -> str:
        return self.settings.name


def pin_settings(name: str, s: Snapshot) -> PinSettings:
    """The settings of a pin of snapshot ``s`` (what the URL keeps of it)."""
    return PinSettings(
        name=name,
        harmonic=s.harmonic,
        n_modes=s.n_modes,
        dof=s.dof,
        coupling=s.coupling,
        residual=s.residual,
        noise=s.noise,
        target=s.target,
        frequency_dependent=s.frequency_dependent,
        rounds=s.rounds,
        seed=s.seed,
        percentile=s.percentile,
        models=s.models.key,
    )


def _snapshot_of(ps: PinSettings, current: Snapshot) -> Snapshot | None:
    """The snapshot a pin describes (None: its uploaded models are not in this session)."""
    if ps.models == current.models.key:
        models = current.models
    elif ps.models == REFERENCE.key:
        models = REFERENCE
    else:  # a pin of another candidate of the review: kept while that candidate is loaded
        cands = current.review.candidates
        found = [
            m
            for m in (candidate_models(current.models, c) for c in (cands or ()))
            if m.key == ps.models
        ]
        if not found:
            return None
        models = found[0]
    return current.settings().replace(
        harmonic=ps.harmonic,
        n_modes=ps.n_modes,
        dof=ps.dof,
        coupling=ps.coupling,
        residual=ps.residual,
        noise=ps.noise,
        target=ps.target,
        frequency_dependent=ps.frequency_dependent,
        rounds=ps.rounds,
        seed=ps.seed,
        percentile=ps.percentile,
        models=models,
        scope="corner",  # a pin is of the corner (the thesis' case), whatever the scope
    )


def build_pin(ps: PinSettings, current: Snapshot) -> Pin:
    """The pin of settings ``ps`` with its data (its response: the coupled-response view's
    result of its snapshot; a problem with its settings is its note)."""
    s = _snapshot_of(ps, current)
    if s is None:
        return Pin(ps, None, None, "its uploaded data are not loaded in this session")
    try:
        core = response_result(s).core
    except (FBSError, ValueError) as e:  # settings the models cannot have (a crafted link)
        return Pin(ps, s, None, f"not computed: {e}")
    result: dict[str, Any] = {"response": core["truncated"], "reference": core["reference"]}
    band = compute.cached_band(s.band_key())
    note = ""
    if band is not None:
        b = compute.band_data(band, s.dof, s.percentile)
        for k in ("minimum", "maximum", "pct_low", "pct_high"):
            result[f"band_{k}"] = (("freq",), b[k])
    else:
        note = "no scatter band (not computed for these settings in this server)"
    settings = {
        **dataclasses.asdict(ps),
        "N (retained tire modes)": s.n_modes,
        "response DOF": f"bushing:{s.dof}",
        "models": s.models.describe(),
    }
    data = pin_state(
        ps.name,
        result,
        settings=settings,
        sources={"models": s.models.key, "fbs_core": compute.version()},
    )
    return Pin(ps, s, data, note)


def build_pins(s: Snapshot) -> tuple[Pin, ...]:
    """The pins the URL lists (``s.pin_text``), keeping those already built (``s.pins``).

    Raises
    ------
    FBSError
        For a malformed link (the pins stay as they were).
    """
    wanted = decode_pins(s.pin_text)
    # a pin is kept while its models are loaded (a candidate removed: built again, said)
    have = {
        p.settings: p
        for p in s.pins
        if (p.snapshot is None) == (_snapshot_of(p.settings, s) is None)
    }
    return tuple(have.get(ps) or build_pin(ps, s) for ps in wanted)


def _describe_settings(s: Snapshot | PinSettings) -> str:
    res = " + residual" if s.residual else ""
    return (
        f"h{s.harmonic} N={s.n_modes}{res} bushing:{s.dof} {s.coupling} noise {s.noise:g} % "
        f"in {NOISE_WHERE[s.target]}{' (every line)' if s.frequency_dependent else ''} "
        f"R={s.rounds} "
        f"seed {s.seed}"
    )


def _describe(p: Pin) -> str:
    txt = _describe_settings(p.settings)
    if p.data is not None:
        txt += f"; {p.data.settings.get('models', '')}; pinned {p.data.created}"
    return txt + (f" ({p.note})" if p.note else "")


def _band_edges(data: PinnedState | None) -> tuple[np.ndarray, np.ndarray] | None:
    if data is None or "band_pct_low" not in data.arrays:
        return None
    return data.arrays["band_pct_low"][1], data.arrays["band_pct_high"][1]


def _relabel(resp: FRF, like: FRF) -> FRF:
    """``resp`` with the labels of ``like`` (a pin of another DOF compares level to level)."""
    return FRF(resp.freq, resp.data, like.outputs, like.inputs, resp.quantity)


def difference_scale(diff_pp: np.ndarray) -> tuple[float, int, float]:
    """The colour range of a difference map: ``(limit, n_beyond, largest)``.

    ``limit`` is the :data:`SCALE_QUANTILE` quantile of ``|diff|`` over the cells that differ
    (``|diff| > SAME_PP``; NaN cells ignored), so no single cell sets the range; ``n_beyond``
    counts the cells with ``|diff| > limit`` (drawn in the end colours), ``largest`` is the
    largest ``|diff|``. Maps without differing cells give ``(0, 0, largest)``.
    """
    a = np.abs(np.asarray(diff_pp, float))
    a = a[np.isfinite(a)]
    largest = float(a.max()) if a.size else 0.0
    differ = a[a > SAME_PP]
    if differ.size == 0:
        return 0.0, 0, largest
    limit = float(np.quantile(differ, SCALE_QUANTILE))
    return limit, int(np.count_nonzero(a > limit)), largest


def compare_result(s: Snapshot) -> Result:
    """The Compare tab's result: curves, differences, band edges, difference map."""
    pins, compare_to = s.pins, s.compare_to
    current = response_result(s)
    cur = current.core["truncated"]
    # the corner's band (in vehicle scope the published band is the car's)
    band = s.current_band() if not s.vehicle else None
    corner = compute.cached_band(s.replace(scope="corner").band_key()) if s.vehicle else None
    cur_band = None
    if band is not None or corner is not None:
        band = band or Band(corner, s.settings().replace(scope="corner"), 0.0)
        b = compute.band_data(band.result, s.dof, s.percentile)
        cur_band = (b["pct_low"], b["pct_high"])
    curves = [
        {
            "name": "current",
            "freq": np.asarray(cur.freq, float),
            "level": current.columns["truncated_dB"],
            "diff": np.full(cur.freq.size, np.nan),
            "band": cur_band,
            "note": "",
        }
    ]
    meta: dict[str, Any] = {
        "view": "comparison of pinned states: coupled bushing response v_e* (eq. 4.1)",
        "curve 0": f"current: {_describe_settings(s)}; {s.models.describe()}",
        "diff_dB": "20 log10 |current| - 20 log10 |pin| on the same frequency grid "
        "(fbs_core.analysis.db_difference); NaN: another grid (another harmonic)",
        "band": f"central percentile band edges of |v_e| ({s.percentile} % for the current"
        + ("" if band is not None else ", not computed yet")
        + ")",
    }
    for i, p in enumerate(pins, start=1):
        meta[f"curve {i}"] = f"pin {p.name!r}: {_describe(p)}"
        if p.data is None:
            continue
        resp = p.data.frfs["response"]
        note = ""
        try:
            diff = db_difference(cur, _relabel(resp, cur))
            dd = np.asarray(diff.db[:, 0, 0], float)
        except FBSError as e:
            dd = np.full(resp.freq.size, np.nan)
            note = f"no difference: {e}"
            meta[f"curve {i} difference"] = note
        curves.append(
            {
                "name": p.name,
                "freq": np.asarray(resp.freq, float),
                "level": magnitude_db(resp.data[:, 0, 0]),
                "diff": dd,
                "band": _band_edges(p.data),
                "note": note or p.note,
            }
        )
    # the difference map: current minus the chosen pin, at the current map DOF
    target = next((p for p in pins if p.name == compare_to), pins[0] if pins else None)
    dmap, map_note = None, ""
    if target is not None and target.data is not None and target.snapshot is not None:
        ps = target.snapshot
        try:
            md = truncation_map_difference(
                compute.error_map(s.harmonic, s.coupling, s.models, s.residual),
                compute.error_map(ps.harmonic, ps.coupling, ps.models, ps.residual),
            )
            what = s.map_dof
            err = md.max_diff if what is None else md.diff[:, :, md.dofs.index(f"bushing:{what}")]
            diff_pct = percent(np.asarray(err, float))
            limit, beyond, largest = difference_scale(diff_pct)
            dmap = {
                "n_modes": np.asarray(md.n_modes, int),
                "centres": np.asarray(md.centres, float),
                "diff_pct": diff_pct,
                "pin": target.name,
                "what": f"bushing:{what}" if what else "max over 6 DOFs",
                "scale_pp": limit,
                "beyond": beyond,
                "largest_pp": largest,
            }
        except FBSError as e:
            map_note = f"no difference map against {target.name!r}: {e}"
    if dmap is not None:
        meta["difference map"] = (
            f"error (eq. 5.1) of the current state minus pin {dmap['pin']!r} in percentage "
            f"points, {dmap['what']}; in the CSV of the error map view of each state; "
            f"colours span +-{dmap['scale_pp']:.3g} pp (the {percent(SCALE_QUANTILE):g}th "
            f"percentile of the cells that differ), {dmap['beyond']} cells beyond, up to "
            f"{dmap['largest_pp']:.4g} pp"
        )
    elif map_note:
        meta["difference map"] = map_note
    meta["models"] = s.models.describe()
    res = " + residual" if s.residual else ""
    return Result(
        columns=_long_columns(curves),
        meta=meta,
        filename=csv_name(
            s,
            "compare",
            f"h{s.harmonic}",
            f"N{s.n_modes}",
            res_part(s),
            s.dof,
            s.coupling,
            f"{len(pins)}pins",
        ),
        caption=(
            f"**{len(pins)} pinned** &middot; current: harmonic {s.harmonic}, N = {s.n_modes}"
            f"{res}, bushing:{s.dof}, {s.coupling}" + (f" &middot; {map_note}" if map_note else "")
        ),
        draw={"curves": curves, "map": dmap, "dof": s.dof, "pins": [p.name for p in pins]},
    )


def pinned_result(s: Snapshot) -> tuple[Result, ...]:
    """Each pin against the current state (for the report and the CSV of a pin): its
    level, the current level (the coupled-response view's) and their difference (the
    current one and the difference only on the same frequency grid); pins without data
    are left out."""
    if not any(p.data is not None for p in s.pins):
        return ()
    current = response_result(s)
    return tuple(_pinned(s, p, current) for p in s.pins if p.data is not None)


def _pinned(s: Snapshot, p: Pin, current: Result) -> Result:
    assert p.data is not None
    resp = p.data.frfs["response"]
    label = p.name.replace(" ", "_")
    cols: dict[str, np.ndarray] = {
        "freq_Hz": np.asarray(resp.freq, float),
        f"pin_{label}_dB": magnitude_db(resp.data[:, 0, 0]),
    }
    cur = current.core["truncated"]
    meta: dict[str, Any] = {
        "view": f"pinned state {p.name!r} against the current state",
        "pin": _describe(p),
        "pin sources": ", ".join(f"{k}={v}" for k, v in p.data.sources.items()),
        "current": f"{_describe_settings(s)}; {s.models.describe()}",
        "unit": compute.level_unit(p.settings.dof),
    }
    try:
        diff = db_difference(cur, _relabel(resp, cur))
        cols["current_dB"] = current.columns["truncated_dB"]
        cols["current_minus_pin_dB"] = np.asarray(diff.db[:, 0, 0], float)
    except FBSError as e:
        meta["difference"] = f"none: {e}"
    return Result(
        columns=cols,
        meta=meta,
        filename=csv_name(
            s,
            f"pin_{label}_vs",
            f"h{s.harmonic}",
            f"N{s.n_modes}",
            res_part(s),
            s.dof,
            s.coupling,
        ),
        caption=f"Pin **{p.name}**: {_describe(p)}",
    )


def _long_columns(curves: list[dict]) -> dict[str, np.ndarray]:
    """One row per (curve, frequency line)."""
    parts: dict[str, list[np.ndarray]] = {
        k: [] for k in ("curve", "freq_Hz", "level_dB", "diff_dB", "band_low_dB", "band_high_dB")
    }
    for i, c in enumerate(curves):
        n = c["freq"].size
        parts["curve"].append(np.full(n, float(i)))
        parts["freq_Hz"].append(c["freq"])
        parts["level_dB"].append(c["level"])
        parts["diff_dB"].append(c["diff"])
        lo_hi = c["band"]
        nan = np.full(n, np.nan)
        parts["band_low_dB"].append(magnitude_db(lo_hi[0]) if lo_hi is not None else nan)
        parts["band_high_dB"].append(magnitude_db(lo_hi[1]) if lo_hi is not None else nan)
    return {k: np.concatenate(v) for k, v in parts.items()}
