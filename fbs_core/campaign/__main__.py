"""Command line of the campaigns: ``python -m fbs_core.campaign {run,summary,plan,corridor}``.

``run`` shows a progress bar (tasks done/total, rounds per second, time left); Ctrl-C
stops cleanly (running tasks are cancelled, finished ones are in the result file) and the
same command resumes. Exit status: 0 complete, 1 some tasks failed, 2 bad input, 130
stopped.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from collections.abc import Sequence
from types import FrameType

from .browse import open_campaign
from .run import SCHEDULER_ENV, WRITING, n_lines, plan, run_campaign
from .spec import BandCase, CampaignError, load_campaign
from .variants import VariantsCase


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m fbs_core.campaign", description=__doc__)
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="run or resume a campaign")
    r.add_argument("campaign", help="campaign file (TOML)")
    r.add_argument(
        "--scheduler",
        help=f"address of an existing Dask scheduler (default ${SCHEDULER_ENV}, else a "
        "LocalCluster on this machine)",
    )
    r.add_argument(
        "--workers",
        type=int,
        help="worker processes of the LocalCluster (default: one in-process worker)",
    )
    r.add_argument("--output", help="result file (default: the campaign's output)")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    s = sub.add_parser("summary", help="list the cases of a result file")
    s.add_argument("result", help="campaign result file (HDF5)")
    pl = sub.add_parser("plan", help="list the cases and tasks of a campaign without running")
    pl.add_argument("campaign")
    co = sub.add_parser("corridor", help="corridor and sensitivity tables of a variants study")
    co.add_argument("result", help="campaign result file (HDF5)")
    co.add_argument("--case", help="the variants case (default: all)")
    co.add_argument("--harmonic", type=int, help="one harmonic (default: all of the study)")
    co.add_argument("--dofs", nargs="+", help="DOFs of the sensitivity tables (default: all)")
    return p


def _corridor(args: argparse.Namespace) -> int:
    from ..variants.report import corridor_text, sensitivity_text

    res = open_campaign(args.result)
    cases = [c for c in res.cases if c.kind == "variants"]
    if args.case is not None:
        cases = [res.case(args.case)]
    if not cases:
        raise CampaignError(f"{args.result} holds no variants study")
    for c in cases:
        st = res.variants(c.name)
        print(f"{c.name}: {c.label()}")
        for k in [args.harmonic] if args.harmonic is not None else st.settings.harmonics:
            print(corridor_text(st.corridor(k, c.settings["percentiles"])))
            if st.design.method == "saltelli":
                print(sensitivity_text(st.sensitivity(k), args.dofs))
    return 0


def _plan(path: str) -> int:
    c = load_campaign(path)
    tasks, _ = plan(c)
    band = [x for x in tasks if x.kind == "band"]
    rl = sum(x.work for x in band)
    print(f"campaign {c.name!r}: {len(c.cases)} cases -> {c.output}")
    print(
        f"  {len(c.band_cases)} scatter cases, {len(c.truncation_cases)} truncation cases; "
        f"{len(tasks)} tasks ({len(band)} band blocks, {rl:.3g} round-lines)"
    )
    for case in c.cases:
        if isinstance(case, BandCase):
            nl = n_lines(case.harmonic, case.df)
            nb = sum(1 for x in band if x.case is case)
            print(f"  {case.name}  {nl} lines in {nb} tasks  seed={case.seed}")
        elif isinstance(case, VariantsCase):
            mine = [x for x in tasks if x.case is case]
            nv = sum(len(x.rows) for x in mine)
            print(f"  {case.name}  {nv} variants in {len(mine)} tasks (by tire)  seed={case.seed}")
        else:
            print(f"  {case.name}")
    return 0


def _run(args: argparse.Namespace) -> int:
    c = load_campaign(args.campaign)
    stop = threading.Event()

    def interrupt(signum: int, frame: FrameType | None) -> None:
        # Ctrl-C / SIGTERM: stop; a task result being written is finished first
        stop.set()
        if not WRITING.is_set():
            raise KeyboardInterrupt

    previous = {}
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            previous[sig] = signal.signal(sig, interrupt)
    print(f"campaign {c.name!r}: {len(c.cases)} cases -> {args.output or c.output}")
    try:
        report = run_campaign(
            c,
            scheduler=args.scheduler,
            workers=args.workers,
            output=args.output,
            progress=not args.quiet,
            stop=stop,
        )
    finally:
        # the caller's handlers again (main() called in-process must not leave its own)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    print()
    print(
        f"{report.status}: {report.tasks_done} tasks done this run, {report.tasks_skipped} "
        f"done before, of {report.tasks_total}; {report.rounds_done:,.0f} rounds in "
        f"{report.seconds:.1f} s ({report.rounds_per_second:,.0f} rounds/s) on "
        f"{report.workers} worker(s) at {report.scheduler or '-'}"
    )
    for unit, msg in report.errors:
        print(f"  FAILED {unit}: {msg}")
    if report.status == "stopped":
        print("stopped: finished tasks are saved; run the same command again to resume")
        return 130
    print(open_campaign(report.output).summary())
    return 1 if report.errors else 0


def main(argv: Sequence[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.cmd == "summary":
            print(open_campaign(args.result).summary())
            return 0
        if args.cmd == "plan":
            return _plan(args.campaign)
        if args.cmd == "corridor":
            return _corridor(args)
        return _run(args)
    except CampaignError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\nstopped", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
