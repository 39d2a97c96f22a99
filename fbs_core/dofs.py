"""DOF labels: ``"node:dir"`` strings such as ``"hub:z"`` or ``"bushing:rx"``.

A label names one degree of freedom by the node it sits on and its direction,
one of :data:`DIRECTIONS` (:data:`fbs_core.vocabulary.DIRECTIONS`). A label without
a colon (for example ``"patch"``) names a generalised DOF, such as a distributed load
whose spatial shape is part of the model rather than a single node.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence

from .errors import DOFError
from .vocabulary import DIRECTIONS

__all__ = ["DIRECTIONS", "parse_label", "validate_labels", "index_of", "node_labels"]

_NODE = re.compile(r"^[A-Za-z0-9_.\-/\[\]]+$")


def parse_label(label: str) -> tuple[str, str | None]:
    """Split a DOF label into ``(node, direction)``.

    Parameters
    ----------
    label : str
        ``"node:dir"`` with ``dir`` in :data:`DIRECTIONS`, or a bare name for a
        generalised DOF (direction ``None``).

    Returns
    -------
    tuple of (str, str or None)

    Raises
    ------
    DOFError
        If the label is not a string, is empty, has an unknown direction or
        characters other than letters, digits and ``_ . - / [ ]`` in the node.

    Examples
    --------
    >>> parse_label("hub:rz")
    ('hub', 'rz')
    >>> parse_label("patch")
    ('patch', None)
    """
    if not isinstance(label, str):
        raise DOFError(f"DOF label must be a string like 'hub:z', got {label!r}")
    node, sep, direction = label.partition(":")
    if not _NODE.match(node):
        raise DOFError(
            f"malformed DOF label {label!r}: the node name must be non-empty and use "
            "letters, digits or _ . - / [ ]"
        )
    if not sep:
        return node, None
    if direction not in DIRECTIONS:
        raise DOFError(
            f"unknown direction {direction!r} in DOF label {label!r}; "
            f"allowed: {', '.join(DIRECTIONS)}"
        )
    return node, direction


def validate_labels(labels: Iterable[str], what: str = "DOF") -> tuple[str, ...]:
    """Check a sequence of labels and return it as a tuple.

    Raises
    ------
    DOFError
        On a malformed label or a duplicate.
    """
    if isinstance(labels, str):
        labels = [labels]
    out = tuple(labels)
    for lab in out:
        parse_label(lab)
    seen: set[str] = set()
    dups = []
    for lab in out:
        if lab in seen:
            dups.append(lab)
        seen.add(lab)
    if dups:
        raise DOFError(f"duplicate {what} labels: {', '.join(sorted(set(dups)))}")
    return out


def index_of(labels: Sequence[str], wanted: Iterable[str] | str, what: str = "DOF") -> list[int]:
    """Positions of ``wanted`` labels in ``labels``.

    Raises
    ------
    DOFError
        Naming the unknown label and the available ones.
    """
    if isinstance(wanted, str):
        wanted = [wanted]
    lookup = {lab: i for i, lab in enumerate(labels)}
    idx = []
    for w in wanted:
        if w not in lookup:
            raise DOFError(f"unknown {what} {w!r}; available: {', '.join(labels)}")
        idx.append(lookup[w])
    return idx


def node_labels(node: str, directions: Iterable[str] = DIRECTIONS) -> tuple[str, ...]:
    """All labels of one node, e.g. ``node_labels("hub")`` -> ``("hub:x", ..., "hub:rz")``.

    Parameters
    ----------
    node : str
        Node name.
    directions : iterable of str
        Directions to include; default all six of :data:`DIRECTIONS`.
    """
    return validate_labels(f"{node}:{d}" for d in directions)
