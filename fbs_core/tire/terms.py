"""The modal synthesis of a tire model split into the terms of its modes.

:class:`~fbs_core.tire.TireModel` synthesises the hub mobility and the free hub
velocity as sums over its modes (``H = sum_r R_r / (s - lambda_r)``, thesis eq. 2.5
with the residues ``R_r = psi_r chi_r^T`` and ``psi_r p_r``), every line at its own
speed. For "which modes matter" the sum is wanted term by term: the term of
every stored (tracked) mode pair at every line, such that the terms add up to the
model's own all-modes synthesis.

Between two operating points a mode's pole and residue are interpolated exactly as the
model does (:mod:`.interp`: Lagrange weights on the interval's nodes); a cluster of
veering modes, which the model sums through its rational form ``N(z) / (rho P(z))``,
is split into its members' poles and residues at the line (the roots of the
interpolated ``P`` and ``N(z_r) / P'(z_r)``, :func:`.interp.cluster_at`): their partial
fractions add up to the rational form, so the terms of all modes add up to the model's
synthesis (to round-off; tested). Inside a cluster the ``i``-th root (by frequency) is
the term of the member whose interpolated pole is the ``i``-th (the rule of
``TireModel.poles_at``), so at the operating points every term is the stored mode's.

The model is read through its public :meth:`~fbs_core.tire.TireModel.interval_of` (the
interval of every line's speed) and :meth:`~fbs_core.tire.TireModel.interval` (the
interval's stencil, residues and clusters with their moments).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray, IntArray
from ..errors import FBSError
from .interp import cluster_at, lagrange_weights

__all__ = ["ModeTerms", "mode_terms", "pair_labels"]

#: Lines per chunk (bounds the memory of the (lines, modes, columns) residues).
_CHUNK = 96


@dataclass(frozen=True, eq=False)
class ModeTerms:
    """Receptance terms of every mode pair of a tire model, line by line.

    Attributes
    ----------
    freq, speeds : ndarray, shape (n_f,)
        Frequency (Hz) and speed (km/h) of every line.
    cols : ndarray of int, shape (n_c,)
        Residue columns: ``0..35`` the hub receptance 6 x 6 (row major), ``36 + 6 h + i``
        the hub response ``i`` to the patch load of wavelength ``h``.
    dynamic : ndarray, shape (n_p, n_f, n_c)
        ``sum_(r in pair) R_r / (s - lambda_r)`` of every pair (both members; a pair of
        two real poles is one first-order "mode" too), receptance.
    static : ndarray, shape (n_p, n_f, n_c) or None
        The pairs' quasi-static parts ``sum R_r / (-lambda_r)`` (zero poles: none), the
        upper residual flexibility they leave when left out (docs/tire-model.md).
    frequency : ndarray, shape (n_p, n_f)
        Eigenfrequency ``|Im lambda| / 2 pi`` (Hz) of every pair at every line (0 for a
        pair of real poles).
    damping : ndarray, shape (n_p, n_f)
        Damping ratio ``-Re lambda / |lambda|`` of the pair's first member.
    """

    freq: FloatArray
    speeds: FloatArray
    cols: IntArray
    dynamic: ComplexArray
    static: ComplexArray | None
    frequency: FloatArray
    damping: FloatArray

    @property
    def n_pairs(self) -> int:
        """Number of mode pairs."""
        return int(self.dynamic.shape[0])


def mode_terms(
    tire: Any,
    freq: ArrayLike,
    speeds: ArrayLike,
    harmonic_index: int | None = None,
    *,
    static: bool = False,
    hub: bool = True,
) -> ModeTerms:
    """The modal synthesis of ``tire`` term by term: one term per stored mode pair.

    Parameters
    ----------
    tire : TireModel
        A modal tire model (:class:`fbs_core.tire.TireModel`).
    freq, speeds : array_like, shape (n_f,)
        Frequency (Hz) and speed (km/h) of every line (along a harmonic line
        ``v = 3.6 f lambda``, or one fixed speed).
    harmonic_index : int, optional
        Index into ``tire.wavelengths`` of the patch load whose hub response is wanted.
    static : bool
        Keyword only: also the quasi-static parts ``R_r / (-lambda_r)``.
    hub : bool
        Keyword only: include the hub receptance columns (False: the patch response only).

    Returns
    -------
    ModeTerms
        ``dynamic.sum(0)`` equals the model's all-modes receptance synthesis (times
        ``j omega`` its mobility, ``tire.truncations``).

    Raises
    ------
    FBSError
        For mismatched lines, or neither hub nor patch columns.
    OperatingPointError
        For speeds outside the model's operating points.
    """
    f = np.atleast_1d(np.asarray(freq, float))
    v = np.atleast_1d(np.asarray(speeds, float))
    if f.shape != v.shape or f.ndim != 1:
        raise FBSError(f"freq and speeds must be 1-D of one length, got {f.shape} and {v.shape}")
    k_of = tire.interval_of(v)  # OperatingPointError outside the operating points
    cols = np.arange(36) if hub else np.arange(0)
    if harmonic_index is not None:
        cols = np.r_[cols, 36 + 6 * int(harmonic_index) + np.arange(6)]
    if cols.size == 0:
        raise FBSError("mode_terms needs hub=True or a harmonic_index (no columns asked for)")
    n_m = tire.n_modes
    n_p = n_m // 2
    s = 2j * np.pi * f
    dyn = np.zeros((n_p, f.size, cols.size), complex)
    sta = np.zeros_like(dyn) if static else None
    fr = np.zeros((n_p, f.size))
    zeta = np.zeros((n_p, f.size))
    for k in np.unique(k_of):
        iv = tire.interval(int(k), cols)
        poles_nd = iv.poles  # (n_nodes, n_m)
        Zc = iv.residues  # (n_nodes, n_m, n_c)
        lines = np.flatnonzero(k_of == k)
        for idx in np.array_split(lines, max(1, int(np.ceil(lines.size / _CHUNK)))):
            w = lagrange_weights(iv.speeds, v[idx])  # (n_l, n_nodes)
            n_l = idx.size
            lam = w @ poles_nd  # (n_l, n_m)
            # interpolated residues, one matrix product: (n_l, n_nodes) @ (n_nodes, n_m n_c)
            R = (w.astype(complex) @ Zc.reshape(Zc.shape[0], -1)).reshape(n_l, n_m, -1)
            rows = np.arange(n_l)[:, None, None]
            for cl in iv.clusters:  # members of a cluster: roots and partial fractions
                p, r = cluster_at(cl, w)  # (n_l, n_c, k), (n_l, n_c, k, n_cols)
                # the i-th root by frequency goes to the member whose interpolated pole is
                # i-th (as TireModel.poles_at): exact at the operating points
                perm = np.argsort(np.abs(lam[:, cl.members].imag), axis=-1)
                mem = np.take_along_axis(cl.members[None], perm, axis=-1)  # (n_l, n_c, k)
                lam[rows, mem] = p
                R[rows, mem] = r
            g = 1.0 / (s[idx, None] - lam)  # (n_l, n_m)
            # both members of every pair summed in place: (n_l, n_p, n_c)
            T = R[:, 0::2] * g[:, 0::2, None]
            T += R[:, 1::2] * g[:, 1::2, None]
            dyn[:, idx] = T.transpose(1, 0, 2)
            if sta is not None:
                inv = np.divide(-1.0, lam, out=np.zeros_like(lam), where=lam != 0)
                S = R[:, 0::2] * inv[:, 0::2, None]
                S += R[:, 1::2] * inv[:, 1::2, None]
                sta[:, idx] = S.transpose(1, 0, 2)
            fr[:, idx] = (np.abs(lam[:, 0::2].imag) / (2 * np.pi)).T
            a = np.abs(lam[:, 0::2])
            zeta[:, idx] = np.where(a > 0, -lam[:, 0::2].real / np.where(a > 0, a, 1.0), 1.0).T
    return ModeTerms(f, v, cols, dyn, sta, fr, zeta)


def pair_labels(tire: Any) -> tuple[str, ...]:
    """Short labels of the stored mode pairs: ``"mode 7"`` (0-based pair index), with
    ``" (first order)"`` for a pair of real poles."""
    p = np.asarray(tire.poles)[:, 0::2]
    real = np.all(p.imag == 0, axis=0)
    return tuple(f"mode {i}" + (" (first order)" if r else "") for i, r in enumerate(real))
