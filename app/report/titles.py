"""Title blocks and file names of plots, images, CSV files and reports (pure functions).

Every plot, saved image, CSV and report of a dashboard state says what it shows: the
quantity, the harmonic with its road wavelength, speed range and frequency band, the
response DOF, the retained modes N, the hub coupling, the noise settings where noise is
applied, the data in use (reference models or uploaded file names), the date and the page
URL that reproduces it. The file name says the same in short.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import fbs_core

from .data import ReportData, ReportError

__all__ = [
    "VIEWS",
    "TitleBlock",
    "harmonic_description",
    "coupling_description",
    "modes_description",
    "noise_description",
    "title_block",
    "compact_title",
    "file_stem",
]

#: The things that carry a title block: view key -> what it shows.
VIEWS: dict[str, str] = {
    "report": "tire-fbs report",
    "coupled-response": "Coupled bushing response v_e* (eq. 4.1): all tire modes and N modes",
    "truncation-map": "Truncation error (eq. 5.1, floating band) over centre frequency and N",
    "suggested-modes": "Suggested number of tire modes (thesis table 5.1)",
    "scatter-band": "Noise scatter band of v_e* (eqs. 5.2-5.4)",
    "eigenfrequency": "Highest retained eigenfrequency vs N (thesis fig. 5.8)",
    "uncoupled": "Uncoupled subsystems: free hub velocity Y_ja^A F_a and chassis mobility",
    "compare": "Compare pinned states: coupled response and difference in dB",
    "contributions": "Contributions of the six hub forces to the bushing response (eq. 4.1)",
    "phase": "Coupled response: magnitude and phase, peaks and the coupled modes near them",
    "campbell": "Campbell diagram: tire eigenfrequencies vs speed, harmonic order lines",
    "speed-map": "Bushing level over speed and frequency for the harmonic",
    "wheel-contributions": "Contribution of each wheel's road to the car's response (eq. 4.1)",
    "participation": "Participation of the tire modes in the bushing response (docs/modes.md)",
    "mode-shape": "Tire mode shape: the deformed belt over one period",
    "waves": "Campbell diagram of the belt waves, branches tracked by shape",
    "selected-modes": "Selected tire modes beside the lowest N (table 5.1)",
    "chassis-truncation": "Truncation of the chassis side (eq. 5.1, the tire exact)",
}
#: What a view shows in vehicle scope, where it differs (the whole car).
_VEHICLE_WHAT = {
    "coupled-response": "Coupled response of the car v_e* (eq. 4.1, four tires): all tire "
    "modes and N modes",
    "scatter-band": "Noise scatter band of the car's v_e* (eqs. 5.2-5.4, noise per wheel and "
    "on the body)",
}
#: Views of one harmonic's tire alone (the harmonic's line only, no case line).
_TIRE_VIEWS = ("campbell", "mode-shape", "waves")
#: Views judged by the truncation criterion (the map's DOF, the threshold, no chosen N).
_CRITERION_VIEWS = ("truncation-map", "suggested-modes", "selected-modes", "chassis-truncation")
#: Views that do not depend on the chosen N.
_NO_N_VIEWS = ("suggested-modes", *_TIRE_VIEWS, "participation", "selected-modes",
               "chassis-truncation")  # fmt: skip

#: The views whose numbers residual compensation changes (their titles and names say it).
RESIDUAL_VIEWS = (
    "report",
    "coupled-response",
    "truncation-map",
    "suggested-modes",
    "compare",
    "contributions",
    "phase",
    "wheel-contributions",
    "selected-modes",
    "chassis-truncation",
)

_NOISE_EQ = {"tire": "5.2", "chassis": "5.3", "both": "5.4"}
#: Where the noise is, in words (``"noise 5 % in tire and chassis"``), by noise target.
NOISE_WHERE = {"tire": "the tire", "chassis": "the chassis", "both": "tire and chassis"}
_NOISE_WHERE = NOISE_WHERE
#: Views with a chosen N that residual compensation does not change: with it on, their
#: titles say that they are plain truncations (the page's switch acts on the others).
PLAIN_VIEWS = ("scatter-band",)
PLAIN_TEXT = "plain truncation (residual compensation not applied to the band)"


@dataclass(frozen=True)
class TitleBlock:
    """What a plot shows, as a heading and detail lines.

    Attributes
    ----------
    what : str
        The heading (quantity and equation).
    lines : tuple of str
        Harmonic, case, noise, data, date and link lines (only those that apply).
    """

    what: str
    lines: tuple[str, ...]

    @property
    def text(self) -> str:
        """Heading and lines, one per line."""
        return "\n".join((self.what, *self.lines))


def harmonic_description(k: int) -> str:
    """``"Harmonic 4: road wavelength 0.2395 m, 30-120 km/h, band 34.8-139.2 Hz"``.

    From :func:`fbs_core.harmonic` (thesis fig. 4.4, table 5.1).

    Raises
    ------
    fbs_core.harmonics.HarmonicError
        For anything but 1..7.
    """
    h = fbs_core.harmonic(k)
    lo, hi = h.freq_range
    v0, v1 = h.speed_range
    return (
        f"Harmonic {h.k}: road wavelength {h.wavelength:g} m, {v0:g}-{v1:g} km/h, "
        f"band {lo:.1f}-{hi:.1f} Hz"
    )


def coupling_description(coupling: str) -> str:
    """Plain words for the hub coupling option."""
    if coupling == "6dof":
        return "6-DOF hub coupling (braked wheel)"
    if coupling == "5dof":
        return "5-DOF hub coupling (wheel spin ry released)"
    raise ReportError(f"unknown coupling {coupling!r}; allowed: 6dof, 5dof")


def modes_description(n_modes: int, n_total: int | None = None) -> str:
    """``"N = 60 of 400 tire modes"``; ``"all 400 tire modes"`` when N reaches the total."""
    n = int(n_modes)
    if n_total is not None and n >= n_total:
        return f"N = all {int(n_total)} tire modes"
    of = f" of {int(n_total)}" if n_total is not None else ""
    return f"N = {n}{of} tire modes"


def noise_description(settings: Mapping[str, Any]) -> str:
    """The noise settings in one line (thesis eqs. 5.2-5.4)."""
    s = settings
    target = s["target"]
    how = "new scaling matrix at every line" if s["frequency_dependent"] else "one per round"
    return (
        f"Noise p = {s['noise']:g} % in {_NOISE_WHERE[target]} (eq. {_NOISE_EQ[target]}), "
        f"{how}, R = {s['rounds']:,} rounds, seed {s['seed']}, "
        f"{s['percentile']} % central band, round #{s['single_round']}"
    )


def _dof_text(snap: ReportData, view: str) -> str:
    if view in ("truncation-map", "suggested-modes"):
        d = snap.map_dof
        return f"DOF {d}" if d is not None else f"DOF: maximum over the 6 {_node(snap)} DOFs"
    if view == "uncoupled":
        return f"DOF hub:{snap.settings['dof']} (tire) and {snap.response_dof} (chassis)"
    return f"DOF {snap.response_dof}"


def _node(snap: ReportData) -> str:
    """The response node: ``bushing``, or the car's point in vehicle scope."""
    return str(snap.settings["point"]) if snap.vehicle else "bushing"


def vehicle_line(snap: ReportData) -> str | None:
    """The car's line of a title block in vehicle scope (None in corner scope)."""
    if not snap.vehicle:
        return None
    s = snap.settings
    tracks = f"coherence {s['coherence']:g}" if s["tracks"] == "coherence" else s["tracks"]
    return f"Vehicle (reference car): wheels {s['wheels']} | tracks {tracks} | point {s['point']}"


def _vehicle_part(snap: ReportData) -> list[str]:
    """The car's part of a file name: ``car-wFLFRRLRR-inphase``."""
    if not snap.vehicle:
        return []
    s = snap.settings
    tracks = {"in phase": "inphase", "anti-phase": "antiphase"}.get(
        s["tracks"], f"coh{_num(s.get('coherence', 0.0))}"
    )
    return [f"car-w{s['wheels'].replace(' ', '')}-{tracks}"]


def _date_text(snap: ReportData) -> str:
    t = snap.created.astimezone(snap.created.tzinfo)
    return f"{t:%Y-%m-%d %H:%M} {t.tzname() or 'UTC'}"


#: The parts of each view's title block, in order (those of the report are optional).
_PARTS: dict[str, tuple[str, ...]] = {
    "report": ("harmonic", "dof", "modes", "threshold", "coupling", "noise"),
    "coupled-response": ("harmonic", "dof", "modes", "coupling"),
    "truncation-map": ("harmonic", "dof", "chosen", "threshold", "coupling"),
    "suggested-modes": ("all-harmonics", "dof", "threshold", "coupling", "residual"),
    "scatter-band": ("harmonic", "dof", "modes", "coupling", "noise"),
    "eigenfrequency": ("chosen",),
    "uncoupled": ("harmonic", "dof", "modes"),
    "wheel-contributions": ("harmonic", "dof", "modes", "coupling"),
}


def _part(snap: ReportData, view: str, part: str) -> str | None:
    s = snap.settings
    if part == "harmonic":
        return harmonic_description(s["harmonic"])
    if part == "all-harmonics":
        return "All seven harmonics, 30-120 km/h"
    if part == "dof":
        return _dof_text(snap, view)
    residual = bool(s.get("residual")) and view in RESIDUAL_VIEWS
    if part in ("modes", "chosen"):
        text = modes_description(s["n_modes"], snap.n_modes_total)
        text += " + residual compensation" if residual else ""
        if s.get("residual") and view in PLAIN_VIEWS:
            text += f", {PLAIN_TEXT}"
        return "chosen " + text if part == "chosen" else text
    if part == "residual":
        return "with residual compensation" if residual else None
    if part == "coupling":
        return coupling_description(s["coupling"])
    need = ("threshold", "f_max") if part == "threshold" else ("noise", "target", "rounds")
    missing = [k for k in need if k not in s]
    if missing:
        if view == "report":
            return None
        raise ReportError(f"the {view} title needs the setting(s) {', '.join(missing)}")
    if part == "threshold":
        return f"threshold {s['threshold']:g} % up to f_max {s['f_max']:g} Hz"
    return noise_description(s)


def title_block(snap: ReportData, view: str) -> TitleBlock:
    """The title block of a view (key of :data:`VIEWS`) for a snapshot.

    Lines: the harmonic (wavelength, speeds, band); DOF, N, threshold and coupling in one
    line; the noise settings (scatter band and report); the data in use; date and version;
    the reproducing link.

    Raises
    ------
    ReportError
        For an unknown view, naming the allowed ones; for a view whose settings the
        snapshot lacks (e.g. the scatter band without noise settings).
    """
    if view not in VIEWS:
        raise ReportError(f"unknown view {view!r}; allowed: {', '.join(VIEWS)}")
    parts = {p: _part(snap, view, p) for p in _PARTS[view]}
    lines = [line for p in ("harmonic", "all-harmonics") if p in parts and (line := parts.pop(p))]
    car = vehicle_line(snap)
    if car:
        lines.append(car)
    noise = parts.pop("noise", None)
    case = [v for v in parts.values() if v]
    if case:
        lines.append(" | ".join(case))
    if noise:
        lines.append(noise)
    lines.append("Data: " + snap.provenance.describe())
    lines.append(f"{_date_text(snap)} | tire-fbs {fbs_core.__version__}")
    if snap.url:
        lines.append(snap.url)
    what = _VEHICLE_WHAT.get(view, VIEWS[view]) if snap.vehicle else VIEWS[view]
    if view == "truncation-map" and snap.map_dof is None:
        what = (
            f"Truncation error (eq. 5.1), maximum over the 6 {_node(snap)} DOFs (thesis fig. 5.6)"
        )
    return TitleBlock(what, tuple(lines))


_SHORT_WHAT = {
    "coupled-response": "Coupled bushing response v_e* (eq. 4.1)",
    "truncation-map": "Truncation error, eq. 5.1",
    "scatter-band": "Noise scatter band of v_e* (eqs. 5.2-5.4)",
    "eigenfrequency": "Highest retained eigenfrequency (fig. 5.8)",
    "uncoupled": "Uncoupled subsystems",
    "suggested-modes": "Suggested number of modes (table 5.1)",
    "compare": "Pinned states compared",
    "contributions": "Hub-force contributions (eq. 4.1)",
    "phase": "Magnitude and phase, peaks",
    "campbell": "Campbell diagram",
    "speed-map": "Bushing level over speed",
    "wheel-contributions": "Per-wheel contributions (eq. 4.1)",
    "participation": "Which tire modes matter",
    "mode-shape": "Tire mode shape",
    "waves": "Campbell diagram of the belt waves",
    "selected-modes": "Selected modes beside table 5.1",
    "chassis-truncation": "Chassis-side truncation, eq. 5.1",
    "report": "tire-fbs",
}
_SHORT_COUPLING = {"6dof": "6-DOF hub (braked)", "5dof": "5-DOF hub (spin free)"}


def compact_title(snap: ReportData, view: str) -> TitleBlock:
    """The title block of a live plot in short lines (a plot's title does not wrap).

    The harmonic (wavelength, speeds, band); DOF, N, threshold, coupling; the noise
    (scatter band); the data in use with the date; the link.
    """
    if view not in VIEWS:
        raise ReportError(f"unknown view {view!r}; allowed: {', '.join(VIEWS)}")
    s = snap.settings
    lines = []
    if view in _TIRE_VIEWS:  # the tire across speed: the chosen harmonic's line only
        lines.append(harmonic_description(s["harmonic"]))
    elif view not in ("eigenfrequency", "suggested-modes"):
        h = snap.harmonic
        lo, hi = h.freq_range
        lines.append(
            f"Harmonic {h.k}: wavelength {h.wavelength:g} m, {h.speed_range[0]:g}-"
            f"{h.speed_range[1]:g} km/h, {lo:.1f}-{hi:.1f} Hz"
        )
    car = vehicle_line(snap)
    if car and view not in ("eigenfrequency", "campbell"):
        lines.append(car)
    case = []
    if view not in ("eigenfrequency", *_TIRE_VIEWS):
        d = snap.map_dof if view in _CRITERION_VIEWS else snap.response_dof
        case.append(d or "max over 6 DOFs")
    total = snap.n_modes_total
    n = f"N = {s['n_modes']}" + (f" of {total}" if total else "")
    residual = bool(s.get("residual")) and view in RESIDUAL_VIEWS
    if view in ("truncation-map", "eigenfrequency"):
        n = "chosen " + n
    if view not in _NO_N_VIEWS:
        plain = bool(s.get("residual")) and view in PLAIN_VIEWS
        case.append(n + (" + residual" if residual else "") + (f", {PLAIN_TEXT}" if plain else ""))
    if view in _CRITERION_VIEWS and "threshold" in s:
        case.append(f"threshold {s['threshold']:g} % to {s['f_max']:g} Hz")
    if view == "participation" and "f_max" in s:
        case.append(f"band up to {s['f_max']:g} Hz")
    if view in ("suggested-modes", "selected-modes", "chassis-truncation") and residual:
        case.append("with residuals")
    if view not in ("eigenfrequency", "uncoupled", "campbell", "mode-shape", "waves"):
        case.append(_SHORT_COUPLING[s["coupling"]])
    if case:
        lines.append(" | ".join(case))
    if view == "scatter-band" and "noise" in s:
        how = "every line" if s["frequency_dependent"] else "per round"
        lines.append(
            f"Noise p = {s['noise']:g} % in {_NOISE_WHERE[s['target']]} (eq. "
            f"{_NOISE_EQ[s['target']]}), {how}, R = {s['rounds']:,}, seed {s['seed']}"
        )
    p = snap.provenance
    data = (
        "reference models"
        if p.is_reference
        else ", ".join(f"uploaded {d.role} '{d.name}'" for d in p.uploads)
    )
    lines.append(f"Data: {data} | {_date_text(snap)}")
    if snap.url:
        lines.append(snap.url)
    what = _SHORT_WHAT[view]
    if snap.vehicle and view in _VEHICLE_WHAT:
        what = what.replace("bushing response", "response of the car").replace("v_e*", "car's v_e*")
    return TitleBlock(what, tuple(lines))


def _num(x: float) -> str:
    return f"{x:g}".replace("+", "")


def _safe(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9.-]+", "-", text).strip("-.")


def file_stem(snap: ReportData, view: str = "report") -> str:
    """File name without extension that says what a view shows.

    ``tire-fbs_h4_bushing-z_N60_6dof_2026-12-01`` for the report (``_N60_res_`` with
    residual compensation),
    ``tire-fbs_scatter-band_h4_bushing-z_N60_6dof_p10-both_R10000_2026-12-01`` for the band;
    ``_upload`` before the date when uploaded data are in use. Only ``[A-Za-z0-9._-]``.

    Raises
    ------
    ReportError
        For an unknown view.
    """
    if view not in VIEWS:
        raise ReportError(f"unknown view {view!r}; allowed: {', '.join(VIEWS)}")
    s = snap.settings
    dof = snap.map_dof if view in _CRITERION_VIEWS else snap.response_dof
    dof_part = dof.replace(":", "-") if dof else f"{_node(snap)}-max6"
    parts = ["tire-fbs"] if view == "report" else ["tire-fbs", view]
    if view == "suggested-modes":
        parts += [f"thr{_num(s['threshold'])}", f"fmax{_num(s['f_max'])}", dof_part]
    elif view == "eigenfrequency":
        parts += [f"N{s['n_modes']}"]
    elif view == "truncation-map":
        parts += [f"h{s['harmonic']}", dof_part, f"thr{_num(s['threshold'])}"]
    elif view == "uncoupled":
        parts += [f"h{s['harmonic']}", f"hub-{s['dof']}", f"N{s['n_modes']}"]
    elif view in _TIRE_VIEWS:
        parts += [f"h{s['harmonic']}"]
    elif view in ("selected-modes", "chassis-truncation"):
        parts += [f"h{s['harmonic']}", dof_part, f"thr{_num(s['threshold'])}"]
        parts += [f"fmax{_num(s['f_max'])}"]
    elif view == "participation":
        parts += [f"h{s['harmonic']}", dof_part, f"fmax{_num(s['f_max'])}"]
    else:
        parts += [f"h{s['harmonic']}", dof_part, f"N{s['n_modes']}"]
    if s.get("residual") and view in RESIDUAL_VIEWS:
        parts.append("res")
    if view not in ("eigenfrequency", "uncoupled", *_TIRE_VIEWS):
        parts.append(s["coupling"])
        parts += _vehicle_part(snap)
    if view == "scatter-band":
        parts += [f"p{_num(s['noise'])}-{s['target']}", f"R{s['rounds']}"]
        if s["frequency_dependent"]:
            parts.append("fdep")
    if not snap.provenance.is_reference:
        parts.append("upload")
    parts.append(f"{snap.created:%Y-%m-%d}")
    return "_".join(_safe(p) for p in parts)
