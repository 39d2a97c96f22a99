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

import threading
from collections import OrderedDict
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from fbs_core import FRF
from fbs_core.candidates import Candidate, CandidateSet
from fbs_core.delivery import assess_delivery
from fbs_core.errors import FBSError
from fbs_core.targets import Target
from fbs_core.verdict import NoiseEdge, Verdict, verdict
from fbs_core.vocabulary import DIRECTIONS, HARMONIC_CASES, magnitude_db

from .. import compute
from ..datasource import candidate_models
from . import vehicle_compute as vc
from .base import VEHICLE_FIELDS, Result, Snapshot
from .scope import vehicle_meta

__all__ = [
    "BANDS_DEPENDS",
    "CURVES_DEPENDS",
    "VERDICT_DEPENDS",
    "candidates_of",
    "curves_work",
    "bands_work",
    "review_bands_result",
    "review_curves_result",
    "verdict_result",
    "verdict_work",
]

#: The noise settings of the verdict's bands (while ``verdict_band`` is on).
BAND_FIELDS = ("noise", "target", "frequency_dependent", "rounds", "seed", "percentile")
#: The snapshot fields the verdict is made of.
VERDICT_DEPENDS = (
    "review",
    "coupling",
    "models",
    "threshold",
    "f_max",
    "verdict_band",
    *BAND_FIELDS,
)
BUSHING = tuple(f"bushing:{d}" for d in DIRECTIONS)
#: Responses kept (harmonic, coupling, models' digest -> FRF, ~15 kB each): every harmonic
#: of the candidates of a few sessions. Keyed by the digest, not the models: a tire leaves
#: memory with its sessions.
KEPT = 256


class _Kept:
    """What the verdict computed so far (responses, band edges), most recent last, at most
    :data:`KEPT`."""

    def __init__(self, limit: int = KEPT) -> None:
        self._lock = threading.Lock()
        self._items: OrderedDict[tuple, Any] = OrderedDict()
        self.limit = int(limit)

    def get(self, key: tuple) -> Any:
        with self._lock:
            frf = self._items.get(key)
            if frf is not None:
                self._items.move_to_end(key)
            return frf

    def put(self, key: tuple, frf: Any) -> None:
        with self._lock:
            self._items[key] = frf
            self._items.move_to_end(key)
            while len(self._items) > self.limit:
                self._items.popitem(last=False)

    def __contains__(self, key: tuple) -> bool:
        with self._lock:
            return key in self._items


_DONE = _Kept()
#: The noise bands' upper edges computed so far (NoiseEdge, ~4 kB each; not the bands).
_EDGES = _Kept()


def candidates_of(s: Snapshot) -> CandidateSet:
    """The session's candidates (the reference alone before any tire upload)."""
    c = s.review.candidates
    return CandidateSet([Candidate.reference()]) if c is None else c


def _key(k: int, coupling: str, models) -> tuple:
    return (k, coupling, models.key)


def _response(k: int, coupling: str, models) -> FRF:
    """The all-modes bushing response of ``models`` to harmonic ``k`` (eq. 4.1)."""
    key = _key(k, coupling, models)
    frf = _DONE.get(key)
    if frf is None:
        data = compute.coupled_response(k, None, coupling, models)
        freq = np.asarray(compute.error_map(k, coupling, models).freq, float)
        frf = FRF(freq, np.asarray(data)[:, :, None], BUSHING, ["patch"])
        _DONE.put(key, frf)
    return frf


def _band_settings(s: Snapshot) -> tuple:
    """The noise settings of the verdict's bands and the upper edge's percentile."""
    return (
        float(s.noise),
        s.target,
        bool(s.frequency_dependent),
        int(s.rounds),
        int(s.seed),
        (100 + float(s.percentile)) / 2,
    )


def _edge_key(k: int, coupling: str, models, band: tuple) -> tuple:
    return (k, coupling, models.key, *band)


def _edge(k: int, coupling: str, models, band: tuple) -> NoiseEdge:
    """The upper edge (percentile ``band[-1]``) of the all-modes scatter band of ``models``
    to harmonic ``k`` at the noise settings ``band`` (thesis eqs. 5.2-5.4)."""
    key = _edge_key(k, coupling, models, band)
    edge = _EDGES.get(key)
    if edge is None:
        noise, target, fdep, rounds, seed, q = band
        res = compute.band_once(k, None, coupling, noise, target, fdep, rounds, seed, models)
        edge = NoiseEdge.of_band(res, q)
        _EDGES.put(key, edge)
    return edge


def _jobs(s: Snapshot) -> tuple[list[tuple], list[tuple], list[tuple]]:
    """What the verdict needs: responses ``(k, coupling, models)``, tables
    ``(threshold, f_max, coupling, None, models)`` and, with the noise band on, band edges
    ``(k, coupling, models, band settings)``, each list in the candidates' order."""
    responses, tables, edges = [], [], []
    band = _band_settings(s)
    for c in candidates_of(s):
        m = candidate_models(s.models, c)
        responses += [(k, s.coupling, m) for k in HARMONIC_CASES]
        tables.append((s.threshold, s.f_max, s.coupling, None, m))
        if s.verdict_band:
            edges += [(k, s.coupling, m, band) for k in HARMONIC_CASES]
    return responses, tables, edges


def _missing(s: Snapshot) -> tuple[list[tuple], list[tuple], list[tuple]]:
    responses, tables, edges = _jobs(s)
    return (
        [r for r in responses if _key(*r) not in _DONE],
        [t for t in tables if not compute.suggested_table_ready(*t)],
        [e for e in edges if _edge_key(*e) not in _EDGES],
    )


def verdict_work(s: Snapshot) -> Callable[[], Iterator[None]] | None:
    """The responses and tables the verdict still lacks, one by one (None: none)."""
    if not s.review.judged:
        return None
    responses, tables, edges = _missing(s)
    if not responses and not tables and not edges:
        return None

    def work() -> Iterator[None]:
        for k, coupling, m in responses:
            _response(k, coupling, m)
            yield
        for t in tables:
            compute.suggested_table(*t)
            yield
        for e in edges:  # the slowest last: the verdict without them is not shown meanwhile
            _edge(*e)
            yield

    return work


def _verdict(s: Snapshot) -> Verdict:
    cands = candidates_of(s)
    responses: dict[tuple[str, int], FRF] = {}
    bands: dict[tuple[str, int], NoiseEdge] = {}
    deliveries = []
    band = _band_settings(s)
    for c in cands:
        m = candidate_models(s.models, c)
        for k in HARMONIC_CASES:
            responses[(c.name, k)] = _response(k, s.coupling, m)
            if s.verdict_band:
                bands[(c.name, k)] = _edge(k, s.coupling, m, band)
        table = compute.suggested_table(s.threshold, s.f_max, s.coupling, None, m)
        deliveries.append(assess_delivery(c, table["result"]))
    targets: list[Any] = list(s.review.targets)
    if s.review.incumbent is not None:
        targets.append(s.review.incumbent)
    return verdict(responses, targets, bands or None, candidates=cands, deliveries=deliveries)


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
        "noise band": (
            f"upper {(100 + s.percentile) / 2:g} % edge of {s.rounds:,} rounds, noise "
            f"{s.noise:g} % on {s.target}"
            + (", a new factor per line" if s.frequency_dependent else "")
            + f", seed {s.seed}"
            if s.verdict_band
            else "off (pass or fail of the nominal responses only)"
        ),
        "delivery threshold_pct": s.threshold,
        "delivery f_max_Hz": s.f_max,
        "models": s.models.describe(),
    }


def verdict_result(s: Snapshot) -> Result:
    """The verdict's table (one row per candidate x harmonic x DOF with a target), its
    ranking and the deliveries; pending while :func:`verdict_work` computes."""
    cands = candidates_of(s)
    meta = _meta(s, cands)
    band = f"_band{s.noise:g}pct_R{s.rounds}_s{s.seed}" if s.verdict_band else ""
    name = f"verdict_{len(cands)}cand_{s.review.key[:8]}_{s.coupling}{band}.csv"
    if not s.review.judged:
        return Result(
            meta=meta,
            filename=name,
            caption="No targets: load a target file, type a target or choose the incumbent.",
            draw={"state": "no targets", "candidates": cands},
        )
    responses, tables, edges = _missing(s)
    if responses or tables or edges:
        total = len(cands) * (len(HARMONIC_CASES) * (2 if s.verdict_band else 1) + 1)
        done = total - len(responses) - len(tables) - len(edges)
        what = "responses and noise bands" if s.verdict_band else "responses"
        return Result(
            meta=meta,
            filename=name,
            caption=f"Computing the candidates' {what}: {done} of {total} ...",
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
            + (" with the noise band" if s.verdict_band else "")
            + (f"; best: **{best.candidate}** ({best.status})" if best is not None else "")
        ),
        draw={"state": "done", "verdict": v, "candidates": cands},
        core={"verdict": v},
    )


# -- the candidates and the target on the coupled-response plot ---------------------------------
#: The snapshot fields the overlay of the candidates and the target is made of.
CURVES_DEPENDS = (
    "review", "harmonic", "dof", "coupling", "models", "level_scale", "scope",
    *VEHICLE_FIELDS,
)  # fmt: skip


def _target_of(s: Snapshot, freq: np.ndarray) -> tuple[np.ndarray | None, str]:
    """The target level (dB re 1 SI, NaN outside its range) of the shown DOF and harmonic:
    its own target, else one of every harmonic, else the incumbent rule (None: none)."""
    dof = f"bushing:{s.dof}"
    mine = [t for t in s.review.targets if t.dof == dof]
    t = next((t for t in mine if t.harmonic == s.harmonic), None) or next(
        (t for t in mine if t.harmonic is None), None
    )
    if t is not None:
        k = "all" if t.harmonic is None else t.harmonic
        return np.asarray(t.level_db_at(freq, "mobility", 1.0), float), f"{t.dof} h{k} {t.source}"
    inc = s.review.incumbent
    if inc is None or (inc.dofs is not None and dof not in inc.dofs):
        return None, ""
    c = candidates_of(s).get(inc.candidate)
    m = candidate_models(s.models, c)
    if _key(s.harmonic, s.coupling, m) not in _DONE:
        return None, ""  # the incumbent's response is being computed (curves_work)
    label = f"incumbent {inc.candidate} {inc.margin_db:+g} dB"
    t = Target.from_response(
        _response(s.harmonic, s.coupling, m), dof, inc.margin_db, s.harmonic, label
    )
    return np.asarray(t.level_db_at(freq, "mobility", 1.0), float), label


def _others(s: Snapshot, vehicle: bool = False) -> list[tuple[Candidate, Any, int]]:
    """The candidates other than the current one, with their models and colour slots (in
    vehicle scope only where ``vehicle``: the views that draw the car's candidates)."""
    cands = s.review.candidates
    if cands is None or (s.vehicle and not vehicle):
        return []
    return [
        (c, candidate_models(s.models, c), cands.slot(c.digest))
        for c in cands
        if c.digest != cands.current_digest
    ]


#: The car's all-modes levels at a point per candidate (one DOF's level per line, the
#: road's tracks and wheels as the page's), ~15 kB each.
_CAR = _Kept()


def _car_key(s: Snapshot, models) -> tuple:
    return (s.harmonic, s.coupling, s.point, s.road, tuple(s.wheels), models.key)


def _car_levels(s: Snapshot, models) -> np.ndarray:
    """The car's all-modes response level at the page's point (six DOFs, shape (n_f, 6))
    with ``models``' tire on the four wheels, to the page's road (thesis eq. 4.1, the four
    hubs as one interface)."""
    key = _car_key(s, models)
    got = _CAR.get(key)
    if got is None:
        resp = vc.response(s.harmonic, None, s.coupling, s.point, s.road, tuple(s.wheels), models)
        outs = list(resp.response.outputs)
        got = np.stack([resp.level[:, outs.index(f"{s.point}:{d}")] for d in DIRECTIONS], 1)
        _CAR.put(key, got)
    return got


def curves_work(s: Snapshot) -> Callable[[], Iterator[None]] | None:
    """The other candidates' responses to the shown harmonic not computed yet (None: none)."""
    if s.vehicle:
        cars = [m for _c, m, _slot in _others(s, True) if _car_key(s, m) not in _CAR]
        if not cars:
            return None

        def car_work() -> Iterator[None]:
            for m in cars:
                _car_levels(s, m)
                yield

        return car_work
    todo = [(s.harmonic, s.coupling, m) for _c, m, _slot in _others(s)]
    inc = s.review.incumbent
    if inc is not None and not s.vehicle and inc.candidate in candidates_of(s):
        todo.append(
            (
                s.harmonic,
                s.coupling,
                candidate_models(s.models, candidates_of(s).get(inc.candidate)),
            )
        )
    todo = [t for t in dict.fromkeys(todo) if _key(*t) not in _DONE]
    if not todo:
        return None

    def work() -> Iterator[None]:
        for k, coupling, m in todo:
            _response(k, coupling, m)
            yield

    return work


def review_curves_result(s: Snapshot) -> Result:
    """The other candidates' coupled responses (all modes) to the shown harmonic at the
    shown DOF, and the target there, for the coupled-response plot (corner scope)."""
    freq = np.asarray(compute.frequencies(s.harmonic), float)
    j = DIRECTIONS.index(s.dof)
    lin = s.level_scale != "dB"
    curves, cols, pending = [], {"freq_Hz": freq}, []
    for c, m, slot in _others(s, True) if s.vehicle else ():
        if _car_key(s, m) not in _CAR:
            pending.append(c.name)
            continue
        lv = _car_levels(s, m)[:, j]
        db = magnitude_db(lv)
        cols[f"{c.name}_dB"] = db
        curves.append({"name": c.name, "slot": slot, "y": lv if lin else db, "freq": freq})
    for c, m, slot in _others(s):
        if _key(s.harmonic, s.coupling, m) not in _DONE:
            pending.append(c.name)
            continue
        r = _response(s.harmonic, s.coupling, m)
        h = r.data[:, j, 0]
        db = magnitude_db(h)
        cols[f"{c.name}_dB"] = db
        curves.append({"name": c.name, "slot": slot, "y": np.abs(h) if lin else db, "freq": r.freq})
    target, label = (None, "") if s.vehicle else _target_of(s, freq)
    if target is not None:
        cols["target_dB"] = target
    return Result(
        columns=cols,
        meta={
            "view": "review: the other candidates (all modes) and the target at the response",
            "harmonic": s.harmonic,
            "response DOF": s.output,
            "coupling": s.coupling,
            **(vehicle_meta(s) if s.vehicle else {}),
            "candidates": ", ".join(str(c["name"]) for c in curves) or "none",
            "target": label or "none",
            "models": s.models.describe(),
        },
        filename=f"review_curves_h{s.harmonic}_{s.output.replace(':', '_')}_{s.review.key[:8]}.csv",
        draw={
            "freq": freq,
            "curves": curves,
            "target": None if target is None else (10 ** (target / 20) if lin else target),
            "target_label": f"target: {label}" if label else "",
            "pending": bool(pending),
        },
    )


# -- the candidates' scatter bands on the scatter-band plot -------------------------------------
#: The snapshot fields the other candidates' bands are made of (those of the page's band).
BANDS_DEPENDS = (
    "review",
    "harmonic",
    "n_modes",
    "dof",
    "coupling",
    "models",
    "percentile",
    "scope",
    *BAND_FIELDS[:5],
)
#: Band edges kept (per candidate, harmonic, N, noise settings and percentile band: the
#: central band's two edges at the six DOFs, at most ~0.2 MB each).
KEPT_BANDS = 64
_BANDS = _Kept(KEPT_BANDS)


def _band_key(s: Snapshot, m) -> tuple:
    return (
        compute.band_key(
            s.harmonic, s.n_modes, s.coupling, s.noise, s.target, s.frequency_dependent,
            s.rounds, s.seed, m,
        ),
        int(s.percentile),
    )  # fmt: skip


def _band_edges(s: Snapshot, m) -> dict[str, Any]:
    """The central percentile band of ``models`` at the page's band settings (thesis
    eqs. 5.2-5.4, N modes as the page's band): its two edges at the six DOFs."""
    key = _band_key(s, m)
    got = _BANDS.get(key)
    if got is None:
        res = compute.band_once(
            s.harmonic, s.n_modes, s.coupling, s.noise, s.target, s.frequency_dependent,
            s.rounds, s.seed, m,
        )  # fmt: skip
        lo, hi = (100 - s.percentile) / 2, (100 + s.percentile) / 2
        q = [float(x) for x in np.asarray(res.q, float)]
        pct = np.asarray(res.percentiles, float)
        got = {
            "freq": np.asarray(res.freq, float),
            "dofs": tuple(res.dofs),
            "low": pct[q.index(lo)].copy(),
            "high": pct[q.index(hi)].copy(),
        }
        _BANDS.put(key, got)
    return got


def _digest_of(curves: list[dict[str, Any]]) -> str:
    """A short digest of the candidates drawn (their files' digests): a file name of its own
    per set of candidates, not per target."""
    import hashlib

    digests = "\n".join(str(c["digest"]) for c in curves)
    return hashlib.sha256(digests.encode()).hexdigest()[:8]


def bands_work(s: Snapshot) -> Callable[[], Iterator[None]] | None:
    """The other candidates' bands not computed yet (None: none)."""
    todo = [m for _c, m, _slot in _others(s) if _band_key(s, m) not in _BANDS]
    if not todo:
        return None

    def work() -> Iterator[None]:
        for m in todo:
            _band_edges(s, m)
            yield

    return work


def review_bands_result(s: Snapshot) -> Result:
    """The other candidates' central percentile bands at the shown DOF, at the page's band
    settings (N modes, noise, rounds, seed), for the scatter-band plot (corner scope)."""
    label = f"bushing:{s.dof}"
    curves, pending = [], []
    freq = np.asarray(compute.frequencies(s.harmonic), float)
    cols: dict[str, np.ndarray] = {"freq_Hz": freq}
    for c, m, slot in _others(s):
        if _band_key(s, m) not in _BANDS:
            pending.append(c.name)
            continue
        e = _band_edges(s, m)
        j = e["dofs"].index(label)
        low, high = magnitude_db(e["low"][:, j]), magnitude_db(e["high"][:, j])
        cols[f"{c.name}_low_dB"], cols[f"{c.name}_high_dB"] = low, high
        curves.append(
            {"name": c.name, "digest": c.digest, "slot": slot, "freq": e["freq"], "low": low,
             "high": high}
        )  # fmt: skip
    lo, hi = (100 - s.percentile) / 2, (100 + s.percentile) / 2
    return Result(
        columns=cols,
        meta={
            "view": "review: the other candidates' scatter bands (central percentile band)",
            "harmonic": s.harmonic,
            "N": s.n_modes,
            "response DOF": label,
            "coupling": s.coupling,
            "noise_pct": s.noise,
            "target": s.target,
            "frequency dependent": s.frequency_dependent,
            "rounds": s.rounds,
            "seed": s.seed,
            "percentiles": f"{lo:g}-{hi:g}",
            "candidates": ", ".join(str(c["name"]) for c in curves) or "none",
            "models": s.models.describe(),
        },
        filename=f"review_bands_h{s.harmonic}_N{s.n_modes}_{s.dof}_{_digest_of(curves)}.csv",
        draw={"curves": curves, "pending": pending},
    )
