"""Consistency of a virtual point measurement (van der Seijs et al., IMAC 2015, sec. 3.3).

The rigid interface displacement modes explain only part of what the channels measure; the
rest (``mu``, the residual) is flexibility of the interface, noise, or a measurement error.
Projecting the measured FRFs back through the virtual point gives the *filtered* FRFs

    ``Y~_u = R_u T_u Y`` (sensors),  ``Y~_f = Y (R_f T_f)^T`` (impacts),

and comparing them with the measured ones the consistency indicators, per line:

- overall sensor consistency ``rho_u = ||Y~_u||_F / ||Y||_F`` (all channels and impacts:
  with equal weights, the share of the measured amplitude the rigid modes explain);
- specific sensor consistency of channel k, over the impacts j,
  ``rho_u,k = |sum_j conj(y~_kj) y_kj| / max(sum_j |y~_kj|^2, sum_j |y_kj|^2)``,
  which is 1 when the filtered channel equals the measured one and drops for a channel
  that disagrees with the others in level (a loose sensor above its mount resonance), in
  phase or in sign (a mislabelled direction);
- the same for the impacts, over the columns (the sensors).

A virtual point transformed on the response side only (sensors around a point that is not
excited, IMAC 2015 eqs. 5-6 alone) has sensor indicators only: :func:`response_consistency`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray
from ..vocabulary import readonly

__all__ = [
    "Consistency",
    "consistency",
    "leverage",
    "response_consistency",
    "specific_consistency",
]


def leverage(R: FloatArray, T: FloatArray) -> list[float]:
    """Diagonal of the filter ``R T`` per channel: the share of a channel's own error that
    stays in its filtered value (the leverage of least squares; they sum to the number of
    IDMs). A channel with leverage 1 alone observes some rigid-body motion: its filtered
    value equals its measured one whatever it measured, so no consistency indicator can
    check it; at 0 it is fully redundant.

    Examples
    --------
    >>> import numpy as np
    >>> R = np.array([[1.0], [1.0]])
    >>> [round(v, 12) for v in leverage(R, np.linalg.pinv(R))]
    [0.5, 0.5]
    """
    return [float(v) for v in np.einsum("ij,ji->i", R, T)]


def specific_consistency(filtered: ArrayLike, measured: ArrayLike, axis: int) -> FloatArray:
    """``|sum conj(a) b| / max(sum |a|^2, sum |b|^2)`` along ``axis`` (the other channels).

    Parameters
    ----------
    filtered, measured : array_like, shape (n_freq, n_out, n_in)
    axis : int
        Axis summed over: 2 (impacts) for sensor channels, 1 (sensors) for impacts.

    Returns
    -------
    ndarray, shape (n_freq, n_channels)
        In [0, 1]; 1 where filtered and measured agree; 1 where both vanish.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.ones((1, 1, 2), complex)
    >>> specific_consistency(0.5 * y, y, 2).tolist()
    [[0.5]]
    >>> specific_consistency(-y, y, 2).tolist()
    [[1.0]]
    """
    a, b = np.asarray(filtered), np.asarray(measured)
    num = np.abs(np.sum(np.conj(a) * b, axis=axis))
    den = np.maximum(np.sum(np.abs(a) ** 2, axis=axis), np.sum(np.abs(b) ** 2, axis=axis))
    out: FloatArray = np.divide(num, den, out=np.ones_like(num), where=den > 0)
    return out


@dataclass(frozen=True, eq=False)
class Consistency:
    """Sensor and impact consistency of a virtual point measurement, per line.

    Attributes
    ----------
    freq : ndarray, shape (n_freq,)
    sensors, impacts : tuple of str
        Channel labels.
    sensor_overall, impact_overall : ndarray, shape (n_freq,)
        ``rho_u``, ``rho_f`` per line (``impact_overall`` NaN when no impacts were
        transformed: :func:`response_consistency`).
    sensor_specific : ndarray, shape (n_freq, n_s)
        ``rho_u,k`` per line and sensor channel.
    impact_specific : ndarray, shape (n_freq, n_i)
        ``rho_f,k`` per line and impact channel.
    """

    freq: FloatArray
    sensors: tuple[str, ...]
    impacts: tuple[str, ...]
    sensor_overall: FloatArray
    impact_overall: FloatArray
    sensor_specific: FloatArray
    impact_specific: FloatArray

    def sensor_table(
        self, fmin: float | None = None, fmax: float | None = None
    ) -> dict[str, float]:
        """Mean specific consistency of each sensor channel over ``[fmin, fmax]`` Hz."""
        m = self._band(fmin, fmax)
        return {
            s: float(v) for s, v in zip(self.sensors, self.sensor_specific[m].mean(0), strict=True)
        }

    def impact_table(
        self, fmin: float | None = None, fmax: float | None = None
    ) -> dict[str, float]:
        """Mean specific consistency of each impact channel over ``[fmin, fmax]`` Hz."""
        m = self._band(fmin, fmax)
        return {
            s: float(v) for s, v in zip(self.impacts, self.impact_specific[m].mean(0), strict=True)
        }

    def overall(self, fmin: float | None = None, fmax: float | None = None) -> tuple[float, float]:
        """Mean overall sensor and impact consistency over ``[fmin, fmax]`` Hz."""
        m = self._band(fmin, fmax)
        return float(self.sensor_overall[m].mean()), float(self.impact_overall[m].mean())

    def worst(self, fmin: float | None = None, fmax: float | None = None) -> tuple[str, float]:
        """The channel (sensor or impact) with the lowest mean specific consistency."""
        table = {**self.sensor_table(fmin, fmax), **self.impact_table(fmin, fmax)}
        k = min(table, key=table.__getitem__)
        return k, table[k]

    def _band(self, fmin: float | None, fmax: float | None) -> np.ndarray:
        f = self.freq
        m = np.ones(f.size, bool)
        if fmin is not None:
            m &= f >= fmin
        if fmax is not None:
            m &= f <= fmax
        if not m.any():
            from ..errors import FrequencyGridError

            raise FrequencyGridError(
                f"no line of the measurement ({f[0]:g}-{f[-1]:g} Hz) in [{fmin}, {fmax}] Hz"
            )
        return m


def consistency(
    Y: ComplexArray,
    Ru: FloatArray,
    Tu: FloatArray,
    Rf: FloatArray,
    Tf: FloatArray,
    sensors: Sequence[str],
    impacts: Sequence[str],
    freq: ArrayLike,
) -> Consistency:
    """Filtered FRFs and the consistency indicators of the module docstring.

    Parameters
    ----------
    Y : ndarray, shape (n_freq, n_s, n_i)
        Measured FRFs, sensors by impacts.
    Ru, Rf : ndarray, shape (n_s, m), (n_i, m)
        IDMs of the sensors and impacts.
    Tu, Tf : ndarray, shape (m, n_s), (m, n_i)
        Their transformations (:func:`fbs_core.vpt.transform.transformation`).
    sensors, impacts : sequence of str
    freq : array_like, shape (n_freq,)

    Returns
    -------
    Consistency
    """
    Fu = Ru @ Tu  # (n_s, n_s) filter: measured -> rigid part
    Ff = Rf @ Tf
    Yu = np.matmul(Fu, Y)
    n_f, n_s, n_i = Y.shape
    Yf = (Y.reshape(n_f * n_s, n_i) @ Ff.T).reshape(n_f, n_s, n_i)
    norm = np.sqrt(np.sum(np.abs(Y) ** 2, axis=(1, 2)))
    safe = np.where(norm > 0, norm, 1.0)
    ru = np.sqrt(np.sum(np.abs(Yu) ** 2, axis=(1, 2))) / safe
    rf = np.sqrt(np.sum(np.abs(Yf) ** 2, axis=(1, 2))) / safe
    return Consistency(
        readonly(np.asarray(freq, float)),
        tuple(sensors),
        tuple(impacts),
        readonly(ru),
        readonly(rf),
        readonly(specific_consistency(Yu, Y, 2)),
        readonly(specific_consistency(Yf, Y, 1)),
    )


def response_consistency(
    Y: ComplexArray,
    Ru: FloatArray,
    Tu: FloatArray,
    sensors: Sequence[str],
    freq: ArrayLike,
) -> Consistency:
    """Sensor consistency of a response-side virtual point (IMAC 2015 sec. 3.3).

    The sensors around a point that is observed but not excited (a bushing) are filtered
    as in :func:`consistency`, ``Y~_u = R_u T_u Y``, over whatever inputs the set has; the
    inputs are not transformed, so there are no impact indicators.

    Parameters
    ----------
    Y : ndarray, shape (n_freq, n_s, n_i)
        Measured FRFs, the point's sensors by the set's inputs.
    Ru : ndarray, shape (n_s, m)
    Tu : ndarray, shape (m, n_s)
    sensors : sequence of str
    freq : array_like, shape (n_freq,)

    Returns
    -------
    Consistency
        ``impacts`` empty, ``impact_overall`` NaN, ``impact_specific`` of shape
        ``(n_freq, 0)``.
    """
    Yu = np.matmul(Ru @ Tu, Y)
    norm = np.sqrt(np.sum(np.abs(Y) ** 2, axis=(1, 2)))
    ru = np.sqrt(np.sum(np.abs(Yu) ** 2, axis=(1, 2))) / np.where(norm > 0, norm, 1.0)
    n_f = Y.shape[0]
    return Consistency(
        readonly(np.asarray(freq, float)),
        tuple(sensors),
        (),
        readonly(ru),
        readonly(np.full(n_f, np.nan)),
        readonly(specific_consistency(Yu, Y, 2)),
        readonly(np.zeros((n_f, 0))),
    )
