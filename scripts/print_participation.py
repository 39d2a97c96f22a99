"""Which tire modes matter: ranked participation tables per harmonic and DOF (issue 30).

Usage: ``.venv/bin/python scripts/print_participation.py [--dof bushing:z] [--top 10]
[--harmonics 1 4 7] [--by loo] [--fmax 160]``

For every harmonic (the band up to ``--fmax``, default the whole band) and response DOF
(``--dof``; several allowed, ``max`` for the largest over the six), the modes ranked by
the measure ``--by`` (leave-one-out error by default): each mode's eigenfrequency where
the harmonic line comes closest to it and the speed there, its band share and level,
the leave-one-out error (both paths) and the direct path alone; with the tire's
matrices, the dominant belt family, ring order and direction of the mode's shape at
that speed.
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from fbs_core import harmonic, reference_tire  # noqa: E402
from fbs_core.analysis import mode_participation, tire_mode_shape  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dof", nargs="+", default=["bushing:z", "max"])
    ap.add_argument("--top", type=int, default=10)
    ap.add_argument("--harmonics", type=int, nargs="+", default=list(range(1, 8)))
    ap.add_argument("--by", default="loo")
    ap.add_argument("--fmax", type=float, default=None, help="upper end of the band, Hz")
    a = ap.parse_args()
    tire = reference_tire()
    for k in a.harmonics:
        h = harmonic(k)
        band = None if a.fmax is None else (h.freq_range[0], min(a.fmax, h.freq_range[1]))
        p = mode_participation(k, band)
        for dof in a.dof:
            d = None if dof == "max" else dof
            print(p.table(d, by=a.by, top=a.top))
            print("      shape of the top modes where the line meets them:")
            for m in p.ranking(a.by, d)[: min(a.top, 5)]:
                if p.first_order[m]:
                    print(f"      mode {m:3d}: first-order tread slip state")
                    continue
                sh = tire_mode_shape(int(m), float(p.mode_speed[m]), tire)
                print(
                    f"      mode {m:3d}: {sh.freq:6.1f} Hz at {sh.speed_kmh:5.1f} km/h, "
                    f"{sh.family} n={sh.order} {sh.direction} ({sh.share:.0%} of the belt), "
                    f"hub {sh.hub_share:.0%}"
                )
            print()


if __name__ == "__main__":
    main()
