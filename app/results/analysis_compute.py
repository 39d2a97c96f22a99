"""Cached calls into :mod:`fbs_core.analysis` for the Analysis card.

Like :mod:`app.compute` (whose caches and model tokens it shares): process-wide caches
keyed by the session's ``Models`` token, so reference results are shared by all sessions
and uploads never mix. The expensive ones (the speed map, the coupled modes near a peak)
are only asked for when their tab is shown (:mod:`app.store`); the Campbell diagram
depends on the tire only. No numerics here beyond picking rows: everything comes from the
core.
"""

from __future__ import annotations

import threading
from collections import OrderedDict

from fbs_core import FRF, analysis
from fbs_core.errors import FBSError

from .. import compute
from ..compute import cache_key, models_kw, retained, shared_cache

__all__ = [
    "campbell",
    "contributions",
    "peak_modes",
    "peaks",
    "speed_map",
    "uncoupled_frfs",
]


# -- contributions of the interface forces (eq. 4.1 term by term) ----------------------------
def contributions(harmonic: int, n_modes: int, coupling: str, models=None, residual=False):
    """The contributions of the interface forces on the harmonic's grid, cached.

    For a count the harmonic's truncation map holds (N = 10, 20, ...: the N slider's
    steps), read from the map's interface forces (:func:`fbs_core.analysis.
    map_contributions`: a product, no tire synthesis); otherwise
    :func:`fbs_core.analysis.bushing_contributions`. Both are eq. 4.1 term by term.
    ``residual``: of the residual-compensated response (read from the residual map, which
    holds every count below the tire's total: the others have no mode left out).

    Raises
    ------
    FBSError
        For residual compensation of a count the residual map does not hold.
    """
    models = cache_key(models)
    n = retained(models, n_modes)
    return _contributions(int(harmonic), n, coupling, models, bool(residual) and n is not None)


@shared_cache(maxsize=16)
def _contributions(harmonic, n_modes, coupling, models, residual=False):
    m = compute.error_map(harmonic, coupling, models, residual)
    if m.forces_for(n_modes) is not None:
        return analysis.map_contributions(m, n_modes)
    if residual:
        raise FBSError(
            f"no contributions with residual compensation for N = {n_modes}: the residual "
            f"map holds N = {', '.join(str(int(n)) for n in m.n_modes)}"
        )
    return analysis.bushing_contributions(
        harmonic,
        n_modes=n_modes,
        freq=compute.frequencies(harmonic),
        coupling=coupling,
        **models_kw(models),
    )


# -- phase views ------------------------------------------------------------------------------
def uncoupled_frfs(
    harmonic: int, n_modes: int, dof: str, which: str, spindle_input: str, models
) -> dict[str, FRF]:
    """The uncoupled FRFs of the phase view: ``{"all modes", "N modes"}`` of the tire's
    free hub velocity (``which="tire"``), ``{"chassis": FRF}`` for the chassis mobility."""
    f = compute.frequencies(harmonic)
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


#: Coupled modes solved so far (snapped point -> candidates), looked up without solving.
_KNOWN: OrderedDict = OrderedDict()
_KNOWN_LOCK = threading.Lock()
KNOWN_SIZE = 256


def peak_modes(
    freq: float, speed_kmh: float, coupling: str, models=None, n: int = 2, known_only=False
) -> tuple | None:
    """The ``n`` modes of the assembled tire + chassis nearest a peak.

    The system is the one at the peak's speed rounded to :data:`PEAK_SNAP_KMH`, solved
    (cached) for the :data:`PEAK_CANDIDATES` modes nearest the peak's frequency rounded
    to :data:`PEAK_SNAP_HZ`; of those, the ``n`` nearest the peak itself are returned.
    Returns ``()`` for models without the physical system (an uploaded modal tire or an
    FRF chassis: the coupled eigenvalues need the assembled system). ``known_only``:
    None instead of solving when the modes are not known yet.
    """
    f = float(freq)
    f_snap = max(PEAK_SNAP_HZ, round(f / PEAK_SNAP_HZ) * PEAK_SNAP_HZ)
    v_snap = round(float(speed_kmh) / PEAK_SNAP_KMH) * PEAK_SNAP_KMH
    args = (f_snap, v_snap, coupling, cache_key(models), max(PEAK_CANDIDATES, n))
    with _KNOWN_LOCK:
        cand = _KNOWN.get(args)
    if cand is None:
        if known_only:
            return None
        cand = _peak_modes(*args)
        with _KNOWN_LOCK:
            _KNOWN[args] = cand
            while len(_KNOWN) > KNOWN_SIZE:
                _KNOWN.popitem(last=False)
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
    return _campbell(cache_key(models))


@shared_cache(maxsize=8)
def _campbell(models):
    return analysis.campbell(tire=None if models is None else models.tire, fmax=450.0)


def speed_map(harmonic: int, n_modes: int, coupling: str, models=None):
    """:func:`fbs_core.analysis.speed_map` of a harmonic (every 5 km/h), cached."""
    models = cache_key(models)
    n = retained(models, n_modes)
    return _speed_map(int(harmonic), n, coupling, models)


@shared_cache(maxsize=16)
def _speed_map(harmonic, n_modes, coupling, models):
    return analysis.speed_map(harmonic, n_modes, coupling=coupling, **models_kw(models))
