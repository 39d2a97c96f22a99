"""Running a campaign on a ``dask.distributed`` cluster.

The cluster: an existing one when a scheduler address is given (``scheduler=`` or the
environment variable ``FBS_DASK_SCHEDULER``, e.g. ``tcp://host:8786``), else a
:class:`distributed.LocalCluster` started here and closed at the end: by default one
in-process worker (threads of this process; the compiled kernels use all cores, as
:func:`fbs_core.scatter_band` does), with ``workers=N`` N worker processes.

The work: model variants read from files are sent to the workers once
(``client.scatter(..., broadcast=True)``); the subsystem arrays of every (harmonic, models,
coupling) are computed here once, stored and scattered, and feed the band blocks of all
cases that use them; every scatter case is split into blocks of lines holding
``task_round_lines`` (rounds x lines) of work (see :mod:`.work` for why lines), small blocks
sharing their arrays going as one task (:func:`group_blocks`); every truncation case is one
task. The tasks are submitted as soon as what they need is ready, so that the workers start
on the first harmonic while the arrays of the next are prepared. Results are gathered with
``as_completed`` as they finish, each task's units written at once as one part file and
merged into the open copy of the result file (:mod:`.store`), so that a stop (Ctrl-C,
``stop`` event, a killed process) loses at most the tasks in flight, a rerun computes only
what is missing, and the end of a run has little left to merge.
"""

from __future__ import annotations

import functools
import math
import os
import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

import fbs_core

from . import variants as _variants
from . import work
from .spec import BandCase, Campaign, CampaignError, TruncationCase
from .store import CampaignStore, Merging, Unit, file_sha256

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


@functools.lru_cache(maxsize=256)
def n_lines(harmonic: int, df: float) -> int:
    """Lines of a harmonic's grid at ``df`` (asked for every unit written: cached)."""
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
    ``cluster`` is None when joining an existing one.

    A scheduler is joined as :mod:`fbs_core.campaign.security` allows: over TLS with the
    certificates of ``$FBS_DASK_TLS_DIR``, or in plain TCP on the loopback interface only
    (elsewhere with ``FBS_DASK_ALLOW_PLAIN=1``); a refused address raises
    :class:`~fbs_core.campaign.security.InsecureScheduler` (a :class:`CampaignError`).
    """
    from distributed import Client, LocalCluster

    from .security import connect

    addr = scheduler or os.environ.get(SCHEDULER_ENV) or None
    if addr:
        try:
            return connect(addr, "30s"), None
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


def _unit(campaign: Campaign, t: Task, res: dict[str, Any]) -> Unit:
    """The unit of a finished band or truncation task, as :meth:`.CampaignStore.write_units`
    takes it (the provenance keys are taken out of ``res``)."""
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
        return t.unit, {k: res[k] for k in keys}, attrs, parents
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
    return t.unit, {k: res[k] for k in keys}, attrs, parents


def _write_group(
    store: CampaignStore, campaign: Campaign, group: list[Task], results: list[dict[str, Any]]
) -> Path:
    """Write the units of one finished cluster task (a band group's blocks, or one task) as
    one part file."""
    t = group[0]
    if t.kind == "variants":
        assert isinstance(t.case, _variants.VariantsCase) and len(group) == 1
        return _variants.write_result(store, t.case, t.unit, list(t.rows), results[0])
    units = [_unit(campaign, x, r) for x, r in zip(group, results, strict=True)]
    return store.write_units(units)


def _write(store: CampaignStore, campaign: Campaign, t: Task, res: dict[str, Any]) -> Path:
    """Write one finished task as its own part file."""
    return _write_group(store, campaign, [t], [res])


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


class _Sender:
    """Submits a campaign's tasks to the cluster, preparing what a task needs when it is first
    needed: a tire variant from a file (sent to every worker once), the chassis on a
    harmonic's grid, the subsystem arrays of the scatter cases (computed here once, stored
    as a unit and scattered; see :mod:`.work` for why here). The workers thus start on the
    first task while the arrays of the next harmonics are prepared.
    """

    def __init__(
        self,
        client: Any,
        campaign: Campaign,
        store: CampaignStore,
        done: set[str],
        numba_threads: int | None,
    ) -> None:
        self.client, self.campaign, self.store, self.done = client, campaign, store, done
        self.numba_threads = numba_threads
        self.token = uuid.uuid4().hex[:12]
        self.tire_objs = {n: work.load_model("tire", src) for n, src in campaign.tires.items()}
        self.chassis_src = {n: work.load_model("chassis", s) for n, s in campaign.chassis.items()}
        self.tires: dict[str, Any] = {}
        self.grids: dict[tuple[int, float, str], FRF] = {}
        self.grids_f: dict[tuple[int, float, str], Any] = {}
        self.inputs_f: dict[str, Any] = {}

    def _tire(self, name: str) -> Any:
        """The tire as the tasks get it: "reference", or a future of the scattered model."""
        if name not in self.tires:
            o = self.tire_objs[name]
            self.tires[name] = o if isinstance(o, str) else self.client.scatter(o, broadcast=True)
        return self.tires[name]

    def _grid(self, c: BandCase | TruncationCase) -> FRF:
        g = (c.harmonic, c.df, c.chassis)
        if g not in self.grids:
            f = fbs_core.harmonic(c.harmonic).frequencies(c.df)
            self.grids[g] = work.chassis_on(self.chassis_src[c.chassis], f)
        return self.grids[g]

    def _grid_future(self, c: TruncationCase) -> Any:
        g = (c.harmonic, c.df, c.chassis)
        if g not in self.grids_f:
            self.grids_f[g] = self.client.scatter(work.frf_payload(self._grid(c)))
        return self.grids_f[g]

    def _inputs(self, t: Task) -> Any:
        """The future of a band task's subsystem arrays (prepared, stored, scattered once)."""
        if t.inputs not in self.inputs_f:
            c = t.case
            assert isinstance(c, BandCase)
            inp = work.prepare_inputs(
                self.tire_objs[c.tire], self._grid(c), c.harmonic, c.n_modes, c.coupling, c.df
            )
            if f"inputs/{t.inputs}" not in self.done:
                _write_inputs(self.store, t.inputs, c, inp)
            self.inputs_f[t.inputs] = self.client.scatter(inp)
        return self.inputs_f[t.inputs]

    def submit(self, group: list[Task]) -> Any:
        """Submit one cluster task: band blocks sharing their arrays, or one other task."""
        t, client = group[0], self.client
        if t.kind == "variants":
            return _variants.submit(client, t, self.numba_threads, self.token)
        c = t.case
        assert isinstance(c, BandCase | TruncationCase)
        if t.kind == "band":
            blocks = [_block_args(b) for b in group]
            return client.submit(
                work.band_blocks,
                self._inputs(t),
                blocks,
                self.campaign.max_chunk_bytes,
                self.numba_threads,
                key=f"band-{c.name}-{t.l0}-{len(group)}-{self.token}",
                pure=False,
            )
        assert isinstance(c, TruncationCase)
        return client.submit(
            work.truncation_case,
            self._tire(c.tire),
            self._grid_future(c),
            c,
            key=f"trunc-{c.name}-{self.token}",
            pure=False,
        )


def _block_args(b: Task) -> tuple[Any, ...]:
    """The arguments of :func:`.work.band_block` of a band task, as band_blocks takes them."""
    c = b.case
    assert isinstance(c, BandCase)
    return (c.noise, c.target, c.rounds, c.frequency_dependent, c.seed, c.percentiles, b.l0, b.l1)


def _collect(
    fut: Any,
    group: list[Task],
    store: CampaignStore,
    campaign: Campaign,
    merge: Merging,
    report: RunReport,
) -> str:
    """Take a finished cluster task: its units written as one part file and merged into the
    result file's open copy (or its error recorded); the report updated. Returns the
    future's status ("finished", "error" or "cancelled")."""
    status = str(fut.status)
    if status == "error":
        exc = fut.exception()
        for t in group:
            report.errors.append((t.unit, f"{type(exc).__name__}: {exc}"))
        return status
    if status == "cancelled":
        return status
    results = fut.result()
    fut.release()
    # a band task returns its blocks' results, any other task its own
    each = results if group[0].kind == "band" else [results]
    report.task_seconds += sum(float(r.get("seconds", 0.0)) for r in each)
    tw = time.perf_counter()
    WRITING.set()
    try:
        merge.add(_write_group(store, campaign, group, each))
    finally:
        WRITING.clear()
    report.write_seconds += time.perf_counter() - tw
    report.tasks_done += len(group)
    report.rounds_done += sum(t.rounds for t in group)
    return status


def _advance(
    group: list[Task],
    status: str,
    report: RunReport,
    bar: Progress | None,
    progress: Callable[[int, int, float], object] | bool | None,
    n_todo: int,
) -> None:
    """Move the progress bar (or call ``progress``) by the units of a cluster task taken by
    :func:`_collect`, one unit at a time."""
    if status == "cancelled":
        return
    ok = status == "finished"
    done = report.tasks_done - (len(group) if ok else 0)
    rounds = report.rounds_done - (sum(t.rounds for t in group) if ok else 0.0)
    for t in group:
        if bar:
            bar.update(1, t.rounds if ok else 0.0, t.work if ok else 0.0)
        elif callable(progress) and ok:
            done += 1
            rounds += t.rounds
            progress(done, n_todo, rounds)


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
    futures: dict[Any, list[Task]] = {}
    merge: Merging | None = None
    try:
        if todo:
            report.scheduler = str(client.scheduler.address)
            report.workers = len(client.scheduler_info().get("workers", {}))
            if numba_threads is None and cluster is not None and workers:
                numba_threads = max(1, (os.cpu_count() or 1) // int(workers))
            merge = store.merging(_root_attrs(campaign))
            sender = _Sender(client, campaign, store, done, numba_threads)
            # small blocks of cases sharing their arrays go as one task (a partial run,
            # max_tasks, counts single blocks)
            groups = (
                group_blocks(tasks, campaign.task_round_lines)
                if max_tasks is None
                else [[t] for t in tasks]
            )
            t_submit = 0.0
            for group in groups:  # the workers start on the first while the next are prepared
                futures[sender.submit(group)] = group
                t_submit = t_submit or time.perf_counter()
            ac = as_completed(list(futures))
            try:
                for fut in ac:
                    group = futures.pop(fut)
                    status = _collect(fut, group, store, campaign, merge, report)
                    report.compute_wall = time.perf_counter() - t_submit
                    _advance(group, status, report, bar, progress, len(todo))
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
        if futures:
            client.cancel(list(futures))
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
        if merge is None:
            store.commit(_root_attrs(campaign))
        else:
            merge.finish()
        if own and client is not None:
            client.close()
            if cluster is not None:
                cluster.close()
    return report
