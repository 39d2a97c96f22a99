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

__all__ = ["EMPTY_REVIEW", "Review", "target_label"]


def target_label(t: Target) -> str:
    """A target in one line: DOF, harmonic, range and source."""
    k = "every harmonic" if t.harmonic is None else f"harmonic {t.harmonic}"
    return (
        f"{t.dof} ({k}, {t.quantity}, {float(t.freq[0]):g}-{float(t.freq[-1]):g} Hz, "
        f"{t.level_db.min():.1f} to {t.level_db.max():.1f} dB): {t.source or 'typed'}"
    )


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
