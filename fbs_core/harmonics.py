"""The seven harmonic excitation cases of the thesis (fig. 4.4, table 5.1).

Each case is a road wave of fixed wavelength ``lambda`` rolled over at a vehicle
speed ``v`` between 30 and 120 km/h, so that the excitation frequency follows the
line ``f = v / lambda`` (thesis section 4.1.2). Every band therefore spans exactly
a factor four in frequency. The names "1st harmonic" ... "7th harmonic" do not
count events per revolution (thesis section 4.1.2).

The wavelengths are fitted to the band edges of table 5.1 (12.9-51.5 Hz for case 1
... 105.6-422.3 Hz for case 7); see ``docs/tire-model.md``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .errors import FrequencyGridError, HarmonicError

__all__ = ["Harmonic", "HarmonicError", "HARMONICS", "WAVELENGTHS", "SPEED_RANGE", "harmonic"]

#: Road wavelengths in metres of the seven cases (thesis table 5.1: f_max / f_min = 4
#: between 30 and 120 km/h).
WAVELENGTHS: tuple[float, ...] = (0.646, 0.499, 0.339, 0.2395, 0.166, 0.1156, 0.0789)

#: Vehicle speed range of every case in km/h (thesis fig. 4.4).
SPEED_RANGE: tuple[float, float] = (30.0, 120.0)

_REL_TOL = 1e-9


@dataclass(frozen=True)
class Harmonic:
    """One harmonic excitation case: a road wave rolled over along ``f = v / lambda``.

    Parameters
    ----------
    k : int
        Case number, 1..7.
    wavelength : float
        Road wavelength in m.
    speed_range : tuple of float
        ``(v_min, v_max)`` in km/h.

    Examples
    --------
    >>> h = harmonic(1)
    >>> round(h.freq_range[0], 1), round(h.freq_range[1], 1)
    (12.9, 51.6)
    >>> round(h.speed_at(25.0), 2)
    58.14
    """

    k: int
    wavelength: float
    speed_range: tuple[float, float] = SPEED_RANGE

    @property
    def name(self) -> str:
        suffix = {1: "st", 2: "nd", 3: "rd"}.get(self.k, "th")
        return f"{self.k}{suffix} harmonic"

    @property
    def wavenumber(self) -> float:
        """Road wavenumber ``2 pi / lambda`` in rad/m."""
        return 2 * np.pi / self.wavelength

    @property
    def freq_range(self) -> tuple[float, float]:
        """``(f_min, f_max)`` in Hz: ``v / lambda`` at the ends of the speed range."""
        lo, hi = self.speed_range
        return (lo / 3.6 / self.wavelength, hi / 3.6 / self.wavelength)

    def _check(self, freq: ArrayLike) -> np.ndarray:
        f = np.asarray(freq, dtype=float)
        lo, hi = self.freq_range
        bad = (f < lo * (1 - _REL_TOL)) | (f > hi * (1 + _REL_TOL)) | ~np.isfinite(f)
        if np.any(bad):
            first = float(np.atleast_1d(f)[np.atleast_1d(bad)][0])
            raise FrequencyGridError(
                f"frequency {first:g} Hz is outside the {self.name} band "
                f"{lo:.4g}-{hi:.4g} Hz (speeds {self.speed_range[0]:g}-"
                f"{self.speed_range[1]:g} km/h at wavelength {self.wavelength:g} m)"
            )
        return f

    def speed_at(self, freq: ArrayLike) -> np.ndarray | float:
        """Vehicle speed in km/h at which the road wave excites ``freq`` Hz: ``3.6 f lambda``.

        Parameters
        ----------
        freq : float or array_like
            Frequencies in Hz inside :attr:`freq_range`.

        Returns
        -------
        float or ndarray
            Speeds in km/h, same shape as ``freq``.

        Raises
        ------
        FrequencyGridError
            If a frequency lies outside the band.
        """
        f = self._check(freq)
        v = 3.6 * f * self.wavelength
        return float(v) if v.ndim == 0 else v

    def frequencies(self, df: float = 0.5) -> np.ndarray:
        """Default analysis grid: the multiples of ``df`` inside :attr:`freq_range`, in Hz.

        Multiples of a common ``df`` put all cases on one lattice, so that their
        lines coincide where the bands overlap.

        Raises
        ------
        FrequencyGridError
            If ``df`` is not positive or leaves fewer than two lines in the band.
        """
        if not np.isfinite(df) or df <= 0:
            raise FrequencyGridError(f"df must be a positive number of Hz, got {df!r}")
        lo, hi = self.freq_range
        n0 = int(np.ceil(lo / df - _REL_TOL))
        n1 = int(np.floor(hi / df + _REL_TOL))
        if n1 - n0 < 1:
            raise FrequencyGridError(
                f"df = {df:g} Hz leaves fewer than two lines in the {self.name} band "
                f"{lo:.4g}-{hi:.4g} Hz"
            )
        return np.arange(n0, n1 + 1) * df


#: The seven cases, ``HARMONICS[k - 1] == harmonic(k)``.
HARMONICS: tuple[Harmonic, ...] = tuple(Harmonic(k + 1, lam) for k, lam in enumerate(WAVELENGTHS))


def harmonic(k: int | Harmonic) -> Harmonic:
    """The harmonic excitation case number ``k`` (1..7, thesis table 5.1).

    Parameters
    ----------
    k : int or Harmonic
        Case number; a :class:`Harmonic` is returned unchanged.

    Raises
    ------
    HarmonicError
        For anything but the integers 1..7, naming the allowed values.

    Examples
    --------
    >>> harmonic(7).wavelength
    0.0789
    """
    if isinstance(k, Harmonic):
        return k
    if isinstance(k, bool) or not isinstance(k, int | np.integer) or not 1 <= k <= 7:
        raise HarmonicError(
            f"unknown harmonic {k!r}; allowed: 1, 2, 3, 4, 5, 6, 7 (thesis table 5.1)"
        )
    return HARMONICS[int(k) - 1]


def renamed_argument(
    harmonic: int | Harmonic | None,
    harmonic_case: int | Harmonic | None,
    function: str,
    stacklevel: int = 3,
) -> int | Harmonic:
    """The harmonic given as ``harmonic`` or under its deprecated name ``harmonic_case``
    (kept for one release, with a :class:`DeprecationWarning`).

    Raises
    ------
    TypeError
        For neither or both.
    """
    if harmonic_case is None:
        if harmonic is None:
            raise TypeError(f"{function}() missing the argument 'harmonic'")
        return harmonic
    warnings.warn(
        f"{function}(harmonic_case=...) is deprecated; use harmonic=...",
        DeprecationWarning,
        stacklevel=stacklevel,
    )
    if harmonic is not None:
        raise TypeError(f"{function}(): give 'harmonic' only (harmonic_case is its old name)")
    return harmonic_case
