"""A report snapshot of a dashboard session: its settings, its data and its results.

Reads the session's :class:`~app.state.DashboardState` (plain values) and takes the results
from the app's caches (:mod:`app.compute`): the same objects the views show, so the report
holds what the page showed. The scatter band is passed in (the one on the page) and only kept
when it was computed for the current settings.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

import fbs_core
from fbs_core import studies
from fbs_core.vocabulary import fraction, percent

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


def settings_of(state: Any, n_axis: str = "linear") -> dict[str, Any]:
    """The settings of a ``DashboardState`` as the plain dict of a report snapshot.

    Read through :meth:`app.store.Snapshot.of` (the one place that reads a state's values).
    """
    from ..store import Snapshot as StateSnapshot

    return _settings(StateSnapshot.of(state), n_axis)


def _settings(st: Any, n_axis: str) -> dict[str, Any]:
    """The report's settings of an :class:`app.store.Snapshot` of the state."""
    return dict(
        harmonic=st.harmonic,
        n_modes=st.n_modes,
        dof=str(st.dof),
        coupling=str(st.coupling),
        threshold=st.threshold,
        f_max=st.f_max,
        map_mode=str(st.map_mode),
        n_axis=n_axis,
        noise=st.noise,
        target=str(st.target),
        frequency_dependent=st.frequency_dependent,
        rounds=st.rounds,
        seed=st.seed,
        single_round=st.single_round,
        percentile=st.percentile,
    )


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


def band_matches(band: Any, settings: Mapping[str, Any], models: Any = None) -> bool:
    """True when ``band`` (a ScatterBand) was computed for these settings."""
    if band is None:
        return False
    s = settings
    return bool(
        band.harmonic == s["harmonic"]
        and abs(percent(band.noise) - s["noise"]) <= 1e-9 * max(1.0, s["noise"])
        and band.target == s["target"]
        and band.frequency_dependent == s["frequency_dependent"]
        and band.rounds == s["rounds"]
        and band.seed == s["seed"]
    )


#: Results of the store that the report's own sections show; every other published
#: ``Result`` (or tuple of them) of the store becomes a section of its own.
BUILTIN_RESULTS = ("response", "error_map", "suggested", "eigen", "band_curves")


def store_sections(store: Any) -> tuple[ExtraSection, ...]:
    """The sections other views contribute: each published :class:`app.store.Result`
    parameter of ``store`` beyond :data:`BUILTIN_RESULTS` (and the uncoupled subsystems only
    while the page shows them), in the store's parameter order.

    A view that wants its result in the report publishes it as a parameter of the store
    (``param.ClassSelector(class_=Result)``, or a tuple of results, e.g. pinned curves);
    nothing in :mod:`app.report` needs to change.
    """
    from ..store import Result

    out: list[ExtraSection] = []
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


def _frf(freq: Any, data: Any) -> fbs_core.FRF:
    return fbs_core.FRF(
        np.asarray(freq, float),
        np.asarray(data)[:, :, None],
        [f"bushing:{d}" for d in _DIRS],
        ["patch"],
    )


def session_snapshot(
    state: Any,
    *,
    url: str = "",
    band: Any = None,
    band_n_modes: int | None = None,
    n_axis: str = "linear",
    notes: Iterable[str] = (),
    created: dt.datetime | None = None,
    extra: Sequence[ExtraSection] = (),
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
    from ..store import Snapshot as StateSnapshot

    st = StateSnapshot.of(state)
    s = _settings(st, n_axis)
    models = st.models
    k, coupling = s["harmonic"], s["coupling"]
    m = compute.error_map(k, coupling, models)
    ref = compute.coupled_response(k, None, coupling, models)
    tr = compute.coupled_response(k, s["n_modes"], coupling, models)
    map_dof = None if st.map_dof is None else f"bushing:{st.map_dof}"
    sugg = studies.suggest_modes(
        fraction(s["threshold"]),
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
