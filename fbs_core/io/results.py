"""Results as "arrays with axes + metadata", and their export to CSV, UFF 58 and HDF5.

Any result object is flattened into a :class:`ResultData`: FRFs, named arrays
with axis names, coordinates of the axes, and a metadata dictionary (settings
such as harmonic, number of modes, noise, seed, plus the fbs_core version and
the time of export), so that an exported result can be traced and reproduced.

:func:`as_result_data` understands an :class:`~fbs_core.FRF`, a mapping, a
:class:`ResultData` and frozen dataclasses such as the study results
(``TruncationMap``, ``ScatterBand``, ...): array fields become arrays, scalar
and text fields metadata, nested dataclasses are flattened with a ``/`` prefix.
The axis names of an array are taken from the class docstring's numpydoc
``shape (n_N, n_f, n_dof)`` entries, and an axis is labelled by the field
documented with that single symbol (``freq : ndarray, shape (n_f,)``).
"""

from __future__ import annotations

import dataclasses
import re
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..dofs import parse_label
from ..errors import DataFormatError, DOFError
from ..frf import FRF

__all__ = [
    "ResultData",
    "as_result_data",
    "result_to_csv",
    "result_to_uff",
    "FREQ_DIMS",
]

#: Axis names treated as a frequency axis in Hz (abscissa of UFF records).
FREQ_DIMS = ("freq", "frequency", "centres", "centers")


@dataclass(frozen=True)
class ResultData:
    """Arrays with named axes, their coordinates, FRFs and metadata.

    Attributes
    ----------
    kind : str
        What the result is (e.g. the class name ``"TruncationMap"``).
    arrays : dict of str to (tuple of str, ndarray)
        Name -> (axis names, values).
    coords : dict of str to ndarray
        Axis name -> coordinate values (numbers or str).
    frfs : dict of str to FRF
    metadata : dict
        JSON-compatible settings.
    """

    kind: str
    arrays: dict[str, tuple[tuple[str, ...], np.ndarray]] = field(default_factory=dict)
    coords: dict[str, np.ndarray] = field(default_factory=dict)
    frfs: dict[str, FRF] = field(default_factory=dict)
    metadata: dict[str, Any] = field(default_factory=dict)


_SHAPE_DOC = re.compile(r"^\s*([\w ,]+?)\s*:[^\n]*?\b(?:shape|length)\s*\(?([\w ,]*)\)?", re.M)


def _doc_dims(cls: type) -> dict[str, tuple[str, ...]]:
    dims: dict[str, tuple[str, ...]] = {}
    for m in _SHAPE_DOC.finditer(cls.__doc__ or ""):
        syms = tuple(s.strip() for s in m.group(2).split(",") if s.strip())
        for nm in m.group(1).split(","):
            dims[nm.strip()] = syms
    return dims


def _is_numeric(v: object) -> bool:
    return isinstance(v, np.ndarray) and v.dtype.kind in "biufc"


def _labels(v: object) -> bool:
    return isinstance(v, tuple | list) and bool(v) and all(isinstance(x, str) for x in v)


def _scalar(v: object) -> bool:
    return isinstance(v, bool | int | float | str | np.number) or v is None


def _jsonable(v: Any) -> Any:
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, tuple | list):
        return [_jsonable(x) for x in v]
    if isinstance(v, Mapping):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, np.ndarray) and v.size <= 64 and v.dtype.kind in "biuf":
        return v.tolist()
    return v if _scalar(v) else str(v)


def _flatten(
    obj: Any, prefix: str, out: ResultData, inherited: dict[str, str] | None = None
) -> None:
    if isinstance(obj, FRF):
        out.frfs[prefix.rstrip("/") or "frf"] = obj
        return
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        items = {
            f.name: getattr(obj, f.name)
            for f in dataclasses.fields(obj)
            if not f.name.startswith("_")
        }
        docdims = _doc_dims(type(obj))
    elif isinstance(obj, Mapping):
        items = dict(obj)
        docdims = {}
        if isinstance(items.get("coords"), Mapping):
            for k, v in items.pop("coords").items():
                out.coords[prefix + str(k)] = np.asarray(v)
        if isinstance(items.get("metadata"), Mapping):
            out.metadata.update(_jsonable(items.pop("metadata")))
    else:
        raise DataFormatError(
            f"cannot export a {type(obj).__name__}: expected an FRF, a mapping of arrays, a "
            "ResultData or a dataclass of arrays"
        )
    # coordinates: 1-D fields documented with a single symbol label that axis; nested
    # results see the axes of their parent (ScatterBand.convergence shares n_f, n_dof)
    local: dict[str, str] = {}
    for k, syms in docdims.items():
        if (
            len(syms) == 1
            and k in items
            and (_labels(items[k]) or (isinstance(items[k], np.ndarray) and items[k].ndim == 1))
        ):
            local.setdefault(syms[0], prefix + k)  # the first documented field labels it
    # an undocumented tuple of numbers or labels ahead of that field labels an axis when
    # its length fits exactly one symbol (SuggestedModes.harmonics for n_h)
    order = list(items)
    sizes: dict[str, set[int]] = {}
    for k, syms in docdims.items():
        v = items.get(k)
        if isinstance(v, np.ndarray) and v.ndim == len(syms):
            for sym, n in zip(syms, v.shape, strict=True):
                sizes.setdefault(sym, set()).add(n)
    for k, v in items.items():
        if (
            k in docdims
            or not isinstance(v, tuple | list)
            or not v
            or not all(isinstance(x, int | float | str | np.number) for x in v)
        ):
            continue
        fits = [sym for sym, n in sizes.items() if n == {len(v)}]
        if len(fits) == 1 and (
            fits[0] not in local or order.index(k) < order.index(local[fits[0]][len(prefix) :])
        ):
            local[fits[0]] = prefix + k
            out.coords[prefix + k] = np.asarray(v)
    axis_coord = {**(inherited or {}), **local}
    for k, v in items.items():
        key = prefix + str(k)
        if key in out.coords and key in axis_coord.values():
            continue
        if isinstance(v, FRF):
            out.frfs[key] = v
        elif (
            isinstance(v, tuple | list)
            and v
            and all(
                isinstance(x, FRF) or (dataclasses.is_dataclass(x) and not isinstance(x, type))
                for x in v
            )
        ):
            for i, x in enumerate(v):
                _flatten(x, f"{key}/{i}/", out, axis_coord)
        elif isinstance(v, tuple) and len(v) == 2 and _labels(v[0]) and hasattr(v[1], "shape"):
            out.arrays[key] = (tuple(prefix + d for d in v[0]), np.asarray(v[1]))
        elif _labels(v):
            out.coords[key] = np.asarray(v, dtype=str)
        elif isinstance(v, np.ndarray) and v.ndim >= 1 and (_is_numeric(v) or v.dtype.kind == "U"):
            syms = docdims.get(k, ())
            if len(syms) == v.ndim:
                dims = tuple(
                    f"{key}_dim{i}" if s.isdigit() else axis_coord.get(s, prefix + s)
                    for i, s in enumerate(syms)
                )
            else:
                dims = tuple(f"{key}_dim{d}" for d in range(v.ndim))
            if v.ndim == 1 and dims[0] == key:
                out.coords[key] = v
            else:
                out.arrays[key] = (dims, v)
        elif (dataclasses.is_dataclass(v) and not isinstance(v, type)) or (
            isinstance(v, Mapping) and not all(_scalar(x) for x in v.values())
        ):
            _flatten(v, key + "/", out, axis_coord)
        elif _scalar(v) or isinstance(v, Mapping | tuple | list | np.ndarray):
            out.metadata[key] = _jsonable(v)
    for name, (dims, v) in out.arrays.items():
        for d, n in zip(dims, v.shape, strict=True):
            c = out.coords.get(d)
            if c is not None and len(c) != n:
                raise DataFormatError(
                    f"array {name!r} has {n} entries along {d!r} but the coordinate has {len(c)}"
                )


def as_result_data(
    obj: Any, metadata: Mapping[str, Any] | None = None, kind: str | None = None
) -> ResultData:
    """Flatten a result object into :class:`ResultData`, adding traceability metadata.

    Parameters
    ----------
    obj : FRF, Mapping, ResultData or dataclass
        The result. A mapping maps names to arrays, ``(dims, array)`` pairs or FRFs,
        with optional ``"coords"`` and ``"metadata"`` entries.
    metadata : mapping, optional
        Settings to record (harmonic, N, noise, seed, ...); they override fields.
    kind : str, optional
        Result type name; default the class name.

    Returns
    -------
    ResultData
        Its metadata always holds ``fbs_core_version``, ``exported`` (UTC) and ``kind``.

    Raises
    ------
    DataFormatError
        For objects that cannot be flattened or arrays that disagree with their axes.
    """
    from .. import __version__

    if isinstance(obj, ResultData):
        out = ResultData(
            obj.kind, dict(obj.arrays), dict(obj.coords), dict(obj.frfs), dict(obj.metadata)
        )
    else:
        out = ResultData(kind or type(obj).__name__)
        _flatten(obj, "", out)
    out.metadata.update(_jsonable(dict(metadata or {})))
    out.metadata.setdefault("kind", kind or out.kind)
    out.metadata["fbs_core_version"] = __version__
    out.metadata["exported"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    if not (out.arrays or out.frfs):
        raise DataFormatError(f"the {out.kind} holds no arrays or FRFs to export")
    return out


def _long_table(
    name: str, dims: Sequence[str], values: Any, coords: Mapping[str, np.ndarray]
) -> tuple[str, list[str], list[list[Any]]]:
    v = np.asarray(values)
    cols = list(dims) + (["re", "im"] if np.iscomplexobj(v) else ["value"])
    axes = [coords.get(d, np.arange(n)) for d, n in zip(dims, v.shape, strict=True)]
    idx = np.indices(v.shape).reshape(v.ndim, -1).T
    rows = []
    for ix, x in zip(idx, v.ravel(), strict=True):
        row = [
            axes[k][i].item() if hasattr(axes[k][i], "item") else axes[k][i]
            for k, i in enumerate(ix)
        ]
        row += [float(x.real), float(x.imag)] if np.iscomplexobj(v) else [x.item()]
        rows.append(row)
    return name, cols, rows


def result_to_csv(res: ResultData) -> bytes:
    """One CSV text: ``# key: value`` metadata lines, then one table per FRF and array.

    FRFs use the FRF layout of :mod:`fbs_core.io.csv`; arrays the long format (one
    row per element: the coordinates of its axes, then ``value`` or ``re``, ``im``).
    """
    import csv as _csv
    import io

    from .csv import _header, safe_cell, write_csv

    out = io.StringIO()
    out.write("\n".join(_header(res.metadata, res.kind)) + "\n")
    for name, frf in res.frfs.items():
        out.write(f"\n# table: {name}\n")
        body = write_csv(frf).decode().splitlines()
        out.write(
            "\n".join(
                ln
                for ln in body
                if not ln.startswith("# tire-fbs") and not ln.startswith("# fbs_core_version")
            )
            + "\n"
        )
    for name, (dims, values) in res.arrays.items():
        t, cols, rows = _long_table(name, dims, values, res.coords)
        out.write(f"\n# table: {t}\n")
        w = _csv.writer(out, lineterminator="\n")
        w.writerow(cols)
        for r in rows:
            w.writerow(
                [
                    repr(x) if isinstance(x, float) else safe_cell(x) if isinstance(x, str) else x
                    for x in r
                ]
            )
    return out.getvalue().encode()


def result_to_uff(
    res: ResultData, *, nodes: Mapping[Any, Any] | None = None, round_abscissa: bool = False
) -> bytes:
    """The functions of frequency in a result as UFF dataset-58 records.

    FRFs are written as FRF records (function type 4; several FRFs get function
    identification numbers 1, 2, ... in record 6, so FRFs of the same output/input pair
    are each whole FRF records, told apart by it). Every other array with a
    frequency axis (:data:`FREQ_DIMS`) is written slice by slice as general functions
    (type 0): ID line 1 names the array and the slice, e.g. ``upper [dofs=bushing:z]``;
    when a slice has a DOF label it is the record's response DOF. ID lines 2-4 hold the
    producer, the date and the metadata (whole ``key=value`` pairs), line 5 the node map
    of the file (one numbering for all records). Arrays without a frequency axis cannot
    be carried by dataset 58 and are listed in ID line 4 of the first record.

    Raises
    ------
    DataFormatError
        When nothing in the result is a function of frequency.
    """
    from .uff import (
        DIR_CODES,
        _abscissa,
        _ent,
        _node_numbers,
        frf_records,
        id_lines,
        node_map_line,
        pack_items,
        write_uff_records,
    )

    md = {k: v for k, v in res.metadata.items() if _scalar(v)}
    ids = id_lines(md)
    # one numbering of the nodes for the whole file, written in every record's ID line 5
    labels = [lab for frf in res.frfs.values() for lab in (*frf.outputs, *frf.inputs)]
    for dims, _v in res.arrays.values():
        for d in dims:
            for val in res.coords.get(d, ()):
                if isinstance(val, str | np.str_):
                    try:
                        parse_label(str(val))
                        labels.append(str(val))
                    except DOFError:
                        pass
    numbers = _node_numbers(labels, nodes)
    nodes = {n: name for name, n in numbers.items()}
    id5 = node_map_line(numbers)
    recs = []
    # several FRFs: function id 1, 2, ... each (FRF records of the same pairs told apart)
    fid = len(res.frfs) > 1
    for k, (key, frf) in enumerate(res.frfs.items()):
        recs += frf_records(
            frf, nodes=nodes, id_lines=ids, round_abscissa=round_abscissa, name=key,
            function_id=k + 1 if fid else 0,
        )  # fmt: skip
    skipped = []
    for name, (dims, values) in res.arrays.items():
        v = np.asarray(values)
        fd = [
            k for k, d in enumerate(dims) if d.rsplit("/", 1)[-1] in FREQ_DIMS and d in res.coords
        ]
        if not fd or v.dtype.kind not in "biufc":
            skipped.append(name)
            continue
        k = fd[0]
        x = np.asarray(res.coords[dims[k]], dtype=float)
        even = _abscissa(x, round_abscissa)
        moved = np.moveaxis(v, k, -1)
        other = [d for j, d in enumerate(dims) if j != k]
        for ix in np.ndindex(moved.shape[:-1]):
            parts, label = [], None
            for d, i in zip(other, ix, strict=True):
                c = res.coords.get(d)
                val = c[i] if c is not None else i
                parts.append(f"{d.rsplit('/', 1)[-1]}={val}")
                if isinstance(val, str | np.str_):
                    try:
                        parse_label(str(val))
                        label = str(val)
                    except DOFError:
                        pass
            node, code, ent = 0, 0, "NONE"
            if label:
                nn, dr = parse_label(label)
                node = _node_numbers([label], nodes)[nn]
                code, ent = (DIR_CODES.get(dr, 0) if dr is not None else 0), _ent(nn)
            y = moved[ix]
            recs.append(
                dict(
                    func_type=0,
                    ver_num=0,
                    load_case_id=0,
                    id1=f"{name} [{', '.join(parts)}]"[:80],
                    id2=ids[0][:80],
                    id3=ids[1][:80],
                    id4=ids[2][:80],
                    id5=id5,
                    rsp_node=node,
                    rsp_dir=code,
                    rsp_ent_name=ent,
                    ref_node=0,
                    ref_dir=0,
                    ref_ent_name="NONE",
                    data=np.asarray(y, dtype=complex if np.iscomplexobj(y) else float),
                    x=x,
                    abscissa_spacing=even,
                    abscissa_spec_data_type=18,
                    abscissa_axis_units_lab="Hz",
                    ordinate_spec_data_type=0,
                    orddenom_spec_data_type=0,
                    z_axis_spec_data_type=0,
                )
            )
    if not recs:
        raise DataFormatError(
            f"the {res.kind} has no function of frequency; UFF 58 cannot carry it "
            "(export as CSV or HDF5)"
        )
    if skipped:  # said in ID line 4 of the first record (line 5 is the node map)
        recs[0]["id4"] = pack_items(["not in this file: " + ", ".join(skipped)], lines=1)[0][0]
    return write_uff_records(recs)
