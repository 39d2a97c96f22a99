"""Campaign throughput on Dask: in-process, 1 and 2 worker processes; task cost and overhead.

Runs one campaign - all 7 harmonics x noise 1/2/5/10/20 % x targets tire/chassis/both
(105 scatter cases), frequency-independent noise - with the rounds reduced from the
issue's 100,000 to ``--rounds`` (default 2,000) so that each configuration takes a minute
or less on two cores; the work per round is the same, so rounds/s carry over (the band
statistics' sort grows as R log R, a few % of the cost). Each configuration gets the same
campaign with a fresh result file, after a warm-up (fbs_core imported and the compiled
kernels loaded in every worker), timed from the call of ``run_campaign`` to its return
(the result file complete, its final merge included):

- ``in-process``: the default of ``python -m fbs_core.campaign run``: one worker thread in
  this process, the compiled kernels on all cores;
- ``1 process`` / ``2 processes``: LocalCluster worker processes, one core each (one
  kernel thread per worker), so efficiency = throughput(2) / (2 x throughput(1));
- ``plain``: the same cases as plain :func:`fbs_core.studies.scatter_band_arrays` calls in
  this process (the inputs of each harmonic prepared once, as the campaign does), the kernels
  on all cores: the in-process campaign's efficiency = plain time / in-process time.

Then it measures the scheduler's cost per task with a flood of empty tasks on the
2-process cluster, and projects the task size that keeps the overhead under 5 % on 100
workers (docs/deployment.md, "Campaigns on Dask").

    .venv/bin/python bench/bench_campaign.py [--rounds 2000] [--task-seconds 1.0]

The machine is shared: ratios measured side by side in one run are what to compare.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

NOISE = [0.01, 0.02, 0.05, 0.10, 0.20]


def campaign_text(out: Path, rounds: int, harmonics, task_round_lines: int) -> str:
    return f"""
[campaign]
name = "bench"
seed = 19
output = "{out.as_posix()}"
[scatter]
harmonics = {list(harmonics)}
noise = {NOISE}
targets = ["tire", "chassis", "both"]
rounds = {rounds}
[execution]
task_round_lines = {task_round_lines}
"""


def _noop(i):
    return i


def scheduler_overhead(client, n: int) -> float:
    """Seconds per empty task: submit ``n`` of them and gather with as_completed."""
    from distributed import as_completed

    futs = client.map(_noop, range(n), pure=False)  # warm-up of the graph path
    for _ in as_completed(futs):
        pass
    del futs
    t0 = time.perf_counter()
    futs = client.map(_noop, range(n), key=[f"noop-{i}-b" for i in range(n)], pure=False)
    for f in as_completed(futs):
        f.release()
    return (time.perf_counter() - t0) / n


def run_plain(camp) -> float:
    """Seconds of the campaign's scatter cases as plain scatter_band_arrays calls (inputs of
    each harmonic prepared once, as the campaign does)."""
    from fbs_core.campaign import work
    from fbs_core.studies import scatter_band_arrays

    t0 = time.perf_counter()
    inputs = {}
    for c in camp.band_cases:
        inp = inputs.get(c.inputs_name)
        if inp is None:
            inp = inputs[c.inputs_name] = work.prepare_inputs(
                c.tire, c.chassis, c.harmonic, c.n_modes, c.coupling, c.df
            )
        scatter_band_arrays(
            inp.YjjA,
            inp.vj,
            inp.YjjE,
            inp.YejE,
            c.noise,
            c.target,
            c.rounds,
            c.frequency_dependent,
            seed=c.seed,
            percentiles=c.percentiles,
        )
    return time.perf_counter() - t0


def _warm_worker(threads):
    """A small band block on this worker: fbs_core imported and the kernels loaded."""
    from fbs_core.campaign import work

    inp = work.prepare_inputs("reference", "reference", 1, None, "6dof", 0.5)
    work.band_blocks(inp, [(0.1, "both", 50, False, 1, (5.0, 95.0), 0, 2)], 64e6, threads)


def run_config(label, client, workers, threads, tmp, args):
    """``(report, wall)`` of the campaign on ``client`` after a warm-up of every worker;
    ``wall``: run_campaign's call, up to the result file complete (the final merge of the
    parts included, which ``report.seconds`` leaves out)."""
    from fbs_core.campaign import parse_campaign, run_campaign

    warm = parse_campaign(campaign_text(tmp / f"warm-{label}.h5", 50, [1], 10**9), tmp)
    run_campaign(warm, client=client, numba_threads=threads)
    # the warm-up campaign is one task (its blocks go together): it warms one worker only
    client.run(_warm_worker, threads)
    camp = parse_campaign(
        campaign_text(tmp / f"{label}.h5", args.rounds, args.harmonics, args.task_round_lines),
        tmp,
    )
    t0 = time.perf_counter()
    rep = run_campaign(camp, client=client, numba_threads=threads)
    wall = time.perf_counter() - t0
    assert rep.status == "complete", rep.errors
    return rep, wall


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--rounds", type=int, default=2000)
    p.add_argument("--harmonics", type=int, nargs="+", default=[1, 2, 3, 4, 5, 6, 7])
    p.add_argument(
        "--task-round-lines",
        type=int,
        default=2_000_000,
        help="work per task (rounds x lines); default about 1 s on one core",
    )
    p.add_argument("--noop-tasks", type=int, default=2000)
    p.add_argument("--configs", nargs="+", default=["plain", "in-process", "1", "2"])
    args = p.parse_args(argv)

    from distributed import Client, LocalCluster

    from fbs_core.campaign import parse_campaign, plan
    from fbs_core.campaign.run import n_lines

    tmp = Path(tempfile.mkdtemp(prefix="bench-campaign-"))
    camp = parse_campaign(
        campaign_text(tmp / "x.h5", args.rounds, args.harmonics, args.task_round_lines), tmp
    )
    tasks, _ = plan(camp)
    work = sum(t.work for t in tasks)
    total_rounds = sum(c.rounds for c in camp.band_cases)
    print(
        f"campaign: {len(camp.band_cases)} scatter cases (harmonics {args.harmonics}, "
        f"5 noise levels, 3 targets) x {args.rounds} rounds = {total_rounds:,} rounds, "
        f"{work:.3g} round-lines, {len(tasks)} tasks of <= {args.task_round_lines:.2g} "
        f"round-lines; {os.cpu_count()} cores (machine shared with other jobs)"
    )
    rows = {}
    overhead = None
    plain_s = None
    for cfg in args.configs:
        if cfg == "plain":
            warm = parse_campaign(campaign_text(tmp / "warm-plain.h5", 50, [1], 10**9), tmp)
            run_plain(warm)  # compiled kernels loaded
            plain_s = run_plain(camp)
            continue
        t0 = time.perf_counter()
        if cfg == "in-process":
            cluster = LocalCluster(
                n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0"
            )
            n, threads = 1, None
        else:
            n = int(cfg)
            cluster = LocalCluster(
                n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0"
            )
            threads = 1
        with cluster, Client(cluster) as client:
            client.wait_for_workers(n)
            start = time.perf_counter() - t0
            rep, wall = run_config(cfg.replace(" ", ""), client, n, threads, tmp, args)
            if cfg != "in-process" and n == max(int(c) for c in args.configs if c.isdigit()):
                overhead = (n, scheduler_overhead(client, args.noop_tasks))
        rows[cfg] = (n, rep, start, wall)

    print()
    hdr = (
        f"{'configuration':<14s} {'workers':>7s} {'tasks':>6s} {'wall s':>8s} "
        f"{'rounds/s':>10s} {'Mround-lines/s':>15s} {'task s (mean)':>14s} "
        f"{'overhead/task s':>16s} {'speedup':>8s} {'efficiency':>10s}"
    )
    print(hdr)
    print("-" * len(hdr))
    base = rows.get("1")
    for cfg, (n, rep, _start, wall) in rows.items():
        rate = rep.rounds_done / wall
        rl = work / wall / 1e6
        mean_task = rep.task_seconds / max(1, rep.tasks_done)
        # wall time of all worker slots not spent computing, per task
        ovh = (rep.compute_wall * n - rep.task_seconds) / max(1, rep.tasks_done)
        if base and cfg != "in-process":
            sp = base[3] / wall
            eff = f"{sp / n:10.2f}"
            sp = f"{sp:8.2f}"
        else:
            sp, eff = f"{'-':>8s}", f"{'-':>10s}"
        print(
            f"{cfg:<14s} {n:>7d} {rep.tasks_done:>6d} {wall:8.1f} {rate:10,.0f} "
            f"{rl:15.2f} {mean_task:14.3f} {ovh:16.4f} {sp} {eff}"
        )
    if plain_s is not None:
        print(
            f"{'plain calls':<14s} {1:>7d} {len(camp.band_cases):>6d} {plain_s:8.1f} "
            f"{total_rounds / plain_s:10,.0f} {work / plain_s / 1e6:15.2f}"
        )
        if "in-process" in rows:
            ip = rows["in-process"][3]
            print(
                f"\nin-process campaign against plain scatter_band calls (both on all cores): "
                f"{plain_s:.1f} s / {ip:.1f} s = {plain_s / ip:.2f} (issue 33: >= 0.9)"
            )
    print()
    for cfg, (_n, rep, start, wall) in rows.items():
        print(
            f"{cfg}: cluster start {start:.1f} s; run {wall:.1f} s (to the result file "
            f"complete; {wall - rep.seconds:.2f} s of it the checks before the run and the "
            f"final merge) of which tasks "
            f"submitted to last result {rep.compute_wall:.1f} s; client-side writes "
            f"{rep.write_seconds:.2f} s "
            f"({1e3 * rep.write_seconds / max(1, rep.tasks_done):.1f} ms per task)"
        )
    if base is None or overhead is None:
        return
    n1, rep1, _, _ = base
    c = rep1.task_seconds / work  # seconds per round-line on one core
    n_ov, o_s = overhead
    o_w = max(0.0, (rep1.compute_wall - rep1.task_seconds) / rep1.tasks_done)
    o_c = rep1.write_seconds / rep1.tasks_done
    print(
        f"\nper-task cost: {1e9 * c:.0f} ns per round-line on one core "
        f"({c * 100_000 * 1e6:.0f} us per line at 100,000 rounds); "
        f"scheduler + client per empty task ({n_ov} workers, {args.noop_tasks} tasks): "
        f"{1e3 * o_s:.2f} ms; per-task overhead on 1 worker {1e3 * o_w:.1f} ms "
        f"(of which writing {1e3 * o_c:.1f} ms)"
    )
    print("projection (overhead < 5 %: worker side o_w / T and central side W o / T each <= 5 %):")
    # the campaign: 7 harmonics x 15 cases x 100,000 rounds over each grid's lines
    full = 15 * 100_000 * sum(n_lines(k, 0.5) for k in range(1, 8))
    for w in (2, 10, 100):
        central = max(o_s, o_c)
        t_min = max(20 * o_w, 20 * w * central)
        trl = t_min / c
        wall = full * c / w / 0.95
        print(
            f"  {w:>3d} workers: task >= {t_min:6.2f} s = {trl:12,.0f} round-lines "
            f"({trl / 100_000:6.0f} lines at R = 100,000); the issue's campaign "
            f"({full:.3g} round-lines): {full * c / t_min:6.0f} tasks of that size, ~{wall:7.0f} s"
        )
    print(f"\nresult files in {tmp}")


if __name__ == "__main__":
    main()
