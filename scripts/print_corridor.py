"""Print a corridor study of the reference models: the corridor beside the noise band, and
which parameter moves the bushing response most per frequency band (issue 32).

Usage (from the repository root)::

    .venv/bin/python scripts/print_corridor.py --parameters knuckle_mass body_bushing_stiffness \\
        --design saltelli --n 16 --harmonics 4
    .venv/bin/python scripts/print_corridor.py --parameters inflation_pressure tread_mass \\
        --design sobol --n 16 --speeds 20 30 40 50 60 70 80 90 100 110 120

Tire parameters rebuild the tire at every operating point the harmonics read (the
reference's 40 of 43 points from 27.5 km/h for 30-120 km/h; a few CPU seconds per tire,
fewer with ``--speeds``); chassis parameters cost well under a second per variant. A
Saltelli design of ``N`` base rows and ``k`` parameters has ``N (k + 2)`` variants, of which
``N (2 + k_tire)`` need a tire of their own. The tires are rebuilt in ``--processes``
worker processes (default: the machine's cores), or on a Dask cluster with ``--scheduler``
(or ``$FBS_DASK_SCHEDULER``); progress goes to stderr, one line per tire group.
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
    ap.add_argument(
        "--processes", type=int, default=os.cpu_count() or 1, help="worker processes (no Dask)"
    )
    ap.add_argument("--scheduler", help="address of a Dask scheduler to run the tires on")
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
    client = None
    addr = a.scheduler or os.environ.get("FBS_DASK_SCHEDULER")
    if addr:
        from fbs_core.campaign.run import make_client

        client, _ = make_client(addr)
    t0 = time.perf_counter()

    def progress(done: int, total: int) -> None:
        el = time.perf_counter() - t0
        eta = f", about {el * (total - done) / done:.0f} s to go" if 0 < done < total else ""
        sys.stderr.write(f"  {done}/{total} variants, {el:.0f} s{eta}\n")
        sys.stderr.flush()

    study = fv.run_variants(
        design, settings, cache=cache, progress=progress, client=client, processes=a.processes
    )
    where = f"Dask at {addr}" if client is not None else f"up to {a.processes} process(es)"
    print(
        f"computed in {time.perf_counter() - t0:.1f} s on {where} "
        f"({len(set(study.tire_keys))} distinct tires)"
    )
    if client is not None:
        client.close()
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
