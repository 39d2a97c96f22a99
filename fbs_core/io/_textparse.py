"""Parsers of the text formats (UFF, CSV) that run in the sandbox process.

This module imports nothing but the standard library and numpy, so that the sandbox
worker (:mod:`fbs_core.io._worker`, which never imports ``fbs_core``) loads it by
path. Both parsers are linear in the size of the file and never build one Python
object per number of the file's data: numbers are parsed by numpy from whole blocks.

* :func:`parse_uff` splits a Universal File into its datasets (a block between two
  ``-1`` lines; binary 58b blocks are skipped by their announced byte count, so bytes
  looking like ``-1`` inside them do not split them) and reads datasets 58 / 58b
  (header records 1-11 and the data), 164 (units), 151 (header) and the node
  coordinates of 15 and 2411 completely; of other datasets only the type is kept. A
  file that ends inside a dataset is refused with the line where it ends.
* :func:`parse_csv` reads the ``#`` header lines and the column-header row as text
  and the data rows as one float array.
* :func:`parse_table` reads a small CSV table whose cells are text (a geometry table:
  channel labels beside numbers), at most :data:`MAX_TABLE_CELLS` cells.

Both return ``(meta, arrays)``: JSON-compatible ``meta`` referring to ``arrays`` by
position, as the other sandbox handlers do. Refusals raise :class:`ParseError` with
a message for the user.
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["ParseError", "parse_uff", "parse_csv", "parse_table"]


class ParseError(ValueError):
    """A refusal with a message for the user."""


_DELIM = re.compile(rb"^[ \t]*-1[ \t]*\r?$", re.M)
_CLOSE_BIN = re.compile(rb"[ \t\r\n]*-1[ \t]*(?=\r?\n|$)")
_TYPE = re.compile(rb"^[ \t]*(\d{1,6})([bB]?)(.*)$")


def _line_no(raw: bytes, pos: int) -> int:
    return raw.count(b"\n", 0, pos) + 1


def _text(b: bytes) -> str:
    try:
        return b.decode("utf-8")
    except UnicodeDecodeError:
        return b.decode("latin-1")  # every byte is a character; labels like m/s² (0xB2)


def _int(s: str, what: str) -> int:
    try:
        return int(s.strip() or 0)
    except ValueError:
        raise ParseError(f"{what}: {s.strip()!r} is not an integer") from None


def _float(s: str, what: str) -> float:
    try:
        return float(s.strip().replace("D", "E").replace("d", "e") or 0.0)
    except ValueError:
        raise ParseError(f"{what}: {s.strip()!r} is not a number") from None


def _fields(line: str, widths: Sequence[int], what: str) -> list[str]:
    out: list[str] = []
    p = 0
    for w in widths:
        out.append(line[p : p + w])
        p += w
    return out


def _next_line(raw: bytes, pos: int) -> tuple[bytes, int]:
    """The line starting at ``pos`` (without its end) and the position after it."""
    e = raw.find(b"\n", pos)
    if e < 0:
        return raw[pos:].rstrip(b"\r"), len(raw)
    return raw[pos:e].rstrip(b"\r"), e + 1


_FUNC_TYPES = {
    0: "general functions",
    1: "time responses",
    2: "auto spectra",
    3: "cross spectra",
    4: "FRFs",
    5: "transmissibilities",
    6: "coherences",
    7: "auto correlations",
    8: "cross correlations",
    9: "PSDs",
    10: "ESDs",
    11: "probability densities",
    12: "spectra",
    18: "mode indicator functions",
    27: "order functions",
}


def _header58(lines: list[str], where: str) -> dict[str, Any]:
    d: dict[str, Any] = {}
    for k in range(5):
        d[f"id{k + 1}"] = lines[k].rstrip()
    f = _fields(lines[5], (5, 10, 5, 10, 11, 10, 4, 11, 10, 4), where)
    w6 = f"{where} record 6"
    d.update(
        func_type=_int(f[0], w6),
        func_id=_int(f[1], w6),
        ver_num=_int(f[2], w6),
        load_case_id=_int(f[3], w6),
        rsp_ent_name=f[4].strip(),
        rsp_node=_int(f[5], w6),
        rsp_dir=_int(f[6], w6),
        ref_ent_name=f[7].strip(),
        ref_node=_int(f[8], w6),
        ref_dir=_int(f[9], w6),
    )
    f = _fields(lines[6], (10, 10, 10, 13, 13, 13), where)
    w7 = f"{where} record 7"
    d.update(
        ord_data_type=_int(f[0], w7),
        num_pts=_int(f[1], w7),
        abscissa_spacing=_int(f[2], w7),
        abscissa_min=_float(f[3], w7),
        abscissa_inc=_float(f[4], w7),
        z_axis_value=_float(f[5], w7),
    )
    if d["ord_data_type"] not in (2, 4, 5, 6):
        raise ParseError(
            f"{where}: ordinate data type {d['ord_data_type']}; allowed: 2, 4 (real), "
            "5, 6 (complex)"
        )
    if d["abscissa_spacing"] not in (0, 1) or d["num_pts"] < 0:
        raise ParseError(
            f"{where}: record 7 has abscissa spacing {d['abscissa_spacing']} and "
            f"{d['num_pts']} values"
        )
    for line, prefix, rec in zip(
        lines[7:11], ("abscissa", "ordinate", "orddenom", "z_axis"), (8, 9, 10, 11), strict=True
    ):
        f = _fields(line, (10, 5, 5, 5, 21, 21), where)
        w = f"{where} record {rec}"
        d[f"{prefix}_spec_data_type"] = _int(f[0], w)
        d[f"{prefix}_len_unit_exp"] = _int(f[1], w)
        d[f"{prefix}_force_unit_exp"] = _int(f[2], w)
        d[f"{prefix}_temp_unit_exp"] = _int(f[3], w)
        d[f"{prefix}_axis_lab"] = f[4].strip()
        d[f"{prefix}_axis_units_lab"] = f[5].strip()
    return d


def _values_count(d: dict[str, Any]) -> int:
    n = d["num_pts"]
    per = 2 if d["ord_data_type"] in (5, 6) else 1
    count: int = n * (per + (1 if d["abscissa_spacing"] == 0 else 0))
    return count


def _ascii_values(body: bytes, d: dict[str, Any], where: str, line0: int) -> np.ndarray:
    want = _values_count(d)
    text = body.replace(b"D", b"E").replace(b"d", b"e")
    vals = np.fromstring(text, dtype=float, sep=" ") if text.strip() else np.empty(0)
    if vals.size == want:
        return vals
    # numbers written without spaces between them: fixed-width fields
    double = d["ord_data_type"] in (4, 6)
    widths: tuple[int, ...]
    if d["abscissa_spacing"] == 0 and double:
        widths = (13, 20, 20) if d["ord_data_type"] == 6 else (13, 20)
    else:
        widths = (20,) if double else (13,)
    out: list[float] = []
    bad = False  # a cell that is not a number: not fixed-width data
    for ln in text.splitlines():
        p = 0
        s = ln.decode("latin-1")
        while p < len(s) and s[p:].strip():
            for w in widths:
                cell = s[p : p + w]
                p += w
                if cell.strip():
                    try:
                        out.append(float(cell))
                    except ValueError:
                        bad = True
                        break
            if bad:
                break
        if bad:
            break
    if not bad and len(out) == want:
        return np.asarray(out, dtype=float)
    n_lines = body.count(b"\n")
    raise ParseError(
        f"{where}: record 7 announces {d['num_pts']} values ({want} numbers) but the data "
        f"(lines {line0}-{line0 + n_lines}) hold {vals.size} readable numbers; the file is "
        "truncated or damaged"
    )


def _split58(vals: np.ndarray, d: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    n = d["num_pts"]
    cplx = d["ord_data_type"] in (5, 6)
    if d["abscissa_spacing"] == 0:
        k = 3 if cplx else 2
        v = vals[: n * k].reshape(n, k)
        x = v[:, 0].copy()
        y = v[:, 1] + 1j * v[:, 2] if cplx else v[:, 1].copy()
    else:
        x = d["abscissa_min"] + np.arange(n) * d["abscissa_inc"]
        y = vals[0 : 2 * n : 2] + 1j * vals[1 : 2 * n : 2] if cplx else vals[:n].copy()
    return x, y


def parse_uff(raw: bytes, max_values: int | None = None) -> tuple[dict[str, Any], list[np.ndarray]]:
    """Split a Universal File into datasets and read 58/58b, 164 and 151.

    The steps, dataset by dataset: where it opens (:func:`_opening`), its type line
    (:func:`_type_of`), the announced extent of binary data (:func:`_binary_extent`),
    where it closes (:func:`_closing`), then its content (:func:`_header_of_58` and
    :func:`_values_of_58`, :func:`_units_164`, :func:`_header_151`).

    Parameters
    ----------
    raw : bytes
    max_values : int, optional
        Refuse a file whose datasets 58 hold more numbers than this in total (what may
        come back from the sandbox).

    Raises
    ------
    ParseError
        For a file that ends inside a dataset, damaged headers, data shorter or longer
        than record 7 announces, unknown binary formats, and text outside datasets.
    """
    sets: list[dict[str, Any]] = []
    arrays: list[np.ndarray] = []
    lines = _Lines(raw)
    pos = 0
    empty = 0
    total = 0
    while (p := _opening(raw, pos)) is not None:
        type_line, body_start = _next_line(raw, p)
        if _DELIM.fullmatch(type_line):  # "-1" twice: an empty dataset
            empty += 1
            pos = body_start
            continue
        dtype, binary, rest = _type_of(raw, p, type_line)
        line = lines.at(p)
        where = f"dataset {len(sets) + 1} (type {dtype}{'b' if binary else ''}, line {line})"
        extent = _binary_extent(raw, body_start, dtype, rest, type_line, where) if binary else None
        e = _closing(raw, body_start, extent, where)
        entry: dict[str, Any] = {"type": dtype, "binary": int(binary), "line": line}
        if dtype == 58:
            d, data_start = _header_of_58(
                raw, body_start, extent[0] if extent else e.start(), where
            )
            total += _values_count(d)
            if max_values is not None and total > max_values:
                raise ParseError(
                    f"the datasets 58 hold more than {max_values} numbers, more than this "
                    "tool accepts from one file"
                )
            if extent:
                vals = _binary_values(raw, extent, d, where)
            else:
                vals = _ascii_values(raw[data_start : e.start()], d, where, lines.at(data_start))
            x, y = _split58(vals, d)
            d["data"] = len(arrays)
            arrays.append(y)
            if d["abscissa_spacing"] == 0:  # even spacing: abscissa_min + k abscissa_inc
                d["x"] = len(arrays)
                arrays.append(x)
            entry.update(d)
        elif dtype == 164:
            entry.update(_units_164(raw[body_start : e.start()].splitlines(), where))
        elif dtype in (15, 2411):
            ids, cs, xyz = _nodes(raw[body_start : e.start()].splitlines(), dtype, where)
            total += 6 * len(ids)
            if max_values is not None and total > max_values:
                raise ParseError(
                    "the datasets hold more numbers than this tool accepts from one file"
                )
            entry.update(nodes=len(arrays), cs=len(arrays) + 1, xyz=len(arrays) + 2)
            arrays += [ids, cs, xyz]
        elif dtype == 151:
            body = raw[body_start : e.start()].splitlines()
            entry.update({f"line{i + 1}": _text(b).rstrip()[:80] for i, b in enumerate(body[:7])})
        sets.append(entry)
        pos = e.end()
    return {"format": "uff", "sets": sets, "empty": empty, "contents": _contents(sets)}, arrays


class _Lines:
    """Line numbers of positions, counted once, forwards (positions mostly increase)."""

    def __init__(self, raw: bytes) -> None:
        self.raw = raw
        self.mark = [0, 1]  # a position and its line number

    def at(self, q: int) -> int:
        if q < self.mark[0]:
            return _line_no(self.raw, q)
        self.mark[1] += self.raw.count(b"\n", self.mark[0], q)
        self.mark[0] = q
        return self.mark[1]


def _opening(raw: bytes, pos: int) -> int | None:
    """Where the next dataset's type line starts (after its opening ``-1`` line), or
    None at the end of the file.

    Raises
    ------
    ParseError
        For text outside a dataset, and a file that ends right after an opening ``-1``.
    """
    m = _DELIM.search(raw, pos)
    if m is None:
        rest = raw[pos:]
        if rest.strip():
            ln = _line_no(raw, pos + len(rest) - len(rest.lstrip()))
            raise ParseError(
                f"text after the last dataset at line {ln} ({_text(rest.strip()[:40])!r}"
                "...): every dataset must lie between two '    -1' lines; the file may be "
                "truncated or damaged"
            )
        return None
    junk = raw[pos : m.start()]
    if junk.strip():
        ln = _line_no(raw, pos + len(junk) - len(junk.lstrip()))
        raise ParseError(
            f"text outside a dataset at line {ln} ({_text(junk.strip()[:40])!r}): every "
            "dataset must lie between two '    -1' lines"
        )
    p = m.end() + 1  # after the newline of the opening "-1"
    if p > len(raw):
        raise ParseError(
            f"the file ends at its line {_line_no(raw, len(raw))} right after a '-1' line "
            "that opens a dataset; it is truncated"
        )
    return p


def _type_of(raw: bytes, p: int, type_line: bytes) -> tuple[int, bool, bytes]:
    """Dataset type, binary flag (``58b``) and the rest of the type line."""
    tm = _TYPE.match(type_line)
    if tm is None:
        raise ParseError(
            f"line {_line_no(raw, p)}: {_text(type_line[:40])!r} is not a dataset type "
            "number (the line after '    -1' names the dataset, e.g. '    58')"
        )
    return int(tm.group(1)), bool(tm.group(2)), tm.group(3)


def _binary_extent(
    raw: bytes, body_start: int, dtype: int, rest: bytes, type_line: bytes, where: str
) -> tuple[int, int, int]:
    """Start, end and byte order (1 little, 2 big endian) of a 58b dataset's binary data,
    from its type line and header (so that bytes looking like ``-1`` inside the data do
    not end the dataset)."""
    n = len(raw)
    if dtype != 58:
        raise ParseError(f"{where}: binary datasets other than 58b are not read")
    try:
        bo, fp, n_ascii, n_bytes = (int(x) for x in _text(rest).split()[:4])
    except ValueError:
        raise ParseError(f"{where}: damaged 58b header {_text(type_line)!r}") from None
    if bo not in (1, 2) or fp != 2 or not 0 < n_ascii < 100 or n_bytes < 0:
        raise ParseError(
            f"{where}: 58b header announces byte order {bo}, floating-point format "
            f"{fp}, {n_ascii} header lines; readable are byte order 1 (little "
            "endian) or 2 (big endian), format 2 (IEEE 754)"
        )
    q = body_start
    lines = []
    for _ in range(n_ascii):
        if q >= n:
            raise ParseError(
                f"{where}: the file ends at its line {_line_no(raw, n)} inside the "
                "header of this dataset; it is truncated"
            )
        hl, q = _next_line(raw, q)
        lines.append(_text(hl))
    if n_ascii < 11:
        raise ParseError(f"{where}: the 58b header has {n_ascii} of 11 lines")
    d58 = _header58(lines[:11], where)
    need = _values_count(d58) * (8 if d58["ord_data_type"] in (4, 6) else 4)
    # some writers announce the count of one part only: the header's count is what counts
    if q + need > n:
        raise ParseError(
            f"{where}: the binary data need {need} bytes but the file ends after "
            f"{n - q} of them (line {_line_no(raw, n)}, byte {n}); it is truncated"
        )
    return q, q + need, bo


def _closing(
    raw: bytes, body_start: int, extent: tuple[int, int, int] | None, where: str
) -> re.Match[bytes]:
    """The ``-1`` line that closes the dataset (after its binary data, if any)."""
    e = _CLOSE_BIN.match(raw, extent[1]) if extent else None
    if e is None:
        e = _DELIM.search(raw, extent[1] if extent else body_start)
    if e is None:
        raise ParseError(
            f"{where} has no closing '    -1' line: the file ends at its line "
            f"{_line_no(raw, len(raw))} (byte {len(raw)}) inside it; the file is truncated "
            "(nothing of it is read rather than losing this dataset silently)"
        )
    return e


def _header_of_58(raw: bytes, start: int, stop: int, where: str) -> tuple[dict[str, Any], int]:
    """Records 1-11 of a dataset 58 (up to ``stop``) and where its data start."""
    lines = []
    pos = start
    for _ in range(11):
        if pos >= stop:
            break
        hl, pos = _next_line(raw, pos)
        lines.append(_text(hl))
    if len(lines) < 11:
        raise ParseError(f"{where}: the header has {len(lines)} of 11 records")
    return _header58(lines, where), pos


def _binary_values(
    raw: bytes, extent: tuple[int, int, int], d: dict[str, Any], where: str
) -> np.ndarray:
    a, b, bo = extent
    want = _values_count(d)
    size = 8 if d["ord_data_type"] in (4, 6) else 4
    if want * size > b - a:
        raise ParseError(
            f"{where}: record 7 announces {d['num_pts']} values ({want * size} "
            f"bytes) but the binary data hold {b - a} bytes"
        )
    dt = np.dtype(("<" if bo == 1 else ">") + ("f8" if size == 8 else "f4"))
    return np.frombuffer(raw, dtype=dt, count=want, offset=a).astype(float)


def _nodes(body: list[bytes], dtype: int, where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node numbers, (definition, displacement) coordinate systems and coordinates of a
    dataset 15 (one line per node: I10 node, I10 def. CS, I10 disp. CS, I10 colour, 3E13.5)
    or 2411 (two lines per node: 4I10 node, export CS, disp. CS, colour; then 3D25.16)."""
    lines = [b for b in body if b.strip()]
    ids, cs, xyz = [], [], []
    step = 1 if dtype == 15 else 2
    if len(lines) % step:
        raise ParseError(f"{where}: a node of dataset 2411 needs two lines, the last has one")
    for k in range(0, len(lines), step):
        text = _text(b" ".join(lines[k : k + step])).replace("D", "E").replace("d", "e")
        f = text.split()
        if len(f) != 7:
            raise ParseError(
                f"{where}: node record {k // step + 1} has {len(f)} fields, expected 7 "
                "(node, two coordinate systems, colour, x, y, z)"
            )
        ids.append(_int(f[0], where))
        cs.append((_int(f[1], where), _int(f[2], where)))
        xyz.append([_float(v, where) for v in f[4:7]])
    return (
        np.asarray(ids, dtype=np.int64),
        np.asarray(cs, dtype=np.int64).reshape(-1, 2),
        np.asarray(xyz, dtype=float).reshape(-1, 3),
    )


def _units_164(body: list[bytes], where: str) -> dict[str, Any]:
    if len(body) < 3:
        raise ParseError(f"{where}: a units dataset needs 3 lines, it has {len(body)}")
    first = _text(body[0])
    nums = _text(b" ".join(body[1:])).replace("D", "E").replace("d", "e").split()
    try:
        factors = [float(v) for v in nums[:4]]
    except ValueError:
        raise ParseError(f"{where}: damaged unit factors {nums[:4]}") from None
    if len(factors) < 3:
        raise ParseError(f"{where}: needs length, force and temperature factors")
    return dict(
        units_code=_int(first[:10], where),
        units_description=first[10:30].strip(),
        temp_mode=_int(first[30:40], where) if first[30:40].strip() else 0,
        length=factors[0],
        force=factors[1],
        temp=factors[2],
        temp_offset=factors[3] if len(factors) > 3 else 0.0,
    )


def _contents(sets: list[dict[str, Any]]) -> dict[str, int]:
    """How many datasets of each kind (FRFs, spectra, ... by function type) the file holds."""
    counts: dict[str, int] = {}
    for s in sets:
        if s["type"] == 58:
            key = _FUNC_TYPES.get(s["func_type"], f"function type {s['func_type']}")
        else:
            key = f"dataset {s['type']}"
        counts[key] = counts.get(key, 0) + 1
    return counts


# -- CSV ---------------------------------------------------------------------------------
#: Most columns of a CSV file: 10,000 complex FRF columns (e.g. 1,666 output DOFs x 6
#: inputs). Each column becomes labels and Python objects in the server process: a file of
#: 100,000 columns (4 MB) took 17 s and 160 MB there.
MAX_COLUMNS = 20_000


def parse_csv(raw: bytes, max_values: int | None = None) -> tuple[dict[str, Any], list[np.ndarray]]:
    """The ``#`` header lines, the column-header row and the data rows of a CSV file.

    Returns
    -------
    meta : dict
        ``comments`` (the ``#`` lines without ``#``), ``header`` (the column-header row),
        ``header_line`` (its 1-based line number), ``delimiter``.
    arrays : [ndarray (n_rows, n_columns)]

    Raises
    ------
    ParseError
        For text that is not UTF-8, NUL bytes, no header row, rows of other lengths than
        the header and cells that are not numbers (naming line and column).
    """
    if raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]
    raw = _lf(raw)
    nul = raw.find(b"\x00")
    if nul >= 0:
        raise ParseError(f"contains NUL bytes (line {_line_no(raw, nul)}); not a text file")
    comments: list[str] = []
    pos = 0
    n = len(raw)
    header = None
    line = 0
    while pos < n:
        ln, nxt = _next_line(raw, pos)
        line += 1
        s = ln.strip()
        if s and not s.startswith(b"#"):
            header = ln
            break
        if s:
            comments.append(_utf8(s[1:], line).strip())
        pos = nxt
    if header is None:
        raise ParseError("has no header row (after the '#' lines)")
    htext = _utf8(header, line)
    delim = max((",", ";", "\t"), key=htext.count)
    if htext.count(delim) >= MAX_COLUMNS:
        raise ParseError(
            f"has {htext.count(delim) + 1:,} columns (line {line}), more than the "
            f"{MAX_COLUMNS:,} this tool reads from one CSV file"
        )
    cells = next(csv.reader([htext], delimiter=delim))
    ncol = len(cells)
    body_start = nxt
    body = memoryview(raw)[body_start:]
    try:
        bytes(body).decode("utf-8")
    except UnicodeDecodeError as e:
        raise ParseError(
            f"is not UTF-8 text (line {_line_no(raw, body_start + e.start)})"
        ) from None
    n_lines = raw.count(b"\n", body_start) + 1
    if max_values is not None and n_lines * ncol > max_values:
        raise ParseError(
            f"holds up to {n_lines} rows of {ncol} columns, more numbers than this tool "
            f"accepts from one file ({max_values})"
        )
    try:
        a = np.loadtxt(
            io.BytesIO(body),
            delimiter=delim,
            dtype=float,
            ndmin=2,
            comments=None,
            encoding="utf-8",
        )
    except ValueError:
        _csv_error(raw, body_start, line + 1, delim, ncol)
        raise ParseError("the data rows cannot be read as numbers") from None
    if a.size and a.shape[1] != ncol:
        raise ParseError(
            f"line {line + 1}: {a.shape[1]} fields, the header (line {line}) has {ncol}"
        )
    return (
        {
            "format": "csv",
            "comments": comments,
            "header": [c.strip() for c in cells],
            "header_line": line,
            "delimiter": delim,
        },
        [a.reshape(-1, ncol) if a.size else np.empty((0, ncol))],
    )


#: Most cells of a text table (a geometry table has a few hundred).
MAX_TABLE_CELLS = 200_000


def parse_table(
    raw: bytes, max_values: int | None = None
) -> tuple[dict[str, Any], list[np.ndarray]]:
    """A small CSV table of text cells: ``#`` comment lines, a header row, data rows.

    Returns
    -------
    meta : dict
        ``comments``, ``header``, ``rows`` (lists of stripped cells), ``lines`` (the
        1-based line number of each row), ``delimiter``.
    arrays : []

    Raises
    ------
    ParseError
        For text that is not UTF-8, NUL bytes, no header row, rows of other lengths than
        the header, more than :data:`MAX_TABLE_CELLS` cells.
    """
    if raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]
    raw = _lf(raw)
    nul = raw.find(b"\x00")
    if nul >= 0:
        raise ParseError(f"contains NUL bytes (line {_line_no(raw, nul)}); not a text file")
    text = _utf8(raw, 1)
    comments: list[str] = []
    header: list[str] | None = None
    delim = ","
    rows: list[list[str]] = []
    lines: list[int] = []
    cells = 0
    limit = MAX_TABLE_CELLS if max_values is None else min(MAX_TABLE_CELLS, max_values)
    for no, line in enumerate(text.split("\n"), start=1):
        s = line.strip()
        if not s:
            continue
        if header is None:
            if s.startswith("#"):
                comments.append(s[1:].strip())
                continue
            delim = max((",", ";", "\t"), key=line.count)
            header = [c.strip() for c in next(csv.reader([line], delimiter=delim))]
            continue
        if s.startswith("#"):
            continue
        row = [c.strip() for c in next(csv.reader([line], delimiter=delim))]
        if len(row) != len(header):
            raise ParseError(f"line {no}: {len(row)} fields, the header has {len(header)}")
        cells += len(row)
        if cells > limit:
            raise ParseError(f"holds more than {limit:,} cells, more than a table may have")
        rows.append(row)
        lines.append(no)
    if header is None:
        raise ParseError("has no header row (after the '#' lines)")
    meta = {
        "format": "table",
        "comments": comments,
        "header": header,
        "rows": rows,
        "lines": lines,
        "delimiter": delim,
    }
    return meta, []


def _lf(raw: bytes) -> bytes:
    """Lines of a file that ends them with CR alone (classic Mac OS, some exporters) as LF
    lines; other files as they are (CRLF lines are read as they are)."""
    if b"\r" in raw and b"\n" not in raw:
        return raw.replace(b"\r", b"\n")
    return raw


def _utf8(b: bytes, line: int) -> str:
    try:
        return b.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ParseError(f"is not UTF-8 text (line {line}, byte {e.start + 1})") from None


def _csv_error(raw: bytes, pos: int, line: int, delim: str, ncol: int) -> None:
    """Find the first bad row without holding the file as Python objects; raise."""
    d = delim.encode()
    n = len(raw)
    while pos < n:
        ln, nxt = _next_line(raw, pos)
        if ln.strip():
            cells = ln.split(d)
            if len(cells) != ncol:
                raise ParseError(f"line {line}: {len(cells)} fields, the header has {ncol}")
            for c, cell in enumerate(cells):
                try:
                    float(cell)
                except ValueError:
                    raise ParseError(
                        f"line {line} column {c + 1}: {_text(cell.strip()[:40])!r} is not a number"
                    ) from None
        pos, line = nxt, line + 1
