"""The review's verdict: every candidate's response against its targets, and a ranking.

:func:`verdict` is a pure function of the responses (the coupled bushing response of
eq. 4.1, or any response with labelled outputs, per candidate and harmonic), the targets
(:mod:`fbs_core.targets`) and, optionally, the noise scatter bands of eqs. 5.2-5.4
(:class:`fbs_core.studies.ScatterBand`: the upper edge is its highest percentile). It
returns a :class:`Verdict`: one :class:`VerdictRow` per candidate x harmonic x output DOF
that has a target, and a ranking of the candidates.

Rules (docs/verdict.md):

* **Level.** ``L = 20 log10 |v|`` in dB re 1 SI unit at every line
  (:func:`fbs_core.targets.response_level`; the upper band edge likewise), the target
  ``T`` evaluated on the response's lines in the response's quantity
  (:meth:`fbs_core.targets.Target.level_db_at`).
* **Judged lines.** The lines inside the target's range, the first and last included;
  outside it the target is not extrapolated and the lines are not judged. Every judged
  line counts alike, the band's first and last lines as any other.
* **Worst.** ``d = max (L - T)`` over the judged lines, with the frequency of that line
  and its vehicle speed on the harmonic's speed line ``v = 3.6 f lambda``
  (:meth:`fbs_core.harmonics.Harmonic.speed_at`). ``d > 0`` is the worst exceedance;
  otherwise ``-d >= 0`` is the margin (the smallest distance below the target).
* **Status.** ``fail`` when ``d > 0``; otherwise ``fails within the noise band`` when
  the band's upper edge exceeds the target at some judged line; otherwise ``pass``. A
  level equal to the target passes. ``not judged`` when no line is inside the target's
  range.
* **Ranking.** A candidate's status is its worst row's (fail > fails within the noise
  band > pass; ``not judged`` only when no row is judged); candidates are ranked by
  status (pass first, fail last, not judged after them), then by their largest ``d``
  over all rows (the smallest exceedance, or the largest smallest margin, first), then in
  their given order.

Which target a row takes: a :class:`~fbs_core.targets.Target` of that DOF and harmonic,
else one of that DOF for every harmonic, else the
:class:`~fbs_core.targets.IncumbentTarget` (the incumbent's response to the same
harmonic plus its margin).
"""

from __future__ import annotations

import csv as _csv
import io
import math
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ._typing import FloatArray
from .delivery import Delivery
from .dofs import parse_label
from .errors import DOFError, FBSError, FrequencyGridError, QuantityError
from .frf import FRF
from .harmonics import harmonic as _harmonic
from .targets import IncumbentTarget, Target, response_level
from .vocabulary import magnitude_db, readonly

if TYPE_CHECKING:
    from .candidates import CandidateSet
    from .studies import ScatterBand

__all__ = [
    "FAIL",
    "NOISE_FAIL",
    "NOT_JUDGED",
    "PASS",
    "STATUSES",
    "NoiseEdge",
    "Standing",
    "Verdict",
    "VerdictRow",
    "verdict",
]

PASS = "pass"
NOISE_FAIL = "fails within the noise band"
FAIL = "fail"
NOT_JUDGED = "not judged"
#: The statuses from best to worst (the ranking's order).
STATUSES: tuple[str, ...] = (PASS, NOISE_FAIL, FAIL, NOT_JUDGED)


@dataclass(frozen=True)
class NoiseEdge:
    """The upper edge of a noise band: the level the response reaches with noise.

    Parameters
    ----------
    freq : array_like, shape (n_f,)
        Lines in Hz.
    dofs : tuple of str, length n_dof
    upper : array_like, shape (n_f, n_dof)
        Linear level (SI) of the upper edge.
    q : float
        Its percentile in % (100: the maximum over the rounds).
    quantity : str
        Quantity of the levels (that of the response).
    """

    freq: FloatArray
    dofs: tuple[str, ...]
    upper: FloatArray
    q: float = 100.0
    quantity: str = "mobility"

    def __post_init__(self) -> None:
        from .frf import check_grid

        f = check_grid(self.freq)
        u = np.asarray(self.upper, float)
        dofs = tuple(self.dofs)
        if u.shape != (f.size, len(dofs)):
            raise FBSError(
                f"the band's upper edge has shape {u.shape}, expected (n_f, n_dof) = "
                f"{(f.size, len(dofs))}"
            )
        if not np.all(np.isfinite(u)) or np.any(u < 0):
            raise FBSError("the band's upper edge must be finite non-negative levels")
        object.__setattr__(self, "freq", readonly(f))
        object.__setattr__(self, "upper", readonly(u))
        object.__setattr__(self, "dofs", dofs)
        object.__setattr__(self, "q", float(self.q))

    @classmethod
    def of_band(cls, band: ScatterBand, q: float | None = None) -> NoiseEdge:
        """The upper edge of a scatter band (eqs. 5.2-5.4): its percentile ``q`` (default
        the highest it holds); ``q=100`` takes the maximum over the rounds.

        Raises
        ------
        FBSError
            For a percentile the band does not hold, naming those it does.
        """
        qs = [float(x) for x in np.asarray(band.q, float)]
        if q is None:
            q = max(qs) if qs else 100.0
        q = float(q)
        if q == 100.0 and q not in qs:
            upper = np.asarray(band.maximum, float)
        elif q in qs:
            upper = np.asarray(band.percentiles, float)[qs.index(q)]
        else:
            raise FBSError(
                f"the band holds the percentiles {', '.join(f'{x:g}' for x in qs)} %, not "
                f"{q:g} % (100: the maximum)"
            )
        return cls(band.freq, tuple(band.dofs), upper, q, "mobility")


@dataclass(frozen=True)
class VerdictRow:
    """One candidate x harmonic x output DOF against its target (module notes).

    Attributes
    ----------
    candidate, digest : str
    harmonic : int
    point, dof : str
        The response point (node) and its DOF label ``"point:dir"``.
    status : str
        One of :data:`STATUSES`.
    worst_db : float
        ``max (L - T)`` over the judged lines, dB (NaN when not judged).
    freq, speed : float
        Line (Hz) and vehicle speed (km/h) of ``worst_db``.
    margin_db : float
        ``-worst_db`` where it passes (``>= 0``), NaN where it fails.
    band_worst_db, band_freq, band_speed : float
        The same for the band's upper edge (NaN without a band).
    band_q : float
        Percentile of the band's edge (NaN without a band).
    lines : int
        Lines judged.
    target : str
        Where the target came from.
    """

    candidate: str
    digest: str
    harmonic: int
    point: str
    dof: str
    status: str
    worst_db: float
    freq: float
    speed: float
    margin_db: float
    band_worst_db: float
    band_freq: float
    band_speed: float
    band_q: float
    lines: int
    target: str

    @property
    def exceedance_db(self) -> float:
        """The worst exceedance in dB (0 where it passes, NaN when not judged)."""
        return max(self.worst_db, 0.0) if math.isfinite(self.worst_db) else math.nan


@dataclass(frozen=True)
class Standing:
    """A candidate's place in the ranking.

    Attributes
    ----------
    rank : int
        1 for the best.
    candidate, digest, status : str
    worst_db : float
        Largest ``worst_db`` of its rows (NaN when none is judged).
    harmonic : int
    dof : str
    freq, speed : float
        Where that worst row's worst line is (harmonic 0, dof "" when none is judged).
    fails, noise_fails, passes : int
        Rows of each status.
    """

    rank: int
    candidate: str
    digest: str
    status: str
    worst_db: float
    harmonic: int
    dof: str
    freq: float
    speed: float
    fails: int
    noise_fails: int
    passes: int


_ROW_FIELDS = (
    "candidate",
    "digest",
    "harmonic",
    "point",
    "dof",
    "status",
    "worst_db",
    "freq",
    "speed",
    "margin_db",
    "band_worst_db",
    "band_freq",
    "band_speed",
    "band_q",
    "lines",
    "target",
)
_CSV_NAMES = {"freq": "freq_Hz", "speed": "speed_kmh", "band_freq": "band_freq_Hz"}
_CSV_NAMES["band_speed"] = "band_speed_kmh"
_STANDING_FIELDS = (
    "rank",
    "candidate",
    "digest",
    "status",
    "worst_db",
    "harmonic",
    "dof",
    "freq",
    "speed",
    "fails",
    "noise_fails",
    "passes",
)
_DELIVERY_FIELDS = (
    "candidate",
    "digest",
    "adequate",
    "n_modes",
    "suggested",
    "required",
    "converged",
    "enough_modes",
    "speeds",
    "uncovered",
    "warnings",
)


@dataclass(frozen=True)
class Verdict:
    """Rows, ranking and delivery adequacy of a review (:func:`verdict`).

    Attributes
    ----------
    rows : tuple of VerdictRow
        Candidate by candidate (given order), harmonic ascending, DOFs in the response's
        order.
    ranking : tuple of Standing
        Best first.
    deliveries : tuple of Delivery
        Per candidate, where given.
    """

    rows: tuple[VerdictRow, ...]
    ranking: tuple[Standing, ...]
    deliveries: tuple[Delivery, ...] = ()

    def row(self, candidate: str, harmonic: int, dof: str) -> VerdictRow:
        """The row of a candidate (name or digest), harmonic and DOF.

        Raises
        ------
        FBSError
            Naming what the verdict holds.
        """
        for r in self.rows:
            if candidate in (r.candidate, r.digest) and r.harmonic == harmonic and r.dof == dof:
                return r
        raise FBSError(
            f"no verdict row for {candidate!r}, harmonic {harmonic}, {dof}; rows: "
            f"{len(self.rows)} of {', '.join(dict.fromkeys(r.candidate for r in self.rows))}"
        )

    def table(self) -> str:
        """The verdict as plain text: the ranking, then the rows."""
        lines = ["rank  candidate             status                        worst dB"]
        for s in self.ranking:
            lines.append(
                f"{s.rank:>4d}  {s.candidate:<20.20s}  {s.status:<28s}  {s.worst_db:+8.2f}"
            )
        lines.append("")
        lines.append(
            "candidate             h  dof          status                        worst dB"
            "    f Hz  km/h"
        )
        for r in self.rows:
            lines.append(
                f"{r.candidate:<20.20s} {r.harmonic:>2d}  {r.dof:<11s}  {r.status:<28s}  "
                f"{r.worst_db:+8.2f}  {r.freq:6.1f}  {r.speed:4.0f}"
            )
        return "\n".join(lines)

    def to_csv(self, metadata: Mapping[str, Any] | None = None) -> bytes:
        """The verdict as CSV: ``# key: value`` metadata lines (the fbs_core version, the
        export time, the rules), then ``# table: verdict``, ``# table: ranking`` and, with
        deliveries, ``# table: delivery`` blocks with a header row each (the layout of
        :func:`fbs_core.io.export_result`'s CSV; numbers with 17 significant digits; text
        cells safe from spreadsheet formulas)."""
        from .io.csv import _header, safe_cell

        meta: dict[str, Any] = {
            "exported": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "levels": "dB re 1 SI unit of the response (e.g. (m/s)/m)",
            "worst_db": "max over the judged lines of level - target; > 0 fails",
            "margin_db": "-worst_db where the row passes",
            "rule": "fail if worst_db > 0, else 'fails within the noise band' if the band's "
            "upper edge exceeds the target, else pass",
            "ranking": "status (pass, noise band, fail, not judged), then worst_db ascending",
        }
        meta.update(dict(metadata or {}))
        out = io.StringIO()
        out.write("\n".join(_header(meta, "verdict")) + "\n")
        w = _csv.writer(out, lineterminator="\n")

        def cell(x: Any) -> Any:
            if isinstance(x, bool | np.bool_):
                return "yes" if x else "no"
            if isinstance(x, float):
                return repr(x)
            if isinstance(x, str):
                return safe_cell(x)
            if isinstance(x, tuple | list | np.ndarray):
                return safe_cell("; ".join(str(getattr(v, "item", lambda v=v: v)()) for v in x))
            return x

        out.write("\n# table: verdict\n")
        w.writerow([_CSV_NAMES.get(f, f) for f in _ROW_FIELDS])
        for r in self.rows:
            w.writerow([cell(getattr(r, f)) for f in _ROW_FIELDS])
        out.write("\n# table: ranking\n")
        w.writerow([_CSV_NAMES.get(f, f) for f in _STANDING_FIELDS])
        for s in self.ranking:
            w.writerow([cell(getattr(s, f)) for f in _STANDING_FIELDS])
        if self.deliveries:
            out.write("\n# table: delivery\n")
            w.writerow(_DELIVERY_FIELDS)
            for d in self.deliveries:
                w.writerow([cell(getattr(d, f)) for f in _DELIVERY_FIELDS])
        return out.getvalue().encode()


# -- the verdict ----------------------------------------------------------------------------
def verdict(
    responses: Mapping[tuple[str, int], FRF],
    targets: Iterable[Target | IncumbentTarget],
    bands: Mapping[tuple[str, int], ScatterBand | NoiseEdge] | None = None,
    *,
    candidates: CandidateSet | None = None,
    deliveries: Iterable[Delivery] = (),
) -> Verdict:
    """Judge every candidate's responses against the targets (module notes for the rules).

    Parameters
    ----------
    responses : mapping
        ``(candidate, harmonic) -> FRF``: the response of each candidate to each
        harmonic case (e.g. ``bushing_response(k, tire=candidate.model)``), on lines
        inside the harmonic's band. Candidates by name (or digest with ``candidates``).
    targets : iterable of Target or IncumbentTarget
        At most one target per DOF and harmonic (``harmonic=None``: every harmonic).
    bands : mapping, optional
        ``(candidate, harmonic) -> ScatterBand or NoiseEdge`` on the response's lines.
    candidates : CandidateSet, optional
        Resolves names and digests and gives the candidates' order.
    deliveries : iterable of Delivery
        Delivery adequacy to report beside the rows (:func:`fbs_core.delivery.assess_delivery`).

    Returns
    -------
    Verdict

    Raises
    ------
    FBSError
        Unknown candidates or harmonics, two targets for one DOF and harmonic, a missing
        incumbent response.
    DOFError
        A target or band DOF that no response has.
    FrequencyGridError
        Responses outside their harmonic's band, bands on other lines.
    QuantityError
        Targets per another input kind than the response's.
    """
    resp, order = _responses(responses, candidates)
    explicit, incumbent = _targets(targets)
    outputs = {o for r in resp.values() for o in r.outputs}
    for dof, _h in explicit:
        if dof not in outputs:
            raise DOFError(
                f"a target for {dof!r}, which no response has; response DOFs: "
                f"{', '.join(sorted(outputs))}"
            )
    edges = _bands(bands, resp, candidates)
    inc_name = None
    if incumbent is not None:
        inc_name = _candidate(incumbent.candidate, candidates)[0]
        if inc_name not in order:
            raise FBSError(
                f"the incumbent {incumbent.candidate!r} has no responses; candidates: "
                f"{', '.join(order)}"
            )
    rows: list[VerdictRow] = []
    resolved: dict[int, dict[str, Target]] = {}  # the incumbent's targets per harmonic
    for name in order:
        digest = candidates.get(name).digest if candidates is not None else ""
        for k in sorted(h for n, h in resp if n == name):
            frf = resp[(name, k)]
            inc_targets: dict[str, Target] = {}
            if incumbent is not None and inc_name is not None:
                if k not in resolved:
                    base = resp.get((inc_name, k))
                    if base is None:
                        raise FBSError(
                            f"the incumbent {inc_name!r} has no response to harmonic {k}; the "
                            f"target 'incumbent + {incumbent.margin_db:g} dB' needs it"
                        )
                    resolved[k] = {t.dof: t for t in incumbent.resolve(base, k)}
                inc_targets = resolved[k]
            rows += _judge(name, digest, k, frf, explicit, inc_targets, edges.get((name, k)))
    return Verdict(tuple(rows), _ranking(rows, order, candidates), tuple(deliveries))


def _candidate(key: str, candidates: CandidateSet | None) -> tuple[str, str]:
    if candidates is None:
        return str(key), ""
    c = candidates.get(key)
    return c.name, c.digest


def _responses(
    responses: Mapping[tuple[str, int], FRF], candidates: CandidateSet | None
) -> tuple[dict[tuple[str, int], FRF], list[str]]:
    out: dict[tuple[str, int], FRF] = {}
    order: list[str] = []
    for key, frf in responses.items():
        if not (isinstance(key, tuple) and len(key) == 2):
            raise FBSError(f"responses are keyed by (candidate, harmonic), got {key!r}")
        name = _candidate(key[0], candidates)[0]
        k = _harmonic(key[1]).k
        if not isinstance(frf, FRF):
            raise FBSError(f"the response of {name}, harmonic {k} must be an FRF")
        if (name, k) in out:
            raise FBSError(f"two responses of {name} to harmonic {k}")
        out[(name, k)] = frf
        if name not in order:
            order.append(name)
    if not out:
        raise FBSError("no responses to judge")
    if candidates is not None:
        order = [c.name for c in candidates if c.name in order]
    return out, order


def _targets(
    targets: Iterable[Target | IncumbentTarget],
) -> tuple[dict[tuple[str, int | None], Target], IncumbentTarget | None]:
    explicit: dict[tuple[str, int | None], Target] = {}
    incumbent = None
    for t in targets:
        if isinstance(t, IncumbentTarget):
            if incumbent is not None:
                raise FBSError("one incumbent target at a time (its DOFs choose where it applies)")
            incumbent = t
        elif isinstance(t, Target):
            key = (t.dof, t.harmonic)
            if key in explicit:
                h = "every harmonic" if t.harmonic is None else f"harmonic {t.harmonic}"
                raise FBSError(
                    f"two targets for {t.dof} ({h}): {explicit[key].source or 'a target'} and "
                    f"{t.source or 'a target'}"
                )
            explicit[key] = t
        else:
            raise FBSError(f"targets are Target or IncumbentTarget objects, got {type(t).__name__}")
    return explicit, incumbent


def _bands(
    bands: Mapping[tuple[str, int], ScatterBand | NoiseEdge] | None,
    resp: Mapping[tuple[str, int], FRF],
    candidates: CandidateSet | None,
) -> dict[tuple[str, int], NoiseEdge]:
    out: dict[tuple[str, int], NoiseEdge] = {}
    for key, band in (bands or {}).items():
        name = _candidate(key[0], candidates)[0]
        k = _harmonic(key[1]).k
        edge = band if isinstance(band, NoiseEdge) else NoiseEdge.of_band(band)
        frf = resp.get((name, k))
        if frf is None:
            raise FBSError(f"a band for {name}, harmonic {k}, which has no response")
        if edge.freq.shape != frf.freq.shape or not np.allclose(
            edge.freq, frf.freq, rtol=1e-12, atol=0.0
        ):
            raise FrequencyGridError(
                f"the band of {name}, harmonic {k} is on {edge.freq.size} lines "
                f"{edge.freq[0]:g}-{edge.freq[-1]:g} Hz, the response on {frf.freq.size} lines "
                f"{frf.freq[0]:g}-{frf.freq[-1]:g} Hz; compute both on one grid"
            )
        if edge.quantity != frf.quantity:
            raise QuantityError(
                f"the band of {name}, harmonic {k} is a {edge.quantity}, the response a "
                f"{frf.quantity}"
            )
        out[(name, k)] = edge
    return out


def _judge(
    name: str,
    digest: str,
    k: int,
    frf: FRF,
    explicit: Mapping[tuple[str, int | None], Target],
    inc_targets: Mapping[str, Target],
    edge: NoiseEdge | None,
) -> list[VerdictRow]:
    h = _harmonic(k)
    speed = np.atleast_1d(np.asarray(h.speed_at(frf.freq), float))
    level = magnitude_db(response_level(frf))  # (n_f, n_out) dB re 1 SI
    in_kinds = set(frf.input_kinds)
    rows = []
    for o, dof in enumerate(frf.outputs):
        t = explicit.get((dof, k)) or explicit.get((dof, None)) or inc_targets.get(dof)
        if t is None:
            continue
        if {t.input_kind} != in_kinds:
            raise QuantityError(
                f"the target of {dof} is per {t.input_kind} ({t.unit}); the response of "
                f"{name} is per {', '.join(sorted(in_kinds))} ({frf.unit(dof, frf.inputs[0])})"
            )
        tdb = t.level_db_at(frf.freq, frf.quantity, ref=1.0)
        judged = np.isfinite(tdb)
        nan = math.nan
        bw, bf, bs, bq = nan, nan, nan, nan
        if not judged.any():
            rows.append(
                VerdictRow(
                    name,
                    digest,
                    k,
                    parse_label(dof)[0],
                    dof,
                    NOT_JUDGED,
                    nan,
                    nan,
                    nan,
                    nan,
                    bw,
                    bf,
                    bs,
                    bq,
                    0,
                    t.source or t.describe(),
                )  # fmt: skip
            )
            continue
        d = np.where(judged, level[:, o] - tdb, -np.inf)
        i = int(np.argmax(d))
        worst = float(d[i])
        if edge is not None:
            if dof not in edge.dofs:
                raise DOFError(
                    f"the band of {name}, harmonic {k} has no {dof!r}; its DOFs: "
                    f"{', '.join(edge.dofs)}"
                )
            bd = np.where(judged, magnitude_db(edge.upper[:, edge.dofs.index(dof)]) - tdb, -np.inf)
            j = int(np.argmax(bd))
            bw, bf, bs, bq = float(bd[j]), float(frf.freq[j]), float(speed[j]), edge.q
        if worst > 0:
            status = FAIL
        elif edge is not None and bw > 0:
            status = NOISE_FAIL
        else:
            status = PASS
        rows.append(
            VerdictRow(
                name,
                digest,
                k,
                parse_label(dof)[0],
                dof,
                status,
                worst,
                float(frf.freq[i]),
                float(speed[i]),
                -worst if worst <= 0 else nan,
                bw,
                bf,
                bs,
                bq,
                int(judged.sum()),
                t.source or t.describe(),
            )
        )
    return rows


def _ranking(
    rows: list[VerdictRow], order: list[str], candidates: CandidateSet | None
) -> tuple[Standing, ...]:
    entries = []
    for pos, name in enumerate(order):
        mine = [r for r in rows if r.candidate == name]
        judged = [r for r in mine if r.status != NOT_JUDGED]
        counts = {s: sum(r.status == s for r in judged) for s in (PASS, NOISE_FAIL, FAIL)}
        if counts[FAIL]:
            status = FAIL
        elif counts[NOISE_FAIL]:
            status = NOISE_FAIL
        elif counts[PASS]:
            status = PASS
        else:
            status = NOT_JUDGED
        worst = max(judged, key=lambda r: r.worst_db) if judged else None
        digest = candidates.get(name).digest if candidates is not None else ""
        entries.append(
            (
                (STATUSES.index(status), worst.worst_db if worst else math.inf, pos),
                name,
                digest,
                status,
                worst,
                counts,
            )
        )
    entries.sort(key=lambda e: e[0])
    return tuple(
        Standing(
            rank,
            name,
            digest,
            status,
            w.worst_db if w else math.nan,
            w.harmonic if w else 0,
            w.dof if w else "",
            w.freq if w else math.nan,
            w.speed if w else math.nan,
            counts[FAIL],
            counts[NOISE_FAIL],
            counts[PASS],
        )
        for rank, (_, name, digest, status, w, counts) in enumerate(entries, start=1)
    )
