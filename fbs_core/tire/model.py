"""The modal tire model in the form a tire supplier delivers it.

A :class:`TireModel` holds, per operating point (vehicle speed), the complex
poles, the right and left mode shapes at the hub's 6 DOFs (normalised to
``a_r = 1``, see :mod:`.modes`) and the modal participation of the patch load
of each harmonic case, ``p_r = chi_r^T f_patch``. From these it synthesises

* the hub mobility ``Y_jj^A(omega) = j omega sum_r psi_r chi_r^T / (j omega - lambda_r)``,
* the free hub velocity ``Y_ja^A F_a = j omega sum_r psi_r p_r / (j omega - lambda_r)``,

keeping the first ``N`` modes (``N / 2`` conjugate pairs of lowest eigenfrequency
at the nearest operating point; thesis section 5.1). Along a harmonic line every
line has its own speed ``v = f lambda`` (thesis section 4.1.2); between the
operating points the poles and the residues (``psi_r chi_r^T`` and ``psi_r p_r``,
which do not depend on how the shapes are scaled) are interpolated in speed,
cubic on the four nearest points, and clusters of close modes (veering pairs of
the gyroscopic tire) through their characteristic polynomial and moments
(:mod:`.interp`). Modes are tracked across operating points before storing
(:func:`.modes.track_modes`), so that mode ``r`` is the same mode at every speed.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..direct import SecondOrderSystem
from ..errors import DataFormatError, FBSError, ModeCountError, OperatingPointError
from ..frf import FRF, check_grid
from ..harmonics import Harmonic
from ..harmonics import harmonic as _harmonic
from ..vocabulary import readonly as _ro
from . import interp, sums
from .interp import Interval, cluster_at, cluster_ends, find_clusters, lagrange_weights
from .params import TireParameters
from .ring import HUB_DOFS, build_tire_system
from .ring import patch_load as _patch_load

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from .interp import Cluster
    from .sums import Flat

__all__ = ["TireModel", "OperatingPointError", "ModeCountError", "INTERPOLATIONS"]

#: Interpolation schemes between operating points.
INTERPOLATIONS = ("cubic", "cluster", "linear")


def _renamed(
    harmonic: int | Harmonic | None, harmonic_case: int | Harmonic | None
) -> int | Harmonic:
    """The keyword ``harmonic_case`` was renamed ``harmonic`` (kept for one release)."""
    if harmonic_case is not None:
        warnings.warn(
            "the keyword harmonic_case is deprecated; use harmonic",
            DeprecationWarning,
            stacklevel=3,
        )
        if harmonic is not None:
            raise FBSError("give harmonic or harmonic_case (deprecated), not both")
        return harmonic_case
    if harmonic is None:
        raise FBSError("harmonic is required: a case 1..7 or a Harmonic")
    return harmonic


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
    residual : ndarray, shape (n_s, 36 + 6 n_h), optional
        Upper residual flexibility of modes *not* in the model (a supplier's
        truncated delivery, :meth:`truncated`): receptance ``-sum R_r / lambda_r`` of
        the hub mobility (6 x 6, row major) and of the hub velocity per wavelength;
        used by the syntheses with ``residual=True``.
    interpolation : {"cubic", "cluster", "linear"}
        Between operating points (:mod:`.interp`): ``"cubic"`` (default) cubic
        Lagrange in speed on the four nearest operating points (linear in the
        first and last interval), with clusters of close modes interpolated
        through their characteristic polynomial and moments; ``"cluster"`` the
        same with linear weights; ``"linear"`` plain linear weights on every
        pole and residue (thesis section 4.1.2, for comparison).
    """

    speeds: np.ndarray
    poles: np.ndarray
    psi: np.ndarray
    chi: np.ndarray
    wavelengths: np.ndarray
    participation: np.ndarray
    params: TireParameters | None = None
    meta: dict[str, Any] = field(default_factory=dict)
    hub_dofs: tuple[str, ...] = HUB_DOFS
    interpolation: str = "cubic"
    residual: np.ndarray | None = None
    if TYPE_CHECKING:  # set in __post_init__; not dataclass fields at run time
        _Z: np.ndarray = field(init=False)
        _clusters: tuple[tuple[Cluster, ...], ...] = field(init=False)
        _nodes: tuple[slice, ...] = field(init=False)
        _order: np.ndarray = field(init=False)
        _Z_parts: tuple[np.ndarray, np.ndarray] = field(init=False)
        _rank: np.ndarray = field(init=False)
        _flat_cache: list[Flat] = field(init=False)

    def __post_init__(self) -> None:
        if self.interpolation not in INTERPOLATIONS:
            raise FBSError(
                f"unknown interpolation {self.interpolation!r}; allowed: "
                f"{', '.join(map(repr, INTERPOLATIONS))}"
            )
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
        if self.residual is not None:
            res = np.asarray(self.residual, complex)
            if res.shape != (n_s, 36 + 6 * lam.size):
                raise DataFormatError(
                    f"residual has shape {res.shape}, expected {(n_s, 36 + 6 * lam.size)} "
                    "(hub mobility 6 x 6 and the hub velocity of every wavelength)"
                )
            object.__setattr__(self, "residual", _ro(res))
        # residues, invariant to the scaling of the shapes: (n_s, n_m, 6 * 6 + 6 * n_h)
        R = np.einsum("smi,smj->smij", self.psi, self.chi).reshape(n_s, n_m, 36)
        Q = np.einsum("smi,shm->smhi", self.psi, part).reshape(n_s, n_m, 6 * lam.size)
        Z = np.concatenate([R, Q], axis=2)
        Z.setflags(write=False)
        object.__setattr__(self, "_Z", Z)
        parts = (np.ascontiguousarray(Z.real), np.ascontiguousarray(Z.imag))
        for p in parts:
            p.setflags(write=False)
        object.__setattr__(self, "_Z_parts", parts)  # for the kernel (sums.truncated_sums)
        nodes: list[slice] = []
        for k in range(n_s - 1):
            nd = slice(k, k + 2)
            if self.interpolation == "cubic" and 1 <= k <= n_s - 3:
                nd = slice(k - 1, k + 3)  # centred stencil; end intervals stay linear
            nodes.append(nd)
        # clusters of every interval, found when the interval is first used (_clusters_of)
        clusters: list[tuple[Cluster, ...] | None] = [None] * (n_s - 1)
        object.__setattr__(self, "_clusters", clusters)
        object.__setattr__(self, "_nodes", tuple(nodes))
        # truncation order at every operating point: pairs by eigenfrequency there
        pairs = np.argsort(poles[:, 0::2].imag, axis=1, kind="stable")
        order = np.stack([2 * pairs, 2 * pairs + 1], axis=-1).reshape(n_s, -1)
        order.setflags(write=False)
        object.__setattr__(self, "_order", order)
        rank = np.empty_like(order)
        np.put_along_axis(rank, order, np.arange(n_m)[None].repeat(n_s, 0), axis=1)
        rank.setflags(write=False)
        object.__setattr__(self, "_rank", rank)  # rank of every mode at every point
        object.__setattr__(self, "_flat_cache", [])  # the kernel's cluster arrays (_flat)

    def _clusters_of(self, k: int) -> tuple[Cluster, ...]:
        """Clusters of interval ``k`` (:mod:`.interp`), found on first use and kept.

        Two threads may find them at once; both get the same tuple (deterministic), so
        the race costs time, never correctness.
        """
        hit = self._clusters[k]
        if hit is not None:
            return hit
        nd = self._nodes[k]
        groups: list[np.ndarray] = []
        if self.interpolation != "linear":
            Z, poles = self._Z, self.poles
            moving = interp.residue_change(Z[k, 0::2], Z[k + 1, 0::2]) > interp.TAU
            groups = find_clusters(poles[k, 0::2], poles[k + 1, 0::2], moving=moving)
        e = (k - nd.start, k + 1 - nd.start)
        groups = [2 * g + par for g in groups for par in (0, 1)]
        out = tuple(cluster_ends(groups, self.poles[nd], None, e))  # poles only: no moments
        self._clusters[k] = out
        return out

    def interval_of(self, speed_kmh: ArrayLike) -> np.ndarray:
        """Interval of the operating points holding every speed, shape (n_v,): ``k`` for
        ``speeds[k] <= v < speeds[k + 1]`` (the last interval includes its end).

        Raises
        ------
        OperatingPointError
            For a speed outside the operating points.
        """
        return self._weights(speed_kmh)[0]

    def interval(self, k: int, columns: ArrayLike | None = None) -> Interval:
        """What interpolates the model in interval ``k`` (:class:`.interp.Interval`): the
        stencil's speeds, poles and residue ``columns`` (default: the hub receptance,
        0..35), and its clusters of close modes with their moments of those columns,
        computed anew (the model keeps only the clusters' poles).

        Raises
        ------
        FBSError
            For an interval or columns out of range.
        """
        n_res = self._Z.shape[2]
        cols = np.arange(36) if columns is None else np.asarray(columns)
        if not 0 <= k < self.speeds.size - 1 or not (
            cols.ndim == 1
            and np.issubdtype(cols.dtype, np.integer)
            and np.all((cols >= 0) & (cols < n_res))
        ):
            raise FBSError(
                f"interval {k!r} must be 0..{self.speeds.size - 2} and columns integers "
                f"0..{n_res - 1} (hub receptance 0..35, then 6 per wavelength)"
            )
        nd = self._nodes[k]
        Zc = np.ascontiguousarray(self._Z[nd][:, :, cols])
        groups = [m for cl in self._clusters_of(k) for m in cl.members]
        e = (k - nd.start, k + 1 - nd.start)
        clusters = tuple(cluster_ends(groups, self.poles[nd], Zc, e))
        return Interval(_ro(self.speeds[nd]), _ro(self.poles[nd]), _ro(cols), _ro(Zc), clusters)

    # -- basic information -----------------------------------------------------------
    @property
    def n_modes(self) -> int:
        """Number of complex modes (both members of every pair)."""
        return int(self.poles.shape[1])

    def _weights(self, speed_kmh: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
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

    def _poles_at(self, k: int, t: np.ndarray) -> np.ndarray:
        """Poles ``(n_l, n_m)`` in interval ``k`` at fractions ``t``, stored order; within a
        cluster the roots go to the members in the order of their interpolated poles."""
        nd = self._nodes[k]
        v = self.speeds[k] + np.asarray(t, float) * (self.speeds[k + 1] - self.speeds[k])
        w = lagrange_weights(self.speeds[nd], v)
        lam: np.ndarray = w @ self.poles[nd]
        rows = np.arange(w.shape[0])[:, None, None]
        for cl in self._clusters_of(k):
            p, _ = cluster_at(cl, w, np.arange(0))
            perm = np.argsort(np.abs(lam[:, cl.members].imag), axis=-1)
            lam[rows, np.take_along_axis(cl.members[None], perm, axis=-1)] = p
        return lam

    def poles_at(self, speed_kmh: float) -> np.ndarray:
        """Poles at ``speed_kmh``, shape (n_m,), in the stored (tracked) order.

        Interpolated in speed between the operating points with the model's weights
        (``interpolation="cubic"``, the default: cubic Lagrange on the four nearest
        operating points, linear in the first and last interval; ``"cluster"`` and
        ``"linear"``: linear), exactly as the synthesis; the poles of a cluster of
        close modes (:mod:`.interp`) are the roots of its interpolated characteristic
        polynomial.
        """
        k, t = self._weights(speed_kmh)
        p: np.ndarray = self._poles_at(int(k[0]), t[:1])[0]
        return p

    def eigenfrequencies(self, speed_kmh: float) -> np.ndarray:
        """Positive eigenfrequencies ``Im(lambda) / 2 pi`` in Hz at ``speed_kmh``, sorted.

        Raises
        ------
        OperatingPointError
            Outside the operating points.
        """
        p = self.poles_at(speed_kmh)
        return np.sort(p[p.imag > 0].imag) / (2 * np.pi)

    def _check_n(self, n_modes: int | None) -> int:
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
    def _flat(self) -> Flat:
        """The clusters of all intervals in the compiled kernel's arrays (:mod:`.sums`),
        found on first use and kept; deterministic, so a race costs time only."""
        hit = self._flat_cache
        if hit:
            return hit[0]
        flat = sums.flatten(
            self._nodes,
            self.n_modes,
            [self._clusters_of(k) for k in range(self.speeds.size - 1)],
        )
        hit.append(flat)
        return flat

    def _line_weights(self, k: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Weights ``(n_l, 4)`` of every line's interval nodes (zero past the stencil):
        :func:`.interp.lagrange_weights`, the same operations, all lines at once."""
        flat = self._flat()
        v = self.speeds[k] + t * (self.speeds[k + 1] - self.speeds[k])
        w = np.zeros((k.size, 4))
        for m in np.unique(flat.n_nodes[k]):
            sel = flat.n_nodes[k] == m
            x = self.speeds[flat.node0[k[sel], None] + np.arange(m)]  # (n_sel, m)
            ws = np.ones((x.shape[0], m))
            for i in range(m):
                for j in range(m):
                    if i != j:
                        ws[:, i] *= (v[sel] - x[:, j]) / (x[:, i] - x[:, j])
            w[sel, :m] = ws
        return w

    def _sums(
        self,
        freq: ArrayLike,
        speeds: ArrayLike,
        n_list: Sequence[int],
        h_index: int | None,
        residual: bool = False,
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Cumulative modal sums: mobility (n_N, n_f, 6, 6) and patch velocity (n_N, n_f, 6).

        The modes are interpolated to every line's speed. The ``N`` retained modes
        are the ``N / 2`` pairs of lowest eigenfrequency at the nearest operating
        point (thesis section 5.1: "the first 50 positive eigenfrequencies"; exact
        at the operating points, where the modes are delivered). With ``residual``
        every mode left out of a truncation still enters with its quasi-static
        part ``R_r / (-lambda_r)`` (upper residual flexibility, docs/tire-model.md).
        The blocks of modes between the counts are summed by the compiled kernel of
        :mod:`.sums`, every line on its own (its numbers do not depend on the others).
        """
        f = np.asarray(freq, float)
        k, t = self._weights(speeds)
        s = 2j * np.pi * f
        patch = None if h_index is None else 36 + 6 * h_index  # its columns of _Z
        n_list = list(n_list)
        edges = np.r_[0, n_list]
        want = bool(residual)
        residual = want and n_list != [self.n_modes]
        if residual and edges[-1] != self.n_modes:
            # one more block up to all modes, so that the static part of every mode
            # (zero poles: none) comes from the same sums
            edges = np.r_[edges, self.n_modes]
        block = np.searchsorted(edges, self._rank, side="right") - 1
        block[self._rank >= edges[-1]] = -1  # beyond the largest count: left out
        w = self._line_weights(k, t)
        extra = None
        if want and self.residual is not None:  # + the static part of modes not delivered
            cols = np.r_[np.arange(36), [] if patch is None else patch + np.arange(6)]
            extra = np.zeros((f.size, cols.size), complex)
            for kk in np.unique(k):
                idx = np.flatnonzero(k == kk)
                nd = self._nodes[kk]
                extra[idx] = w[idx, : nd.stop - nd.start] @ self.residual[nd][:, cols.astype(int)]
        return sums.truncated_sums(
            self._flat(),
            self.poles,
            *self._Z_parts,
            s,
            k,
            w,
            k + (t >= 0.5),  # the nearer operating point ranks the modes
            self._order,
            block,
            self._rank,
            int(edges[-1]),
            patch,
            len(edges) - 1,
            len(n_list),
            residual,
            extra,
        )

    def synthesis(
        self,
        freq: ArrayLike,
        speeds: ArrayLike,
        harmonic_index: int | None = None,
        n_modes: int | None = None,
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Hub mobility and free hub velocity line by line, each line at its own speed.

        Parameters
        ----------
        freq, speeds : array_like, shape (n,)
            Frequency (Hz) and vehicle speed (km/h) of every line; any order.
        harmonic_index : int, optional
            Index into :attr:`wavelengths` of the patch load; None: mobility only.
        n_modes : int, optional
            Even count of retained modes (lowest pairs of the nearest operating point).

        Returns
        -------
        Y : ndarray, shape (n, 6, 6)
        v : ndarray, shape (n, 6) or None
        """
        f = np.asarray(freq, float).ravel()
        sp = np.asarray(speeds, float).ravel()
        if f.shape != sp.shape:
            raise FBSError(f"freq and speeds must have one length, got {f.size} and {sp.size}")
        Y, v = self._sums(f, sp, [self._check_n(n_modes)], harmonic_index)
        return Y[0], (None if v is None else v[0])

    def subset(self, modes: Sequence[int] | np.ndarray, *, residual: bool = True) -> TireModel:
        """The stored mode pairs ``modes`` plus the residual of all the others.

        What a supplier with the full modal set delivers to save size, choosing the
        modes by their stored (tracked) index: the lowest ones (``range(N // 2)``) or the
        ones that matter for a case (:func:`fbs_core.analysis.select_modes`). Per
        operating point the upper residual flexibility ``-sum_(r left out) R_r /
        lambda_r`` of the modes left out (hub mobility and patch residues, added to
        any residual this model already carries) is stored; synthesis with
        ``residual=True`` uses it.

        Note the rule: a subset keeps the same tracked modes at every speed, whereas
        ``n_modes=N`` of the syntheses keeps the ``N / 2`` pairs of lowest
        eigenfrequency at the nearest operating point, which are not the same
        ``N / 2`` stored pairs at every speed.

        Parameters
        ----------
        modes : sequence of int
            Stored pair indices (0 .. n_modes / 2 - 1; pair ``m`` is modes ``2 m``,
            ``2 m + 1``), each at most once; kept in the stored order.
        residual : bool
            Keyword only: store the residual of the pairs left out (default).

        Raises
        ------
        ModeCountError
            For an empty selection, repeated or out-of-range pair indices.
        """
        idx = np.asarray(modes)
        n_p = self.n_modes // 2
        if (
            idx.ndim != 1
            or idx.size == 0
            or not np.issubdtype(idx.dtype, np.integer)
            or np.any((idx < 0) | (idx >= n_p))
            or np.unique(idx).size != idx.size
        ):
            raise ModeCountError(
                f"modes must be distinct stored pair indices 0..{n_p - 1} (at least one), got "
                f"{np.asarray(modes).tolist()!r}"
            )
        keep = np.zeros(n_p, bool)
        keep[idx] = True
        cols = np.stack([keep, keep], axis=-1).ravel()  # both members of every pair
        res = self.residual
        if residual and not cols.all():
            p = self.poles[:, ~cols]
            inv = np.divide(-1.0, p, out=np.zeros_like(p), where=p != 0)  # zero poles: none
            rest = (self._Z[:, ~cols] * inv[:, :, None]).sum(axis=1)
            res = rest if res is None else rest + res
        return TireModel(
            self.speeds,
            self.poles[:, cols],
            self.psi[:, cols],
            self.chi[:, cols],
            self.wavelengths,
            self.participation[:, :, cols],
            params=self.params,
            meta={
                **self.meta,
                "subset_of": int(self.n_modes),
                "pairs": np.flatnonzero(keep).tolist(),
            },
            hub_dofs=self.hub_dofs,
            interpolation=self.interpolation,
            residual=res,
        )

    def truncated(self, n_modes: int) -> TireModel:
        """Deprecated: :meth:`subset` of the first ``n_modes // 2`` *stored* pairs.

        The name hid the rule: it keeps the first stored modes (speed-averaged order),
        while ``n_modes=N`` of the syntheses keeps the lowest pairs at the nearest
        operating point (at 60 km/h with N = 40 one of the 20 pairs differs, and the
        hub mobility by 14 % of its peak). Use ``subset(range(n_modes // 2))``.

        Parameters
        ----------
        n_modes : int
            Even count of stored modes kept.
        """
        warnings.warn(
            "TireModel.truncated(N) is deprecated: it keeps the first N stored modes, not the "
            "lowest of each operating point; use TireModel.subset(range(N // 2))",
            DeprecationWarning,
            stacklevel=2,
        )
        n = self._check_n(n_modes)
        return self.subset(np.arange(n // 2))

    def hub_mobility(
        self,
        freq: ArrayLike,
        speed_kmh: float,
        n_modes: int | None = None,
        *,
        residual: bool = False,
    ) -> FRF:
        """Hub mobility ``Y_jj^A`` (6 x 6) at a fixed speed, from the first ``n_modes`` modes.

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz.
        speed_kmh : float
            Vehicle speed within the operating points.
        n_modes : int, optional
            Even number of complex modes, 10..n_modes; ``None`` keeps all.
        residual : bool
            Keyword only: add the quasi-static part ``R_r / (-lambda_r)`` of every mode
            left out (upper residual flexibility; docs/tire-model.md).

        Returns
        -------
        FRF
            Mobility, outputs and inputs ``hub:x`` ... ``hub:rz`` (vehicle axes).
        """
        f = check_grid(freq)
        n = self._check_n(n_modes)
        Y, _ = self._sums(f, np.full(f.size, float(speed_kmh)), [n], None, residual)
        return FRF(f, Y[0], self.hub_dofs, self.hub_dofs, "mobility")

    def patch_response(
        self,
        freq: ArrayLike,
        harmonic: int | Harmonic | None = None,
        n_modes: int | None = None,
        speed_kmh: float | None = None,
        *,
        residual: bool = False,
        harmonic_case: int | Harmonic | None = None,
    ) -> FRF:
        """Free hub velocity ``Y_ja^A F_a`` for the patch load of a harmonic case.

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz inside the harmonic's band.
        harmonic : int or Harmonic
            Case 1..7 (``harmonic_case=`` is the deprecated name).
        n_modes : int, optional
            Even number of complex modes kept; ``None`` keeps all.
        speed_kmh : float, optional
            Evaluate at this fixed speed instead of along the line ``v = f lambda``
            (then any positive frequencies are allowed).
        residual : bool
            Keyword only: compensate the modes left out by their quasi-static part.

        Returns
        -------
        FRF
            Outputs ``hub:*``, one input ``patch`` (per metre of road amplitude).
        """
        h = _harmonic(_renamed(harmonic, harmonic_case))
        f = check_grid(freq)
        n = self._check_n(n_modes)
        hi = self._harmonic_index(h)
        v = h.speed_at(f) if speed_kmh is None else np.full(f.size, float(speed_kmh))
        _, vj = self._sums(f, np.atleast_1d(v), [n], hi, residual)
        assert vj is not None  # a harmonic index was given
        return FRF(f, vj[0][:, :, None], self.hub_dofs, ["patch"], "mobility")

    def truncations(
        self,
        freq: ArrayLike,
        harmonic: int | Harmonic | None = None,
        n_modes_list: Sequence[int] | np.ndarray | None = None,
        *,
        residual: bool = False,
        harmonic_case: int | Harmonic | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Hub mobility and free hub velocity along a harmonic line for many truncations.

        Cumulative modal sums give every truncation for the price of one full
        synthesis.

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz inside the harmonic's band.
        harmonic : int or Harmonic
            Case 1..7 (``harmonic_case=`` is the deprecated name).
        n_modes_list : sequence of int
            Increasing even mode counts, each 10..n_modes.
        residual : bool
            Keyword only: compensate the modes left out of every truncation by their
            quasi-static part ``R_r / (-lambda_r)`` (upper residual flexibility).

        Returns
        -------
        Yjj : ndarray, shape (n_N, n_freq, 6, 6)
        vj : ndarray, shape (n_N, n_freq, 6)
        """
        h = _harmonic(_renamed(harmonic, harmonic_case))
        f = check_grid(freq)
        if n_modes_list is None:
            raise ModeCountError("n_modes_list is required (increasing even mode counts)")
        ns = [
            self._check_n(int(n)) if isinstance(n, int | np.integer) else self._check_n(n)
            for n in n_modes_list
        ]
        if not ns or np.any(np.diff(ns) <= 0):
            raise ModeCountError(f"n_modes_list must be non-empty and increasing, got {ns}")
        Y, v = self._sums(f, h.speed_at(f), ns, self._harmonic_index(h), residual)
        assert v is not None  # a harmonic index was given
        return Y, v

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
