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
from typing import TYPE_CHECKING, Any, Literal, TypeAlias, overload

import numpy as np

from ..direct import SecondOrderSystem
from ..errors import DataFormatError, FBSError, ModeCountError, OperatingPointError
from ..frf import FRF, check_grid
from ..harmonics import Harmonic
from ..harmonics import harmonic as _harmonic
from . import interp
from .interp import cluster_at, cluster_ends, cluster_sum, find_clusters, lagrange_weights
from .params import TireParameters
from .ring import HUB_DOFS, build_tire_system
from .ring import patch_load as _patch_load

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from .interp import Cluster

#: A truncation plan of :meth:`TireModel._plan`: the truncation order and, per cluster
#: batch, its members, the clusters whole inside a block and those split by a block edge
#: (with their members ranked).
#: Where the modes of an interval go for some blocks (see TireModel._layout).
_Layout: TypeAlias = tuple[
    np.ndarray, np.ndarray, list[tuple[int, np.ndarray]], list[tuple[int, Any]]
]
_Plan: TypeAlias = (
    "tuple[np.ndarray, list[tuple[np.ndarray, Cluster | None, Cluster | None, np.ndarray | None]]]"
)

__all__ = ["TireModel", "OperatingPointError", "ModeCountError", "INTERPOLATIONS"]

#: Interpolation schemes between operating points.
INTERPOLATIONS = ("cubic", "cluster", "linear")


#: Lines per chunk of the modal sums (bounds the memory of the (lines, modes) terms).
_CHUNK = 512


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


def _ro(a: ArrayLike) -> np.ndarray:
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
        _plans: dict[tuple[int, int, tuple[int, ...]], _Plan] = field(init=False)
        _columns: dict[tuple[int, bytes], np.ndarray] = field(init=False)
        _layouts: dict[tuple[int, int, tuple[int, ...]], _Layout] = field(init=False)

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
        object.__setattr__(self, "_plans", {})  # cache of truncation plans (see _plan)
        object.__setattr__(self, "_columns", {})  # residue columns per interval (_node_columns)
        object.__setattr__(self, "_layouts", {})  # modes per block of a plan (_layout)

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
        out = tuple(cluster_ends(groups, self.poles[nd], self._Z[nd], e))
        self._clusters[k] = out
        return out

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

        Linear in speed between the operating points, except for clusters of
        close modes (:mod:`.interp`), whose poles are the roots of the
        interpolated characteristic polynomial.
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
    def _total(self, k: int, t: np.ndarray, s: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Receptance sum over all modes at lines of interval ``k``: linear part by
        matrix products, every cluster by its rational form (no roots needed)."""
        nd = self._nodes[k]
        v = self.speeds[k] + np.asarray(t, float) * (self.speeds[k + 1] - self.speeds[k])
        w = lagrange_weights(self.speeds[nd], v)
        T = 1.0 / (s[:, None] - w @ self.poles[nd])  # (n_l, n_m)
        for cl in self._clusters_of(k):
            T[:, cl.members.ravel()] = 0.0
        Zn = self._Z[nd]  # (n_nodes, n_m, n_res), a view
        tot: np.ndarray = sum(w[:, i, None] * (T @ Zn[i]) for i in range(Zn.shape[0]))[:, cols]
        for cl in self._clusters_of(k):
            tot = tot + cluster_sum(cl, w, s, cols)
        return tot

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
        """
        f = np.asarray(freq, float)
        k, t = self._weights(speeds)
        s = 2j * np.pi * f
        cols = np.arange(36)
        if h_index is not None:
            cols = np.r_[cols, 36 + 6 * h_index + np.arange(6)]
        n_list = list(n_list)
        only_all = n_list == [self.n_modes]
        edges = np.r_[0, n_list]
        out = np.zeros((len(n_list), f.size, cols.size), complex)
        want = bool(residual)
        residual = want and not only_all
        if residual:
            sta = np.zeros_like(out)  # static parts of the blocks
            tot = np.zeros((f.size, cols.size), complex)  # static part of all modes
        for kk in np.unique(k):
            lines = np.flatnonzero(k == kk)
            if only_all:
                for idx in np.array_split(lines, max(1, int(np.ceil(lines.size / _CHUNK)))):
                    out[0, idx] = self._total(int(kk), t[idx], s[idx], cols)
                continue
            for near in (0, 1):  # lines nearer the lower / upper operating point
                sel = lines[(t[lines] >= 0.5) == bool(near)]
                for idx in np.array_split(sel, max(1, int(np.ceil(sel.size / _CHUNK)))):
                    if not idx.size:
                        continue
                    if residual:
                        # one more block up to all modes, so that the static part of
                        # every mode (zero poles: none) comes from the same sums
                        full = edges if edges[-1] == self.n_modes else np.r_[edges, self.n_modes]
                        dyn, st = self._blocks(
                            int(kk), near, t[idx], s[idx], cols, full, static=True
                        )
                        nb = len(edges) - 1
                        out[:, idx], sta[:, idx] = dyn[:nb], st[:nb]
                        tot[idx] = st.sum(axis=0)
                    else:
                        out[:, idx] = self._blocks(int(kk), near, t[idx], s[idx], cols, edges)
        out = np.cumsum(out, axis=0)
        if residual:  # + the quasi-static part of the modes left out
            out += tot[None] - np.cumsum(sta, axis=0)
        if want and self.residual is not None:  # + that of the modes not delivered
            for kk in np.unique(k):
                idx = np.flatnonzero(k == kk)
                nd = self._nodes[kk]
                v = self.speeds[kk] + t[idx] * (self.speeds[kk + 1] - self.speeds[kk])
                w = lagrange_weights(self.speeds[nd], v)
                out[:, idx] += (w @ self.residual[nd][:, cols])[None]
        out *= s[None, :, None]  # mobility = j omega H
        Y = out[:, :, :36].reshape(len(n_list), f.size, 6, 6)
        v = out[:, :, 36:] if h_index is not None else None
        return Y, v

    def _plan(self, k: int, near: int, edges: np.ndarray) -> _Plan:
        """Truncation order at operating point ``k + near`` and, per cluster batch, the
        clusters inside one block of ``edges`` and those split by a block edge (with
        their members ranked at that point). Cached: it depends on the counts only."""
        key = (k, near, tuple(int(e) for e in edges))
        hit = self._plans.get(key)
        if hit is not None:
            return hit
        order = self._order[k + near]
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        block = np.searchsorted(edges, rank, side="right") - 1  # block of every mode
        plan = []
        for cl in self._clusters_of(k):
            b = block[cl.members]
            whole = np.all(b == b[:, :1], axis=1)  # cluster inside one block
            w_sub = interp.subset(cl, whole) if whole.any() else None
            s_sub = interp.subset(cl, ~whole) if (~whole).any() else None
            # the lowest root goes to the member ranked lowest at the operating point
            s_mem = None
            if s_sub is not None:
                s_mem = np.take_along_axis(s_sub.members, np.argsort(rank[s_sub.members], 1), 1)
            plan.append((cl.members.ravel(), w_sub, s_sub, s_mem))
        if len(self._plans) > 4 * len(self._clusters):
            self._plans.clear()
        self._plans[key] = (order, plan)
        return order, plan

    @overload
    def _blocks(
        self,
        k: int,
        near: int,
        t: np.ndarray,
        s: np.ndarray,
        cols: np.ndarray,
        edges: np.ndarray,
        static: Literal[False] = False,
    ) -> np.ndarray: ...
    @overload
    def _blocks(
        self,
        k: int,
        near: int,
        t: np.ndarray,
        s: np.ndarray,
        cols: np.ndarray,
        edges: np.ndarray,
        static: Literal[True],
    ) -> tuple[np.ndarray, np.ndarray]: ...
    def _blocks(
        self,
        k: int,
        near: int,
        t: np.ndarray,
        s: np.ndarray,
        cols: np.ndarray,
        edges: np.ndarray,
        static: bool = False,
    ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        """Receptance sums over the blocks of retained modes ``edges`` (n_N, n_l, n_cols),
        modes ranked at operating point ``k + near``; with ``static`` also the sums of
        their quasi-static parts ``R_r / (-lambda_r)`` (same shape).

        The modes are interpolated to every line's speed (weights ``w_i`` of the
        interval's nodes), yet the interpolated residues ``sum_i w_i Z_i`` are never
        formed per line: the modal sum of eq. 2.5 over a block ``b`` is
        ``sum_i w_i (T_b @ Z_i,b)`` with ``T = 1 / (s - lambda)``, a few matrix products.
        Clusters of veering modes enter by their rational form (whole in a block) or by
        their interpolated roots (split by a block edge).
        """
        order, plan = self._plan(k, near, edges)
        nd = self._nodes[k]
        v = self.speeds[k] + np.asarray(t, float) * (self.speeds[k + 1] - self.speeds[k])
        w = lagrange_weights(self.speeds[nd], v)
        n_l, n_b = t.size, len(edges) - 1
        Zc = self._node_columns(k, cols)  # (n_nodes, n_m, n_cols)
        block, used, per_block, wholes = self._layout(k, near, edges, order, plan)
        lam = w @ self.poles[nd][:, used]
        X = 1.0 / (s[:, None] - lam)  # (n_l, n_used)
        if static:  # -R / lambda below the dynamic terms; a zero pole has no static part
            X = np.vstack([X, np.divide(-1.0, lam, out=np.zeros_like(lam), where=lam != 0)])
        wx = np.vstack([w, w]) if static else w
        out = np.zeros((n_b, X.shape[0], cols.size), complex)
        for b, j in per_block:  # j: columns of X in block b
            Xb, modes = X[:, j], used[j]
            for i in range(Zc.shape[0]):
                out[b] += wx[:, i, None] * (Xb @ Zc[i, modes])
        zero = np.zeros_like(s)
        for b, sub in wholes:  # a whole cluster's sum goes to the block of its first member
            out[b, :n_l] += cluster_sum(sub, w, s, cols)
            if static:
                out[b, n_l:] += cluster_sum(sub, w, zero, cols)
        for _members, _whole, split, split_members in plan:
            if split is not None:  # split by a block edge: every member on its own
                # roots by frequency, lowest first; lines at one speed share them
                wu, inv = np.unique(w, axis=0, return_inverse=True)
                p, r = cluster_at(split, wu, cols)
                p, r = p[inv.ravel()], r[inv.ravel()]
                bs = block[split_members]  # (n_c, k)
                keep = bs >= 0
                dyn = r / (s[:, None, None, None] - p[..., None])  # (n_l, n_c, k, n_cols)
                np.add.at(out[:, :n_l], bs[keep], np.moveaxis(dyn[:, keep], 1, 0))
                if static:
                    sta = np.moveaxis((-r / p[..., None])[:, keep], 1, 0)
                    np.add.at(out[:, n_l:], bs[keep], sta)
        if not static:
            return out
        return out[:, :n_l], out[:, n_l:]

    def _layout(
        self, k: int, near: int, edges: np.ndarray, order: np.ndarray, plan: list[Any]
    ) -> _Layout:
        """Where every mode of interval ``k`` goes for the blocks ``edges`` (cached with the
        plan: it depends on the counts only): the block of every mode (-1: left out), the
        modes summed term by term (outside every cluster), their columns per block, and
        the whole clusters of each block."""
        key = (k, near, tuple(int(e) for e in edges))
        hit = self._layouts.get(key)
        if hit is not None:
            return hit
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        block = np.searchsorted(edges, rank, side="right") - 1  # block of every mode
        block[rank >= edges[-1]] = -1  # beyond the largest count: left out
        lone = np.ones(order.size, bool)  # modes outside every cluster
        for members, _whole, _split, _members in plan:
            lone[members] = False
        used = np.flatnonzero((block >= 0) & lone)  # the terms summed one by one
        per_block = [(b, np.flatnonzero(block[used] == b)) for b in range(len(edges) - 1)]
        wholes = []
        for _members, whole, _split, _sm in plan:
            if whole is not None:
                bw = block[whole.members[:, 0]]
                wholes += [(int(b), interp.subset(whole, bw == b)) for b in np.unique(bw[bw >= 0])]
        out = (block, used, [(b, j) for b, j in per_block if j.size], wholes)
        if len(self._layouts) > 4 * len(self._clusters):
            self._layouts.clear()
        self._layouts[key] = out
        return out

    def _node_columns(self, k: int, cols: np.ndarray) -> np.ndarray:
        """The residues of interval ``k``'s nodes, columns ``cols`` (cached, read-only)."""
        key = (k, cols.tobytes())
        hit = self._columns.get(key)
        if hit is None:
            if len(self._columns) > 64:
                self._columns.clear()
            hit = np.ascontiguousarray(self._Z[self._nodes[k]][:, :, cols])
            hit.setflags(write=False)
            self._columns[key] = hit
        return hit

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

    def truncated(self, n_modes: int) -> TireModel:
        """The first ``n_modes`` stored modes plus the residual of all the others.

        What a supplier with the full modal set delivers to save size: per operating
        point the upper residual flexibility ``-sum_(r > N) R_r / lambda_r`` of the
        modes left out (hub mobility and patch residues, added to any residual this
        model already carries). Synthesis with ``residual=True`` uses it.

        Parameters
        ----------
        n_modes : int
            Even count of stored modes kept (in the stored, speed-averaged order).
        """
        n = self._check_n(n_modes)
        p = self.poles[:, n:]
        inv = np.divide(-1.0, p, out=np.zeros_like(p), where=p != 0)  # zero poles: none
        rest = (self._Z[:, n:] * inv[:, :, None]).sum(axis=1)
        res = rest if self.residual is None else rest + self.residual
        return TireModel(
            self.speeds,
            self.poles[:, :n],
            self.psi[:, :n],
            self.chi[:, :n],
            self.wavelengths,
            self.participation[:, :, :n],
            params=self.params,
            meta={**self.meta, "truncated_from": int(self.n_modes)},
            hub_dofs=self.hub_dofs,
            interpolation=self.interpolation,
            residual=res,
        )

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
