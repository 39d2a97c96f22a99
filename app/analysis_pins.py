"""Pinned baselines of the Compare tab (issue 18): what a pin holds and the comparison.

A pin is the session's state at one moment, named (up to four,
:data:`fbs_core.analysis.MAX_PINS`): its settings (:class:`~app.analysis_state.PinSettings`,
in the URL as ``pins=``) and its data as a :class:`fbs_core.analysis.PinnedState` (the coupled
response with N and all modes at its DOF, the scatter band's edges when its band was
computed, its provenance: models, fbs_core version, time). The data are recomputed from the
settings through the same caches as the live views (:mod:`app.compute`), so a pin made by a
click and one restored from a link are the same; a pin of uploaded data can only be
restored where the same upload is loaded (its models key is a digest of the bytes).

The comparison (:func:`compare_result`) overlays the current coupled response and the
pins', gives their difference in dB (:func:`fbs_core.analysis.db_difference`, current minus
pin, only on the same frequency grid: another harmonic has no difference curve), the band
edges of each, and the error map of the current state minus the chosen pin's
(:func:`fbs_core.analysis.truncation_map_difference`, same harmonic only) at the current
map DOF.
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

from . import compute
from .analysis_state import PinSettings
from .datasource import REFERENCE
from .store import Result, Snapshot

__all__ = ["Pin", "build_pin", "compare_result", "pin_result", "pin_settings"]


@dataclass(frozen=True, eq=False)
class Pin:
    """A pinned baseline: its settings, its data (None if its models are not loaded here)."""

    settings: PinSettings
    data: PinnedState | None
    note: str = ""

    @property
    def name(self) -> str:
        return self.settings.name


def pin_settings(name: str, s: Snapshot) -> PinSettings:
    """The settings of a pin of snapshot ``s``."""
    return PinSettings(
        name=name,
        harmonic=s.harmonic,
        n_modes=s.n_modes,
        dof=s.dof,
        coupling=s.coupling,
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
    else:
        return None
    return dataclasses.replace(
        current,
        harmonic=ps.harmonic,
        n_modes=ps.n_modes,
        dof=ps.dof,
        coupling=ps.coupling,
        noise=ps.noise,
        target=ps.target,
        frequency_dependent=ps.frequency_dependent,
        rounds=ps.rounds,
        seed=ps.seed,
        percentile=ps.percentile,
        models=models,
    )


def build_pin(ps: PinSettings, current: Snapshot) -> Pin:
    """The pin of settings ``ps`` with its data, computed through the app's caches."""
    s = _snapshot_of(ps, current)
    if s is None:
        return Pin(ps, None, "its uploaded data are not loaded in this session")
    d = compute.mobility_data(s.harmonic, s.n_modes, s.dof, s.coupling, s.models)
    out = [f"bushing:{s.dof}"]
    result: dict[str, Any] = {
        "response": FRF(d["freq"], d["truncated"][:, None, None], out, ["patch"]),
        "reference": FRF(d["freq"], d["reference"][:, None, None], out, ["patch"]),
    }
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
    return Pin(ps, data, note)


def _describe(p: Pin) -> str:
    s = p.settings
    txt = (
        f"h{s.harmonic} N={s.n_modes} bushing:{s.dof} {s.coupling} noise {s.noise:g} % "
        f"{s.target} R={s.rounds} seed {s.seed}"
    )
    if p.data is not None:
        txt += f"; {p.data.settings.get('models', '')}; pinned {p.data.created}"
    return txt + (f" ({p.note})" if p.note else "")


def _band_edges(data: PinnedState | None) -> tuple[np.ndarray, np.ndarray] | None:
    if data is None or "band_pct_low" not in data.arrays:
        return None
    return data.arrays["band_pct_low"][1], data.arrays["band_pct_high"][1]


def compare_result(s: Snapshot, pins: tuple[Pin, ...], compare_to: str) -> Result:
    """The Compare tab's result: curves, differences, band edges, difference map."""
    d = compute.mobility_data(s.harmonic, s.n_modes, s.dof, s.coupling, s.models)
    cur = FRF(d["freq"], d["truncated"][:, None, None], [f"bushing:{s.dof}"], ["patch"])
    band = compute.cached_band(s.band_key())
    cur_band = None
    if band is not None:
        b = compute.band_data(band, s.dof, s.percentile)
        cur_band = (b["pct_low"], b["pct_high"])
    curves = [
        {
            "name": "current",
            "freq": np.asarray(cur.freq, float),
            "level": magnitude_db(cur.data[:, 0, 0]),
            "diff": np.full(cur.freq.size, np.nan),
            "band": cur_band,
            "note": "",
        }
    ]
    meta: dict[str, Any] = {
        "view": "comparison of pinned states: coupled bushing response v_e* (eq. 4.1)",
        "curve 0": f"current: h{s.harmonic} N={s.n_modes} bushing:{s.dof} {s.coupling} "
        f"noise {s.noise:g} % {s.target} R={s.rounds} seed {s.seed}; {s.models.describe()}",
        "diff_dB": "20 log10 |current| - 20 log10 |pin| on the same frequency grid "
        "(fbs_core.analysis.db_difference); NaN: another grid (another harmonic)",
        "band": f"central percentile band edges of |v_e| ({s.percentile} % for the current)",
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
    if target is not None and target.data is not None:
        ps = _snapshot_of(target.settings, s)
        try:
            md = truncation_map_difference(
                compute.error_map(s.harmonic, s.coupling, s.models),
                compute.error_map(ps.harmonic, ps.coupling, ps.models),
            )
            what = s.map_dof
            err = md.max_diff if what is None else md.diff[:, :, md.dofs.index(f"bushing:{what}")]
            dmap = {
                "n_modes": np.asarray(md.n_modes, int),
                "centres": np.asarray(md.centres, float),
                "diff_pct": percent(np.asarray(err, float)),
                "pin": target.name,
                "what": f"bushing:{what}" if what else "max over 6 DOFs",
            }
        except FBSError as e:
            map_note = f"no difference map against {target.name!r}: {e}"
    if dmap is not None:
        meta["difference map"] = (
            f"error (eq. 5.1) of the current state minus pin {dmap['pin']!r} in percentage "
            f"points, {dmap['what']}; in the CSV of the error map view of each state"
        )
    elif map_note:
        meta["difference map"] = map_note
    meta["models"] = s.models.describe()
    cols = _long_columns(curves)
    return Result(
        columns=cols,
        meta=meta,
        filename=f"compare_h{s.harmonic}_N{s.n_modes}_{s.dof}_{len(pins)}pins.csv",
        caption=(
            f"**{len(pins)} pinned** &middot; current: harmonic {s.harmonic}, N = {s.n_modes}, "
            f"bushing:{s.dof}, {s.coupling}" + (f" &middot; {map_note}" if map_note else "")
        ),
        draw={"curves": curves, "map": dmap, "dof": s.dof, "pins": [p.name for p in pins]},
    )


def pin_result(s: Snapshot, p: Pin) -> Result | None:
    """One pin against the current state, for the report and the CSV of a pin: its level,
    the current level and their difference (the current one and the difference only on
    the same frequency grid). None for a pin without data."""
    if p.data is None:
        return None
    resp = p.data.frfs["response"]
    cols: dict[str, np.ndarray] = {
        "freq_Hz": np.asarray(resp.freq, float),
        f"pin_{p.name.replace(' ', '_')}_dB": magnitude_db(resp.data[:, 0, 0]),
    }
    d = compute.mobility_data(s.harmonic, s.n_modes, s.dof, s.coupling, s.models)
    cur = FRF(d["freq"], d["truncated"][:, None, None], [f"bushing:{s.dof}"], ["patch"])
    meta: dict[str, Any] = {
        "view": f"pinned state {p.name!r} against the current state",
        "pin": _describe(p),
        "pin sources": ", ".join(f"{k}={v}" for k, v in p.data.sources.items()),
        "current": f"h{s.harmonic} N={s.n_modes} bushing:{s.dof} {s.coupling}; "
        f"{s.models.describe()}",
        "unit": compute.level_unit(p.settings.dof),
    }
    try:
        diff = db_difference(cur, _relabel(resp, cur))
        cols["current_dB"] = magnitude_db(cur.data[:, 0, 0])
        cols["current_minus_pin_dB"] = np.asarray(diff.db[:, 0, 0], float)
    except FBSError as e:
        meta["difference"] = f"none: {e}"
    return Result(
        columns=cols,
        meta=meta,
        filename=f"pin_{p.name.replace(' ', '_')}.csv",
        caption=f"Pin **{p.name}**: {_describe(p)}",
    )


def _relabel(resp: FRF, like: FRF) -> FRF:
    """``resp`` with the labels of ``like`` (a pin of another DOF compares level to level)."""
    return FRF(resp.freq, resp.data, like.outputs, like.inputs, resp.quantity)


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
