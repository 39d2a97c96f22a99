"""Build the supplier-style modal model from the physical tire.

At every operating point the complex modes of the full tire (all belt and hub
DOFs) are computed (:func:`.modes.complex_modes`), tracked across the speeds
(:func:`.modes.track_modes`), and reduced to what a supplier delivers: poles,
right and left shapes at the hub, and the modal participation of the patch load
of every harmonic case.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..harmonics import WAVELENGTHS
from .model import TireModel
from .modes import complex_modes, track_modes
from .params import DEFAULT_PARAMETERS, TireParameters
from .ring import build_tire_system, patch_load

__all__ = ["OPERATING_POINTS", "build_modal_model"]

#: Operating points of the shipped modal model in km/h: every 2.5 km/h from 20 to 120
#: (the thesis' supplier model had 20, 40, ..., 120; section 4.1.2). Finer points keep
#: the interpolated prediction within 0.4 dB of the physics near the peaks
#: (docs/tire-model.md, bench/bench_speed_fidelity.py).
OPERATING_POINTS: tuple[float, ...] = tuple(20.0 + 2.5 * i for i in range(41))


def build_modal_model(
    params: TireParameters = DEFAULT_PARAMETERS,
    speeds: Sequence[float] | np.ndarray = OPERATING_POINTS,
    wavelengths: Sequence[float] | np.ndarray = WAVELENGTHS,
) -> TireModel:
    """Complex-mode model of the physical tire at the given operating points.

    Parameters
    ----------
    params : TireParameters
    speeds : sequence of float
        Operating points in km/h, increasing.
    wavelengths : sequence of float
        Road wavelengths in m for the patch participation.

    Returns
    -------
    TireModel
        With ``meta["mac_median"]`` and ``meta["mac_share_above_0.9"]``: the
        median MAC of tracked modes between consecutive operating points and
        the share of tracked modes with MAC above 0.9.
    """
    modes, loads = [], np.array([patch_load(w, params) for w in wavelengths])  # (n_h, n_dof)
    for v in speeds:
        s = build_tire_system(v, params)
        modes.append(complex_modes(s.M, s.C, s.K))
    tracked, macs = track_modes(modes)
    poles = np.array([m.poles for m in tracked])
    psi = np.array([m.psi[:6].T for m in tracked])
    chi = np.array([m.chi[:6].T for m in tracked])
    part = np.array([loads @ m.chi for m in tracked])  # (n_s, n_h, n_m)
    meta = {
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
