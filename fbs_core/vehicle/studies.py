"""The thesis' studies on the whole car: modal truncation (eq. 5.1) and noise (eqs. 5.2-5.4).

Both reuse the single corner's machinery of :mod:`fbs_core.studies` on the four
hubs as one interface (24 DOFs, 20 with the spin released):

- the truncation map calls :func:`~fbs_core.studies.truncation_map_arrays` (eq. 4.1
  for every retained count, the floating-band error of eq. 5.1, the suggested count
  of table 5.1) with the tires' block-diagonal hub mobility and their free hub
  velocities combined by the road (:class:`~.road.Road`: wheelbase delay, tracks in
  phase or anti-phase);
- the scatter band calls :func:`~fbs_core.studies.scatter_band_arrays` (the compiled
  kernels, counter-based random factors) on the same arrays: every element gets its
  own factor, so each wheel's tire FRFs get noise of their own (target ``"tire"``),
  the car's hub and transfer mobilities theirs (``"chassis"``: the body), or both.

One tire synthesis along the harmonic line serves all four wheels and every
retained count (:func:`~.tires.wheel_arrays`: cumulative modal sums, mirrored on
the right). The studies need a coherent road (``tracks`` ``"in phase"``,
``"anti-phase"`` or a coherency of +-1): eq. 5.1 compares complex responses.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray
from ..dofs import DIRECTIONS
from ..errors import FBSError
from ..frf import check_grid
from ..harmonics import Harmonic
from ..harmonics import harmonic as _harmonic
from ..studies import (
    ScatterBand,
    SuggestedModes,
    TruncationMap,
    mode_frequencies,
    scatter_band_arrays,
    truncation_map_arrays,
)
from .layout import WHEELS, hub_labels
from .response import (
    Vehicle,
    _car,
    _car_arrays,
    _geometry,
    _n_total,
    coupled_directions,
    interface_arrays,
)
from .road import Road
from .tires import wheel_arrays, wheel_models

__all__ = ["vehicle_truncation_map", "vehicle_suggest_modes", "vehicle_scatter_band"]

#: Working-memory bound of one chunk of retained counts (the 24 x 24 interface of every
#: line and count), bytes.
_CHUNK_BYTES = 64e6


def _setup(
    harmonic: int | Harmonic,
    freq: ArrayLike | None,
    df: float,
    coupling: str | Mapping[str, str],
    tracks: str | float,
    wheels: Sequence[str],
    outputs: Any,
    vehicle: Vehicle | None,
) -> tuple[Harmonic, FloatArray, ComplexArray, ComplexArray, tuple[str, ...], Any, Any]:
    h = _harmonic(harmonic)
    f = h.frequencies(df) if freq is None else check_grid(freq)
    h.speed_at(f)
    dirs = coupled_directions(coupling)
    car = _car(vehicle)
    YjjE, YejE, resp, _ = _car_arrays(car, f, dirs, outputs)
    L, B = _geometry(car)
    labels, U = Road(wavelength=h.wavelength, tracks=tracks, wheels=tuple(wheels)).components(
        f, L, B
    )
    if len(labels) != 1:
        raise FBSError(
            f"the studies need a coherent road (tracks 'in phase' or 'anti-phase'), got "
            f"tracks={tracks!r}: two uncorrelated components {', '.join(labels)}"
        )
    return h, f, YjjE, YejE, resp, dirs, U[:, :, 0]


def _tire_interface(
    YA: ComplexArray, vA: ComplexArray, dirs: Mapping[str, Sequence[str]], u: ComplexArray
) -> tuple[ComplexArray, ComplexArray]:
    """Block-diagonal tires ``(..., n_j, n_j)`` and their road-combined free velocity
    ``(..., n_j)`` (``u`` (n_f, 4): each wheel's road input)."""
    blocks = [[DIRECTIONS.index(d) for d in dirs[w]] for w in WHEELS]
    A, V = interface_arrays(YA, vA, blocks)
    v = np.einsum("...jw,...w->...j", V, np.broadcast_to(u, V.shape[:-2] + u.shape[-1:]))
    return A, v


def vehicle_truncation_map(
    harmonic: int | Harmonic,
    n_modes: ArrayLike | None = None,
    *,
    outputs: Sequence[str] | str | None = "seat_fl",
    tracks: str | float = "in phase",
    wheels: Sequence[str] = WHEELS,
    coupling: str | Mapping[str, str] = "6dof",
    vehicle: Vehicle | None = None,
    tire: Any = None,
    freq: ArrayLike | None = None,
    df: float = 0.5,
    width: float = 12.0,
    step: float = 1.0,
    edges: str = "clip",
    centres: ArrayLike | None = None,
    residual: bool = False,
) -> TruncationMap:
    """Truncation error map of a car response for one harmonic (thesis eq. 5.1, fig. 5.6).

    Parameters
    ----------
    harmonic : int or Harmonic
    n_modes : array_like of int, optional
        Retained tire-mode counts, ascending (default 10, 20, ... all modes).
    outputs : labels or node names
        Response DOFs judged (default the six DOFs of ``seat_fl``).
    tracks, wheels
        The road (:class:`~.road.Road`); coherent only.
    coupling, vehicle, tire, freq, df, residual
        As :func:`~.response.vehicle_transfer`.
    width, step, edges, centres
        The floating band (:func:`fbs_core.studies.floating_band_error`).

    Returns
    -------
    TruncationMap
        As the corner's, with the interface ``hub_fl:x`` ... (24 DOFs) and the car's
        transfer mobility (its terms are the path contributions).
    """
    h, f, YjjE, YejE, resp, dirs, u = _setup(
        harmonic, freq, df, coupling, tracks, wheels, outputs, vehicle
    )
    n_total = _n_total(tire)
    n = np.arange(10, n_total + 1, 10) if n_modes is None else np.asarray(n_modes, int)
    if n.ndim != 1 or n.size == 0 or np.any(np.diff(n) <= 0) or n[0] < 1 or n[-1] > n_total:
        raise FBSError(
            f"n_modes must be ascending counts in 1..{n_total} (the tire's modes), "
            f"got {np.asarray(n_modes).tolist()}"
        )
    counts = list(n) + ([] if n[-1] == n_total else [n_total])
    YA, vA = wheel_arrays(tire, f, h, counts, residual)  # (4, n_N, n_f, 6, 6): one synthesis
    A_ref, v_ref = _tire_interface(YA[:, -1], vA[:, -1], dirs, u)
    n_j = YjjE.shape[-1]
    per = max(1, int(_CHUNK_BYTES // (3 * 16 * f.size * n_j * n_j)))
    iface = tuple(lab for w in WHEELS for lab in hub_labels(w, dirs[w]))
    maps = []
    for a in range(0, n.size, per):
        b = min(a + per, n.size)  # (the all-modes count appended last is the reference)
        A, v = _tire_interface(YA[:, a:b], vA[:, a:b], dirs, u)
        maps.append(
            truncation_map_arrays(
                f,
                A,
                v,
                A_ref,
                v_ref,
                YjjE,
                YejE,
                n[a:b],
                dofs=resp,
                harmonic=h.k,
                n_modes_total=n_total,
                width=width,
                step=step,
                edges=edges,
                centres=centres,
                interface=iface,
            )
        )
    m0 = maps[0]

    def cat(name: str) -> Any:
        out = np.concatenate([getattr(m, name) for m in maps])
        out.setflags(write=False)
        return out

    return TruncationMap(
        harmonic=h.k,
        n_modes=cat("n_modes"),
        n_modes_total=n_total,
        centres=m0.centres,
        dofs=m0.dofs,
        error=cat("error"),
        freq=m0.freq,
        response=cat("response"),
        reference=m0.reference,
        width=m0.width,
        step=m0.step,
        edges=m0.edges,
        _interface=m0.interface,
        _forces=cat("forces"),
        _forces_reference=m0.forces_reference,
        _transfer=m0.transfer,
    )


def vehicle_suggest_modes(
    threshold: float = 0.2,
    f_max: float = 160.0,
    *,
    harmonics: Sequence[int] = (1, 2, 3, 4, 5, 6, 7),
    dof: str | None = None,
    speed: float = 80.0,
    maps: Sequence[TruncationMap] | None = None,
    tire: Any = None,
    **kw: Any,
) -> SuggestedModes:
    """Suggested number of tire modes per harmonic for a car response (thesis table 5.1).

    Parameters
    ----------
    threshold : float
        Largest acceptable eq. 5.1 error (0.2 = 20 %).
    f_max : float
        Upper frequency of the predictions, Hz.
    harmonics : sequence of int
        Cases to map (when ``maps`` is not given).
    dof : str, optional
        Judge one response DOF; default the maximum over the map's DOFs.
    speed : float
        Operating point (km/h) of the reported highest eigenfrequency.
    maps : sequence of TruncationMap, optional
        Maps of :func:`vehicle_truncation_map`, reused (no new coupling).
    tire : optional
        As :func:`vehicle_truncation_map`; further keywords go to that function.

    Returns
    -------
    SuggestedModes
    """
    if maps is None:
        maps = tuple(vehicle_truncation_map(k, tire=tire, **kw) for k in harmonics)
    maps = tuple(maps)
    ns = np.array([m.suggest(threshold, f_max, dof) for m in maps], int)
    ef = np.full(ns.size, np.nan)
    models = wheel_models(tire)
    first = models[WHEELS[0]][0]
    if np.any(ns > 0):
        ef[ns > 0] = mode_frequencies((speed,), ns[ns > 0], tire=first).frequency[0]
    hs = [_harmonic(m.harmonic if m.harmonic is not None else 0) for m in maps]
    ro = np.array(ns)
    ro.setflags(write=False)
    ef.setflags(write=False)
    fr = np.array([h.freq_range for h in hs])
    fr.setflags(write=False)
    return SuggestedModes(
        tuple(h.k for h in hs), ro, ef, fr, float(threshold), float(f_max), float(speed), dof, maps
    )


def vehicle_scatter_band(
    harmonic: int | Harmonic,
    noise: float = 0.1,
    target: str = "both",
    rounds: int = 10_000,
    frequency_dependent: bool = False,
    seed: int | np.integer[Any] | np.random.Generator = 0,
    *,
    outputs: Sequence[str] | str | None = "seat_fl",
    tracks: str | float = "in phase",
    wheels: Sequence[str] = WHEELS,
    n_modes: int | None = None,
    coupling: str | Mapping[str, str] = "6dof",
    vehicle: Vehicle | None = None,
    tire: Any = None,
    freq: ArrayLike | None = None,
    df: float = 0.5,
    percentiles: ArrayLike = (5.0, 95.0),
    checkpoints: ArrayLike | None = None,
    max_chunk_bytes: float = 64e6,
    max_chunk_seconds: float | None = 0.1,
    cancel: Callable[[], bool] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> ScatterBand:
    """Noise scatter band of a car response (thesis eqs. 5.2-5.4 on the four hubs).

    ``target="tire"``: every element of each wheel's tire hub mobility and free hub
    velocity scaled by its own factor in ``[1 - p, 1 + p]`` (noise per wheel);
    ``"chassis"``: the car's hub and transfer mobilities (noise on the body);
    ``"both"``.

    Parameters
    ----------
    harmonic : int or Harmonic
    noise, target, rounds, frequency_dependent, seed
        As :func:`fbs_core.scatter_band`.
    outputs, tracks, wheels, coupling, vehicle, tire, freq, df
        As :func:`vehicle_truncation_map` (a coherent road).
    n_modes : int, optional
        Retained tire modes (default all).
    percentiles, checkpoints, max_chunk_bytes, max_chunk_seconds, cancel, progress
        As :func:`fbs_core.studies.scatter_band_arrays`.

    Returns
    -------
    ScatterBand
    """
    h, f, YjjE, YejE, resp, dirs, u = _setup(
        harmonic, freq, df, coupling, tracks, wheels, outputs, vehicle
    )
    n = [_n_total(tire) if n_modes is None else int(n_modes)]
    YA, vA = wheel_arrays(tire, f, h, n)
    A, v = _tire_interface(YA[:, 0], vA[:, 0], dirs, u)
    return scatter_band_arrays(
        A,
        v,
        YjjE,
        YejE,
        noise,
        target,
        rounds,
        frequency_dependent,
        seed,
        freq=f,
        dofs=resp,
        harmonic=h.k,
        percentiles=percentiles,
        checkpoints=checkpoints,
        max_chunk_bytes=max_chunk_bytes,
        max_chunk_seconds=max_chunk_seconds,
        cancel=cancel,
        progress=progress,
    )
