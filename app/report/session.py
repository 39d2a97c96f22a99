"""A report snapshot of a dashboard session: its settings, its data and its results.

Reads the session's :class:`~app.state.DashboardState` (plain values) and takes the results
from the app's caches (:mod:`app.compute`): the same objects the views show, so the report
holds what the page showed. The scatter band is passed in (the one on the page) and only kept
when it was computed for the current settings.
"""

from __future__ import annotations

import datetime as dt

import numpy as np

import fbs_core
from fbs_core import studies

from .. import compute
from .snapshot import DataFile, ExtraSection, Provenance, Snapshot

__all__ = [
    "settings_of",
    "provenance_of",
    "session_snapshot",
    "band_matches",
    "store_sections",
    "BUILTIN_RESULTS",
]

_DIRS = ("x", "y", "z", "rx", "ry", "rz")


def settings_of(state, n_axis: str = "linear") -> dict:
    """The settings of a ``DashboardState`` as the plain dict of a report snapshot."""
    c, n, t = state.case, state.noise, state.truncation
    return dict(
        harmonic=int(c.harmonic),
        n_modes=int(c.n_modes),
        dof=str(c.dof),
        coupling=str(c.coupling),
        threshold=float(t.threshold),
        f_max=float(t.f_max),
        map_mode=str(t.map_mode),
        n_axis=n_axis,
        noise=float(n.noise),
        target=str(n.target),
        frequency_dependent=bool(n.frequency_dependent),
        rounds=int(n.rounds),
        seed=int(n.seed),
        single_round=int(n.single_round),
        percentile=int(n.percentile),
    )


def _digests(key: str) -> dict[str, str]:
    out = {}
    for part in str(key).split(";"):
        if "=" in part:
            k, v = part.split("=", 1)
            out[k.strip()] = v.strip()
    return out


def provenance_of(models, notes=()) -> Provenance:
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


def band_matches(band, settings: dict, models=None) -> bool:
    """True when ``band`` (a ScatterBand) was computed for these settings."""
    if band is None:
        return False
    s = settings
    return bool(
        band.harmonic == s["harmonic"]
        and abs(band.noise * 100 - s["noise"]) <= 1e-9 * max(1.0, s["noise"])
        and band.target == s["target"]
        and band.frequency_dependent == s["frequency_dependent"]
        and band.rounds == s["rounds"]
        and band.seed == s["seed"]
    )


#: Results of the store that the report's own sections show; every other published
#: ``Result`` (or tuple of them) of the store becomes a section of its own.
BUILTIN_RESULTS = ("response", "error_map", "suggested", "eigen", "band_curves")


def store_sections(store) -> tuple[ExtraSection, ...]:
    """The sections other views contribute: each published :class:`app.store.Result`
    parameter of ``store`` beyond :data:`BUILTIN_RESULTS` (and the uncoupled subsystems only
    while the page shows them), in the store's parameter order.

    A view that wants its result in the report publishes it as a parameter of the store
    (``param.ClassSelector(class_=Result)``, or a tuple of results, e.g. pinned curves);
    nothing in :mod:`app.report` needs to change.
    """
    from ..store import Result

    out = []
    for name in store.param:
        if name in BUILTIN_RESULTS:
            continue
        if name == "uncoupled" and not store.state.case.show_uncoupled:
            continue
        value = getattr(store, name, None)
        if isinstance(value, Result):
            out.append(ExtraSection.of_result(name, value))
        elif isinstance(value, (tuple, list)) and value:
            if all(isinstance(v, Result) for v in value):
                out += [ExtraSection.of_result(f"{name}-{i + 1}", v) for i, v in enumerate(value)]
    return tuple(out)


def _frf(freq, data) -> fbs_core.FRF:
    return fbs_core.FRF(
        np.asarray(freq, float),
        np.asarray(data)[:, :, None],
        [f"bushing:{d}" for d in _DIRS],
        ["patch"],
    )


def session_snapshot(
    state,
    *,
    url: str = "",
    band=None,
    band_n_modes: int | None = None,
    n_axis: str = "linear",
    notes=(),
    created: dt.datetime | None = None,
    extra=(),
) -> Snapshot:
    """The report snapshot of a session's current state.

    Parameters
    ----------
    state : app.state.DashboardState
    url : str
        The page URL that reproduces the state.
    band : fbs_core.ScatterBand, optional
        The band on the page; kept only if it matches the settings (and ``band_n_modes``,
        the N it was computed with, equals the chosen N).
    n_axis : {"linear", "log"}
        Scale of the error map's N axis on the page.
    notes : sequence of str
        Import notes of the uploads.
    extra : sequence of ExtraSection
        Sections of other views (:func:`store_sections` of the page's store).
    """
    s = settings_of(state, n_axis)
    models = state.case.models
    k, coupling = s["harmonic"], s["coupling"]
    m = compute.error_map(k, coupling, models)
    ref = compute.coupled_response(k, None, coupling, models)
    tr = compute.coupled_response(k, s["n_modes"], coupling, models)
    map_dof = f"bushing:{s['dof']}" if s["map_mode"] == "selected DOF" else None
    sugg = studies.suggest_modes(
        s["threshold"] / 100.0,
        s["f_max"],
        maps=[compute.error_map(h, coupling, models) for h in range(1, 8)],
        dof=map_dof,
        tire=None if models is None else models.tire,
    )
    eigen = studies.mode_frequencies(
        compute.EIGEN_SPEEDS, tire=None if models is None else models.tire
    )
    keep = band_matches(band, s, models) and band_n_modes in (None, s["n_modes"])
    return Snapshot(
        settings=s,
        provenance=provenance_of(models, notes),
        url=url,
        created=created or dt.datetime.now(dt.UTC),
        reference=_frf(m.freq, ref),
        truncated=_frf(m.freq, tr),
        truncation=m,
        suggested=sugg,
        band=band if keep else None,
        eigen=eigen,
        n_modes_total=m.n_modes_total,
        extra=tuple(extra),
    )
