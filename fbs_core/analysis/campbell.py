"""The tire across speed: Campbell diagram with forward / backward branches and the
harmonic order lines ``f = v / lambda`` of the seven excitation cases.

Branches are the tracked complex modes of the modal tire model (mode ``r`` is the
same tracked mode at every operating point, :func:`fbs_core.tire.track_modes`);
their eigenfrequencies ``Im(lambda_r) / 2 pi`` are interpolated in speed exactly as the
model does for synthesis (:meth:`fbs_core.tire.TireModel.poles_at`: cubic Lagrange
weights by default, clusters through their characteristic polynomial; thesis section
4.1.2). That tracking serves the interpolation (MAC and frequency distance between
neighbouring operating points), not the waves: on the reference tire these branches
do not follow the forward waves of ring orders 4-8 (docs/modes.md). A model with its
matrices has :func:`fbs_core.analysis.wave_campbell`, whose branches are the waves.

Forward or backward: in the space-fixed frame a wave travelling with the
rotation is Doppler shifted up and one travelling against it down. For a ring of
order ``n`` (reference-models.md sec. 2.1; Huang & Soedel 1987)

``omega_n(+/-) = (+/- g_n + sqrt(g_n^2 + M_n K_n)) / M_n``,  ``g_n = rhoA Omega n (n^2 - 1)``.

Two criteria (``method=``):

* ``"shape"`` (for a model that carries its physical parameters): the
  travelling direction of the belt wave in the mode shape. A belt order ``n`` is
  ``a_c cos(n theta) + a_s sin(n theta)``; a wave ``cos(n theta - omega t)``
  running in the spin direction (+theta, see :mod:`fbs_core.tire.ring`) has
  ``(a_c, a_s) ~ (1, -j)``, one running against it ``(1, +j)``. The travelling
  index ``tau = sum 2 Im(conj(a_c) a_s) / sum (|a_c|^2 + |a_s|^2)`` (over all
  cos/sin pairs of the shape) is -1 for a pure forward wave, +1 for a pure
  backward wave and 0 for a standing wave. It is computed from the complex modes
  of ``tire.system(v)`` at every operating point, matched to the model's tracked
  modes by their poles, and averaged over the operating points: ``tau < -0.2``
  forward, ``> 0.2`` backward, else standing. On the ring without contact the
  ``+`` branch of the closed form has ``tau = -1`` (tested).
* ``"slope"`` (the default, and the only one for a supplier's model without
  matrices, whose 6 hub DOFs do not show the belt wave): the sign of the mean
  ``df/dv`` of the tracked branch over the operating points (least-squares slope),
  forward if the shift over the range exceeds ``max(0.5 Hz, 1 %)``, backward below
  minus that, standing in between. It is exact for the ring (the gyroscopic split is
  odd in ``Omega`` and the ring's even part is small), but centrifugal softening and
  the veering of dense branches bias it in the full tire; the shape criterion does
  not depend on the frequencies. On the reference tire the two agree on 73 % of the
  103 branches that shift by more than 10 Hz over 20-120 km/h, and 35 branches
  labelled standing by shape are called backward by slope
  (``scripts/print_campbell_check.py``): the model's tracked modes pass between waves
  at the veerings, 34 of those 35 flip between a forward and a backward wave along
  the speeds (median ``|tau|`` 0.76 at an operating point, 0.09 averaged). The shape
  criterion costs one dense complex-mode solve per
  operating point (about 40 s for the reference tire on a loaded 2-core machine, then
  cached per model), the slope criterion milliseconds.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.optimize import linear_sum_assignment

from ..errors import FBSError
from ..harmonics import HARMONICS

__all__ = [
    "Campbell",
    "travelling_index",
    "Crossing",
    "DIRECTIONS_OF_TRAVEL",
    "campbell",
    "classify_branches",
    "harmonic_lines",
]

#: Labels of the branches.
DIRECTIONS_OF_TRAVEL = ("forward", "backward", "standing")


def classify_branches(
    speeds: npt.ArrayLike, freq: npt.ArrayLike, tol_hz: float = 0.5, tol_rel: float = 0.01
) -> tuple[tuple[str, ...], np.ndarray]:
    """Forward / backward / standing label of each branch from its mean ``df/dv``.

    Parameters
    ----------
    speeds : ndarray, shape (n_s,)
        Operating speeds in km/h (at least 2, increasing).
    freq : ndarray, shape (n_s, n_b)
        Eigenfrequency of each tracked branch in Hz.
    tol_hz, tol_rel : float
        A branch is standing when its shift over the range, ``slope (v_max - v_min)``,
        is below ``max(tol_hz, tol_rel * mean frequency)``.

    Returns
    -------
    labels : tuple of str, length n_b
        ``"forward"``, ``"backward"`` or ``"standing"``.
    slope : ndarray, shape (n_b,)
        Least-squares slope in Hz per km/h.

    Raises
    ------
    FBSError
        For fewer than two speeds or mismatched shapes.
    """
    v = np.asarray(speeds, float)
    F = np.asarray(freq, float)
    if v.ndim != 1 or v.size < 2 or np.any(np.diff(v) <= 0):
        raise FBSError(f"speeds must be >= 2 increasing values in km/h, got {v.tolist()}")
    if F.ndim != 2 or F.shape[0] != v.size:
        raise FBSError(f"freq must have shape (n_speeds={v.size}, n_branches), got {F.shape}")
    vc = v - v.mean()
    a = vc @ (F - F.mean(axis=0)) / (vc @ vc)
    shift = a * (v[-1] - v[0])
    tol = np.maximum(tol_hz, tol_rel * np.abs(F).mean(axis=0))
    labels = np.where(shift > tol, "forward", np.where(shift < -tol, "backward", "standing"))
    return tuple(str(x) for x in labels), a


def travelling_index(psi: np.ndarray, dofs: Sequence[str]) -> np.ndarray:
    """Travelling-wave index of mode shapes: -1 forward, +1 backward, 0 standing.

    ``tau = sum_pairs 2 Im(conj(a_c) a_s) / sum_pairs (|a_c|^2 + |a_s|^2)`` over the
    cos / sin pairs of the belt coordinates (labels ending in ``c`` and ``s`` with
    the same stem, e.g. ``belt.ip.n03c`` / ``belt.ip.n03s``); see the module notes.

    Parameters
    ----------
    psi : ndarray, shape (n_dof, n_modes)
        Right mode shapes (complex).
    dofs : sequence of str, length n_dof
        DOF labels of the rows.

    Returns
    -------
    ndarray, shape (n_modes,)
        0 for shapes without any cos / sin pair content.

    Raises
    ------
    FBSError
        If the labels hold no cos / sin pair.
    """
    pos = {d: i for i, d in enumerate(dofs)}
    pairs = [
        (i, pos[d[:-1] + "s"]) for d, i in pos.items() if d.endswith("c") and d[:-1] + "s" in pos
    ]
    if not pairs:
        raise FBSError("no cos / sin coordinate pairs (labels '...c' / '...s') among the DOFs")
    c, s = (np.array(x) for x in zip(*pairs, strict=True))
    pc, ps = psi[c], psi[s]
    num = 2 * np.imag(np.conj(pc) * ps).sum(0)
    den = (np.abs(pc) ** 2 + np.abs(ps) ** 2).sum(0)
    return np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)


@functools.lru_cache(maxsize=8)
def _shape_index(tire: Any) -> np.ndarray:
    """Travelling index of every tracked mode pair at every operating point, (n_s, n_b)."""
    from ..tire import complex_modes

    out = np.empty((tire.speeds.size, tire.n_modes // 2))
    for i, v in enumerate(tire.speeds):
        s = tire.system(float(v))
        md = complex_modes(np.real(s.M), np.real(s.C), np.real(s.K))
        tau = travelling_index(md.psi[:, 0::2], s.dofs)
        model = tire.poles[i, 0::2]
        # the model's tracked modes are modes of this very system: match by pole
        cost = np.abs(model[:, None] - md.poles[0::2][None, :])
        _, cols = linear_sum_assignment(cost)
        out[i] = tau[cols]
    return out


def harmonic_lines(speeds: npt.ArrayLike, wavelengths: npt.ArrayLike | None = None) -> np.ndarray:
    """Order lines ``f = v / lambda`` (v in m/s) of the harmonic cases, shape (n_v, n_h).

    Parameters
    ----------
    speeds : array_like, shape (n_v,)
        Speeds in km/h.
    wavelengths : array_like, shape (n_h,), optional
        Road wavelengths in m; default the seven cases (thesis table 5.1).
    """
    lam = np.array([h.wavelength for h in HARMONICS] if wavelengths is None else wavelengths)
    return np.asarray(np.asarray(speeds, float)[:, None] / 3.6 / lam[None, :], float)


@dataclass(frozen=True)
class Crossing:
    """A harmonic line crossing a tire branch: that case excites that mode at that speed.

    Attributes
    ----------
    harmonic : int
        Case number 1..7.
    branch : int
        Index of the tracked mode pair.
    speed_kmh, freq : float
        Where the line meets the branch.
    direction : str
        The branch's label.
    """

    harmonic: int
    branch: int
    speed_kmh: float
    freq: float
    direction: str


@dataclass(frozen=True, eq=False)
class Campbell:
    """Tire eigenfrequencies versus speed with the harmonic order lines.

    Attributes
    ----------
    speeds : ndarray, shape (n_v,)
        Speeds in km/h.
    branch : ndarray of int, shape (n_b,)
        Index of each tracked mode pair in the model (0 = lowest); pairs of real poles
        (first-order states, no eigenfrequency) are left out.
    freq : ndarray, shape (n_v, n_b)
        Eigenfrequency of each branch in Hz.
    damping : ndarray, shape (n_v, n_b)
        Damping ratio of each branch.
    direction : ndarray of str, shape (n_b,)
        ``"forward"``, ``"backward"`` or ``"standing"`` (see module notes).
    slope : ndarray, shape (n_b,)
        Mean ``df/dv`` of each branch in Hz per km/h.
    travelling : ndarray, shape (n_b,)
        Travelling index averaged over the operating points (-1 forward, +1
        backward); NaN with ``method="slope"``.
    method : str
        Criterion of ``direction``: ``"shape"`` or ``"slope"``.
    harmonic : ndarray of int, shape (n_h,)
        Harmonic case numbers.
    wavelength : ndarray, shape (n_h,)
        Road wavelengths in m.
    lines : ndarray, shape (n_v, n_h)
        ``f = v / lambda`` in Hz.
    in_band : ndarray of bool, shape (n_v, n_h)
        Where the line lies inside the case's speed range (30-120 km/h).
    """

    speeds: np.ndarray
    branch: np.ndarray
    freq: np.ndarray
    damping: np.ndarray
    direction: np.ndarray
    slope: np.ndarray
    travelling: np.ndarray
    method: str
    harmonic: np.ndarray
    wavelength: np.ndarray
    lines: np.ndarray
    in_band: np.ndarray

    def crossings(self, in_band: bool = True) -> tuple[Crossing, ...]:
        """Speeds where a harmonic line meets a branch (linear between grid speeds).

        Parameters
        ----------
        in_band : bool
            Only crossings inside each case's speed range.

        Returns
        -------
        tuple of Crossing
            Sorted by harmonic, then speed.
        """
        out = []
        v = self.speeds
        for k, (hk, lam) in enumerate(zip(self.harmonic, self.wavelength, strict=True)):
            d = self.freq - self.lines[:, k : k + 1]  # (n_v, n_b)
            i, b = np.nonzero(np.sign(d[:-1]) * np.sign(d[1:]) <= 0)
            for ii, bb in zip(i, b, strict=True):
                d0, d1 = d[ii, bb], d[ii + 1, bb]
                t = 0.0 if d0 == d1 else d0 / (d0 - d1)
                vs = v[ii] + t * (v[ii + 1] - v[ii])
                if in_band and not (
                    HARMONICS[hk - 1].speed_range[0] - 1e-9
                    <= vs
                    <= HARMONICS[hk - 1].speed_range[1] + 1e-9
                ):
                    continue
                out.append(
                    Crossing(
                        int(hk),
                        int(self.branch[bb]),
                        float(vs),
                        float(vs / 3.6 / lam),
                        str(self.direction[bb]),
                    )
                )
        # a crossing exactly on a grid speed is found on both sides of it
        uniq = {(c.harmonic, c.branch, round(c.speed_kmh, 9)): c for c in out}
        return tuple(sorted(uniq.values(), key=lambda c: (c.harmonic, c.speed_kmh, c.branch)))

    def export_mapping(self) -> dict[str, Any]:
        """The data as a mapping for :func:`fbs_core.io.export_result` (arrays with axes)."""
        return {
            "freq": (("speed_kmh", "branch"), self.freq),
            "damping": (("speed_kmh", "branch"), self.damping),
            "direction": (("branch",), np.asarray(self.direction, dtype=str)),
            "slope_hz_per_kmh": (("branch",), self.slope),
            "travelling_index": (("branch",), self.travelling),
            "harmonic_line": (("speed_kmh", "harmonic"), self.lines),
            "wavelength": (("harmonic",), self.wavelength),
            "coords": {
                "speed_kmh": self.speeds,
                "branch": self.branch,
                "harmonic": self.harmonic,
            },
            "metadata": {"direction_method": self.method},
        }


METHODS = ("slope", "shape")


def campbell(
    tire: Any = None,
    speeds: npt.ArrayLike | None = None,
    fmax: float = 450.0,
    n_modes: int | None = None,
    method: str = "slope",
) -> Campbell:
    """Campbell diagram of a modal tire model (forward / backward branches, order lines).

    Parameters
    ----------
    tire : TireModel, optional
        Default the reference tire.
    speeds : array_like, shape (n_v,), optional
        Speeds in km/h within the model's operating points; default 41 speeds
        spanning them (20-120 km/h for the reference tire).
    fmax : float
        Keep the branches that come below ``fmax`` Hz somewhere in the range
        (default 450 Hz: above the 7th case's band, 422 Hz).
    n_modes : int, optional
        Only the first ``n_modes`` complex modes (``n_modes / 2`` branches), as in a
        truncated synthesis; default all.
    method : {"slope", "shape"}
        Forward / backward criterion (module notes). ``"shape"`` needs the
        model's physical parameters and solves the tire's complex modes once per
        operating point (cached per model: slow the first time).

    Returns
    -------
    Campbell

    Raises
    ------
    OperatingPointError
        For speeds outside the operating points.
    FBSError
        For ``fmax <= 0``, an odd / out-of-range ``n_modes`` or an unknown method.
    DataFormatError
        ``method="shape"`` for a model without physical parameters.

    Examples
    --------
    >>> cb = campbell()                                  # doctest: +SKIP
    >>> cb.freq.shape[0] == cb.speeds.size                # doctest: +SKIP
    True
    """
    if tire is None:
        from .. import reference_tire

        tire = reference_tire()
    if not np.isfinite(fmax) or fmax <= 0:
        raise FBSError(f"fmax must be a positive frequency in Hz, got {fmax!r}")
    if method not in METHODS:
        raise FBSError(f"unknown method {method!r}; allowed: {', '.join(METHODS)}")
    n_all = tire.n_modes
    if n_modes is not None and (
        isinstance(n_modes, bool)
        or int(n_modes) != n_modes
        or n_modes % 2
        or not 2 <= n_modes <= n_all
    ):
        raise FBSError(f"n_modes must be an even count 2..{n_all} or None, got {n_modes!r}")
    nb = (n_all if n_modes is None else int(n_modes)) // 2
    v = (
        np.linspace(tire.speeds[0], tire.speeds[-1], 41)
        if speeds is None
        else np.asarray(speeds, float).ravel()
    )
    if v.size < 2 or np.any(np.diff(v) <= 0):
        raise FBSError(f"speeds must be >= 2 increasing values in km/h, got {v.tolist()}")
    poles = np.stack([tire.poles_at(s)[0::2][:nb] for s in v])  # raises OperatingPointError
    F = poles.imag / (2 * np.pi)
    # vibration modes only: the first-order states of a tire with tread relaxation have
    # real poles (stored in pairs ahead of the conjugate pairs) and no eigenfrequency
    oscillatory = np.all(tire.poles[:, 0::2][:, :nb].imag > 0, axis=0) & np.all(F > 0, axis=0)
    keep = np.flatnonzero(oscillatory & (F.min(axis=0) <= fmax))
    F = F[:, keep]
    op = tire.poles[:, 0::2][:, keep].imag / (2 * np.pi)
    labels, a = classify_branches(tire.speeds, op)
    tau = np.full(keep.size, np.nan)
    if method == "shape":
        tire.system(float(tire.speeds[0]))  # DataFormatError without parameters
        tau = _shape_index(tire)[:, keep].mean(axis=0)
        labels = tuple(
            str(x)
            for x in np.where(tau < -0.2, "forward", np.where(tau > 0.2, "backward", "standing"))
        )
    hk = np.array([h.k for h in HARMONICS])
    lam = np.array([h.wavelength for h in HARMONICS])
    lo = np.array([h.speed_range[0] for h in HARMONICS])
    hi = np.array([h.speed_range[1] for h in HARMONICS])
    p = poles[:, keep]
    return Campbell(
        speeds=v,
        branch=keep,
        freq=F,
        damping=-p.real / np.abs(p),
        direction=np.array(labels, dtype=str),
        slope=a,
        travelling=tau,
        method=method,
        harmonic=hk,
        wavelength=lam,
        lines=harmonic_lines(v, lam),
        in_band=(v[:, None] >= lo - 1e-9) & (v[:, None] <= hi + 1e-9),
    )
