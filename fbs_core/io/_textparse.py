"""Parsers of the text formats (UFF, CSV) that run in the sandbox process.

This module imports nothing but the standard library and numpy, so that the sandbox
worker (:mod:`fbs_core.io._worker`, which never imports ``fbs_core``) loads it by
path. Both parsers are linear in the size of the file and never build one Python
object per number of the file's data: numbers are parsed by numpy from whole blocks.

* :func:`parse_uff` splits a Universal File into its datasets (a block between two
  ``-1`` lines; binary 58b blocks are skipped by their announced byte count, so bytes
  looking like ``-1`` inside them do not split them) and reads datasets 58 / 58b
  (header records 1-11 and the data), 164 (units) and 151 (header) completely; of
  other datasets only the type is kept. A file that ends inside a dataset is refused
  with the line where it ends.
* :func:`parse_csv` reads the ``#`` header lines and the column-header row as text
  and the data rows as one float array.

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

__all__ = ["ParseError", "parse_uff", "parse_csv"]


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
    pos = 0
    n = len(raw)
    empty = 0
    total = 0
    mark = [0, 1]  # a position and its line number: lines are counted once, forwards

    def line_at(q: int) -> int:
        if q < mark[0]:
            return _line_no(raw, q)
        mark[1] += raw.count(b"\n", mark[0], q)
        mark[0] = q
        return mark[1]

    while True:
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
            break
        junk = raw[pos : m.start()]
        if junk.strip():
            ln = _line_no(raw, pos + len(junk) - len(junk.lstrip()))
            raise ParseError(
                f"text outside a dataset at line {ln} ({_text(junk.strip()[:40])!r}): every "
                "dataset must lie between two '    -1' lines"
            )
        p = m.end() + 1  # after the newline of the opening "-1"
        if p > n:
            raise ParseError(
                f"the file ends at its line {_line_no(raw, n)} right after a '-1' line that "
                "opens a dataset; it is truncated"
            )
        type_line, after_type = _next_line(raw, p)
        if _DELIM.fullmatch(type_line):  # "-1" twice: an empty dataset
            empty += 1
            pos = after_type
            continue
        tm = _TYPE.match(type_line)
        if tm is None:
            raise ParseError(
                f"line {_line_no(raw, p)}: {_text(type_line[:40])!r} is not a dataset type "
                "number (the line after '    -1' names the dataset, e.g. '    58')"
            )
        dtype = int(tm.group(1))
        binary = bool(tm.group(2))
        k = len(sets) + 1
        line = line_at(p)
        where = f"dataset {k} (type {dtype}{'b' if binary else ''}, line {line})"
        body_start = after_type
        bin_range = None
        if binary:
            if dtype != 58:
                raise ParseError(f"{where}: binary datasets other than 58b are not read")
            f = _text(tm.group(3))
            try:
                bo, fp, n_ascii, n_bytes = (int(x) for x in f.split()[:4])
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
            size = 8 if d58["ord_data_type"] in (4, 6) else 4
            need = _values_count(d58) * size
            if need > n_bytes:
                n_bytes = need  # some writers announce the count of one part only
            if q + need > n:
                raise ParseError(
                    f"{where}: the binary data need {need} bytes but the file ends after "
                    f"{n - q} of them (line {_line_no(raw, n)}, byte {n}); it is truncated"
                )
            bin_range = (q, q + need, bo)
            search_from = q + need
        else:
            search_from = body_start
        e = _CLOSE_BIN.match(raw, search_from) if binary else None
        if e is None:
            e = _DELIM.search(raw, search_from)
        if e is None:
            raise ParseError(
                f"{where} has no closing '    -1' line: the file ends at its line "
                f"{_line_no(raw, n)} (byte {n}) inside it; the file is truncated (nothing of "
                "it is read rather than losing this dataset silently)"
            )
        entry: dict[str, Any] = {"type": dtype, "binary": int(binary), "line": line}
        if dtype == 58:
            hdr_end = body_start
            lines = []
            for _ in range(11):
                if hdr_end >= (bin_range[0] if bin_range else e.start()):
                    break
                hl, hdr_end = _next_line(raw, hdr_end)
                lines.append(_text(hl))
            if len(lines) < 11:
                raise ParseError(f"{where}: the header has {len(lines)} of 11 records")
            d = _header58(lines, where)
            want = _values_count(d)
            total += want
            if max_values is not None and total > max_values:
                raise ParseError(
                    f"the datasets 58 hold more than {max_values} numbers, more than this "
                    "tool accepts from one file"
                )
            if bin_range:
                a, b, bo = bin_range
                size = 8 if d["ord_data_type"] in (4, 6) else 4
                if want * size > b - a:
                    raise ParseError(
                        f"{where}: record 7 announces {d['num_pts']} values ({want * size} "
                        f"bytes) but the binary data hold {b - a} bytes"
                    )
                dt = np.dtype(("<" if bo == 1 else ">") + ("f8" if size == 8 else "f4"))
                vals = np.frombuffer(raw, dtype=dt, count=want, offset=a).astype(float)
            else:
                vals = _ascii_values(raw[hdr_end : e.start()], d, where, line_at(hdr_end))
            x, y = _split58(vals, d)
            d["data"] = len(arrays)
            arrays.append(y)
            if d["abscissa_spacing"] == 0:  # even spacing: abscissa_min + k abscissa_inc
                d["x"] = len(arrays)
                arrays.append(x)
            entry.update(d)
        elif dtype == 164:
            body = raw[body_start : e.start()].splitlines()
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
            entry.update(
                units_code=_int(first[:10], where),
                units_description=first[10:30].strip(),
                temp_mode=_int(first[30:40], where) if first[30:40].strip() else 0,
                length=factors[0],
                force=factors[1],
                temp=factors[2],
                temp_offset=factors[3] if len(factors) > 3 else 0.0,
            )
        elif dtype == 151:
            body = raw[body_start : e.start()].splitlines()
            entry.update({f"line{i + 1}": _text(b).rstrip()[:80] for i, b in enumerate(body[:7])})
        sets.append(entry)
        pos = e.end()
    counts: dict[str, int] = {}
    for s in sets:
        if s["type"] == 58:
            key = _FUNC_TYPES.get(s["func_type"], f"function type {s['func_type']}")
        else:
            key = f"dataset {s['type']}"
        counts[key] = counts.get(key, 0) + 1
    return {"format": "uff", "sets": sets, "empty": empty, "contents": counts}, arrays


# -- CSV ---------------------------------------------------------------------------------
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
