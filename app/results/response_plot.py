"""The coupled-response plot as a test lab's FRF display: further bushing DOFs
overlaid, a dB or linear level axis, two labelled cursors with a readout (frequency, level
of every curve, difference) that may snap to the nearest peak.

A pure function of one snapshot, as every result (:mod:`app.results`); the curves are the
coupled response of thesis eq. 4.1 (:func:`app.compute.mobility_data`, the same cached
numbers as the response view).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fbs_core.analysis import find_peaks_db
from fbs_core.analysis.views import interp_level
from fbs_core.errors import FBSError
from fbs_core.vocabulary import magnitude_db

from .. import compute
from .base import Result, Snapshot, csv_name
from .main import res_part, residual_meta

__all__ = ["PEAK_PROMINENCE_DB", "linear_unit", "response_plot_result", "snap_to_peak"]

#: The prominence (dB) a local maximum needs to be a peak a cursor snaps to (the phase
#: view's peak labels use the same figure).
PEAK_PROMINENCE_DB = 3.0


def linear_unit(dof: str) -> str:
    """The unit of the magnitude ``|v|`` of a bushing DOF's response (m/s or rad/s per
    metre of road amplitude)."""
    return compute.level_unit(dof).removeprefix("dB re 1 ")


def snap_to_peak(freq: np.ndarray, level_db: np.ndarray, f0: float) -> float | None:
    """The frequency of the peak of ``level_db`` nearest to ``f0`` (sub-line, parabolic:
    :func:`fbs_core.analysis.find_peaks_db`), or None where the curve has no peak."""
    fp, _, _, _ = find_peaks_db(freq, level_db, prominence_db=PEAK_PROMINENCE_DB)
    if fp.size == 0:
        return None
    return float(fp[np.argmin(np.abs(fp - f0))])


def _curves(s: Snapshot) -> list[dict]:
    """The curves drawn: the selected DOF with all modes and with N, then each overlaid DOF
    with N (the selected one is not repeated)."""
    d = compute.mobility_data(s.harmonic, s.n_modes, s.dof, s.coupling, s.models, s.residual)
    res = " + residual" if s.residual else ""
    out: list[dict[str, Any]] = [
        {"key": "reference", "dof": s.dof, "label": f"bushing:{s.dof}, all modes"},
        {"key": "truncated", "dof": s.dof, "label": f"bushing:{s.dof}, N modes{res}"},
    ]
    out[0]["h"], out[1]["h"] = d["reference"], d["truncated"]
    for dof in s.overlay:
        if dof == s.dof:
            continue
        o = compute.mobility_data(s.harmonic, s.n_modes, dof, s.coupling, s.models, s.residual)
        unit = "" if linear_unit(dof) == linear_unit(s.dof) else f" [{linear_unit(dof)}]"
        out.append(
            {
                "key": f"overlay_{dof}",
                "dof": dof,
                "label": f"bushing:{dof}, N modes{res}{unit}",
                "h": o["truncated"],
            }
        )
    for c in out:
        c["db"] = magnitude_db(c["h"])
    return out


def _cursor(s: Snapshot, k: int, f0: float, freq: np.ndarray, main_db: np.ndarray) -> dict:
    """Cursor ``k`` asked at ``f0`` Hz: where it stands (snapped or not) and why."""
    note = ""
    f = f0
    if s.snap:
        peak = snap_to_peak(freq, main_db, f0)
        if peak is None:
            note = " (no peak to snap to)"
        else:
            f = peak
            note = f" (snapped to the peak nearest {f0:g} Hz)"
    return {"k": k, "asked": f0, "f": f, "note": note}


def _fmt(scale: str, level_db: float) -> str:
    return f"{level_db:.2f} dB" if scale == "dB" else f"{10 ** (level_db / 20):.4g}"


def response_plot_result(s: Snapshot) -> Result:
    """The curves of the coupled-response plot in the level scale asked for, and the
    cursors' readout.

    The readout's levels are interpolated linearly in dB between the neighbouring lines
    (:func:`fbs_core.analysis.interp_level`, as the phase view's delta cursors); in the
    linear scale they are shown as magnitudes ``10**(L/20)`` and the difference as the
    ratio of the magnitudes.
    """
    d = compute.mobility_data(s.harmonic, s.n_modes, s.dof, s.coupling, s.models, s.residual)
    freq = np.asarray(d["freq"], float)
    curves = _curves(s)
    scale = s.level_scale
    unit = compute.level_unit(s.dof) if scale == "dB" else linear_unit(s.dof)
    y_label = f"Level ({unit})" if scale == "dB" else f"|v| ({unit})"
    main_db = curves[1]["db"]
    asked = [(k, f0) for k, f0 in ((1, s.mcursor1), (2, s.mcursor2)) if f0 > 0]
    cursors = [_cursor(s, k, f0, freq, main_db) for k, f0 in asked]
    meta_c: dict[str, str] = {}
    rows = []  # readout: curve, level at each cursor, difference
    for c in curves:
        levels = []
        for cur in cursors:
            try:
                levels.append(interp_level(freq, c["db"], cur["f"]))
            except FBSError as e:
                levels.append(float("nan"))
                cur["error"] = str(e)
        c["levels"] = levels
        cells = [c["label"], *("—" if lv != lv else _fmt(scale, lv) for lv in levels)]
        if len(levels) == 2:
            l1, l2 = levels
            diff = f"{l2 - l1:+.2f} dB" if scale == "dB" else f"× {10 ** ((l2 - l1) / 20):.4g}"
            cells.append("—" if l1 != l1 or l2 != l2 else diff)
        rows.append(cells)
    for cur in cursors:
        k = cur["k"]
        if "error" in cur:
            meta_c[f"cursor {k}"] = f"f{k} = {cur['asked']:g} Hz: {cur['error']}"
            continue
        main_level = _fmt(scale, curves[1]["levels"][cursors.index(cur)])
        meta_c[f"cursor {k}"] = (
            f"f{k} = {cur['f']:.6g} Hz{cur['note']}: {main_level} ({curves[1]['label']})"
        )
    header = ["curve", *(f"f{c['k']} = {c['f']:.2f} Hz" for c in cursors)]
    if len(cursors) == 2 and not any("error" in c for c in cursors):
        df = cursors[1]["f"] - cursors[0]["f"]
        header.append(f"f2 - f1 = {df:.2f} Hz")
        what = "L2 - L1" if scale == "dB" else "|v2| / |v1|"
        meta_c["cursor difference"] = f"f2 - f1 = {df:.6g} Hz, {rows[1][0]}: {rows[1][-1]} ({what})"
    overlaid = [c["dof"] for c in curves[2:]]
    res = " + residual" if s.residual else ""
    cols: dict[str, np.ndarray] = {"freq_Hz": freq}
    for c in curves[2:]:
        cols[f"bushing_{c['dof']}_dB"] = c["db"]
        cols[f"bushing_{c['dof']}"] = c["h"]
    return Result(
        columns=cols,
        meta={
            "view": "coupled bushing response v_e* (thesis eq. 4.1): overlays and cursors",
            "harmonic": s.harmonic,
            "N (retained tire modes)": s.n_modes,
            "residual compensation": residual_meta(s.residual),
            "response DOF": f"bushing:{s.dof}",
            "overlaid DOFs (N modes)": ", ".join(f"bushing:{x}" for x in overlaid) or "none",
            "coupling": s.coupling,
            "level axis": (
                compute.level_unit(s.dof)
                if scale == "dB"
                else f"linear: |v| in {linear_unit(s.dof)}"
            ),
            "cursors snap to peaks": "yes" if s.snap else "no",
            **meta_c,
            "models": s.models.describe(),
        },
        filename=csv_name(
            s,
            "bushing_response_overlay",
            f"h{s.harmonic}",
            f"N{s.n_modes}",
            res_part(s),
            s.dof,
            s.coupling,
            *overlaid,
        ),
        caption=(
            f"**Harmonic {s.harmonic}** &middot; bushing:{s.dof} &middot; N = {s.n_modes}"
            f"{res} &middot; {s.coupling} coupling"
            + "".join(f" &middot; {v}" for v in meta_c.values())
        ),
        draw={
            "freq": freq,
            "scale": scale,
            "y_label": y_label,
            "curves": [
                {
                    "key": c["key"],
                    "dof": c["dof"],
                    "label": c["label"],
                    "y": c["db"] if scale == "dB" else np.abs(c["h"]),
                }
                for c in curves
            ],
            "cursors": [
                {
                    "k": c["k"],
                    "f": c["f"],
                    "y": (
                        None
                        if "error" in c
                        else (
                            curves[1]["levels"][i]
                            if scale == "dB"
                            else 10 ** (curves[1]["levels"][i] / 20)
                        )
                    ),
                    "error": c.get("error", ""),
                }
                for i, c in enumerate(cursors)
            ],
            "readout": {"header": header, "rows": rows if cursors else []},
        },
    )
