"""Who sees what of a project: the pure access policy (no storage, no I/O).

A project lists the groups that may open it (:class:`~app.projects.records.GroupAccess`); a
user opens it when one of its groups is listed. A group either sees every candidate (its
``suppliers`` is ``None``: the OEM team, who also administer the project) or only the
candidates whose supplier it lists (a supplier's engineers: their own tire and the targets).
A user in several listed groups gets the union. What a user may not see, it gets nothing of:
not the project's name, not a candidate's name or file, not a view that shows such a
candidate, not a note or audit line written for a wider audience.

The service (:mod:`app.projects.service`) sends every read and write through these functions;
``tests/test_projects_access.py`` proves the rules as a table.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from .records import FULL_ONLY, Audience, Candidate, Note, ProjectInfo, User, View

__all__ = [
    "ANOTHER_CANDIDATE",
    "PUBLIC_DIGESTS",
    "audience_of",
    "audience_visible",
    "can_open",
    "candidate_visible",
    "full_access",
    "may_add_candidate",
    "may_administer",
    "may_remove_candidate",
    "note_visible",
    "redact_ranking",
    "supplier_key",
    "supplier_scope",
    "view_visible",
    "visible_candidates",
]

#: What a ranking shows in place of a candidate the user may not see.
ANOTHER_CANDIDATE = "another candidate"

#: Digests of models every user may see by name: the shipped reference tire.
PUBLIC_DIGESTS = frozenset({"reference"})


def supplier_key(name: str) -> str:
    """A supplier's name as compared by the rules: words joined by one space, no case."""
    return " ".join(name.split()).casefold()


def supplier_scope(user: User, project: ProjectInfo) -> tuple[bool, frozenset[str] | None]:
    """``(may_open, suppliers)`` of ``user`` in ``project``.

    ``suppliers`` is ``None`` when one of the user's groups sees every candidate, else the
    union of the supplier names (:func:`supplier_key`) its listed groups see.
    """
    entries = [a for a in project.access if a.group in user.groups]
    if not entries:
        return False, frozenset()
    if any(a.suppliers is None for a in entries):
        return True, None
    out: set[str] = set()
    for a in entries:
        out.update(supplier_key(s) for s in a.suppliers or ())
    return True, frozenset(out)


def can_open(user: User, project: ProjectInfo) -> bool:
    """Whether ``user`` may open ``project`` at all (know its name, see anything of it)."""
    return supplier_scope(user, project)[0]


def full_access(user: User, project: ProjectInfo) -> bool:
    """Whether ``user`` sees every candidate and administers ``project``."""
    ok, suppliers = supplier_scope(user, project)
    return ok and suppliers is None


def candidate_visible(user: User, project: ProjectInfo, candidate: Candidate) -> bool:
    """Whether ``user`` may see ``candidate`` (its name, metadata, file)."""
    ok, suppliers = supplier_scope(user, project)
    if not ok:
        return False
    return suppliers is None or supplier_key(candidate.supplier) in suppliers


def visible_candidates(
    user: User, project: ProjectInfo, candidates: Iterable[Candidate]
) -> tuple[Candidate, ...]:
    """The candidates of ``candidates`` that ``user`` may see, in their order."""
    return tuple(c for c in candidates if candidate_visible(user, project, c))


def view_visible(
    user: User, project: ProjectInfo, view: View, candidates: Mapping[int, Candidate]
) -> bool:
    """Whether ``user`` may see ``view``: it opens the project and sees all the view's
    candidates (removed ones included; an id without a record counts as hidden)."""
    if not can_open(user, project):
        return False
    for cid in view.candidates:
        c = candidates.get(cid)
        if c is None or not candidate_visible(user, project, c):
            return False
    return True


def audience_of(user: User, project: ProjectInfo) -> Audience:
    """The audience of what ``user`` writes in ``project`` (a note, an audit line): the
    full-access groups and the groups that see at least what the writer sees."""
    ok, suppliers = supplier_scope(user, project)
    if not ok:
        raise ValueError(f"user {user.name!r} may not open this project")
    return FULL_ONLY if suppliers is None else suppliers


def audience_visible(user: User, project: ProjectInfo, audience: Audience) -> bool:
    """Whether ``user`` may read a text written for ``audience``."""
    ok, suppliers = supplier_scope(user, project)
    if not ok:
        return False
    if audience is None or suppliers is None:
        return True
    return audience <= suppliers


def note_visible(user: User, project: ProjectInfo, note: Note) -> bool:
    """Whether ``user`` may read ``note``."""
    return audience_visible(user, project, note.audience)


def may_administer(user: User, project: ProjectInfo) -> bool:
    """Change the access list, add or remove targets, remove any candidate."""
    return full_access(user, project)


def may_add_candidate(user: User, project: ProjectInfo, supplier: str) -> bool:
    """Add a candidate of ``supplier``: full access, or a group that sees that supplier."""
    ok, suppliers = supplier_scope(user, project)
    return ok and (suppliers is None or supplier_key(supplier) in suppliers)


def may_remove_candidate(user: User, project: ProjectInfo, candidate: Candidate) -> bool:
    """Remove ``candidate``: full access, or a group that sees its supplier."""
    return may_add_candidate(user, project, candidate.supplier)


def _blank(value: Any) -> Any:
    if isinstance(value, bool):
        return False
    if isinstance(value, int):
        return 0
    if isinstance(value, float):
        return math.nan
    if isinstance(value, str):
        return ""
    return None


def redact_ranking[T](
    user: User,
    project: ProjectInfo,
    candidates: Iterable[Candidate],
    ranking: Sequence[T],
) -> tuple[T, ...]:
    """The verdict's ranking as ``user`` may see it.

    A standing (a dataclass such as ``fbs_core.verdict.Standing``, or a mapping) of a
    candidate the user may see is kept as it is. Any other keeps only its ``rank``: its
    ``candidate`` reads :data:`ANOTHER_CANDIDATE` and every other field is blanked (text
    empty, numbers NaN or 0), so neither its name, digest, status nor levels are shown.
    A standing is matched to the project's candidates by its ``digest``; a digest the project
    does not hold is hidden from all but the full-access groups, except the shipped reference
    tire's (:data:`PUBLIC_DIGESTS`).

    Parameters
    ----------
    user, project
        Who looks at which project.
    candidates : iterable of Candidate
        The project's candidates (removed ones included).
    ranking : sequence of standings
        Each with ``rank``, ``candidate`` and ``digest``.
    """
    ok, suppliers = supplier_scope(user, project)
    if not ok:
        return ()
    if suppliers is None:
        return tuple(ranking)
    shown = {c.digest for c in candidates if candidate_visible(user, project, c)}
    shown |= PUBLIC_DIGESTS
    out: list[T] = []
    for s in ranking:
        if isinstance(s, Mapping):
            digest, fields = s.get("digest"), dict(s)
        elif dataclasses.is_dataclass(s) and not isinstance(s, type):
            digest = getattr(s, "digest", None)
            fields = {f.name: getattr(s, f.name) for f in dataclasses.fields(s)}
        else:
            raise TypeError(f"a standing must be a dataclass or a mapping, got {type(s)}")
        if digest in shown:
            out.append(s)
            continue
        hidden = {k: (v if k == "rank" else _blank(v)) for k, v in fields.items()}
        hidden["candidate"] = ANOTHER_CANDIDATE
        if isinstance(s, Mapping):
            out.append(hidden)  # type: ignore[arg-type]
        else:
            out.append(dataclasses.replace(s, **hidden))  # type: ignore[type-var]
    return tuple(out)
