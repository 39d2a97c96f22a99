"""CSV export of the data behind a view: a metadata header, then the plotted columns.

Format::

    # tire-fbs dashboard export (<view>)
    # harmonic: 1
    # ...
    freq_Hz,reference_dB,...
    12.5,-93.1,...

Header lines start with ``#`` (``numpy.loadtxt`` / ``pandas.read_csv(comment="#")`` skip
them). Complex columns are written as two columns ``<name>_re`` and ``<name>_im``. Numbers
are written with 17 significant digits, so that they read back exactly.
"""

from __future__ import annotations

import io
from collections.abc import Mapping

import numpy as np

from fbs_core.io.csv import safe_text

__all__ = ["to_csv", "read_csv"]


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
