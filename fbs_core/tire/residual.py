"""Residual terms of a truncated modal model estimated from FRFs.

A supplier with the full modal set gives the residual of the modes left out per
operating point directly (``TireModel.truncations(..., residual=True)``: every mode
``r`` not kept enters with its quasi-static part ``R_r / (-lambda_r)``). A car maker
with measured (or delivered full) FRFs ``H`` and a delivered truncated modal model
``H_N`` estimates them instead by a least-squares fit over a band below the first
mode left out::

    H(omega) - H_N(omega) ~ A + B / omega^2          (receptance)

``A`` is the upper residual flexibility (modes above the band), ``B`` the lower
residual (inertia of modes below the band, e.g. rigid-body-like modes). For a
gyroscopic, non-reciprocal tire both are full complex matrices, not symmetric.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..errors import FBSError

__all__ = ["fit_residual"]


def fit_residual(
    freq: ArrayLike,
    H: ArrayLike,
    H_trunc: ArrayLike,
    band: tuple[float, float] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Fit ``H - H_trunc ~ A + B / omega^2`` per matrix entry (receptances).

    Parameters
    ----------
    freq : array_like, shape (n_f,)
        Frequencies in Hz (> 0).
    H, H_trunc : array_like, shape (n_f, ...)
        Full and truncated receptance on ``freq`` (any trailing shape).
    band : (float, float), optional
        Fit band in Hz (default all lines).

    Returns
    -------
    A, B : ndarray, shape H.shape[1:]
        Upper residual flexibility and lower residual term.
    """
    f = np.asarray(freq, float)
    H = np.asarray(H)
    Ht = np.asarray(H_trunc)
    if H.shape != Ht.shape or H.shape[0] != f.size:
        raise FBSError(
            f"H and H_trunc must have one shape (n_f={f.size}, ...), got {H.shape}, {Ht.shape}"
        )
    if np.any(f <= 0):
        raise FBSError("fit_residual needs frequencies > 0 Hz")
    sel = np.ones(f.size, bool) if band is None else (f >= band[0]) & (f <= band[1])
    if sel.sum() < 2:
        raise FBSError(f"the fit band {band} holds fewer than 2 lines")
    w = 2 * np.pi * f[sel]
    X = np.stack([np.ones_like(w), 1.0 / w**2], axis=1)  # (n, 2), real basis
    D = (H - Ht)[sel].reshape(sel.sum(), -1)
    coef, *_ = np.linalg.lstsq(X, D, rcond=None)
    return coef[0].reshape(H.shape[1:]), coef[1].reshape(H.shape[1:])
