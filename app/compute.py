"""Cached calls into the core's studies, shaped for the results of :mod:`app.results`.

The studies the dashboard shows are computed here (:mod:`app.results.analysis_compute` for the
Analysis card's): results are cached per argument tuple (the core result objects are
immutable), so that a control change that only selects (another response DOF, another N
of the truncation map) costs a lookup. No statistics are computed here: the band's own
(its percentiles' confidence, :meth:`fbs_core.ScatterBand.percentile_confidence_db`) are
methods of the core's result; what is added is the conversion to dB for display
(:func:`fbs_core.vocabulary.magnitude_db`) and the selection of one DOF's columns.

The coupled response for N retained modes is read from the harmonic's truncation map
(:func:`fbs_core.studies.truncation_map` computes the eq. 4.1 response for every
N = 10, 20, ... at once with the modal model's cumulative truncation), so moving the N slider
costs no new coupling.

Every function takes the session's ``models`` (an :class:`app.datasource.Models` token:
the uploaded tire and chassis, or None / the reference); the token is part of the cache key
(it is hashed by a digest of the uploaded bytes), so uploads never mix with the reference
results nor with each other's.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass
from functools import lru_cache, wraps
from typing import Any, NamedTuple

import numpy as np

import fbs_core
from fbs_core import studies
from fbs_core.units import frf_unit, output_kind
from fbs_core.vocabulary import (
    DB_FLOOR,
    DIRECTIONS,
    EIGEN_SPEEDS,
    fraction,
    magnitude_db,
    percent,
    readonly,
)

__all__ = [
    "DB_FLOOR",
    "EIGEN_SPEEDS",
    "PERCENTILE_BANDS",
    "Q_LEVELS",
    "BandKey",
    "BandTime",
    "band",
    "band_once",
    "band_computed",
    "band_data",
    "cache_key",
    "chassis_of",
    "coupled_response",
    "eigen_curves",
    "error_map",
    "error_map_data",
    "frequencies",
    "level_unit",
    "mobility_data",
    "models_kw",
    "retained",
    "single_round_data",
    "suggested_table",
    "suggested_table_ready",
    "tire_of",
    "tire_quality",
    "uncoupled_data",
    "version",
]

#: Central percentile bands offered (width in %) and the percentile levels they need.
PERCENTILE_BANDS = (50, 80, 90, 95, 99)
Q_LEVELS = tuple(sorted({q for w in PERCENTILE_BANDS for q in ((100 - w) / 2, (100 + w) / 2)}))


_thread_kind = threading.local()


def mark_background() -> None:
    """Mark the calling thread as background work (app/runtime/background.py): a session's thread
    that needs a result such a thread is computing computes it itself (see shared_cache)."""
    _thread_kind.background = True


def in_background() -> bool:
    """True on a thread marked by :func:`mark_background`."""
    return bool(getattr(_thread_kind, "background", False))


#: Every function of :func:`shared_cache`, for :func:`clear_shared_caches`.
_SHARED_CACHES: list = []


def clear_shared_caches() -> None:
    """Empty every :func:`shared_cache` of the process (tests: a build that computes)."""
    for wrapper in _SHARED_CACHES:
        wrapper.cache_clear()


#: Longest a thread waits for another thread's computation of the same entry (s); then it
#: computes the entry itself (the owner may be stuck: a wait never lasts forever).
SHARED_WAIT_S = 90.0

#: How often a waiting thread looks whether the owner of the computation is still alive (s).
_OWNER_POLL_S = 0.5


class _Entry:
    """A computation of one cache entry under way: who computes it, and how it ended."""

    __slots__ = ("done", "background", "owner", "error")

    def __init__(self, background: bool) -> None:
        self.done = threading.Event()
        self.background = background
        self.owner = threading.current_thread()
        self.error: BaseException | None = None

    def wait(self, deadline_s: float) -> bool:
        """Wait until the owner finished (True), or its thread ended without finishing or
        ``deadline_s`` passed (False: the caller computes it itself)."""
        t_end = time.monotonic() + deadline_s
        while not self.done.wait(min(_OWNER_POLL_S, max(t_end - time.monotonic(), 0.0))):
            if not self.owner.is_alive() or time.monotonic() >= t_end:
                return self.done.is_set()
        return True


def shared_cache(maxsize: int):
    """``functools.lru_cache`` that computes a missing entry once for all threads.

    Sessions run their callbacks on a thread pool; when several of them ask for the same
    missing result at once (a review meeting opening the same link, many tabs loading the
    default view), the first computes it and the others wait for it instead of computing
    it again beside it on the same cores. A wait has a deadline: the waiting thread
    computes the entry itself when the owner's thread ended without finishing it or after
    :data:`SHARED_WAIT_S` (a stuck or very slow owner never holds a session for ever).
    When the owner's computation raises, every thread that waited for it gets the same
    error (it is not computed again by each of them); the next call tries again.
    """

    def decorate(fn):
        cached = lru_cache(maxsize=maxsize)(fn)
        guard = threading.Lock()
        running: dict = {}

        @wraps(fn)
        def wrapper(*args):
            me = in_background()
            with guard:
                found = running.get(args)
                mine = found is None
                entry = running[args] = _Entry(me) if found is None else found
            if not mine:
                if entry.background and not me:
                    # never wait for a low-priority thread (app/runtime/background.py): on a busy
                    # machine it runs at a fraction of a core; compute it here instead
                    return cached(*args)
                if entry.wait(wrapper.wait_s):
                    if entry.error is not None:
                        raise entry.error  # the owner's failure, reported to every waiter
                    return cached(*args)  # a hit
                if not entry.owner.is_alive():  # lost: the next callers need not wait for it
                    with guard:
                        if running.get(args) is entry:
                            del running[args]
                return cached(*args)  # computed here (owner gone or too slow)
            try:
                return cached(*args)
            except BaseException as e:
                entry.error = e
                raise
            finally:
                with guard:
                    if running.get(args) is entry:
                        del running[args]
                entry.done.set()

        wrapper.cache_clear = cached.cache_clear
        wrapper.cache_info = cached.cache_info
        wrapper.wait_s = SHARED_WAIT_S
        wrapper.running = running  # the computations under way (tests)
        _SHARED_CACHES.append(wrapper)
        return wrapper

    return decorate


def version() -> str:
    return str(getattr(fbs_core, "__version__", "unknown"))


def level_unit(dof: str) -> str:
    """Display unit of a velocity response to the patch input for a DOF direction.

    The ``patch`` input of the reference tire is a unit road wave (1 m amplitude), so
    responses are m/s (rad/s) per metre of road amplitude (``fbs_core.bushing_response``).
    """
    d = dof.split(":")[-1]
    return f"dB re 1 {frf_unit(output_kind(f'bushing:{d}'), 'road', 'mobility')}"


@shared_cache(maxsize=8)
def frequencies(harmonic: int) -> np.ndarray:
    """The analysis grid of a harmonic case in Hz (read-only)."""
    return readonly(fbs_core.harmonic(harmonic).frequencies(), float)


def cache_key(models):
    """The models' part of a cache key: ``None`` for the reference models, else the
    (hashable) session models token."""
    return None if models is None or models.is_reference else models


def tire_of(models=None):
    """The session's tire model (the reference tire when none is uploaded)."""
    t = None if models is None else models.tire
    return fbs_core.reference_tire() if t is None else t


def chassis_of(models=None):
    """The session's chassis (the reference chassis when none is uploaded)."""
    c = None if models is None else models.chassis
    return fbs_core.reference_chassis() if c is None else c


def models_kw(models) -> dict:
    """``tire=`` / ``chassis=`` for the core (None keeps the core's reference caches)."""
    return {} if models is None else {"tire": models.tire, "chassis": models.chassis}


def retained(models, n_modes):
    """A retained-mode count the session's tire has (``None``: all of its modes)."""
    if n_modes is None or int(n_modes) >= tire_of(models).n_modes:
        return None
    return int(n_modes)


# -- truncation study and coupled response ---------------------------------------------------
def error_map(harmonic: int, coupling: str, models=None, residual: bool = False):
    """Truncation error map of a harmonic (thesis figs. 5.3, 5.6, 5.7), cached.

    Holds the coupled responses for every N of the map and the all-modes reference too.
    The counts are 10, 20, ... below the tire's total (the total is the reference itself).
    ``residual``: the N-mode responses compensated by the quasi-static part of the modes
    left out (the reference stays the all-modes response).
    """
    return _error_map(int(harmonic), coupling, cache_key(models), bool(residual))


@shared_cache(maxsize=48)
def _error_map(harmonic: int, coupling: str, models, residual: bool = False):
    n_total = int(tire_of(models).n_modes)
    return studies.truncation_map(
        harmonic,
        n_modes=np.arange(10, n_total, 10),
        coupling=coupling,
        residual=residual,
        **models_kw(models),
    )


@shared_cache(maxsize=64)
def _bushing_response(
    harmonic: int, n_modes: int | None, coupling: str, models=None, residual: bool = False
) -> np.ndarray:
    frf = fbs_core.bushing_response(
        harmonic,
        n_modes=n_modes,
        freq=frequencies(harmonic),
        coupling=coupling,
        residual=residual,
        **models_kw(models),
    )
    return np.stack(
        [frf.sel(outputs=f"bushing:{d}").data[:, 0, 0] for d in DIRECTIONS],
        axis=1,
    )


def coupled_response(
    harmonic: int, n_modes: int | None, coupling: str, models=None, residual: bool = False
) -> np.ndarray:
    """Bushing velocity v_e* (eq. 4.1), shape ``(n_freq, 6)`` for ``bushing:x`` ... ``rz``.

    ``n_modes=None`` is the all-modes reference. Read from the cached truncation map when it
    holds that N (:meth:`fbs_core.studies.TruncationMap.response_for`), else computed with
    :func:`fbs_core.bushing_response`; ``residual`` compensates the modes left out.
    """
    models = cache_key(models)
    n = retained(models, n_modes)
    residual = bool(residual) and n is not None  # all modes: nothing left out
    m = error_map(harmonic, coupling, models, residual)
    order = [m.dofs.index(f"bushing:{d}") for d in DIRECTIONS]
    row = m.response_for(n)
    if row is not None:
        return row[:, order]
    return _bushing_response(harmonic, n, coupling, models, residual)


def mobility_data(
    harmonic: int, n_modes: int, dof: str, coupling: str, models=None, residual: bool = False
) -> dict:
    """Columns of the coupled-response view: reference (all modes) and truncated (N modes,
    with ``residual`` compensated by the quasi-static part of the modes left out).

    Returns
    -------
    dict
        ``freq`` (Hz), ``reference`` and ``truncated`` (complex v_e*), ``reference_db`` and
        ``truncated_db`` (dB), each of shape ``(n_freq,)``.
    """
    j = DIRECTIONS.index(dof)
    ref = coupled_response(harmonic, None, coupling, models)[:, j]
    trunc = coupled_response(harmonic, int(n_modes), coupling, models, residual)[:, j]
    return {
        "freq": np.asarray(error_map(harmonic, coupling, models).freq, float),
        "reference": ref,
        "truncated": trunc,
        "reference_db": magnitude_db(ref),
        "truncated_db": magnitude_db(trunc),
    }


def error_map_data(
    harmonic: int, coupling: str, dof: str | None, models=None, residual: bool = False
) -> dict:
    """Error in percent over retained modes and centre frequency.

    ``dof=None`` gives the maximum over the 6 bushing DOFs (fig. 5.6); ``residual``: the
    N-mode responses with residual compensation.

    Returns
    -------
    dict
        ``centre_freq`` (n_c,), ``n_modes`` (n_N,), ``error_pct`` (n_N, n_c).
    """
    m = error_map(harmonic, coupling, models, residual)
    err = m.max_error if dof is None else m.dof_error(f"bushing:{dof}")
    return {
        "centre_freq": np.asarray(m.centres, float),
        "n_modes": np.asarray(m.n_modes, int),
        "error_pct": percent(np.asarray(err, float)),
    }


def suggested_table(
    threshold_pct: float,
    f_max: float,
    coupling: str,
    dof: str | None = None,
    models=None,
    residual: bool = False,
) -> dict:
    """Suggested number of modes for all seven harmonics (thesis table 5.1).

    ``dof=None`` judges the maximum error over the 6 DOFs (as the thesis' table);
    ``residual``: judged on the residual-compensated responses. ``result`` is the core's
    :class:`~fbs_core.studies.SuggestedModes` the columns come from.
    """
    key = (float(threshold_pct), float(f_max), coupling, dof, cache_key(models), bool(residual))
    out = _suggested_table(*key)
    _TABLES_DONE.add(key)
    return out


#: Argument tuples of suggested tables computed so far (a look-up, no computation).
_TABLES_DONE: set = set()


def suggested_table_ready(
    threshold_pct: float,
    f_max: float,
    coupling: str,
    dof: str | None = None,
    models=None,
    residual: bool = False,
) -> bool:
    """True when :func:`suggested_table` of these arguments has been computed before
    (then it is a cache look-up, unless the cache has dropped it since)."""
    key = (float(threshold_pct), float(f_max), coupling, dof, cache_key(models), bool(residual))
    return key in _TABLES_DONE


@shared_cache(maxsize=64)
def _suggested_table(threshold_pct, f_max, coupling, dof, models, residual=False) -> dict:
    maps = [error_map(k, coupling, models, residual) for k in range(1, 8)]
    s = studies.suggest_modes(
        threshold=fraction(threshold_pct),
        f_max=f_max,
        maps=maps,
        dof=None if dof is None else f"bushing:{dof}",
        tire=None if models is None else models.tire,
    )
    return {
        "harmonic": np.asarray(s.harmonics, int),
        "f_low": np.asarray(s.freq_range[:, 0], float),
        "f_high": np.asarray(s.freq_range[:, 1], float),
        "n_modes": np.asarray(s.n_modes, int),
        "eigenfrequency": np.asarray(s.eigenfrequency, float),
        "speed": float(s.speed),
        "result": s,
    }


def tire_quality(models=None) -> dict:
    """How far the session's tire can be trusted between and beyond its operating points.

    Computed once per tire (cached by the models token): the leave-one-out interpolation
    error per harmonic band (:func:`fbs_core.tire.quality.interpolation_quality`: every
    interior operating point predicted from its neighbours, worst dB per harmonic) and
    the speed coverage of every band (:func:`fbs_core.tire.quality.speed_coverage`,
    whose :class:`~fbs_core.tire.quality.SpeedRangeWarning` texts are collected here).

    Returns
    -------
    dict
        ``harmonic`` (7,), ``loo_db`` (7,) worst leave-one-out error in dB (NaN: no
        interior point in the band's speeds), ``covered`` (7,) bool, ``warnings`` list of
        str (one per band needing speeds outside the stored ones), ``speeds`` (min, max)
        km/h, ``n_points``, ``method`` (str).
    """
    return _tire_quality(cache_key(models))


@shared_cache(maxsize=8)
def _tire_quality(models) -> dict:
    import warnings

    from fbs_core.tire.quality import SpeedRangeWarning, interpolation_quality, speed_coverage
    from fbs_core.vocabulary import HARMONIC_CASES

    tire = tire_of(models)
    ks = tuple(HARMONIC_CASES)
    stored = tire.meta.get("interpolation_quality", {}).get("worst_db", {})
    if models is None and all(str(k) in stored for k in ks):
        # the shipped tire: the estimate its build script stored (the same function on
        # the same data, rounded to 0.001 dB), so that no page waits for it
        loo = np.array([np.nan if stored[str(k)] is None else stored[str(k)] for k in ks])
    elif tire.speeds.size >= 3:
        loo = np.asarray(interpolation_quality(tire, ks).worst_db, float)
    else:
        loo = np.full(len(ks), np.nan)
    covered, texts = [], []
    for k in ks:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", SpeedRangeWarning)
            speed_coverage(tire, k)
        msgs = [str(w.message) for w in caught if issubclass(w.category, SpeedRangeWarning)]
        covered.append(not msgs)
        texts += msgs
    return {
        "harmonic": readonly(np.asarray(ks, int)),
        "loo_db": readonly(np.asarray(loo, float)),
        "covered": readonly(np.asarray(covered, bool)),
        "warnings": tuple(texts),
        "speeds": (float(tire.speeds[0]), float(tire.speeds[-1])),
        "n_points": int(tire.speeds.size),
        "method": "leave one operating point out, predict it from its neighbours (twice "
        "the spacing: an upper estimate); worst over the band's speeds",
    }


def eigen_curves(models=None) -> dict:
    """Highest retained eigenfrequency versus N at 20, 80, 120 km/h (thesis fig. 5.8):
    ``n_modes``, ``f_20``, ``f_80``, ``f_120`` and the core's ``result``
    (:class:`~fbs_core.studies.ModeFrequencies`)."""
    return _eigen_curves(cache_key(models))


@shared_cache(maxsize=8)
def _eigen_curves(models) -> dict:
    mf = studies.mode_frequencies(EIGEN_SPEEDS, tire=None if models is None else models.tire)
    out: dict = {"n_modes": np.asarray(mf.n_modes, int), "result": mf}
    for v, row in zip(mf.speeds, mf.frequency, strict=True):
        out[f"f_{int(v)}"] = np.asarray(row, float)
    return out


# -- uncoupled subsystems --------------------------------------------------------------------
@shared_cache(maxsize=64)
def _tire_hub(harmonic: int, n_modes: int | None, models=None):
    return tire_of(models).patch_response(
        frequencies(harmonic), fbs_core.harmonic(harmonic), retained(models, n_modes)
    )


@shared_cache(maxsize=8)
def _chassis_frf(harmonic: int, models=None):
    return chassis_of(models).mobility(frequencies(harmonic))


def uncoupled_data(harmonic: int, n_modes: int, dof: str, spindle_input: str, models=None) -> dict:
    """Uncoupled subsystems (thesis figs. 4.6-4.7 and 4.2-4.3).

    Returns
    -------
    dict
        ``freq``; ``tire_reference`` / ``tire_truncated``: free hub velocity ``Y_ja^A F_a`` at
        ``hub:<dof>`` with all / N modes; ``chassis``: chassis mobility ``Y_ej^E`` from
        ``spindle:<spindle_input>`` to ``bushing:<dof>``; and their ``*_db`` columns.
    """
    models = cache_key(models)
    t_ref = _tire_hub(harmonic, None, models).sel(outputs=f"hub:{dof}").data[:, 0, 0]
    t_tr = _tire_hub(harmonic, int(n_modes), models).sel(outputs=f"hub:{dof}").data[:, 0, 0]
    ch = (
        _chassis_frf(harmonic, models)
        .sel(outputs=f"bushing:{dof}", inputs=f"spindle:{spindle_input}")
        .data[:, 0, 0]
    )
    return {
        "freq": frequencies(harmonic),
        "tire_reference": t_ref,
        "tire_truncated": t_tr,
        "chassis": ch,
        "tire_reference_db": magnitude_db(t_ref),
        "tire_truncated_db": magnitude_db(t_tr),
        "chassis_db": magnitude_db(ch),
    }


# -- noise study -----------------------------------------------------------------------------
#: Scatter bands kept (about 2.3 MB each at harmonic 7 with 10,000 rounds).
BAND_CACHE_SIZE = 32
_bands: OrderedDict = OrderedDict()
_bands_lock = threading.Lock()


class BandKey(NamedTuple):
    """The settings that define a scatter band (its cache key), by name.

    ``vehicle``: ``(wheels, track relation, response point)`` of a car's band (vehicle
    scope, :mod:`app.results.vehicle_compute`); None for a corner's band.
    """

    harmonic: int
    n_modes: int | None
    coupling: str
    noise_pct: float
    target: str
    frequency_dependent: bool
    rounds: int
    seed: int
    models: Any
    vehicle: tuple | None = None

    @property
    def is_car(self) -> bool:
        """Whether it is a car's band (vehicle scope)."""
        return self.vehicle is not None


def band_key(
    harmonic: int,
    n_modes: int | None,
    coupling: str,
    noise_pct: float,
    target: str,
    frequency_dependent: bool,
    rounds: int,
    seed: int,
    models=None,
    vehicle: tuple | None = None,
) -> BandKey:
    """The settings that define a scatter band (its cache key), normalised
    (:class:`BandKey`)."""
    return BandKey(
        int(harmonic),
        retained(cache_key(models), n_modes),
        str(coupling),
        float(noise_pct),
        str(target),
        bool(frequency_dependent),
        int(rounds),
        int(seed),
        cache_key(models),
        None if vehicle is None else tuple(vehicle),
    )


def is_car_key(key: BandKey) -> bool:
    """Whether :func:`band_key` ``key`` is a car's (vehicle scope)."""
    return key.is_car


def cached_band(key: tuple):
    """The band of ``key`` if it was computed before, else None."""
    with _bands_lock:
        res = _bands.get(key)
        if res is not None:
            _bands.move_to_end(key)
        return res


def band(*args, cancel=None, progress=None, **kwargs):
    """The Monte-Carlo scatter band (thesis 5.2) of :func:`band_key`'s settings, cached.

    ``cancel`` is handed to :func:`fbs_core.scatter_band` (asked between chunks of lines;
    :class:`fbs_core.StudyCancelled` when it returns True), and ``progress`` (called with
    the lines done and the total after each chunk). Sessions asking for the same missing
    band at once share one computation (:class:`app.runtime.bands.SharedRun`).
    """
    key = band_key(*args, **kwargs)
    res = cached_band(key)
    if res is not None:
        return res
    t0 = time.perf_counter()
    res = _scatter_band(key, cancel, progress)
    remember_band(key, res, time.perf_counter() - t0)
    return res


def band_once(*args, **kwargs):
    """The scatter band of :func:`band_key`'s settings: the cached one if it was computed,
    else computed here **without keeping it**.

    For callers that keep only a small digest of a band (the verdict's upper edges, the
    other candidates' percentile edges): a candidate x harmonic sweep must not push the
    bands the pages are showing out of the process-wide cache of :data:`BAND_CACHE_SIZE`.
    """
    key = band_key(*args, **kwargs)
    res = cached_band(key)
    return _scatter_band(key) if res is None else res


def _scatter_band(key: BandKey, cancel=None, progress=None):
    if is_car_key(key):
        raise ValueError("a car's band is computed by app.results.vehicle_compute.cached_band")
    harmonic, n_modes, coupling, noise_pct, target, fdep, rounds, seed, models, _ = key
    return studies.scatter_band(
        harmonic,
        noise=fraction(noise_pct),
        target=target,
        rounds=rounds,
        frequency_dependent=fdep,
        seed=seed,
        n_modes=n_modes,
        coupling=coupling,
        percentiles=Q_LEVELS,
        cancel=cancel,
        progress=progress,
        **models_kw(models),
    )


def remember_band(key: tuple, res, seconds: float | None = None) -> None:
    """Cache the band ``res`` of :func:`band_key` ``key`` (computed here or on a cluster in
    ``seconds``: :func:`band_computed`)."""
    with _bands_lock:
        _bands[key] = res
        _band_times[key] = BandTime(seconds, time.monotonic())
        _bands.move_to_end(key)
        while len(_bands) > BAND_CACHE_SIZE:
            old, _ = _bands.popitem(last=False)
            _band_times.pop(old, None)


@dataclass(frozen=True)
class BandTime:
    """When a cached band was computed: its wall time (None: not known) and the
    ``time.monotonic()`` at which it was ready."""

    seconds: float | None
    ready: float


_band_times: dict = {}


def band_computed(key: tuple) -> BandTime | None:
    """When the cached band of ``key`` was computed (None: not cached)."""
    with _bands_lock:
        return _band_times.get(key)


def _label(dof: str) -> str:
    """A response DOF's label: a direction is the bushing's (``z`` -> ``bushing:z``)."""
    return dof if ":" in dof else f"bushing:{dof}"


def first_order(
    harmonic: int,
    n_modes: int | None,
    coupling: str,
    noise_pct: float,
    target: str,
    models=None,
):
    """The first-order band (:func:`fbs_core.first_order_band`) of a scatter band's settings
    (its rounds, seed and frequency dependence do not enter), cached."""
    models = cache_key(models)
    return _first_order(
        int(harmonic),
        retained(models, n_modes),
        str(coupling),
        float(noise_pct),
        str(target),
        models,
    )


@shared_cache(maxsize=16)
def _first_order(harmonic, n_modes, coupling, noise_pct, target, models):
    return studies.first_order_band(
        harmonic,
        noise=fraction(noise_pct),
        target=target,
        n_modes=n_modes,
        coupling=coupling,
        **models_kw(models),
    )


def band_data(result, dof: str, percentile: float = 90) -> dict:
    """Columns of the scatter-band view for one response DOF (a direction: the bushing's).

    ``percentile`` is the width of the central band in percent (one of
    :data:`PERCENTILE_BANDS`; 90 -> the 5 % and 95 % percentiles).
    """
    j = result.dofs.index(_label(dof))
    lo, hi = (100 - percentile) / 2, (100 + percentile) / 2
    q = list(np.asarray(result.q, float))
    ref = result.reference[:, j]
    cols = {
        "freq": np.asarray(result.freq, float),
        "reference": ref,
        "minimum": np.asarray(result.minimum[:, j], float),
        "maximum": np.asarray(result.maximum[:, j], float),
        "pct_low": np.asarray(result.percentiles[q.index(lo), :, j], float),
        "pct_high": np.asarray(result.percentiles[q.index(hi), :, j], float),
    }
    for k in ("reference", "minimum", "maximum", "pct_low", "pct_high"):
        cols[f"{k}_db"] = magnitude_db(cols[k])
    return cols


def single_round_data(result, index: int, dof: str) -> dict:
    """One regenerated polluted round (thesis figs. 5.10-5.11) for one response DOF."""
    j = result.dofs.index(_label(dof))
    v = result.round(int(index))[:, j]
    return {"freq": np.asarray(result.freq, float), "round": v, "round_db": magnitude_db(v)}


def peak_round(result, freq: float, dof: str, which: str = "max") -> int:
    """The round with the highest (lowest) level at the line nearest ``freq``."""
    return int(result.peak_round(float(freq), _label(dof), which))
