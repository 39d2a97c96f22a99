"""The thesis' landmarks next to the reference tire's, each physics addition switched off.

Usage (from the repository root)::

    .venv/bin/python scripts/print_landmarks.py [--json data/landmarks.json]

Rebuilds the reference tire and one variant per physics addition (asymmetry, slip, the
static deflection) from physics, couples each to the reference chassis and prints the
thesis' hub peaks, case-1 bushing shapes, table 5.1 (130 and 160 Hz) and fig. 5.3's modes
for case 5 z (``fbs_core.tire.landmarks``; the table in ``docs/tire-model.md`` is this
output). With ``--json`` it also measures table 5.1 per mechanism
(``scripts/print_mechanisms.py``) and writes both tables for the dashboard.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from fbs_core.tire.landmarks import landmark_table, mechanism_table  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path, help="also write both tables to this JSON file")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    table = landmark_table()
    print(table.text())
    print(f"\n({len(table.columns)} tires built and coupled in {time.perf_counter() - t0:.1f} s)")
    if args.json:
        mech = mechanism_table()
        print()
        print(mech.text())
        data = {"landmarks": table.to_dict(), "mechanisms": mech.to_dict()}
        args.json.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
        print(f"\nwrote {args.json} in {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
