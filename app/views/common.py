"""Shared colours, axis labels and hover lines of the views."""

from __future__ import annotations

from .. import compute

#: Colours: reference (dark), truncated (accent), uncoupled subsystems.
COLORS = {
    "reference": "#1f2937",
    "truncated": "#d9480f",
    "tire": "#1971c2",
    "chassis": "#2b8a3e",
    "band": "#4dabf7",
    "percentile": "#1864ab",
    "round": "#e8590c",
    "suggested": "#0ca678",
    "first_order": "#ae3ec9",
}

#: One colour per review candidate's colour slot (fbs_core.candidates: kept while the
#: candidate stays), distinct from the main curves' colours above (Okabe-Ito and three more).
CANDIDATE_COLORS = (
    "#0072b2",
    "#e69f00",
    "#009e73",
    "#cc79a7",
    "#56b4e9",
    "#8c6d31",
    "#7048e8",
    "#5c940d",
)
#: The target line on the response plots.
TARGET_COLOR = "#c92a2a"

FREQ_LABEL = "Frequency (Hz)"
MODES_LABEL = "Retained modes N"


def level_label(dof: str, label: str = "Level") -> str:
    """Axis label of a bushing/hub velocity level per road amplitude for a DOF direction."""
    return f"{label} ({compute.level_unit(dof)})"


def level_tooltips(what: str, column: str = "level") -> list[tuple[str, str]]:
    """Hover lines of a level curve: what it is, frequency and level."""
    return [("", what), ("Frequency", "@freq{0.0} Hz"), ("Level", "@" + column + "{0.0} dB")]


def tap_cursor(group, x: float | None, k: int) -> int:
    """A click at frequency ``x`` (Hz) places cursor ``k`` (1 or 2) of the state ``group``
    (its ``cursor1`` / ``cursor2``, rounded to 0.01 Hz within 0.01-1000 Hz); returns the
    cursor the next click places (1, 2, 1, ...; ``k`` again when the click hit no frequency)."""
    if x is None:
        return k
    f = min(max(round(float(x), 2), 0.01), 1000.0)
    setattr(group, f"cursor{k}", f)
    return 2 if k == 1 else 1
