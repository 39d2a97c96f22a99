"""Array kernels of frequency based substructuring (no labels, no I/O).

All arrays are frequency first: an FRF matrix is ``(n_freq, n_out, n_in)``; any
number of leading batch axes is allowed where noted, so that the same kernel
runs over frequencies, retained-mode counts or Monte-Carlo rounds at once.

Notation follows the thesis (Rosholm & Westers 2018): subsystem A (tire) with
internal DOFs a, subsystem E (chassis) with internal DOFs e, interface j.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NoReturn, TypedDict, Unpack

import numpy as np

from ._typing import AnyArray, BoolArray, ComplexArray, FloatArray, IndexLike
from .errors import FBSError, SingularInterfaceError

__all__ = [
    "solve_interface",
    "condition_number",
    "receptance_coupling",
    "impedance_coupling",
    "lm_fbs",
    "lm_fbs_pairs",
    "generalized_receptance",
    "couple_response_kernel",
]

#: Condition number above which an interface matrix counts as singular.
MAX_COND = 1e13


class SolveOptions(TypedDict, total=False):
    """Keyword options of :func:`solve_interface` that coupling functions pass through."""

    rcond: float | None
    max_cond: float | None
    freq: FloatArray | None


def condition_number(A: AnyArray) -> FloatArray:
    """2-norm condition number of every matrix in a stack ``(..., n, n)``.

    ``inf`` where a matrix is exactly singular.
    """
    s = np.linalg.svd(A, compute_uv=False)
    with np.errstate(divide="ignore"):
        return np.where(s[..., -1] > 0, s[..., 0] / s[..., -1], np.inf)


def _tsvd_solve(A: AnyArray, B: AnyArray, rcond: float) -> ComplexArray:
    """Truncated-SVD solution of ``A X = B`` on a stack: singular values below
    ``rcond * s_max`` are discarded (a regularised pseudo-inverse)."""
    U, s, Vh = np.linalg.svd(A)
    keep = s > rcond * s[..., :1]
    s_inv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    UhB = np.conj(np.swapaxes(U, -1, -2)) @ B
    X: ComplexArray = np.conj(np.swapaxes(Vh, -1, -2)) @ (s_inv[..., :, None] * UhB)
    return X


def solve_interface(
    A: ComplexArray,
    B: ComplexArray,
    rcond: float | None = None,
    max_cond: float | None = None,
    freq: FloatArray | None = None,
) -> ComplexArray:
    """Solve ``A X = B`` for a stack of interface matrices ``A (..., n, n)``.

    Parameters
    ----------
    A : ndarray, shape (..., n, n)
        The matrices to be "inverted" (e.g. ``Y_jj^A + Y_jj^E``, eq. 2.44).
    B : ndarray, shape (..., n, m)
        Right-hand sides.
    rcond : float, optional
        If given, use a truncated SVD: singular values below ``rcond * s_max``
        are dropped (regularisation of an ill-conditioned interface).
    max_cond : float, optional
        If given (and ``rcond`` is not), raise when any matrix has a larger
        condition number.
    freq : ndarray, optional
        Frequencies of the last batch axis, only used in error messages.

    Raises
    ------
    SingularInterfaceError
        Naming the first offending frequency line.
    """
    if rcond is not None:
        r = float(rcond) if isinstance(rcond, int | float | np.number) else None
        if isinstance(rcond, bool) or r is None or not 0.0 <= r < 1.0:
            # rcond >= 1 (or NaN) would drop every singular value: the "coupled" result
            # would silently be the uncoupled one
            raise FBSError(
                f"rcond must be a number in [0, 1) (relative cut-off of the singular values, "
                f"e.g. 1e-6), got {rcond!r}"
            )
        return _tsvd_solve(A, B, r)
    if max_cond is not None:
        c = condition_number(A)
        bad = ~(c <= max_cond)
        if np.any(bad):
            _raise_singular(bad, c, freq, max_cond)
    try:
        return np.linalg.solve(A, B)
    except np.linalg.LinAlgError:
        c = condition_number(A)
        _raise_singular(~np.isfinite(c) | (c > 1 / np.finfo(float).eps), c, freq, None)
        raise  # pragma: no cover - solve failed although no matrix looks singular


def _raise_singular(
    bad: BoolArray, c: FloatArray, freq: FloatArray | None, max_cond: float | None
) -> NoReturn:
    idx = np.argwhere(bad)[0]
    line = int(idx[-1]) if idx.size else 0
    where = f"{freq[line]:g} Hz" if freq is not None and bad.ndim >= 1 else f"line {line}"
    limit = f" (limit {max_cond:g})" if max_cond is not None else ""
    raise SingularInterfaceError(
        f"interface matrix is singular or ill-conditioned at {where}: condition number "
        f"{c[tuple(idx)]:.3g}{limit} at {int(bad.sum())} of {bad.size} lines. Check that the "
        "interface DOFs are independent and present in both subsystems, or pass rcond=... "
        "for a truncated-SVD regularisation"
    )


def receptance_coupling(
    YA: ComplexArray,
    YB: ComplexArray,
    a_o: IndexLike,
    a_i: IndexLike,
    ja_o: IndexLike,
    ja_i: IndexLike,
    b_o: IndexLike,
    b_i: IndexLike,
    jb_o: IndexLike,
    jb_i: IndexLike,
    **solve_kw: Unpack[SolveOptions],
) -> ComplexArray:
    """Receptance coupling of two subsystems, thesis eq. 2.44 in general form.

    No reciprocity is assumed (eq. 2.45 is not used): the right factor is built
    from the rows ``Y_ja^A, Y_jj^A, -Y_je^E``, the left from the columns
    ``Y_aj^A, Y_jj^A, -Y_ej^E``. Derivation (eqs. 2.26-2.29): the interface
    force ``g`` on E (``-g`` on A) makes the interface velocities equal,
    ``(Y_jj^A + Y_jj^E) g = Y_ja^A F_a + Y_jj^A F_j - Y_je^E F_e``, and an
    external interface force ``F_j`` is taken to act on A.

    Parameters
    ----------
    YA, YB : ndarray, shape (n_freq, n_out, n_in)
    a_o, a_i : index arrays of A's internal outputs / inputs
    ja_o, ja_i : index arrays of A's interface DOFs among its outputs / inputs
    b_o, b_i, jb_o, jb_i : the same for B

    Returns
    -------
    ndarray, shape (n_freq, n_ao + n_j + n_bo, n_ai + n_j + n_bi)
        Coupled FRF, rows ``[a, j, b]``, columns ``[a, j, b]``.
    """
    nf = YA.shape[0]
    nao, nj, nbo = len(a_o), len(ja_o), len(b_o)
    nai, nbi = len(a_i), len(b_i)

    def sub(Y: ComplexArray, r: IndexLike, c: IndexLike) -> ComplexArray:
        return Y[:, r][:, :, c]

    Y0 = np.zeros((nf, nao + nj + nbo, nai + nj + nbi), complex)
    Y0[:, : nao + nj, : nai + nj] = sub(YA, np.r_[a_o, ja_o], np.r_[a_i, ja_i])
    Y0[:, nao + nj :, nai + nj :] = sub(YB, b_o, b_i)
    left = np.concatenate([sub(YA, np.r_[a_o, ja_o], ja_i), -sub(YB, b_o, jb_i)], axis=1)
    right = np.concatenate([sub(YA, ja_o, np.r_[a_i, ja_i]), -sub(YB, jb_o, b_i)], axis=2)
    Yjj = sub(YA, ja_o, ja_i) + sub(YB, jb_o, jb_i)
    return Y0 - left @ solve_interface(Yjj, right, **solve_kw)


def impedance_coupling(
    YA: ComplexArray,
    YB: ComplexArray,
    a: IndexLike,
    ja: IndexLike,
    b: IndexLike,
    jb: IndexLike,
) -> ComplexArray:
    """Impedance coupling of two subsystems, thesis eqs. 2.18-2.19.

    ``YA`` and ``YB`` must be square over all their DOFs (outputs == inputs in
    the same order). Each is inverted to an impedance, the impedances are added
    at the interface and the assembled impedance is inverted back.

    Parameters
    ----------
    YA, YB : ndarray, shape (n_freq, n, n)
    a, ja : index arrays of A's internal and interface DOFs
    b, jb : the same for B

    Returns
    -------
    ndarray, shape (n_freq, n_a + n_j + n_b, n_a + n_j + n_b), order ``[a, j, b]``.
    """
    ZA = _inv(YA[:, np.r_[a, ja]][:, :, np.r_[a, ja]], "subsystem A's FRF matrix")
    ZB = _inv(YB[:, np.r_[jb, b]][:, :, np.r_[jb, b]], "subsystem B's FRF matrix")
    na, nj, nb = len(a), len(ja), len(b)
    n = na + nj + nb
    Z = np.zeros((YA.shape[0], n, n), complex)
    Z[:, : na + nj, : na + nj] += ZA
    Z[:, na:, na:] += ZB
    return _inv(Z, "the assembled impedance matrix")


def _inv(M: ComplexArray, what: str) -> ComplexArray:
    """Inverse of every matrix of a stack; SingularInterfaceError naming the first
    singular line instead of numpy's LinAlgError."""
    try:
        return np.linalg.inv(M)
    except np.linalg.LinAlgError:
        c = condition_number(M)
        bad = ~np.isfinite(c) | (c > 1 / np.finfo(float).eps)
        line = int(np.argmax(bad)) if bad.any() else 0
        raise SingularInterfaceError(
            f"{what} is singular at line {line} (condition number {c[line]:.3g}); impedance "
            "coupling inverts every FRF matrix, use couple_receptance for singular or "
            "rank-deficient subsystems"
        ) from None


def lm_fbs(Y: ComplexArray, B: AnyArray, **solve_kw: Unpack[SolveOptions]) -> ComplexArray:
    """LM-FBS with a general signed Boolean matrix (de Klerk, Rixen & Voormeeren 2008).

    ``Y* = Y - Y B^T (B Y B^T)^-1 B Y``, with ``Y`` the block-diagonal FRF of all
    uncoupled subsystems, ``(n_freq, n, n)``, and ``B`` of shape ``(n_c, n)``.
    """
    BY = np.einsum("cn,fnm->fcm", B, Y)  # (n_freq, n_c, n)
    YBt = np.einsum("fnm,cm->fnc", Y, B)  # (n_freq, n, n_c)
    BYBt = np.einsum("fcm,dm->fcd", BY, B)  # (n_freq, n_c, n_c)
    out: ComplexArray = Y - YBt @ solve_interface(BYBt, BY, **solve_kw)
    return out


def lm_fbs_pairs(
    Y: ComplexArray, plus: IndexLike, minus: IndexLike, **solve_kw: Unpack[SolveOptions]
) -> ComplexArray:
    """LM-FBS where every row of ``B`` has one +1 (``plus``) and one -1 (``minus``).

    Same result as :func:`lm_fbs`, with ``B Y`` formed by row differences
    instead of a matrix product.
    """
    BY = Y[:, plus, :] - Y[:, minus, :]  # (n_freq, n_c, n)
    YBt = Y[:, :, plus] - Y[:, :, minus]  # (n_freq, n, n_c)
    BYBt = BY[:, :, plus] - BY[:, :, minus]  # (n_freq, n_c, n_c)
    return Y - YBt @ solve_interface(BYBt, BY, **solve_kw)


def generalized_receptance(
    Ys: Sequence[ComplexArray],
    internal: Sequence[IndexLike],
    interfaces: Sequence[Sequence[IndexLike]],
    Mbool: AnyArray,
    **solve_kw: Unpack[SolveOptions],
) -> ComplexArray:
    """Jetmundsen's generalized receptance coupling, thesis eq. 2.46.

    Parameters
    ----------
    Ys : list of ndarray, each (n_freq, n_i, n_i)
        Square FRFs of the subsystems.
    internal : list of index arrays
        Retained DOFs alpha of each subsystem (rows/columns of ``Y*``).
    interfaces : list of list of index arrays
        ``interfaces[i][k]``: subsystem i's DOFs at interface k (gamma), or an
        empty array where subsystem i has no part in interface k.
    Mbool : ndarray, shape (n_sub, n_interfaces)
        Boolean mapping matrix with entries +1, -1, 0 (eq. 2.50).

    Returns
    -------
    ndarray, shape (n_freq, n_alpha, n_alpha)
        ``Y_aa - (M o Y_ag) [sum_i M_i^T M_i o Y_gg^i]^-1 (M o Y_ga)``. The
        transpose of eq. 2.46 is replaced by the transfer ``Y_ga`` itself, so
        that non-reciprocal subsystems are coupled correctly.
    """
    nf = Ys[0].shape[0]
    n_sub, n_if = Mbool.shape
    sizes_a = [len(x) for x in internal]
    sizes_g = [max(len(interfaces[i][k]) for i in range(n_sub)) for k in range(n_if)]
    off_a = np.r_[0, np.cumsum(sizes_a)]
    off_g = np.r_[0, np.cumsum(sizes_g)]
    Yaa = np.zeros((nf, off_a[-1], off_a[-1]), complex)
    Yag = np.zeros((nf, off_a[-1], off_g[-1]), complex)
    Yga = np.zeros((nf, off_g[-1], off_a[-1]), complex)
    S = np.zeros((nf, off_g[-1], off_g[-1]), complex)
    for i, Y in enumerate(Ys):
        ra = slice(off_a[i], off_a[i + 1])
        Yaa[:, ra, ra] = Y[:, internal[i]][:, :, internal[i]]  # eq. 2.47
        for k in range(n_if):
            if Mbool[i, k] == 0:
                continue
            gk = slice(off_g[k], off_g[k + 1])
            Yag[:, ra, gk] = Mbool[i, k] * Y[:, internal[i]][:, :, interfaces[i][k]]  # eq. 2.48
            Yga[:, gk, ra] = Mbool[i, k] * Y[:, interfaces[i][k]][:, :, internal[i]]
            for m in range(n_if):  # M_i^T M_i o Y_gg^i, eqs. 2.49, 2.57
                if Mbool[i, m] == 0:
                    continue
                gm = slice(off_g[m], off_g[m + 1])
                S[:, gk, gm] += (
                    Mbool[i, k] * Mbool[i, m] * Y[:, interfaces[i][k]][:, :, interfaces[i][m]]
                )
    return Yaa - Yag @ solve_interface(S, Yga, **solve_kw)


def couple_response_kernel(
    Yej: ComplexArray,
    YjjA: ComplexArray,
    YjjE: ComplexArray,
    vj: ComplexArray,
    **solve_kw: Unpack[SolveOptions],
) -> ComplexArray:
    """The response at E's internal DOFs, thesis eq. 4.1 (and 2.37).

    ``v_e* = Y_ej^E (Y_jj^A + Y_jj^E)^-1 (Y_ja^A F_a)``, by one batched solve
    (no explicit inverse, no Python loop over frequencies).

    Parameters
    ----------
    Yej : ndarray, shape (..., n_e, n_j)
    YjjA, YjjE : ndarray, shape (..., n_j, n_j)
    vj : ndarray, shape (..., n_j) or (..., n_j, n_load)
        Free interface velocity of A under the external load, ``Y_ja^A F_a``.

    Returns
    -------
    ndarray, shape (..., n_e) or (..., n_e, n_load)
    """
    vec = vj.ndim == YjjA.ndim - 1
    rhs = vj[..., None] if vec else vj
    g = solve_interface(YjjA + YjjE, rhs, **solve_kw)  # interface force on E
    out = Yej @ g
    return out[..., 0] if vec else out
