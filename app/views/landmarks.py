"""The thesis' landmarks next to the reference tire's: a small read-only table.

The table is measured by ``fbs_core.tire.landmarks`` (each physics addition of the
reference tire switched off in turn, each mechanism behind table 5.1's trend switched) and
precomputed into ``data/landmarks.json`` by ``scripts/print_landmarks.py --json`` (the
measurement rebuilds several tires, minutes; the page only reads the file, once per
process).
"""

from __future__ import annotations

import functools
import json
from pathlib import Path
from typing import Any

import panel as pn

from fbs_core.tire.landmarks import FINDING, NOTES
from fbs_core.tire.storage import DATA_FILE

from .layout import font

__all__ = ["LANDMARKS_FILE", "load_landmarks", "landmarks_markdown", "landmarks_card"]

#: The precomputed table (written by ``scripts/print_landmarks.py --json``).
LANDMARKS_FILE = DATA_FILE.parent / "landmarks.json"

#: Readable names of the landmark keys.
LABELS = {
    "hub_peaks_hz": "free hub, case 1: peaks (Hz)",
    "bushing_z_peaks_hz": "bushing z, case 1: peaks (Hz)",
    "bushing_translation_largest": "largest bushing translation",
    "bushing_rotation_largest": "largest bushing rotation",
    "bushing_rz": "bushing rz",
    "table_5_1_130": "table 5.1: modes to 130 Hz, cases 1-7",
    "table_5_1_160": "table 5.1: modes to 160 Hz, cases 1-7",
    "fig_5_3_case5_z_160": "fig. 5.3: case 5 bushing z, modes to 160 Hz",
}


@functools.lru_cache(maxsize=4)
def load_landmarks(path: Path = LANDMARKS_FILE) -> dict[str, Any]:
    """The precomputed landmark and mechanism tables (read once per process)."""
    data: dict[str, Any] = json.loads(Path(path).read_text(encoding="utf-8"))
    for key in ("landmarks", "mechanisms"):
        if key not in data:
            raise ValueError(f"{path}: no '{key}' table; regenerate it with print_landmarks")
    return data


def _cell(text: object) -> str:
    return str(text).replace("|", "/").replace("\n", " ")


def landmarks_markdown(data: dict[str, Any]) -> str:
    """Both tables as Markdown: landmarks per column, then table 5.1 per mechanism."""
    lm = data["landmarks"]
    cols = list(lm["columns"])
    out = [
        "| landmark | thesis | " + " | ".join(cols) + " | mechanism (measured) |",
        "|---" * (len(cols) + 3) + "|",
    ]
    for i, key in enumerate(lm["keys"]):
        row = [LABELS.get(key, key), lm["thesis"][i]] + [lm["columns"][c][i] for c in cols]
        row.append(NOTES.get(key, ""))
        out.append("| " + " | ".join(_cell(x) for x in row) + " |")
    mech = data["mechanisms"]
    out += [
        "",
        "**Which mechanism drives table 5.1?** Suggested modes (eq. 5.1, 20 %) per variant:",
        "",
        "| variant | to 130 Hz, cases 1-7 | to 160 Hz, cases 1-7 | fig. 5.3 | patch (m) |",
        "|---|---|---|---|---|",
    ]
    for name, r in mech["rows"].items():
        out.append(
            f"| {_cell(name)} | {' '.join(map(str, r['table_130']))} | "
            f"{' '.join(map(str, r['table_160']))} | {r['case5_z_160']} | "
            f"{r['patch_length']:.3f} |"
        )
    if FINDING:
        out += ["", FINDING]
    return "\n".join(out)


def landmarks_card(parts: object = None) -> pn.Card:
    """A collapsed card with both tables (``parts``: the page's parts, unused)."""
    try:
        text = landmarks_markdown(load_landmarks())
    except (OSError, ValueError, KeyError) as exc:  # a missing or old file: say so
        text = f"The landmark table is not available ({exc})."
    return pn.Card(
        pn.pane.Markdown(text, sizing_mode="stretch_width", styles={"font-size": font("0.85em")}),
        title="The thesis' landmarks next to the reference tire",
        collapsible=True,
        collapsed=True,
        sizing_mode="stretch_width",
        header_background="#e9ecef",
        margin=(4, 4),
        css_classes=["landmarks-card"],
    )
