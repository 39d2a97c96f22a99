"""Cached calls into :mod:`fbs_core.analysis` for the Analysis card (issue 18).

Like :mod:`app.compute` (whose caches and model tokens it shares): process-wide caches
keyed by the session's ``Models`` token, so reference results are shared by all sessions
and uploads never mix. The expensive ones (the speed map, the coupled modes near a peak)
are only asked for when their tab is shown; the Campbell diagram depends on the tire only.
No numerics here beyond picking rows and the dB conversion: everything comes from the core.
"""

from __future__ import annotations

import numpy as np

from fbs_core import FRF, analysis
from fbs_core.errors import FBSError
from fbs_core.vocabulary import DIRECTIONS, magnitude_db

from . import compute
from .compute import _key, _models_kw, _n, _tire, shared_cache

__all__ = [
    "campbell",
    "contributions",
    "coupled_frf",
    "peak_modes",
    "peaks",
    "phase_frfs",
    "speed_map",
]


# -- contributions of the interface forces (eq. 4.1 term by term) ----------------------------
def contributions(harmonic: int, n_modes: int, coupling: str, models=None):
    """The contributions of the interface forces on the harmonic's grid, cached.

    For a count the harmonic's truncation map holds (N = 10, 20, ...: the N slider's
    steps), read from the map's interface forces (:func:`fbs_core.analysis.
    map_contributions`: a product, no tire synthesis); otherwise
    :func:`fbs_core.analysis.bushing_contributions`. Both are eq. 4.1 term by term.
    """
    models = _key(models)
    return _contributions(int(harmonic), _n(models, n_modes), coupling, models)


@shared_cache(maxsize=16)
def _contributions(harmonic, n_modes, coupling, models):
    m = compute.error_map(harmonic, coupling, models)
    if m.forces_for(n_modes) is not None:
        return analysis.map_contributions(m, n_modes)
    return analysis.bushing_contributions(
        harmonic,
        n_modes=n_modes,
        freq=compute.frequencies(harmonic),
        coupling=coupling,
        **_models_kw(models),
    )


# -- phase views ------------------------------------------------------------------------------
def coupled_frf(harmonic: int, n_modes: int | None, dof: str, coupling: str, models=None) -> FRF:
    """The coupled response v_e* at ``bushing:<dof>`` as an FRF (``n_modes=None``: all)."""
    v = compute.coupled_response(harmonic, n_modes, coupling, models)[:, DIRECTIONS.index(dof)]
    return FRF(compute.frequencies(harmonic), v[:, None, None], [f"bushing:{dof}"], ["patch"])


def phase_frfs(
    harmonic: int, n_modes: int, dof: str, coupling: str, which: str, spindle_input: str, models
) -> dict:
    """The FRFs of the phase view: ``{"all modes": FRF, "N modes": FRF}`` for the coupled
    response or the tire's free hub velocity, ``{"chassis": FRF}`` for the chassis."""
    f = compute.frequencies(harmonic)
    if which == "coupled":
        return {
            "all modes": coupled_frf(harmonic, None, dof, coupling, models),
            "N modes": coupled_frf(harmonic, n_modes, dof, coupling, models),
        }
    d = compute.uncoupled_data(harmonic, n_modes, dof, spindle_input, models)
    if which == "tire":
        return {
            "all modes": FRF(f, d["tire_reference"][:, None, None], [f"hub:{dof}"], ["patch"]),
            "N modes": FRF(f, d["tire_truncated"][:, None, None], [f"hub:{dof}"], ["patch"]),
        }
    return {
        "chassis": FRF(
            f, d["chassis"][:, None, None], [f"bushing:{dof}"], [f"spindle:{spindle_input}"]
        )
    }


def peaks(frf: FRF, harmonic: int) -> tuple:
    """Automatic peak labels (:func:`fbs_core.analysis.peak_labels`) without the modes."""
    return analysis.peak_labels(frf, harmonic=harmonic, max_peaks=8)


#: Grid (Hz, km/h) to which a peak is snapped before the coupled eigenvalue solve, and the
#: number of modes solved there: a peak that moves a little when N, the DOF or the view
#: changes (the coupled system itself does not depend on N) finds its modes in the cache.
PEAK_SNAP_HZ = 0.5
PEAK_SNAP_KMH = 0.5
PEAK_CANDIDATES = 6


def peak_modes(freq: float, speed_kmh: float, coupling: str, models=None, n: int = 2) -> tuple:
    """The ``n`` modes of the assembled tire + chassis nearest a peak.

    The system is the one at the peak's speed rounded to :data:`PEAK_SNAP_KMH`, solved
    (cached) for the :data:`PEAK_CANDIDATES` modes nearest the peak's frequency rounded
    to :data:`PEAK_SNAP_HZ`; of those, the ``n`` nearest the peak itself are returned.
    Returns ``()`` for models without the physical system (an uploaded modal tire or an
    FRF chassis: the coupled eigenvalues need the assembled system).
    """
    f = float(freq)
    f_snap = max(PEAK_SNAP_HZ, round(f / PEAK_SNAP_HZ) * PEAK_SNAP_HZ)
    v_snap = round(float(speed_kmh) / PEAK_SNAP_KMH) * PEAK_SNAP_KMH
    cand = _peak_modes(f_snap, v_snap, coupling, _key(models), max(PEAK_CANDIDATES, n))
    return tuple(sorted(cand, key=lambda m: abs(m.freq - f))[:n])


@shared_cache(maxsize=256)
def _peak_modes(freq, speed, coupling, models, n):
    try:
        return analysis.coupled_modes_near(
            freq,
            speed,
            coupling,
            n,
            tire=None if models is None else models.tire,
            chassis=None if models is None else models.chassis,
        )
    except (FBSError, AttributeError, TypeError):
        return ()


# -- across speed -----------------------------------------------------------------------------
def campbell(models=None):
    """Campbell diagram of the session's tire (slope criterion: works for any modal model)."""
    return _campbell(_key(models))


@shared_cache(maxsize=8)
def _campbell(models):
    return analysis.campbell(tire=None if models is None else models.tire, fmax=450.0)


def speed_map(harmonic: int, n_modes: int, coupling: str, models=None):
    """:func:`fbs_core.analysis.speed_map` of a harmonic (every 5 km/h), cached."""
    models = _key(models)
    n = _n(models, n_modes)
    return _speed_map(int(harmonic), n, coupling, models)


@shared_cache(maxsize=16)
def _speed_map(harmonic, n_modes, coupling, models):
    return analysis.speed_map(harmonic, n_modes, coupling=coupling, **_models_kw(models))


def tire_speeds(models=None) -> np.ndarray:
    """The operating points of the session's tire in km/h."""
    return np.asarray(_tire(models).speeds, float)


def db(x) -> np.ndarray:
    return magnitude_db(x)
