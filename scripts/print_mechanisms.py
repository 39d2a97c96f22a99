"""Which mechanism drives the thesis' table 5.1 trend? Each one switched, measured.

Usage (from the repository root)::

    .venv/bin/python scripts/print_mechanisms.py [variant ...]

Rebuilds the reference (loaded) tire and one variant per mechanism
(``fbs_core.tire.landmarks.MECHANISMS``: the round belt, the round belt with the loaded
patch length, the lumped patch load without the exp(jkx) modulation, twice the
circumferential orders) from physics, couples each to the reference chassis (6 DOFs)
and prints the suggested number of modes (eq. 5.1, 20 %, maximum over the bushing DOFs)
up to 130 and 160 Hz for the seven cases, and fig. 5.3's case 5 bushing z, next to the
thesis' numbers (the table in ``docs/tire-model.md`` is this output).
"""

from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from fbs_core.tire.landmarks import mechanism_table  # noqa: E402


def main(argv=None):
    names = (sys.argv[1:] if argv is None else argv) or None
    t0 = time.perf_counter()
    table = mechanism_table(names=names)
    print(table.text())
    print(f"\n({len(table.rows)} tires built and coupled in {time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main()
