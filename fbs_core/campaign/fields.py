"""Reading the values of a campaign file: checked against their allowed types and ranges, a
bad one raised as :class:`~fbs_core.errors.CampaignError` naming the key; the case digests
and seeds.

Shared by the campaign's own tables (:mod:`.spec`) and its corridor table (:mod:`.variants`).
"""

from __future__ import annotations

import hashlib
import json
import zlib
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import CampaignError

__all__ = ["case_seed"]


def _digest(settings: dict[str, Any]) -> str:
    text = json.dumps(settings, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def case_seed(campaign_seed: int, name: str) -> int:
    """The seed of one case: ``SeedSequence(campaign_seed, spawn_key=(crc32(name),))``.

    A pure function of the campaign seed and the case's settings (its name), not of the
    case's position in the matrix: adding cases to a campaign leaves the others' seeds.
    """
    ss = np.random.SeedSequence(campaign_seed, spawn_key=(zlib.crc32(name.encode()),))
    return int(ss.generate_state(1, np.uint64)[0])


def _err(where: str, msg: str) -> CampaignError:
    return CampaignError(f"campaign file, {where}: {msg}")


def _table(d: dict[str, Any], key: str, where: str) -> dict[str, Any]:
    v = d.get(key, {})
    if not isinstance(v, dict):
        raise _err(where, f"[{key}] must be a table, got {type(v).__name__}")
    return v


def _known(d: dict[str, Any], allowed: Sequence[str], where: str) -> None:
    bad = sorted(set(d) - set(allowed))
    if bad:
        raise _err(where, f"unknown key(s) {bad}; allowed: {', '.join(allowed)}")


def _list(v: Any, where: str) -> list[Any]:
    return list(v) if isinstance(v, list) else [v]


def _int(v: Any, where: str, lo: int, hi: int | None = None) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < lo or (hi is not None and v > hi):
        rng = f"{lo}..{hi}" if hi is not None else f">= {lo}"
        raise _err(where, f"must be an integer {rng}, got {v!r}")
    return int(v)


def _float(v: Any, where: str, lo: float, hi: float, hi_open: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise _err(where, f"must be a number, got {v!r}")
    x = float(v)
    if not (lo <= x and (x < hi if hi_open else x <= hi)):
        raise _err(where, f"must be in [{lo:g}, {hi:g}{')' if hi_open else ']'}, got {v!r}")
    return x


def _choice(v: Any, allowed: Sequence[str], where: str) -> str:
    if not isinstance(v, str) or v not in allowed:
        raise _err(where, f"{v!r} is not allowed; allowed: {', '.join(allowed)}")
    return v


def _name(v: str, where: str) -> str:
    if not v or not all(c.isalnum() or c in "-." for c in v):
        raise _err(where, f"variant name {v!r} must be letters, digits, '-' or '.'")
    return v
