"""MATLAB MAT-files: v5 (scipy.io) and v7.3 (HDF5 via h5py), read in a sandbox.

Only plain variables are read: numeric and logical arrays, char arrays and cell
arrays of char. MATLAB objects, function handles, structs, sparse matrices,
``string`` objects and opaque classes are refused by class before any data is
loaded; nothing in a file is executed or unpickled. Parsing runs in a separate
process (:mod:`fbs_core.io._sandbox`), because both parsers can crash on damaged
files.

FRF variable layout (see ``docs/file-formats.md``):

``freq``
    Frequencies, a vector (Hz unless ``freq_unit`` says ``rad/s``).
``H``
    Complex FRF, ``n_freq x n_out x n_in`` (MATLAB drops trailing singleton
    dimensions; they are restored from the label counts).
``outputs``, ``inputs``
    DOF labels ``'node:dir'``, char matrix or cell array of char.
``quantity``
    ``'receptance'``, ``'mobility'`` or ``'accelerance'`` (optional when ``units``
    identifies it or ``quantity=`` is passed).
``units``, ``freq_unit``, ``metadata``
    Optional char: e.g. ``'m/(N s)'``; ``'Hz'``; a JSON text.
"""

from __future__ import annotations

import io
import json
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import DataFormatError
from ..frf import FRF
from ._sandbox import DEFAULT_TIMEOUT, parse_isolated
from .assembly import FileUnits, assemble, dof_labels, metadata_from_json
from .checks import Source, check_finite, frequency_from_units, kinds_text, sniff, units_line

__all__ = ["read_mat_vars", "read_mat", "write_mat", "frf_from_vars", "MatVars"]

#: Variables of a MAT-file: numeric arrays (MATLAB index order) or lists of strings.
MatVars = dict[str, "np.ndarray | list[str]"]

_NUMERIC = {
    "double",
    "single",
    "int8",
    "uint8",
    "int16",
    "uint16",
    "int32",
    "uint32",
    "int64",
    "uint64",
    "logical",
}
H_NAMES = ("H", "Y", "FRF", "frf")


def _attr_str(v: Any) -> str:
    if isinstance(v, list):
        v = "".join(str(x) for x in v)
    return str(v)


def _mat73_vars(meta: dict[str, Any], arrays: list[np.ndarray], name: str) -> MatVars:
    ds = meta["datasets"]
    out: MatVars = {}
    for path, attrs in meta["groups"].items():
        top = path.count("/") == 1 and not path.startswith("/#") and path != "/"
        if top:
            cls = _attr_str(attrs.get("MATLAB_class", "group"))
            raise DataFormatError(
                f"MATLAB file {name!r}: variable {path[1:]!r} is of class {cls!r}; only "
                "numeric, logical, char and cell arrays of char are read (structs, objects, "
                "strings and function handles are refused)"
            )
    for path, e in ds.items():
        if path.count("/") != 1 or path.startswith("/#"):
            continue
        var = path[1:]
        a = e["attrs"]
        cls = _attr_str(a.get("MATLAB_class", "?"))
        if "MATLAB_object_decode" in a or cls not in _NUMERIC | {"char", "cell"}:
            raise DataFormatError(
                f"MATLAB file {name!r}: variable {var!r} is of class {cls!r}; only numeric, "
                "logical, char and cell arrays of char are read (objects, function handles, "
                "structs, strings and opaque classes are refused)"
            )
        if np.any(np.asarray(a.get("MATLAB_empty", 0), dtype=float)):
            out[var] = [] if cls in ("char", "cell") else np.zeros((0,))
            continue
        if cls == "cell":
            refs = e.get("refs")
            if refs is None:
                raise DataFormatError(f"MATLAB file {name!r}: cell {var!r} is damaged")
            strs = []
            # C order of the h5py array is MATLAB's linear (column-major) order
            for k in range(len(refs)):
                t = ds.get(refs[k]) if refs[k] else None
                if t is None or _attr_str(t["attrs"].get("MATLAB_class", "")) != "char":
                    raise DataFormatError(
                        f"MATLAB file {name!r}: cell {var!r} may only hold character strings"
                    )
                strs.extend(_chars(arrays[t["array"]]) if "array" in t else [""])
            out[var] = strs
            continue
        if "array" not in e:
            raise DataFormatError(f"MATLAB file {name!r}: variable {var!r} is not an array")
        arr = arrays[e["array"]].T  # MATLAB is column-major: h5py sees reversed axes
        out[var] = _chars(arrays[e["array"]]) if cls == "char" else arr
    return out


def _chars(h5_codes: np.ndarray) -> list[str]:
    """MATLAB v7.3 char (uint16, h5py axes reversed) -> one string per row."""
    c = np.atleast_2d(np.asarray(h5_codes)).T  # rows x cols in MATLAB
    if c.dtype.kind not in "iu" or c.ndim != 2:
        raise DataFormatError("a char variable is not a 2-D array of character codes")
    return ["".join(chr(int(v)) for v in row if 0 < int(v) < 0x110000).rstrip() for row in c]


def read_mat_vars(
    src: Source, kind: str | None = None, *, timeout: float = DEFAULT_TIMEOUT
) -> MatVars:
    """Variables of a MAT-file (``kind`` ``"mat5"`` or ``"mat73"``; default what
    :func:`~.checks.sniff` finds in the content).

    Raises
    ------
    DataFormatError
        For damaged files and refused classes, naming the variable.
    """
    what = f"MATLAB file {src.name!r}"
    kind = kind or sniff(src.raw)
    if kind == "mat5":
        meta, arrays = parse_isolated("mat5", src.raw, what, timeout=timeout)
        return {
            k: (arrays[v["array"]] if "array" in v else list(v["strings"]))
            for k, v in meta["variables"].items()
        }
    if kind == "mat73":
        meta, arrays = parse_isolated("hdf5", src.raw, what, timeout=timeout)
        return _mat73_vars(meta, arrays, src.name)
    raise DataFormatError(f"{what} is neither a v5 nor a v7.3 MAT-file")


def _text(v: MatVars, key: str, name: str) -> str | None:
    if key not in v:
        return None
    s = v[key]
    if not isinstance(s, list):
        raise DataFormatError(f"MATLAB file {name!r}: variable {key!r} must be text")
    return " ".join(s).strip()


def _labels(v: MatVars, key: str, name: str) -> list[str]:
    if key not in v:
        raise DataFormatError(f"MATLAB file {name!r} lacks the variable {key!r} (DOF labels)")
    s = v[key]
    if not isinstance(s, list) or not s:
        raise DataFormatError(
            f"MATLAB file {name!r}: {key!r} must be a char matrix or cell array of labels "
            "like 'spindle:z'"
        )
    return s


def _vector(a: np.ndarray | list[str], key: str, name: str) -> np.ndarray:
    if isinstance(a, list):
        raise DataFormatError(f"MATLAB file {name!r}: {key!r} must be numeric, got text")
    a = np.asarray(a)
    if sum(n > 1 for n in a.shape) > 1:
        raise DataFormatError(f"MATLAB file {name!r}: {key!r} must be a vector, got {a.shape}")
    flat: np.ndarray = a.ravel()
    return flat


def _strip1(shape: Sequence[int]) -> tuple[int, ...]:
    s = list(shape)
    while len(s) > 1 and s[-1] == 1:
        s.pop()
    return tuple(s)


def frf_from_vars(
    v: MatVars,
    name: str,
    *,
    nodes: Mapping[Any, Any] | None = None,
    quantity: str | None = None,
) -> tuple[FRF, list[str], dict[str, Any]]:
    """Build the FRF from MAT-file variables in the documented layout."""
    if "freq" not in v:
        raise DataFormatError(
            f"MATLAB file {name!r} lacks the variable 'freq' (found: {', '.join(v) or 'none'})"
        )
    found = [k for k in H_NAMES if k in v]
    if len(found) != 1:
        raise DataFormatError(
            f"MATLAB file {name!r} must hold exactly one FRF variable named "
            f"{' or '.join(H_NAMES)}; found {found or 'none'} among {', '.join(v)}"
        )
    hk = found[0]
    f = _vector(v["freq"], "freq", name)
    check_finite(f, f"MATLAB file {name!r} variable 'freq'")
    if np.iscomplexobj(f):
        raise DataFormatError(f"MATLAB file {name!r}: 'freq' must be real")
    f = frequency_from_units(f.astype(float), _text(v, "freq_unit", name), repr(name))
    H = v[hk]
    if isinstance(H, list):
        raise DataFormatError(f"MATLAB file {name!r}: {hk!r} must be numeric, got text")
    H = np.asarray(H)
    check_finite(H, f"MATLAB file {name!r} variable {hk!r}")
    raw_o, raw_i = _labels(v, "outputs", name), _labels(v, "inputs", name)
    expected = (f.size, len(raw_o), len(raw_i))
    if _strip1(H.shape) != _strip1(expected):
        raise DataFormatError(
            f"MATLAB file {name!r}: {hk!r} has size {'x'.join(map(str, H.shape))}, expected "
            f"n_freq x n_out x n_in = {'x'.join(map(str, expected))} from 'freq', "
            "'outputs' and 'inputs'"
        )
    outs, so = dof_labels(raw_o, "output", nodes)
    ins, si = dof_labels(raw_i, "input", nodes)
    frf, notes = assemble(
        f,
        H.reshape(expected).astype(complex),
        outs,
        ins,
        where=repr(name),
        quantity=quantity,
        declared=_text(v, "quantity", name) or None,
        units=FileUnits(_text(v, "units", name)),
        kinds=_text(v, "kinds", name),
        signs=np.outer(so, si),
    )
    return frf, notes, metadata_from_json(_text(v, "metadata", name))


def read_mat(
    src: Source,
    kind: str | None = None,
    *,
    nodes: Mapping[Any, Any] | None = None,
    quantity: str | None = None,
    timeout: float = DEFAULT_TIMEOUT,
) -> tuple[FRF, list[str], dict[str, Any]]:
    """Read an FRF from a MAT-file in the documented layout (``kind`` as in
    :func:`read_mat_vars`)."""
    return frf_from_vars(
        read_mat_vars(src, kind, timeout=timeout), src.name, nodes=nodes, quantity=quantity
    )


# -- writing ---------------------------------------------------------------------------
def _mat_vars(frf: FRF, metadata: Mapping[str, Any] | None) -> dict[str, Any]:
    return {
        "freq": np.asarray(frf.freq, dtype=float),
        "H": np.asarray(frf.data),
        "outputs": list(frf.outputs),
        "inputs": list(frf.inputs),
        "quantity": frf.quantity,
        "units": units_line(frf),
        **({"kinds": kinds_text(frf.kinds)} if frf.kinds else {}),
        "freq_unit": "Hz",
        "metadata": json.dumps(dict(metadata or {}), default=str),
    }


def write_mat(frf: FRF, *, version: str = "5", metadata: Mapping[str, Any] | None = None) -> bytes:
    """An FRF as MAT-file content (``version`` ``"5"`` or ``"7.3"``), documented layout."""
    return write_mat_vars(_mat_vars(frf, metadata), version=version)


def write_mat_vars(variables: Mapping[str, Any], *, version: str = "5") -> bytes:
    """Write numeric arrays, strings and lists of strings as a MAT-file.

    Vectors are written as columns; strings as char rows; lists of strings as
    char matrices padded with blanks.
    """
    if version not in ("5", "7.3"):
        raise DataFormatError(f"unknown MAT-file version {version!r}; allowed: '5', '7.3'")
    if version == "5":
        import scipy.io

        out: dict[str, Any] = {}
        for k, val in variables.items():
            if isinstance(val, list):
                width = max((len(s) for s in val), default=0)
                out[k] = np.array([s.ljust(width) for s in val], dtype=f"<U{max(width, 1)}")
            else:
                out[k] = val
        b = io.BytesIO()
        scipy.io.savemat(b, out, do_compression=True, oned_as="column")
        return b.getvalue()
    return _write_mat73(variables)


def _write_mat73(variables: Mapping[str, Any]) -> bytes:
    import h5py

    b = io.BytesIO()
    with h5py.File(b, "w", userblock_size=512, libver="earliest") as h:
        for k, val in variables.items():
            if isinstance(val, str | list):
                rows = [val] if isinstance(val, str) else list(val)
                width = max((len(s) for s in rows), default=0)
                codes = np.array(
                    [[ord(c) for c in s.ljust(width)] for s in rows], dtype=np.uint16
                ).reshape(len(rows), width)
                d = h.create_dataset(k, data=codes.T)
                d.attrs["MATLAB_class"] = np.bytes_("char")
                d.attrs["MATLAB_int_decode"] = np.int32(2)
                continue
            a = np.asarray(val)
            if a.ndim == 1:
                a = a[:, None]  # column vector
            if np.iscomplexobj(a):
                ct = np.dtype([("real", "<f8"), ("imag", "<f8")])
                c = np.empty(a.shape, dtype=ct)
                c["real"], c["imag"] = a.real, a.imag
                a = c
                cls = "double"
            else:
                a = a.astype(float)
                cls = "double"
            d = h.create_dataset(k, data=a.T)
            d.attrs["MATLAB_class"] = np.bytes_(cls)
    raw = bytearray(b.getvalue())
    text = (
        f"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: "
        f"{time.strftime('%a %b %d %H:%M:%S %Y')} HDF5 schema 1.00 ."
    ).ljust(116)
    header = text.encode("ascii")[:116] + b" " * 8 + b"\x00\x02" + b"IM"
    raw[: len(header)] = header
    return bytes(raw)
