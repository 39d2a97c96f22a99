"""A session's review: its tire candidates, its targets and the incumbent rule, immutable.

A supplier review compares several tire models against the bushing targets
(docs/verdict.md). The session keeps them as one :class:`Review` token in its
:class:`~app.datasource.DataSource` (mirrored to the state's ``case.review`` like the
models): the :class:`~fbs_core.candidates.CandidateSet` (the shipped reference first, each
uploaded tire added to it), the :class:`~fbs_core.targets.Target` curves read from files
or typed as segments, and optionally the :class:`~fbs_core.targets.IncumbentTarget`
("the incumbent + margin dB"). Equal and hashed by :attr:`Review.key`, a digest of all of
it, so the verdict's result is made again only when the review changed.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np

from fbs_core.candidates import REFERENCE_DIGEST, CandidateSet
from fbs_core.errors import FBSError
from fbs_core.targets import IncumbentTarget, Target

__all__ = [
    "EMPTY_REVIEW",
    "LinkReview",
    "Review",
    "read_review_link",
    "review_link",
]


def _digest(candidates: CandidateSet | None, targets, incumbent) -> str:
    h = hashlib.sha256()
    if candidates is not None:
        h.update(repr((candidates.digests, candidates.current_digest, candidates.slots)).encode())
        for c in candidates:
            h.update(repr((c.name, c.supplier, c.size, c.version)).encode())
    for t in targets:
        h.update(repr((t.dof, t.quantity, t.input_kind, t.ref, t.axis, t.harmonic)).encode())
        h.update(np.asarray(t.freq, float).tobytes() + np.asarray(t.level_db, float).tobytes())
    if incumbent is not None:
        h.update(repr((incumbent.candidate, incumbent.margin_db, incumbent.dofs)).encode())
    return h.hexdigest()[:24]


@dataclass(frozen=True, eq=False)
class Review:
    """The candidates, targets and incumbent rule of one session (immutable).

    Attributes
    ----------
    candidates : CandidateSet or None
        None until the first tire upload: the session then has one tire, the reference.
    targets : tuple of Target
        At most one per DOF and harmonic (a later one replaces an earlier one).
    incumbent : IncumbentTarget or None
        "The incumbent candidate + margin dB", for the DOFs without a target of their own.
    key : str
        Digest of all of it (equality and hash).
    """

    candidates: CandidateSet | None = None
    targets: tuple[Target, ...] = ()
    incumbent: IncumbentTarget | None = None
    key: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "key", _digest(self.candidates, self.targets, self.incumbent))

    def __eq__(self, other) -> bool:
        return isinstance(other, Review) and other.key == self.key

    def __hash__(self) -> int:
        return hash(("Review", self.key))

    # -- reading ---------------------------------------------------------------------------
    @property
    def judged(self) -> bool:
        """Whether there is anything to judge against (a target or the incumbent rule)."""
        return bool(self.targets) or self.incumbent is not None

    def names(self) -> tuple[str, ...]:
        """The candidates' names (``("reference",)`` before any upload)."""
        return ("reference",) if self.candidates is None else self.candidates.names

    def with_candidates(self, candidates: CandidateSet) -> Review:
        """The same review with another candidate set; an incumbent no longer in the set
        is dropped."""
        inc = self.incumbent
        if inc is not None and inc.candidate not in candidates:
            inc = None
        return Review(candidates, self.targets, inc)

    def with_targets(self, targets: tuple[Target, ...]) -> Review:
        """The same review with ``targets`` added; each replaces a target of the same DOF
        and harmonic."""
        new = {(t.dof, t.harmonic): t for t in targets}
        keep = tuple(t for t in self.targets if (t.dof, t.harmonic) not in new)
        return Review(self.candidates, keep + tuple(new.values()), self.incumbent)

    def without_targets(self) -> Review:
        return Review(self.candidates, (), self.incumbent)

    def with_incumbent(self, incumbent: IncumbentTarget | None) -> Review:
        """The same review with the incumbent rule set (None: removed).

        Raises
        ------
        FBSError
            For a candidate the review does not hold.
        """
        if incumbent is not None and incumbent.candidate not in self.names():
            raise FBSError(
                f"no candidate {incumbent.candidate!r} to take as the incumbent; candidates: "
                f"{', '.join(self.names())}"
            )
        return Review(self.candidates, self.targets, incumbent)

    def digest_of(self, name: str) -> str:
        """The digest of a candidate by name (the reference's before any upload)."""
        if self.candidates is None:
            if name != "reference":
                raise FBSError(f"unknown candidate {name!r}; candidates: reference")
            return REFERENCE_DIGEST
        return self.candidates.get(name).digest


EMPTY_REVIEW = Review()


# -- the review in the link ---------------------------------------------------------------------
#: Characters of a candidate's digest in the link (as the link's ``data`` key).
LINK_DIGEST = 12
#: Longest review text a link carries; beyond it the targets are left out (and it says so).
LINK_CHARS = 8000
_SEP = "~"


def _num(x: float) -> str:
    """A number as the shortest text that reads back as the same float (exact levels)."""
    return repr(float(x))


@dataclass(frozen=True)
class LinkReview:
    """What a link's ``review`` value asks for: candidate digests (12 characters), the
    current one, the incumbent rule and the targets (exact points)."""

    candidates: tuple[str, ...] = ()
    current: str = ""
    incumbent: tuple[str, float] | None = None
    targets: tuple[Target, ...] = ()
    targets_left_out: bool = False
    #: Every candidate of the link in its order (``candidates``: those still to load).
    order: tuple[str, ...] = ()


def _short(digest: str) -> str:
    return digest if digest == REFERENCE_DIGEST else digest[:LINK_DIGEST]


def review_link(review: Review, pending: LinkReview | None = None) -> str:
    """The review as a link's value: ``c:`` the candidates' digests, ``cur:`` the current
    one, ``inc:`` the incumbent and its margin, ``t:`` each target
    (``dof:harmonic:axis:quantity:f_dB_f_dB...``); ``""`` for the empty review.

    ``pending``: what the link opened with that the session has not loaded yet (candidates
    whose files are not uploaded, an incumbent among them): kept in the link.
    """
    cands = review.candidates
    digests = [] if cands is None else [_short(d) for d in cands.digests]
    current = "" if cands is None else _short(str(cands.current_digest))
    inc = review.incumbent
    incumbent = None
    if inc is not None:
        d = review.digest_of(inc.candidate) if inc.candidate in review.names() else ""
        incumbent = (_short(d), inc.margin_db) if d else None
    if pending is not None:
        digests += [d for d in pending.candidates if d not in digests]
        if incumbent is None and pending.incumbent is not None:
            incumbent = pending.incumbent
        loaded = set() if cands is None else {_short(d) for d in cands.digests}
        if pending.current and pending.current not in loaded:
            current = pending.current  # the link's current candidate, not uploaded yet
    parts = []
    if digests and digests != [REFERENCE_DIGEST]:
        parts.append("c:" + ".".join(digests))
        parts.append("cur:" + current)
    if incumbent is not None:
        parts.append(f"inc:{incumbent[0]}:{_num(incumbent[1])}")
    head = _SEP.join(parts)
    ts = []
    for t in review.targets:
        pts = "_".join(f"{_num(f)}_{_num(L)}" for f, L in zip(t.freq, t.level_db, strict=True))
        k = "*" if t.harmonic is None else str(t.harmonic)
        ts.append(f"t:{t.dof}:{k}:{t.axis}:{t.quantity}:{_num(t.ref)}:{pts}")
    text = _SEP.join([head, *ts]) if head else _SEP.join(ts)
    if len(text) > LINK_CHARS:
        text = _SEP.join([p for p in (head, "t:-") if p])
    return text


def read_review_link(text: str) -> LinkReview:
    """A link's ``review`` value (:func:`review_link`) as what it asks for.

    Raises
    ------
    FBSError
        Naming the part that is malformed (a crafted or cut link).
    """
    cands: tuple[str, ...] = ()
    current, incumbent, targets, left_out = "", None, [], False
    for part in (p for p in str(text or "").split(_SEP) if p):
        kind, _, rest = part.partition(":")
        try:
            if kind == "c":
                cands = tuple(d for d in rest.split(".") if d)
                if any(not (d == REFERENCE_DIGEST or d.isalnum()) for d in cands):
                    raise ValueError("digests are letters and digits")
            elif kind == "cur":
                current = rest
            elif kind == "inc":
                d, _, margin = rest.rpartition(":")
                incumbent = (d, float(margin))
                if not np.isfinite(incumbent[1]):
                    raise ValueError("the margin is not finite")
            elif kind == "t" and rest == "-":
                left_out = True
            elif kind == "t":
                dof_node, dof_dir, k, axis, quantity, ref, pts = rest.split(":", 6)
                nums = [float(x) for x in pts.split("_")]
                if len(nums) % 2:
                    raise ValueError("points come in pairs")
                targets.append(
                    Target(
                        f"{dof_node}:{dof_dir}",
                        np.array(nums[0::2]),
                        np.array(nums[1::2]),
                        quantity,
                        "road",
                        float(ref),
                        axis,
                        None if k == "*" else int(k),
                        "from the link",
                    )
                )
            else:
                raise ValueError(f"unknown part {kind!r}")
        except (ValueError, FBSError) as e:
            shown = part if len(part) <= 60 else part[:60] + "..."
            raise FBSError(f"the link's review part {shown!r} cannot be read: {e}") from None
    return LinkReview(cands, current, incumbent, tuple(targets), left_out, cands)
