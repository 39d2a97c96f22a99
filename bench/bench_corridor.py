"""A corridor study's cost, this checkout beside another (e.g. main), in one run.

Two figures, each measured in a fresh process per code tree, the trees alternating:

- **one variant rebuild**: ``variant_responses`` of one tire variant (inflation pressure)
  of the reference models, harmonic 4: the tire rebuilt at its operating points and the
  bushing response; CPU seconds (``time.process_time``) and wall seconds, after a warm-up
  (imports, the shipped tire, the compiled kernels);
- **the corridor example** of docs/corridor.md (``corridor_study`` of ``--parameters``,
  Saltelli, ``--n`` base rows): wall seconds and the CPU seconds of the process and its
  workers (``resource.getrusage``), with ``--processes`` worker processes where the tree
  has them (a tree without the option computes in its own process). The corridors of the
  trees are compared: the largest relative difference of their edges and percentiles.

    .venv/bin/python bench/bench_corridor.py --other /path/to/main-checkout \\
        [--n 16] [--processes 2] [--rebuilds 2] [--repeat 1] [--skip-study]

The machine may be shared: the load average is printed with every figure; CPU seconds are
what a busy machine distorts least.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]


def child(a: argparse.Namespace) -> None:
    import inspect

    import numpy as np

    import fbs_core
    import fbs_core.variants as fv

    out: dict[str, object] = {"root": str(Path(fbs_core.__file__).parents[1])}
    s = fv.VariantSettings()
    fv.variant_responses({}, s)  # warm: the shipped tire, the chassis, the kernels
    if a.child == "rebuild":
        rows = []
        for i in range(a.rebuilds):
            c, w = time.process_time(), time.perf_counter()
            fv.variant_responses({"inflation_pressure": 2.0e5 + 1000.0 * i}, s, fv.TireCache())
            rows.append((time.process_time() - c, time.perf_counter() - w))
        out["rebuild"] = rows
    else:
        kw = {}
        if "processes" in inspect.signature(fv.corridor_study).parameters:
            kw["processes"] = a.processes
        r0 = resource.getrusage(resource.RUSAGE_SELF)
        w = time.perf_counter()
        st = fv.corridor_study(a.parameters, n=a.n, method="saltelli", **kw)
        wall = time.perf_counter() - w
        r1 = resource.getrusage(resource.RUSAGE_SELF)
        rc = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime) + rc.ru_utime + rc.ru_stime
        c = st.corridor(4)
        np.savez(a.save, minimum=c.minimum, maximum=c.maximum, percentiles=c.percentiles)
        out.update(
            study_wall=wall, study_cpu=cpu, variants=st.design.n, processes=kw.get("processes", 1)
        )
    print(json.dumps(out))


def run(root: Path, mode: str, a: argparse.Namespace, save: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(root), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", mode, "--save", str(save)]
    cmd += ["--n", str(a.n), "--processes", str(a.processes), "--rebuilds", str(a.rebuilds)]
    cmd += ["--parameters", *a.parameters]
    load = os.getloadavg()[0]
    p = subprocess.run(cmd, env=env, cwd=root, capture_output=True, text=True, check=False)
    if p.returncode:
        raise SystemExit(f"{root}: {p.stderr[-2000:]}")
    d = json.loads(p.stdout.strip().splitlines()[-1])
    d["load"] = load
    return d


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--other", type=Path, help="another checkout (e.g. main) to measure beside")
    ap.add_argument("--parameters", nargs="+", default=["inflation_pressure", "knuckle_mass"])
    ap.add_argument("--n", type=int, default=16)
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--rebuilds", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--skip-study", action="store_true")
    ap.add_argument("--child", choices=["rebuild", "study"])
    ap.add_argument("--save", default="")
    a = ap.parse_args(argv)
    if a.child:
        child(a)
        return
    import numpy as np

    roots = [("this", HERE)] + ([("other", a.other.resolve())] if a.other else [])
    res: dict[str, list[dict]] = {k: [] for k, _ in roots}
    with tempfile.TemporaryDirectory(prefix="fbs-bench-corridor-") as d:
        for i in range(a.repeat):
            order = roots if i % 2 == 0 else roots[::-1]
            for mode in ["rebuild"] + ([] if a.skip_study else ["study"]):
                for name, root in order:
                    save = Path(d) / f"{name}.npz"
                    res[name].append(run(root, mode, a, save) | {"mode": mode})
        print("one variant rebuild (inflation pressure, reference tire, harmonic 4):")
        print(f"{'tree':<7}{'load':>6}{'CPU s':>8}{'wall s':>8}   root")
        for name, _ in roots:
            for r in res[name]:
                if r["mode"] == "rebuild":
                    for c, w in r["rebuild"]:
                        print(f"{name:<7}{r['load']:>6.1f}{c:>8.2f}{w:>8.2f}   {r['root']}")
        if not a.skip_study:
            print(
                f"\ncorridor example: {', '.join(a.parameters)}, saltelli n={a.n} "
                f"(target: README's 64 variants < 60 s on 2 cores):"
            )
            print(
                f"{'tree':<7}{'load':>6}{'variants':>9}{'processes':>10}{'wall s':>8}{'CPU s':>8}"
            )
            for name, _ in roots:
                for r in res[name]:
                    if r["mode"] == "study":
                        print(
                            f"{name:<7}{r['load']:>6.1f}{r['variants']:>9}{r['processes']:>10}"
                            f"{r['study_wall']:>8.1f}{r['study_cpu']:>8.1f}"
                        )
            if a.other:
                x, y = (np.load(Path(d) / f"{n}.npz") for n in ("this", "other"))
                rel = max(
                    float(np.max(np.abs(x[k] - y[k]) / np.abs(y[k])))
                    for k in ("minimum", "maximum", "percentiles")
                )
                print(f"corridor (edges and percentiles), largest relative difference: {rel:.2e}")


if __name__ == "__main__":
    main()
