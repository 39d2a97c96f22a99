"""The modal tire model in the form a tire supplier delivers it.

A :class:`TireModel` holds, per operating point (vehicle speed), the complex
poles, the right and left mode shapes at the hub's 6 DOFs (normalised to
``a_r = 1``, see :mod:`.modes`) and the modal participation of the patch load
of each harmonic case, ``p_r = chi_r^T f_patch``. From these it synthesises

* the hub mobility ``Y_jj^A(omega) = j omega sum_r psi_r chi_r^T / (j omega - lambda_r)``,
* the free hub velocity ``Y_ja^A F_a = j omega sum_r psi_r p_r / (j omega - lambda_r)``,

keeping the first ``N`` modes (``N / 2`` conjugate pairs, lowest first; thesis
section 5.1). Along a harmonic line the speed is ``v = f lambda``; between two
operating points the poles and the residues (``psi_r chi_r^T`` and
``psi_r p_r``, which do not depend on how the shapes are scaled) are
interpolated linearly in speed (thesis section 4.1.2). Modes are tracked across
operating points before storing (:func:`.modes.track_modes`), so that mode ``r``
is the same mode at every speed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..direct import SecondOrderSystem
from ..errors import DataFormatError, FBSError
from ..frf import FRF, check_grid
from ..harmonics import Harmonic, harmonic
from .params import TireParameters
from .ring import HUB_DOFS, build_tire_system
from .ring import patch_load as _patch_load

__all__ = ["TireModel", "OperatingPointError", "ModeCountError"]


class OperatingPointError(FBSError):
    """A speed outside the operating points of the modal model."""


class ModeCountError(FBSError):
    """A number of retained modes that is not an even count in the allowed range."""


def _ro(a) -> np.ndarray:
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class TireModel:
    """Complex-mode model of a rolling tire at several operating points.

    Parameters
    ----------
    speeds : ndarray, shape (n_s,)
        Operating points in km/h, increasing.
    poles : ndarray, shape (n_s, n_m)
        ``lambda_r`` in rad/s, conjugate pairs ``[r, conj(r), ...]`` lowest first.
    psi, chi : ndarray, shape (n_s, n_m, 6)
        Right and left mode shapes at ``hub:x`` ... ``hub:rz`` (m, rad per unit
        modal coordinate), scaled so that ``a_r = 1``.
    wavelengths : ndarray, shape (n_h,)
        Road wavelengths in m for which the patch participation is stored.
    participation : ndarray, shape (n_s, n_h, n_m)
        ``chi_r^T f_patch`` per operating point and wavelength (patch load per
        metre of road amplitude).
    params : TireParameters or None
        Physical parameters, if the model was built from them (enables
        :meth:`system` and :meth:`patch_load`).
    meta : dict
        Free-form provenance (source, format version, ...).
    hub_dofs : tuple of str
        Labels of the 6 hub DOFs, ``hub:x`` ... ``hub:rz`` in vehicle coordinates.
    """

    speeds: np.ndarray
    poles: np.ndarray
    psi: np.ndarray
    chi: np.ndarray
    wavelengths: np.ndarray
    participation: np.ndarray
    params: TireParameters | None = None
    meta: dict = field(default_factory=dict)
    hub_dofs: tuple[str, ...] = HUB_DOFS

    def __post_init__(self):
        sp = np.asarray(self.speeds, float)
        n_s = sp.size
        if sp.ndim != 1 or n_s < 2 or np.any(np.diff(sp) <= 0):
            raise DataFormatError(f"speeds must be >= 2 increasing values, got {sp}")
        poles = np.asarray(self.poles, complex)
        if poles.ndim != 2 or poles.shape[0] != n_s or poles.shape[1] % 2:
            raise DataFormatError(
                f"poles must have shape (n_speeds={n_s}, even n_modes), got {poles.shape}"
            )
        n_m = poles.shape[1]
        for name in ("psi", "chi"):
            a = np.asarray(getattr(self, name))
            if a.shape != (n_s, n_m, 6):
                raise DataFormatError(f"{name} has shape {a.shape}, expected {(n_s, n_m, 6)}")
        lam = np.asarray(self.wavelengths, float).ravel()
        part = np.asarray(self.participation, complex)
        if part.shape != (n_s, lam.size, n_m):
            raise DataFormatError(
                f"participation has shape {part.shape}, expected {(n_s, lam.size, n_m)}"
            )
        a, b = poles[:, 0::2], poles[:, 1::2]
        first_order = (a.imag == 0) & (b.imag == 0)  # two real poles (e.g. tread slip)
        if not np.all(first_order | (np.isclose(b, np.conj(a)) & (a.imag > 0))):
            raise DataFormatError(
                "poles must come in conjugate pairs [r, conj(r), ...] with the member of "
                "positive eigenfrequency first, or in pairs of two real poles (first-order "
                "modes)"
            )
        for name, val in (
            ("speeds", sp),
            ("poles", poles),
            ("psi", self.psi),
            ("chi", self.chi),
            ("wavelengths", lam),
            ("participation", part),
        ):
            object.__setattr__(self, name, _ro(np.asarray(val)))
        object.__setattr__(self, "hub_dofs", tuple(self.hub_dofs))
        # residues, invariant to the scaling of the shapes: (n_s, n_m, 6 * 6 + 6 * n_h)
        R = np.einsum("smi,smj->smij", self.psi, self.chi).reshape(n_s, n_m, 36)
        Q = np.einsum("smi,shm->smhi", self.psi, part).reshape(n_s, n_m, 6 * lam.size)
        object.__setattr__(self, "_Z", np.concatenate([R, Q], axis=2))

    # -- basic information -----------------------------------------------------------
    @property
    def n_modes(self) -> int:
        """Number of complex modes (both members of every pair)."""
        return self.poles.shape[1]

    def _weights(self, speed_kmh) -> tuple[np.ndarray, np.ndarray]:
        v = np.atleast_1d(np.asarray(speed_kmh, float))
        lo, hi = self.speeds[0], self.speeds[-1]
        bad = ~np.isfinite(v) | (v < lo - 1e-9) | (v > hi + 1e-9)
        if np.any(bad):
            raise OperatingPointError(
                f"speed {v[bad][0]:g} km/h is outside the operating points "
                f"{', '.join(f'{s:g}' for s in self.speeds)} km/h; the modal model is "
                "interpolated between them, never extrapolated"
            )
        k = np.clip(np.searchsorted(self.speeds, v, side="right") - 1, 0, self.speeds.size - 2)
        t = np.clip((v - self.speeds[k]) / (self.speeds[k + 1] - self.speeds[k]), 0.0, 1.0)
        return k, t

    def poles_at(self, speed_kmh: float) -> np.ndarray:
        """Poles interpolated linearly in speed, shape (n_m,)."""
        k, t = self._weights(speed_kmh)
        return (1 - t[0]) * self.poles[k[0]] + t[0] * self.poles[k[0] + 1]

    def eigenfrequencies(self, speed_kmh: float) -> np.ndarray:
        """Positive eigenfrequencies ``Im(lambda) / 2 pi`` in Hz at ``speed_kmh``, sorted.

        Raises
        ------
        OperatingPointError
            Outside the operating points.
        """
        p = self.poles_at(speed_kmh)
        return np.sort(p[p.imag > 0].imag) / (2 * np.pi)

    def _check_n(self, n_modes) -> int:
        if n_modes is None:
            return self.n_modes
        ok = (
            isinstance(n_modes, int | np.integer)
            and not isinstance(n_modes, bool)
            and n_modes % 2 == 0
            and 10 <= n_modes <= self.n_modes
        )
        if not ok:
            raise ModeCountError(
                f"n_modes must be an even integer from 10 to {self.n_modes} (modes are kept "
                f"in conjugate pairs, lowest first) or None for all; got {n_modes!r}"
            )
        return int(n_modes)

    def _harmonic_index(self, h: Harmonic) -> int:
        i = np.flatnonzero(np.isclose(self.wavelengths, h.wavelength, rtol=1e-9))
        if i.size == 0:
            raise DataFormatError(
                f"the model has no patch participation for wavelength {h.wavelength:g} m "
                f"({h.name}); stored: {', '.join(f'{w:g}' for w in self.wavelengths)} m"
            )
        return int(i[0])

    # -- modal synthesis -------------------------------------------------------------
    def _sums(self, freq, speeds, n_list, h_index) -> tuple[np.ndarray, np.ndarray]:
        """Cumulative modal sums: mobility (n_N, n_f, 6, 6) and patch velocity (n_N, n_f, 6)."""
        f = np.asarray(freq, float)
        k, t = self._weights(speeds)
        s = 2j * np.pi * f
        if h_index is None:
            Z = self._Z[:, :, :36]
        else:
            Z = self._Z[:, :, np.r_[np.arange(36), 36 + 6 * h_index + np.arange(6)]]
        edges = np.r_[0, n_list]
        out = np.zeros((len(n_list), f.size, Z.shape[2]), complex)
        for kk in np.unique(k):
            idx = np.flatnonzero(k == kk)
            tt = t[idx][:, None]
            lam = (1 - tt) * self.poles[kk][None, :] + tt * self.poles[kk + 1][None, :]
            T = 1.0 / (s[idx, None] - lam)  # (n_lines, n_modes)
            Ta, Tb = T * (1 - tt), T * tt
            for b in range(len(n_list)):
                sl = slice(edges[b], edges[b + 1])
                # (n_lines, n_block) @ (n_block, n_res)
                out[b, idx] = Ta[:, sl] @ Z[kk, sl] + Tb[:, sl] @ Z[kk + 1, sl]
        out = np.cumsum(out, axis=0) * s[None, :, None]  # mobility = j omega H
        Y = out[:, :, :36].reshape(len(n_list), f.size, 6, 6)
        v = out[:, :, 36:] if h_index is not None else None
        return Y, v

    def hub_mobility(self, freq, speed_kmh: float, n_modes: int | None = None) -> FRF:
        """Hub mobility ``Y_jj^A`` (6 x 6) at a fixed speed, from the first ``n_modes`` modes.

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz.
        speed_kmh : float
            Vehicle speed within the operating points.
        n_modes : int, optional
            Even number of complex modes, 10..n_modes; ``None`` keeps all.

        Returns
        -------
        FRF
            Mobility, outputs and inputs ``hub:x`` ... ``hub:rz`` (vehicle axes).
        """
        f = check_grid(freq)
        n = self._check_n(n_modes)
        Y, _ = self._sums(f, np.full(f.size, float(speed_kmh)), [n], None)
        return FRF(f, Y[0], self.hub_dofs, self.hub_dofs, "mobility")

    def patch_response(
        self, freq, harmonic_case, n_modes: int | None = None, speed_kmh: float | None = None
    ) -> FRF:
        """Free hub velocity ``Y_ja^A F_a`` for the patch load of a harmonic case.

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz inside the harmonic's band.
        harmonic_case : int or Harmonic
            Case 1..7.
        n_modes : int, optional
            Even number of complex modes kept; ``None`` keeps all.
        speed_kmh : float, optional
            Evaluate at this fixed speed instead of along the line ``v = f lambda``
            (then any positive frequencies are allowed).

        Returns
        -------
        FRF
            Outputs ``hub:*``, one input ``patch`` (per metre of road amplitude).
        """
        h = harmonic(harmonic_case)
        f = check_grid(freq)
        n = self._check_n(n_modes)
        hi = self._harmonic_index(h)
        v = h.speed_at(f) if speed_kmh is None else np.full(f.size, float(speed_kmh))
        _, vj = self._sums(f, np.atleast_1d(v), [n], hi)
        return FRF(f, vj[0][:, :, None], self.hub_dofs, ["patch"], "mobility")

    def truncations(self, freq, harmonic_case, n_modes_list) -> tuple[np.ndarray, np.ndarray]:
        """Hub mobility and free hub velocity along a harmonic line for many truncations.

        Cumulative modal sums give every truncation for the price of one full
        synthesis.

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz inside the harmonic's band.
        harmonic_case : int or Harmonic
        n_modes_list : sequence of int
            Increasing even mode counts, each 10..n_modes.

        Returns
        -------
        Yjj : ndarray, shape (n_N, n_freq, 6, 6)
        vj : ndarray, shape (n_N, n_freq, 6)
        """
        h = harmonic(harmonic_case)
        f = check_grid(freq)
        ns = [
            self._check_n(int(n)) if isinstance(n, int | np.integer) else self._check_n(n)
            for n in n_modes_list
        ]
        if not ns or np.any(np.diff(ns) <= 0):
            raise ModeCountError(f"n_modes_list must be non-empty and increasing, got {ns}")
        return self._sums(f, h.speed_at(f), ns, self._harmonic_index(h))

    # -- physical model --------------------------------------------------------------
    def _need_params(self) -> TireParameters:
        if self.params is None:
            raise DataFormatError(
                "this modal model carries no physical parameters (e.g. a supplier's "
                "model), so its system matrices are not available"
            )
        return self.params

    def system(self, speed_kmh: float) -> SecondOrderSystem:
        """The tire's matrices at ``speed_kmh`` (``M``, ``C = D + G``, ``K``), hub first."""
        return build_tire_system(float(speed_kmh), self._need_params())

    def patch_load(self, speed_kmh: float, wavelength: float) -> np.ndarray:
        """Physical load vector of the input ``patch`` (N per m of road), shape (n_dof,).

        The patch is space fixed, so the load does not depend on the speed.
        """
        if not np.isfinite(wavelength) or wavelength <= 0:
            raise FBSError(f"wavelength must be a positive length in m, got {wavelength!r}")
        return _patch_load(float(wavelength), self._need_params())
