"""Thesis eqs. 2.34-2.42 block by block, derived again and decided by a direct solution.

The printed eqs. 2.34, 2.35, 2.38 and 2.41 mix up subscripts. Derivation (eqs.
2.26-2.30): with the interface force ``g = F_j^E`` and ``S = Y_jj^A + Y_jj^E``,

    g = S^-1 (Y_ja^A F_a + Y_jj^A F_j - Y_je^E F_e)                       (2.29)
    v_a = Y_aa^A F_a + Y_aj^A (F_j - g),  v_j = Y_ja^A F_a + Y_jj^A (F_j - g)
    v_e = Y_ee^E F_e + Y_ej^E g

so that, block by block (corrected forms),

    Y*_aa = Y_aa^A - Y_aj^A S^-1 Y_ja^A         (2.34; printed: Y_aj^A - Y_aa^A S^-1 Y_ja^A)
    Y*_aj = Y_aj^A - Y_aj^A S^-1 Y_jj^A         (2.35; printed: S with Y_aj^A for Y_jj^A)
    Y*_ae = Y_aj^A S^-1 Y_je^E                  (2.36)
    Y*_ea = Y_ej^E S^-1 Y_ja^A                  (2.37, the basis of eq. 4.1)
    Y*_ej = Y_ej^E S^-1 Y_jj^A                  (2.38; printed: S with Y_aj^A for Y_jj^A)
    Y*_ee = Y_ee^E - Y_ej^E S^-1 Y_je^E         (2.39)
    Y*_ja = Y_ja^A - Y_jj^A S^-1 Y_ja^A         (2.40)
    Y*_jj = Y_jj^A - Y_jj^A S^-1 Y_jj^A         (2.41; printed: S with Y_aj^A for Y_jj^A)
    Y*_je = Y_jj^A S^-1 Y_je^E                  (2.42)

Each corrected block must equal the direct solution of the assembled structure;
each printed form must not (A has as many internal as interface DOFs here, so
the printed forms can be evaluated at all).
"""

from __future__ import annotations

import numpy as np
import pytest
from discrete import build, frf_of, label

FREQ = np.linspace(0.5, 40.0, 80)
PART = {"A": [0, 3], "E": [3, 4, 5]}
a = [label(0, d) for d in "xy"]
j = [label(3, d) for d in "xy"]
e = [label(4, d) for d in "xy"] + [label(5, d) for d in "xy"]


@pytest.fixture(scope="module")
def blocks():
    subs, glob = build(PART, gyro=35.0, seed=11)  # gyroscopic: nothing is reciprocal
    YA = frf_of(*subs["A"], FREQ)
    YE = frf_of(*subs["E"], FREQ)
    Yd = frf_of(*glob, FREQ)

    def A(r, c):
        return YA.sel(r, c).data

    def E(r, c):
        return YE.sel(r, c).data

    def D(r, c):
        return Yd.sel(r, c).data

    return A, E, D


def _rel(x, ref):
    return np.max(np.abs(x - ref)) / np.max(np.abs(ref))


def _Sinv(A, E, X):
    return np.linalg.solve(A(j, j) + E(j, j), X)


def test_corrected_blocks_equal_direct_solution(blocks):
    A, E, D = blocks
    Sinv = lambda X: _Sinv(A, E, X)  # noqa: E731
    corrected = {
        "2.34 aa": (A(a, a) - A(a, j) @ Sinv(A(j, a)), D(a, a)),
        "2.35 aj": (A(a, j) - A(a, j) @ Sinv(A(j, j)), D(a, j)),
        "2.36 ae": (A(a, j) @ Sinv(E(j, e)), D(a, e)),
        "2.37 ea": (E(e, j) @ Sinv(A(j, a)), D(e, a)),
        "2.38 ej": (E(e, j) @ Sinv(A(j, j)), D(e, j)),
        "2.39 ee": (E(e, e) - E(e, j) @ Sinv(E(j, e)), D(e, e)),
        "2.40 ja": (A(j, a) - A(j, j) @ Sinv(A(j, a)), D(j, a)),
        "2.41 jj": (A(j, j) - A(j, j) @ Sinv(A(j, j)), D(j, j)),
        "2.42 je": (A(j, j) @ Sinv(E(j, e)), D(j, e)),
    }
    for name, (got, ref) in corrected.items():
        assert _rel(got, ref) < 1e-10, name


def test_printed_forms_with_mixed_subscripts_are_wrong(blocks):
    A, E, D = blocks
    Sinv = lambda X: _Sinv(A, E, X)  # noqa: E731
    Tinv = lambda X: np.linalg.solve(A(a, j) + E(j, j), X)  # noqa: E731  printed inverse
    printed = {
        "2.34 aa": (A(a, j) - A(a, a) @ Sinv(A(j, a)), D(a, a)),
        "2.35 aj": (A(a, j) - A(a, j) @ Tinv(A(j, j)), D(a, j)),
        "2.38 ej": (E(e, j) @ Tinv(A(j, j)), D(e, j)),
        "2.41 jj": (A(j, j) - A(j, j) @ Tinv(A(j, j)), D(j, j)),
    }
    for name, (got, ref) in printed.items():
        assert _rel(got, ref) > 1e-2, name
