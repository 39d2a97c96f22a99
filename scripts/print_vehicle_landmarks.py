"""Print the reference car's landmarks beside the ranges published for mid-size cars.

Usage::

    .venv/bin/python scripts/print_vehicle_landmarks.py

Modes: the trimmed body alone (free-free) and the car on its tires (the tires
condensed onto their hubs at standstill), identified by their shapes
(fbs_core/vehicle/landmarks.py); then geometry, mass and inertias. Sources and how
the derived ranges are derived: docs/vehicle-model.md.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fbs_core.vehicle.landmarks import landmark_table, mass_properties  # noqa: E402


def main() -> int:
    rows = landmark_table()
    print(f"{'landmark':34s} {'model':>8s}   {'published range':>15s}   source")
    for r in rows:
        flag = "" if r.inside else "  <- outside"
        print(
            f"{r.name:34s} {r.frequency:6.2f} Hz   {r.low:6.1f}-{r.high:5.1f} Hz   {r.source}{flag}"
        )
    print()
    print(f"{'mass property':34s} {'model':>8s}   {'published range':>15s}   source")
    for r in mass_properties():
        flag = "" if r.inside else "  <- outside"
        print(f"{r.name:34s} {r.frequency:8.4g}   {r.low:7.4g}-{r.high:7.4g}   {r.source}{flag}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
