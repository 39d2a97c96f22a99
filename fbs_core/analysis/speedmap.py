"""Speed-frequency map of the bushing response for one harmonic case (waterfall / colour map).

For every vehicle speed ``v`` of a grid, the tire is taken at that fixed speed
(its poles and residues interpolated linearly between the operating points,
thesis section 4.1.2) and loaded by the patch load of the harmonic's road
wavelength ``lambda``; the bushing response over a frequency range is the
coupled response of eq. 4.1,

``v_e*(v, f) = Y_ej^E (Y_jj^A(v) + Y_jj^E)^-1 Y_ja^A(v) F_a``.

In operation only the points on the harmonic line ``f = v / lambda`` are
excited; the line is a cut through the map, and there the map equals
:func:`fbs_core.bushing_response` along the line. The rest of the map shows
which resonances the line would meet at other speeds.

The tire FRFs of all speeds come from one modal synthesis per speed,
``Y(v, f) = j omega sum_r Z_r(v) / (j omega - lambda_r(v))`` with the residues
``Z_r = [psi_r chi_r^T, psi_r p_r]`` (hub mobility and free hub velocity at once;
reference-models.md sec. 2.5), and the coupling solves all speeds and lines in one
batched call.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .. import kernels
from ..chassis import BUSHING, SPINDLE, reference_chassis
from ..dofs import index_of
from ..errors import DataFormatError, FBSError
from ..frf import check_grid
from ..harmonics import Harmonic, renamed_argument
from ..harmonics import harmonic as _harmonic
from ..prediction import coupled_dofs
from ..tire.model import ModeCountError, OperatingPointError
from ..vocabulary import magnitude_db, readonly

__all__ = ["SpeedMap", "speed_map", "default_speeds", "default_freq"]


def default_speeds(tire: Any = None, step: float = 5.0) -> np.ndarray:
    """Speeds ``v_min, v_min + step, ..., v_max`` over the tire's operating points (km/h).

    Parameters
    ----------
    tire : TireModel, optional
        Default the reference tire (20-120 km/h).
    step : float
        Speed step in km/h.
    """
    if tire is None:
        from .. import reference_tire

        tire = reference_tire()
    lo, hi = float(tire.speeds[0]), float(tire.speeds[-1])
    return np.append(np.arange(lo, hi - 1e-9, step), hi)


def default_freq(h: Harmonic, speeds: npt.ArrayLike, df: float = 0.5) -> np.ndarray:
    """Multiples of ``df`` from ``v_min / lambda`` to ``v_max / lambda`` in Hz.

    Parameters
    ----------
    h : Harmonic
    speeds : array_like
        Speeds in km/h.
    df : float
        Line spacing in Hz.
    """
    v = np.asarray(speeds, float)
    lo, hi = v.min() / 3.6 / h.wavelength, v.max() / 3.6 / h.wavelength
    return np.arange(np.ceil(lo / df - 1e-9), np.floor(hi / df + 1e-9) + 1) * df


@functools.lru_cache(maxsize=16)
def _residues(tire: Any, h_index: int) -> np.ndarray:
    """``Z`` of every operating point: (n_s, n_m, 36 + 6), hub mobility and patch residues."""
    R = np.einsum("smi,smj->smij", tire.psi, tire.chi).reshape(*tire.psi.shape[:2], 36)
    Q = tire.psi * tire.participation[:, h_index, :, None]  # (n_s, n_m, 6)
    Z = np.concatenate([R, Q], axis=2)
    Z.setflags(write=False)
    return Z


def _tire_at_speeds(
    tire: Any, h: Harmonic, f: np.ndarray, speeds: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray]:
    """Hub mobility (n_v, n_f, 6, 6) and free hub velocity (n_v, n_f, 6) at fixed speeds."""
    hi = np.flatnonzero(np.isclose(tire.wavelengths, h.wavelength, rtol=1e-9))
    if hi.size == 0:
        raise DataFormatError(
            f"the tire model has no patch participation for wavelength {h.wavelength:g} m "
            f"({h.name}); stored: {', '.join(f'{w:g}' for w in tire.wavelengths)} m"
        )
    if hasattr(tire, "synthesis"):  # the model's own interpolation between its points
        ff = np.tile(f, speeds.size)
        vv = np.repeat(speeds, f.size)
        Y, vj = tire.synthesis(ff, vv, int(hi[0]), None if n >= tire.n_modes else n)
        return Y.reshape(speeds.size, f.size, 6, 6), vj.reshape(speeds.size, f.size, 6)
    Z = _residues(tire, int(hi[0]))[:, :n]
    op = tire.speeds
    k = np.clip(np.searchsorted(op, speeds, side="right") - 1, 0, op.size - 2)
    t = np.clip((speeds - op[k]) / (op[k + 1] - op[k]), 0.0, 1.0)
    s = 2j * np.pi * f
    out = np.empty((speeds.size, f.size, Z.shape[2]), complex)
    for i in range(speeds.size):
        lam = (1 - t[i]) * tire.poles[k[i], :n] + t[i] * tire.poles[k[i] + 1, :n]
        Zi = (1 - t[i]) * Z[k[i]] + t[i] * Z[k[i] + 1]  # (n, 42)
        # (n_f, n) @ (n, 42): the modal sum of eq. 2.5 form, mobility = j omega H
        out[i] = ((1.0 / (s[:, None] - lam[None, :])) @ Zi) * s[:, None]
    return out[..., :36].reshape(speeds.size, f.size, 6, 6), out[..., 36:]


@dataclass(frozen=True, eq=False)
class SpeedMap:
    """Bushing response versus speed and frequency for one harmonic case.

    Attributes
    ----------
    harmonic : int
        Case number 1..7.
    wavelength : float
        Road wavelength in m.
    speeds : ndarray, shape (n_v,)
        Vehicle speeds in km/h.
    freq : ndarray, shape (n_f,)
        Frequencies in Hz.
    outputs : tuple of str, length n_out
        Response DOFs (``bushing:*``).
    response : ndarray, shape (n_v, n_f, n_out)
        Complex mobility (per metre of road amplitude) at each speed and line.
    n_modes : int
        Retained complex tire modes.
    coupling : str
        ``"6dof"`` or ``"5dof"``.
    """

    harmonic: int
    wavelength: float
    speeds: np.ndarray
    freq: np.ndarray
    outputs: tuple[str, ...]
    response: np.ndarray
    n_modes: int
    coupling: str

    def __post_init__(self) -> None:
        for name in ("speeds", "freq", "response"):
            object.__setattr__(self, name, readonly(getattr(self, name)))

    @property
    def line_freq(self) -> np.ndarray:
        """The harmonic line ``f = v / lambda`` in Hz at each speed, shape ``(n_v,)``."""
        return self.speeds / 3.6 / self.wavelength

    def level_db(self, output: str, ref: float = 1.0) -> np.ndarray:
        """``20 log10(|response| / ref)`` of one output, shape ``(n_v, n_f)``.

        Parameters
        ----------
        output : str
            E.g. ``"bushing:z"``.
        ref : float
            Reference of 0 dB.

        Raises
        ------
        DOFError
            For an unknown output.
        """
        i = index_of(self.outputs, output, "response DOF")[0]
        return magnitude_db(self.response[:, :, i], ref, floor=None)

    def export_mapping(self, output: str | None = None) -> dict[str, Any]:
        """The map as a mapping for :func:`fbs_core.io.export_result` (level in dB and
        the complex response, axes speed and frequency)."""
        outs = self.outputs if output is None else (output,)
        idx = index_of(self.outputs, outs, "response DOF")
        lv = magnitude_db(self.response[:, :, idx], floor=None)
        return {
            "level_db": (("speed_kmh", "freq", "output"), lv),
            "response": (("speed_kmh", "freq", "output"), self.response[:, :, idx]),
            "harmonic_line_freq": (("speed_kmh",), self.line_freq),
            "coords": {"speed_kmh": self.speeds, "freq": self.freq, "output": list(outs)},
            "metadata": {
                "harmonic": self.harmonic,
                "wavelength_m": self.wavelength,
                "n_modes": self.n_modes,
                "coupling": self.coupling,
            },
        }


@functools.lru_cache(maxsize=16)
def _cached(k: int, n_modes: int | None, sbytes: bytes, fbytes: bytes, coupling: str) -> SpeedMap:
    from .. import reference_tire

    return _compute(
        reference_tire(),
        reference_chassis(),
        _harmonic(k),
        n_modes,
        np.frombuffer(sbytes, float),
        np.frombuffer(fbytes, float),
        coupling,
    )


def _compute(
    tire: Any,
    chassis: Any,
    h: Harmonic,
    n_modes: int | None,
    v: np.ndarray,
    f: np.ndarray,
    coupling: str,
) -> SpeedMap:
    dofs = coupled_dofs(coupling)
    n = tire.n_modes if n_modes is None else n_modes
    YjjA, vj = _tire_at_speeds(tire, h, f, v, n)
    Y_E = chassis.mobility(f, outputs=SPINDLE + BUSHING, inputs=SPINDLE)
    hub = list(tire.hub_dofs)
    ta = index_of(hub, list(dofs), "coupled hub DOF")
    tc = [SPINDLE.index("spindle:" + d.split(":")[1]) for d in dofs]
    YE = Y_E.data
    YjjE = YE[:, tc][:, :, tc]
    Yej = YE[:, 6:][:, :, tc]
    # eq. 4.1 for all speeds and lines at once: g = (Y_jj^A + Y_jj^E)^-1 v_j, v_e = Y_ej g;
    # singular matrices still raise (no condition-number check: it cost 30 % of the map)
    g = kernels.solve_interface(
        YjjA[:, :, ta][:, :, :, ta] + YjjE[None], vj[:, :, ta][..., None], freq=f
    )
    resp = (Yej[None] @ g)[..., 0]
    return SpeedMap(h.k, h.wavelength, v, f, BUSHING, resp, int(n), coupling)


def speed_map(
    harmonic: Any = None,
    n_modes: int | None = None,
    *,
    speeds: npt.ArrayLike | None = None,
    freq: npt.ArrayLike | None = None,
    coupling: str = "6dof",
    tire: Any = None,
    chassis: Any = None,
    harmonic_case: Any = None,
) -> SpeedMap:
    """Bushing response of a harmonic case over speed and frequency (eq. 4.1 at each speed).

    Parameters
    ----------
    harmonic : int or Harmonic
        Excitation case 1..7 (its wavelength sets the patch load).
    n_modes : int, optional
        Even number of retained complex tire modes; ``None`` keeps all.
    speeds : array_like, shape (n_v,), optional
        Speeds in km/h within the tire's operating points; default every 5 km/h
        over them (20-120 km/h: 21 speeds).
    freq : array_like, shape (n_f,), optional
        Frequencies in Hz; default multiples of 0.5 Hz from ``v_min / lambda`` to
        ``v_max / lambda``.
    coupling : {"6dof", "5dof"}
    tire : TireModel, optional
        Default the reference tire.
    chassis : ChassisModel, optional
        Default the reference chassis.
    harmonic_case : int or Harmonic, optional
        Deprecated name of ``harmonic`` (a ``DeprecationWarning``; removed in the next
        release).

    Returns
    -------
    SpeedMap

    Raises
    ------
    OperatingPointError
        Speeds outside the operating points.
    ModeCountError
        An odd or out-of-range ``n_modes``.
    HarmonicError, CouplingOptionError, FrequencyGridError, SingularInterfaceError

    Examples
    --------
    >>> m = speed_map(1, n_modes=40)                      # doctest: +SKIP
    >>> m.level_db("bushing:z").shape == (m.speeds.size, m.freq.size)  # doctest: +SKIP
    True
    """
    h = _harmonic(renamed_argument(harmonic, harmonic_case, "speed_map"))
    coupled_dofs(coupling)
    ref = tire is None and chassis is None
    if tire is None:
        from .. import reference_tire

        tire = reference_tire()
    n_total = tire.n_modes
    if n_modes is not None and (
        isinstance(n_modes, bool)
        or not isinstance(n_modes, int | np.integer)
        or n_modes % 2
        or not 2 <= n_modes <= n_total
    ):
        raise ModeCountError(
            f"n_modes must be an even integer from 2 to {n_total} or None for all; got {n_modes!r}"
        )
    v = default_speeds(tire) if speeds is None else np.asarray(speeds, float).ravel()
    if v.size == 0 or np.any(np.diff(v) <= 0):
        raise FBSError(f"speeds must be increasing values in km/h, got {v.tolist()}")
    lo, hi = tire.speeds[0], tire.speeds[-1]
    bad = ~np.isfinite(v) | (v < lo - 1e-9) | (v > hi + 1e-9)
    if bad.any():
        raise OperatingPointError(
            f"speed {v[bad][0]:g} km/h is outside the operating points "
            f"{', '.join(f'{s:g}' for s in tire.speeds)} km/h; never extrapolated"
        )
    f = default_freq(h, v) if freq is None else check_grid(np.asarray(freq))
    n = None if n_modes is None else int(n_modes)
    if ref:
        return _cached(h.k, n, v.tobytes(), f.tobytes(), coupling)
    return _compute(tire, reference_chassis() if chassis is None else chassis, h, n, v, f, coupling)
