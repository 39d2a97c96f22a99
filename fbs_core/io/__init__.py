"""Import and export in the formats NVH engineers use, with bad input refused.

Entry points (all accept a path, or the bytes of an upload plus its file name):

* :func:`load_frf` - FRFs from UFF dataset 58, MATLAB .mat (v5, v7.3), CSV, HDF5;
  returns an :class:`ImportResult` (the FRF, a short summary, notes, metadata).
* :func:`save_frf` - an FRF to any of these formats (returns bytes without a path).
* :func:`import_tire_model` - a modal tire model from the project's format or MATLAB
  (``load_tire_model`` is its deprecated name; the package's own trusted file is read by
  :func:`fbs_core.tire.read_tire_h5`).
* :func:`load_geometry` - positions and directions of measured channels (UFF 15/2411,
  CSV, HDF5) for the virtual point transformation (:mod:`.geometry`, :mod:`fbs_core.vpt`).
* :func:`export_result` - coupled and study results to CSV, UFF 58 or HDF5 with
  metadata (harmonic, N, noise, seed, fbs_core version) for traceability.

How a file is read: its bytes once, under a size limit (:func:`.checks.read_source`);
its format, the row of :data:`REGISTRY` (:mod:`.formats`) that its ending or
``format=`` names, checked against its first bytes; the row's reader, which parses the
layout in the sandbox process and ends in the one assembly step of every FRF
(:mod:`.assembly`: labels, units, quantity, SI); then the summary (:mod:`.imported`).
Writing and exporting call the row's writer or exporter. The layouts: :mod:`.uff`,
:mod:`.matlab`, :mod:`.csv`, :mod:`.hdf5`; tire models :mod:`.modal`; results
:mod:`.results`; input checks :mod:`.checks` and :mod:`.units`; the parser process
:mod:`._sandbox`, :mod:`._worker`, :mod:`._textparse`.

Every kind of bad input ends in a subclass of :class:`fbs_core.errors.FBSError`
(mostly :class:`~fbs_core.errors.DataFormatError`) with a message naming the file
and the problem. Nothing is executed or unpickled from a file; every format is parsed
in a separate process (:mod:`fbs_core.io._sandbox`). Loading never writes anything but
private temporary files. File formats: ``docs/file-formats.md``.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, overload

from ..errors import DataFormatError
from ..frf import FRF
from ._sandbox import DEFAULT_TIMEOUT
from .checks import (
    DEFAULT_MAX_BYTES,
    check_quantity_arg,
    common_grid,
    describe,
    interface_check,
    prepare_chassis,
    read_source,
    require_dofs,
)
from .formats import FORMATS, REGISTRY, FileFormat, detect_format, format_of
from .geometry import Geometry, load_geometry
from .imported import ImportResult, frf_import, tire_import
from .results import ResultData, as_result_data

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

#: A file path, or the content of an upload.
type SourceLike = str | os.PathLike[str] | bytes | bytearray | memoryview
#: Where to write; None returns the content as bytes.
type PathLike = str | os.PathLike[str]

__all__ = [
    "DEFAULT_MAX_BYTES",
    "FORMATS",
    "FileFormat",
    "Geometry",
    "ImportResult",
    "REGISTRY",
    "ResultData",
    "as_result_data",
    "common_grid",
    "describe",
    "export_result",
    "import_tire_model",
    "interface_check",
    "load_frf",
    "load_geometry",
    "load_measured_chassis",
    "MeasuredChassis",
    "load_result",
    "load_tire_model",
    "prepare_chassis",
    "require_dofs",
    "save_frf",
]


def load_frf(
    source: SourceLike,
    *,
    filename: str | None = None,
    format: str | None = None,
    nodes: Mapping[Any, Any] | None = None,
    quantity: str | None = None,
    freq: ArrayLike | None = None,
    name: str | None = None,
    require_outputs: Iterable[str] = (),
    require_inputs: Iterable[str] = (),
    max_bytes: int = DEFAULT_MAX_BYTES,
    timeout: float = DEFAULT_TIMEOUT,
) -> ImportResult:
    """Read an FRF from UFF 58, MATLAB (.mat v5 / v7.3), CSV or HDF5, with checks.

    Parameters
    ----------
    source : path or bytes
        A file path, or the content of an upload (then pass ``filename``).
    filename : str, optional
        The upload's file name; its ending selects the format.
    format : {"uff", "mat", "csv", "hdf5"}, optional
        Overrides the ending. The content must match it (magic bytes).
    nodes : mapping, optional
        Node names by number or old name, e.g. ``{1: "spindle", 2: "bushing"}``:
        UFF node numbers (and numeric node names in other formats) become these
        names, so the user decides which nodes are the spindle and the bushing.
    quantity : {"receptance", "mobility", "accelerance"}, optional
        Needed when the file does not declare it; checked against the file otherwise.
    freq : array_like, optional
        UFF only: interpolate records on different grids onto this grid (explicitly).
    name : str, optional
        HDF5 only: the FRF group to read.
    require_outputs, require_inputs : sequence of str
        DOF labels that must be present (DOFError lists the missing ones).
    max_bytes : int
        Size limit of the file (default 100 MiB).
    timeout : float
        Seconds the parser (every format runs in the sandbox process) may take.

    Returns
    -------
    ImportResult
        ``.frf`` (SI units, ``(n_freq, n_out, n_in)``) and ``.summary``; unpacks as
        ``frf, summary``.

    Raises
    ------
    DataFormatError
        Unreadable, damaged, too large, wrong layout or shapes, non-finite values, a
        file that is not what its ending says, refused MATLAB classes.
    DOFError
        Unknown directions, malformed or missing labels.
    FrequencyGridError
        Invalid grids, or records on different grids (pass ``freq``).
    QuantityError
        Undeclared quantity, declared quantity contradicting the units or
        ``quantity``, or an inverse FRF (dynamic stiffness, impedance).

    Examples
    --------
    >>> import numpy as np, fbs_core
    >>> Y = fbs_core.FRF([1.0, 2.0], np.ones((2, 1, 1)), ["1:z"], ["1:z"], "mobility")
    >>> raw = save_frf(Y, format="csv")
    >>> frf, summary = load_frf(raw, filename="up.csv", nodes={1: "spindle"})
    >>> frf.outputs
    ('spindle:z',)
    """
    check_quantity_arg(quantity)
    src = read_source(source, filename, max_bytes)
    fmt, content = detect_format(src, format)
    options = {k: v for k, v in (("freq", freq), ("name", name)) if v is not None}
    for key in options.keys() - set(fmt.read_options):
        having = " or ".join(f.label for f in REGISTRY.values() if key in f.read_options)
        hint = "; use FRF.interpolate after loading" if key == "freq" else ""
        raise DataFormatError(f"{key}= applies to {having} files only{hint}")
    frf, notes, meta = fmt.read(src, nodes=nodes, quantity=quantity, timeout=timeout, **options)
    label = fmt.contents[content]
    return frf_import(frf, notes, meta, src.name, label, require_outputs, require_inputs)


@overload
def _deliver(raw: bytes, path: None) -> bytes: ...
@overload
def _deliver(raw: bytes, path: PathLike) -> Path: ...
def _deliver(raw: bytes, path: PathLike | None) -> bytes | Path:
    if path is None:
        return raw
    p = Path(path)
    p.write_bytes(raw)
    return p


@overload
def save_frf(
    frf: FRF,
    path: None = None,
    *,
    format: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    nodes: Mapping[Any, Any] | None = None,
    mat_version: str = "5",
    binary: bool = False,
    round_abscissa: bool = False,
) -> bytes: ...
@overload
def save_frf(
    frf: FRF,
    path: PathLike,
    *,
    format: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    nodes: Mapping[Any, Any] | None = None,
    mat_version: str = "5",
    binary: bool = False,
    round_abscissa: bool = False,
) -> Path: ...
def save_frf(
    frf: FRF,
    path: PathLike | None = None,
    *,
    format: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    nodes: Mapping[Any, Any] | None = None,
    mat_version: str = "5",
    binary: bool = False,
    round_abscissa: bool = False,
) -> bytes | Path:
    """Write an FRF as UFF 58, MATLAB, CSV or HDF5 in the documented layouts.

    Parameters
    ----------
    frf : FRF
    path : path, optional
        Where to write; without it the content is returned as bytes (downloads).
    format : {"uff", "mat", "csv", "hdf5"}, optional
        Default from the path's ending.
    metadata : mapping, optional
        Provenance stored with the data (JSON-compatible values).
    nodes : mapping, optional
        UFF only: node number -> name, e.g. ``{1: "spindle"}``.
    mat_version : {"5", "7.3"}
    binary : bool
        UFF only: write binary dataset 58b.
    round_abscissa : bool
        UFF only: accept a grid that E13.5 would round.

    Returns
    -------
    bytes or pathlib.Path

    Raises
    ------
    DataFormatError
        For an unknown format, or a grid UFF cannot represent.
    """
    if not isinstance(frf, FRF):
        raise DataFormatError(f"save_frf needs an FRF, got {type(frf).__name__}")
    fmt = format_of(path, format)
    given = {"nodes": nodes, "mat_version": mat_version, "binary": binary}
    given["round_abscissa"] = round_abscissa
    options = {fmt.write_options[k]: v for k, v in given.items() if k in fmt.write_options}
    raw = fmt.write(frf, metadata=metadata, **options)
    return _deliver(raw, path)


@overload
def export_result(
    result: Any,
    path: None = None,
    *,
    format: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    nodes: Mapping[Any, Any] | None = None,
    round_abscissa: bool = False,
) -> bytes: ...
@overload
def export_result(
    result: Any,
    path: PathLike,
    *,
    format: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    nodes: Mapping[Any, Any] | None = None,
    round_abscissa: bool = False,
) -> Path: ...
def export_result(
    result: Any,
    path: PathLike | None = None,
    *,
    format: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    nodes: Mapping[Any, Any] | None = None,
    round_abscissa: bool = False,
) -> bytes | Path:
    """Export a coupled or study result as CSV, UFF 58 or HDF5, with metadata.

    Parameters
    ----------
    result : FRF, mapping, ResultData or dataclass
        E.g. a coupled response FRF, a ``TruncationMap``, ``SuggestedModes`` or
        ``ScatterBand``; flattened with :func:`as_result_data`.
    path : path, optional
        Where to write; without it the content is returned as bytes.
    format : {"csv", "uff", "hdf5"}, optional
        Default from the path's ending.
    metadata : mapping, optional
        Settings to record (harmonic, N, noise, seed, ...), added to the result's own
        fields, the fbs_core version and the export time.

    Returns
    -------
    bytes or pathlib.Path

    Raises
    ------
    DataFormatError
        For unknown formats, objects that cannot be flattened, or UFF export of a
        result without a function of frequency.
    """
    fmt = format_of(path, format)
    if fmt.export is None:
        can = [f.name for f in REGISTRY.values() if f.export is not None]
        raise DataFormatError(
            f"results are exported as {', '.join(can[:-1])} or {can[-1]}, not {fmt.name!r}"
        )
    given = {"nodes": nodes, "round_abscissa": round_abscissa}
    raw = fmt.export(
        as_result_data(result, metadata),
        **{k: v for k, v in given.items() if k in fmt.export_options},
    )
    return _deliver(raw, path)


def load_result(
    source: SourceLike,
    *,
    filename: str | None = None,
    max_bytes: int = DEFAULT_MAX_BYTES,
    timeout: float = DEFAULT_TIMEOUT,
) -> ResultData:
    """Read a result exported with :func:`export_result` as HDF5 back.

    Parameters
    ----------
    source : path or bytes
        A file path, or the content of an upload (then pass ``filename``).
    filename, max_bytes, timeout
        As in :func:`load_frf`.

    Returns
    -------
    ResultData
        Arrays with their axis names, coordinates, FRFs and the metadata of the export.

    Raises
    ------
    DataFormatError
        For other formats or layouts and damaged files.
    """
    from .hdf5 import read_hdf5_result

    src = read_source(source, filename, max_bytes)
    detect_format(src, "hdf5")
    return read_hdf5_result(src, timeout=timeout)


def import_tire_model(
    source: SourceLike,
    *,
    filename: str | None = None,
    format: str | None = None,
    max_bytes: int = DEFAULT_MAX_BYTES,
    timeout: float = DEFAULT_TIMEOUT,
) -> ImportResult:
    """Read a modal tire model: the project's own format or MATLAB (.mat v5 / v7.3).

    Parameters
    ----------
    source : path or bytes
        A file path, or the content of an upload (then pass ``filename``).
    filename, format, max_bytes, timeout
        As in :func:`load_frf`.

    Returns
    -------
    ImportResult
        ``.model`` the :class:`~fbs_core.tire.model.TireModel`, ``.summary`` with
        the operating points, modes, eigenfrequency range and wavelengths; unpacks
        as ``model, summary``.

    Raises
    ------
    DataFormatError
        For damaged files, missing variables, wrong shapes, non-finite values.
    """
    src = read_source(source, filename, max_bytes)
    fmt, content = detect_format(src, format)
    if fmt.read_tire is None:
        can = [f"{f.label} ({', '.join(f.suffixes)})" for f in REGISTRY.values() if f.read_tire]
        raise DataFormatError(f"tire models are read from {' or '.join(can)}, not {fmt.name!r}")
    return tire_import(
        fmt.read_tire(src, timeout=timeout), src.name, fmt.tire_label or fmt.contents[content]
    )


def load_tire_model(
    source: SourceLike,
    *,
    filename: str | None = None,
    format: str | None = None,
    max_bytes: int = DEFAULT_MAX_BYTES,
    timeout: float = DEFAULT_TIMEOUT,
) -> ImportResult:
    """Deprecated name of :func:`import_tire_model` (a ``DeprecationWarning``; removed in the
    next release)."""
    warnings.warn(
        "fbs_core.io.load_tire_model is deprecated; use fbs_core.io.import_tire_model",
        DeprecationWarning,
        stacklevel=2,
    )
    return import_tire_model(
        source, filename=filename, format=format, max_bytes=max_bytes, timeout=timeout
    )


# a measured chassis from its two files: built on this package's readers (above) and the
# virtual point transformation
from .measured import MeasuredChassis, load_measured_chassis  # noqa: E402
