"""CSV with a documented layout: FRFs in and out, and results out.

FRF layout (``docs/file-formats.md``)::

    # tire-fbs FRF
    # quantity: mobility
    # units: m/(N s)
    # layout: re-im
    freq [Hz],Re(bushing:z / spindle:x) [m/(N s)],Im(bushing:z / spindle:x) [m/(N s)],...
    0.5,1.25e-05,-3.5e-06,...

Header lines start with ``#`` and hold ``key: value`` pairs: ``quantity``
(receptance, mobility, accelerance), ``units``, ``layout`` (``re-im`` or
``mag-phase``), ``phase_unit`` (``deg`` or ``rad``), ``freq_unit`` (``Hz``,
``rad/s``); other keys are kept as metadata. Then one header row: the frequency
column first, then two columns per output/input pair, ``Re(out / in)`` and
``Im(out / in)`` (or ``Mag(...)`` and ``Phase(...)``), in any order, each optionally
followed by the entry's unit in brackets (``[(rad/s)/m]``; the writer always gives it,
since one FRF can mix translations and rotations, forces, moments and road inputs). A
column unit is checked against the entry's kind (a rotation in m is refused); the
``units`` line, where present, governs the scale (a difference is noted on import);
without a ``units`` line the column units convert the data. Comma, semicolon or tab separated;
UTF-8.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from ..errors import DataFormatError
from ..frf import FRF
from ..units import Units, kinds_of, parse_units
from ._sandbox import DEFAULT_TIMEOUT, parse_isolated
from .assembly import FileUnits, assemble, dof_labels
from .checks import Source, frequency_from_units, kinds_text, missing_pairs, units_line

__all__ = ["read_csv", "write_csv", "safe_cell", "safe_text"]

_COL = re.compile(
    r"^\s*(re|im|mag|abs|phase|ph)\s*[\(\[]\s*(.+?)\s*[\)\]]\s*(?:\[\s*([^\]]*?)\s*\])?\s*$", re.I
)
_FREQ = re.compile(r"^\s*(freq|frequency|f)\s*(?:[\[\(]\s*([^\]\)]*)\s*[\]\)])?\s*$", re.I)


def _split_pair(text: str, where: str) -> tuple[str, str]:
    if " / " in text:
        o, _, i = text.partition(" / ")
    elif text.count("/") == 1:
        o, _, i = text.partition("/")
    else:
        raise DataFormatError(f"{where}: cannot split {text!r} into 'output / input'")
    return o.strip(), i.strip()


#: Header keys that describe the layout; every other ``# key: value`` line is metadata.
_LAYOUT_KEYS = ("quantity", "units", "layout", "phase_unit", "freq_unit", "kinds")
_PARTS = {"re": "re", "im": "im", "mag": "mag", "abs": "mag", "phase": "ph", "ph": "ph"}
#: Columns of one output/input pair as written: part ("re", "im", "mag", "ph") -> column.
_Columns = dict[str, int]
_Pair = tuple[str, str]


def read_csv(
    src: Source,
    *,
    nodes: Mapping[Any, Any] | None = None,
    quantity: str | None = None,
    timeout: float = DEFAULT_TIMEOUT,
) -> tuple[FRF, list[str], dict[str, Any]]:
    """Read an FRF from CSV in the documented layout.

    The numbers are parsed in the sandbox process (:func:`._textparse.parse_csv`, under
    its time and memory limits); this process receives the header lines and one float
    array. Steps: the ``#`` lines (:func:`_key_values`), the column header
    (:func:`_value_columns`), the data block by output/input pair (:func:`_pairs`,
    :func:`_matrix`), then :func:`.assembly.assemble` and the check of the column units
    (:func:`_check_column_units`).

    Raises
    ------
    DataFormatError, DOFError, QuantityError, FrequencyGridError
        Naming the line and column of the problem.
    """
    name = src.name
    parsed, (a,) = parse_isolated("csv", src.raw, f"CSV file {name!r}", timeout=timeout)
    meta = _key_values(parsed["comments"])
    line = int(parsed["header_line"])
    header = [str(h).strip() for h in parsed["header"]]
    m = _FREQ.match(header[0]) if header else None
    if not m:
        raise DataFormatError(
            f"{name!r} line {line}: the first column must be the frequency ('freq' or "
            f"'freq [Hz]'), got {header[0] if header else ''!r}"
        )
    phase_unit = meta.get("phase_unit", "deg").lower()
    if phase_unit not in ("deg", "rad"):
        raise DataFormatError(f"{name!r}: phase_unit {phase_unit!r}; allowed: deg, rad")
    cols, col_units, layout = _value_columns(header, line, name, meta.get("layout", ""))
    if a.shape[0] == 0:
        raise DataFormatError(f"{name!r} has no data rows")
    if not np.all(np.isfinite(a)):
        r, c = np.argwhere(~np.isfinite(a))[0]
        raise DataFormatError(
            f"{name!r}: non-finite value (NaN or inf) in data row {r + 1}, column {c + 1} "
            f"({header[c]!r})"
        )
    freq = frequency_from_units(a[:, 0], m.group(2) or meta.get("freq_unit"), repr(name))
    pairs, entry_units = _pairs(cols, col_units, nodes, name)
    outputs = list(dict.fromkeys(o for o, _ in pairs))
    inputs = list(dict.fromkeys(i for _, i in pairs))
    n_missing, missing = missing_pairs(outputs, inputs, pairs)
    if n_missing:
        shown = ", ".join(f"{o} / {i}" for o, i in missing)
        raise DataFormatError(
            f"{name!r}: {n_missing} output/input pairs have no columns: {shown}; a full "
            "matrix of outputs x inputs is needed"
        )
    data, signs = _matrix(a, pairs, outputs, inputs, layout, phase_unit)
    line_label = meta.get("units") or None
    if line_label is None and entry_units and len(entry_units) != len(pairs):
        # no unit line: the columns' own units say it (all of them, or it is ambiguous)
        raise DataFormatError(
            f"{name!r}: {len(entry_units)} of {len(pairs)} output/input pairs give a "
            "unit after their column name and there is no '# units:' line; give every "
            "pair its unit, or the unit line"
        )
    stated = {pair: _parse_column_unit(pair, text, name) for pair, text in entry_units.items()}
    if line_label is None:
        units = FileUnits(dict(entry_units))
    else:  # the line governs; the columns serve only where the line is not understood
        units = FileUnits(line_label, stated or None)
    frf, notes = assemble(
        freq,
        data,
        outputs,
        inputs,
        where=repr(name),
        quantity=quantity,
        declared=meta.get("quantity") or None,
        units=units,
        kinds=meta.get("kinds"),
        signs=signs,
    )
    if stated:
        notes += _check_column_units(stated, frf, parse_units(line_label), name)
    return frf, notes, {k: v for k, v in meta.items() if k not in _LAYOUT_KEYS}


def _key_values(comments: Iterable[str]) -> dict[str, str]:
    """The ``key: value`` pairs of the ``#`` lines (keys in lower case)."""
    meta: dict[str, str] = {}
    for body in comments:
        if ":" in body:
            key, _, val = body.partition(":")
            meta[key.strip().lower()] = val.strip()
    return meta


def _value_columns(
    header: list[str], line: int, name: str, layout: str
) -> tuple[dict[_Pair, _Columns], dict[_Pair, str], str]:
    """The FRF columns of the header row by output/input pair as written, the unit written
    after them (``[unit]``), and the layout (``"re-im"`` or ``"mag-phase"``).

    Raises
    ------
    DataFormatError
        For a header that is not ``Re(out / in)`` ..., a column given twice, two units of
        one pair, pairs without both parts or of mixed layouts, or a layout line that
        contradicts the columns.
    """
    cols: dict[_Pair, _Columns] = {}
    col_units: dict[_Pair, str] = {}
    for c, h in enumerate(header[1:], start=1):
        mm = _COL.match(h)
        if not mm:
            raise DataFormatError(
                f"{name!r} line {line} column {c + 1}: header {h!r} is not Re(out / in), "
                "Im(out / in), Mag(out / in) or Phase(out / in)"
            )
        part = _PARTS[mm.group(1).lower()]
        key = _split_pair(mm.group(2), f"{name!r} column {c + 1}")
        if part in cols.setdefault(key, {}):
            raise DataFormatError(f"{name!r}: column {h!r} appears twice")
        cols[key][part] = c
        unit = mm.group(3)
        if unit and part in ("re", "im", "mag") and col_units.setdefault(key, unit) != unit:
            raise DataFormatError(
                f"{name!r}: the columns of {key[0]} / {key[1]} give two units, "
                f"{col_units[key]!r} and {unit!r}"
            )
    if not cols:
        raise DataFormatError(f"{name!r} has a frequency column but no FRF columns")
    kinds = {frozenset(v) for v in cols.values()}
    if kinds == {frozenset({"re", "im"})}:
        got = "re-im"
    elif kinds == {frozenset({"mag", "ph"})}:
        got = "mag-phase"
    else:
        bad = next(k for k, v in cols.items() if set(v) not in ({"re", "im"}, {"mag", "ph"}))
        raise DataFormatError(
            f"{name!r}: pair {bad[0]} / {bad[1]} has columns {sorted(cols[bad])}; every pair "
            "needs Re and Im, or Mag and Phase, and all pairs the same layout"
        )
    if layout and layout.lower() != got:
        raise DataFormatError(
            f"{name!r}: header says layout {layout.lower()!r} but columns are {got}"
        )
    return cols, col_units, got


def _pairs(
    cols: Mapping[_Pair, _Columns],
    col_units: Mapping[_Pair, str],
    nodes: Mapping[Any, Any] | None,
    name: str,
) -> tuple[dict[_Pair, tuple[_Columns, float]], dict[_Pair, str]]:
    """The columns and sign of every pair by its normalised labels
    (:func:`.assembly.dof_labels`), and the units written after the columns by pair.

    Raises
    ------
    DOFError
        For labels that are not DOF labels.
    DataFormatError
        For two column pairs that name the same output/input pair.
    """
    o_text = list(dict.fromkeys(o for o, _ in cols))
    i_text = list(dict.fromkeys(i for _, i in cols))
    outs = dict(zip(o_text, zip(*dof_labels(o_text, "output", nodes), strict=True), strict=True))
    ins = dict(zip(i_text, zip(*dof_labels(i_text, "input", nodes), strict=True), strict=True))
    pairs: dict[_Pair, tuple[_Columns, float]] = {}
    units: dict[_Pair, str] = {}
    for (o, i), v in cols.items():
        (lo, so), (li, si) = outs[o], ins[i]
        if (lo, li) in pairs:
            raise DataFormatError(f"{name!r}: two column pairs for {lo} / {li}")
        pairs[(lo, li)] = (v, float(so * si))
        if (o, i) in col_units:
            units[(lo, li)] = col_units[(o, i)]
    return pairs, units


def _matrix(
    a: np.ndarray,
    pairs: Mapping[_Pair, tuple[_Columns, float]],
    outputs: list[str],
    inputs: list[str],
    layout: str,
    phase_unit: str,
) -> tuple[np.ndarray, np.ndarray]:
    """The data block ``(n_freq, n_out, n_in)`` from the columns of ``a`` and the sign of
    every entry ``(n_out, n_in)``."""
    o_pos = {o: k for k, o in enumerate(outputs)}
    i_pos = {i: k for k, i in enumerate(inputs)}
    n = len(pairs)
    first, second = ("re", "im") if layout == "re-im" else ("mag", "ph")
    c1 = np.fromiter((v[first] for v, _ in pairs.values()), np.intp, n)
    c2 = np.fromiter((v[second] for v, _ in pairs.values()), np.intp, n)
    oi = np.fromiter((o_pos[o] for o, _ in pairs), np.intp, n)
    ii = np.fromiter((i_pos[i] for _, i in pairs), np.intp, n)
    if layout == "re-im":
        z = a[:, c1] + 1j * a[:, c2]
    else:
        z = a[:, c1] * np.exp(1j * a[:, c2] * (np.pi / 180 if phase_unit == "deg" else 1.0))
    data = np.empty((a.shape[0], len(outputs), len(inputs)), dtype=complex)
    data[:, oi, ii] = z
    signs = np.ones((len(outputs), len(inputs)))
    signs[oi, ii] = np.fromiter((s for _, s in pairs.values()), float, n)
    return data, signs


def _parse_column_unit(pair: _Pair, text: str, name: str) -> Units:
    u = parse_units(text)
    if u is None or u.quantity is None:
        raise DataFormatError(
            f"{name!r}: the unit {text!r} after the columns of {pair[0]} / {pair[1]} is not "
            "understood as an FRF unit (known: m mm cm um in ft / N kN mN lbf / s ms / rad "
            "deg / g, e.g. '(m/s)/m', 'rad/(N m s)', 'mm/(s N)')"
        )
    return u


def _check_column_units(
    stated: Mapping[_Pair, Units], frf: FRF, line: Units | None, name: str
) -> list[str]:
    """Check the unit written after each column name against the kind of its entry (a
    rotation is not in m) and the quantity; where the file has a unit line understood,
    that line governs the scale (a file whose unit line was edited by hand reads as the
    line says) and the pairs whose column unit gives another scale are noted.

    Raises
    ------
    DataFormatError
        For a column unit of another kind or quantity than its entry.
    """
    ok, ik = kinds_of(frf.outputs, frf.inputs, frf.kinds)
    o_pos = {o: k for k, o in enumerate(frf.outputs)}
    i_pos = {i: k for k, i in enumerate(frf.inputs)}
    q = frf.quantity
    differ: list[str] = []
    for (o, i), u in stated.items():
        kinds = (ok[o_pos[o]], ik[i_pos[i]])
        if u.kinds is not None and u.kinds != kinds:
            raise DataFormatError(
                f"{name!r}: the unit {u.label!r} of {o} / {i} is that of a {u.kinds[0]} per "
                f"{u.kinds[1]}, but {o} is a {kinds[0]} and {i} a {kinds[1]}"
            )
        if u.quantity != q:
            raise DataFormatError(
                f"{name!r}: the unit {u.label!r} of {o} / {i} is that of a {u.quantity}, the "
                f"file holds a {q}"
            )
        if line is not None and not np.isclose(
            u.factor(*kinds, q), line.factor(*kinds, q), rtol=1e-9, atol=0.0
        ):
            differ.append(f"{o} / {i} [{u.label}]")
    if differ and line is not None:
        return [
            f"the unit line {line.label!r} governs; {len(differ)} column pairs state another "
            f"scale, e.g. {differ[0]}"
        ]
    return [f"units of {len(stated)} column pairs checked"]


def _header(metadata: Mapping[str, Any] | None, title: str) -> list[str]:
    from .. import __version__

    lines = [f"# tire-fbs {title}"]
    if "fbs_core_version" not in (metadata or {}):
        lines.append(f"# fbs_core_version: {__version__}")
    for k, v in (metadata or {}).items():
        text = str(v).replace("\r", " ").replace("\n", " ")
        lines.append(safe_text(f"# {k}: {text}"))
    return lines


_FORMULA_START = ("=", "+", "-", "@", "\t", "\r", "\uff1d", "\uff0b", "\uff0d", "\uff20")
_SEPARATORS = re.compile(r"([,;\t])")


def safe_cell(text: str) -> str:
    """A text cell a spreadsheet will not run as a formula (CSV injection).

    Text starting with ``= + - @``, a tab or a carriage return (also the full-width
    forms) gets a leading apostrophe, which spreadsheets show as plain text.
    """
    return "'" + text if text.lstrip(" ").startswith(_FORMULA_START) else text


def safe_text(text: str) -> str:
    """Apply :func:`safe_cell` to every piece of a line a spreadsheet may split into
    cells (at commas, semicolons and tabs)."""
    parts = _SEPARATORS.split(text)
    return "".join(p if k % 2 else safe_cell(p) for k, p in enumerate(parts))


def write_csv(frf: FRF, *, metadata: Mapping[str, Any] | None = None) -> bytes:
    """An FRF as CSV in the documented ``re-im`` layout (full double precision)."""
    lines = _header(metadata, "FRF") + [
        f"# quantity: {frf.quantity}",
        f"# units: {units_line(frf)}",
        "# layout: re-im",
    ]
    if frf.kinds:
        lines.append(f"# kinds: {kinds_text(frf.kinds)}")
    cols = ["freq [Hz]"]
    units = frf.units  # every entry's own SI unit, written after its column name
    for a, o in enumerate(frf.outputs):
        for b, i in enumerate(frf.inputs):
            u = units[a, b]
            cols += [f"Re({o} / {i}) [{u}]", f"Im({o} / {i}) [{u}]"]
    lines.append(",".join(cols))
    d = frf.data.reshape(frf.freq.size, -1)
    block = np.empty((frf.freq.size, 1 + 2 * d.shape[1]))
    block[:, 0] = frf.freq
    block[:, 1::2], block[:, 2::2] = d.real, d.imag
    lines += [",".join(map(repr, row)) for row in block.tolist()]
    return ("\n".join(lines) + "\n").encode()
