"""One guard for every HDF5 file this package reads: the file must hold all its data.

HDF5 can make a file read other files: an external link (``h5py.ExternalLink``) opens
another file when it is followed, a virtual dataset maps its data from datasets of other
files, and a dataset with external storage reads raw bytes from any file named in it. A
file from a user, a supplier or a shared volume must not make the server open, or read
from, ``/etc/passwd``. :func:`open_h5` therefore opens a file and walks every link of it
before anything is read, and refuses

* an external link (also one that names the file itself),
* a soft link that dangles or loops (one that resolves inside the file is kept),
* a virtual dataset with a source outside the file (sources in the same file, ``"."``,
  are kept),
* a dataset with external raw storage,
* a link of a kind HDF5 adds later (user-defined links),

with an error naming the file and the object's path. Nothing of the file is read before the
walk has passed. A passed walk is remembered per file version (device, inode, size, time),
so a file read many times (the blocks of a campaign) is walked once.

Uploads (tire models, FRFs) are parsed by the sandboxed parser
(:mod:`fbs_core.io._worker`), which imports no module of this package and is stricter
still: it follows hard links only and reads no virtual dataset at all.

The walk opens each object relative to its group (HDF5's own visit resolves every full path
from the root, which takes minutes for groups nested thousands deep) and visits an object
reached by several hard links once.
"""

from __future__ import annotations

import os
import threading
from collections import OrderedDict
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from .errors import DataFormatError

__all__ = ["ForeignDataError", "check_self_contained", "open_h5", "refused_link", "refused_dataset"]

#: Number of file versions whose passed walk is remembered.
_REMEMBERED = 256

_passed: OrderedDict[tuple[Any, ...], None] = OrderedDict()
_passed_lock = threading.Lock()


class ForeignDataError(DataFormatError):
    """An HDF5 file that links to, or maps data from, outside itself."""


def refused_link(link: Any, path: str) -> str | None:
    """Why the link object ``link`` (``group.get(name, getlink=True)``) at ``path`` is
    refused, or None for a hard or soft link (a soft link's target is checked apart)."""
    import h5py

    if isinstance(link, h5py.HardLink | h5py.SoftLink):
        return None
    if isinstance(link, h5py.ExternalLink):
        return (
            f"object {path!r} is an external link to {Path(link.filename).name!r}; links to other "
            "files are not followed"
        )
    return f"object {path!r} is a {type(link).__name__}; only links inside the file are followed"


def refused_dataset(ds: Any, path: str) -> str | None:
    """Why the dataset ``ds`` at ``path`` is refused (its data in another file), or None."""
    if ds.external:
        return f"dataset {path!r} stores its data in other files (external storage); refused"
    if ds.is_virtual:
        for src in ds.virtual_sources():
            if src.file_name != ".":
                return (
                    f"dataset {path!r} is a virtual dataset mapping data from the file "
                    f"{Path(src.file_name).name!r}; only sources inside the file are read"
                )
    return None


def check_self_contained(root: Any) -> None:
    """Walk every link under the open file or group ``root``; refuse what leaves the file.

    Raises
    ------
    ForeignDataError
        For the first refused object, naming its path (see the module's docstring).
    """
    import h5py

    seen: set[int] = set()
    stack: list[tuple[Any, str, Iterator[str]]] = [(root, root.name.rstrip("/"), iter(root))]
    while stack:
        group, prefix, names = stack[-1]
        name = next(names, None)
        if name is None:
            stack.pop()
            continue
        path = f"{prefix}/{name}"
        link = group.get(name, getlink=True)
        why = refused_link(link, path)
        if why:
            raise ForeignDataError(why)
        try:
            obj = group[name]
        except (KeyError, RuntimeError, OSError, ValueError) as e:
            if isinstance(link, h5py.SoftLink):
                raise ForeignDataError(
                    f"object {path!r} is a soft link to {link.path!r} that dangles or loops ({e})"
                ) from None
            raise ForeignDataError(f"object {path!r} cannot be opened ({e})") from None
        if isinstance(link, h5py.SoftLink):
            continue  # its target is reached (and checked) through hard links
        key = hash(obj.id)
        if key in seen:
            continue
        seen.add(key)
        if isinstance(obj, h5py.Dataset):
            why = refused_dataset(obj, path)
            if why:
                raise ForeignDataError(why)
        elif isinstance(obj, h5py.Group):
            stack.append((obj, path, iter(obj)))


def _version(path: Path) -> tuple[Any, ...]:
    st = path.stat()
    return (str(path.resolve()), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


@contextmanager
def open_h5(
    path: str | os.PathLike[str],
    mode: str = "r",
    *,
    error: type[Exception] = ForeignDataError,
    name: str | None = None,
    **kwargs: Any,
) -> Iterator[Any]:
    """``h5py.File(path, mode)``, checked by :func:`check_self_contained` before use.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    mode : str
        ``"r"`` or ``"a"`` (a file written from scratch, ``"w"``, needs no guard).
    error : type of Exception
        The error raised for a refused file (e.g. a campaign's ``CampaignError``); its
        message names the file as ``name`` and the object's path.
    name : str, optional
        The file's name in the message (default: ``path``), e.g. relative to a folder so
        messages do not show the server's absolute paths.
    **kwargs
        Passed on to ``h5py.File``.

    Raises
    ------
    error
        When the file links to, or maps data from, other files. ``OSError`` of h5py for a
        file that is not HDF5 passes through.
    """
    import h5py

    p = Path(path)
    h = h5py.File(p, mode, **kwargs)
    try:
        try:
            version = _version(p)
        except OSError:
            version = None
        with _passed_lock:
            known = version is not None and version in _passed
        if not known:
            try:
                check_self_contained(h)
            except ForeignDataError as e:
                raise error(f"{name or p}: {e}") from None
            if version is not None and mode == "r":
                with _passed_lock:
                    _passed[version] = None
                    while len(_passed) > _REMEMBERED:
                        _passed.popitem(last=False)
        yield h
    finally:
        h.close()
