"""Universal File Format dataset 58 ("function at nodal DOF"): FRFs in and out.

Reading goes through the sandbox's own parser (:func:`._textparse.parse_uff`, in the
parser process), writing through pyuff; this module checks the records and makes the
FRF of them (:func:`.assembly.assemble`). One dataset 58 record holds one function
between a response DOF and a reference DOF (record 6: node numbers and direction codes
1..3 = +X..+Z translation, 4..6 = +X..+Z rotation, negative = opposite sign, 0 =
scalar). Records 9 and 10 say what the ordinate is (specific data type 8 displacement,
11 velocity, 12 acceleration over 13 excitation force), which decides receptance,
mobility or accelerance (thesis table 2.1). Dataset 164, when present, gives the unit
system. Abscissa values are single precision in the format (E13.5).
"""

from __future__ import annotations

import functools
import math
import tempfile
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..dofs import parse_label
from ..errors import DataFormatError, DOFError, FBSError, FrequencyGridError, QuantityError
from ..frf import FRF
from ..units import response_unit
from ..vocabulary import DIRECTIONS
from ._sandbox import DEFAULT_TIMEOUT, parse_isolated
from .assembly import FileUnits, assemble
from .checks import Source, Units, check_finite, frequency_from_units, missing_pairs, parse_units

__all__ = ["read_uff", "write_uff", "write_uff_records", "DIR_CODES"]

#: UFF direction codes of the labelled directions (record 6 fields 7 and 10).
DIR_CODES: dict[str, int] = {d: k + 1 for k, d in enumerate(DIRECTIONS)}
_CODE_DIRS = {v: k for k, v in DIR_CODES.items()}

#: Ordinate specific data types (record 9 field 1) of the three FRF quantities.
SPEC_TYPES: dict[str, int] = {"receptance": 8, "mobility": 11, "accelerance": 12}
_SPEC_QUANTITY = {v: k for k, v in SPEC_TYPES.items()}
_FORCE_TYPES = (9, 13)
#: Record 10 (ordinate denominator) of each input kind: specific data type, name, unit.
_DEN_SPEC = {"force": 13, "moment": 13, "road": 8, "generalised": 0}
_DEN_UNITS = {"force": "N", "moment": "N m", "road": "m", "generalised": "NONE"}
_FUNC_NAMES = {
    0: "general",
    1: "time response",
    2: "auto spectrum",
    3: "cross spectrum",
    4: "FRF",
    5: "transmissibility",
    6: "coherence",
    9: "PSD",
    12: "spectrum",
}

_REQUIRED = (
    "func_type",
    "rsp_node",
    "rsp_dir",
    "ref_node",
    "ref_dir",
    "ord_data_type",
    "num_pts",
    "abscissa_spacing",
    "x",
    "data",
)


def _read_sets(src: Source, timeout: float) -> tuple[list[dict[str, Any]], dict[str, int]]:
    """All datasets of the file, parsed in the sandbox (:func:`._textparse.parse_uff`):
    dataset 58 as pyuff-style dictionaries with ``x`` and ``data`` arrays."""
    meta, arrays = parse_isolated("uff", src.raw, f"Universal File {src.name!r}", timeout=timeout)
    sets: list[dict[str, Any]] = []
    for s in meta["sets"]:
        if s.get("type") == 58:
            y = arrays[s["data"]]
            if "x" in s:
                x = arrays[s["x"]]
            else:
                x = s["abscissa_min"] + np.arange(y.size) * s["abscissa_inc"]
            s = dict(s, x=x, data=y)
        sets.append(s)
    if not sets:
        extra = f" ({meta['empty']} empty ones)" if meta.get("empty") else ""
        raise DataFormatError(
            f"{src.name!r} contains no UFF datasets{extra} (blocks between '    -1' lines)"
        )
    return sets, meta.get("contents", {})


def _dof(
    node: Any,
    code: Any,
    ent: Any,
    what: str,
    nodes: Mapping[Any, Any] | None,
    ent_names: dict[int, str],
) -> tuple[str, int]:
    try:
        node, code = int(node), int(code)
    except (TypeError, ValueError):
        raise DataFormatError(
            f"{what}: node {node!r} / direction {code!r} are not integers"
        ) from None
    if abs(code) > 6:
        raise DOFError(
            f"{what}: unknown direction code {code}; allowed: 0 (scalar), 1..3 (+X..+Z "
            "translation), 4..6 (+X..+Z rotation), negative for the opposite sign"
        )
    name = ent_names.get(node, str(node))
    if nodes and (node in nodes or str(node) in nodes):
        name = str(nodes.get(node, nodes.get(str(node))))
    label = name if code == 0 else f"{name}:{_CODE_DIRS[abs(code)]}"
    try:
        parse_label(label)
    except DOFError as e:
        raise DOFError(f"{what}: {e}") from None
    return label, (-1 if code < 0 else 1)


def _entity_names(frf_sets: list[dict[str, Any]]) -> dict[int, str]:
    """Node number -> entity name, used only when the names map one-to-one to nodes."""
    by_node: dict[int, set[str]] = {}
    for s in frf_sets:
        for nk, ek in (("rsp_node", "rsp_ent_name"), ("ref_node", "ref_ent_name")):
            ent = str(s.get(ek, "") or "").strip()
            try:
                by_node.setdefault(int(s[nk]), set()).add(ent)
            except (TypeError, ValueError):
                return {}
    names: dict[int, str] = {}
    for node, ents in by_node.items():
        if len(ents) != 1:
            return {}
        ent = next(iter(ents))
        if not ent or ent.upper() == "NONE":
            return {}
        try:
            parse_label(ent)
        except DOFError:
            return {}
        names[node] = ent
    if len(set(names.values())) != len(names):
        return {}
    return names


def _quantity_of(s: dict[str, Any], what: str) -> str | None:
    num = int(s.get("ordinate_spec_data_type", 0) or 0)
    den = int(s.get("orddenom_spec_data_type", 0) or 0)
    if num in _FORCE_TYPES and den in _SPEC_QUANTITY:
        raise QuantityError(
            f"{what} is force per {_SPEC_QUANTITY[den]} motion (an inverse FRF: dynamic "
            "stiffness, impedance or apparent mass); invert it to an FRF first"
        )
    if den not in (0, 1, 8) + _FORCE_TYPES:
        raise QuantityError(
            f"{what}: ordinate denominator specific data type {den} is not a force "
            "(allowed: 9 reaction force, 13 excitation force (or moment), 8 displacement "
            "of a road input, 0 unknown)"
        )
    if num in _SPEC_QUANTITY:
        return _SPEC_QUANTITY[num]
    if num in (0, 1):
        return None
    raise QuantityError(
        f"{what}: ordinate specific data type {num} is not a motion; allowed: "
        "8 displacement (receptance), 11 velocity (mobility), 12 acceleration (accelerance)"
    )


@functools.lru_cache(maxsize=256)
def _parse_units_cached(label: str) -> Units | None:
    return parse_units(label)


def _units_label(s: dict[str, Any]) -> str:
    """The FRF units of a record: record 9's label, over record 10's (the excitation)
    unless record 9 already is a whole FRF unit such as ``m/s/N``."""
    num = str(s.get("ordinate_axis_units_lab", "") or "").strip()
    den = str(s.get("orddenom_axis_units_lab", "") or "").strip()
    if not num or num.upper() == "NONE":
        return ""
    if not den or den.upper() == "NONE":
        return num
    try:
        u = _parse_units_cached(num)
    except QuantityError:
        return num
    if u is not None and u.kinds is not None and u.kinds[1] != "generalised":
        return num  # the whole FRF unit in record 9 (e.g. "m/(N s)" over "N")
    return f"({num})/({den})"


@dataclass(frozen=True)
class _Record:
    """One FRF record (dataset 58, function type 4) as read, checked on its own."""

    output: str
    input: str
    #: -1 when one of its direction codes is negative (the opposite direction)
    sign: int
    #: frequencies in Hz
    x: np.ndarray
    y: np.ndarray
    #: the quantity records 9 and 10 declare
    quantity: str | None
    #: its units label (:func:`_units_label`), "" for none
    units: str
    #: the ordinate was real (data types 2, 4)
    real: bool
    #: how messages name it
    what: str


def read_uff(
    src: Source,
    *,
    nodes: Mapping[Any, Any] | None = None,
    quantity: str | None = None,
    freq: ArrayLike | None = None,
    timeout: float = DEFAULT_TIMEOUT,
) -> tuple[FRF, list[str], dict[str, Any]]:
    """Read the FRF records (dataset 58, function type 4) of a Universal File.

    The steps: the datasets parsed in the sandbox (:func:`_read_sets`), the FRF records
    among them (:func:`_frf_sets`), each record checked and labelled (:func:`_record`),
    the records on one grid (:func:`_same_grid`) and put in a matrix (:func:`_matrix`),
    the unit system of dataset 164 (:func:`_unit_system`), then the FRF assembled with
    the quantity and units of the records (:func:`.assembly.assemble`).

    Parameters
    ----------
    src : Source
        File content and name.
    nodes : mapping, optional
        Node number -> name, e.g. ``{1: "spindle", 2: "bushing"}``. Without it, nodes
        are named by the record's entity names when those map one-to-one to node
        numbers, else by their numbers (``"1:z"``).
    quantity : str, optional
        Required when the file does not say what the ordinate is; checked otherwise.
    freq : array_like, optional
        Common grid (Hz) onto which records on different grids are interpolated
        explicitly with :meth:`FRF.interpolate`; without it such records raise.

    Returns
    -------
    frf : FRF
        Shape ``(n_freq, n_out, n_in)``, SI units.
    notes : list of str
        What was skipped or converted.
    metadata : dict
        ID lines of the first record.

    Raises
    ------
    DataFormatError, DOFError, FrequencyGridError, QuantityError
    """
    _check_node_map(nodes)
    sets, contents = _read_sets(src, timeout)
    notes: list[str] = []
    frf_sets = _frf_sets(sets, contents, src.name, notes)
    ent_names = {} if nodes else _entity_names(frf_sets)
    frf_sets = _first_function(frf_sets, notes)
    records: dict[tuple[str, str], _Record] = {}
    for k, s in enumerate(frf_sets):
        r = _record(s, f"{src.name!r} FRF record {k + 1}", nodes, ent_names)
        if (r.output, r.input) in records:
            raise DataFormatError(f"{r.what}: a second record for the same output/input pair")
        if records and freq is None:
            _same_grid(r, next(iter(records.values())))
        records[(r.output, r.input)] = r
    if any(r.real for r in records.values()):
        notes.append("real-valued records were read as complex with zero imaginary part")
    if nodes:
        notes += _node_map_note(nodes, frf_sets)
    target, data, signs = _matrix(records, freq, src.name, notes)
    declared = {r.quantity for r in records.values() if r.quantity}
    if len(declared) > 1:
        raise QuantityError(
            f"{src.name!r} mixes quantities across records: {', '.join(sorted(declared))}"
        )
    units = FileUnits({pair: r.units for pair, r in records.items()})
    system = _unit_system([s for s in sets if s.get("type") == 164], src.name)
    if system is not None and not system.is_si:
        # the records' own labels say the units; the unit system serves records without
        if any(not u.is_si for u in units.understood):
            notes.append(f"{system.label} ignored: the records' unit labels are not SI")
        else:
            notes.append(f"{system.label}: {system.summary()} (converted to SI)")
            units = FileUnits(units.labels, system)
    frf, notes = assemble(
        target,
        data,
        list(dict.fromkeys(o for o, _ in records)),
        list(dict.fromkeys(i for _, i in records)),
        where=repr(src.name),
        quantity=quantity,
        declared=next(iter(declared), None),
        units=units,
        signs=signs,
        notes=notes,
    )
    first = frf_sets[0]
    meta = {f"id{k}": str(first.get(f"id{k}", "")).strip() for k in range(1, 6)}
    return frf, notes, meta


def _check_node_map(nodes: Mapping[Any, Any] | None) -> None:
    if nodes:
        bad = [k for k in nodes if not (isinstance(k, int) or str(k).strip().isdigit())]
        if bad:
            raise DataFormatError(
                f"nodes maps UFF node numbers to names, e.g. {{1: 'spindle', 2: 'bushing'}}; "
                f"got keys {', '.join(map(repr, bad[:4]))}"
            )


def _frf_sets(
    sets: list[dict[str, Any]], contents: Mapping[str, int], name: str, notes: list[str]
) -> list[dict[str, Any]]:
    """The FRF records among the datasets; notes what else the file holds.

    Raises
    ------
    DataFormatError
        For a dataset 58 that lacks a field, and a file without FRF records.
    """
    f58 = [s for s in sets if s.get("type") == 58]
    other = sorted({int(s.get("type", -1)) for s in sets} - {58, 164})
    if other:
        notes.append(f"ignored datasets of type {', '.join(map(str, other))}")
    for k, s in enumerate(f58):
        lacks = [key for key in _REQUIRED if key not in s]
        if lacks:
            raise DataFormatError(f"{name!r}: dataset 58 number {k + 1} lacks {', '.join(lacks)}")
    frf_sets = [s for s in f58 if int(s["func_type"]) == 4]
    if len(frf_sets) < len(f58):
        kinds = sorted(
            {
                _FUNC_NAMES.get(int(s["func_type"]), str(s["func_type"]))
                for s in f58
                if int(s["func_type"]) != 4
            }
        )
        notes.append(f"skipped {len(f58) - len(frf_sets)} non-FRF records ({', '.join(kinds)})")
    if not frf_sets:
        held = ", ".join(f"{n} {what}" for what, n in contents.items()) or "nothing"
        raise DataFormatError(
            f"{name!r} holds no FRF records (dataset 58 with function type 4); it holds {held}"
        )
    return frf_sets


def _first_function(frf_sets: list[dict[str, Any]], notes: list[str]) -> list[dict[str, Any]]:
    """Records of an output/input pair that repeats under another function identification
    number (record 6, field 2; e.g. a truncated model's FRF, function id 1, and the
    reference beside it, function id 2): the pair's first record is read, the others are
    skipped with a note. A pair repeated under the same function id is left to the
    reader's error."""

    def pair(s: dict[str, Any]) -> tuple[Any, ...]:
        return tuple(int(s[k]) for k in ("rsp_node", "rsp_dir", "ref_node", "ref_dir"))

    seen: dict[tuple[Any, ...], int] = {}
    kept, skipped = [], []
    for s in frf_sets:
        key, fid = pair(s), int(s.get("func_id", 0) or 0)
        if key in seen and seen[key] != fid:
            skipped.append(s)
            continue
        seen.setdefault(key, fid)
        kept.append(s)
    if skipped:
        ids = sorted({int(s.get("func_id", 0) or 0) for s in skipped})
        names = sorted({str(s.get("id1", "")).split(":")[0] for s in skipped} - {""})
        notes.append(
            f"read the first FRF record of each output/input pair; skipped {len(skipped)} "
            f"FRF records of the same pairs with function ids {', '.join(map(str, ids))}"
            + (f" ({', '.join(names)})" if names else "")
        )
    return kept


def _record(
    s: dict[str, Any],
    what: str,
    nodes: Mapping[Any, Any] | None,
    ent_names: dict[int, str],
) -> _Record:
    """One FRF record: its DOF labels, values, frequencies in Hz, quantity and units.

    Raises
    ------
    DataFormatError, DOFError, FrequencyGridError, QuantityError
        Naming the record and its output/input pair.
    """
    out, so = _dof(s["rsp_node"], s["rsp_dir"], s.get("rsp_ent_name"), what, nodes, ent_names)
    inp, si = _dof(s["ref_node"], s["ref_dir"], s.get("ref_ent_name"), what, nodes, ent_names)
    what = f"{what} ({out} / {inp})"
    x = np.asarray(s["x"])
    y = np.asarray(s["data"])
    n = int(s["num_pts"])
    if x.ndim != 1 or y.ndim != 1 or x.size != y.size or y.size != n or n < 1:
        raise DataFormatError(
            f"{what}: the header announces {n} values but {y.size} ordinates and "
            f"{x.size} abscissae were read (truncated or damaged file?)"
        )
    odt = int(s["ord_data_type"])
    if odt not in (2, 4, 5, 6):
        raise DataFormatError(f"{what}: ordinate data type {odt}; allowed: 2, 4, 5, 6")
    check_finite(x, f"{what} abscissa")
    check_finite(y, f"{what} ordinate")
    ast = int(s.get("abscissa_spec_data_type", 0) or 0)
    if ast not in (0, 1, 18):
        raise DataFormatError(
            f"{what}: the abscissa has specific data type {ast} (17 time, 19 rpm, "
            "20 order); an FRF needs frequency (18)"
        )
    x = frequency_from_units(x, s.get("abscissa_axis_units_lab"), what)
    return _Record(
        out, inp, so * si, x, y, _quantity_of(s, what), _units_label(s), odt in (2, 4), what
    )


def _same_grid(r: _Record, first: _Record) -> None:
    x, grid = r.x, first.x
    if x.shape != grid.shape or not np.allclose(x, grid, rtol=1e-9, atol=0):
        raise FrequencyGridError(
            f"{r.what} is on a different frequency grid ({x.size} lines "
            f"{x[0]:g}-{x[-1]:g} Hz) than record 1 ({grid.size} lines "
            f"{grid[0]:g}-{grid[-1]:g} Hz); pass freq=<common grid> to interpolate "
            "all records onto it explicitly"
        )


def _node_map_note(nodes: Mapping[Any, Any], frf_sets: list[dict[str, Any]]) -> list[str]:
    present = {str(int(s[k])) for s in frf_sets for k in ("rsp_node", "ref_node")}
    unused = [str(k) for k in nodes if str(k) not in present]
    if not unused:
        return []
    return [
        f"node numbers {', '.join(unused)} of the node map are not in the file "
        f"(nodes in the file: {', '.join(sorted(present, key=int))})"
    ]


def _matrix(
    records: Mapping[tuple[str, str], _Record],
    freq: ArrayLike | None,
    name: str,
    notes: list[str],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The grid, the data block ``(n_freq, n_out, n_in)`` of the records (interpolated
    onto ``freq`` when given) and the sign of every entry ``(n_out, n_in)``.

    Raises
    ------
    DataFormatError
        Naming the output/input pairs without a record.
    FrequencyGridError
        For a ``freq`` a record does not cover.
    """
    outputs = {o: k for k, o in enumerate(dict.fromkeys(o for o, _ in records))}
    inputs = {i: k for k, i in enumerate(dict.fromkeys(i for _, i in records))}
    n_missing, missing = missing_pairs(outputs, inputs, records)
    if n_missing:
        shown = ", ".join(f"{o}/{i}" for o, i in missing)
        more = f" and {n_missing - 8} more" if n_missing > 8 else ""
        raise DataFormatError(
            f"{name!r}: {n_missing} of {len(outputs) * len(inputs)} output/input "
            f"pairs have no record: {shown}{more}; a full matrix of outputs x inputs is needed"
        )
    grid = next(iter(records.values())).x
    target = grid if freq is None else np.asarray(freq, dtype=float)
    data = np.empty((len(target), len(outputs), len(inputs)), dtype=complex)
    signs = np.ones((len(outputs), len(inputs)))
    for (o, i), r in records.items():
        y = r.y
        if freq is not None:
            try:
                y = FRF(r.x, y[:, None, None], ["a"], ["b"]).interpolate(target).data[:, 0, 0]
            except FBSError as e:
                raise type(e)(f"{name!r} record {o}/{i}: {e}") from None
        data[:, outputs[o], inputs[i]] = y
        signs[outputs[o], inputs[i]] = r.sign
    if freq is not None:
        notes.append(f"records interpolated onto the requested grid of {len(target)} lines")
    return target, data, signs


def _unit_system(units164: list[dict[str, Any]], name: str) -> Units | None:
    """The unit system of the first dataset 164, as the factors that turn file units into
    SI (dataset 164 gives those that turn SI into file units: 1000 for mm)."""
    if not units164:
        return None
    u164 = units164[0]
    try:
        lf, ff = float(u164["length"]), float(u164["force"])
    except (KeyError, TypeError, ValueError):
        raise DataFormatError(f"{name!r}: damaged units dataset 164") from None
    if not (lf > 0 and ff > 0 and math.isfinite(lf) and math.isfinite(ff)):
        raise DataFormatError(f"{name!r}: dataset 164 has invalid unit factors")
    description = str(u164.get("units_description", "")).strip()
    return Units(f"dataset 164 ({description})", None, 1.0 / lf, 1.0 / ff)


# -- writing ---------------------------------------------------------------------------
def _e13(v: float) -> float:
    return float(f"{v:13.5e}")


def _abscissa(freq: np.ndarray, round_abscissa: bool) -> int:
    """1 for even spacing, 0 for uneven; raise when E13.5 would change the grid."""
    f = np.asarray(freq, dtype=float)
    d = np.diff(f)
    even = f.size > 1 and np.allclose(d, d[0], rtol=1e-9, atol=0)
    if even:
        back = _e13(f[0]) + np.arange(f.size) * _e13(d[0])
    else:
        back = np.array([_e13(v) for v in f])
    err = np.max(np.abs(back - f))
    if err > 1e-9 * max(1.0, np.max(np.abs(f))) and not round_abscissa:
        raise DataFormatError(
            "UFF dataset 58 stores frequencies with 6 significant digits (E13.5); this "
            f"grid would move by up to {err:.3g} Hz. Interpolate onto a representable grid "
            "(FRF.interpolate), export as HDF5 or MATLAB, or pass round_abscissa=True"
        )
    return int(even)


def _node_numbers(labels: Sequence[str], nodes: Mapping[Any, Any] | None) -> dict[str, int]:
    """Node name -> UFF node number, from ``nodes`` (number -> name) or in order."""
    names = list(dict.fromkeys(parse_label(lab)[0] for lab in labels))
    given = {str(v): int(k) for k, v in (nodes or {}).items()}
    numbers = {}
    used = set(given.values())
    nxt = 1
    for n in names:
        if n in given:
            numbers[n] = given[n]
        elif n.isdigit():
            numbers[n] = int(n)
        else:
            while nxt in used:
                nxt += 1
            numbers[n] = nxt
        used.add(numbers[n])
    return numbers


def _ent(name: str) -> str:
    return name if len(name) <= 10 and " " not in name else "NONE"


def write_uff_records(records: list[dict[str, Any]], *, binary: bool = False) -> bytes:
    """Write dataset-58 records given as pyuff dictionaries; returns the file content."""
    import pyuff

    parts = []
    with tempfile.TemporaryDirectory(prefix="fbs_uff_") as d:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                # one small file per record: pyuff re-reads the whole file after every
                # write, which is quadratic in the number of records
                for k, r in enumerate(records):
                    path = Path(d) / f"r{k}.uff"
                    r = dict(r, binary=int(binary))
                    fid = int(r.pop("func_id", 0))  # record 6 field 2: not in prepare_58
                    dset = pyuff.prepare_58(**r)
                    dset["func_id"] = fid
                    pyuff.UFF(str(path)).write_sets(dset, mode="add")
                    parts.append(path.read_bytes())
                    path.unlink()
        except Exception as e:  # pyuff raises bare Exceptions
            raise DataFormatError(f"cannot write UFF dataset 58: {e}") from None
    return b"".join(parts)


def frf_records(
    frf: FRF,
    *,
    nodes: Mapping[Any, Any] | None = None,
    id_lines: Sequence[str] = (),
    round_abscissa: bool = False,
    name: str = "",
    function_id: int = 0,
) -> list[dict[str, Any]]:
    """pyuff dictionaries of one dataset 58 per output/input pair of ``frf``.

    ID line 1: ``name`` (when given), the quantity and the pair; lines 2-4: ``id_lines``
    (:func:`id_lines`); line 5: the node map (:func:`node_map_line`). ``function_id`` is
    record 6's function identification and version number: several FRFs of the same
    output/input pair in one file (e.g. a truncated model's and the reference) are told
    apart by it, each record a whole FRF record (type 4, its nodes, directions, units).
    """
    even = _abscissa(frf.freq, round_abscissa)
    numbers = _node_numbers(frf.outputs + frf.inputs, nodes)
    ids = list(id_lines)[:3] + ["NONE"] * 3
    id5 = node_map_line(numbers)
    label = f"{name}: " if name else ""
    recs = []
    ok, ik = frf.output_kinds, frf.input_kinds
    for o, out in enumerate(frf.outputs):
        for i, inp in enumerate(frf.inputs):
            (no, do), (ni, di) = parse_label(out), parse_label(inp)
            recs.append(
                dict(
                    func_type=4,
                    func_id=int(function_id),
                    ver_num=int(function_id),
                    load_case_id=0,
                    id1=f"{label}{frf.quantity} {out} / {inp}"[:80],
                    id2=ids[0][:80],
                    id3=ids[1][:80],
                    id4=ids[2][:80],
                    id5=id5,
                    rsp_node=numbers[no],
                    rsp_dir=DIR_CODES.get(do, 0) if do is not None else 0,
                    rsp_ent_name=_ent(no),
                    ref_node=numbers[ni],
                    ref_dir=DIR_CODES.get(di, 0) if di is not None else 0,
                    ref_ent_name=_ent(ni),
                    data=np.array(frf.data[:, o, i], dtype=complex),
                    x=np.array(frf.freq),
                    abscissa_spacing=even,
                    abscissa_spec_data_type=18,
                    abscissa_axis_units_lab="Hz",
                    ordinate_spec_data_type=SPEC_TYPES[frf.quantity],
                    ordinate_len_unit_exp=int(ok[o] == "translation"),
                    ordinate_axis_units_lab=response_unit(ok[o], frf.quantity),
                    orddenom_spec_data_type=_DEN_SPEC[ik[i]],
                    orddenom_len_unit_exp=int(ik[i] in ("moment", "road")),
                    orddenom_force_unit_exp=int(ik[i] in ("force", "moment")),
                    orddenom_axis_units_lab=_DEN_UNITS[ik[i]],
                    z_axis_spec_data_type=0,
                )
            )
    return recs


def write_uff(
    frf: FRF,
    *,
    nodes: Mapping[Any, Any] | None = None,
    metadata: Mapping[str, Any] | None = None,
    binary: bool = False,
    round_abscissa: bool = False,
) -> bytes:
    """An FRF as a Universal File of dataset-58 records (one per output/input pair).

    Node names become entity names (when at most 10 characters) and node numbers from
    ``nodes`` (number -> name) or 1, 2, ... in order of appearance. ID line 1 holds
    the quantity and the pair, line 2 the producer and date, lines 3-4 ``metadata`` as
    whole ``key=value`` pairs, line 5 the node map (``nodes: 1=bushing 2=patch``).

    Raises
    ------
    DataFormatError
        When the grid is not representable in E13.5 (see ``round_abscissa``).
    """
    return write_uff_records(
        frf_records(frf, nodes=nodes, id_lines=id_lines(metadata), round_abscissa=round_abscissa),
        binary=binary,
    )


def pack_items(items: Sequence[str], lines: int = 2, width: int = 80) -> tuple[list[str], int]:
    """``items`` joined by ``"; "`` into at most ``lines`` lines of ``width`` characters,
    an item never split across two lines or cut (a reader of one ID line reads whole
    values); returns the lines and the number of items left out (longer than a line, or
    beyond the last line; the last line says how many when there is room).

    Examples
    --------
    >>> pack_items(["a=1", "b=22", "c=333"], lines=1, width=9)
    (['a=1; b=22'], 1)
    """
    out: list[str] = []
    cur = ""
    left = 0
    for item in items:
        if len(item) > width:
            left += 1
        elif not cur:
            cur = item
        elif len(cur) + 2 + len(item) <= width:
            cur += "; " + item
        elif len(out) + 1 < lines:
            out.append(cur)
            cur = item
        else:
            left += 1
    if cur:
        out.append(cur)
    more = f"; +{left} more"
    if left and out and len(out[-1]) + len(more) <= width:
        out[-1] += more
    return out, left


def node_map_line(numbers: Mapping[str, int], width: int = 80) -> str:
    """ID line 5 of every record: the node numbers of the file's node names, e.g.
    ``"nodes: 1=bushing 2=patch"`` (whole pairs only; ``read_uff(nodes=...)`` takes the
    same map back)."""
    pairs = [f"{n}={name}" for name, n in sorted(numbers.items(), key=lambda kv: kv[1])]
    line, left = pack_items(pairs, lines=1, width=width - len("nodes: "))
    return "nodes: " + (line[0].replace("; ", " ") if line else "none")


def id_lines(metadata: Mapping[str, Any] | None) -> list[str]:
    """ID lines 2-4: producer and date, then ``key=value`` pairs of ``metadata`` packed
    whole into lines 3 and 4 (never split, never into line 5, which holds the node map:
    :func:`node_map_line`)."""
    from .. import __version__

    lines = [f"tire-fbs fbs_core {__version__}", time.strftime("%d-%b-%y %H:%M:%S")]
    items = [f"{k}={v}" for k, v in (metadata or {}).items()]
    packed, _ = pack_items(items, lines=2)
    lines = [" ".join(lines)[:80], *packed]
    return lines + ["NONE"] * (3 - len(lines))
