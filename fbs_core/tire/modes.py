"""Complex modes of gyroscopic, damped systems and their tracking across speeds.

For ``M x'' + C x' + K x = f`` with a non-symmetric ``C = D + G(Omega)`` the
modes come from the first-order (state-space) eigenproblem of
``A = [[0, I], [-M^-1 K, -M^-1 C]]``. Right eigenvectors ``[psi; lambda psi]``
give the right mode shapes ``psi_r``; a left eigenvector ``[l1; l2]`` of ``A``
(a row of the inverse of the right eigenvector matrix) gives the left mode shape
``chi_r = M^-1 l2``, which satisfies
``chi_r^T (lambda_r^2 M + lambda_r C + K) = 0``. With
``a_r = chi_r^T (2 lambda_r M + C) psi_r`` the receptance is

    H(s) = sum_r psi_r chi_r^T / (a_r (s - lambda_r)),     s = j omega,

(reference-models.md sec. 2.5; e.g. Lancaster, "Lambda-matrices and vibrating
systems", 1966; Brinkmeier et al., J. Sound Vib. 309, 2008), and the mobility is
``j omega H``. Shapes are scaled so that ``a_r = 1``.

Modes are returned in conjugate pairs, ``[r_1, conj(r_1), r_2, conj(r_2), ...]``,
the member with positive eigenfrequency first, pairs sorted by eigenfrequency,
so that keeping the first ``N`` modes keeps ``N / 2`` pairs, lowest first
(thesis section 5.1). DOFs without mass (first-order states such as the slip of
the tread) give real poles; they are returned in pairs of two real poles ahead
of the conjugate pairs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike
from scipy.optimize import linear_sum_assignment

from ..errors import ModalError

__all__ = ["ComplexModes", "ModalError", "complex_modes", "mac", "track_modes", "receptance"]


@dataclass(frozen=True)
class ComplexModes:
    """Complex modes in conjugate pairs, normalised to ``a_r = 1``.

    Attributes
    ----------
    poles : ndarray, shape (2n,)
        ``lambda_r`` in rad/s, order ``[r_1, conj(r_1), r_2, ...]``.
    psi, chi : ndarray, shape (n_dof, 2n)
        Right and left mode shapes.
    """

    poles: np.ndarray
    psi: np.ndarray
    chi: np.ndarray

    @property
    def frequencies(self) -> np.ndarray:
        """Eigenfrequencies ``Im(lambda) / 2 pi`` in Hz of the positive members, shape (n,)."""
        return self.poles[0::2].imag / (2 * np.pi)

    @property
    def damping_ratios(self) -> np.ndarray:
        """``-Re(lambda) / |lambda|`` of the positive members, shape (n,)."""
        p = self.poles[0::2]
        a = np.abs(p)
        return np.where(a > 0, -p.real / np.where(a > 0, a, 1.0), 1.0)  # zero pole: 1

    def take(self, idx: ArrayLike) -> ComplexModes:
        """The pairs ``idx`` (indices of positive members, 0..n-1), as a new object."""
        idx = np.asarray(idx)
        cols = np.stack([2 * idx, 2 * idx + 1], -1).ravel()
        return ComplexModes(self.poles[cols], self.psi[:, cols], self.chi[:, cols])


def _inverse_of_eigenvectors(lam: np.ndarray, vr: np.ndarray) -> np.ndarray:
    """``inv(vr)`` for the eigenvectors of a real matrix, in real arithmetic.

    LAPACK returns the eigenvectors of a real matrix as real columns (real eigenvalues)
    and conjugate pairs ``v, conj(v)`` (in that order, the member with positive imaginary
    part first). With ``R`` the real matrix of the columns ``Re v, Im v`` of every pair
    (and the real columns as they are), ``vr = R T`` with ``T`` block-diagonal,
    ``[[1, 1], [j, -j]]`` per pair, so ``inv(vr) = inv(T) inv(R)``: the rows of a pair
    are ``(r_p - j r_q) / 2`` and ``(r_p + j r_q) / 2`` of ``inv(R)``. The same left
    eigenvectors as a complex solve (biorthogonal to the right ones, to round-off) at a
    quarter of the cost.

    Parameters
    ----------
    lam : ndarray, shape (N,)
        Eigenvalues as LAPACK returned them (pairs adjacent).
    vr : ndarray, shape (N, N)
        Right eigenvectors as columns; a pair's columns conjugate to round-off (scaled
        by conjugate factors).

    Returns
    -------
    ndarray, shape (N, N), complex
    """
    N = lam.size
    first = np.zeros(N, bool)  # first member of a conjugate pair
    j = 0
    while j < N:
        if lam[j].imag != 0.0 and j + 1 < N and lam[j + 1] == np.conj(lam[j]):
            first[j] = True
            j += 2
        else:
            j += 1
    p = np.flatnonzero(first)
    R = np.ascontiguousarray(vr.real)
    R[:, p + 1] = vr[:, p].imag
    single = np.ones(N, bool)
    single[p] = single[p + 1] = False
    if np.any(vr[:, single].imag != 0.0):  # not LAPACK's real pattern: the complex solve
        return np.linalg.solve(vr, np.eye(N))
    Ri = np.linalg.inv(R)
    W = Ri.astype(complex)
    W[p] = 0.5 * (Ri[p] - 1j * Ri[p + 1])
    W[p + 1] = 0.5 * (Ri[p] + 1j * Ri[p + 1])
    return W


def complex_modes(M: ArrayLike, C: ArrayLike, K: ArrayLike) -> ComplexModes:
    """All complex modes of ``M x'' + C x' + K x = f`` (dense, real matrices).

    Parameters
    ----------
    M, C, K : array_like, shape (n, n)
        Mass, damping plus gyroscopic, stiffness. Real; ``M`` invertible, or zero
        rows and columns for first-order DOFs whose block of ``C`` is invertible.

    Returns
    -------
    ComplexModes
        ``2n`` modes in conjugate pairs sorted by eigenfrequency.

    Raises
    ------
    ModalError
        If not every eigenvalue has a non-zero imaginary part (an overdamped or
        rigid-body mode), so that the modes do not form ``n`` conjugate pairs.
    """
    M, C, K = (np.asarray(a, dtype=float) for a in (M, C, K))
    n = M.shape[0]
    massless = ~np.any(M != 0, axis=0) & ~np.any(M != 0, axis=1)
    if np.any(massless):
        return _descriptor_modes(M, C, K, massless)
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])
    lam, vr = sla.eig(A, overwrite_a=True, check_finite=False)
    pos = np.flatnonzero(lam.imag > 1e-9 * np.abs(lam).max())
    if pos.size != n:
        raise ModalError(
            f"expected {n} eigenvalues with positive imaginary part (underdamped modes in "
            f"conjugate pairs), found {pos.size}; the system has overdamped or rigid-body modes"
        )
    # left eigenvectors as the rows of inv(VR): biorthogonal to the right ones even
    # for (nearly) repeated eigenvalues, e.g. the cos / sin pairs at 0 km/h
    W = _inverse_of_eigenvectors(lam, vr)
    pos = pos[np.argsort(lam[pos].imag)]
    lam = lam[pos]
    psi = vr[:n, pos]
    chi = Minv @ W[pos, n:].T  # l_r^T A = lambda_r l_r^T, chi_r = M^-1 l_r[n:]
    # phase convention: the largest entry of psi is real and positive
    k = np.argmax(np.abs(psi), axis=0)
    ph = psi[k, np.arange(n)]
    psi = psi * (np.abs(ph) / ph)[None, :]
    psi = psi / np.linalg.norm(psi, axis=0)[None, :]
    a = np.einsum("ir,ij,jr->r", chi, 2 * M, psi) * lam + np.einsum("ir,ij,jr->r", chi, C, psi)
    chi = chi / a[None, :]
    poles = np.empty(2 * n, complex)
    poles[0::2], poles[1::2] = lam, np.conj(lam)
    P = np.empty((n, 2 * n), complex)
    X = np.empty((n, 2 * n), complex)
    P[:, 0::2], P[:, 1::2] = psi, np.conj(psi)
    X[:, 0::2], X[:, 1::2] = chi, np.conj(chi)
    return ComplexModes(poles, P, X)


def _descriptor_modes(
    M: np.ndarray, C: np.ndarray, K: np.ndarray, massless: np.ndarray
) -> ComplexModes:
    """Modes of a system with massless (first-order) DOFs, e.g. tread slip states.

    State ``z = [x; v_m]`` (all displacements, velocities of the DOFs with mass):
    ``E z' = A z + B f`` with rows ``x_m' = v_m``, ``C_ss x_s' + C_sm v_m + K_s x = f_s``
    and ``M_mm v_m' + C_ms x_s' + C_mm v_m + K_m x = f_m``. With right eigenvectors
    ``V`` of ``E^-1 A`` and ``W = V^-1``: ``psi_r = V[x, r]``,
    ``chi_r^T = (W E^-1 B)[r]``, so that ``H(s) = sum_r psi_r chi_r^T / (s - lambda_r)``
    (``a_r = 1``). Real poles (first-order modes) come in pairs of two real members,
    ahead of the conjugate pairs (eigenfrequency 0).
    """
    n = M.shape[0]
    mi = np.flatnonzero(~massless)
    si = np.flatnonzero(massless)
    nm = mi.size
    N = n + nm
    E = np.zeros((N, N))
    A = np.zeros((N, N))
    B = np.zeros((N, n))
    E[mi, mi] = 1.0  # x_m' = v_m
    A[mi, n + np.arange(nm)] = 1.0
    E[np.ix_(si, si)] = C[np.ix_(si, si)]
    A[si, :n] = -K[si]
    A[np.ix_(si, n + np.arange(nm))] = -C[np.ix_(si, mi)]
    B[si, si] = 1.0
    E[np.ix_(n + np.arange(nm), si)] = C[np.ix_(mi, si)]
    E[np.ix_(n + np.arange(nm), n + np.arange(nm))] = M[np.ix_(mi, mi)]
    A[n + np.arange(nm), :n] = -K[mi]
    A[np.ix_(n + np.arange(nm), n + np.arange(nm))] = -C[np.ix_(mi, mi)]
    B[n + np.arange(nm), mi] = 1.0
    # E^-1 [A, B] by E's blocks: rows x_m' are unit rows, x_s' takes C_ss^-1, v_m' then
    # M_mm^-1 (the same numbers as a dense solve of E to round-off, a sixth of its work)
    rhs = np.concatenate([A, B], axis=1)
    sol = np.empty_like(rhs)
    sol[mi] = rhs[mi]
    sol[si] = np.linalg.solve(C[np.ix_(si, si)], rhs[si])
    vm = n + np.arange(nm)
    sol[vm] = np.linalg.solve(M[np.ix_(mi, mi)], rhs[vm] - C[np.ix_(mi, si)] @ sol[si])
    EinvB = sol[:, N:]
    lam, vr = sla.eig(sol[:, :N], overwrite_a=True, check_finite=False)
    lam_lapack = lam
    tol = 1e-9 * np.abs(lam).max()
    pos = np.flatnonzero(lam.imag > tol)
    real = np.flatnonzero(np.abs(lam.imag) <= tol)
    if real.size % 2 or pos.size * 2 + real.size != N:
        raise ModalError(
            f"expected conjugate pairs and an even number of real poles, found {pos.size} "
            f"pairs and {real.size} real poles"
        )
    real = real[np.argsort(-lam[real].real)]  # slowest first
    lam = np.where(np.abs(lam.imag) <= tol, lam.real + 0j, lam)
    k = np.argmax(np.abs(vr[:n]), axis=0)
    ph = vr[k, np.arange(N)]
    vr = vr * (np.abs(ph) / ph)[None, :]
    vr = vr / np.linalg.norm(vr[:n], axis=0)[None, :]
    W = _inverse_of_eigenvectors(lam_lapack, vr)
    # zero poles (free sliding: motions without stiffness) are exactly 0 and their
    # shapes a basis of the null space, made unique by unit entries in its first DOFs
    zero = real[np.abs(lam[real]) <= tol]
    if zero.size:
        lam[zero] = 0.0
        rows = np.arange(zero.size)
        blk = vr[np.ix_(rows, zero)]
        if np.linalg.cond(blk) > 1e8:
            rows = sla.qr(vr[:n, zero].T, pivoting=True)[2][: zero.size]
            blk = vr[np.ix_(rows, zero)]
        T = np.linalg.inv(blk)
        vr[:, zero] = vr[:, zero] @ T
        W[zero] = np.linalg.solve(T, W[zero])
    pos = pos[np.argsort(lam[pos].imag)]
    # chi_r of the kept modes only (the conjugates follow), real products of W's parts
    keep = np.r_[real, pos]
    X = np.empty((n, N), complex)  # (n, N): chi_r as columns
    X[:, keep] = (W[keep].real @ EinvB).T + 1j * (W[keep].imag @ EinvB).T
    n_pairs = pos.size + real.size // 2
    poles = np.empty(2 * n_pairs, complex)
    P = np.empty((n, 2 * n_pairs), complex)
    Q = np.empty((n, 2 * n_pairs), complex)
    nr = real.size
    poles[:nr] = lam[real]
    P[:, :nr], Q[:, :nr] = vr[:n, real], X[:, real]
    poles[nr::2], poles[nr + 1 :: 2] = lam[pos], np.conj(lam[pos])
    P[:, nr::2], P[:, nr + 1 :: 2] = vr[:n, pos], np.conj(vr[:n, pos])
    Q[:, nr::2], Q[:, nr + 1 :: 2] = X[:, pos], np.conj(X[:, pos])
    return ComplexModes(poles, P, Q)


def receptance(
    s: ArrayLike,
    modes: ComplexModes,
    out_idx: Sequence[int] | np.ndarray | None = None,
    in_idx: Sequence[int] | np.ndarray | None = None,
    n_modes: int | None = None,
) -> np.ndarray:
    """Modal synthesis ``H(s) = sum_r psi_r chi_r^T / (s - lambda_r)`` (``a_r = 1``).

    Parameters
    ----------
    s : array_like, shape (n_freq,)
        Laplace variable, ``j omega``.
    modes : ComplexModes
    out_idx, in_idx : index arrays, optional
        DOF rows of ``psi`` and ``chi``; default all.
    n_modes : int, optional
        Keep the first ``n_modes`` (whole pairs); default all.

    Returns
    -------
    ndarray, shape (n_freq, n_out, n_in)
    """
    s = np.asarray(s)
    nm = modes.poles.size if n_modes is None else n_modes
    psi = modes.psi[:, :nm] if out_idx is None else modes.psi[out_idx, :nm]
    chi = modes.chi[:, :nm] if in_idx is None else modes.chi[in_idx, :nm]
    T = 1.0 / (s[:, None] - modes.poles[None, :nm])  # (n_freq, n_modes)
    H: np.ndarray = np.einsum("or,fr,ir->foi", psi, T, chi)  # psi (n_out, r), chi (n_in, r)
    return H


def mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Modal assurance criterion between the columns of ``a`` and ``b`` (complex).

    ``MAC_ij = |a_i^H b_j|^2 / ((a_i^H a_i)(b_j^H b_j))``, shape (n_a, n_b).
    """
    num = np.abs(a.conj().T @ b) ** 2
    m: np.ndarray = num / np.outer(np.sum(np.abs(a) ** 2, 0), np.sum(np.abs(b) ** 2, 0))
    return m


def track_modes(modes: list[ComplexModes]) -> tuple[list[ComplexModes], np.ndarray]:
    """Track modes across a sequence of operating points by MAC of the right shapes.

    Mode ``k`` of one operating point is paired with the mode of the next one
    that it resembles most: an optimal assignment (every mode used once) that
    minimises ``-MAC + |f_a - f_b| / (0.05 f_a + 5 Hz)`` over the positive
    members. MAC alone mis-pairs the modes of the dense, veering clusters of the
    rolling tire (MAC drops to 0.5 within 1 km/h there), so the distance in
    eigenfrequency is part of the criterion; it keeps the interpolation error
    against a direct solution at mid-points smallest. The tracked
    identities are then ordered by their eigenfrequency averaged over the
    operating points, lowest first, so that index ``k`` means the same physical
    mode at every operating point and the truncation "first N modes" is well
    defined along a speed sweep.

    Returns
    -------
    tracked : list of ComplexModes
        Re-ordered modes, one per operating point.
    macs : ndarray, shape (n_points - 1, n)
        MAC of every tracked pair between consecutive points (in the order of
        the previous point's tracked modes, before the final re-ordering).
    """
    n = modes[0].frequencies.size
    perm = [np.arange(n)]
    mac_min = []
    for prev, cur in zip(modes[:-1], modes[1:], strict=True):
        a = prev.psi[:, 0::2][:, perm[-1]]
        m = mac(a, cur.psi[:, 0::2])
        fp, fc = prev.frequencies[perm[-1]], cur.frequencies
        cost = -m + np.abs(fp[:, None] - fc[None, :]) / (0.05 * fp[:, None] + 5.0)
        rows, cols = linear_sum_assignment(cost)
        p = np.empty(n, int)
        p[rows] = cols
        perm.append(p)
        mac_min.append(m[rows, cols][np.argsort(rows)])
    mean_f = np.mean([md.frequencies[p] for md, p in zip(modes, perm, strict=True)], axis=0)
    order = np.argsort(mean_f, kind="stable")
    tracked = [md.take(p[order]) for md, p in zip(modes, perm, strict=True)]
    return tracked, np.array(mac_min)
