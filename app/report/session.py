"""The report of a dashboard session: its published results, as they are on the page.

:func:`report_data` reads the session's store (:class:`app.store.Results`): the snapshot of
its state and the results published for that very snapshot (the coupled response, the
error map, the suggested modes, the eigenfrequencies, the scatter band when it is of the
current settings, and every other result that is current: the tire's quality, the
uncoupled subsystems while shown, the pins, the shown Analysis tab's results). Nothing is
computed here: the report holds the numbers the page shows, under the page's settings,
residual compensation included.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterable
from typing import Any

from ..state import SCHEMA
from .data import SETTING_KEYS, DataFile, ExtraSection, Provenance, ReportData, ReportError

__all__ = ["BUILTIN_RESULTS", "depends", "provenance_of", "report_data", "settings_of"]

#: Results of the store that the report's own sections show; every other current result
#: (or tuple of them) of the store becomes a section of its own.
BUILTIN_RESULTS = ("response", "error_map", "suggested", "eigen", "band_curves", "band")
#: Results that are no section: the pins themselves (their comparison is, ``pinned``).
NOT_SECTIONS = ("pins", "verdict", "campaign_cases")


def _digests(key: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for part in str(key).split(";"):
        if "=" in part:
            k, v = part.split("=", 1)
            out[k.strip()] = v.strip()
    return out


def provenance_of(models: Any, notes: Iterable[str] = ()) -> Provenance:
    """Reference models or uploaded file names with their digests (an ``app`` ``Models``)."""
    if models is None or models.is_reference:
        return Provenance(notes=tuple(notes))
    dig = _digests(models.key)
    tire = (
        DataFile("tire", models.tire_name or "upload", dig.get("tire"))
        if models.tire is not None
        else DataFile("tire")
    )
    chassis = (
        DataFile("chassis", models.chassis_name or "upload", dig.get("chassis"))
        if models.chassis is not None
        else DataFile("chassis")
    )
    return Provenance(tire=tire, chassis=chassis, notes=tuple(notes))


def settings_of(s: Any, n_axis: str = "linear") -> dict[str, Any]:
    """The report's settings of a session snapshot (:class:`app.results.Snapshot`, or any
    object with its attribute names)."""
    out = {k: getattr(s, k) for k in SETTING_KEYS if hasattr(s, k)}
    out["n_axis"] = n_axis
    if out.get("scope") != "vehicle":  # the car's settings only where they act
        for k in SCHEMA.vehicle_fields:
            out.pop(k, None)
    else:
        out["wheels"] = " ".join(w.upper() for w in out.get("wheels", ())) or "none"
        if out.get("tracks") != "coherence":
            out.pop("coherence", None)
    return out


def _sections(current: dict[str, Any]) -> tuple[ExtraSection, ...]:
    """The sections of the current results beyond :data:`BUILTIN_RESULTS`, in the store's
    table order (a picked point only when one is picked)."""
    from ..results import Result

    out: list[ExtraSection] = []
    for name, value in current.items():
        if name in BUILTIN_RESULTS or name in NOT_SECTIONS:
            continue
        if name == "pick" and value.draw.get("speed") is None and value.draw.get("freq") is None:
            continue
        if name == "response_plot" and not _plot_extras(value):
            continue  # the coupled response as the report shows it already
        if name == "review_curves" and not value.draw["curves"] and value.draw["target"] is None:
            continue  # no other candidate and no target: nothing beside the coupled response
        if name == "review_bands" and not value.draw["curves"]:
            continue  # no other candidate's band
        if name == "campaign" and not value.columns:
            continue  # the campaign case being read, or why it cannot be shown
        if isinstance(value, Result):
            out.append(ExtraSection.of_result(name, value))
        elif isinstance(value, tuple) and all(isinstance(v, Result) for v in value):
            out += [ExtraSection.of_result(f"{name}-{i + 1}", v) for i, v in enumerate(value)]
    return tuple(out)


def _plot_extras(r: Any) -> bool:
    """Whether the response plot's result holds more than the coupled response: overlaid
    DOFs, cursors or the linear level axis (then it is a section of the report)."""
    d = r.draw
    return len(d["curves"]) > 2 or bool(d["cursors"]) or d["scale"] != "dB"


def depends(store: Any) -> frozenset[str]:
    """The state fields the session's report depends on now: those its settings table
    names and those of every result it holds."""
    from ..store import depends as row_depends

    _, current = store.current(looked_at=True)
    out = set(SETTING_KEYS) | {"models"}
    for name in current:
        out |= row_depends(name)
    return frozenset(out)


def report_data(
    store: Any,
    *,
    url: str = "",
    n_axis: str = "linear",
    notes: Iterable[str] = (),
    created: dt.datetime | None = None,
) -> ReportData:
    """The report of a session's store: its current results, read under its lock.

    Parameters
    ----------
    store : app.store.Results
    url : str
        The page URL that reproduces the state.
    n_axis : {"linear", "log"}
        Scale of the error map's N axis on the page.
    notes : sequence of str
        Import notes of the uploads.
    created : datetime, optional
        When the report is made (default now).

    Raises
    ------
    ReportError
        When a result of the page is missing (the session is closed).
    """
    s, current = store.current(looked_at=True)
    outside = dict(getattr(store, "outside", {}))  # views outside the table (a consistency)
    # the car's map and suggested N need a coherent road (with a coherence: not reported)
    needed = ("response", "eigen") if s.vehicle else ("response", "error_map", "suggested", "eigen")
    missing = [n for n in needed if n not in current]
    if missing:
        raise ReportError(f"the page has no current {', '.join(missing)} to report")
    response, error_map = current["response"], current.get("error_map")
    suggested = current.get("suggested")
    band = s.current_band()
    return ReportData(
        settings=settings_of(s, n_axis),
        provenance=provenance_of(s.models, notes),
        url=url,
        created=created or dt.datetime.now(dt.UTC),
        reference=response.core["reference"],
        truncated=response.core["truncated"],
        truncation=error_map.core["map"] if error_map is not None else None,
        suggested=suggested.core.get("shown") if suggested is not None else None,
        band=band.result if band is not None else None,
        eigen=current["eigen"].core["eigen"],
        suggested_n=int(error_map.draw["suggested_n"]) if error_map is not None else None,
        peaks=tuple(response.core.get("peaks", ())),
        contributions=(
            current["contributions"].core.get("contributions")
            # the Contributions tab is the corner's: a car's report has none of its own
            if "contributions" in current and not s.vehicle
            else None
        ),
        extra=_sections(current) + _sections(outside),
        verdict=current["verdict"].core.get("verdict") if "verdict" in current else None,
    )
