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

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from fbs_core import FRF
from fbs_core.candidates import Candidate, CandidateSet
from fbs_core.delivery import assess_delivery
from fbs_core.dofs import parse_label
from fbs_core.errors import FBSError
from fbs_core.targets import Target, response_level
from fbs_core.vehicle import RESPONSE_NODES
from fbs_core.verdict import NoiseEdge, Verdict, verdict
from fbs_core.vocabulary import DIRECTIONS, HARMONIC_CASES, magnitude_db

from .. import compute
from ..datasource import CAR_DOFS, candidate_models
from . import vehicle_compute as vc
from .base import VEHICLE_FIELDS, Result, Snapshot
from .scope import vehicle_meta

__all__ = [
    "BANDS_DEPENDS",
    "CAR_DOFS",
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
    "scope",
    *VEHICLE_FIELDS,
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


#: Where a car's response is taken: ``(point, track relation, wheels driven)``.
Car = tuple[str, str | float, tuple[str, ...]]


def _key(k: int, coupling: str, models, car: Car | None = None) -> tuple:
    return (k, coupling, models.key) if car is None else (k, coupling, models.key, *car)


def _response(k: int, coupling: str, models, car: Car | None = None) -> FRF:
    """The all-modes response of ``models`` to harmonic ``k`` (eq. 4.1): at the corner's
    bushing to the patch, or (``car``) at a point of the car with the tire on the four
    wheels, per uncorrelated component of the road (the four hubs as one interface)."""
    key = _key(k, coupling, models, car)
    frf = _DONE.get(key)
    if frf is None:
        if car is None:
            data = compute.coupled_response(k, None, coupling, models)
            freq = np.asarray(compute.error_map(k, coupling, models).freq, float)
            frf = FRF(freq, np.asarray(data)[:, :, None], BUSHING, ["patch"])
        else:
            point, road, wheels = car
            frf = vc.response(k, None, coupling, point, road, wheels, models).response
        _DONE.put(key, frf)
    return frf


def _joined(frfs: list[FRF]) -> FRF:
    """The car's responses at several points as one response (their outputs side by side;
    the points share the road, so its components)."""
    if len(frfs) == 1:
        return frfs[0]
    first = frfs[0]
    return FRF(
        first.freq,
        np.concatenate([f.data for f in frfs], axis=1),
        [o for f in frfs for o in f.outputs],
        first.inputs,
        first.quantity,
        kinds={i: k for i, k in first.kinds.items() if i in first.inputs},
    )


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


def _edge_key(k: int, coupling: str, models, band: tuple, car: Car | None = None) -> tuple:
    return (*_key(k, coupling, models, car), *band)


def _edge(k: int, coupling: str, models, band: tuple, car: Car | None = None) -> NoiseEdge:
    """The upper edge (percentile ``band[-1]``) of the all-modes scatter band of ``models``
    to harmonic ``k`` at the noise settings ``band`` (thesis eqs. 5.2-5.4), at the corner
    or at a point of the car (a coherent road). The band itself is not kept."""
    key = _edge_key(k, coupling, models, band, car)
    edge = _EDGES.get(key)
    if edge is None:
        noise, target, fdep, rounds, seed, q = band
        if car is None:
            res = compute.band_once(k, None, coupling, noise, target, fdep, rounds, seed, models)
        else:
            point, road, wheels = car
            bkey = compute.band_key(
                k, None, coupling, noise, target, fdep, rounds, seed, models, (wheels, road, point)
            )
            res = vc.band_once(bkey)
        edge = NoiseEdge.of_band(res, q)
        _EDGES.put(key, edge)
    return edge


def _joined_edges(edges: list[NoiseEdge]) -> NoiseEdge:
    e = edges[0]
    if len(edges) == 1:
        return e
    dofs = tuple(d for x in edges for d in x.dofs)
    return NoiseEdge(
        e.freq, dofs, np.concatenate([x.upper for x in edges], axis=1), e.q, e.quantity
    )


def car_points(s: Snapshot) -> tuple[str, ...]:
    """The car's points the verdict judges in vehicle scope: those with a target, and the
    page's point while the incumbent rule is on (the rule judges the point shown)."""
    pts = {parse_label(t.dof)[0] for t in s.review.targets if t.dof in CAR_DOFS}
    if s.review.incumbent is not None:
        pts.add(s.point)
    return tuple(p for p in RESPONSE_NODES if p in pts)


def _cars(s: Snapshot) -> list[Car | None]:
    """Where the verdict takes its responses: the corner (``[None]``) or the car's judged
    points on the page's road."""
    if not s.vehicle:
        return [None]
    return [(p, s.road, tuple(s.wheels)) for p in car_points(s)]


def _band_judged(s: Snapshot) -> bool:
    """Whether the verdict's noise bands can be computed (the car's need a coherent road)."""
    return bool(s.verdict_band) and (not s.vehicle or vc.coherent(s.road))


def _jobs(s: Snapshot) -> tuple[list[tuple], list[tuple], list[tuple]]:
    """What the verdict needs: responses ``(k, coupling, models, car)``, tables
    ``(threshold, f_max, coupling, None, models)`` and, with the noise band on, band edges
    ``(k, coupling, models, band settings, car)``, each list in the candidates' order."""
    responses, tables, edges = [], [], []
    band = _band_settings(s)
    cars = _cars(s)
    for c in candidates_of(s):
        m = candidate_models(s.models, c)
        responses += [(k, s.coupling, m, car) for k in HARMONIC_CASES for car in cars]
        tables.append((s.threshold, s.f_max, s.coupling, None, m))
        if _band_judged(s):
            edges += [(k, s.coupling, m, band, car) for k in HARMONIC_CASES for car in cars]
    return responses, tables, edges


def _missing(s: Snapshot) -> tuple[list[tuple], list[tuple], list[tuple]]:
    responses, tables, edges = _jobs(s)
    return (
        [r for r in responses if _key(*r) not in _DONE],
        [t for t in tables if not compute.suggested_table_ready(*t)],
        [e for e in edges if _edge_key(*e) not in _EDGES],
    )


def _judged_targets(s: Snapshot) -> list[Target]:
    """The targets of the scope: the corner's bushing, or the car's response points."""
    car = set(CAR_DOFS)
    return [t for t in s.review.targets if (t.dof in car) == s.vehicle]


def verdict_work(s: Snapshot) -> Callable[[], Iterator[None]] | None:
    """The responses and tables the verdict still lacks, one by one (None: none)."""
    if not s.review.judged:
        return None
    responses, tables, edges = _missing(s)
    if not responses and not tables and not edges:
        return None

    def work() -> Iterator[None]:
        for r in responses:
            _response(*r)
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
    cars = _cars(s)
    if s.verdict_band and not _band_judged(s):
        raise FBSError(
            "the noise band of the car needs a coherent road: tracks in phase or in "
            f"anti-phase (now a coherence of {float(s.road):g}); or switch the noise band off"
        )
    for c in cands:
        m = candidate_models(s.models, c)
        for k in HARMONIC_CASES:
            responses[(c.name, k)] = _joined([_response(k, s.coupling, m, car) for car in cars])
            if s.verdict_band:
                bands[(c.name, k)] = _joined_edges(
                    [_edge(k, s.coupling, m, band, car) for car in cars]
                )
        table = compute.suggested_table(s.threshold, s.f_max, s.coupling, None, m)
        deliveries.append(assess_delivery(c, table["result"]))
    targets: list[Any] = _judged_targets(s)
    if s.review.incumbent is not None:
        targets.append(s.review.incumbent)
    return verdict(responses, targets, bands or None, candidates=cands, deliveries=deliveries)


def _meta(s: Snapshot, cands: CandidateSet) -> dict[str, Any]:
    r = s.review
    responses = (
        "the car's velocity at its response points "
        f"({', '.join(car_points(s)) or 'none with a target'}) per metre of road (eq. 4.1, "
        "the tire on the four wheels, the four hubs as one interface)"
        if s.vehicle
        else "coupled bushing velocity per metre of road (eq. 4.1)"
    )
    return {
        "view": "review verdict: candidates against the targets (docs/verdict.md)",
        "responses": f"{responses}, every mode each candidate delivered, harmonics 1-7",
        "coupling": s.coupling,
        **(vehicle_meta(s) if s.vehicle else {"scope": "corner (the bushing's targets)"}),
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
    car = _car_tag(s)
    name = f"verdict_{len(cands)}cand_{s.review.key[:8]}_{s.coupling}{band}{car}.csv"
    if not s.review.judged:
        return Result(
            meta=meta,
            filename=name,
            caption="No targets: load a target file, type a target or choose the incumbent.",
            draw={"state": "no targets", "candidates": cands},
        )
    if not s.vehicle and not _judged_targets(s) and s.review.incumbent is None:
        return Result(
            meta=meta,
            filename=name,
            caption="No target at the bushing: the targets at the car's response points "
            "judge the vehicle scope.",
            draw={"state": "no targets", "candidates": cands},
        )
    if s.vehicle and not car_points(s):
        return Result(
            meta=meta,
            filename=name,
            caption="No target at the car's response points: load targets for its points "
            "(e.g. bushing_rl:z, seat_fl:z) or choose the incumbent rule; the bushing's "
            "targets judge the corner scope.",
            draw={"state": "no targets", "candidates": cands},
        )
    responses, tables, edges = _missing(s)
    if responses or tables or edges:
        per = len(HARMONIC_CASES) * len(_cars(s))
        total = len(cands) * (per * (2 if _band_judged(s) else 1) + 1)
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
            f"**{len(cands)} candidates** against {len(_judged_targets(s))} target(s)"
            + (f" at the car's {', '.join(car_points(s))}" if s.vehicle else "")
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
    dof = s.output
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
    car = _car_of(s)
    if _key(s.harmonic, s.coupling, m, car) not in _DONE:
        return None, ""  # the incumbent's response is being computed (curves_work)
    label = f"incumbent {inc.candidate} {inc.margin_db:+g} dB"
    t = Target.from_response(
        _response(s.harmonic, s.coupling, m, car), dof, inc.margin_db, s.harmonic, label
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


def _car_of(s: Snapshot) -> Car | None:
    """Where the page's response is taken in vehicle scope (None: the corner)."""
    return (s.point, s.road, tuple(s.wheels)) if s.vehicle else None


def _car_key(s: Snapshot, models) -> tuple:
    return _key(s.harmonic, s.coupling, models, _car_of(s))


def _car_levels(s: Snapshot, models) -> np.ndarray:
    """The car's all-modes response level at the page's point (six DOFs, shape (n_f, 6))
    with ``models``' tire on the four wheels, to the page's road (thesis eq. 4.1, the four
    hubs as one interface; uncorrelated road components added in power)."""
    r = _response(s.harmonic, s.coupling, models, _car_of(s))
    level = response_level(r)
    outs = list(r.outputs)
    return np.stack([level[:, outs.index(f"{s.point}:{d}")] for d in DIRECTIONS], 1)


def _incumbent_models(s: Snapshot):
    """The incumbent rule's candidate's models (None: no rule, or its tire not loaded)."""
    inc = s.review.incumbent
    if inc is None or inc.candidate not in candidates_of(s):
        return None
    return candidate_models(s.models, candidates_of(s).get(inc.candidate))


def curves_work(s: Snapshot) -> Callable[[], Iterator[None]] | None:
    """The other candidates' responses to the shown harmonic not computed yet (None: none)."""
    if s.vehicle:
        cars = [m for _c, m, _slot in _others(s, True)]
        inc = _incumbent_models(s)
        if inc is not None:
            cars.append(inc)
        cars = [m for m in dict.fromkeys(cars) if _car_key(s, m) not in _DONE]
        if not cars:
            return None

        def car_work() -> Iterator[None]:
            for m in cars:
                _car_levels(s, m)
                yield

        return car_work
    todo = [(s.harmonic, s.coupling, m) for _c, m, _slot in _others(s)]
    inc = _incumbent_models(s)
    if inc is not None:
        todo.append((s.harmonic, s.coupling, inc))
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
        if _car_key(s, m) not in _DONE:
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
    target, label = _target_of(s, freq)
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
    *VEHICLE_FIELDS,
)
#: Band edges kept (per candidate, harmonic, N, noise settings and percentile band: the
#: central band's two edges at the six DOFs, at most ~0.2 MB each).
KEPT_BANDS = 64
_BANDS = _Kept(KEPT_BANDS)


def _band_key(s: Snapshot, m) -> tuple:
    return (
        compute.band_key(
            s.harmonic, s.n_modes, s.coupling, s.noise, s.target, s.frequency_dependent,
            s.rounds, s.seed, m, s.vehicle_band_key(),
        ),
        int(s.percentile),
    )  # fmt: skip


def _bands_drawn(s: Snapshot) -> bool:
    """Whether the other candidates' bands can be drawn: the car's need a coherent road
    (as the page's own band)."""
    return not s.vehicle or vc.coherent(s.road)


def _band_edges(s: Snapshot, m) -> dict[str, Any]:
    """The central percentile band of ``models`` at the page's band settings (thesis
    eqs. 5.2-5.4, N modes as the page's band): its two edges at the six DOFs of the
    corner's bushing, or of the car's point with the tire on its four wheels."""
    key = _band_key(s, m)
    got = _BANDS.get(key)
    if got is None:
        bkey = key[0]
        if bkey.is_car:
            res = vc.band_once(bkey)
        else:
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


def _digest_text(text: str) -> str:
    """Eight hex digits of ``text``'s SHA-256: a file name's short, stable tag."""
    return hashlib.sha256(text.encode()).hexdigest()[:8]


def _car_tag(s: Snapshot) -> str:
    """``_car_<tag>`` of the car's settings for a file name in vehicle scope, else ``""``."""
    return f"_car_{_digest_text(repr(s.vehicle_key()))}" if s.vehicle else ""


def _digest_of(curves: list[dict[str, Any]]) -> str:
    """A short digest of the candidates drawn (their files' digests): a file name of its own
    per set of candidates, not per target."""
    return _digest_text("\n".join(str(c["digest"]) for c in curves))


def bands_work(s: Snapshot) -> Callable[[], Iterator[None]] | None:
    """The other candidates' bands not computed yet (None: none)."""
    inc = _incumbent_models(s)  # the target line of the incumbent rule needs its response
    car = _car_of(s)
    need_inc = inc is not None and _key(s.harmonic, s.coupling, inc, car) not in _DONE
    todo = (
        [m for _c, m, _slot in _others(s, True) if _band_key(s, m) not in _BANDS]
        if _bands_drawn(s)
        else []
    )
    if not todo and not need_inc:
        return None

    def work() -> Iterator[None]:
        if need_inc:
            _response(s.harmonic, s.coupling, inc, car)
            yield
        for m in todo:
            _band_edges(s, m)
            yield

    return work


def review_bands_result(s: Snapshot) -> Result:
    """The other candidates' central percentile bands at the shown DOF, at the page's band
    settings (N modes, noise, rounds, seed), and the target there (dB, as
    :func:`review_curves_result`), for the scatter-band plot: at the corner's
    bushing, or in vehicle scope at the car's point with each candidate's tire on the four
    wheels (a coherent road, as the page's own band)."""
    label = s.output
    curves, pending = [], []
    freq = np.asarray(compute.frequencies(s.harmonic), float)
    cols: dict[str, np.ndarray] = {"freq_Hz": freq}
    for c, m, slot in _others(s, True) if _bands_drawn(s) else ():
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
    target, target_label = _target_of(s, freq)
    if target is not None:
        cols["target_dB"] = target
    lo, hi = (100 - s.percentile) / 2, (100 + s.percentile) / 2
    car = _car_tag(s)
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
            **(vehicle_meta(s) if s.vehicle else {}),
            "candidates": ", ".join(str(c["name"]) for c in curves) or "none",
            "target line": target_label or "none",
            "models": s.models.describe(),
        },
        filename=f"review_bands_h{s.harmonic}_N{s.n_modes}_{s.output.replace(':', '_')}"
        f"{car}_{_digest_of(curves)}.csv",
        draw={
            "curves": curves,
            "pending": pending,
            "freq": freq,
            "target": target,
            "target_label": f"target: {target_label}" if target_label else "",
        },
    )
