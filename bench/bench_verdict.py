"""The verdict of a full review beside what it judges (docs/verdict.md).

Run:  .venv/bin/python bench/bench_verdict.py [--candidates 8] [--repeat 20]

Prints, side by side in one run, for ``--candidates`` tires (the reference and copies with
their poles moved by 1 % steps) x 7 harmonics x 6 bushing DOFs on the harmonics' 0.5 Hz
lines:

1. the coupled responses of eq. 4.1 of all candidates (``bushing_response``, 60 modes):
   what the verdict needs computed first;
2. the verdict itself with the example targets (every row judged), with an incumbent
   target, and with a noise edge on every row (median of ``--repeat`` runs);
3. reading the example target CSV (sandbox parse included) and writing the CSV export.

The verdict is a small fraction of the responses it judges: it can be recomputed at every
control change of the dashboard.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import fbs_core as fc  # noqa: E402
from fbs_core.verdict import NoiseEdge, verdict  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TARGETS = ROOT / "data" / "targets" / "bushing_targets.csv"


def _median(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=fc.MAX_CANDIDATES)
    ap.add_argument("--repeat", type=int, default=20)
    args = ap.parse_args()
    ref = fc.reference_tire()
    cands = fc.CandidateSet(
        [fc.Candidate.reference()]
        + [
            fc.Candidate(
                f"tire {i}",
                f"{i:024x}",
                dataclasses.replace(ref, poles=ref.poles * (1 + 0.01 * i), params=None, meta={}),
            )
            for i in range(1, args.candidates)
        ]
    )
    t = time.perf_counter()
    resp = {
        (c.name, k): fc.bushing_response(k, 60, tire=c.model) for c in cands for k in range(1, 8)
    }
    t_resp = time.perf_counter() - t
    lines = sum(r.freq.size for r in resp.values()) // len(cands)
    targets = fc.read_targets(TARGETS)
    edges = {
        key: NoiseEdge(r.freq, r.outputs, np.abs(r.data[:, :, 0]) * 1.2) for key, r in resp.items()
    }
    incumbent = [fc.IncumbentTarget("reference", 1.0)]
    v = verdict(resp, targets, edges, candidates=cands)
    t_plain = _median(lambda: verdict(resp, targets, candidates=cands), args.repeat)
    t_inc = _median(lambda: verdict(resp, incumbent, candidates=cands), args.repeat)
    t_band = _median(lambda: verdict(resp, targets, edges, candidates=cands), args.repeat)
    t_read = _median(lambda: fc.read_targets(TARGETS), max(3, args.repeat // 4))
    t_csv = _median(v.to_csv, args.repeat)
    n_rows = len(v.rows)
    n_inc = len(verdict(resp, incumbent, candidates=cands).rows)
    load = os.getloadavg()[0]
    print(f"{len(cands)} candidates x 7 harmonics, {lines} lines per candidate, load {load:.1f}")
    print(f"  responses (eq. 4.1, 60 modes), all candidates  {t_resp * 1e3:9.1f} ms")
    print(
        f"  verdict, example targets ({n_rows} rows)         {t_plain * 1e3:9.2f} ms  "
        f"({t_plain / t_resp:.4f} of the responses)"
    )
    print(f"  verdict, incumbent + 1 dB ({n_inc} rows)        {t_inc * 1e3:9.2f} ms")
    print(f"  verdict, example targets + noise edges        {t_band * 1e3:9.2f} ms")
    print(f"  read the example target CSV (sandbox)         {t_read * 1e3:9.2f} ms")
    print(f"  CSV export of the verdict                     {t_csv * 1e3:9.2f} ms")


if __name__ == "__main__":
    main()
