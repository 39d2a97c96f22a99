"""HDF5: FRFs and results with metadata, in a documented layout.

Layout (``docs/file-formats.md``)::

    /                     attrs: format = "tire-fbs", format_version = 1,
                                 fbs_core_version, created (UTC), metadata (JSON text)
    /frf/freq             (n_freq,) float64, Hz
    /frf/data             (n_freq, n_out, n_in) complex128
    /frf                  attrs: quantity, units, outputs, inputs (arrays of str)
    /frfs/<name>/...      further FRFs of a result, same layout as /frf
    /arrays/<path>        result arrays; attr dims (axis names)
    /coords/<dim>         coordinate values of an axis (numbers or str)

Reading goes through the sandboxed parser (:mod:`fbs_core.io._sandbox`) and never
follows soft or external links nor reads data stored in other files.
"""

from __future__ import annotations

import io
import json
import os
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import DataFormatError
from ..frf import FRF
from ._sandbox import DEFAULT_TIMEOUT, parse_isolated
from .assembly import FileUnits, assemble, dof_labels, metadata_from_json
from .checks import Source, check_finite, frequency_from_units, kinds_text, units_line
from .results import ResultData

if TYPE_CHECKING:
    from ..direct import SecondOrderSystem

__all__ = [
    "read_hdf5",
    "read_hdf5_result",
    "result_to_hdf5",
    "write_hdf5",
    "write_hdf5_result",
    "write_model_hdf5",
    "root_attrs",
]

FORMAT_VERSION = 1


def root_attrs(metadata: Mapping[str, Any] | None, kind: str) -> dict[str, Any]:
    """Attributes every file written here carries, for traceability."""
    from .. import __version__

    md = dict(metadata or {})
    return {
        "format": "tire-fbs",
        "format_version": FORMAT_VERSION,
        "content": kind,
        "fbs_core_version": __version__,
        "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "metadata": json.dumps(md, default=str, sort_keys=True),
    }


def _put_frf(g: Any, frf: FRF) -> None:
    import h5py

    g.create_dataset("freq", data=np.asarray(frf.freq, dtype=float))
    g["freq"].attrs["unit"] = "Hz"
    g.create_dataset("data", data=np.asarray(frf.data, dtype=complex))
    g.attrs["quantity"] = frf.quantity
    g.attrs["units"] = units_line(frf)
    if frf.kinds:
        g.attrs["kinds"] = kinds_text(frf.kinds)
    s = h5py.string_dtype()
    g.attrs.create("outputs", np.array(frf.outputs, dtype=object), dtype=s)
    g.attrs.create("inputs", np.array(frf.inputs, dtype=object), dtype=s)


def _set_attrs(obj: Any, attrs: Mapping[str, Any]) -> None:
    for k, v in attrs.items():
        if isinstance(v, bool | int | float | str | np.number):
            obj.attrs[k] = v


def write_hdf5(frf: FRF, *, metadata: Mapping[str, Any] | None = None) -> bytes:
    """An FRF as HDF5 content in the documented layout (group ``/frf``)."""
    import h5py

    b = io.BytesIO()
    with h5py.File(b, "w") as h:
        _set_attrs(h, root_attrs(metadata, "FRF"))
        _put_frf(h.create_group("frf"), frf)
    return b.getvalue()


def write_model_hdf5(
    path: str | os.PathLike[str],
    frf: FRF,
    metadata: Mapping[str, Any],
    model: str,
    system: SecondOrderSystem,
    matrices: Sequence[str],
) -> None:
    """Write a shipped model's file: its FRF, what model it is, and its FE system.

    The FRF in the documented layout (:func:`write_hdf5`), so that :func:`read_hdf5` reads
    it like any user's FRF; the root attribute ``model``, which
    :func:`fbs_core.frf_model.read_model_frf` checks; and ``/system``: the attribute
    ``dofs`` (the DOF labels) and one group per name of ``matrices`` (``"M"``, ``"K"``,
    ``"C"``) holding that matrix in CSR form (``data``, ``indices``, ``indptr``; attribute
    ``shape``). The caller adds the model's own groups (parameters, modes) afterwards.

    Parameters
    ----------
    path : str or pathlib.Path
        The file to write (replaced).
    frf : FRF
        The model's FRF, shape (n_freq, n_out, n_in).
    metadata : mapping
        The root attribute ``metadata`` (JSON): what the model is, its axes, its script.
    model : str
        The root attribute ``model``, e.g. ``"reference chassis"``.
    system : SecondOrderSystem
        The model's FE system (sparse matrices).
    matrices : sequence of str
        The names of the matrices of ``system`` to store.
    """
    import h5py

    Path(path).write_bytes(write_hdf5(frf, metadata=metadata))
    with h5py.File(path, "a") as h:
        h.attrs["model"] = model
        g = h.create_group("system")
        g.attrs.create("dofs", np.array(system.dofs, dtype=object), dtype=h5py.string_dtype())
        for name in matrices:
            a = getattr(system, name).tocsr()
            sub = g.create_group(name)
            sub["data"], sub["indices"], sub["indptr"] = a.data, a.indices, a.indptr
            sub.attrs["shape"] = a.shape


def write_hdf5_result(result: ResultData, metadata: Mapping[str, Any]) -> bytes:
    """A :class:`~fbs_core.io.results.ResultData` as HDF5 content."""
    import h5py

    b = io.BytesIO()
    s = h5py.string_dtype()
    with h5py.File(b, "w") as h:
        _set_attrs(h, root_attrs(metadata, result.kind))
        for k, v in metadata.items():
            if isinstance(v, bool | int | float | str) and k not in h.attrs:
                h.attrs[k] = v
        for name, frf in result.frfs.items():
            _put_frf(h.require_group("frfs").create_group(name), frf)
        for dim, values in result.coords.items():
            v = np.asarray(values)
            if v.dtype.kind == "U":
                h.require_group("coords").create_dataset(dim, data=v.astype(object), dtype=s)
            else:
                h.require_group("coords").create_dataset(dim, data=v)
        for name, (dims, values) in result.arrays.items():
            v = np.asarray(values)
            if v.dtype.kind == "U":
                d = h.require_group("arrays").create_dataset(name, data=v.astype(object), dtype=s)
            else:
                d = h.require_group("arrays").create_dataset(name, data=v)
            d.attrs.create("dims", np.array(dims, dtype=object), dtype=s)
    return b.getvalue()


def _strings(v: Any, what: str) -> list[str]:
    if isinstance(v, str):
        return [v]
    if isinstance(v, list) and all(isinstance(x, str) for x in v):
        return v
    raise DataFormatError(f"{what} must be a list of DOF labels")


def read_hdf5(
    src: Source,
    *,
    nodes: Mapping[Any, Any] | None = None,
    quantity: str | None = None,
    name: str | None = None,
    timeout: float = DEFAULT_TIMEOUT,
) -> tuple[FRF, list[str], dict[str, Any]]:
    """Read an FRF group (``/frf``, ``/frfs/<name>`` or ``name``) from HDF5 content.

    Raises
    ------
    DataFormatError, DOFError, QuantityError, FrequencyGridError
    """
    what = f"HDF5 file {src.name!r}"
    meta, arrays = parse_isolated("hdf5", src.raw, what, timeout=timeout)
    ds, groups = meta["datasets"], meta["groups"]
    cands = [g for g in groups if f"{g.rstrip('/')}/freq" in ds and f"{g.rstrip('/')}/data" in ds]
    if name is not None:
        g = "/" + name.strip("/")
        if g not in cands and f"/frfs{g}" in cands:
            g = f"/frfs{g}"
        if g not in cands:
            raise DataFormatError(
                f"{what} has no FRF group {name!r}; FRF groups: {', '.join(cands) or 'none'}"
            )
    elif "/frf" in cands:
        g = "/frf"
    elif len(cands) == 1:
        g = cands[0]
    else:
        raise DataFormatError(
            f"{what}: "
            + (
                f"several FRF groups ({', '.join(cands)}); pass name=..."
                if cands
                else "no FRF group (a group with datasets 'freq' and 'data')"
            )
        )
    base = g.rstrip("/")
    attrs = groups[g]
    fe, de = ds[f"{base}/freq"], ds[f"{base}/data"]
    if "array" not in fe or "array" not in de:
        raise DataFormatError(f"{what}: {base}/freq and {base}/data must be numeric")
    freq = np.asarray(arrays[fe["array"]])
    data = np.asarray(arrays[de["array"]])
    check_finite(freq, f"{what} {base}/freq")
    check_finite(data, f"{what} {base}/data")
    if freq.ndim != 1 or np.iscomplexobj(freq):
        raise DataFormatError(f"{what}: {base}/freq must be a real vector, got {freq.shape}")
    freq = frequency_from_units(freq, fe["attrs"].get("unit"), what)

    def labels(key: str) -> list[str]:
        if key in attrs:
            return _strings(attrs[key], f"{what} {base} attribute {key!r}")
        e = ds.get(f"{base}/{key}")
        if e and "strings" in e:
            strings: list[str] = e["strings"]  # the sandbox's parsed text
            return strings
        raise DataFormatError(f"{what}: {base} lacks the DOF labels {key!r}")

    raw_o, raw_i = labels("outputs"), labels("inputs")
    expected = (freq.size, len(raw_o), len(raw_i))
    if data.shape != expected:
        raise DataFormatError(
            f"{what}: {base}/data has shape {data.shape}, expected (n_freq, n_out, n_in) = "
            f"{expected} from freq, outputs and inputs"
        )
    outs, so = dof_labels(raw_o, "output", nodes)
    ins, si = dof_labels(raw_i, "input", nodes)

    def text(key: str) -> str | None:
        value = attrs.get(key)
        return value if isinstance(value, str) else None

    frf, notes = assemble(
        freq,
        data,
        outs,
        ins,
        where=what,
        quantity=quantity,
        declared=text("quantity") or None,
        units=FileUnits(text("units")),
        kinds=attrs.get("kinds"),
        signs=np.outer(so, si),
    )
    root = groups.get("/", {})
    md = metadata_from_json(root.get("metadata"))
    for k in ("fbs_core_version", "created"):
        if k in root:
            md.setdefault(k, root[k])
    return frf, notes, md


def read_hdf5_result(src: Source, *, timeout: float = DEFAULT_TIMEOUT) -> ResultData:
    """Read a result written by :func:`write_hdf5_result` back as ``ResultData``.

    Raises
    ------
    DataFormatError
        For files of another layout or damaged ones.
    """
    what = f"HDF5 file {src.name!r}"
    meta, arrays = parse_isolated("hdf5", src.raw, what, timeout=timeout)
    ds, groups = meta["datasets"], meta["groups"]
    root = groups.get("/", {})
    if root.get("format") != "tire-fbs":
        raise DataFormatError(f"{what} was not written by tire-fbs (no format attribute)")
    try:
        md = json.loads(root.get("metadata", "{}"))
    except (TypeError, ValueError):
        raise DataFormatError(f"{what}: the metadata attribute is not JSON") from None
    res = ResultData(str(root.get("content", "result")), metadata=md)

    def values(e: dict[str, Any]) -> np.ndarray:
        return arrays[e["array"]] if "array" in e else np.asarray(e.get("strings", []))

    for path, e in ds.items():
        if path.startswith("/coords/"):
            res.coords[path[len("/coords/") :]] = values(e)
        elif path.startswith("/arrays/"):
            dims = e["attrs"].get("dims")
            v = values(e)
            if isinstance(dims, str):
                dims = [dims]
            if not isinstance(dims, list) or len(dims) != v.ndim:
                raise DataFormatError(f"{what}: {path} lacks its axis names (attribute dims)")
            if "strings" in e:
                v = v.reshape(e["shape"])
            res.arrays[path[len("/arrays/") :]] = (tuple(dims), v)
    for g in groups:
        if g.startswith("/frfs/") and f"{g}/freq" in ds:
            res.frfs[g[len("/frfs/") :]] = read_hdf5(src, name=g, timeout=timeout)[0]
    if "/frf/freq" in ds:
        res.frfs["frf"] = read_hdf5(src, name="frf", timeout=timeout)[0]
    return res


def result_to_hdf5(res: ResultData) -> bytes:
    """HDF5 content of a result (the layout of :func:`write_hdf5_result`)."""
    return write_hdf5_result(res, res.metadata)
