"""A corridor campaign (issue 32) on 1 and 2 Dask worker processes: its scaling.

A ``[variants]`` study of ``--n`` variants (default 64, a scrambled Sobol' design) of tire
parameters (``--parameters``): every variant rebuilds the tire (its complex modes at every
operating point), one task each, plus one task for the nominal models. The same campaign,
each time with a fresh result file, runs on

- ``1 process``: a LocalCluster of one worker process (one thread);
- ``2 processes``: a LocalCluster of two worker processes (one thread each),

and the bench prints both wall times and their ratio (target: 2 processes in at most 0.6x
the time of one), and beside them the workers' CPU time of the tasks (recorded with every
task in the result file): a CPU share (CPU / wall of the tasks) well below 100 % means the
machine's cores were busy with other work during the run. The tire is rebuilt at
``--speeds`` (default every 20 km/h: about 3 s per variant on one core; ``--speeds
reference`` takes the shipped tire's 43 operating points, about 15 s per variant). Cluster
start-up is timed apart from the campaign.

    .venv/bin/python bench/bench_variants.py [--n 64] [--speeds 20 40 60 80 100 120] [--repeat 2]

The machine is shared: the load average is printed before each configuration; ratios
measured side by side in one run are what to compare.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # workers inherit it: one core each


def campaign_text(out: Path, args) -> str:
    speeds = "" if args.speeds == ["reference"] else f"speeds = {[float(v) for v in args.speeds]}"
    return f"""
[campaign]
name = "bench-variants"
seed = 32
output = "{out.as_posix()}"
[variants]
name = "bench"
parameters = {list(args.parameters)}
design = "{args.design}"
n = {args.n}
harmonics = {list(args.harmonics)}
{speeds}
"""


def run(label: str, workers: int, tmp: Path, args) -> dict:
    from distributed import Client, LocalCluster

    from fbs_core.campaign import parse_campaign, run_campaign

    tmp.mkdir(parents=True, exist_ok=True)
    camp = parse_campaign(campaign_text(tmp / "run.h5", args), tmp)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    with (
        LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address="127.0.0.1:0",
        ) as cluster,
        Client(cluster) as client,
    ):
        client.wait_for_workers(workers)
        start = time.perf_counter() - t0
        t1 = time.perf_counter()
        rep = run_campaign(camp, client=client)
        wall = time.perf_counter() - t1
    assert rep.status == "complete", rep
    import h5py

    with h5py.File(camp.output) as h:  # the workers' CPU time of every task
        g = h["cases"][camp.variants_cases[0].name]
        cpu = sum(float(u.attrs["cpu_seconds"]) for u in [g["nominal"], *g["tires"].values()])
    return {
        "label": label,
        "load": load,
        "start": start,
        "wall": wall,
        "tasks": rep.tasks_done,
        "task_seconds": rep.task_seconds,
        "cpu": cpu,
        "write": rep.write_seconds,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=64)
    ap.add_argument("--design", default="sobol")
    ap.add_argument(
        "--parameters",
        nargs="+",
        default=["inflation_pressure", "tread_mass", "sidewall_radial_stiffness"],
    )
    ap.add_argument("--harmonics", type=int, nargs="+", default=[4])
    ap.add_argument("--speeds", nargs="+", default=["20", "40", "60", "80", "100", "120"])
    ap.add_argument(
        "--repeat", type=int, default=1, help="runs of each configuration, in the order 1 2 2 1"
    )
    args = ap.parse_args(argv)
    order = [1, 2, 2, 1] * ((args.repeat + 1) // 2)
    rows = []
    with tempfile.TemporaryDirectory(prefix="fbs-bench-variants-") as d:
        tmp = Path(d)
        for i, w in enumerate(order[: 2 * args.repeat]):
            rows.append(run(f"{w} process{'es' if w > 1 else ''}", w, tmp / str(i), args))
    print(
        f"corridor campaign: {args.n} variants ({args.design}) of {', '.join(args.parameters)}; "
        f"harmonics {args.harmonics}; tire speeds {' '.join(args.speeds)} km/h"
    )
    print(
        f"{'configuration':<13}{'load':>6}{'start s':>9}{'wall s':>9}{'tasks':>7}"
        f"{'task s (sum)':>14}{'CPU s (sum)':>13}{'CPU share':>11}{'write s':>9}"
    )
    for r in rows:
        print(
            f"{r['label']:<13}{r['load']:>6.2f}{r['start']:>9.1f}{r['wall']:>9.1f}{r['tasks']:>7}"
            f"{r['task_seconds']:>14.1f}{r['cpu']:>13.1f}{r['cpu'] / r['task_seconds']:>11.0%}"
            f"{r['write']:>9.2f}"
        )
    one = min((r for r in rows if r["label"] == "1 process"), key=lambda r: r["wall"])
    two = min((r for r in rows if r["label"] == "2 processes"), key=lambda r: r["wall"])
    ratio = two["wall"] / one["wall"]
    print(
        f"2 processes / 1 process (campaign wall time, best of {args.repeat} each): "
        f"{ratio:.2f} (target <= 0.60)"
    )
    cpu = (two["wall"] / two["cpu"]) / (one["wall"] / one["cpu"])
    print(
        f"the same per CPU second of the tasks: {cpu:.2f} (a CPU share well below 100 %: the "
        "cores were busy with other work, the wall-time ratio says little)"
    )


if __name__ == "__main__":
    main()
