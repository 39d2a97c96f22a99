"""The tire on every wheel: mirrored for the other side, synthesised once per line.

The reference tire is a *left* wheel (docs/tire-model.md: the left rear wheel of
the thesis' corner, camber and toe of a left wheel, hub DOFs in vehicle axes). On
the right side the car carries its mirror image, an exact change of coordinates
(:mod:`.layout`): hub mobility ``T Y T``, free hub velocity ``T v`` with
``T = diag(1, -1, 1, -1, 1, -1)``. Physically this is the same tire with the
signs of its lateral asymmetry flipped in vehicle axes: camber and toe (still
"top towards the car", "toe-in") and the conicity force ``mu_y0``
(:func:`mirror_tire`; ``tests/test_vehicle_tires.py`` checks that the tire's
matrices built with those signs give exactly ``T Y T``).

All four wheels roll at the same speed over the same road wavelength, so one
synthesis of the tire per line serves the four wheels (:func:`wheel_arrays`).
"""

from __future__ import annotations

import dataclasses
import threading
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .._typing import ComplexArray, FloatArray
from ..dofs import DIRECTIONS
from ..errors import DataFormatError, FBSError
from ..harmonics import Harmonic
from .layout import MIRROR, RIGHT, WHEELS

__all__ = ["mirror_tire", "mirror_arrays", "wheel_models", "wheel_arrays", "tire_at_speed"]

_S = np.asarray(MIRROR)


def mirror_arrays(Y: ComplexArray, v: ComplexArray | None = None) -> tuple[ComplexArray, Any]:
    """``T Y T`` and ``T v`` on the last axes (6 hub DOFs): the mirror image."""
    Ym = _S[:, None] * Y * _S[None, :]
    return Ym, (None if v is None else v * _S)


def mirror_tire(tire: Any) -> Any:
    """The mirror image of a modal tire model (a left tire -> a right one, and back).

    Mode shapes ``psi, chi -> T psi, T chi`` at the hub, the patch participation
    unchanged (the road is the same under both), residuals transformed alike; the
    physical parameters, if any, get the signs of camber, toe and conicity flipped
    (``camber, toe, mu_y0 -> -camber, -toe, -mu_y0``), so that ``system()`` is the
    physical mirror image.

    Parameters
    ----------
    tire : TireModel

    Returns
    -------
    TireModel
        ``mirror_tire(mirror_tire(t))`` has the data of ``t``.

    Raises
    ------
    FBSError
        For an object that is not a :class:`~fbs_core.tire.TireModel`.
    """
    from ..tire import TireModel

    if not isinstance(tire, TireModel):
        raise FBSError(f"mirror_tire needs a TireModel, got {type(tire).__name__}")
    res = tire.residual
    if res is not None:
        n_h = (res.shape[1] - 36) // 6
        signs = np.concatenate([np.outer(_S, _S).ravel(), np.tile(_S, n_h)])
        res = res * signs
    params = tire.params
    if params is not None:
        params = dataclasses.replace(
            params, camber=-params.camber, toe=-params.toe, mu_y0=-params.mu_y0
        )
    meta = dict(tire.meta)
    meta["mirrored"] = not bool(meta.get("mirrored", False))
    return dataclasses.replace(
        tire,
        psi=tire.psi * _S,
        chi=tire.chi * _S,
        params=params,
        meta=meta,
        residual=res,
    )


def wheel_models(tire: Any) -> dict[str, tuple[Any, bool]]:
    """Which model and whether mirrored, per wheel.

    ``tire`` is one model (a left-side tire, mirrored on the right wheels) or a mapping
    of the four wheels to models already in their wheel's vehicle coordinates.
    """
    if tire is None:
        from .. import reference_tire

        tire = reference_tire()
    if isinstance(tire, Mapping):
        missing = [w for w in WHEELS if w not in tire]
        extra = [w for w in tire if w not in WHEELS]
        if missing or extra:
            raise FBSError(
                f"a tire per wheel needs exactly the wheels {', '.join(WHEELS)}; "
                f"missing {missing}, unknown {extra}"
            )
        return {w: (tire[w], False) for w in WHEELS}
    return {w: (tire, w in RIGHT) for w in WHEELS}


def wheel_arrays(
    tire: Any,
    freq: FloatArray,
    h: Harmonic,
    n_modes_list: Sequence[int],
    residual: bool = False,
) -> tuple[ComplexArray, ComplexArray]:
    """Hub mobility and free hub velocity of the four wheels along a harmonic line.

    One ``truncations`` call per distinct model (one for the same tire on all wheels);
    the right wheels of a single model get its mirror image.

    Returns
    -------
    Y : ndarray, shape (4, n_N, n_f, 6, 6)
    v : ndarray, shape (4, n_N, n_f, 6)
        Wheel order :data:`~.layout.WHEELS`.
    """
    models = wheel_models(tire)
    kw: dict[str, bool] = {"residual": True} if residual else {}
    done: dict[int, tuple[ComplexArray, ComplexArray]] = {}
    n_list = list(n_modes_list)
    Ys, vs = [], []
    for w in WHEELS:
        model, mirrored = models[w]
        if id(model) not in done:
            if not hasattr(model, "truncations"):
                raise FBSError(
                    f"tire of wheel {w} must be a modal tire model with truncations(...), "
                    f"got {type(model).__name__}"
                )
            Yw, vw = model.truncations(freq, h, n_list, **kw)
            done[id(model)] = (np.asarray(Yw), np.asarray(vw))
        Yw, vw = done[id(model)]
        if mirrored:
            Yw, vw = mirror_arrays(Yw, vw)
        Ys.append(Yw)
        vs.append(vw)
    return np.stack(Ys), np.stack(vs)


_MODES: OrderedDict[tuple[int, float], tuple[Any, Any]] = OrderedDict()
_MODES_LOCK = threading.Lock()


def _modes_at(tire: Any, speed_kmh: float) -> Any:
    """All complex modes of the tire's matrices at one speed (cached per model)."""
    from ..tire import complex_modes

    key = (id(tire), float(speed_kmh))
    with _MODES_LOCK:
        hit = _MODES.get(key)
        if hit is not None and hit[0] is tire:
            return hit[1]
    s = tire.system(float(speed_kmh))
    modes = complex_modes(np.asarray(s.M), np.asarray(s.C), np.asarray(s.K))
    with _MODES_LOCK:
        _MODES[key] = (tire, modes)
        while len(_MODES) > 8:
            _MODES.popitem(last=False)
    return modes


def tire_at_speed(
    tire: Any, freq: FloatArray, speed_kmh: float
) -> tuple[ComplexArray, ComplexArray]:
    """Hub mobility and free hub velocity at one speed, each line at its own road wavelength.

    At a fixed speed ``v`` the road wave exciting line ``f`` has the wavelength
    ``lambda = v / f`` (the random road of every wavelength), so the patch load
    changes from line to line: ``Y_ja^A F_a = j omega sum_r psi_r (chi_r^T f(lambda_f))
    / (j omega - lambda_r)`` with all complex modes of the tire's own matrices at
    ``v`` (exact: the modal sum of all modes is the direct solution). Needs a tire
    with physical parameters (a supplier's modal model stores the participation of a
    few wavelengths only).

    Parameters
    ----------
    tire : TireModel
        With physical parameters (``tire.system``, ``tire.patch_load``).
    freq : ndarray, shape (n_f,)
        Positive frequencies in Hz.
    speed_kmh : float
        Positive speed.

    Returns
    -------
    Y : ndarray, shape (n_f, 6, 6)
    v : ndarray, shape (n_f, 6)
        Per metre of road amplitude.

    Raises
    ------
    DataFormatError
        For a tire without physical parameters, or a non-positive speed or frequency.
    """
    if not hasattr(tire, "system") or getattr(tire, "params", True) is None:
        raise DataFormatError(
            "a road of every wavelength (fixed speed, random road) needs the patch load at "
            "every wavelength: a tire with physical parameters (e.g. the reference tire); "
            "this modal model stores the participation of "
            f"{', '.join(f'{w:g}' for w in getattr(tire, 'wavelengths', []))} m only"
        )
    f = np.asarray(freq, float)
    v = float(speed_kmh)
    if not (np.isfinite(v) and v > 0) or f.size == 0 or f.min() <= 0:
        raise DataFormatError(
            f"a fixed-speed road needs a positive speed and frequencies, got {speed_kmh!r} km/h "
            f"and {f.min() if f.size else 'no'} Hz"
        )
    modes = _modes_at(tire, v)
    loads = np.stack([tire.patch_load(v, v / 3.6 / fi) for fi in f])  # (n_f, n_dof)
    s = 2j * np.pi * f
    g = 1.0 / (s[:, None] - modes.poles[None, :])  # (n_f, n_m)
    psi = modes.psi[: len(DIRECTIONS)]  # (6, n_m) hub rows
    chi = modes.chi  # (n_dof, n_m)
    # Y = s sum_r psi_r chi_r^T g_r (hub 6 x 6); v = s sum_r psi_r (chi_r^T f) g_r
    Y = s[:, None, None] * np.einsum("ir,fr,jr->fij", psi, g, chi[: len(DIRECTIONS)])
    part = loads @ chi  # (n_f, n_m)
    vv = s[:, None] * np.einsum("ir,fr->fi", psi, g * part)
    return Y, vv
