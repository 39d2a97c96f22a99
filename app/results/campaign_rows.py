"""The campaign card's results as rows of the store: the case table and the chosen case.

Pure functions of a :class:`~app.results.Snapshot` (its ``campaign_*`` fields): the file is
the server's folder's (``campaign_dir``) file named by ``campaign_file``, read through the
per-process cache of :mod:`app.runtime.campaign_files`, so every session browsing a file
shares one reading. Reading takes seconds for a large file: :func:`open_work` is the
store's background work of both rows, and until it is done the rows are pending results
that say which file is being read. What a case shows is made by :mod:`app.results.campaign`
from the opened file (nothing is recomputed).

A row is None when there is nothing to show (no file chosen, no case chosen): a page
costs no file access until its card is opened or its link names a file. A file that
cannot be used, or a case that cannot be shown, is a result whose ``draw["problem"]`` is
the message naming the file and the problem (its folder's path left out); it has no
columns, so it is neither exported nor a section of the report.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path
from types import MappingProxyType
from typing import Any

from fbs_core.campaign import CampaignError

from ..runtime.campaign_files import (
    Opened,
    cached,
    campaign_path,
    read_campaign,
    relative_names,
)
from .base import Result, Snapshot
from .campaign import scatter_case_result, truncation_case_result, variants_case_result

__all__ = [
    "CASE_DEPENDS",
    "CASES_DEPENDS",
    "case_result",
    "cases_result",
    "open_work",
]

log = logging.getLogger(__name__)

#: The snapshot fields the case table is made of.
CASES_DEPENDS = ("campaign_dir", "campaign_file")
#: The snapshot fields the chosen case's result is made of.
CASE_DEPENDS = (
    *CASES_DEPENDS,
    "campaign_case",
    "campaign_dof",
    "campaign_max",
    "campaign_harmonic",
)


def _problem(s: Snapshot, message: str) -> Result:
    text = relative_names(message, s.campaign_dir)
    return Result(caption=text, draw={"state": "problem", "problem": text})


def _pending(s: Snapshot) -> Result:
    return Result(
        caption=f"Reading {s.campaign_file} ...",
        draw={"state": "pending", "file": s.campaign_file},
    )


def _opened(s: Snapshot) -> Opened | Result | None:
    """The snapshot's file as read so far: :class:`Opened`, a pending or problem result,
    or None (no file chosen)."""
    if not s.campaign_file:
        return None
    try:
        got = cached(campaign_path(s.campaign_dir, s.campaign_file))
    except CampaignError as exc:
        return _problem(s, str(exc))
    return _pending(s) if got is None else got


def open_work(s: Snapshot) -> Callable[[], Any] | None:
    """The reading of the snapshot's campaign file, when it is not read yet (None: read,
    none chosen, or not a file of the folder)."""
    if not _is_pending(_opened(s)):
        return None
    path = campaign_path(s.campaign_dir, s.campaign_file)  # pending: a file of the folder
    return lambda: read_campaign(path)


def _is_pending(r: Any) -> bool:
    return isinstance(r, Result) and r.draw.get("state") == "pending"


def cases_result(s: Snapshot) -> Result | None:
    """The case table of the snapshot's campaign file (``draw["rows"]``: column ->
    tuple of cells, :func:`app.results.campaign.case_rows`), its headline as the
    caption."""
    got = _opened(s)
    if got is None or isinstance(got, Result):
        return got
    rows = MappingProxyType({k: tuple(v) for k, v in got.rows.items()})
    return Result(
        caption=relative_names(got.headline, s.campaign_dir),
        filename=f"{Path(s.campaign_file).stem}_cases.csv",
        draw={"state": "done", "file": s.campaign_file, "rows": rows},
    )


def case_result(s: Snapshot) -> Result | None:
    """The chosen case of the snapshot's campaign file: a scatter case's band, a variants
    case's corridor (at ``campaign_harmonic`` when the case has it, else its first), or a
    truncation case's error map (the maximum over the DOFs with ``campaign_max``)."""
    got = _opened(s)
    if got is None or isinstance(got, Result):
        return got
    name = s.campaign_case
    if not name:
        return None
    result = got.result
    try:
        c = result.case(name)
        if c.kind == "scatter":
            return scatter_case_result(result, name, s.campaign_dof)
        if c.kind == "variants":
            hs = [int(h) for h in c.settings["harmonics"]]
            h = s.campaign_harmonic if s.campaign_harmonic in hs else None
            return variants_case_result(result, name, s.campaign_dof, h)
        dof = None if s.campaign_max else s.campaign_dof
        return truncation_case_result(result, name, dof)
    except CampaignError as exc:  # incomplete, stored without these outputs, malformed
        return _problem(s, str(exc))
    except Exception as exc:  # noqa: BLE001 (a file's problem: said in the card)
        log.exception("campaign case %s of %s", name, s.campaign_file)
        return _problem(s, f"{s.campaign_file}: case {name!r} cannot be shown ({exc})")
