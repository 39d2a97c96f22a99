"""Cached calls into :mod:`fbs_core.vehicle` for the dashboard's vehicle scope.

The whole car: the reference vehicle with the session's tire on all four wheels (the right
ones mirrored), a harmonic road on both tracks (the rear wheels a wheelbase later), the
response at one of the car's response points. As :mod:`app.compute` for the corner, the
caches are process-wide and keyed by the session's ``Models`` token (``None`` for the
reference tire), so reference results are shared by all sessions and uploads never mix.

- :func:`transfer`: the response per metre of road under each wheel
  (:func:`fbs_core.vehicle.vehicle_transfer`, eq. 4.1 with the four hubs as one
  interface), at the point's six DOFs, for one N (or all modes); a change of wheels or
  track relation only applies another road to it (:meth:`WheelTransfer.apply`).
- :func:`truncation_map`: eq. 5.1 on the car (:func:`fbs_core.vehicle.
  vehicle_truncation_map`); it needs a coherent road (tracks in phase or anti-phase).
- :func:`band`: the scatter band (eqs. 5.2-5.4, :func:`fbs_core.vehicle.
  vehicle_scatter_band`), coherent road as the map.

The car is always the shipped reference vehicle (a car of the user's own is a library
feature, ``FRFVehicle``; the dashboard has no vehicle upload yet).
"""

from __future__ import annotations

import numpy as np

import fbs_core
from fbs_core.errors import FBSError
from fbs_core.vehicle import Road, vehicle_scatter_band, vehicle_transfer, vehicle_truncation_map
from fbs_core.vehicle.response import VehicleResponse, WheelTransfer
from fbs_core.vocabulary import fraction

from ..compute import (
    Q_LEVELS,
    cache_key,
    frequencies,
    remember_band,
    retained,
    shared_cache,
    tire_of,
)
from ..compute import cached_band as compute_cached_band

__all__ = ["band", "band_once", "coherent", "response", "road", "transfer", "truncation_map"]


def _tire_kw(models) -> dict:
    """``tire=`` for the core (nothing for the reference tire: the core's own caches)."""
    return {} if models is None or models.tire is None else {"tire": models.tire}


def coherent(tracks: str | float) -> bool:
    """Whether a track relation is a coherent road (what the studies need)."""
    return tracks in ("in phase", "anti-phase") or (
        not isinstance(tracks, str) and abs(float(tracks)) == 1.0
    )


def road(harmonic: int, tracks: str | float, wheels: tuple[str, ...]) -> Road:
    """The road of a harmonic case on both tracks, ``wheels`` driven."""
    return Road(
        wavelength=fbs_core.harmonic(int(harmonic)).wavelength,
        tracks=tracks,
        wheels=tuple(wheels),
    )


def transfer(
    harmonic: int,
    n_modes: int | None,
    coupling: str,
    point: str,
    models=None,
    residual: bool = False,
) -> WheelTransfer:
    """The car's response at ``point`` (six DOFs) per metre of road under each wheel, with
    ``n_modes`` tire modes (None: all), on the harmonic's analysis grid."""
    models = cache_key(models)
    n = retained(models, n_modes)
    return _transfer(int(harmonic), n, coupling, point, models, bool(residual) and n is not None)


@shared_cache(maxsize=64)
def _transfer(harmonic, n_modes, coupling, point, models, residual) -> WheelTransfer:
    return vehicle_transfer(
        harmonic,
        n_modes,
        frequencies(harmonic),
        coupling,
        outputs=point,
        residual=residual,
        **_tire_kw(models),
    )


def response(
    harmonic: int,
    n_modes: int | None,
    coupling: str,
    point: str,
    tracks: str | float,
    wheels: tuple[str, ...],
    models=None,
    residual: bool = False,
) -> VehicleResponse:
    """The car's response to the harmonic road (``tracks``, ``wheels`` driven)."""
    t = transfer(harmonic, n_modes, coupling, point, models, residual)
    return t.apply(road(harmonic, tracks, wheels))


def truncation_map(
    harmonic: int,
    coupling: str,
    point: str,
    tracks: str | float,
    wheels: tuple[str, ...],
    models=None,
    residual: bool = False,
):
    """Truncation error map (eq. 5.1) of the point's six DOFs, cached.

    Raises
    ------
    FBSError
        For a partially coherent road (the map compares complex responses).
    """
    if not coherent(tracks):
        raise FBSError(
            "the truncation map and the scatter band of the car need a coherent road: tracks "
            f"in phase or in anti-phase (now a coherence of {float(tracks):g})"
        )
    return _truncation_map(
        int(harmonic), coupling, point, tracks, tuple(wheels), cache_key(models), bool(residual)
    )


@shared_cache(maxsize=48)
def _truncation_map(harmonic, coupling, point, tracks, wheels, models, residual):
    n_total = int(tire_of(models).n_modes)
    m = vehicle_truncation_map(
        harmonic,
        np.arange(10, n_total, 10),
        outputs=point,
        tracks=tracks,
        wheels=wheels,
        coupling=coupling,
        residual=residual,
        **_tire_kw(models),
    )
    _MAPS_DONE.add((harmonic, coupling, point, tracks, wheels, models, residual))
    return m


def truncation_map_ready(
    harmonic: int,
    coupling: str,
    point: str,
    tracks: str | float,
    wheels: tuple[str, ...],
    models=None,
    residual: bool = False,
) -> bool:
    """Whether :func:`truncation_map` of these arguments was computed (a suggested table
    of the car reads only the maps computed so far; the rest come in the background)."""
    key = (int(harmonic), coupling, point, tracks, tuple(wheels), cache_key(models), bool(residual))
    return key in _MAPS_DONE


#: Keys of the maps computed (the cache may have dropped some since: then recomputed).
_MAPS_DONE: set = set()


def cached_band(key: tuple, cancel=None, progress=None):
    """:func:`band` of ``key``, from and into the bands' cache of :mod:`app.compute`."""
    res = compute_cached_band(key)
    if res is None:
        res = band(key, cancel=cancel, progress=progress)
        remember_band(key, res)
    return res


def band_once(key: tuple):
    """The car's band of ``key``: the cached one if it was computed, else computed here
    without keeping it (as :func:`app.compute.band_once` for a corner's band)."""
    return compute_cached_band(key) or band(key)


def band(key: tuple, cancel=None, progress=None):
    """The car's scatter band of :func:`app.compute.band_key` ``key`` (with its vehicle
    part ``(wheels, tracks, point)``)."""
    harmonic, n_modes, coupling, noise_pct, target, fdep, rounds, seed, models, vehicle = key
    wheels, tracks, point = vehicle
    if not coherent(tracks):
        truncation_map(harmonic, coupling, point, tracks, wheels)  # raises: the message
    return vehicle_scatter_band(
        harmonic,
        noise=fraction(noise_pct),
        target=target,
        rounds=rounds,
        frequency_dependent=fdep,
        seed=seed,
        outputs=point,
        tracks=tracks,
        wheels=wheels,
        n_modes=n_modes,
        coupling=coupling,
        percentiles=Q_LEVELS,
        cancel=cancel,
        progress=progress,
        **_tire_kw(models),
    )
