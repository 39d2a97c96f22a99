"""Phase views of an FRF: Bode (magnitude in dB, unwrapped phase in degrees), real and
imaginary parts, and delta cursors between two frequencies.

Small pure functions on the frequency-first data ``(n_f, n_out, n_in)`` of an
:class:`~fbs_core.FRF` (thesis table 2.1 for the quantities). Levels are
``20 log10(|H| / ref)`` (:func:`fbs_core.vocabulary.magnitude_db`); the phase is
``angle(H)`` unwrapped along frequency, so that a transfer through several resonances
keeps falling (-180, -360, ...) instead of jumping by 360 degrees.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..errors import FrequencyGridError
from ..frf import FRF
from ..vocabulary import magnitude_db

__all__ = [
    "Bode",
    "Delta",
    "bode",
    "real_imag",
    "level_db",
    "phase_deg",
    "delta_cursor",
    "interp_level",
]


def level_db(h: npt.ArrayLike, ref: float = 1.0) -> np.ndarray:
    """Deprecated name of ``fbs_core.vocabulary.magnitude_db(h, ref, floor=None)``
    (``20 log10(|h| / ref)``, ``-inf`` where ``h == 0``); a ``DeprecationWarning``,
    removed in the next release."""
    warnings.warn(
        "fbs_core.analysis.level_db is deprecated; use "
        "fbs_core.vocabulary.magnitude_db(h, ref, floor=None)",
        DeprecationWarning,
        stacklevel=2,
    )
    return np.asarray(magnitude_db(h, ref, floor=None), float)


def phase_deg(h: npt.ArrayLike, unwrap: bool = True, axis: int = 0) -> np.ndarray:
    """Phase of ``h`` in degrees, unwrapped along ``axis`` (frequency) by default.

    Parameters
    ----------
    h : array_like (complex)
        Frequency along ``axis``.
    unwrap : bool
        Remove the 360-degree jumps (``numpy.unwrap``); else in (-180, 180].
    axis : int
        The frequency axis.
    """
    p = np.angle(np.asarray(h))
    if unwrap:
        p = np.unwrap(p, axis=axis)
    return np.asarray(np.degrees(p), float)


@dataclass(frozen=True, eq=False)
class Bode:
    """Magnitude and phase of an FRF.

    Attributes
    ----------
    freq : ndarray, shape (n_f,)
        Frequencies in Hz.
    outputs, inputs : tuple of str
        DOF labels of the FRF.
    magnitude_db : ndarray, shape (n_f, n_out, n_in)
        ``20 log10(|H| / ref)``.
    phase_deg : ndarray, shape (n_f, n_out, n_in)
        Phase in degrees, unwrapped along frequency unless ``unwrap=False``.
    ref : float
        Reference of 0 dB.
    quantity : str
        FRF quantity.
    """

    freq: np.ndarray
    outputs: tuple[str, ...]
    inputs: tuple[str, ...]
    magnitude_db: np.ndarray
    phase_deg: np.ndarray
    ref: float
    quantity: str


def bode(frf: FRF, ref: float = 1.0, unwrap: bool = True) -> Bode:
    """Bode data of an FRF: level in dB and phase in degrees.

    Parameters
    ----------
    frf : FRF
    ref : float
        Reference of 0 dB, in the FRF's unit (e.g. 1 m/(N s) for a mobility).
    unwrap : bool
        Unwrap the phase along frequency (default) or keep it in (-180, 180].

    Returns
    -------
    Bode

    Examples
    --------
    >>> import numpy as np
    >>> from fbs_core import FRF
    >>> b = bode(FRF([1.0, 2.0], np.array([1j, -1.0]).reshape(2, 1, 1), ["a:x"], ["a:x"]))
    >>> b.phase_deg[:, 0, 0].tolist()
    [90.0, 180.0]
    """
    return Bode(
        frf.freq,
        frf.outputs,
        frf.inputs,
        magnitude_db(frf.data, ref, floor=None),
        phase_deg(frf.data, unwrap, axis=0),
        float(ref),
        frf.quantity,
    )


def real_imag(frf: FRF) -> tuple[np.ndarray, np.ndarray]:
    """Real and imaginary parts of an FRF, each of shape ``(n_f, n_out, n_in)``.

    Parameters
    ----------
    frf : FRF
    """
    return frf.data.real.copy(), frf.data.imag.copy()


def interp_level(freq: npt.ArrayLike, level: npt.ArrayLike, f0: float) -> float:
    """Level (dB) at ``f0`` by linear interpolation between the two nearest lines.

    Parameters
    ----------
    freq : ndarray, shape (n_f,)
        Increasing frequencies in Hz.
    level : ndarray, shape (n_f,)
        Levels in dB.
    f0 : float
        Frequency in Hz inside ``[freq[0], freq[-1]]``.

    Raises
    ------
    FrequencyGridError
        If ``f0`` lies outside the grid (no extrapolation).
    """
    freq = np.asarray(freq, float)
    f0 = float(f0)
    if not np.isfinite(f0) or f0 < freq[0] or f0 > freq[-1]:
        raise FrequencyGridError(
            f"cursor at {f0:g} Hz is outside the FRF's {freq[0]:g}-{freq[-1]:g} Hz; "
            "cursors are never extrapolated"
        )
    return float(np.interp(f0, freq, np.asarray(level, float)))


@dataclass(frozen=True)
class Delta:
    """Two cursors and their difference.

    Attributes
    ----------
    f1, f2 : float
        Cursor frequencies in Hz.
    level1, level2 : float
        Interpolated levels in dB at the cursors.
    """

    f1: float
    f2: float
    level1: float
    level2: float

    @property
    def df(self) -> float:
        """``f2 - f1`` in Hz."""
        return self.f2 - self.f1

    @property
    def d_db(self) -> float:
        """``level2 - level1`` in dB."""
        return self.level2 - self.level1

    @property
    def ratio(self) -> float:
        """``f2 / f1`` (an octave is 2)."""
        return self.f2 / self.f1 if self.f1 else float("inf")


def delta_cursor(
    frf: FRF,
    f1: float,
    f2: float,
    output: str | None = None,
    input: str | None = None,
    ref: float = 1.0,
) -> Delta:
    """Delta cursors: frequency and level difference between two frequencies.

    The levels are interpolated linearly in dB between the neighbouring lines.

    Parameters
    ----------
    frf : FRF
    f1, f2 : float
        Cursor frequencies in Hz, inside the FRF's range.
    output, input : str, optional
        The element; may be omitted where the FRF has a single output / input.
    ref : float
        Reference of 0 dB.

    Returns
    -------
    Delta

    Raises
    ------
    FrequencyGridError
        For a cursor outside the grid.
    DOFError
        For an unknown label, or a missing one on a multi-DOF FRF.
    """
    h = _element(frf, output, input)
    lv = magnitude_db(h, ref, floor=None)
    return Delta(
        float(f1), float(f2), interp_level(frf.freq, lv, f1), interp_level(frf.freq, lv, f2)
    )


def _element(frf: FRF, output: str | None, input: str | None) -> np.ndarray:
    """The complex values of one element, shape (n_f,)."""
    from ..errors import DOFError

    def pick(labels: Sequence[str], want: str | None, what: str) -> int:
        if want is None:
            if len(labels) != 1:
                raise DOFError(
                    f"the FRF has {len(labels)} {what}s; name one of: {', '.join(labels)}"
                )
            return 0
        if want not in labels:
            raise DOFError(f"unknown {what} DOF {want!r}; available: {', '.join(labels)}")
        return labels.index(want)

    return frf.data[:, pick(frf.outputs, output, "output"), pick(frf.inputs, input, "input")]
