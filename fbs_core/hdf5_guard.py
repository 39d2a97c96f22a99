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

The walk is HDF5's own (in C: a file of 1,000 groups and 10,000 datasets in about a second
on a busy machine, against 10 s opening each object from Python).
"""

from __future__ import annotations

import os
import threading
from collections import OrderedDict
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from .errors import ForeignDataError

__all__ = ["ForeignDataError", "check_self_contained", "open_h5"]

#: Number of file versions whose passed walk is remembered.
_REMEMBERED = 256

_passed: OrderedDict[tuple[Any, ...], None] = OrderedDict()
_passed_lock = threading.Lock()


def check_self_contained(root: Any) -> None:
    """Walk every link under the open file or group ``root``; refuse what leaves the file.

    HDF5's own visits run in C: every link once (``H5Lvisit``, through hard links; a group
    reached by several hard links, or by a cycle of them, is walked once) for the kinds of
    link, then every object once (``H5Ovisit``) for the datasets' storage (their creation
    properties: layout, virtual sources, external files), each dataset opened by its path.

    Raises
    ------
    ForeignDataError
        For the first refused object, naming its path (see the module's docstring).
    """
    from h5py import h5d, h5l, h5o

    gid = root.id
    prefix = root.name.rstrip("/")

    def where(name: bytes) -> str:
        return f"{prefix}/{name.decode('utf-8', 'replace')}"

    def link(name: bytes, info: Any) -> str | None:
        if info.type == h5l.TYPE_HARD:
            return None
        path = where(name)
        if info.type == h5l.TYPE_SOFT:
            soft.append(name)  # resolved once no link of the file leads out of it
            return None
        if info.type == h5l.TYPE_EXTERNAL:
            filename = gid.links.get_val(name)[0].decode("utf-8", "replace")
            return (
                f"object {path!r} is an external link to {Path(filename).name!r}; links to "
                "other files are not followed"
            )
        return f"object {path!r} is a user-defined link; only links inside the file are followed"

    def dataset(name: bytes, info: Any) -> str | None:
        if info.type != h5o.TYPE_DATASET:
            return None
        dcpl = h5d.open(gid, name).get_create_plist()
        path = where(name)
        if dcpl.get_external_count():
            return f"dataset {path!r} stores its data in other files (external storage); refused"
        if dcpl.get_layout() == h5d.VIRTUAL:
            for k in range(dcpl.get_virtual_count()):
                src = dcpl.get_virtual_filename(k)
                if src != ".":
                    return (
                        f"dataset {path!r} is a virtual dataset mapping data from the file "
                        f"{Path(src).name!r}; only sources inside the file are read"
                    )
        return None

    def resolved(name: bytes) -> str | None:
        target = gid.links.get_val(name).decode("utf-8", "replace")
        try:
            h5o.open(gid, name).close()  # follows the soft link (and any chain of them)
        except (KeyError, RuntimeError, OSError, ValueError) as e:
            return (
                f"object {where(name)!r} is a soft link to {target!r} that dangles or loops ({e})"
            )
        return None

    soft: list[bytes] = []
    # a callback returns the refusal, which ends the visit (raising inside one is not safe)
    why = gid.links.visit(link, info=True)
    why = why or next((w for w in map(resolved, soft) if w), None)
    why = why or h5o.visit(gid, dataset, info=True)
    if why:
        raise ForeignDataError(why)


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
