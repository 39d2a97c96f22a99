"""One step from what a file holds to an FRF: labels, units and quantity.

Every FRF reader (:mod:`.uff`, :mod:`.matlab`, :mod:`.csv`, :mod:`.hdf5`) parses its own
layout into a frequency vector in Hz, a data block ``(n_freq, n_out, n_in)`` as the file
gives it, the DOF labels and what the file says about units and quantity. Then
:func:`assemble` makes the FRF the same way for all of them:

1. **labels**: :func:`dof_labels` normalises the labels of a file (``"hub:-Z"`` is
   ``"hub:z"`` with sign -1, :func:`~.checks.normalize_label`) and applies the user's node
   map (:func:`~.checks.rename_node`); an entry given for the opposite direction changes
   sign, and the import notes say how many did;
2. **units**: one label for the whole file (MATLAB, HDF5, the CSV unit line) or one per
   entry (UFF records, CSV column units), read by :func:`fbs_core.units.parse_units`;
   labels that are not understood are noted, labels of different quantities refused;
3. **quantity**: decided from the file's declaration, its units and the caller's
   ``quantity=`` (:func:`~.units.reconcile_quantity`: any two that disagree, or none that
   says it, raise :class:`~fbs_core.errors.QuantityError`);
4. **SI**: every entry converted by what it is (translation or rotation per force, moment
   or road input, :meth:`fbs_core.units.Units.factor`); the notes say from what.

Nothing is converted or renamed without a note, and a file that contradicts itself is
refused (thesis table 2.1 for the quantities).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import QuantityError
from ..frf import FRF
from ..units import Units, kinds_of, parse_units
from .checks import normalize_label, rename_node
from .units import parse_kinds, reconcile_quantity, units_note

__all__ = ["FileUnits", "assemble", "dof_labels", "metadata_from_json"]

#: An output/input pair of labels.
Pair = tuple[str, str]


def dof_labels(
    texts: Iterable[str], what: str, nodes: Mapping[Any, Any] | None = None
) -> tuple[tuple[str, ...], np.ndarray]:
    """The DOF labels of a file as ``"node:dir"``, with the node map applied, and their signs.

    Parameters
    ----------
    texts : iterable of str
        Labels as written (any case, ``tx``/``ty``/``tz``, a leading ``+`` or ``-`` on the
        direction).
    what : str
        ``"output"`` or ``"input"`` (for messages).
    nodes : mapping, optional
        Node map, e.g. ``{1: "spindle", "101": "bushing"}``.

    Returns
    -------
    labels : tuple of str
    signs : ndarray, shape (n,)
        -1.0 where the label names the opposite direction (``"hub:-z"``), else 1.0.

    Raises
    ------
    DOFError
        For unknown directions and malformed node names.

    Examples
    --------
    >>> dof_labels(["1:-Z", "1:tx"], "output", {1: "spindle"})
    (('spindle:z', 'spindle:x'), array([-1.,  1.]))
    """
    labels: list[str] = []
    signs: list[float] = []
    for text in texts:
        label, sign = normalize_label(text, what)
        labels.append(rename_node(label, nodes))
        signs.append(float(sign))
    return tuple(labels), np.array(signs, dtype=float)


@dataclass(frozen=True)
class FileUnits:
    """What a file says about the units of its entries.

    Attributes
    ----------
    labels : str, mapping of (output, input) to str, or None
        One label for every entry (MATLAB, HDF5, the CSV unit line), or one per entry
        (UFF records, CSV column units; an entry missing or ``""`` has none). None: the
        file gives no units.
    fallback : Units, mapping of (output, input) to Units, or None
        The units of entries that ``labels`` leaves unsaid (no label, or one not
        understood): the unit system of a UFF dataset 164, the column units of a CSV file
        whose unit line is not understood.
    parsed : dict of str to Units or None
        Every distinct label (stripped; ``NONE`` is no label) read by
        :func:`fbs_core.units.parse_units`, in the file's order; None where not understood.

    Raises
    ------
    QuantityError
        From :func:`~fbs_core.units.parse_units` for a label of an inverse FRF (``N/m``).
    """

    labels: str | Mapping[Pair, str] | None = None
    fallback: Units | Mapping[Pair, Units] | None = None
    parsed: dict[str, Units | None] = field(default_factory=dict, init=False, compare=False)

    def __post_init__(self) -> None:
        found = (
            [self.labels] if isinstance(self.labels, str) else list((self.labels or {}).values())
        )
        for label in dict.fromkeys(s.strip() for s in found):
            if label and label.upper() != "NONE":
                self.parsed[label] = parse_units(label)

    def of(self, pair: Pair) -> Units | None:
        """The units of one entry: its label's, else the fallback's."""
        label = self.labels if isinstance(self.labels, str) else (self.labels or {}).get(pair)
        u = self.parsed.get(label.strip()) if label else None
        if u is not None:
            return u
        if isinstance(self.fallback, Mapping):
            return self.fallback.get(pair)
        return self.fallback

    @property
    def converting(self) -> list[Units]:
        """The units, stated or fallback, that are not SI."""
        fb = self.fallback
        more = list(fb.values()) if isinstance(fb, Mapping) else [] if fb is None else [fb]
        return [u for u in (*self.understood, *more) if not u.is_si]

    @property
    def understood(self) -> list[Units]:
        """The labels read, in the order the file gives them."""
        return [u for u in self.parsed.values() if u is not None]

    @property
    def not_understood(self) -> list[str]:
        """The labels not understood, as written."""
        return [label for label, u in self.parsed.items() if u is None]

    def system(self, where: str) -> Units | None:
        """The file's unit system: the first label that says the quantity, else the first
        label read.

        Raises
        ------
        QuantityError
            When the labels are those of different quantities.
        """
        by_q = {u.quantity for u in self.understood if u.quantity}
        if len(by_q) > 1:
            raise QuantityError(
                f"{where} mixes units across its entries: "
                + ", ".join(f"{u.label!r} ({u.quantity})" for u in self.understood)
            )
        return next((u for u in self.understood if u.quantity), next(iter(self.understood), None))

    def unclear(self) -> str | None:
        """The first label that does not say the quantity (quoted when nothing else does)."""
        return next((lab for lab, u in self.parsed.items() if u is None or not u.quantity), None)


def assemble(
    freq: np.ndarray,
    data: np.ndarray,
    outputs: Sequence[str],
    inputs: Sequence[str],
    *,
    where: str,
    quantity: str | None = None,
    declared: str | None = None,
    units: FileUnits | None = None,
    kinds: object = None,
    signs: np.ndarray | None = None,
    notes: Iterable[str] = (),
) -> tuple[FRF, list[str]]:
    """The FRF of a file, in SI, and the import notes: the step every reader ends with.

    Parameters
    ----------
    freq : ndarray, shape (n_freq,)
        Frequencies in Hz.
    data : ndarray, shape (n_freq, n_out, n_in)
        The values as the file gives them (file units, label directions).
    outputs, inputs : sequence of str
        Labels from :func:`dof_labels` (or built as ``"node:dir"`` by the reader).
    where : str
        How messages name the file, e.g. ``"'chassis.mat'"``.
    quantity : str, optional
        The caller's ``quantity=``.
    declared : str, optional
        The quantity the file declares.
    units : FileUnits, optional
        The file's unit labels.
    kinds : str, optional
        Kind overrides as written in the file (``"patch=road"``, :func:`~.units.parse_kinds`).
    signs : ndarray, shape (n_out, n_in), optional
        -1 for the entries given for the opposite direction.
    notes : iterable of str
        The reader's own notes, kept first.

    Returns
    -------
    frf : FRF
        In SI units.
    notes : list of str

    Raises
    ------
    QuantityError
        For a quantity contradicted by the units or by ``quantity``, or said by nothing;
        for labels of different quantities.
    DOFError, FrequencyGridError
        From :class:`~fbs_core.FRF` (repeated labels, invalid grid).
    """
    notes = list(notes)
    units = units or FileUnits()
    if signs is not None and np.any(signs < 0):
        data = data * signs[None]
        n = int(np.count_nonzero(signs < 0))
        notes.append(
            f"{n} of {signs.size} entries are given for the opposite direction (a '-' "
            "direction or a negative direction code): their sign was flipped"
        )
    unread = units.not_understood
    if unread:
        notes.append(f"units {', '.join(map(repr, unread))} not understood; not checked")
    system = units.system(where)
    q = reconcile_quantity(declared, system, quantity, where, units.unclear())
    frf = FRF(freq, data, outputs, inputs, q, parse_kinds(kinds, where))
    notes += units_note(system)
    converted = units.converting
    if converted:
        factors = si_factors_of(frf, units)
        if np.any(factors != 1.0):
            frf = frf.replace(data=frf.data * factors[None])
            names = ", ".join(dict.fromkeys(u.label for u in converted))
            notes.append(f"converted from {names} to SI ({frf.unit()})")
    return frf, notes


def si_factors_of(frf: FRF, units: FileUnits) -> np.ndarray:
    """Factors ``(n_out, n_in)`` that turn each entry of ``frf`` from file units into SI
    (1 where the file gives no units)."""
    ok, ik = kinds_of(frf.outputs, frf.inputs, frf.kinds)
    out = np.ones((len(ok), len(ik)))
    for a, o in enumerate(frf.outputs):
        for b, i in enumerate(frf.inputs):
            u = units.of((o, i))
            if u is not None:
                out[a, b] = u.factor(ok[a], ik[b], frf.quantity)
    return out


def metadata_from_json(text: object) -> dict[str, Any]:
    """Provenance stored as JSON text in a file; other text is kept as ``{"metadata": text}``.

    Examples
    --------
    >>> metadata_from_json('{"supplier": "A"}'), metadata_from_json("free text")
    ({'supplier': 'A'}, {'metadata': 'free text'})
    """
    if not isinstance(text, str) or not text.strip():
        return {}
    try:
        md = json.loads(text)
    except ValueError:
        return {"metadata": text}
    return md if isinstance(md, dict) else {"metadata": md}
