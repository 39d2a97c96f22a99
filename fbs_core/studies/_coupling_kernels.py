"""Compiled eq. 4.1 for many truncations at once (the truncation map's coupling).

For every retained-mode count ``N`` and line ``l``:

    g = (Y_jj^A[N, l] + Y_jj^E[l])^-1 v_j[N, l]      (interface forces, eq. 2.37)
    v_e = Y_ej^E[l] g                                 (eq. 4.1)

Gaussian elimination with partial pivoting on the small interface matrix (the pivot
of largest ``|Re| + |Im|`` in its column, as LAPACK's ``zgetrf``), one system after the
other without numpy's per-matrix overhead. A zero pivot marks the system singular; the
caller reports it (:func:`fbs_core.kernels.solve_interface` names the line).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .._typing import ComplexArray

__all__ = ["couple_many"]


def couple_many(
    YjjA: ComplexArray, vj: ComplexArray, YjjE: ComplexArray, YejE: ComplexArray
) -> tuple[ComplexArray, ComplexArray, bool]:
    """Interface forces and responses of eq. 4.1 for every count and line.

    Parameters
    ----------
    YjjA : ndarray, shape (n_N, n_f, n_j, n_j)
    vj : ndarray, shape (n_N, n_f, n_j)
    YjjE : ndarray, shape (n_f, n_j, n_j)
    YejE : ndarray, shape (n_f, n_e, n_j)

    Returns
    -------
    g : ndarray, shape (n_N, n_f, n_j)
    resp : ndarray, shape (n_N, n_f, n_e)
    singular : bool
        Some interface matrix had a zero pivot (its ``g`` and ``resp`` are NaN).
    """
    n_N, n_f, n_j = vj.shape
    g = np.empty((n_N, n_f, n_j), complex)
    resp = np.empty((n_N, n_f, YejE.shape[1]), complex)
    singular = _couple(
        np.ascontiguousarray(YjjA, complex),
        np.ascontiguousarray(vj, complex),
        np.ascontiguousarray(YjjE, complex),
        np.ascontiguousarray(YejE, complex),
        g,
        resp,
    )
    return g, resp, bool(singular)


@njit(cache=True, nogil=True, error_model="numpy")
def _couple(
    YjjA: ComplexArray,
    vj: ComplexArray,
    YjjE: ComplexArray,
    YejE: ComplexArray,
    g: ComplexArray,
    resp: ComplexArray,
) -> bool:
    n_N, n_f, n = vj.shape
    n_e = YejE.shape[1]
    A = np.empty((n, n), np.complex128)
    x = np.empty(n, np.complex128)
    singular = False
    for k in range(n_N):
        for f in range(n_f):
            for i in range(n):
                for j in range(n):
                    A[i, j] = YjjA[k, f, i, j] + YjjE[f, i, j]
                x[i] = vj[k, f, i]
            ok = True
            for c in range(n):  # elimination with partial pivoting
                p = c
                best = abs(A[c, c].real) + abs(A[c, c].imag)
                for i in range(c + 1, n):
                    m = abs(A[i, c].real) + abs(A[i, c].imag)
                    if m > best:
                        best, p = m, i
                if best == 0.0:
                    ok = False
                    break
                if p != c:
                    for j in range(n):
                        A[c, j], A[p, j] = A[p, j], A[c, j]
                    x[c], x[p] = x[p], x[c]
                inv = 1.0 / A[c, c]
                for i in range(c + 1, n):
                    fac = A[i, c] * inv
                    if fac != 0:
                        for j in range(c + 1, n):
                            A[i, j] -= fac * A[c, j]
                        x[i] -= fac * x[c]
            if not ok:
                singular = True
                g[k, f, :] = np.nan
                resp[k, f, :] = np.nan
                continue
            for i in range(n - 1, -1, -1):  # back substitution
                acc = x[i]
                for j in range(i + 1, n):
                    acc -= A[i, j] * x[j]
                x[i] = acc / A[i, i]
            for i in range(n):
                g[k, f, i] = x[i]
            for e in range(n_e):
                acc = 0j
                for j in range(n):
                    acc += YejE[f, e, j] * x[j]
                resp[k, f, e] = acc
    return singular
