"""Campaign result files on the server's disk, and the files opened, kept per process.

The files come from a server-side directory the operator trusts, ``FBS_CAMPAIGN_DIR``
(:func:`campaign_dir`; the campaigns' ``output`` files, e.g. a volume the campaign runs
write to). Its ``*.h5`` files whose root says they are campaign results are listed
(:func:`list_campaigns`) and opened with :func:`fbs_core.campaign.open_campaign` (together
with the parts of a run still going on). Nothing is uploaded: an HDF5 file from a browser
is never opened in the server process (see ``fbs_core.io``'s sandbox), and a campaign file
holds many cases, so it belongs on the server's disk anyway.

Reading a large file takes seconds, so what is read is kept per process and read again
only when a file changes (size and modification time): whether a file is a campaign
result, and the last :data:`CACHED_FILES` opened files with their case tables
(:func:`open_cached`; sessions opening the same file at once wait for one reading). A
malformed file is a :class:`~fbs_core.campaign.CampaignError` naming the file and the
problem, kept like a good file and said with the campaign folder's path left out
(:func:`relative_names`). No Panel, no Bokeh: the browser
(:mod:`app.views.campaign`) shows what this module reads.
"""

from __future__ import annotations

import logging
import os
import threading
from collections import OrderedDict
from pathlib import Path

from fbs_core.campaign import CampaignError, CampaignResult, open_campaign

from ..results.campaign import case_rows
from ..state.campaign import CAMPAIGN_DIR_ENV, campaign_dir

__all__ = [
    "CACHED_FILES",
    "CAMPAIGN_DIR_ENV",
    "Opened",
    "cached",
    "campaign_dir",
    "campaign_path",
    "list_campaigns",
    "open_cached",
    "read_campaign",
    "relative_names",
]

log = logging.getLogger(__name__)

#: Opened campaign files kept per process (their case tables with them).
CACHED_FILES = 4


#: path -> ((mtime_ns, size), is a campaign result)
_IS_CAMPAIGN: dict[Path, tuple[tuple[int, int], bool]] = {}


def _stamp(p: Path) -> tuple[int, int]:
    st = p.stat()
    return st.st_mtime_ns, st.st_size


def _is_campaign(p: Path) -> bool:
    """Whether ``p``'s root says it is a campaign result (read again only when it changed)."""
    from fbs_core.hdf5_guard import ForeignDataError, open_h5

    stamp = _stamp(p)
    known = _IS_CAMPAIGN.get(p)
    if known is not None and known[0] == stamp:
        return known[1]
    try:
        with open_h5(p) as h:
            ok = h.attrs.get("content") == "campaign"
    except ForeignDataError:  # listed: opening it says why it is refused
        ok = True
    except (OSError, ValueError, TypeError, KeyError, RuntimeError):  # not (readable) HDF5
        ok = False
    _IS_CAMPAIGN[p] = (stamp, ok)
    return ok


def list_campaigns(directory: Path | None) -> list[str]:
    """Names of the campaign result files directly in ``directory`` (sorted).

    Only regular ``*.h5`` files inside the directory (a link pointing elsewhere is left
    out) whose root says it is a campaign result; a file is opened for that only when it is
    new or changed since it was last looked at.
    """
    if directory is None or not directory.is_dir():
        return []
    out = []
    for p in sorted(directory.glob("*.h5")):
        try:
            if p.is_file() and p.resolve().parent == directory and _is_campaign(p):
                out.append(p.name)
        except OSError:  # removed meanwhile
            continue
    return out


def campaign_path(directory: Path | None, name: str) -> Path:
    """The campaign result file ``name`` of the campaign folder ``directory``.

    ``name`` comes from a link, so it is only ever a file listed by :func:`list_campaigns`:
    a plain ``*.h5`` name directly in the folder whose root says it is a campaign result.

    Raises
    ------
    CampaignError
        No folder is set, or ``name`` is no campaign result file of the folder.
    """
    if directory is None:
        raise CampaignError(f"No campaign directory configured (set {CAMPAIGN_DIR_ENV}).")
    if not name or Path(name).name != name or not name.endswith(".h5") or name in (".", ".."):
        raise CampaignError(f"{name!r} is not a campaign result file name")
    path = directory / name
    try:
        ok = path.is_file() and path.resolve().parent == directory and _is_campaign(path)
    except OSError:
        ok = False
    if not ok:
        raise CampaignError(f"{name}: no campaign result file of that name in the campaign folder")
    return path


class Opened:
    """A campaign file as the browser shows it: the result, its case table, its first line."""

    def __init__(self, result: CampaignResult) -> None:
        self.result = result
        self.rows = case_rows(result)
        self.headline = result.headline(planned=False)


_OPENED: OrderedDict[tuple, Opened | CampaignError] = OrderedDict()
_OPENING: dict[tuple, threading.Lock] = {}
_OPEN_LOCK = threading.Lock()


def _file_key(path: Path) -> tuple:
    """The file and the parts of a run not merged yet, with their sizes and times."""
    from fbs_core.campaign.store import CampaignStore

    try:
        files = CampaignStore(path).files()
        return (str(path), *((str(p), *_stamp(p)) for p in files))
    except OSError as exc:
        return (str(path), "unreadable", str(exc))


def open_cached(path: Path) -> Opened:
    """:class:`Opened` of the campaign file ``path``, read once per change of the file.

    Sessions opening the same file at once wait for one reading; a malformed file's
    :class:`CampaignError` is kept too (not read again until the file changes).

    Raises
    ------
    CampaignError
        For a file that cannot be used, naming the file and the problem.
    """
    key = _file_key(path)
    with _OPEN_LOCK:
        lock = _OPENING.setdefault(key, threading.Lock())
    with lock:
        with _OPEN_LOCK:
            got = _OPENED.get(key)
        if got is None:
            try:
                got = Opened(open_campaign(path))
            except CampaignError as exc:
                got = exc
            except Exception as exc:  # noqa: BLE001 (the card must say it, not the page fail)
                log.exception("campaign file %s", path)
                got = CampaignError(f"{path}: cannot be read ({type(exc).__name__}: {exc})")
            with _OPEN_LOCK:
                _OPENED[key] = got
                while len(_OPENED) > CACHED_FILES:
                    _OPENED.popitem(last=False)
        with _OPEN_LOCK:
            _OPENING.pop(key, None)
            if key in _OPENED:
                _OPENED.move_to_end(key)
    if isinstance(got, CampaignError):
        raise got
    return got


def cached(path: Path) -> Opened | None:
    """:class:`Opened` of ``path`` when it was read since its last change, without reading
    it (None: not read yet, :func:`open_cached` reads it).

    Raises
    ------
    CampaignError
        The kept problem of a malformed file (see :func:`open_cached`).
    """
    key = _file_key(path)
    with _OPEN_LOCK:
        got = _OPENED.get(key)
    if isinstance(got, CampaignError):
        raise got
    return got


def relative_names(text: str, directory: Path | None) -> str:
    """``text`` with the campaign folder's path left out of the file names it quotes.

    A user sees ``run.h5`` or ``run.h5.parts/0001.h5``, never the server's absolute paths.

    Parameters
    ----------
    text : str
        A message, e.g. a :class:`~fbs_core.campaign.CampaignError`'s.
    directory : Path or None
        The campaign folder; None leaves ``text`` as it is.

    Returns
    -------
    str
        The message with the folder's path removed (the folder itself said ``.``).
    """
    if directory is None:
        return text
    folder = str(directory).rstrip(os.sep)
    return text.replace(folder + os.sep, "").replace(folder, ".")


def read_campaign(path: Path) -> tuple[Opened | None, str]:
    """The campaign file ``path`` opened (:func:`open_cached`), or why it cannot be.

    Parameters
    ----------
    path : Path
        A campaign result file of the campaign folder.

    Returns
    -------
    tuple of (Opened or None, str)
        ``(the opened file, "")``, or ``(None, the message of its CampaignError)`` with its
        file names relative to the campaign folder (:func:`relative_names`).
    """
    try:
        return open_cached(path), ""
    except CampaignError as exc:
        return None, relative_names(str(exc), path.parent)
