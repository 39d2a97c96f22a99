"""Build the supplier-style modal model from the physical tire.

At every operating point the complex modes of the full tire (all belt and hub
DOFs) are computed (:func:`.modes.complex_modes`), tracked across the speeds
(:func:`.modes.track_modes`), and reduced to what a supplier delivers: poles,
right and left shapes at the hub, and the modal participation of the patch load
of every harmonic case.

With ``refine_tol`` the operating points are refined where the physics asks for
it: a supplier with the matrices compares the interpolated model between its
points with the direct solution there (:func:`interval_errors`) and adds the
midpoint of every interval that misses the tolerance (docs/tire-model.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..harmonics import WAVELENGTHS
from .model import TireModel
from .modes import ComplexModes, complex_modes, track_modes
from .params import DEFAULT_PARAMETERS, TireParameters
from .ring import build_tire_system, patch_load

__all__ = [
    "OPERATING_POINTS",
    "REFINE_TOL",
    "REFINE_MIN_STEP",
    "build_modal_model",
    "interval_errors",
]

#: Base operating points of the shipped modal model in km/h: every 2.5 km/h from 20 to
#: 120 (the thesis' supplier model had 20, 40, ..., 120; section 4.1.2). The shipped file
#: adds midpoints where :func:`interval_errors` exceeds :data:`REFINE_TOL`
#: (docs/tire-model.md, bench/bench_speed_fidelity.py).
OPERATING_POINTS: tuple[float, ...] = tuple(20.0 + 2.5 * i for i in range(41))

#: Relative error of the interpolated hub mobility / free hub velocity against the
#: direct solution between operating points above which an interval is halved (1 %,
#: 0.09 dB). At a deep minimum of the coupled response (chassis and tire cancelling)
#: a few per cent on the tire's side become several dB at the bushing.
REFINE_TOL = 0.01
#: Smallest spacing the refinement creates, km/h.
REFINE_MIN_STEP = 0.625
#: Fractions of an interval at which :func:`interval_errors` checks the model.
CHECK_FRACTIONS = (0.25, 0.5, 0.75)


def _modes_at(
    speeds: Sequence[float], params: TireParameters, cache: dict[float, ComplexModes]
) -> list[ComplexModes]:
    out = []
    for v in speeds:
        key = float(v)
        if key not in cache:
            s = build_tire_system(key, params)
            cache[key] = complex_modes(s.M, s.C, s.K)
        out.append(cache[key])
    return out


def _assemble(
    speeds: Sequence[float],
    params: TireParameters,
    wavelengths: Sequence[float] | np.ndarray,
    modes: list[ComplexModes],
    loads: np.ndarray,
) -> TireModel:
    tracked, macs = track_modes(modes)
    poles = np.array([m.poles for m in tracked])
    psi = np.array([m.psi[:6].T for m in tracked])
    chi = np.array([m.chi[:6].T for m in tracked])
    part = np.array([loads @ m.chi for m in tracked])  # (n_s, n_h, n_m)
    meta: dict[str, Any] = {
        "source": "fbs_core.tire.build_modal_model",
        "mac_median": np.median(macs, axis=1).round(4).tolist(),
        "mac_share_above_0.9": np.mean(macs > 0.9, axis=1).round(4).tolist(),
    }
    return TireModel(
        np.asarray(speeds, float),
        poles,
        psi,
        chi,
        np.asarray(wavelengths, float),
        part,
        params=params,
        meta=meta,
    )


def interval_errors(model: TireModel, fractions: Sequence[float] = CHECK_FRACTIONS) -> np.ndarray:
    """Interpolation error of a model with physics between each pair of operating points.

    At the speeds ``v`` inside every interval (``fractions`` of it) and, for every
    stored wavelength, at the line that wavelength excites there, ``f = v / (3.6
    lambda)`` (where a harmonic case needs the tire at ``v``), the interpolated hub
    mobility and free hub velocity are compared with the direct solution of the tire's
    matrices at ``v`` (``K - omega^2 M + j omega C``, no modes).

    Parameters
    ----------
    model : TireModel
        With physical parameters.
    fractions : sequence of float
        Where inside each interval to check (0 < t < 1).

    Returns
    -------
    ndarray, shape (n_s - 1,)
        Largest relative error per interval, ``|X_interp - X| / |X|`` (Frobenius norm of
        the 6 x 6 mobility, vector norm of the velocity), over the checked speeds and
        wavelengths.
    """
    params = model._need_params()
    sp = model.speeds
    loads = np.array([patch_load(w, params) for w in model.wavelengths])  # (n_h, n_dof)
    out = np.zeros(sp.size - 1)
    for k in range(sp.size - 1):
        for t in fractions:
            v = float(sp[k] + t * (sp[k + 1] - sp[k]))
            f = v / 3.6 / model.wavelengths  # (n_h,)
            Y, _ = model.synthesis(f, np.full(f.size, v))  # mobility only: velocity below
            ts = build_tire_system(v, params)
            for i, fi in enumerate(f):
                w = 2 * np.pi * fi
                Z = ts.K - w**2 * ts.M + 1j * w * ts.C
                rhs = np.zeros((ts.n, 7), complex)
                rhs[:6, :6] = np.eye(6)
                rhs[:, 6] = loads[i]
                X = 1j * w * np.linalg.solve(Z, rhs)
                _, xv = model.synthesis(f[i : i + 1], [v], harmonic_index=i)
                assert xv is not None  # a harmonic index was given
                eY = np.linalg.norm(Y[i] - X[:6, :6]) / np.linalg.norm(X[:6, :6])
                ev = np.linalg.norm(xv[0] - X[:6, 6]) / np.linalg.norm(X[:6, 6])
                out[k] = max(out[k], eY, ev)
    return out


def build_modal_model(
    params: TireParameters = DEFAULT_PARAMETERS,
    speeds: Sequence[float] | np.ndarray = OPERATING_POINTS,
    wavelengths: Sequence[float] | np.ndarray = WAVELENGTHS,
    refine_tol: float | None = None,
    min_step: float = REFINE_MIN_STEP,
) -> TireModel:
    """Complex-mode model of the physical tire at the given operating points.

    Parameters
    ----------
    params : TireParameters
    speeds : sequence of float
        Operating points in km/h, increasing.
    wavelengths : sequence of float
        Road wavelengths in m for the patch participation.
    refine_tol : float, optional
        Halve every interval whose :func:`interval_errors` exceeds this relative
        error (e.g. :data:`REFINE_TOL`), and repeat until none does or the spacing
        would drop below ``min_step``. None: the given points only.
    min_step : float
        Smallest spacing the refinement creates, km/h.

    Returns
    -------
    TireModel
        With ``meta["mac_median"]`` and ``meta["mac_share_above_0.9"]``: the
        median MAC of tracked modes between consecutive operating points and
        the share of tracked modes with MAC above 0.9; with ``refine_tol`` also
        ``meta["refinement"]`` (tolerance, points added, worst remaining error).
    """
    loads = np.array([patch_load(w, params) for w in wavelengths])  # (n_h, n_dof)
    cache: dict[float, ComplexModes] = {}
    sp = [float(v) for v in speeds]
    model = _assemble(sp, params, wavelengths, _modes_at(sp, params, cache), loads)
    if refine_tol is None:
        return model
    added: list[float] = []
    while True:
        err = interval_errors(model)
        new = [
            0.5 * (sp[k] + sp[k + 1])
            for k in np.flatnonzero(err > refine_tol)
            if (sp[k + 1] - sp[k]) / 2 >= min_step - 1e-12
        ]
        if not new:
            break
        added += new
        sp = sorted(sp + new)
        model = _assemble(sp, params, wavelengths, _modes_at(sp, params, cache), loads)
    model.meta["refinement"] = {
        "method": "midpoint of every interval whose interpolated hub mobility or free hub "
        "velocity differs from the direct solution by more than tol (relative)",
        "tol": float(refine_tol),
        "min_step_kmh": float(min_step),
        "base_speeds_kmh": [float(v) for v in speeds],
        "added_kmh": sorted(added),
        "worst_remaining": float(err.max()),
    }
    return model
