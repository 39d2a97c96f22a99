"""The road as each wheel sees it: wheelbase delay, the two tracks, ISO 8608 roughness.

A road profile ``z(s)`` along the left track is met by the front-left wheel at
``s = v t`` and by the rear-left wheel a wheelbase ``L`` later: at the spatial
frequency ``n = 1 / lambda`` (cycles/m) the rear wheel's input is the front's
times ``exp(-j 2 pi n L)``. Along a harmonic line (fixed wavelength, thesis section
4.1.2) that phase is the same at every line, ``2 pi L / lambda``; at a fixed speed
``v`` it turns with frequency, ``2 pi f L / v`` (wheelbase filtering: a bounce
input cancels where ``f L / v`` is half an odd integer).

The right track relates to the left one by a real coherency ``rho`` in [-1, 1]:
``"in phase"`` (1), ``"anti-phase"`` (-1), a constant, or ``"isotropic"``, the
coherency of two parallel tracks a distance ``B`` apart on an isotropic road with
the ISO 8608 spectrum (waviness ``w = 2``; Dodds & Robson, J. Sound Vib. 31(2),
1973; Kamash & Robson, J. Sound Vib. 57(1), 1978)::

    rho(n) = 2 pi n B K_1(2 pi n B)          (K_1: modified Bessel function)

(1 for long waves, falling to 0.5 at ``n B = 0.20`` and to 0.1 at ``n B = 0.51``;
derivation in docs/vehicle-model.md). The two tracks are written as two
uncorrelated components, ``z_L = a s + b d``, ``z_R = a s - b d`` with
``a = sqrt((1 + rho) / 2)``, ``b = sqrt((1 - rho) / 2)``: the in-phase and the
anti-phase component, each a coherent input of all four wheels.

Random roads follow ISO 8608 (1995, 2016): displacement PSD (one-sided)
``G_d(n) = G_d(n_0) (n / n_0)^-w``, ``n_0 = 0.1`` cycles/m, ``w = 2``, classes A-H
with ``G_d(n_0)`` = 16, 64, 256, 1024, 4096, 16384, 65536, 262144 x 1e-6 m^3 (the
geometric means of the classes); at speed ``v`` the temporal PSD is
``G(f) = G_d(f / v) / v`` in m^2/Hz.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import k1

from .._typing import ComplexArray, FloatArray
from ..errors import FBSError
from .layout import WHEELS, check_wheels

__all__ = [
    "ISO_8608",
    "N0",
    "TRACKS",
    "RoadProfile",
    "Road",
    "iso8608_psd",
    "isotropic_coherence",
    "COMPONENTS",
]

#: ISO 8608 classes: ``G_d(n_0)`` in m^3 (geometric mean of each class), n_0 = 0.1 /m.
ISO_8608: dict[str, float] = {c: 16e-6 * 4**k for k, c in enumerate("ABCDEFGH")}
#: Reference spatial frequency of ISO 8608, cycles/m.
N0 = 0.1
#: Named relations between the two tracks (a number in [-1, 1] is also allowed).
TRACKS: tuple[str, ...] = ("in phase", "anti-phase", "isotropic")
#: Labels of the two uncorrelated track components.
COMPONENTS: tuple[str, str] = ("road_in_phase", "road_anti_phase")


def iso8608_psd(n: ArrayLike, gd0: float, waviness: float = 2.0) -> FloatArray:
    """ISO 8608 displacement PSD ``G_d(n) = G_d(n_0) (n / n_0)^-w``, m^3 (one-sided).

    Parameters
    ----------
    n : array_like
        Spatial frequencies, cycles/m (> 0).
    gd0 : float
        ``G_d(n_0)`` in m^3 (:data:`ISO_8608`).
    waviness : float
        ``w`` (2 in the standard's classification).
    """
    a = np.asarray(n, float)
    out: FloatArray = gd0 * (a / N0) ** (-waviness)
    return out


def isotropic_coherence(n: ArrayLike, track: float) -> FloatArray:
    """Coherency of two parallel tracks ``track`` m apart on an isotropic road (w = 2).

    ``rho = 2 pi n B K_1(2 pi n B)`` (Dodds & Robson 1973), 1 at ``n = 0``.
    """
    x = 2 * np.pi * np.asarray(n, float) * float(track)
    with np.errstate(invalid="ignore"):
        out: FloatArray = np.where(x > 0, x * k1(np.where(x > 0, x, 1.0)), 1.0)
    return out


@dataclass(frozen=True)
class RoadProfile:
    """Random road roughness of ISO 8608.

    Parameters
    ----------
    road_class : str, optional
        ``"A"`` ... ``"H"`` (sets ``gd0``).
    gd0 : float, optional
        ``G_d(n_0)`` in m^3, instead of a class.
    waviness : float
        ``w``; 2 in the standard (the isotropic coherency assumes 2).
    """

    road_class: str | None = "C"
    gd0: float | None = None
    waviness: float = 2.0

    def __post_init__(self) -> None:
        if self.gd0 is None:
            if self.road_class not in ISO_8608:
                raise FBSError(
                    f"unknown ISO 8608 road class {self.road_class!r}; allowed: "
                    f"{', '.join(ISO_8608)} (or give gd0 in m^3)"
                )
        elif not (np.isfinite(self.gd0) and self.gd0 > 0):
            raise FBSError(f"gd0 must be a positive G_d(n0) in m^3, got {self.gd0!r}")
        if not (np.isfinite(self.waviness) and 0 < self.waviness < 5):
            raise FBSError(f"waviness must be in (0, 5) (ISO 8608: 2), got {self.waviness!r}")

    @property
    def level(self) -> float:
        """``G_d(n_0)`` in m^3."""
        return float(ISO_8608[str(self.road_class)] if self.gd0 is None else self.gd0)

    def psd(self, n: ArrayLike) -> FloatArray:
        """Displacement PSD at spatial frequencies ``n`` (cycles/m), m^3."""
        return iso8608_psd(n, self.level, self.waviness)


def _coherency(tracks: str | float) -> str | float:
    if isinstance(tracks, str):
        if tracks not in TRACKS:
            raise FBSError(
                f"unknown track relation {tracks!r}; allowed: {', '.join(map(repr, TRACKS))} "
                "or a coherency in [-1, 1]"
            )
        return {"in phase": 1.0, "anti-phase": -1.0}.get(tracks, tracks)
    r = float(tracks)
    if isinstance(tracks, bool) or not -1.0 <= r <= 1.0:
        raise FBSError(f"the coherency of the two tracks must be in [-1, 1], got {tracks!r}")
    return r


@dataclass(frozen=True)
class Road:
    """What the four wheels see: one wavelength (a harmonic case) or one speed.

    Exactly one of ``wavelength`` and ``speed_kmh`` is given.

    Parameters
    ----------
    wavelength : float, optional
        Road wavelength in m (harmonic case: the speed follows the line).
    speed_kmh : float, optional
        Vehicle speed (every line its own wavelength ``v / f``).
    tracks : str or float
        ``"in phase"``, ``"anti-phase"``, ``"isotropic"`` or a coherency in [-1, 1].
    profile : RoadProfile, optional
        Random roughness (fixed speed only): the inputs become amplitude spectral
        densities ``sqrt(G(f))`` in m / sqrt(Hz); without it every wheel's input is
        1 m of road amplitude (the left-front wheel's phase as reference).
    wheels : sequence of str
        Wheels whose road input is on (the others still carry their tire).
    """

    wavelength: float | None = None
    speed_kmh: float | None = None
    tracks: str | float = "in phase"
    profile: RoadProfile | None = None
    wheels: tuple[str, ...] = WHEELS

    def __post_init__(self) -> None:
        if (self.wavelength is None) == (self.speed_kmh is None):
            raise FBSError("give a road wavelength (harmonic case) or a speed, not both")
        x = self.wavelength if self.wavelength is not None else self.speed_kmh
        if not (x is not None and np.isfinite(x) and x > 0):
            raise FBSError(f"the road wavelength (m) or speed (km/h) must be positive, got {x!r}")
        if self.profile is not None and self.wavelength is not None:
            raise FBSError("a random road profile needs a fixed speed (all wavelengths)")
        _coherency(self.tracks)
        object.__setattr__(self, "wheels", check_wheels(self.wheels, "driven wheel"))

    def spatial_frequency(self, freq: ArrayLike) -> FloatArray:
        """``n`` (cycles/m) of every line: ``1 / lambda`` or ``f / v``."""
        f = np.asarray(freq, float)
        if self.wavelength is not None:
            out: FloatArray = np.full(f.shape, 1.0 / self.wavelength)
            return out
        assert self.speed_kmh is not None
        out = f / (self.speed_kmh / 3.6)
        return out

    def coherency(self, freq: ArrayLike, track: float) -> FloatArray:
        """``rho`` between the tracks at every line (``track``: their distance, m)."""
        c = _coherency(self.tracks)
        f = np.asarray(freq, float)
        if c == "isotropic":
            return isotropic_coherence(self.spatial_frequency(f), track)
        return np.full(f.shape, float(c))

    def components(
        self, freq: ArrayLike, wheelbase: float, track: float
    ) -> tuple[tuple[str, ...], ComplexArray]:
        """Road input of every wheel for each uncorrelated component.

        Returns
        -------
        labels : tuple of str
            :data:`COMPONENTS` that are not identically zero.
        U : ndarray, shape (n_f, 4, n_c)
            Input of wheel ``WHEELS[w]`` (m per m of road amplitude, or m / sqrt(Hz)
            with a profile); the response to component ``c`` is ``H @ U[:, :, c]``.
        """
        f = np.asarray(freq, float)
        n = self.spatial_frequency(f)
        rho = self.coherency(f, track)
        d = np.exp(-2j * np.pi * n * float(wheelbase))  # rear = front delayed
        a, b = np.sqrt((1 + rho) / 2), np.sqrt((1 - rho) / 2)
        one = np.ones_like(d)
        pattern = {
            COMPONENTS[0]: (a, np.stack([one, one, d, d], axis=1)),
            COMPONENTS[1]: (b, np.stack([one, -one, d, -d], axis=1)),
        }
        on = np.array([w in self.wheels for w in WHEELS], float)
        amp = np.ones(f.shape)
        if self.profile is not None:
            v = float(self.speed_kmh or 0.0) / 3.6
            amp = np.sqrt(self.profile.psd(n) / v)
        labels, cols = [], []
        for name, (weight, u) in pattern.items():
            if np.all(weight == 0):
                continue
            labels.append(name)
            cols.append((weight * amp)[:, None] * u * on[None, :])
        return tuple(labels), np.stack(cols, axis=-1)
