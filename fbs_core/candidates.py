"""Tire candidates of a supplier review: several modal tire models side by side.

A design review asks whether a supplier's tire meets the bushing targets and how it
compares with the incumbent tire and with other suppliers' (docs/verdict.md). Each tire
model is a :class:`Candidate`: its name, supplier, tire size or description, version,
the digest of its file and the :class:`~fbs_core.tire.TireModel` itself (the modal model
of thesis section 4.1.2, used as the subsystem A of eq. 4.1). A :class:`CandidateSet`
holds at most :data:`MAX_CANDIDATES` of them, one marked current, and gives each a
colour slot that it keeps while it is in the set.

Candidates are identified by the digest of their file (:func:`file_digest`, the digest
the dashboard keys its uploads by); the shipped reference tire has the digest
:data:`REFERENCE_DIGEST`.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, cast

from .errors import FBSError

if TYPE_CHECKING:
    from .tire.model import TireModel

__all__ = [
    "MAX_CANDIDATES",
    "REFERENCE_DIGEST",
    "Candidate",
    "CandidateSet",
    "file_digest",
]

#: Most candidates one set holds: a review compares a handful of tires (the incumbent and
#: a few suppliers' deliveries); each candidate keeps a modal model of a few MB in memory
#: and adds its responses to every overlay, so the set is bounded. Eight distinct colours
#: remain readable on one plot (docs/verdict.md).
MAX_CANDIDATES = 8

#: The digest that names the shipped reference tire (it has no uploaded file).
REFERENCE_DIGEST = "reference"

#: Characters of the hexadecimal SHA-256 digest kept (96 bits: no collision in practice).
DIGEST_CHARS = 24


def file_digest(data: bytes, **settings: object) -> str:
    """The digest that identifies an uploaded file and its import settings.

    SHA-256 of the bytes, then of the sorted settings' ``repr``, cut to
    :data:`DIGEST_CHARS` hexadecimal characters: the same digest the dashboard keys its
    uploads by, so that a candidate is found again from a link.

    Parameters
    ----------
    data : bytes
        The file's content.
    **settings
        Import settings that change what the file means (none for a tire model).

    Examples
    --------
    >>> file_digest(b"abc")
    '01281324cb2794786a55c9f5'
    """
    h = hashlib.sha256(bytes(data))
    h.update(repr(sorted(settings.items())).encode())
    return h.hexdigest()[:DIGEST_CHARS]


def _text(value: object, what: str, required: bool = False) -> str:
    if not isinstance(value, str):
        raise FBSError(f"the candidate's {what} must be text, got {type(value).__name__}")
    s = " ".join(value.split())
    if required and not s:
        raise FBSError(f"the candidate's {what} must not be empty")
    if len(s) > 120:
        raise FBSError(f"the candidate's {what} is {len(s)} characters long; at most 120")
    return s


@dataclass(frozen=True)
class Candidate:
    """One tire model of a review.

    Parameters
    ----------
    name : str
        Short unique name in the review (table rows, legends), e.g. ``"Supplier X v2"``.
    digest : str
        Identity of the model's file (:func:`file_digest`; :data:`REFERENCE_DIGEST` for
        the shipped tire).
    model : TireModel
        The modal tire model (thesis section 4.1.2).
    supplier, size, version : str
        Who delivered it, the tire size or a description (``"205/55 R16"``), the
        delivery's version.
    notes : tuple of str
        Quality warnings of the import (:func:`fbs_core.io.checks.check_tire`).

    Raises
    ------
    FBSError
        For an empty name or digest, or text fields that are not text.
    """

    name: str
    digest: str
    model: TireModel = field(repr=False, compare=False)
    supplier: str = ""
    size: str = ""
    version: str = ""
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", _text(self.name, "name", required=True))
        object.__setattr__(self, "digest", _text(self.digest, "digest", required=True))
        for what in ("supplier", "size", "version"):
            object.__setattr__(self, what, _text(getattr(self, what), what))
        object.__setattr__(self, "notes", tuple(str(n) for n in self.notes))
        if not hasattr(self.model, "n_modes") or not hasattr(self.model, "speeds"):
            raise FBSError(
                f"candidate {self.name!r}: the model must be a modal tire model "
                f"(fbs_core.tire.TireModel), got {type(self.model).__name__}"
            )

    @property
    def is_reference(self) -> bool:
        """True for the shipped reference tire."""
        return self.digest == REFERENCE_DIGEST

    @classmethod
    def reference(cls, name: str = "reference", **fields: Any) -> Candidate:
        """The shipped reference tire (:func:`fbs_core.reference_tire`) as a candidate."""
        from .tire import reference_tire

        fields.setdefault("supplier", "tire-fbs")
        fields.setdefault("size", "reference rolling tire (docs/tire-model.md)")
        return cls(name, REFERENCE_DIGEST, reference_tire(), **fields)

    @classmethod
    def from_file(
        cls,
        data: bytes,
        filename: str,
        name: str | None = None,
        **fields: Any,
    ) -> Candidate:
        """A candidate from the bytes of a tire model file (an upload).

        The file is read by :func:`fbs_core.io.import_tire_model` (parsed in the sandbox
        process) and checked by :func:`fbs_core.io.checks.check_tire`, whose notes become
        the candidate's ``notes``; a model unfit for the studies is refused as an upload
        is.

        Parameters
        ----------
        data : bytes
            The file's content.
        filename : str
            Its name (the ending selects the format; the default candidate name).
        name : str, optional
            The candidate's name (default the file name).
        **fields
            ``supplier``, ``size``, ``version``.

        Raises
        ------
        FBSError
            From the import or the checks, naming the file.
        """
        from .io import import_tire_model
        from .io.checks import check_tire

        try:
            res = import_tire_model(bytes(data), filename=filename)
            notes = check_tire(res.model)
        except FBSError as e:
            raise type(e)(f"{filename}: {e}") from None
        model = cast("TireModel", res.model)
        return cls(
            filename if name is None else name,
            file_digest(bytes(data)),
            model,
            notes=tuple(notes),
            **fields,
        )


@dataclass(frozen=True)
class CandidateSet:
    """An immutable set of at most :data:`MAX_CANDIDATES` candidates, one of them current.

    Every method returns a new set; a refused change raises and leaves the set as it was.
    Each candidate has a colour slot ``0 .. MAX_CANDIDATES - 1`` (:meth:`slot`): the
    lowest slot free when it was added, kept while it stays, so that a candidate's colour
    does not change when another is added or removed. The dashboard and the report map
    slots to their palette.

    Parameters
    ----------
    candidates : iterable of Candidate
        In order of addition; names and digests unique.
    current : str, optional
        Digest of the current candidate (default the first).
    slots : tuple of int, optional
        Colour slots in the order of ``candidates`` (default 0, 1, 2, ...).

    Raises
    ------
    FBSError
        For more than :data:`MAX_CANDIDATES` candidates, a repeated name or digest, an
        unknown current digest or bad slots.

    Examples
    --------
    >>> s = CandidateSet([Candidate.reference()])           # doctest: +SKIP
    >>> s.current.name                                      # doctest: +SKIP
    'reference'
    """

    candidates: tuple[Candidate, ...] = ()
    current_digest: str | None = None
    slots: tuple[int, ...] | None = None

    def __init__(
        self,
        candidates: Iterable[Candidate] = (),
        current: str | None = None,
        slots: Iterable[int] | None = None,
    ) -> None:
        cs = tuple(candidates)
        for c in cs:
            if not isinstance(c, Candidate):
                raise FBSError(f"a candidate set holds Candidate objects, got {type(c).__name__}")
        if len(cs) > MAX_CANDIDATES:
            raise FBSError(
                f"{len(cs)} candidates: a review holds at most {MAX_CANDIDATES}; remove one "
                "before adding another"
            )
        for what in ("name", "digest"):
            seen: dict[str, str] = {}
            for c in cs:
                key = getattr(c, what)
                if key in seen:
                    raise FBSError(
                        f"two candidates with the {what} {key!r} ({seen[key]!r} and "
                        f"{c.name!r}); each candidate needs its own"
                    )
                seen[key] = c.name
        sl = tuple(range(len(cs))) if slots is None else tuple(int(s) for s in slots)
        if (
            len(sl) != len(cs)
            or len(set(sl)) != len(sl)
            or any(not 0 <= s < MAX_CANDIDATES for s in sl)
        ):
            raise FBSError(
                f"colour slots {list(sl)} must be {len(cs)} distinct values in "
                f"0..{MAX_CANDIDATES - 1}"
            )
        if current is None:
            current = cs[0].digest if cs else None
        elif current not in {c.digest for c in cs}:
            raise FBSError(
                f"no candidate with the digest {current!r} to make current; candidates: "
                f"{', '.join(f'{c.name} ({c.digest})' for c in cs) or 'none'}"
            )
        object.__setattr__(self, "candidates", cs)
        object.__setattr__(self, "current_digest", current)
        object.__setattr__(self, "slots", sl)

    # -- reading -------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.candidates)

    def __iter__(self) -> Iterator[Candidate]:
        return iter(self.candidates)

    def __contains__(self, key: object) -> bool:
        return any(key in (c.digest, c.name) for c in self.candidates)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.candidates)

    @property
    def digests(self) -> tuple[str, ...]:
        return tuple(c.digest for c in self.candidates)

    @property
    def current(self) -> Candidate | None:
        """The candidate of the detail views (None for an empty set)."""
        return None if self.current_digest is None else self.get(self.current_digest)

    def get(self, key: str) -> Candidate:
        """The candidate with this digest or name.

        Raises
        ------
        FBSError
            Naming the candidates there are.
        """
        for c in self.candidates:
            if key in (c.digest, c.name):
                return c
        raise FBSError(
            f"unknown candidate {key!r}; candidates: "
            f"{', '.join(f'{c.name} ({c.digest})' for c in self.candidates) or 'none'}"
        )

    def slot(self, key: str) -> int:
        """The colour slot of a candidate (by digest or name), stable while it stays."""
        c = self.get(key)
        assert self.slots is not None  # set in __init__
        return self.slots[self.candidates.index(c)]

    # -- changing (new sets) -------------------------------------------------------------
    def add(self, candidate: Candidate, current: bool = False) -> CandidateSet:
        """A set with ``candidate`` added (the lowest free colour slot), made current if
        ``current``.

        Raises
        ------
        FBSError
            When the set is full (naming the limit) or the name or digest is taken.
        """
        if len(self.candidates) >= MAX_CANDIDATES:
            raise FBSError(
                f"cannot add {candidate.name!r}: the review already holds {MAX_CANDIDATES} "
                f"candidates ({', '.join(self.names)}), the most it holds; remove one first"
            )
        assert self.slots is not None
        free = min(set(range(MAX_CANDIDATES)) - set(self.slots))
        return CandidateSet(
            (*self.candidates, candidate),
            candidate.digest if current else self.current_digest,
            (*self.slots, free),
        )

    def remove(self, key: str) -> CandidateSet:
        """A set without the candidate of this digest or name (the others keep their
        slots; the first remaining becomes current if the removed one was)."""
        c = self.get(key)
        assert self.slots is not None
        keep = [(x, s) for x, s in zip(self.candidates, self.slots, strict=True) if x is not c]
        cur = None if self.current_digest == c.digest else self.current_digest
        return CandidateSet([x for x, _ in keep], cur, [s for _, s in keep])

    def with_current(self, key: str) -> CandidateSet:
        """The same set with another current candidate (by digest or name)."""
        return CandidateSet(self.candidates, self.get(key).digest, self.slots)

    def renamed(self, key: str, **fields: Any) -> CandidateSet:
        """The same set with one candidate's ``name``, ``supplier``, ``size`` or
        ``version`` changed."""
        bad = set(fields) - {"name", "supplier", "size", "version"}
        if bad:
            raise FBSError(
                f"cannot change {', '.join(sorted(bad))}; allowed: name, supplier, size, version"
            )
        c = self.get(key)
        new = replace(c, **fields)
        return CandidateSet(
            [new if x is c else x for x in self.candidates], self.current_digest, self.slots
        )
