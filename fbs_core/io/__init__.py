"""Import and export in the formats NVH engineers use, with bad input refused.

Entry points (all accept a path, or the bytes of an upload plus its file name):

* :func:`load_frf` - FRFs from UFF dataset 58, MATLAB .mat (v5, v7.3), CSV, HDF5;
  returns an :class:`ImportResult` (the FRF, a short summary, notes, metadata).
* :func:`save_frf` - an FRF to any of these formats (returns bytes without a path).
* :func:`import_tire_model` - a modal tire model from the project's format or MATLAB
  (``load_tire_model`` is its deprecated name; the package's own trusted file is read by
  :func:`fbs_core.tire.read_tire_h5`).
* :func:`export_result` - coupled and study results to CSV, UFF 58 or HDF5 with
  metadata (harmonic, N, noise, seed, fbs_core version) for traceability.

Every kind of bad input ends in a subclass of :class:`fbs_core.errors.FBSError`
(mostly :class:`~fbs_core.errors.DataFormatError`) with a message naming the file
and the problem. Nothing is executed or unpickled from a file; the binary parsers
run in a separate process (:mod:`fbs_core.io._sandbox`). Loading never writes
anything but private temporary files. File formats: ``docs/file-formats.md``.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias, overload

from ..errors import DataFormatError
from ..frf import FRF
from ._sandbox import DEFAULT_TIMEOUT
from .checks import (
    DEFAULT_MAX_BYTES,
    FORMATS,
    Source,
    check_quantity_arg,
    common_grid,
    describe,
    detect_format,
    interface_check,
    prepare_chassis,
    quantity_notes,
    read_source,
    require_dofs,
)
from .results import ResultData, as_result_data

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

#: A file path, or the content of an upload.
SourceLike: TypeAlias = "str | os.PathLike[str] | bytes | bytearray | memoryview"
#: Where to write; None returns the content as bytes.
PathLike: TypeAlias = "str | os.PathLike[str]"

__all__ = [
    "DEFAULT_MAX_BYTES",
    "FORMATS",
    "ImportResult",
    "ResultData",
    "as_result_data",
    "common_grid",
    "describe",
    "export_result",
    "import_tire_model",
    "interface_check",
    "load_frf",
    "load_result",
    "load_tire_model",
    "prepare_chassis",
    "require_dofs",
    "save_frf",
]


@dataclass(frozen=True)
class ImportResult:
    """What an importer read.

    Attributes
    ----------
    frf : FRF or None
        The FRF (None for a tire model).
    model : TireModel or None
        The tire model (None for an FRF).
    summary : str
        Short human-readable description: quantity, DOFs, frequency range,
        operating points; with the notes appended.
    notes : tuple of str
        Conversions applied, records skipped, plausibility warnings.
    metadata : dict
        Provenance stored in the file.
    source : str
        File name; ``format`` the format it was read as.
    """

    frf: FRF | None
    summary: str
    notes: tuple[str, ...] = ()
    metadata: dict[str, Any] = field(default_factory=dict)
    source: str = ""
    format: str = ""
    model: object | None = None

    def __iter__(self) -> Iterator[Any]:
        """Unpack as ``frf, summary = load_frf(...)``."""
        return iter((self.frf if self.model is None else self.model, self.summary))


def _finish(
    frf: FRF,
    notes: list[str],
    meta: dict[str, Any],
    name: str,
    fmt: str,
    require_outputs: Iterable[str] = (),
    require_inputs: Iterable[str] = (),
) -> ImportResult:
    require_dofs(frf, require_outputs, require_inputs, what=f"{name!r}")
    notes = list(notes) + quantity_notes(frf)
    text = f"{name} ({fmt}): " + describe(frf)
    if notes:
        text += "\nnotes: " + "; ".join(notes)
    return ImportResult(frf, text, tuple(notes), dict(meta), name, fmt)


#: How an import names each format in its summary (MATLAB by its container version).
_LABELS = {
    "uff": "UFF 58",
    "csv": "CSV",
    "hdf5": "HDF5",
    "mat5": "MATLAB v5",
    "mat73": "MATLAB v7.3",
}


def _open(
    source: SourceLike, filename: str | None, format: str | None, max_bytes: int
) -> tuple[Source, str, str, str]:
    """The source read once and its format: ``(source, format, kind, label)``.

    What every importer does before its parser runs in the sandbox: the size limit, the
    format from the ending or ``format``, the magic bytes checked against it, and the
    format's name for the summary.
    """
    src = read_source(source, filename, max_bytes)
    fmt, kind = detect_format(src, format)
    return src, fmt, kind, _LABELS[kind if fmt == "mat" else fmt]


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
    src, fmt, kind, label = _open(source, filename, format, max_bytes)
    if freq is not None and fmt != "uff":
        raise DataFormatError("freq= applies to UFF files only; use FRF.interpolate after loading")
    if name is not None and fmt != "hdf5":
        raise DataFormatError("name= applies to HDF5 files only")
    if fmt == "uff":
        from .uff import read_uff

        frf, notes, meta = read_uff(src, nodes=nodes, quantity=quantity, freq=freq, timeout=timeout)
    elif fmt == "mat":
        from .matlab import read_mat

        frf, notes, meta = read_mat(src, kind, nodes=nodes, quantity=quantity, timeout=timeout)
    elif fmt == "csv":
        from .csv import read_csv

        frf, notes, meta = read_csv(src, nodes=nodes, quantity=quantity, timeout=timeout)
    else:
        from .hdf5 import read_hdf5

        frf, notes, meta = read_hdf5(
            src, nodes=nodes, quantity=quantity, name=name, timeout=timeout
        )
    return _finish(frf, notes, meta, src.name, label, require_outputs, require_inputs)


def _format_for(path: PathLike | None, format: str | None) -> str:
    if format is not None:
        if format not in FORMATS:
            raise DataFormatError(f"unknown format {format!r}; allowed: {', '.join(FORMATS)}")
        return format
    if path is None:
        raise DataFormatError(f"pass format=... (one of {', '.join(FORMATS)}) or a path")
    suffix = Path(path).suffix.lower()
    for fmt, ends in FORMATS.items():
        if suffix in ends:
            return fmt
    raise DataFormatError(
        f"cannot tell the format from {str(path)!r}; known endings: "
        f"{', '.join(e for ends in FORMATS.values() for e in ends)}"
    )


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
    fmt = _format_for(path, format)
    if fmt == "uff":
        from .uff import write_uff

        raw = write_uff(
            frf, nodes=nodes, metadata=metadata, binary=binary, round_abscissa=round_abscissa
        )
    elif fmt == "mat":
        from .matlab import write_mat

        raw = write_mat(frf, version=mat_version, metadata=metadata)
    elif fmt == "csv":
        from .csv import write_csv

        raw = write_csv(frf, metadata=metadata)
    else:
        from .hdf5 import write_hdf5

        raw = write_hdf5(frf, metadata=metadata)
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
    fmt = _format_for(path, format)
    res = as_result_data(result, metadata)
    if fmt == "csv":
        from .results import result_to_csv

        raw = result_to_csv(res)
    elif fmt == "uff":
        from .results import result_to_uff

        raw = result_to_uff(res, nodes=nodes, round_abscissa=round_abscissa)
    elif fmt == "hdf5":
        from .results import result_to_hdf5

        raw = result_to_hdf5(res)
    else:
        raise DataFormatError(f"results are exported as csv, uff or hdf5, not {fmt!r}")
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
    src = read_source(source, filename, max_bytes)
    fmt, _ = detect_format(src, None if src.suffix in FORMATS["hdf5"] else "hdf5")
    from .hdf5 import read_hdf5_result

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
    src, fmt, kind, label = _open(source, filename, format, max_bytes)
    if fmt == "mat":
        from .modal import read_tire_mat

        model = read_tire_mat(src, kind, timeout=timeout)
    elif fmt == "hdf5":
        from .modal import read_tire_native

        model = read_tire_native(src, timeout=timeout)
        label = "tire-fbs tire model"
    else:
        raise DataFormatError(
            f"tire models are read from MATLAB (.mat) or the project's format (.h5), not {fmt!r}"
        )
    return ImportResult(
        None,
        f"{src.name} ({label}): " + describe_tire(model),
        (),
        dict(model.meta),
        src.name,
        label,
        model,
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


def describe_tire(model: Any) -> str:
    """Short summary of a tire model: operating points, modes, frequencies, wavelengths."""
    import numpy as np

    f = np.abs(np.asarray(model.poles).imag) / (2 * np.pi)
    return "\n".join(
        [
            f"modal tire model, {model.n_modes} complex modes ({model.n_modes // 2} pairs), "
            f"eigenfrequencies {f.min():.1f}-{f.max():.1f} Hz",
            "operating points: " + ", ".join(f"{v:g}" for v in model.speeds) + " km/h",
            "hub DOFs: " + ", ".join(model.hub_dofs),
            "patch participation for wavelengths: "
            + ", ".join(f"{w:g}" for w in model.wavelengths)
            + " m",
        ]
    )
