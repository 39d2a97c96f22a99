"""Cached calls into the core's mode analyses for the Modes and Selection tabs.

Like :mod:`app.compute` (whose caches and model tokens it shares): process-wide caches
keyed by the session's ``Models`` token, so reference results are shared by all sessions
and uploads never mix. Every function is asked for only while its tab is shown
(:mod:`app.store`); the Campbell diagram of the waves (one dense complex-mode solve per
operating point; the reference tire's is stored) is computed once per tire for every
session on a thread of its own (:data:`WAVES`), asked for with :func:`request_waves` and
looked up without solving with :func:`waves_status`. No numerics here beyond choosing
the band: everything comes from :mod:`fbs_core`.
"""

from __future__ import annotations

import numpy as np

import fbs_core
from fbs_core.analysis import mode_participation, select_modes, tire_mode_shape, wave_campbell
from fbs_core.errors import FBSError
from fbs_core.studies import chassis_truncation_map

from ..compute import cache_key, models_kw, shared_cache, tire_of
from ..runtime.shared_jobs import JobStatus, SharedJobs

__all__ = [
    "chassis_map",
    "participation",
    "participation_band",
    "selection",
    "shape",
    "request_waves",
    "waves",
    "waves_status",
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
    return _participation(int(harmonic), band, coupling, cache_key(models))


@shared_cache(maxsize=32)
def _participation(harmonic, band, coupling, models):
    return mode_participation(harmonic, band, coupling=coupling, **models_kw(models))


def shape(mode: int, speed_kmh: float, models=None):
    """:func:`fbs_core.analysis.tire_mode_shape` of a stored pair at a speed, cached; the
    speed is clipped to the tire's operating points and rounded to 0.1 km/h."""
    tire = tire_of(models)
    v = float(np.clip(round(float(speed_kmh), 1), tire.speeds[0], tire.speeds[-1]))
    return _shape(int(mode), v, cache_key(models))


@shared_cache(maxsize=64)
def _shape(mode, speed, models):
    return tire_mode_shape(mode, speed, None if models is None else models.tire)


#: How long the waves' diagram of a tire may take before its waiters are told why (s): the
#: reference tire's is stored (well under a second); an uploaded tire's takes about 12 s of
#: dense solves on an idle core, minutes on a busy one.
WAVES_DEADLINE_S = 45.0

#: The waves' diagrams of the sessions' tires: one computation per tire for every session,
#: on a thread of its own at the server's priority, each waiter told how it moves.
WAVES = SharedJobs("fbs-waves", threads=1, deadline_s=WAVES_DEADLINE_S)


def _waves_job(models):
    tire = None if models is None else models.tire

    def work(progress):
        return wave_campbell(tire, progress=progress)

    return work


def _no_matrices(models) -> JobStatus | None:
    """A failed status at once for a tire without its matrices (an uploaded modal model),
    else None."""
    tire = tire_of(models)
    if getattr(tire, "params", None) is not None:
        return None
    try:
        wave_campbell(tire)  # raises at once, before any solve
    except (FBSError, AttributeError, TypeError) as e:
        return JobStatus("failed", message=f"the tire's matrices are needed: {e}")
    return None  # (not reached: a tire without parameters has no matrices)


def waves_status(models=None) -> JobStatus | None:
    """Where the waves' diagram of the session's tire stands (a look-up: nothing is
    computed): None when nobody asked for it yet, else a :class:`JobStatus` (its ``value``
    the :class:`~fbs_core.analysis.WaveCampbell` once done)."""
    return _no_matrices(models) or WAVES.status(("waves", cache_key(models)))


def request_waves(models=None, listener_key=None, listener=None) -> JobStatus:
    """Ask for the waves' diagram of the session's tire (see :data:`WAVES`); ``listener``
    is told of its progress, its end or its failure."""
    return _no_matrices(models) or WAVES.request(
        ("waves", cache_key(models)), _waves_job(cache_key(models)), listener_key, listener
    )


def waves(models=None, timeout: float = 600.0):
    """:func:`fbs_core.analysis.wave_campbell` of the session's tire (its operating
    points, hub free), computed here or waited for (no page to be told on: tests, exports).

    Raises
    ------
    FBSError
        For a tire without its matrices (an uploaded modal model), or when the computation
        failed or did not end within ``timeout`` seconds (the message says which).
    """
    st = _no_matrices(models) or WAVES.run_here(
        ("waves", cache_key(models)), _waves_job(cache_key(models)), timeout
    )
    if st.state == "done":
        return st.value
    raise FBSError(st.describe("solving the tire's modes at its operating points"))


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
        cache_key(models),
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
        **models_kw(models),
    )


def chassis_map(harmonic: int, residual: bool, coupling: str, models=None):
    """:func:`fbs_core.studies.chassis_truncation_map` of the harmonic, cached."""
    return _chassis_map(int(harmonic), bool(residual), coupling, cache_key(models))


@shared_cache(maxsize=32)
def _chassis_map(harmonic, residual, coupling, models):
    return chassis_truncation_map(
        harmonic, residual=residual, coupling=coupling, **models_kw(models)
    )
