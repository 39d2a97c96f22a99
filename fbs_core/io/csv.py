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

import csv as _csv
import io
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import DataFormatError
from ..frf import FRF
from ._sandbox import DEFAULT_TIMEOUT, parse_isolated
from .checks import (
    Source,
    Units,
    frequency_from_units,
    kinds_text,
    missing_pairs,
    normalize_label,
    parse_kinds,
    parse_units,
    reconcile_quantity,
    rename_node,
    si_factors,
    units_line,
    units_note,
)

__all__ = ["read_csv", "write_csv", "write_csv_tables"]

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
    array.

    Raises
    ------
    DataFormatError, DOFError, QuantityError, FrequencyGridError
        Naming the line and column of the problem.
    """
    name = src.name
    parsed, (a,) = parse_isolated("csv", src.raw, f"CSV file {name!r}", timeout=timeout)
    meta: dict[str, str] = {}
    for body in parsed["comments"]:
        if ":" in body:
            key, _, val = body.partition(":")
            meta[key.strip().lower()] = val.strip()
    k = int(parsed["header_line"]) - 1
    header = [str(h).strip() for h in parsed["header"]]
    m = _FREQ.match(header[0]) if header else None
    if not m:
        raise DataFormatError(
            f"{name!r} line {k + 1}: the first column must be the frequency ('freq' or "
            f"'freq [Hz]'), got {header[0] if header else ''!r}"
        )
    freq_unit = m.group(2) or meta.get("freq_unit")
    layout = meta.get("layout", "").lower()
    phase_unit = meta.get("phase_unit", "deg").lower()
    if phase_unit not in ("deg", "rad"):
        raise DataFormatError(f"{name!r}: phase_unit {phase_unit!r}; allowed: deg, rad")
    cols: dict[tuple[str, str], dict[str, int]] = {}
    col_units: dict[tuple[str, str], str] = {}  # optional "[unit]" after a column name
    for c, h in enumerate(header[1:], start=1):
        mm = _COL.match(h)
        if not mm:
            raise DataFormatError(
                f"{name!r} line {k + 1} column {c + 1}: header {h!r} is not Re(out / in), "
                "Im(out / in), Mag(out / in) or Phase(out / in)"
            )
        part = {"re": "re", "im": "im", "mag": "mag", "abs": "mag", "phase": "ph", "ph": "ph"}[
            mm.group(1).lower()
        ]
        o, i = _split_pair(mm.group(2), f"{name!r} column {c + 1}")
        key = (o, i)
        if part in cols.setdefault(key, {}):
            raise DataFormatError(f"{name!r}: column {h!r} appears twice")
        cols[key][part] = c
        if mm.group(3) and part in ("re", "im", "mag"):
            if col_units.setdefault(key, mm.group(3)) != mm.group(3):
                raise DataFormatError(
                    f"{name!r}: the columns of {o} / {i} give two units, "
                    f"{col_units[key]!r} and {mm.group(3)!r}"
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
    if layout and layout != got:
        raise DataFormatError(f"{name!r}: header says layout {layout!r} but columns are {got}")

    if a.shape[0] == 0:
        raise DataFormatError(f"{name!r} has no data rows")
    if not np.all(np.isfinite(a)):
        r, c = np.argwhere(~np.isfinite(a))[0]
        raise DataFormatError(
            f"{name!r}: non-finite value (NaN or inf) in data row {r + 1}, column {c + 1} "
            f"({header[c]!r})"
        )
    freq = frequency_from_units(a[:, 0], freq_unit, repr(name))

    norm = {}
    labels: dict[tuple[str, str], tuple[str, int]] = {}

    def norm_label(text: str, what: str) -> tuple[str, int]:
        key = (text, what)
        if key not in labels:
            lab, sign = normalize_label(text, what)
            labels[key] = (rename_node(lab, nodes), sign)
        return labels[key]

    entry_units: dict[tuple[str, str], str] = {}
    for (o, i), v in cols.items():
        (lo, so), (li, si) = norm_label(o, "output"), norm_label(i, "input")
        key = (lo, li)
        if key in norm:
            raise DataFormatError(f"{name!r}: two column pairs for {key[0]} / {key[1]}")
        norm[key] = (v, so * si)
        if (o, i) in col_units:
            entry_units[key] = col_units[(o, i)]
    outputs = list(dict.fromkeys(o for o, _ in norm))
    inputs = list(dict.fromkeys(i for _, i in norm))
    n_missing, missing = missing_pairs(outputs, inputs, norm)
    if n_missing:
        shown = ", ".join(f"{o} / {i}" for o, i in missing)
        raise DataFormatError(
            f"{name!r}: {n_missing} output/input pairs have no columns: {shown}; a full "
            "matrix of outputs x inputs is needed"
        )
    o_pos = {o: k for k, o in enumerate(outputs)}
    i_pos = {i: k for k, i in enumerate(inputs)}
    first, second = ("re", "im") if got == "re-im" else ("mag", "ph")
    c1 = np.fromiter((v[first] for v, _ in norm.values()), np.intp, len(norm))
    c2 = np.fromiter((v[second] for v, _ in norm.values()), np.intp, len(norm))
    sg = np.fromiter((s for _, s in norm.values()), float, len(norm))
    oi = np.fromiter((o_pos[o] for o, _ in norm), np.intp, len(norm))
    ii = np.fromiter((i_pos[i] for _, i in norm), np.intp, len(norm))
    if got == "re-im":
        z = a[:, c1] + 1j * a[:, c2]
    else:
        z = a[:, c1] * np.exp(1j * a[:, c2] * (np.pi / 180 if phase_unit == "deg" else 1.0))
    data = np.empty((a.shape[0], len(outputs), len(inputs)), dtype=complex)
    data[:, oi, ii] = z * sg
    notes = []
    units = parse_units(meta.get("units"))
    if meta.get("units") and units is None:
        notes.append(f"units {meta['units']!r} not understood; not checked")
    if not meta.get("units") and entry_units:
        # no unit line: the columns' own units say it (all of them, or it is ambiguous)
        if len(entry_units) != len(norm):
            raise DataFormatError(
                f"{name!r}: {len(entry_units)} of {len(norm)} output/input pairs give a "
                "unit after their column name and there is no '# units:' line; give every "
                "pair its unit, or the unit line"
            )
    declared = units
    if not meta.get("units") and entry_units:
        declared = _parse_column_unit(next(iter(entry_units.items())), name)
    q = reconcile_quantity(
        meta.get("quantity") or None, declared, quantity, repr(name), meta.get("units")
    )
    frf = FRF(freq, data, outputs, inputs, q, kinds=parse_kinds(meta.get("kinds"), repr(name)))
    notes += units_note(units)
    factors = None
    if units is not None:
        factors = si_factors(units, outputs, inputs, frf.kinds, q)
    if entry_units:
        factors, differ = _column_factors(entry_units, factors, frf, q, o_pos, i_pos, name)
        if differ:
            notes.append(
                f"the unit line {meta['units']!r} governs; {len(differ)} column pairs state "
                f"another scale, e.g. {differ[0]}"
            )
        else:
            notes.append(f"units of {len(entry_units)} column pairs checked")
    if factors is not None and not np.all(factors == 1.0):
        frf = frf.replace(data=frf.data * factors[None])
        came = units.label if units is not None else "the column units"
        notes.append(f"converted from {came} to SI ({frf.unit()})")
    extra = {
        k: v
        for k, v in meta.items()
        if k not in ("quantity", "units", "layout", "phase_unit", "freq_unit", "kinds")
    }
    return frf, notes, extra


def _parse_column_unit(item: tuple[tuple[str, str], str], name: str) -> Units:
    (o, i), text = item
    u = parse_units(text)
    if u is None or u.quantity is None:
        raise DataFormatError(
            f"{name!r}: the unit {text!r} after the columns of {o} / {i} is not understood "
            "as an FRF unit (known: m mm cm um in ft / N kN mN lbf / s ms / rad deg / g, "
            "e.g. '(m/s)/m', 'rad/(N m s)', 'mm/(s N)')"
        )
    return u


def _column_factors(
    entry_units: Mapping[tuple[str, str], str],
    factors: np.ndarray | None,
    frf: FRF,
    q: str,
    o_pos: Mapping[str, int],
    i_pos: Mapping[str, int],
    name: str,
) -> tuple[np.ndarray, list[str]]:
    """SI factors from the unit written after each column name, checked against the kind
    of each entry (a rotation is not in m). Where the file has a unit line, that line
    governs the scale (a file whose unit line was edited by hand reads as the line says);
    the pairs whose column unit gives another scale are returned for the import notes."""
    from ..units import input_kind, output_kind

    out = np.ones((len(o_pos), len(i_pos))) if factors is None else factors.copy()
    differ: list[str] = []
    for (o, i), text in entry_units.items():
        u = _parse_column_unit(((o, i), text), name)
        ok, ik = output_kind(o, frf.kinds), input_kind(i, frf.kinds)
        if u.kinds is not None and u.kinds != (ok, ik):
            raise DataFormatError(
                f"{name!r}: the unit {text!r} of {o} / {i} is that of a {u.kinds[0]} per "
                f"{u.kinds[1]}, but {o} is a {ok} and {i} a {ik}"
            )
        if u.quantity != q:
            raise DataFormatError(
                f"{name!r}: the unit {text!r} of {o} / {i} is that of a {u.quantity}, the "
                f"file holds a {q}"
            )
        f = u.factor(ok, ik, q)
        a, b = o_pos[o], i_pos[i]
        if factors is None:
            out[a, b] = f
        elif not np.isclose(f, factors[a, b], rtol=1e-9, atol=0.0):
            differ.append(f"{o} / {i} [{text}]")
    return out, differ


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


def write_csv_tables(
    tables: list[tuple[str, list[str], np.ndarray]],
    metadata: Mapping[str, Any] | None = None,
    title: str = "result",
) -> bytes:
    """Several tables in one CSV text, each introduced by ``# table: <name>``.

    ``tables`` holds ``(name, column_names, rows)`` with ``rows`` a 2-D array;
    tables are separated by a blank line.
    """
    out = io.StringIO()
    out.write("\n".join(_header(metadata, title)) + "\n")
    for name, columns, rows in tables:
        out.write(f"\n# table: {name}\n")
        w = _csv.writer(out, lineterminator="\n")
        w.writerow(columns)
        for row in np.atleast_2d(rows):
            w.writerow(
                [
                    safe_cell(x)
                    if isinstance(x, str)
                    else repr(float(x))
                    if np.isreal(x)
                    else repr(complex(x))
                    for x in row
                ]
            )
    return out.getvalue().encode()
