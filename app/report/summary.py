"""The report's first page: what someone who was not in the room reads first.

The suggested N and the chosen N's largest eq. 5.1 error, the scatter band's width at the
peaks, the largest contributions and the table of peaks, all read from the results the
session published (:class:`~app.report.data.ReportData`): the peaks of the coupled
response as the phase view labels them, the band and the contributions when the page
computed them for these settings. Nothing is computed again here; a result the page did
not compute is said to be missing, with the view that computes it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fbs_core.vocabulary import fraction, magnitude_db, percent

from .data import ReportData

__all__ = ["Summary", "WorstError", "report_summary", "worst_error"]


@dataclass(frozen=True)
class WorstError:
    """The largest eq. 5.1 error of one N up to f_max (percent) and where it is."""

    n_modes: int
    error: float  # percent (nan: no centre up to f_max, or N not in the map)
    centre: float  # Hz
    below: bool  # below the threshold


@dataclass(frozen=True)
class Summary:
    """The first page's numbers, formatted: ``(quantity, value)`` rows and the peak table."""

    rows: tuple[tuple[str, str], ...]
    peak_header: tuple[str, ...]
    peak_rows: tuple[tuple[str, ...], ...]
    peak_caption: str


def _f(x: float, digits: int = 1) -> str:
    v = round(float(x), digits)
    return f"{v + 0.0:.{digits}f}"


def suggested_n(snap: ReportData) -> int | None:
    """The N the page's error map marks (read from the map when the page gave none)."""
    if snap.suggested_n is not None:
        return int(snap.suggested_n)
    m = snap.truncation
    if m is None:
        return None
    return int(
        m.suggest(fraction(snap.settings["threshold"]), snap.settings["f_max"], snap.map_dof)
    )


def worst_error(snap: ReportData, n: int) -> WorstError | None:
    """The largest error of the published map for ``n`` modes at centres up to f_max."""
    m = snap.truncation
    if m is None:
        return None
    s = snap.settings
    err = percent(m.max_error if snap.map_dof is None else m.dof_error(snap.map_dof))
    rows = np.flatnonzero(np.asarray(m.n_modes) == n)
    sel = np.asarray(m.centres) <= s["f_max"] + 1e-9
    if not rows.size or not sel.any():
        return WorstError(n, float("nan"), float("nan"), False)
    e = np.where(sel, err[rows[0]], -np.inf)
    k = int(np.argmax(e))
    return WorstError(n, float(e[k]), float(m.centres[k]), bool(e[k] < s["threshold"]))


def _level_db(frf: Any, dof: str) -> np.ndarray:
    """The level of a response to its one input (the corner's road at the patch, ``patch``;
    the car's road, ``road``) at output ``dof``."""
    if len(frf.inputs) != 1:
        raise ValueError(f"a response has one input (the road), got {', '.join(frf.inputs)}")
    return magnitude_db(frf.sel(outputs=dof).data[:, 0, 0])


def _peaks(snap: ReportData) -> list[Any]:
    """The peaks of the N-mode response the page labels (highest first); the highest line
    alone when the data hold no peak labels."""
    if snap.peaks:
        return sorted(snap.peaks, key=lambda p: -p.level_db)
    tr = snap.truncated
    if tr is None:
        return []
    lv = _level_db(tr, snap.response_dof)
    i = int(np.argmax(lv))
    h = snap.harmonic

    @dataclass(frozen=True)
    class _Line:
        freq: float
        level_db: float
        line: int
        speed_kmh: float | None

    return [_Line(float(tr.freq[i]), float(lv[i]), i, float(h.speed_at(tr.freq[i])))]


def _highest(snap: ReportData) -> Any:
    """The highest level of the N-mode response over the whole band, the band's edge lines
    included: the maximum the plot shows, by one rule for the corner and the car (a peak
    label is a local maximum inside the band; the highest level can sit at an edge where
    the response still rises beyond the band)."""
    tr = snap.truncated
    if tr is None:
        return None
    lv = _level_db(tr, snap.response_dof)
    i = int(np.argmax(lv))
    h = snap.harmonic

    @dataclass(frozen=True)
    class _Line:
        freq: float
        level_db: float
        line: int
        speed_kmh: float | None
        edge: str
        freqs: Any  # the lines of the curve

    edge = "lower" if i == 0 else ("upper" if i == lv.size - 1 else "")
    return _Line(float(tr.freq[i]), float(lv[i]), i, float(h.speed_at(tr.freq[i])), edge, tr.freq)


def _line_of(freq: np.ndarray, f: float) -> int | None:
    """The grid line at frequency ``f`` (None: not on this grid)."""
    i = int(np.argmin(np.abs(np.asarray(freq, float) - f)))
    step = np.min(np.diff(freq)) if len(freq) > 1 else 1.0
    return i if abs(freq[i] - f) <= 0.51 * step else None


def _band_width(snap: ReportData, f: float) -> tuple[float, float] | None:
    """(max - min, central band) width in dB of the published band at ``f``."""
    b = snap.band
    if b is None:
        return None
    i = _line_of(b.freq, f)
    if i is None:
        return None
    j = b.dofs.index(snap.response_dof)
    w = snap.settings["percentile"]
    q = [float(x) for x in b.q]
    lo, hi = q.index((100 - w) / 2), q.index((100 + w) / 2)
    full = magnitude_db(b.maximum[i, j]) - magnitude_db(b.minimum[i, j])
    central = magnitude_db(b.percentiles[hi, i, j]) - magnitude_db(b.percentiles[lo, i, j])
    return float(full), float(central)


def _contributions(snap: ReportData, f: float, top: int = 3) -> str | None:
    """The ``top`` largest shares of the published contributions at ``f``."""
    c = snap.contributions
    if c is None:
        return None
    i = _line_of(c.freq, f)
    if i is None:
        return None
    shares = c.shares(snap.response_dof)[i]
    order = np.argsort(-np.abs(shares))[:top]
    return ", ".join(f"{c.interface[k]} {_f(percent(shares[k]), 0)} %" for k in order)


def report_summary(snap: ReportData) -> Summary:
    """The first page of the report of ``snap`` (every number from its published results)."""
    s = snap.settings
    res = " + residual" if s.get("residual") else ""
    rows: list[tuple[str, str]] = []
    n_sugg = suggested_n(snap)
    thr, fmax = s.get("threshold"), s.get("f_max")
    if n_sugg is not None:
        rows.append(
            (
                "suggested N",
                f"{n_sugg}: the eq. 5.1 error stays below {thr:g} % up to {fmax:g} Hz "
                f"(table 5.1{', with residual compensation' if res else ''})",
            )
        )
    we = worst_error(snap, s["n_modes"])
    if we is not None:
        if np.isfinite(we.error):
            verdict = "below" if we.below else "at or above"
            text = (
                f"{_f(we.error)} % at the {_f(we.centre)} Hz band ({verdict} the {thr:g} % "
                "threshold)"
            )
        else:
            text = "not in the error map (N off its grid, or no centre up to f_max)"
        rows.append((f"largest eq. 5.1 error of the chosen N = {s['n_modes']}{res}", text))
    peaks = _peaks(snap)
    top = _highest(snap)
    if top is not None:
        where = f" (the band's {top.edge} edge)" if top.edge else ""
        rows.append(
            (
                f"highest level of {snap.response_dof}",
                f"{_f(top.level_db, 2)} dB at {_f(top.freq)} Hz{where}"
                + (f", {_f(top.speed_kmh)} km/h" if top.speed_kmh is not None else ""),
            )
        )
        if snap.peaks:
            pk = max(snap.peaks, key=lambda p: p.level_db)
            if _line_of(np.asarray(top.freqs), pk.freq) != top.line:
                rows.append(
                    (
                        "highest labelled peak",
                        f"{_f(pk.level_db, 2)} dB at {_f(pk.freq)} Hz"
                        + (f", {_f(pk.speed_kmh)} km/h" if pk.speed_kmh is not None else ""),
                    )
                )
        bw = _band_width(snap, top.freq)
        if snap.band is None:
            band = "not computed for these settings (scatter band view)"
        elif bw is None:
            band = "the line is off the band's grid"
        else:
            band = (
                f"{_f(bw[0], 2)} dB between minimum and maximum, {_f(bw[1], 2)} dB for the "
                f"{s['percentile']} % central band (p = {s['noise']:g} %, R = {s['rounds']:,})"
            )
        rows.append(("scatter band width at the highest level", band))
        con = _contributions(snap, top.freq)
        rows.append(
            (
                "largest contributions at the highest level (share of the total)",
                con
                if con is not None
                else "not computed in this session (Analysis card, Contributions tab)",
            )
        )
    header = ["frequency", "vehicle speed", f"level, N = {s['n_modes']}{res}"]
    ref = snap.reference
    ref_lv = _level_db(ref, snap.response_dof) if ref is not None else None
    if ref_lv is not None:
        header += ["level, all modes"]
    if snap.band is not None:
        header += ["band max - min"]
    if snap.contributions is not None:
        header += ["largest contributions"]
    prow = []
    for p in sorted(peaks, key=lambda p: p.freq):
        row = [
            f"{_f(p.freq)} Hz",
            f"{_f(p.speed_kmh)} km/h" if p.speed_kmh is not None else "-",
            f"{_f(p.level_db, 2)} dB",
        ]
        if ref_lv is not None and ref is not None:
            i = _line_of(ref.freq, p.freq)
            row.append("-" if i is None else f"{_f(ref_lv[i], 2)} dB")
        if snap.band is not None:
            bw = _band_width(snap, p.freq)
            row.append("-" if bw is None else f"{_f(bw[0], 2)} dB")
        if snap.contributions is not None:
            row.append(_contributions(snap, p.freq, top=2) or "-")
        prow.append(tuple(row))
    caption = f"Peaks of the coupled response at {snap.response_dof} (N = {s['n_modes']}{res})"
    return Summary(tuple(rows), tuple(header), tuple(prow), caption)
