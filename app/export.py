"""CSV export of the data behind a view: a metadata header, then the plotted columns.

Format::

    # tire-fbs dashboard export (<view>)
    # harmonic: 1
    # ...
    freq_Hz,reference_dB,...
    12.5,-93.1,...

Header lines start with ``#`` (``numpy.loadtxt`` / ``pandas.read_csv(comment="#")`` skip
them). Complex columns are written as two columns ``<name>_re`` and ``<name>_im``, and a
header line states their unit. Numbers are written with 17 significant digits, so that they
read back exactly. A view's data over frequency along the harmonic's speed line get a
``speed_kmh`` column (:func:`export_columns`), and file names carry the date
(:func:`dated`).

The same views export as UFF dataset 58 (:func:`to_uff`): their case (harmonic, N,
residual compensation, coupling, DOF, models) always comes from the snapshot the result
was made of, never from the caller.
"""

from __future__ import annotations

import datetime as dt
import io
from collections.abc import Mapping
from typing import Any

import numpy as np

from fbs_core.io.csv import safe_text

#: The header line that states the unit of the complex columns.
COMPLEX_UNIT_KEY = "Re/Im columns"

__all__ = ["dated", "export_columns", "linear_unit", "read_csv", "to_csv", "to_uff"]


def to_csv(columns: Mapping[str, np.ndarray], meta: Mapping[str, object], view: str) -> str:
    """CSV text of equally long 1-D ``columns`` with a ``# key: value`` header.

    Raises
    ------
    ValueError
        If the columns are not 1-D of one length, or a header value contains a newline.
    """
    names, arrays = [], []
    n = None
    for name, col in columns.items():
        a = np.asarray(col)
        if a.ndim != 1:
            raise ValueError(f"column {name!r} must be 1-D, got shape {a.shape}")
        if n is None:
            n = a.size
        elif a.size != n:
            raise ValueError(f"column {name!r} has {a.size} rows, expected {n}")
        if np.iscomplexobj(a):
            names += [f"{name}_re", f"{name}_im"]
            arrays += [a.real, a.imag]
        else:
            names.append(name)
            arrays.append(a.astype(float))
    complex_names = [n[: -len("_re")] for n in names if n.endswith("_re")]
    if complex_names and COMPLEX_UNIT_KEY not in meta:
        unit = linear_unit(str(meta.get("unit", "")))
        meta = {
            **meta,
            COMPLEX_UNIT_KEY: f"{', '.join(f'{c}_re, {c}_im' for c in complex_names)}: real "
            f"and imaginary parts, in {unit or 'the SI unit of the quantity'}",
        }
    buf = io.StringIO()
    buf.write(f"# tire-fbs dashboard export ({view})\n")
    for key, value in meta.items():
        text = str(value)
        if "\n" in text or "\n" in str(key):
            raise ValueError(f"header entry {key!r} must be a single line")
        buf.write(safe_text(f"# {key}: {text}") + "\n")  # no formula cells (CSV injection)
    buf.write(",".join(names) + "\n")
    if arrays:
        np.savetxt(buf, np.column_stack(arrays), delimiter=",", fmt="%.17g")
    return buf.getvalue()


def read_csv(text: str) -> tuple[dict[str, str], dict[str, np.ndarray]]:
    """Parse :func:`to_csv` output back into ``(meta, columns)`` (used by the tests)."""
    meta: dict[str, str] = {}
    lines = text.splitlines()
    i = 0
    while i < len(lines) and lines[i].startswith("#"):
        body = lines[i][1:].strip()
        if ": " in body:
            k, v = body.split(": ", 1)
            meta[k] = v
        i += 1
    names = lines[i].split(",")
    rows = [list(map(float, ln.split(","))) for ln in lines[i + 1 :] if ln.strip()]
    data = np.array(rows, float).reshape(len(rows), len(names))
    return meta, {n: data[:, k] for k, n in enumerate(names)}


def linear_unit(unit: str) -> str:
    """The unit of the complex values behind a level unit: ``"dB re 1 (m/s)/m"`` ->
    ``"(m/s)/m"``, ``"Level (dB re 1 rad/(N s))"`` -> ``"rad/(N s)"``; a unit that is no
    level is returned as it is."""
    u = unit.strip()
    if u.startswith("Level (") and u.endswith(")"):
        u = u[len("Level (") : -1]
    return u[len("dB re 1 ") :] if u.startswith("dB re 1 ") else u


def dated(filename: str, when: dt.datetime | None = None) -> str:
    """``filename`` with the date of the export before its ending:
    ``bushing_response_h4_N60_z_6dof.csv`` -> ``..._6dof_2026-12-03.csv`` (after
    ``_upload``, as the report's names)."""
    day = (when or dt.datetime.now(dt.UTC)).strftime("%Y-%m-%d")
    stem, dot, ext = filename.rpartition(".")
    if not dot:
        return f"{filename}_{day}"
    return f"{stem}_{day}.{ext}"


def export_columns(result: Any) -> tuple[dict[str, np.ndarray], dict[str, object]]:
    """The columns and header of a published result as exported: a ``speed_kmh`` column
    after ``freq_Hz`` when the result is a function of frequency (the vehicle speed at which
    the snapshot's harmonic excites each line, v = 3.6 f lambda; thesis section 2.5)."""
    cols = dict(result.columns)
    meta = dict(result.meta)
    freq = cols.get("freq_Hz")
    s = result.snapshot
    along = (
        freq is not None
        and "speed_kmh" not in cols
        and s is not None
        and np.ndim(freq) == 1
        and np.size(freq) > 1
        and bool(np.all(np.diff(np.asarray(freq, float)) > 0))
    )
    if along:
        import fbs_core

        h = fbs_core.harmonic(s.harmonic)
        out: dict[str, np.ndarray] = {}
        for k, v in cols.items():
            out[k] = v
            if k == "freq_Hz":
                out["speed_kmh"] = np.asarray(h.speed_at(np.asarray(freq, float)), float)
        cols = out
        meta["speed_kmh"] = (
            f"vehicle speed at which harmonic {s.harmonic} (road wavelength {h.wavelength:g} m) "
            "excites the line: v = 3.6 f lambda"
        )
    return cols, meta


def _case(s: Any) -> dict[str, object]:
    """The case of a snapshot, recorded in every UFF export (ID lines 3-4, first)."""
    return {
        "h": s.harmonic,
        "N": s.n_modes,
        "residual": "yes" if s.residual else "no",
        "coupling": s.coupling,
        "dof": f"bushing:{s.dof}",
        "models": "reference" if s.models.is_reference else "upload",
    }


def to_uff(result: Any, meta: Mapping[str, object] | None = None) -> bytes:
    """A view's data over frequency as UFF dataset-58 records.

    The FRFs the result holds (``result.core``) are FRF records (function type 4, their
    nodes, directions and units; several FRFs, e.g. the N-mode response and the
    all-modes reference beside it, are function ids 1 and 2 of record 6, named in ID
    line 1; a reader takes function id 1); without FRFs, the
    view's complex columns over ``freq_Hz`` (or, for levels only such as the scatter
    band's, its real ones) as general function records. ID lines 3-4 hold the case
    of the snapshot the result was made of (harmonic, N, residual compensation, coupling,
    DOF, models) and then ``meta``, as whole ``key=value`` pairs; line 5 the node map.

    Raises
    ------
    ValueError
        For a result without its snapshot or without a function of frequency.
    """
    from fbs_core import FRF
    from fbs_core.io import export_result

    s = result.snapshot
    if s is None:
        raise ValueError("a UFF export needs the snapshot the result was made of")
    freq = result.columns.get("freq_Hz")
    if freq is None:
        raise ValueError(
            f"the view {result.meta.get('view', '?')!r} is no function of frequency; "
            "export it as CSV"
        )
    frfs: dict[str, Any] = {}
    arrays: dict[str, Any] = {}
    # the N-mode response first (function id 1: what a reader takes), the all-modes
    # reference beside it (function id 2), each a whole FRF record
    for name in sorted(result.core, key=lambda k: k != "truncated"):
        v = result.core[name]
        if isinstance(v, FRF):
            frfs[name] = v
    if not frfs:  # the complex curves, or (a band: levels only) the real ones
        curves = {
            k: np.asarray(v)
            for k, v in result.columns.items()
            if k not in ("freq_Hz", "speed_kmh") and np.shape(v) == np.shape(freq)
        }
        cx = {k: v for k, v in curves.items() if np.iscomplexobj(v)}
        arrays = {k: (("freq",), v) for k, v in (cx or curves).items()}
    if not frfs and not arrays:
        raise ValueError(
            f"the view {result.meta.get('view', '?')!r} holds no curve over frequency; "
            "export it as CSV"
        )
    data = {**frfs, **arrays, "coords": {"freq": np.asarray(freq, float)}}
    md = {**_case(s), **{k: v for k, v in (meta or {}).items() if k not in ("view",)}}
    return export_result(data, format="uff", metadata=md, round_abscissa=True)
