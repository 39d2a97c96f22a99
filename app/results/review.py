"""The review's verdict: every candidate tire against the targets (docs/verdict.md).

The verdict is :func:`fbs_core.verdict.verdict` of the coupled bushing responses (eq. 4.1)
of every candidate of the session's :class:`~app.review.Review` to the seven harmonic
cases, with **all the modes each candidate delivered** (the best prediction its model
gives; whether those modes are enough is the delivery's adequacy beside it), on the
session's chassis and coupling. Beside it, each candidate's delivery
(:func:`fbs_core.delivery.assess_delivery`): its modes against table 5.1's suggested N at
the meeting's threshold and f_max.

The responses and the tables are computed on the background worker
(:func:`verdict_work`); until they are, the result says how many are done and judges
nothing (never a verdict of part of the candidates).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from fbs_core import FRF
from fbs_core.candidates import Candidate, CandidateSet
from fbs_core.delivery import assess_delivery
from fbs_core.errors import FBSError
from fbs_core.verdict import Verdict, verdict
from fbs_core.vocabulary import DIRECTIONS, HARMONIC_CASES

from .. import compute
from ..datasource import candidate_models
from .base import Result, Snapshot

__all__ = ["VERDICT_DEPENDS", "candidates_of", "verdict_result", "verdict_work"]

#: The snapshot fields the verdict is made of.
VERDICT_DEPENDS = ("review", "coupling", "models", "threshold", "f_max")
#: (harmonic, coupling, models) whose all-modes responses are computed.
_DONE: set[tuple] = set()
BUSHING = tuple(f"bushing:{d}" for d in DIRECTIONS)


def candidates_of(s: Snapshot) -> CandidateSet:
    """The session's candidates (the reference alone before any tire upload)."""
    c = s.review.candidates
    return CandidateSet([Candidate.reference()]) if c is None else c


def _response(k: int, coupling: str, models) -> FRF:
    data = compute.coupled_response(k, None, coupling, models)
    freq = np.asarray(compute.error_map(k, coupling, models).freq, float)
    _DONE.add((k, coupling, models))
    return FRF(freq, np.asarray(data)[:, :, None], BUSHING, ["patch"])


def _jobs(s: Snapshot) -> tuple[list[tuple], list[tuple]]:
    """What the verdict needs: responses ``(k, coupling, models)`` and tables
    ``(threshold, f_max, coupling, None, models)``, each list in the candidates' order."""
    responses, tables = [], []
    for c in candidates_of(s):
        m = candidate_models(s.models, c)
        responses += [(k, s.coupling, m) for k in HARMONIC_CASES]
        tables.append((s.threshold, s.f_max, s.coupling, None, m))
    return responses, tables


def _missing(s: Snapshot) -> tuple[list[tuple], list[tuple]]:
    responses, tables = _jobs(s)
    return (
        [r for r in responses if r not in _DONE],
        [t for t in tables if not compute.suggested_table_ready(*t)],
    )


def verdict_work(s: Snapshot) -> Callable[[], Iterator[None]] | None:
    """The responses and tables the verdict still lacks, one by one (None: none)."""
    if not s.review.judged:
        return None
    responses, tables = _missing(s)
    if not responses and not tables:
        return None

    def work() -> Iterator[None]:
        for k, coupling, m in responses:
            _response(k, coupling, m)
            yield
        for t in tables:
            compute.suggested_table(*t)
            yield

    return work


def _verdict(s: Snapshot) -> Verdict:
    cands = candidates_of(s)
    responses: dict[tuple[str, int], FRF] = {}
    deliveries = []
    for c in cands:
        m = candidate_models(s.models, c)
        for k in HARMONIC_CASES:
            responses[(c.name, k)] = _response(k, s.coupling, m)
        table = compute.suggested_table(s.threshold, s.f_max, s.coupling, None, m)
        deliveries.append(assess_delivery(c, table["result"]))
    targets: list[Any] = list(s.review.targets)
    if s.review.incumbent is not None:
        targets.append(s.review.incumbent)
    return verdict(responses, targets, candidates=cands, deliveries=deliveries)


def _meta(s: Snapshot, cands: CandidateSet) -> dict[str, Any]:
    r = s.review
    return {
        "view": "review verdict: candidates against the targets (docs/verdict.md)",
        "responses": "coupled bushing velocity per metre of road (eq. 4.1), every mode each "
        "candidate delivered, harmonics 1-7",
        "coupling": s.coupling,
        "candidates": "; ".join(
            f"{c.name} ({c.supplier or 'no supplier'}, {c.digest})" for c in cands
        ),
        "targets": "; ".join(f"{t.dof} h{t.harmonic or 'all'} {t.source}" for t in r.targets)
        or "none",
        "incumbent rule": "none"
        if r.incumbent is None
        else f"{r.incumbent.candidate} {r.incumbent.margin_db:+g} dB",
        "delivery threshold_pct": s.threshold,
        "delivery f_max_Hz": s.f_max,
        "models": s.models.describe(),
    }


def verdict_result(s: Snapshot) -> Result:
    """The verdict's table (one row per candidate x harmonic x DOF with a target), its
    ranking and the deliveries; pending while :func:`verdict_work` computes."""
    cands = candidates_of(s)
    meta = _meta(s, cands)
    name = f"verdict_{len(cands)}cand_{s.review.key[:8]}_{s.coupling}.csv"
    if not s.review.judged:
        return Result(
            meta=meta,
            filename=name,
            caption="No targets: load a target file, type a target or choose the incumbent.",
            draw={"state": "no targets", "candidates": cands},
        )
    responses, tables = _missing(s)
    if responses or tables:
        total = len(cands) * (len(HARMONIC_CASES) + 1)
        done = total - len(responses) - len(tables)
        return Result(
            meta=meta,
            filename=name,
            caption=f"Computing the candidates' responses: {done} of {total} ...",
            draw={"state": "pending", "pending": True, "candidates": cands},
        )
    try:
        v = _verdict(s)
    except FBSError as e:
        return Result(
            meta=meta,
            filename=name,
            caption=f"No verdict: {e}",
            draw={"state": "problem", "problem": str(e), "candidates": cands},
        )
    rows = v.rows
    best = v.ranking[0] if v.ranking else None
    return Result(
        columns={
            "candidate": np.array([r.candidate for r in rows], dtype=object),
            "harmonic": np.array([r.harmonic for r in rows], int),
            "dof": np.array([r.dof for r in rows], dtype=object),
            "status": np.array([r.status for r in rows], dtype=object),
            "worst_dB": np.array([r.worst_db for r in rows], float),
            "freq_Hz": np.array([r.freq for r in rows], float),
            "speed_kmh": np.array([r.speed for r in rows], float),
            "margin_dB": np.array([r.margin_db for r in rows], float),
            "target": np.array([r.target for r in rows], dtype=object),
        },
        meta=meta,
        filename=name,
        caption=(
            f"**{len(cands)} candidates** against {len(s.review.targets)} target(s)"
            + ("" if s.review.incumbent is None else " and the incumbent rule")
            + (f"; best: **{best.candidate}** ({best.status})" if best is not None else "")
        ),
        draw={"state": "done", "verdict": v, "candidates": cands},
        core={"verdict": v},
    )
