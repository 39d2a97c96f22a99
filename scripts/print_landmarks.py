"""The thesis' landmarks next to the reference tire's, each physics addition switched off.

Usage (from the repository root)::

    .venv/bin/python scripts/print_landmarks.py

Rebuilds the reference tire and one variant per physics addition (asymmetry, ...)
from physics, couples each to the reference chassis and prints the thesis' hub peaks,
case-1 bushing shapes, table 5.1 (130 and 160 Hz) and fig. 5.3's modes for case 5 z
(``fbs_core.tire.landmarks``; the table in ``docs/tire-model.md`` is this output).
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from fbs_core.tire.landmarks import landmark_table  # noqa: E402


def main():
    t0 = time.perf_counter()
    table = landmark_table()
    print(table.text())
    print(f"\n({len(table.columns)} tires built and coupled in {time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main()
