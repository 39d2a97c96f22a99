"""The file formats of :mod:`fbs_core.io`, in one table.

Each row (:class:`FileFormat`) says what a format is called, the file-name endings that
select it, what its content must look like (:func:`~.checks.sniff`), and the functions
that read and write it: an FRF reader and writer, a result exporter and a tire-model
reader where the format has them, and whether its parser runs in the sandbox process
(:mod:`._sandbox`). Every entry point (:func:`~fbs_core.io.load_frf`,
:func:`~fbs_core.io.save_frf`, :func:`~fbs_core.io.export_result`,
:func:`~fbs_core.io.import_tire_model`, :func:`~fbs_core.io.load_result`) looks its
format up here (:func:`format_of`, :func:`detect_format`), so a new format is one row.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from ..errors import DataFormatError
from ..frf import FRF
from . import csv, hdf5, matlab, modal, results, uff
from .checks import Source, sniff

if TYPE_CHECKING:
    from ..tire.model import TireModel

__all__ = ["FileFormat", "REGISTRY", "FORMATS", "format_of", "detect_format"]

#: ``reader(src, *, nodes, quantity, timeout, **read_options) -> (frf, notes, metadata)``
FRFReader = Callable[..., tuple[FRF, list[str], dict[str, Any]]]
#: ``writer(frf, *, metadata, **write_options) -> bytes``
FRFWriter = Callable[..., bytes]
#: ``exporter(result, **export_options) -> bytes``
ResultWriter = Callable[..., bytes]
#: ``reader(src, *, timeout) -> TireModel``
TireReader = Callable[..., "TireModel"]


@dataclass(frozen=True)
class FileFormat:
    """One file format: its names, endings, content and the functions that handle it.

    Attributes
    ----------
    name : str
        The ``format=`` value (``"uff"``, ``"mat"``, ``"csv"``, ``"hdf5"``).
    label : str
        Short name in messages ("UFF 58", "MATLAB").
    suffixes : tuple of str
        File-name endings that select it (lower case, with the dot).
    title : str
        What a file of this format is, in messages ("MATLAB MAT-file (v5 or v7.3)").
    contents : mapping of str to str
        What :func:`~.checks.sniff` may find in such a file -> how an import summary
        names the format read (``{"mat5": "MATLAB v5", "mat73": "MATLAB v7.3"}``).
    read, write : callable
        FRF reader and writer (see :data:`FRFReader`, :data:`FRFWriter`).
    read_options : tuple of str
        Keywords of :func:`~fbs_core.io.load_frf` only this format takes (``"freq"``).
    write_options : mapping of str to str
        Keywords of :func:`~fbs_core.io.save_frf` this format takes -> the writer's name
        for them (``{"mat_version": "version"}``); other formats ignore them.
    export : callable or None
        Writer of results (:class:`~.results.ResultData`), None when the format cannot
        carry them.
    export_options : tuple of str
        Keywords of :func:`~fbs_core.io.export_result` the exporter takes.
    read_tire : callable or None
        Reader of modal tire models, None when the format holds none.
    tire_label : str or None
        How an import summary names a tire model read from it (default from
        ``contents``).
    sandboxed : bool
        Its content is parsed in the sandbox process, never in this one.
    """

    name: str
    label: str
    suffixes: tuple[str, ...]
    title: str
    contents: Mapping[str, str]
    read: FRFReader
    write: FRFWriter
    read_options: tuple[str, ...] = ()
    write_options: Mapping[str, str] = field(default_factory=dict)
    export: ResultWriter | None = None
    export_options: tuple[str, ...] = ()
    read_tire: TireReader | None = None
    tire_label: str | None = None
    sandboxed: bool = True


REGISTRY: Mapping[str, FileFormat] = MappingProxyType(
    {
        f.name: f
        for f in (
            FileFormat(
                name="uff",
                label="UFF 58",
                suffixes=(".uff", ".unv", ".uf", ".58"),
                title="Universal File (dataset 58)",
                contents={"uff": "UFF 58"},
                read=uff.read_uff,
                write=uff.write_uff,
                read_options=("freq",),
                write_options={k: k for k in ("nodes", "binary", "round_abscissa")},
                export=results.result_to_uff,
                export_options=("nodes", "round_abscissa"),
            ),
            FileFormat(
                name="mat",
                label="MATLAB",
                suffixes=(".mat",),
                title="MATLAB MAT-file (v5 or v7.3)",
                contents={"mat5": "MATLAB v5", "mat73": "MATLAB v7.3"},
                read=matlab.read_mat,
                write=matlab.write_mat,
                write_options={"mat_version": "version"},
                read_tire=modal.read_tire_mat,
            ),
            FileFormat(
                name="csv",
                label="CSV",
                suffixes=(".csv", ".txt"),
                title="CSV text file",
                contents={"text": "CSV"},
                read=csv.read_csv,
                write=csv.write_csv,
                export=results.result_to_csv,
            ),
            FileFormat(
                name="hdf5",
                label="HDF5",
                suffixes=(".h5", ".hdf5", ".hdf"),
                title="HDF5 file",
                # a MATLAB v7.3 file is an HDF5 file with a header
                contents={"hdf5": "HDF5", "mat73": "HDF5"},
                read=hdf5.read_hdf5,
                write=hdf5.write_hdf5,
                read_options=("name",),
                export=hdf5.result_to_hdf5,
                read_tire=modal.read_tire_native,
                tire_label="tire-fbs tire model",
            ),
        )
    }
)

#: File formats by name and the file-name endings that select them.
FORMATS: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {f.name: f.suffixes for f in REGISTRY.values()}
)

#: How messages name a content :func:`~.checks.sniff` found (else its own words).
_CONTENT_NAMES = {
    "mat5": "a MATLAB v5 MAT-file",
    "mat73": "a MATLAB v7.3 MAT-file",
    "hdf5": "an HDF5 file",
    "text": "a text file",
    "uff": "a Universal File",
}


def _endings(formats: Iterable[FileFormat]) -> str:
    return "; ".join(f"{', '.join(f.suffixes)} ({f.name})" for f in formats)


def format_of(path: str | os.PathLike[str] | None, format: str | None = None) -> FileFormat:
    """The format named by ``format``, else the one ``path``'s ending selects.

    Raises
    ------
    DataFormatError
        For an unknown format or ending, naming the known ones.

    Examples
    --------
    >>> format_of("chassis.UNV").name, format_of(None, "mat").title
    ('uff', 'MATLAB MAT-file (v5 or v7.3)')
    """
    if format is not None:
        if format not in REGISTRY:
            raise DataFormatError(f"unknown format {format!r}; allowed: {', '.join(REGISTRY)}")
        return REGISTRY[format]
    if path is None:
        raise DataFormatError(f"pass format=... (one of {', '.join(REGISTRY)}) or a path")
    suffix = Path(path).suffix.lower()
    for f in REGISTRY.values():
        if suffix in f.suffixes:
            return f
    raise DataFormatError(
        f"cannot tell the format from {str(path)!r}; known endings: "
        f"{_endings(REGISTRY.values())} (or pass format=...)"
    )


def detect_format(src: Source, format: str | None = None) -> tuple[FileFormat, str]:
    """The format from ``format`` or the file-name ending, with the content checked.

    Returns
    -------
    format : FileFormat
    content : str
        What :func:`~.checks.sniff` found, one of ``format.contents``.

    Raises
    ------
    DataFormatError
        For an unknown format or ending, or content that is not what the name says
        (e.g. a ZIP archive named ``.uff``).
    """
    if format is None and not any(src.suffix in f.suffixes for f in REGISTRY.values()):
        raise DataFormatError(
            f"cannot tell the format of {src.name!r} from its name; known endings: "
            f"{_endings(REGISTRY.values())} (or pass format=...)"
        )
    fmt = format_of(src.name, format)
    content = sniff(src.raw)
    if content not in fmt.contents:
        found = _CONTENT_NAMES.get(content, content)
        raise DataFormatError(
            f"file {src.name!r} should be a {fmt.title} but its content is {found}"
        )
    return fmt, content
