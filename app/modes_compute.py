"""Cached calls into the core's mode analyses (issue 30) for the Modes and Selection tabs.

Like :mod:`app.compute` (whose caches and model tokens it shares): process-wide caches
keyed by the session's ``Models`` token, so reference results are shared by all sessions
and uploads never mix. Every function is asked for only while its tab is shown
(:mod:`app.store`); the Campbell diagram of the waves (one dense complex-mode solve per
operating point, about 20 s the first time) is computed on the background worker and
looked up here without solving (:func:`waves_known`). No numerics here beyond choosing
the band: everything comes from :mod:`fbs_core`.
"""

from __future__ import annotations

import threading

import numpy as np

import fbs_core
from fbs_core.analysis import mode_participation, select_modes, tire_mode_shape, wave_campbell
from fbs_core.studies import chassis_truncation_map

from .compute import _key, _models_kw, _tire, shared_cache

__all__ = [
    "chassis_map",
    "participation",
    "participation_band",
    "selection",
    "shape",
    "waves",
    "waves_known",
]

#: Fewest lines a participation band holds (the core needs 3).
MIN_LINES = 3


def participation_band(harmonic: int, f_max: float) -> tuple[float, float]:
    """The band of the participation: the harmonic's band up to ``f_max`` (the truncation
    study's upper frequency), or the whole band when ``f_max`` lies above it or leaves
    fewer than :data:`MIN_LINES` lines."""
    h = fbs_core.harmonic(int(harmonic))
    f = h.frequencies()
    kept = f[f <= float(f_max) + 1e-9]
    hi = float(kept[-1]) if kept.size >= MIN_LINES else float(f[-1])
    return float(f[0]), hi


def participation(harmonic: int, f_max: float, coupling: str, models=None):
    """:func:`fbs_core.analysis.mode_participation` of the harmonic over
    :func:`participation_band`, all six bushing DOFs, cached."""
    band = participation_band(harmonic, f_max)
    return _participation(int(harmonic), band, coupling, _key(models))


@shared_cache(maxsize=32)
def _participation(harmonic, band, coupling, models):
    return mode_participation(harmonic, band, coupling=coupling, **_models_kw(models))


def shape(mode: int, speed_kmh: float, models=None):
    """:func:`fbs_core.analysis.tire_mode_shape` of a stored pair at a speed, cached; the
    speed is clipped to the tire's operating points and rounded to 0.1 km/h."""
    tire = _tire(models)
    v = float(np.clip(round(float(speed_kmh), 1), tire.speeds[0], tire.speeds[-1]))
    return _shape(int(mode), v, _key(models))


@shared_cache(maxsize=64)
def _shape(mode, speed, models):
    return tire_mode_shape(mode, speed, None if models is None else models.tire)


_WAVES_DONE: set = set()  # models whose waves are computed, or failed at once
_WAVES_LOCK = threading.Lock()


def waves(models=None):
    """:func:`fbs_core.analysis.wave_campbell` of the session's tire (its operating
    points, hub free), cached; the first call solves the tire at every operating point.

    Raises
    ------
    FBSError
        For a tire without its matrices (an uploaded modal model); remembered, so that
        :func:`waves_known` says it is known (it fails at once again).
    """
    key = _key(models)
    try:
        return _waves(key)
    finally:
        with _WAVES_LOCK:
            _WAVES_DONE.add(key)


def waves_known(models=None) -> bool:
    """True when :func:`waves` has been called for these models (a look-up: computed,
    or failed at once for a tire without matrices)."""
    with _WAVES_LOCK:
        return _key(models) in _WAVES_DONE


@shared_cache(maxsize=4)
def _waves(models):
    return wave_campbell(None if models is None else models.tire)


#: The orderings of the selected-modes table: by the leave-one-out error as the criterion
#: reads it, and greedy elimination (docs/modes.md, section 2).
SELECTION_ORDERS = ("loo_floating", "greedy")


def selection(
    harmonic: int,
    threshold_pct: float,
    f_max: float,
    by: str,
    residual: bool,
    dof: str | None,
    coupling: str,
    models=None,
):
    """:func:`fbs_core.analysis.select_modes` (threshold in percent), cached."""
    return _selection(
        int(harmonic),
        float(threshold_pct),
        float(f_max),
        by,
        bool(residual),
        dof,
        coupling,
        _key(models),
    )


@shared_cache(maxsize=64)
def _selection(harmonic, threshold_pct, f_max, by, residual, dof, coupling, models):
    return select_modes(
        harmonic,
        threshold_pct / 100.0,
        f_max,
        by=by,
        residual=residual,
        dof=dof,
        coupling=coupling,
        **_models_kw(models),
    )


def chassis_map(harmonic: int, residual: bool, coupling: str, models=None):
    """:func:`fbs_core.studies.chassis_truncation_map` of the harmonic, cached."""
    return _chassis_map(int(harmonic), bool(residual), coupling, _key(models))


@shared_cache(maxsize=32)
def _chassis_map(harmonic, residual, coupling, models):
    return chassis_truncation_map(
        harmonic, residual=residual, coupling=coupling, **_models_kw(models)
    )
