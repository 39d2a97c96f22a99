"""Running a campaign on a ``dask.distributed`` cluster.

The cluster: an existing one when a scheduler address is given (``scheduler=`` or the
environment variable ``FBS_DASK_SCHEDULER``, e.g. ``tcp://host:8786``), else a
:class:`distributed.LocalCluster` started here and closed at the end: by default one
in-process worker (threads of this process; the compiled kernels use all cores, as
:func:`fbs_core.scatter_band` does), with ``workers=N`` N worker processes.

The work: model variants read from files are sent to the workers once
(``client.scatter(..., broadcast=True)``); the subsystem arrays of every (harmonic, models,
coupling) are one task whose result stays on the cluster and feeds the band blocks of all
cases that use it; every scatter case is split into blocks of lines holding
``task_round_lines`` (rounds x lines) of work (see :mod:`.work` for why lines); every
truncation case is one task. Results are gathered with ``as_completed`` as they finish,
each written at once as a unit of the result file (:mod:`.store`), so that a stop (Ctrl-C,
``stop`` event, a killed process) loses at most the tasks in flight and a rerun computes
only what is missing.
"""

from __future__ import annotations

import math
import os
import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import IO, TYPE_CHECKING, Any

import numpy as np

import fbs_core

from . import variants as _variants
from . import work
from .spec import BandCase, Campaign, CampaignError, TruncationCase
from .store import CampaignStore, file_sha256

if TYPE_CHECKING:
    from ..frf import FRF
    from .variants import VariantsCase

__all__ = [
    "Task",
    "plan",
    "group_blocks",
    "run_campaign",
    "RunReport",
    "make_client",
    "SCHEDULER_ENV",
]

SCHEDULER_ENV = "FBS_DASK_SCHEDULER"

#: Set while a finished task is being written: a Ctrl-C handler then only sets the stop
#: event (the command line's handler), so that no write is cut short.
WRITING = threading.Event()


@dataclass(frozen=True)
class Task:
    """One unit of work: ``kind`` is "band", "truncation" or "variants" (the design's
    ``rows`` sharing one tire, none: the nominal models)."""

    kind: str
    unit: str
    case: BandCase | TruncationCase | VariantsCase
    l0: int = 0
    l1: int = 0
    inputs: str = ""
    rounds: float = 0.0  # rounds of its case this task computes (lines / n_lines x R)
    work: float = 0.0  # rounds x lines
    rows: tuple[int, ...] = ()


@dataclass
class RunReport:
    """What a run did. ``status``: "complete", "stopped" or "failed"."""

    output: str
    status: str
    tasks_total: int
    tasks_skipped: int
    tasks_done: int
    rounds_done: float
    seconds: float
    errors: list[tuple[str, str]] = field(default_factory=list)
    scheduler: str = ""
    workers: int = 0
    task_seconds: float = 0.0  # compute time of the finished tasks, summed (on the workers)
    write_seconds: float = 0.0  # time this process spent writing their results
    compute_wall: float = 0.0  # from the first task submitted to the last result written

    @property
    def rounds_per_second(self) -> float:
        return self.rounds_done / self.seconds if self.seconds > 0 else 0.0


def n_lines(harmonic: int, df: float) -> int:
    from ..harmonics import harmonic as _h

    return int(_h(harmonic).frequencies(df).size)


def block_lines(rounds: int, lines: int, task_round_lines: int) -> int:
    """Lines per task so that a task holds about ``task_round_lines`` of work, with the
    blocks of a case of equal size (at most one line apart)."""
    per = max(1, min(lines, task_round_lines // max(1, rounds)))
    nb = math.ceil(lines / per)
    return math.ceil(lines / nb)


def _missing_runs(lines: int, covered: list[tuple[int, int]]) -> list[tuple[int, int]]:
    mask = np.ones(lines, bool)
    for a, b in covered:
        mask[a:b] = False
    runs, i = [], 0
    while i < lines:
        if mask[i]:
            j = i
            while j < lines and mask[j]:
                j += 1
            runs.append((i, j))
            i = j
        else:
            i += 1
    return runs


def plan(campaign: Campaign, done: set[str] | None = None) -> tuple[list[Task], int]:
    """The tasks still to do, and the number of tasks already done.

    A scatter case's missing lines (not covered by stored blocks) are split into blocks of
    :func:`block_lines`; a truncation case is one task.
    """
    done = done or set()
    covered: dict[str, list[tuple[int, int]]] = {}
    n_done = 0
    for u in done:
        parts = u.split("/")
        if len(parts) == 4 and parts[0] == "cases" and parts[2] == "blocks":
            sa, sb = parts[3].split("_")
            covered.setdefault(parts[1], []).append((int(sa), int(sb)))
    tasks: list[Task] = []
    for c in campaign.cases:
        if isinstance(c, _variants.VariantsCase):  # a corridor study: a task per tire
            for unit, rows in _variants.groups(c):
                if unit in done:
                    n_done += 1
                else:
                    w = max(1, len(rows)) * _variants.VARIANT_WORK
                    tasks.append(Task("variants", unit, c, rows=tuple(rows), work=w))
            continue
        if isinstance(c, TruncationCase):
            unit = f"cases/{c.name}/result"
            if unit in done:
                n_done += 1
            else:
                tasks.append(Task("truncation", unit, c))
            continue
        nl = n_lines(c.harmonic, c.df)
        have = covered.get(c.name, [])
        n_done += len(have)
        per = block_lines(c.rounds, nl, campaign.task_round_lines)
        for a, b in _missing_runs(nl, have):
            for l0 in range(a, b, per):
                l1 = min(b, l0 + per)
                tasks.append(
                    Task(
                        "band",
                        f"cases/{c.name}/blocks/{l0}_{l1}",
                        c,
                        l0,
                        l1,
                        c.inputs_name,
                        c.rounds * (l1 - l0) / nl,
                        float(c.rounds) * (l1 - l0),
                    )
                )
    return tasks, n_done


def group_blocks(tasks: list[Task], task_round_lines: float) -> list[list[Task]]:
    """The tasks as they are sent to the cluster: band blocks of cases that share their
    subsystem arrays go together, in order, while their work (rounds x lines) stays within
    ``task_round_lines``; every other task alone.

    A block is a case's lines cut to about ``task_round_lines`` (:func:`block_lines`), but a
    case of few rounds is smaller than that whole: at 2,000 rounds a case was a task of
    0.04-0.07 s, where Dask's cost per task (~1.6 ms on the scheduler and client, ~5 ms of
    writing on the client, beside the workers on the same cores) took a quarter of two
    workers' throughput (``bench/bench_campaign.py``). Each block keeps its own unit and
    result (:func:`.work.band_blocks`).
    """
    groups: list[list[Task]] = []
    open_: dict[str, list[Task]] = {}  # the group still filling, by subsystem arrays
    for t in tasks:
        if t.kind != "band":
            groups.append([t])
            continue
        g = open_.get(t.inputs)
        if g is not None and sum(x.work for x in g) + t.work <= task_round_lines:
            g.append(t)
            continue
        g = [t]
        groups.append(g)
        open_[t.inputs] = g
    return groups


def make_client(scheduler: str | None = None, workers: int | None = None) -> tuple[Any, Any]:
    """``(client, cluster)``: join ``scheduler`` (or ``$FBS_DASK_SCHEDULER``), else start a
    LocalCluster (in-process with one worker thread, or ``workers`` worker processes);
    ``cluster`` is None when joining an existing one."""
    from distributed import Client, LocalCluster

    addr = scheduler or os.environ.get(SCHEDULER_ENV) or None
    if addr:
        try:
            return Client(addr, timeout="30s"), None
        except OSError as e:
            raise CampaignError(f"cannot reach the Dask scheduler at {addr}: {e}") from None
    if workers:
        # the scheduler, the workers and the diagnostics dashboard on the loopback
        # interface only: a Dask scheduler runs what any client that reaches it sends
        cluster = LocalCluster(
            n_workers=int(workers),
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address="127.0.0.1:0",
        )
    else:
        cluster = LocalCluster(
            n_workers=1,
            threads_per_worker=1,
            processes=False,
            dashboard_address="127.0.0.1:0",
        )
    return Client(cluster), cluster


def _versions() -> dict[str, str]:
    import h5py
    import numba
    import scipy

    import fbs_core

    out = {
        "fbs_core": fbs_core.__version__,
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
        "h5py": h5py.__version__,
    }
    try:
        import dask
        import distributed

        out["dask"] = dask.__version__
        out["distributed"] = distributed.__version__
    except ImportError:  # pragma: no cover - a dependency
        pass
    return out


def _root_attrs(campaign: Campaign) -> dict[str, Any]:
    return {
        "campaign_name": campaign.name,
        "campaign_seed": campaign.seed,
        "seeds": campaign.seeds,
        "campaign_toml": campaign.text,
    }


def _model_units(campaign: Campaign, store: CampaignStore, done: set[str]) -> None:
    for kind, variants in (("tire", campaign.tires), ("chassis", campaign.chassis)):
        for name, src in variants.items():
            unit = f"models/{kind}/{name}"
            sha = "" if src == "reference" else file_sha256(src)
            if unit in done:
                old = store.unit_attrs(unit) or {}
                if (str(old.get("source")), str(old.get("sha256"))) != (src, sha):
                    raise CampaignError(
                        f"{store.output} was computed with {kind} variant {name!r} from "
                        f"{old.get('source')} (sha256 {str(old.get('sha256'))[:12]}...), now "
                        f"{src} ({sha[:12] or '-'}): a changed model needs a new output file"
                    )
                continue
            store.write_unit(unit, {}, {"source": src, "sha256": sha})


def _case_attrs(c: BandCase | TruncationCase) -> dict[str, Any]:
    attrs: dict[str, Any] = {
        "kind": c.kind,
        "name": c.name,
        "digest": c.digest(),
        "settings": c.settings(),
        "harmonic": c.harmonic,
        "coupling": c.coupling,
        "tire": c.tire,
        "chassis": c.chassis,
    }
    if isinstance(c, BandCase):
        attrs.update(
            noise=c.noise,
            target=c.target,
            frequency_dependent=c.frequency_dependent,
            rounds=c.rounds,
            seed=str(c.seed),  # up to 2**64 - 1: text, exact
            n_lines=n_lines(c.harmonic, c.df),
            inputs=c.inputs_name,
        )
    return attrs


def _write_inputs(store: CampaignStore, name: str, c: BandCase, inp: work.BandInputs) -> None:
    data = {
        "freq": inp.freq,
        "YjjA": inp.YjjA,
        "vj": inp.vj,
        "YjjE": inp.YjjE,
        "YejE": inp.YejE,
        "reference": inp.reference,
    }
    attrs = {
        "dofs": list(inp.dofs),
        "harmonic": c.harmonic,
        "n_modes": "all" if c.n_modes is None else c.n_modes,
        "n_modes_total": inp.n_modes_total,
        "coupling": c.coupling,
        "tire": c.tire,
        "chassis": c.chassis,
        "df": c.df,
    }
    store.write_unit(f"inputs/{name}", data, attrs)


def _write(store: CampaignStore, campaign: Campaign, t: Task, res: dict[str, Any]) -> None:
    if t.kind == "variants":
        assert isinstance(t.case, _variants.VariantsCase)
        _variants.write_result(store, t.case, t.unit, list(t.rows), res)
        return
    assert isinstance(t.case, BandCase | TruncationCase)
    parents = {f"cases/{t.case.name}": _case_attrs(t.case)}
    prov: dict[str, Any] = {k: res.pop(k) for k in ("worker", "host", "pid", "seconds") if k in res}
    if t.kind == "band":
        assert isinstance(t.case, BandCase)
        out = campaign.outputs["scatter"]
        keys: list[str] = []
        if "band" in out:
            keys += ["lower", "upper", "argmin_round", "argmax_round"]
        if "percentiles" in out:
            keys += ["percentiles"]
        if "convergence" in out:
            keys += ["checkpoints", "conv_lower", "conv_upper"]
        attrs: dict[str, Any] = {
            "l0": res["l0"],
            "l1": res["l1"],
            "q": list(t.case.percentiles),
            **prov,
        }
        store.write_unit(t.unit, {k: res[k] for k in keys}, attrs, parents)
    else:
        out = campaign.outputs["truncation"]
        keys = ["n_modes", "centres"]
        if "error" in out:
            keys += ["error"]
        if "suggested" in out:
            keys += ["suggested"]
        if "responses" in out:
            keys += ["freq", "response", "reference"]
        c = t.case
        assert isinstance(c, TruncationCase)
        attrs = {
            "dofs": list(res["dofs"]),
            "n_modes_total": res["n_modes_total"],
            "thresholds": list(c.thresholds),
            "f_max": list(c.f_max),
            "width": res["width"],
            "step": res["step"],
            "edges": res["edges"],
            **prov,
        }
        store.write_unit(t.unit, {k: res[k] for k in keys}, attrs, parents)


class Progress:
    """Text progress bar: tasks done/total, rounds per second, time left (to a stream).

    The time left is projected from the work (rounds x lines) done and left, not from the
    rounds: a round of a harmonic with many lines costs more than one with few.
    """

    def __init__(
        self, total: int, work_total: float, stream: IO[str] | None = None, every: float = 0.5
    ) -> None:
        import sys

        self.total, self.work_total = total, work_total
        self.stream = sys.stderr if stream is None else stream
        self.every = every
        self.t0 = time.perf_counter()
        self.last = 0.0
        self.done = 0
        self.rounds = 0.0
        self.work = 0.0

    def line(self) -> str:
        dt = time.perf_counter() - self.t0
        rate = self.rounds / dt if dt > 0 else 0.0
        wrate = self.work / dt if dt > 0 else 0.0
        left = (self.work_total - self.work) / wrate if wrate > 0 else float("nan")
        frac = self.done / self.total if self.total else 1.0
        bar = "#" * int(30 * frac) + "-" * (30 - int(30 * frac))
        eta = "--:--" if not np.isfinite(left) else time.strftime("%H:%M:%S", time.gmtime(left))
        return (
            f"[{bar}] {self.done}/{self.total} tasks  {rate:,.0f} rounds/s  "
            f"elapsed {time.strftime('%H:%M:%S', time.gmtime(dt))}  left {eta}"
        )

    def update(
        self, tasks: int = 1, rounds: float = 0.0, work: float = 0.0, force: bool = False
    ) -> None:
        self.done += tasks
        self.rounds += rounds
        self.work += work
        now = time.perf_counter()
        if force or now - self.last >= self.every or self.done == self.total:
            self.last = now
            end = "\n" if self.done == self.total else ""
            self.stream.write("\r" + self.line() + end)
            self.stream.flush()


def run_campaign(
    campaign: Campaign,
    *,
    client: Any = None,
    scheduler: str | None = None,
    workers: int | None = None,
    output: str | os.PathLike[str] | None = None,
    progress: Callable[[int, int, float], object] | bool | None = None,
    stop: threading.Event | None = None,
    max_tasks: int | None = None,
    numba_threads: int | None = None,
) -> RunReport:
    """Run (or resume) a campaign and write its result file.

    Parameters
    ----------
    campaign : Campaign
        From :func:`~fbs_core.campaign.load_campaign`.
    client : distributed.Client, optional
        Use this client (not closed here).
    scheduler : str, optional
        Address of an existing scheduler (default ``$FBS_DASK_SCHEDULER``, else a
        LocalCluster is started and closed here).
    workers : int, optional
        Worker processes of the LocalCluster (default: one in-process worker).
    output : path, optional
        Result file (default the campaign's ``output``).
    progress : callable or True, optional
        ``progress(done, total, rounds_done)`` after every task, or True for the text bar.
    stop : threading.Event, optional
        Set it to stop: running tasks are cancelled, finished ones kept (resumable).
    max_tasks : int, optional
        Stop after this many finished tasks (a partial run; resumable).
    numba_threads : int, optional
        Threads of the compiled kernels in each task (default: all cores in-process,
        cores / workers with local worker processes, the workers' own default on an
        existing cluster).

    Returns
    -------
    RunReport
    """
    from distributed import as_completed

    out_path = campaign.output if output is None else output
    store = CampaignStore(out_path)
    store.check(campaign)
    store.commit(_root_attrs(campaign))  # leftovers of a killed run; creates the file
    done = store.done()
    _model_units(campaign, store, done)
    _variants.write_designs(campaign, store, done)
    tasks, n_skipped = plan(campaign, done)
    todo = [t for t in tasks if t.unit not in done]
    bar = Progress(len(todo), sum(t.work for t in todo)) if progress is True else None
    t_start = time.perf_counter()
    started = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    report = RunReport(str(out_path), "complete", len(tasks), n_skipped, 0, 0.0, 0.0)
    own = client is None
    cluster = None
    if own and todo:
        client, cluster = make_client(scheduler, workers)
    try:
        if todo:
            report.scheduler = str(client.scheduler.address)
            report.workers = len(client.scheduler_info().get("workers", {}))
            if numba_threads is None and cluster is not None and workers:
                numba_threads = max(1, (os.cpu_count() or 1) // int(workers))
            # model variants from files: loaded here; tires sent to every worker once
            tire_objs = {n: work.load_model("tire", src) for n, src in campaign.tires.items()}
            tires = {
                n: o if isinstance(o, str) else client.scatter(o, broadcast=True)
                for n, o in tire_objs.items()
            }
            chassis_src = {n: work.load_model("chassis", s) for n, s in campaign.chassis.items()}
            # the chassis on each harmonic's grid and the subsystem arrays of the scatter
            # cases: computed here once (see fbs_core.campaign.work), stored, scattered
            grids: dict[tuple[int, float, str], FRF] = {}
            inputs_f: dict[str, Any] = {}
            for t in tasks:
                if t.kind == "variants":  # no subsystem arrays: the task builds its models
                    continue
                c = t.case
                assert isinstance(c, BandCase | TruncationCase)
                g = (c.harmonic, c.df, c.chassis)
                if g not in grids:
                    f = fbs_core.harmonic(c.harmonic).frequencies(c.df)
                    grids[g] = work.chassis_on(chassis_src[c.chassis], f)
                if t.kind == "band" and t.inputs not in inputs_f:
                    assert isinstance(c, BandCase)
                    inp = work.prepare_inputs(
                        tire_objs[c.tire],
                        grids[g],
                        c.harmonic,
                        c.n_modes,
                        c.coupling,
                        c.df,
                    )
                    if f"inputs/{t.inputs}" not in done:
                        _write_inputs(store, t.inputs, c, inp)
                    inputs_f[t.inputs] = client.scatter(inp)
            grids_f = {g: client.scatter(work.frf_payload(v)) for g, v in grids.items()}
            futures: dict[Any, list[Task]] = {}
            token = uuid.uuid4().hex[:12]
            t_submit = time.perf_counter()
            # small blocks of cases sharing their arrays go as one task (a partial run,
            # max_tasks, counts single blocks)
            groups = (
                group_blocks(tasks, campaign.task_round_lines)
                if max_tasks is None
                else [[t] for t in tasks]
            )
            for group in groups:
                t = group[0]
                c = t.case
                if t.kind == "variants":
                    fut = _variants.submit(client, t, numba_threads, token)
                    futures[fut] = group
                    continue
                assert isinstance(c, BandCase | TruncationCase)
                if t.kind == "band":  # one block, or small ones sharing their arrays
                    blocks = []
                    for b in group:
                        bc = b.case
                        assert isinstance(bc, BandCase)
                        blocks.append(
                            (
                                bc.noise,
                                bc.target,
                                bc.rounds,
                                bc.frequency_dependent,
                                bc.seed,
                                bc.percentiles,
                                b.l0,
                                b.l1,
                            )
                        )
                    fut = client.submit(
                        work.band_blocks,
                        inputs_f[t.inputs],
                        blocks,
                        campaign.max_chunk_bytes,
                        numba_threads,
                        key=f"band-{c.name}-{t.l0}-{len(group)}-{token}",
                        pure=False,
                    )
                else:
                    fut = client.submit(
                        work.truncation_case,
                        tires[c.tire],
                        grids_f[(c.harmonic, c.df, c.chassis)],
                        c,
                        key=f"trunc-{c.name}-{token}",
                        pure=False,
                    )
                futures[fut] = group
            ac = as_completed(list(futures))
            try:
                for fut in ac:
                    group = futures.pop(fut)
                    if fut.status == "error":
                        exc = fut.exception()
                        for t in group:
                            report.errors.append((t.unit, f"{type(exc).__name__}: {exc}"))
                            if bar:
                                bar.update(1, 0.0)
                        continue
                    if fut.status == "cancelled":
                        continue
                    results = fut.result()
                    fut.release()
                    # a band task returns its blocks' results, any other task its own
                    each = results if group[0].kind == "band" else [results]
                    for t, res in zip(group, each, strict=True):
                        report.task_seconds += float(res.get("seconds", 0.0))
                        tw = time.perf_counter()
                        WRITING.set()
                        try:
                            _write(store, campaign, t, res)
                        finally:
                            WRITING.clear()
                        report.write_seconds += time.perf_counter() - tw
                        report.compute_wall = time.perf_counter() - t_submit
                        report.tasks_done += 1
                        report.rounds_done += t.rounds
                        if bar:
                            bar.update(1, t.rounds, t.work)
                        elif callable(progress):
                            progress(report.tasks_done, len(todo), report.rounds_done)
                    if (stop is not None and stop.is_set()) or (
                        max_tasks is not None and report.tasks_done >= max_tasks
                    ):
                        report.status = "stopped"
                        break
            except KeyboardInterrupt:
                report.status = "stopped"
            if report.status == "stopped":
                ac.clear()
                client.cancel(list(futures))
            if report.errors and report.status == "complete":
                report.status = "failed"
    except KeyboardInterrupt:
        report.status = "stopped"
    finally:
        report.seconds = time.perf_counter() - t_start
        if todo:
            store.write_unit(
                f"runs/{started.replace(':', '')}_{uuid.uuid4().hex[:8]}",
                {},
                {
                    "started": started,
                    "seconds": report.seconds,
                    "status": report.status,
                    "scheduler": report.scheduler,
                    "workers": report.workers,
                    "tasks_done": report.tasks_done,
                    "tasks_total": report.tasks_total,
                    "errors": report.errors,
                    "versions": _versions(),
                },
            )
        store.commit(_root_attrs(campaign))
        if own and client is not None:
            client.close()
            if cluster is not None:
                cluster.close()
    return report
