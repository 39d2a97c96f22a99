"""Interpolation of tracked complex modes between two operating points.

A modal model is delivered at a few speeds; along a harmonic line every
frequency line needs the model at its own speed (thesis section 4.1.2). Poles
``lambda_r`` and residues ``R_r`` (``psi_r chi_r^T``, ``psi_r p_r``: invariant to
the scaling of the shapes) are interpolated linearly in speed, except for
**clusters**: modes whose poles lie close together at either end of the
interval. In a cluster of a gyroscopic system the modes veer (their shapes
exchange within a fraction of the interval), so the individual residues change
much faster than the cluster's total contribution, and linear weights on them
misplace the response by several dB. The cluster's contribution

    C(s) = sum_{r in G} R_r / (s - lambda_r) = N(z) / P(z),   z = (s - c) / rho

is a rational function whose denominator ``P(z) = prod (z - z_r)`` (the
symmetric functions of the scaled poles ``z_r = (lambda_r - c) / rho``) and
whose moments ``m_j = sum_r z_r^j R_r`` (``j < k``; the Markov parameters of the
cluster's block) are smooth in speed even where the individual eigenvectors
are not. They are interpolated linearly; the poles at the line's speed are the
roots of the interpolated ``P`` and the residues follow from the partial
fractions ``R_r = N(z_r) / P'(z_r)``, ``N`` built from the moments
(``n_{k-1-j} = sum_{i<=j} a_i m_{j-i}``). With one mode per cluster this is
plain linear interpolation, and at the operating points it is exact.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "Cluster",
    "Interval",
    "residue_change",
    "find_clusters",
    "cluster_ends",
    "cluster_at",
    "cluster_sum",
    "subset",
    "lagrange_weights",
]

#: Poles closer than ``KAPPA * (|Re l_r| + |Re l_q|)`` (a fraction of the summed
#: half-power bandwidths) at either end of an interval form a cluster.
KAPPA = 0.15
#: A mode "moves" when its residue vector changes by more than this fraction of its
#: size over the interval; only moving modes start a cluster.
TAU = 0.1
#: Largest cluster; larger groups are split with a tighter distance (conditioning).
KMAX = 4


@dataclass(frozen=True)
class Cluster:
    """All clusters of one size ``k`` in one interval, with their interpolation data.

    Attributes
    ----------
    members : ndarray of int, shape (n_c, k)
        Mode indices of every cluster (one member of each conjugate pair, all of
        the same sign), ordered by ``|Im lambda|`` averaged over the interval's ends.
    c : ndarray, complex, shape (n_c,)
    rho : ndarray, shape (n_c,)
        Centre and scale of the poles, ``z = (lambda - c) / rho``.
    a : ndarray, shape (n_nodes, n_c, k + 1)
        Coefficients of ``P(z)`` at the interpolation nodes (leading 1).
    m : ndarray, shape (n_c, n_nodes, k, n_res)
        Moments ``m_q = sum_r z_r^q R_r`` at the nodes.
    z : ndarray, shape (n_nodes, n_c, k)
        The scaled poles at the nodes (start values of the root finder).
    """

    members: np.ndarray
    c: np.ndarray
    rho: np.ndarray
    a: np.ndarray
    m: np.ndarray
    z: np.ndarray


@dataclass(frozen=True)
class Interval:
    """A tire model between two neighbouring operating points: what interpolates it.

    Built by :meth:`fbs_core.tire.TireModel.interval`; between the operating points
    ``speeds[e0]`` and ``speeds[e0 + 1]`` of the stencil a mode outside every cluster
    has the pole ``w @ poles[:, r]`` and the residue ``w @ residues[:, r]``
    (``w = lagrange_weights(speeds, v)``), the modes of a cluster come from
    :func:`cluster_at` (roots and partial fractions).

    Attributes
    ----------
    speeds : ndarray, shape (n_nodes,)
        Speeds (km/h) of the interpolation nodes (2 for linear, 4 for cubic).
    poles : ndarray, complex, shape (n_nodes, n_m)
        All poles at the nodes, stored (tracked) order.
    columns : ndarray of int, shape (n_c,)
        Residue columns: ``0..35`` the hub receptance 6 x 6 (row major), ``36 + 6 h + i``
        the hub response ``i`` to the patch load of wavelength ``h``.
    residues : ndarray, complex, shape (n_nodes, n_m, n_c)
        Those columns of every mode's residue at the nodes.
    clusters : tuple of Cluster
        The interval's clusters of close modes, their moments of those columns.
    """

    speeds: np.ndarray
    poles: np.ndarray
    columns: np.ndarray
    residues: np.ndarray
    clusters: tuple[Cluster, ...]


def residue_change(R0: np.ndarray, R1: np.ndarray) -> np.ndarray:
    """``|R1 - R0| / max(|R0|, |R1|)`` per mode (rows), 0 for modes without residues."""
    n0 = np.linalg.norm(R0, axis=-1)
    n1 = np.linalg.norm(R1, axis=-1)
    d = np.linalg.norm(R1 - R0, axis=-1)
    rel: np.ndarray = d / np.maximum(np.maximum(n0, n1), np.finfo(float).tiny)
    return rel


def _components(
    lam0: np.ndarray, lam1: np.ndarray, idx: np.ndarray, kappa: float, moving: np.ndarray
) -> list[np.ndarray]:
    """Connected groups of the modes ``idx``: pairs closer than ``kappa`` at either end,
    one of them moving; groups ordered by their first mode."""
    mv = moving[idx]
    near = np.zeros((idx.size, idx.size), bool)
    for lam in (lam0[idx], lam1[idx]):
        d = np.abs(lam[:, None] - lam[None, :])
        w = kappa * (np.abs(lam.real)[:, None] + np.abs(lam.real)[None, :])
        near |= (d < w) & (mv[:, None] | mv[None, :])
    near |= near.T
    # the first mode of every mode's group: the least label among the neighbours, then
    # the label's own label (pointer jumping), until nothing changes
    first = np.arange(idx.size)
    while True:
        nxt = np.minimum(first, np.where(near, first[None, :], idx.size).min(axis=1))
        nxt = nxt[nxt]
        if np.array_equal(nxt, first):
            break
        first = nxt
    return [idx[first == f] for f in np.unique(first)]


def find_clusters(
    lam0: ArrayLike,
    lam1: ArrayLike,
    kappa: float | None = None,
    kmax: int | None = None,
    moving: ArrayLike | None = None,
) -> list[np.ndarray]:
    """Groups (size 2..kmax) of modes whose poles are close at either end.

    Parameters
    ----------
    lam0, lam1 : ndarray, shape (n,)
        Poles of the same tracked modes at the two ends of the interval.
    kappa : float, optional
        Distance criterion as a fraction of the summed ``|Re lambda|`` (default
        :data:`KAPPA`); 0 disables clustering.
    kmax : int, optional
        Largest cluster (default :data:`KMAX`); a larger group is split again
        with ``kappa / 2``.
    moving : ndarray of bool, shape (n,), optional
        Modes whose residues change by more than :data:`TAU` over the interval
        (their shapes veer); a pair is joined only if one of them moves. Default all.

    Returns
    -------
    list of ndarray of int
    """
    kappa = KAPPA if kappa is None else kappa
    kmax = KMAX if kmax is None else kmax
    lam0, lam1 = np.asarray(lam0), np.asarray(lam1)
    moving = np.ones(lam0.size, bool) if moving is None else np.asarray(moving, bool)
    out: list[np.ndarray] = []
    todo = [(np.arange(lam0.size), kappa)]
    if kappa <= 0:
        return out
    while todo:
        idx, kp = todo.pop()
        for g in _components(lam0, lam1, idx, kp, moving):
            if g.size < 2:
                continue
            if g.size <= kmax:
                out.append(np.sort(g))
            else:
                todo.append((g, kp / 2))
    return sorted(out, key=lambda g: g[0])


def lagrange_weights(nodes: ArrayLike, v: ArrayLike) -> np.ndarray:
    """Lagrange interpolation weights of the speeds ``v`` on ``nodes``, shape (n_v, n_nodes)."""
    x = np.asarray(nodes, float)
    vs = np.atleast_1d(np.asarray(v, float))
    w = np.ones((vs.size, x.size))
    for i in range(x.size):
        for j in range(x.size):
            if i != j:
                w[:, i] *= (vs - x[j]) / (x[i] - x[j])
    return w


def _poly(z: np.ndarray) -> np.ndarray:
    """Coefficients of ``prod_r (x - z_r)`` over the last axis (leading 1)."""
    a: np.ndarray = np.ones(z.shape[:-1] + (1,), complex)
    for r in range(z.shape[-1]):
        nxt: np.ndarray = np.zeros(z.shape[:-1] + (a.shape[-1] + 1,), complex)
        nxt[..., :-1] += a
        nxt[..., 1:] -= z[..., r, None] * a
        a = nxt
    return a


def cluster_ends(
    groups: Sequence[np.ndarray],
    lam: np.ndarray,
    R: np.ndarray | None,
    ends: tuple[int, int] = (0, -1),
) -> list[Cluster]:
    """Interpolation data of clusters from their poles and residues at the nodes.

    Parameters
    ----------
    groups : list of ndarray of int
        Member indices of every cluster.
    lam : ndarray, shape (n_nodes, n_m)
        All poles at the interpolation nodes (2 for linear, 4 for cubic).
    R : ndarray, shape (n_nodes, n_m, n_res), or None
        All residues at the nodes; None: no moments (``n_res = 0``: poles only, or the
        moments folded into the coefficients as :mod:`.sums` does).
    ends : pair of int
        The nodes bounding the interval (they set the centre, scale and order).

    Returns
    -------
    list of Cluster
        One batch per cluster size.
    """
    e0, e1 = ends
    out: list[Cluster] = []
    for k in sorted({len(g) for g in groups}):
        mem = np.array([g for g in groups if len(g) == k])  # (n_c, k)
        avg = np.abs(lam[e0][mem].imag + lam[e1][mem].imag)
        mem = np.take_along_axis(mem, np.argsort(avg, axis=1), 1)
        both = np.concatenate([lam[e0][mem], lam[e1][mem]], axis=1)  # (n_c, 2k)
        c = both.mean(axis=1)
        rho = np.maximum(np.abs(both - c[:, None]).max(axis=1), 1e-3 * np.abs(c))
        rho = np.maximum(rho, 1e-12)
        z = (lam[:, mem] - c[None, :, None]) / rho[None, :, None]  # (n_nodes, n_c, k)
        if R is None:
            m = np.zeros((mem.shape[0], lam.shape[0], k, 0), complex)
        else:
            pw = z[:, :, None, :] ** np.arange(k)[None, None, :, None]  # (n_nodes, n_c, j, k)
            m = np.einsum("ncjr,ncrx->cnjx", pw, R[:, mem])  # moments, cluster-major
        out.append(Cluster(mem, c, rho, _poly(z), np.ascontiguousarray(m), z))
    return out


def _coefficients(cl: Cluster, w: np.ndarray) -> np.ndarray:
    """``P``'s coefficients at the lines: ``(n_l, n_c, k + 1)``, linear in the weights."""
    n_l, n_nodes = w.shape
    a: np.ndarray = (w @ cl.a.reshape(n_nodes, -1)).reshape(n_l, *cl.a.shape[1:])
    return a


def _partials(a: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Horner partial sums ``b_i = sum_(i' <= i) a_i' z^(i - i')``, shape ``z.shape + (k + 1,)``.

    ``b_k = P(z)``, and the numerator of the partial fractions regrouped by the
    moments is ``N(z) = sum_q b_(k-1-q) m_q`` (from ``n_j = sum_(i <= j) a_i m_(j-i)``),
    so the moments enter only through one product with these scalars.
    """
    k = a.shape[-1] - 1
    ex = (Ellipsis,) + (None,) * (z.ndim - a.ndim + 1)
    b = np.empty(z.shape + (k + 1,), complex)
    b[..., 0] = a[..., 0][ex]
    for i in range(1, k + 1):
        b[..., i] = b[..., i - 1] * z + a[..., i][ex]
    return b


def subset(cl: Cluster, mask: np.ndarray) -> Cluster:
    """The clusters ``mask`` (boolean or index array over ``n_c``) of a batch."""
    return Cluster(
        cl.members[mask], cl.c[mask], cl.rho[mask], cl.a[:, mask], cl.m[mask], cl.z[:, mask]
    )


def cluster_sum(
    cl: Cluster,
    w: ArrayLike,
    s: ArrayLike,
    cols: Sequence[int] | np.ndarray | None = None,
    per_cluster: bool = False,
) -> np.ndarray:
    """Total receptance contribution of all clusters, ``sum_c N_c(z) / (rho_c P_c(z))``.

    No roots are needed for the sum over a whole cluster; the moments enter
    through one matrix product.

    Parameters
    ----------
    cl : Cluster
    w : ndarray, shape (n_l, n_nodes)
    s : ndarray, shape (n_l,)
        Laplace variable ``j omega`` of every line.
    cols : index array, optional
    per_cluster : bool
        Return every cluster's contribution instead of their sum.

    Returns
    -------
    ndarray, shape (n_l, n_cols) or (n_l, n_c, n_cols)
    """
    wa = np.asarray(w, float)
    n_l, n_nodes = wa.shape
    a = _coefficients(cl, wa)
    k = a.shape[-1] - 1
    zs = (np.asarray(s)[:, None] - cl.c[None, :]) / cl.rho[None, :]  # (n_l, n_c)
    b = _partials(a, zs)  # (n_l, n_c, k + 1); b_k = P(z)
    h = b[..., k - 1 :: -1] / (cl.rho[None, :, None] * b[..., k, None])  # (n_l, n_c, k) by q
    g = wa[:, None, :, None] * h[:, :, None, :]  # (n_l, n_c, n_nodes, k)
    if per_cluster:
        n_c = cl.members.shape[0]
        g = np.moveaxis(g.reshape(n_l, n_c, -1), 1, 0)  # (n_c, n_l, n_nodes k)
        tot: np.ndarray = np.moveaxis(g @ cl.m.reshape(n_c, n_nodes * k, cl.m.shape[-1]), 0, 1)
        return tot if cols is None else tot[..., cols]
    m = cl.m if cols is None else cl.m[..., cols]  # only the columns wanted
    out: np.ndarray = g.reshape(n_l, -1) @ m.reshape(-1, m.shape[-1])
    return out


def cluster_at(
    cl: Cluster, w: ArrayLike, cols: Sequence[int] | np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Poles and residues of a batch of clusters at lines with node weights ``w``.

    Parameters
    ----------
    cl : Cluster
    w : ndarray, shape (n_l, n_nodes)
        Interpolation weights of the nodes for every line.
    cols : index array, optional
        Residue columns wanted (default all).

    Returns
    -------
    poles : ndarray, shape (n_l, n_c, k)
        Sorted by ``|Im lambda|`` ascending, as the members, so that member ``i``
        gets column ``i`` (and a conjugate cluster gets the conjugate poles).
    residues : ndarray, shape (n_l, n_c, k, n_cols)
    """
    wa = np.asarray(w, float)
    n_l, n_nodes = wa.shape
    n_c, k = cl.members.shape
    a = _coefficients(cl, wa)
    if k == 2:  # roots of z^2 + a1 z + a0 in closed form
        d = np.sqrt(a[..., 1] ** 2 / 4 - a[..., 2])
        z = np.stack([-a[..., 1] / 2 + d, -a[..., 1] / 2 - d], axis=-1)
    else:  # companion matrices: one batched eigenvalue call
        comp = np.zeros((n_l, n_c, k, k), complex)
        comp[..., 0, :] = -a[..., 1:]
        comp[..., np.arange(1, k), np.arange(k - 1)] = 1.0
        z = np.linalg.eigvals(comp)
    sign = np.where(cl.c.imag >= 0, 1.0, -1.0)[None, :, None]
    z = np.take_along_axis(z, np.argsort(sign * z.imag, axis=-1), -1)
    b = _partials(a[:, :, None, :], z)  # (n_l, n_c, k_root, k + 1)
    diff = z[..., :, None] - z[..., None, :]
    diff[..., np.arange(k), np.arange(k)] = 1.0
    dp = np.prod(diff, axis=-1)  # P'(z_r)
    h = b[..., k - 1 :: -1] / dp[..., None]  # (n_l, n_c, k_root, k_q)
    g = wa[:, None, None, :, None] * h[:, :, :, None, :]  # (n_l, n_c, k_root, n_nodes, k_q)
    g = np.moveaxis(g, 1, 0).reshape(n_c, n_l * k, n_nodes * k)
    r = g @ cl.m.reshape(n_c, n_nodes * k, cl.m.shape[-1])  # (n_c, n_l * k_root, n_res)
    r = np.moveaxis(r.reshape(n_c, n_l, k, r.shape[-1]), 0, 1)
    if cols is not None:
        r = r[..., cols]
    return cl.c[None, :, None] + cl.rho[None, :, None] * z, r
