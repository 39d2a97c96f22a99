"""The review in a session: adding a tire candidate, and control changes with candidates.

Run:  .venv/bin/python bench/bench_review.py [--reps 5] [--changes 20]

Prints, side by side in one run (no server, no drawing: the compute side of the page, as
``bench/bench_flood.py`` measures it):

1. **adding a candidate**: a reference-size tire file (the reference tire with its poles
   scaled by 1.03, 1.032, ...: a new file every repetition, so no cache is hit), read by
   ``DataSource.load_tire`` in a new session holding the reference and one target (every
   harmonic of ``bushing:z``). From the call, the seconds until

   - the session's models are the new tire (the file read and checked: ``case.models``),
   - the detail views' results of the new tire are published (response, response plot,
     truncation map, suggested modes, eigenfrequencies, tire quality: what the page draws),
   - ``load_tire`` returned,
   - the published ``verdict`` is done (``core["verdict"]``, both candidates, all seven
     harmonics);

   median (min-max) over ``--reps`` files, for two stores, alternated: ``Results(state)``
   (no server: ``slow`` work, the verdict's responses among it, and the scatter band are
   computed in place inside the pass) and ``Results(state, background=True)`` (as when
   served: the pass publishes the views, the verdict's responses go to the background worker
   and the band to its own thread; ``bench/bench_flood.py`` runs its stores so). The
   goal: the detail views within 2 s, the verdict later in the background.
2. **control changes with candidates**: two sessions (``background=True``), A with four
   candidates (the reference and three uploads, the last one current) and one target, its
   verdict done, B with the reference only and no target. Alternately in A and B (A B, B A,
   ...), changes of ``case.n_modes`` (50, 100, 150, 200 in turn) and of ``case.harmonic``
   (1..7 in turn): the time until the store has published the change's results (the setter
   returned: the pass is done) and until its first published result; median, p95 and max.
   First each value once (printed as "first visit"), then ``--changes`` timed changes of
   each; every change waits until its band and the background work are done before the
   next one. The first visits find the truncation maps computed already: the verdict's
   background work computes every harmonic's map of each candidate (of A's current tire, and
   of the reference, which B shares: the caches are the process's), so what is measured is
   the store's pass. The verdict does not depend on N or the harmonic (it judges all the
   modes each candidate delivered), so A and B should agree within noise.
3. the machine's cores and load average at the start and at the end (the machine is shared:
   compare the columns of one run, not runs).

The in-place store computes the scatter band of the new tire inside ``load_tire``
(``--rounds`` Monte-Carlo rounds, the page's default): it is the last row of the pass, after
the verdict.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import os
import statistics
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from bench_flood import _stats, _wait  # noqa: E402

import fbs_core  # noqa: E402
from app.runtime.background import BACKGROUND  # noqa: E402
from app.state import CORNER_ROUNDS, DashboardState  # noqa: E402
from app.store import TABLE, Results  # noqa: E402
from fbs_core.targets import Target  # noqa: E402
from fbs_core.tire.storage import save_tire_model  # noqa: E402

#: The rows the detail views draw (published again when the tire changes).
DETAIL = ("response", "response_plot", "error_map", "suggested", "eigen", "tire_quality")
#: Values the control changes go through (each visited once before the timed changes).
N_VALUES = (50, 100, 150, 200)
#: One target on every harmonic: the verdict judges all seven.
TARGET = Target.segments("bushing:z", [(1.0, 20.0), (500.0, 20.0)])
#: Pole scales of the uploaded tires: each file is new (no cache of another hit).
SCALES = (1.03 + 0.002 * i for i in itertools.count())


def tire_file(scale: float) -> bytes:
    """The reference tire with its poles scaled, as the HDF5 file a user uploads."""
    ref = fbs_core.reference_tire()
    model = dataclasses.replace(ref, poles=ref.poles * scale, params=None, meta={})
    with tempfile.TemporaryDirectory() as d:
        return save_tire_model(model, Path(d) / "tire.h5").read_bytes()


def loadavg() -> str:
    one, five, fifteen = os.getloadavg()
    return f"{one:.2f} {five:.2f} {fifteen:.2f} (1, 5, 15 min)"


def _session(background: bool, rounds: int) -> tuple[DashboardState, Results, dict]:
    """A new session with the reference and one target, its verdict done; ``stamps``:
    the first time each row is published (and ``models``: the tire set) after ``t0``."""
    st = DashboardState()
    st.noise.rounds = rounds
    stamps: dict = {"t0": None}

    def stamp(name: str) -> None:
        if stamps["t0"] is not None and name not in stamps:
            stamps[name] = time.perf_counter() - stamps["t0"]

    # before the store's watchers: called as soon as the models change, before its pass
    st.case.param.watch(lambda e: stamp("models"), "models")
    store = Results(st, background=background)
    for row in TABLE:
        store.param.watch(lambda e, n=row.name: stamp(n), row.name)

    def verdict_done(e) -> None:
        r = e.new
        if r is not None and r.core.get("verdict") is not None:
            if len(r.draw["candidates"]) == stamps.get("want", 0):
                stamp("verdict done")

    store.param.watch(verdict_done, "verdict")
    assert st.data.add_target(TARGET), st.data.error
    _settle(store)
    return st, store, stamps


def _settle(store: Results, timeout: float = 300.0) -> None:
    """Wait until the store's band and the background work are done."""
    _wait(lambda: not store.band_status.busy, timeout)
    BACKGROUND.idle(timeout)


def add_candidate(background: bool, rounds: int, data: bytes) -> dict[str, float]:
    """Seconds from ``load_tire`` to each milestone (see the module docstring)."""
    st, store, stamps = _session(background, rounds)
    stamps["want"] = 2
    stamps["t0"] = t0 = time.perf_counter()
    assert st.data.load_tire(data, "upload.h5"), st.data.error
    stamps["returned"] = time.perf_counter() - t0
    ok = _wait(lambda: "verdict done" in stamps, 300.0)
    assert ok, store.verdict.caption
    assert st.case.models.tire is st.data.review.candidates.current.model
    _settle(store)
    store.close()
    out = {
        "models": stamps["models"],
        "response": stamps["response"],
        "detail": max(stamps[n] for n in DETAIL),
        "returned": stamps["returned"],
        "verdict done": stamps["verdict done"],
    }
    return out


def part_add(args) -> None:
    print(
        f"\n1. adding a candidate: reference + 1 tire file ({len(tire_file(1.0)) / 1e6:.1f} MB, "
        f"poles scaled), 1 target on every harmonic; median (min-max) of {args.reps} files",
        flush=True,
    )
    kinds = {"in place": False, "background": True}
    add_candidate(False, args.rounds, tire_file(0.95))  # imports, reference caches warm
    got: dict[str, list[dict]] = {k: [] for k in kinds}
    for i in range(args.reps):
        order = list(kinds.items()) if i % 2 == 0 else list(kinds.items())[::-1]
        for label, bg in order:
            got[label].append(add_candidate(bg, args.rounds, tire_file(next(SCALES))))
    rows = (
        ("models", "models are the new tire (file read, checked)"),
        ("response", "coupled response published"),
        ("detail", "detail views' results published"),
        ("returned", "load_tire returned"),
        ("verdict done", "verdict done (2 candidates x 7 harmonics)"),
    )
    print(f"  {'seconds from load_tire(bytes, name)':46s}" + "".join(f"{k:>22s}" for k in kinds))
    print(f"  {'':46s}" + "".join(f"{'Results(' + k + ')':>22s}" for k in ("state", "bg=True")))
    for key, text in rows:
        cells = []
        for label in kinds:
            v = [g[key] for g in got[label]]
            cells.append(f"{statistics.median(v):6.2f} ({min(v):.2f}-{max(v):.2f})")
        print(f"  {text:46s}" + "".join(f"{c:>22s}" for c in cells))
    print("  goal: detail views within 2 s, the verdict of all seven harmonics in the background")


def _review_session(uploads: int, rounds: int) -> tuple[DashboardState, Results]:
    st = DashboardState()
    st.noise.rounds = rounds
    store = Results(st, background=True)
    t0 = time.perf_counter()
    for i in range(uploads):
        assert st.data.load_tire(tire_file(next(SCALES)), f"supplier_{i + 1}.h5"), st.data.error
    if uploads:
        assert st.data.add_target(TARGET), st.data.error
        want = uploads + 1
        ok = _wait(
            lambda: (
                store.verdict is not None
                and store.verdict.core.get("verdict") is not None
                and len(store.verdict.draw["candidates"]) == want
            ),
            600.0,
        )
        assert ok, store.verdict.caption
        print(
            f"  (A: {uploads} uploads and the target, verdict of {want} candidates done in "
            f"{time.perf_counter() - t0:.1f} s)",
            flush=True,
        )
    _settle(store)
    return st, store


def _change(store: Results, field: str, stamps: list[float]) -> tuple[float, float]:
    """One change of ``field`` to its next value: (published, first result) in ms."""
    case = store.state.case
    n0 = len(stamps)
    t0 = time.perf_counter()
    if field == "n_modes":
        case.n_modes = N_VALUES[(N_VALUES.index(case.n_modes) + 1) % len(N_VALUES)]
    else:
        case.harmonic = case.harmonic % 7 + 1
    done = time.perf_counter() - t0
    first = (stamps[n0] - t0) if len(stamps) > n0 else done
    _settle(store)
    return 1000 * done, 1000 * first


def _alternated(sessions: dict, stamps: dict, field: str, count: int) -> dict:
    """``count`` changes of ``field`` in each session, A B, B A, ...: label ->
    (published, first result) lists in ms."""
    labels = list(sessions)
    out: dict[str, tuple[list, list]] = {label: ([], []) for label in labels}
    for i in range(2 * count):
        label = labels[i % 2] if (i // 2) % 2 == 0 else labels[1 - i % 2]
        done, first = _change(sessions[label], field, stamps[label])
        out[label][0].append(done)
        out[label][1].append(first)
    return out


def part_controls(args) -> None:
    print(
        f"\n2. control changes, Results(background=True), {args.changes} changes each, "
        "A and B alternated",
        flush=True,
    )
    sessions = {
        "A: 4 candidates + target": _review_session(3, args.rounds)[1],
        "B: reference, no target": _review_session(0, args.rounds)[1],
    }
    stamps: dict[str, list[float]] = {}
    for label, store in sessions.items():
        stamps[label] = s = []
        for row in TABLE:
            store.param.watch(lambda e, s=s: s.append(time.perf_counter()), row.name)
    # first visits (N 100, 150, 200 at harmonic 1; harmonics 2..7 at N 50), then back to the
    # first value: every value of the timed changes visited once (maps and bands cached)
    n_first = _alternated(sessions, stamps, "n_modes", len(N_VALUES))
    h_first = _alternated(sessions, stamps, "harmonic", 7)
    n_timed = _alternated(sessions, stamps, "n_modes", args.changes)
    for store in sessions.values():
        store.state.case.n_modes = N_VALUES[0]
        _settle(store)
    h_timed = _alternated(sessions, stamps, "harmonic", args.changes)
    rows = (
        ("n_modes first visit, published", {k: v[0][:-1] for k, v in n_first.items()}),
        ("harmonic first visit, published", {k: v[0][:-1] for k, v in h_first.items()}),
        ("n_modes results published", {k: v[0] for k, v in n_timed.items()}),
        ("n_modes first result", {k: v[1] for k, v in n_timed.items()}),
        ("harmonic results published", {k: v[0] for k, v in h_timed.items()}),
        ("harmonic first result", {k: v[1] for k, v in h_timed.items()}),
    )
    print(f"  {'':37s}" + "".join(f"{label:>43s}" for label in sessions))
    for text, got in rows:
        n = len(next(iter(got.values())))
        cells = [_stats(got[label]) for label in sessions]
        print(f"  {f'{text} ({n})':37s}" + "".join(f"{c:>43s}" for c in cells))
    for field, timed in (("n_modes", n_timed), ("harmonic", h_timed)):
        a, b = (float(np.median(timed[label][0])) for label in sessions)
        print(f"  {field} changes, median published A / B: {a / b:.2f}")
    print(
        "  (first visits: every harmonic's truncation map of A's tire and of the reference "
        "was computed by the verdict's background work)"
    )
    for store in sessions.values():
        store.close()


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=5, help="tire files added per store")
    ap.add_argument("--changes", type=int, default=20, help="changes of each control")
    ap.add_argument(
        "--rounds", type=int, default=CORNER_ROUNDS, help="scatter band rounds of the sessions"
    )
    ap.add_argument("--only", choices=("add", "controls"), help="one part only")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    print(f"cores: {os.cpu_count()} (usable {len(os.sched_getaffinity(0))})")
    print(f"load average at start: {loadavg()}", flush=True)
    if args.only != "controls":
        part_add(args)
    if args.only != "add":
        part_controls(args)
    print(f"\nload average at end:   {loadavg()}  ({time.perf_counter() - t0:.0f} s in all)")


if __name__ == "__main__":
    main()
