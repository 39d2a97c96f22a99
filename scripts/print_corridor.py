"""Print a corridor study of the reference models: the corridor beside the noise band, and
which parameter moves the bushing response most per frequency band (issue 32).

Usage (from the repository root)::

    .venv/bin/python scripts/print_corridor.py --parameters knuckle_mass body_bushing_stiffness \\
        --design saltelli --n 16 --harmonics 4
    .venv/bin/python scripts/print_corridor.py --parameters inflation_pressure tread_mass \\
        --design sobol --n 16 --speeds 20 30 40 50 60 70 80 90 100 110 120

Tire parameters rebuild the tire at every operating point (about 15 s per tire at the
reference's 43 points, fewer with ``--speeds``); chassis parameters cost well under a
second per variant. A Saltelli design of ``N`` base rows and ``k`` parameters has
``N (k + 2)`` variants, of which ``N (2 + k_tire)`` need a tire of their own.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import fbs_core  # noqa: E402
import fbs_core.variants as fv  # noqa: E402
from fbs_core.variants.report import corridor_text, sensitivity_text  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--parameters", nargs="+", default=["knuckle_mass", "body_bushing_stiffness"])
    ap.add_argument("--design", choices=fv.DESIGNS, default="saltelli")
    ap.add_argument("--n", type=int, default=16, help="variants (saltelli: base rows N)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--harmonics", type=int, nargs="+", default=[4])
    ap.add_argument("--speeds", type=float, nargs="+", help="operating points of rebuilt tires")
    ap.add_argument("--noise", type=float, default=0.05, help="noise band beside (0.05 = 5 %%)")
    ap.add_argument("--rounds", type=int, default=2000)
    a = ap.parse_args(argv)
    settings = fv.VariantSettings(
        harmonics=tuple(a.harmonics), speeds=None if a.speeds is None else tuple(a.speeds)
    )
    space = fv.ParameterSpace.from_names(a.parameters)
    design = fv.sample_design(space, a.n, a.design, a.seed)
    print(f"{a.design} design, seed {a.seed}: {design.n} variants of")
    for p in space.parameters:
        print(
            f"  {p.name:<30} {p.low:>10.4g} .. {p.high:<10.4g} {p.unit:<6} "
            f"(nominal {p.nominal():.4g})"
        )
    cache = fv.TireCache()
    t0 = time.perf_counter()

    def progress(done: int, total: int) -> None:
        sys.stderr.write(f"\r  {done}/{total} variants, {time.perf_counter() - t0:.0f} s")

    study = fv.run_variants(design, settings, cache=cache, progress=progress)
    sys.stderr.write("\n")
    print(
        f"computed in {time.perf_counter() - t0:.1f} s ({cache.builds} tires rebuilt, "
        f"{len(set(study.tire_keys))} distinct)"
    )
    for k in settings.harmonics:
        band = fbs_core.scatter_band(k, a.noise, "both", a.rounds, seed=a.seed)
        print()
        print(corridor_text(study.corridor(k), band))
        if a.design == "saltelli":
            print()
            print(sensitivity_text(study.sensitivity(k), ["bushing:x", "bushing:z", "bushing:ry"]))
    return 0


if __name__ == "__main__":
    np.set_printoptions(precision=3, suppress=True)
    raise SystemExit(main())
