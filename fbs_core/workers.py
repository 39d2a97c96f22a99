"""Whether a Dask client can take work: shared by the studies that spread over a cluster
(:mod:`fbs_core.variants`) and the campaigns (:mod:`fbs_core.campaign`), below both."""

from __future__ import annotations

from typing import Any

__all__ = ["has_workers"]


def has_workers(client: Any) -> bool:
    """Whether the client's scheduler is connected and has at least one worker."""
    try:
        return client.status == "running" and bool(client.scheduler_info().get("workers"))
    except Exception:  # noqa: BLE001 (a closed or broken connection: no)
        return False
