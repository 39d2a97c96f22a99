"""Modal truncation study of the tire model (thesis section 5.1).

The coupled bushing response of eq. 4.1 is computed with the tire's modal sum cut
after ``N`` modes (pairs of positive and negative eigenfrequencies, lowest first;
``N = 10, 20, ..., 400`` in the thesis) and compared with the response using all
modes by the floating-band error of eq. 5.1. All ``N`` come from one cumulative
modal sum of the tire (``tire.truncations``), not from separate syntheses, and all
couplings from one batched solve.

Public entry points: :func:`truncation_map` (thesis figs. 5.3, 5.6, 5.7),
:func:`suggest_modes` (table 5.1) and :func:`mode_frequencies` (fig. 5.8).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .. import kernels
from .._typing import ComplexArray, FloatArray, IntArray
from ..errors import DOFError, FBSError, HarmonicError
from ..frf import check_grid
from ..harmonics import Harmonic
from ..vocabulary import DIRECTIONS
from ..vocabulary import readonly as _ro
from . import _coupling_kernels, _models
from .metric import floating_band_error

__all__ = [
    "TruncationMap",
    "SuggestedModes",
    "ModeFrequencies",
    "truncation_map",
    "truncation_map_arrays",
    "suggest_n_modes",
    "suggest_modes",
    "mode_frequencies",
]


@dataclass(frozen=True, eq=False)
class TruncationMap:
    """Truncation error versus retained modes and centre frequency, for one harmonic.

    Attributes
    ----------
    harmonic : int or None
        Harmonic case number (``None`` for user arrays).
    n_modes : ndarray of int, shape (n_N,)
        Retained-mode counts.
    n_modes_total : int or None
        Modes of the reference (all modes).
    centres : ndarray, shape (n_c,)
        Centre frequencies of the floating band in Hz.
    dofs : tuple of str, length n_dof
        Response DOF labels (e.g. ``bushing:x`` ...).
    error : ndarray, shape (n_N, n_c, n_dof)
        Eq. 5.1 error (0.2 = 20 %).
    freq : ndarray, shape (n_f,)
        Frequency lines of the responses.
    response : ndarray, shape (n_N, n_f, n_dof)
        Coupled responses (eq. 4.1) with ``n_modes`` retained modes.
    reference : ndarray, shape (n_f, n_dof)
        Coupled response with all modes.
    width, step : float
        Band width and step in Hz; ``edges`` the band-edge treatment.
    interface : tuple of str, length n_j
        Coupled interface DOFs of the source (e.g. ``hub:x`` ...); ``()`` when the map
        was made without the interface forces (these four are read-only properties,
        kept from the map's solve and not part of its export).
    forces : ndarray, shape (n_N, n_f, n_j), or None
        Interface forces ``g = (Y_jj^A + Y_jj^E)^-1 v_j`` (eqs. 2.37, 4.1) per retained
        count, from the same solve as :attr:`response`.
    forces_reference : ndarray, shape (n_f, n_j), or None
        The same with all modes.
    transfer : ndarray, shape (n_f, n_dof, n_j), or None
        Receiver transfer mobility ``Y_ej^E`` from the interface to the responses:
        ``response[i] == transfer @ forces[i]`` (the terms of eq. 4.1 are
        ``transfer * forces[i][:, None, :]``, :func:`fbs_core.analysis.map_contributions`).
    """

    harmonic: int | None
    n_modes: IntArray
    n_modes_total: int | None
    centres: FloatArray
    dofs: tuple[str, ...]
    error: FloatArray
    freq: FloatArray
    response: ComplexArray
    reference: ComplexArray
    width: float
    step: float
    edges: str
    # the interface forces of the map's solve (properties below; not exported with the map)
    _interface: tuple[str, ...] = ()
    _forces: ComplexArray | None = None
    _forces_reference: ComplexArray | None = None
    _transfer: ComplexArray | None = None

    @property
    def interface(self) -> tuple[str, ...]:
        """Coupled interface DOFs of the source (``()``: made without the forces)."""
        return self._interface

    @property
    def forces(self) -> ComplexArray | None:
        """Interface forces per retained count, shape ``(n_N, n_f, n_j)``, or None."""
        return self._forces

    @property
    def forces_reference(self) -> ComplexArray | None:
        """Interface forces with all modes, shape ``(n_f, n_j)``, or None."""
        return self._forces_reference

    @property
    def transfer(self) -> ComplexArray | None:
        """Receiver transfer mobility ``Y_ej^E``, shape ``(n_f, n_dof, n_j)``, or None."""
        return self._transfer

    @property
    def max_error(self) -> FloatArray:
        """Maximum error over the response DOFs, shape ``(n_N, n_c)`` (thesis fig. 5.6)."""
        m: FloatArray = self.error.max(axis=-1)
        return m

    def dof_error(self, dof: str) -> FloatArray:
        """Error of one response DOF, shape ``(n_N, n_c)`` (e.g. ``"bushing:z"``, fig. 5.7).

        Raises
        ------
        DOFError
            For a label that is not a response DOF.
        """
        if dof not in self.dofs:
            raise DOFError(f"unknown response DOF {dof!r}; available: {', '.join(self.dofs)}")
        return self.error[:, :, self.dofs.index(dof)]

    def response_for(self, n_modes: int | None) -> ComplexArray | None:
        """The coupled response with ``n_modes`` retained modes, if the map holds it.

        Parameters
        ----------
        n_modes : int or None
            Retained modes; ``None`` or a count of at least ``n_modes_total`` is the
            all-modes reference.

        Returns
        -------
        ndarray, shape (n_f, n_dof), or None
            ``None`` when the map has no row for that count (compute it directly).
        """
        if n_modes is None or (self.n_modes_total is not None and n_modes >= self.n_modes_total):
            return self.reference
        hit = np.flatnonzero(self.n_modes == int(n_modes))
        return self.response[hit[0]] if hit.size else None

    def forces_for(self, n_modes: int | None) -> ComplexArray | None:
        """The interface forces with ``n_modes`` retained modes, shape ``(n_f, n_j)``, if
        the map holds them (``None``: no row for that count, or a map made without the
        forces); ``n_modes`` as in :meth:`response_for`."""
        if self.forces is None or self.forces_reference is None:
            return None
        if n_modes is None or (self.n_modes_total is not None and n_modes >= self.n_modes_total):
            return self.forces_reference
        hit = np.flatnonzero(self.n_modes == int(n_modes))
        return self.forces[hit[0]] if hit.size else None

    def suggest(self, threshold: float = 0.2, f_max: float = 160.0, dof: str | None = None) -> int:
        """Smallest retained-mode count from which the error stays below ``threshold``
        (a fraction, 0.2 = 20 %) at every centre up to ``f_max`` Hz.

        See :func:`suggest_n_modes`; ``dof=None`` uses the maximum over DOFs.
        """
        err = self.max_error if dof is None else self.dof_error(dof)
        return suggest_n_modes(
            err, self.centres, self.n_modes, threshold, f_max, self.n_modes_total
        )


def suggest_n_modes(
    error: ArrayLike,
    centres: ArrayLike,
    n_modes: ArrayLike,
    threshold: float = 0.2,
    f_max: float = 160.0,
    n_total: int | None = None,
) -> int:
    """Thesis table 5.1: the smallest ``N`` from which the error stays below the threshold.

    ``N`` qualifies when, for it and for every larger count in ``n_modes``, the error
    at all centres ``<= f_max`` is below ``threshold``. Adding modes can raise the
    error again (thesis 5.1.2), hence "from which ... stays". The reference (all
    modes, ``n_total``) always qualifies. Larger thresholds never give larger ``N``.

    Parameters
    ----------
    error : ndarray, shape (n_N, n_c)
    centres : ndarray, shape (n_c,)
    n_modes : ndarray of int, shape (n_N,), ascending
    threshold : float
        Largest acceptable error as a fraction (0.2 = 20 %).
    f_max : float
        Highest centre frequency judged, Hz.
    n_total : int, optional
        Modes of the reference; returned when no count in ``n_modes`` qualifies
        (default: ``max(n_modes)``).

    Returns
    -------
    int
        ``0`` when no centre lies at or below ``f_max`` (nothing to predict there).

    Raises
    ------
    FBSError
        For a negative threshold or counts that are not ascending.
    """
    err = np.asarray(error, float)
    c = np.asarray(centres, float)
    n = np.asarray(n_modes)
    if not threshold >= 0:
        raise FBSError(f"threshold must be >= 0 (0.2 = 20 %), got {threshold!r}")
    if n.ndim != 1 or np.any(np.diff(n) <= 0):
        raise FBSError(f"n_modes must be strictly ascending, got {n.tolist()}")
    if err.shape != (n.size, c.size):
        raise FBSError(f"error has shape {err.shape}, expected (n_N, n_c) = {(n.size, c.size)}")
    sel = c <= f_max + 1e-9
    if not sel.any():
        return 0
    ok = np.all(err[:, sel] < threshold, axis=1)
    # ok from index i on: suffix-and
    stays = np.flip(np.logical_and.accumulate(np.flip(ok)))
    if stays.any():
        return int(n[np.argmax(stays)])
    return int(n_total if n_total is not None else n[-1])


def truncation_map_arrays(
    freq: ArrayLike,
    YjjA: ComplexArray,
    vj: ComplexArray,
    YjjA_ref: ComplexArray,
    vj_ref: ComplexArray,
    YjjE: ComplexArray,
    YejE: ComplexArray,
    n_modes: ArrayLike,
    *,
    dofs: Sequence[str] | None = None,
    harmonic: int | None = None,
    n_modes_total: int | None = None,
    width: float = 12.0,
    step: float = 1.0,
    edges: str = "clip",
    centres: ArrayLike | None = None,
    interface: Sequence[str] | None = None,
) -> TruncationMap:
    """The error map from arrays (the kernel behind :func:`truncation_map`).

    Parameters
    ----------
    freq : ndarray, shape (n_f,)
    YjjA : ndarray, shape (n_N, n_f, n_j, n_j)
        Tire hub mobility with ``n_modes[i]`` retained modes.
    vj : ndarray, shape (n_N, n_f, n_j)
        Free hub velocity ``Y_ja^A F_a`` with ``n_modes[i]`` retained modes.
    YjjA_ref, vj_ref : ndarray, shapes (n_f, n_j, n_j), (n_f, n_j)
        The same with all modes (the reference).
    YjjE : ndarray, shape (n_f, n_j, n_j)
        Chassis mobility at the interface.
    YejE : ndarray, shape (n_f, n_e, n_j)
        Chassis transfer mobility interface -> responses.
    n_modes : array_like of int, shape (n_N,)
    dofs : sequence of str, optional
        Response labels (default ``bushing:x`` ...).
    interface : sequence of str, optional
        Labels of the ``n_j`` interface DOFs (default ``hub:x`` ... for six of them,
        ``interface:0`` ... otherwise).

    Returns
    -------
    TruncationMap
    """
    f = check_grid(freq)
    n = np.asarray(n_modes)
    YjjA = np.asarray(YjjA)
    if YjjA.ndim != 4 or YjjA.shape[:2] != (n.size, f.size):
        raise FBSError(
            f"YjjA has shape {YjjA.shape}, expected (n_N, n_f, n_j, n_j) with n_N = {n.size} "
            f"and n_f = {f.size}"
        )
    # eq. 4.1 in two steps, keeping the interface forces g (eq. 2.37) for the contributions
    g, resp = _couple(YjjA, vj, YjjE, YejE)  # (n_N, n_f, n_j), (n_N, n_f, n_e)
    g_ref, ref = (x[0] for x in _couple(YjjA_ref[None], vj_ref[None], YjjE, YejE))
    if not (np.all(np.isfinite(resp)) and np.all(np.isfinite(ref))):
        bad = np.argwhere(~np.isfinite(resp))
        line = int(bad[0][1]) if bad.size else int(np.argwhere(~np.isfinite(ref))[0][0])
        raise FBSError(f"coupled response is not finite at {f[line]:g} Hz (singular interface?)")
    c, err = floating_band_error(f, ref, resp, width, step, edges, centres)
    if dofs is None:
        dofs = tuple(f"bushing:{d}" for d in DIRECTIONS)[: ref.shape[-1]]
    if len(dofs) != ref.shape[-1]:
        raise DOFError(f"{len(dofs)} response labels for {ref.shape[-1]} response DOFs")
    n_j = YjjE.shape[-1]
    if interface is None:
        interface = (
            tuple(f"hub:{d}" for d in DIRECTIONS)
            if n_j == 6
            else tuple(f"interface:{k}" for k in range(n_j))
        )
    if len(interface) != n_j:
        raise DOFError(f"{len(interface)} interface labels for {n_j} interface DOFs")
    return TruncationMap(
        harmonic=harmonic,
        n_modes=_ro(n, int),
        n_modes_total=n_modes_total,
        centres=_ro(c),
        dofs=tuple(dofs),
        error=_ro(err),
        freq=_ro(f),
        response=_ro(resp),
        reference=_ro(ref),
        width=float(width),
        step=float(step),
        edges=edges,
        _interface=tuple(interface),
        _forces=_ro(g),
        _forces_reference=_ro(g_ref),
        _transfer=_ro(YejE),
    )


def _couple(
    YjjA: ComplexArray, vj: ComplexArray, YjjE: ComplexArray, YejE: ComplexArray
) -> tuple[ComplexArray, ComplexArray]:
    """Interface forces and responses (eqs. 2.37, 4.1) of every count: the compiled small
    solves; a singular interface is reported by :func:`fbs_core.kernels.solve_interface`."""
    g, resp, singular = _coupling_kernels.couple_many(YjjA, vj, YjjE, YejE)
    if singular:  # raises SingularInterfaceError naming the line
        g = kernels.solve_interface(YjjA + YjjE[None], vj[..., None])[..., 0]
        resp = (YejE[None] @ g[..., None])[..., 0]
    return g, resp


def default_n_modes(n_total: int, step: int = 10) -> IntArray:
    """``step, 2 step, ...`` up to ``n_total`` (thesis: 10, 20, ..., 400)."""
    return np.arange(step, n_total + 1, step)


def truncation_map(
    harmonic: int | Harmonic,
    n_modes: ArrayLike | None = None,
    *,
    freq: ArrayLike | None = None,
    df: float = 0.5,
    width: float = 12.0,
    step: float = 1.0,
    edges: str = "clip",
    centres: ArrayLike | None = None,
    tire: Any = None,
    chassis: Any = None,
    coupling: str | Sequence[str] = "6dof",
    residual: bool = False,
) -> TruncationMap:
    """Truncation error map of one harmonic (thesis figs. 5.3, 5.6, 5.7).

    Parameters
    ----------
    harmonic : int or Harmonic
        Excitation case 1..7.
    n_modes : array_like of int, optional
        Retained-mode counts (ascending); default ``10, 20, ...`` up to all modes.
    freq : array_like, optional
        Frequency lines in Hz; default ``harmonic.frequencies(df)``.
    width, step, edges, centres
        Floating band (see :func:`~fbs_core.studies.metric.floating_band_error`).
    tire, chassis : optional
        Models (default: the reference tire and chassis); ``chassis`` may also be an
        FRF on ``freq`` (inputs ``spindle:*``).
    coupling : {"6dof", "5dof"} or sequence of directions
        Coupled hub directions.
    residual : bool
        Compensate the modes left out of every truncation by their quasi-static part
        (upper residual flexibility); the reference stays the all-modes response.

    Returns
    -------
    TruncationMap

    Examples
    --------
    >>> import fbs_core
    >>> m = fbs_core.truncation_map(1)                    # doctest: +SKIP
    >>> m.max_error.shape == (m.n_modes.size, m.centres.size)  # doctest: +SKIP
    True
    """
    h = _models.resolve_harmonic(harmonic)
    tire = _models.resolve_tire(tire)
    dirs = _models.coupled_directions(coupling)
    f = h.frequencies(df) if freq is None else check_grid(freq)
    n_total = _models.total_modes(tire)
    n = default_n_modes(n_total) if n_modes is None else np.asarray(n_modes, int)
    if n.ndim != 1 or n.size == 0 or np.any(np.diff(n) <= 0) or n[0] < 1 or n[-1] > n_total:
        raise FBSError(
            f"n_modes must be ascending counts in 1..{n_total} (the tire's modes), "
            f"got {np.asarray(n_modes).tolist()}"
        )
    YjjE, YejE, resp = _models.chassis_arrays(chassis, f, dirs)
    has_all = n[-1] == n_total  # the reference is then the last truncation itself
    YjjA, vj = _models.tire_arrays(
        tire, f, h, list(n) + ([] if has_all else [n_total]), dirs, residual
    )
    k = n.size
    return truncation_map_arrays(
        f,
        YjjA[:k],
        vj[:k],
        YjjA[-1],
        vj[-1],
        YjjE,
        YejE,
        n,
        dofs=resp,
        harmonic=h.k,
        n_modes_total=n_total,
        width=width,
        step=step,
        edges=edges,
        centres=centres,
        interface=[f"hub:{d}" for d in dirs],
    )


@dataclass(frozen=True, eq=False)
class ModeFrequencies:
    """Highest eigenfrequency among the first ``N`` modes (thesis fig. 5.8).

    Attributes
    ----------
    n_modes : ndarray of int, shape (n_N,)
    speeds : ndarray, shape (n_s,)
        Operating points in km/h.
    frequency : ndarray, shape (n_s, n_N)
        Highest eigenfrequency in Hz among ``N`` retained modes (``N / 2`` pairs).
    """

    n_modes: IntArray
    speeds: FloatArray
    frequency: FloatArray


def _highest_retained(tire: Any, speed: float, n: ArrayLike) -> FloatArray:
    """Highest eigenfrequency (Hz) among the first ``n`` modes at ``speed``, per count.

    With ``tire.poles_at`` the retained modes are taken in the model's own order
    (the order of truncation); otherwise the ``n / 2``-th positive eigenfrequency.
    """
    n = np.asarray(n, int)
    run: FloatArray
    eig: FloatArray
    if hasattr(tire, "poles_at"):
        p = np.asarray(tire.poles_at(float(speed)))
        if n.max() > p.size:
            raise FBSError(f"{int(n.max())} modes requested, the tire has {p.size}")
        run = np.maximum.accumulate(np.abs(p.imag)) / (2 * np.pi)
        out: FloatArray = run[np.maximum(n, 1) - 1]
        return out
    eig = np.sort(np.asarray(tire.eigenfrequencies(float(speed))))
    pairs = np.maximum(n // 2, 1)
    if pairs.max() > eig.size:
        raise FBSError(f"{int(n.max())} modes requested, the tire has {2 * eig.size}")
    out = eig[pairs - 1]
    return out


def mode_frequencies(
    speeds: ArrayLike = (20.0, 80.0, 120.0), n_modes: ArrayLike | None = None, tire: Any = None
) -> ModeFrequencies:
    """Eigenfrequency versus number of retained modes at some speeds (thesis fig. 5.8).

    ``N`` modes are ``N / 2`` pairs of positive and negative eigenfrequencies, lowest
    first; the value is the highest ``|Im lambda| / 2 pi`` among the first ``N`` modes
    at each speed (the ``N / 2``-th positive eigenfrequency when they are sorted).

    Parameters
    ----------
    speeds : sequence of float
        Operating points in km/h (thesis: 20, 80 and 120).
    n_modes : array_like of int, optional
        Mode counts (default 10, 20, ... up to all modes).
    tire : optional
        Default the reference tire.

    Returns
    -------
    ModeFrequencies
    """
    tire = _models.resolve_tire(tire)
    n_total = _models.total_modes(tire)
    n = default_n_modes(n_total) if n_modes is None else np.asarray(n_modes, int)
    sp = np.atleast_1d(np.asarray(speeds, float))
    fr = np.stack([_highest_retained(tire, v, n) for v in sp])
    return ModeFrequencies(_ro(n, int), _ro(sp), _ro(fr))


@dataclass(frozen=True, eq=False)
class SuggestedModes:
    """Suggested number of modes per harmonic (thesis table 5.1).

    Attributes
    ----------
    harmonics : tuple of int
    n_modes : ndarray of int, shape (n_h,)
        Smallest retained-mode count from which the error stays below ``threshold``
        up to ``f_max`` (0: the harmonic has no centre at or below ``f_max``).
    eigenfrequency : ndarray, shape (n_h,)
        Highest eigenfrequency among those modes at ``speed`` (NaN where n_modes is 0).
    freq_range : ndarray, shape (n_h, 2)
        Excitation band of each harmonic in Hz.
    threshold : float
        Largest acceptable eq. 5.1 error as a fraction (0.2 = 20 %).
    f_max : float
        Upper frequency of the predictions, Hz.
    speed : float
        Speed of the eigenfrequencies, km/h.
    dof : str or None
        Response DOF judged (None: maximum over DOFs).
    maps : tuple of TruncationMap
        The maps the table was read from (reusable: ``suggest_modes(maps=...)``).
    """

    harmonics: tuple[int, ...]
    n_modes: IntArray
    eigenfrequency: FloatArray
    freq_range: FloatArray
    threshold: float
    f_max: float
    speed: float
    dof: str | None
    maps: tuple[TruncationMap, ...]

    def table(self) -> str:
        """Plain-text table in the layout of thesis table 5.1."""
        head = "harmonic            " + "".join(f"{k:>8d}" for k in self.harmonics)
        rows = [
            ("lowest freq. (Hz)", [f"{a:8.1f}" for a in self.freq_range[:, 0]]),
            ("highest freq. (Hz)", [f"{b:8.1f}" for b in self.freq_range[:, 1]]),
            (f"modes to {self.f_max:g} Hz", [f"{n:8d}" for n in self.n_modes]),
            ("eigenfreq. (Hz)", [f"{e:8.0f}" for e in self.eigenfrequency]),
        ]
        return "\n".join([head] + [f"{t:<20s}" + "".join(v) for t, v in rows])


def suggest_modes(
    threshold: float = 0.2,
    f_max: float = 160.0,
    *,
    harmonics: Sequence[int] = (1, 2, 3, 4, 5, 6, 7),
    dof: str | None = None,
    speed: float = 80.0,
    maps: Sequence[TruncationMap] | None = None,
    n_modes: ArrayLike | None = None,
    df: float = 0.5,
    width: float = 12.0,
    step: float = 1.0,
    edges: str = "clip",
    tire: Any = None,
    chassis: Any = None,
    coupling: str | Sequence[str] = "6dof",
    residual: bool = False,
) -> SuggestedModes:
    """Suggested number of tire modes for every harmonic (thesis table 5.1).

    Parameters
    ----------
    threshold : float
        Largest acceptable eq. 5.1 error (0.2 = 20 %, the thesis' choice).
    f_max : float
        Upper frequency of the predictions in Hz (130 and 160 Hz in the thesis).
    harmonics : sequence of int
    dof : str, optional
        Judge one response DOF (e.g. ``"bushing:z"``); default the maximum over DOFs.
    speed : float
        Operating point (km/h) of the reported highest eigenfrequency (thesis: 80).
    maps : sequence of TruncationMap, optional
        Precomputed maps (one per harmonic, e.g. ``result.maps`` of an earlier call),
        so that several thresholds or ``f_max`` cost no new coupling.
    n_modes, df, width, step, edges, tire, chassis, coupling, residual
        Passed to :func:`truncation_map` (``residual``: with residual compensation).

    Returns
    -------
    SuggestedModes
    """
    tire = _models.resolve_tire(tire)
    if maps is None:
        maps = tuple(
            truncation_map(
                k,
                n_modes,
                df=df,
                width=width,
                step=step,
                edges=edges,
                tire=tire,
                chassis=chassis,
                coupling=coupling,
                residual=residual,
            )
            for k in harmonics
        )
    else:
        maps = tuple(maps)
        for m in maps:
            if m.harmonic is None:  # a map of user arrays (truncation_map_arrays)
                raise HarmonicError(
                    "unknown harmonic None; allowed: 1, 2, 3, 4, 5, 6, 7 (thesis table 5.1): "
                    "maps need a harmonic case (from truncation_map)"
                )
        harmonics = tuple(m.harmonic for m in maps if m.harmonic is not None)
    n = np.array([m.suggest(threshold, f_max, dof) for m in maps], int)
    ef = np.full(n.size, np.nan)
    if np.any(n > 0):
        ef[n > 0] = _highest_retained(tire, speed, n[n > 0])
    hs = [_models.resolve_harmonic(k) for k in harmonics]
    fr = np.array([h.freq_range for h in hs])
    return SuggestedModes(
        tuple(int(k) for k in harmonics),
        _ro(n, int),
        _ro(ef),
        _ro(fr),
        float(threshold),
        float(f_max),
        float(speed),
        dof,
        maps,
    )
