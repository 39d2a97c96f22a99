"""First-order propagation of the FRF noise: a cheap cross-check of the scatter band.

The scatter band (thesis section 5.2, eqs. 5.2-5.4; :mod:`.scatter`) scales every element
of the subsystem FRFs by an independent factor ``1 + e``, ``e`` uniform in ``[-p, p]``
(variance ``sigma^2 = p^2 / 3``), and recomputes the bushing response of eq. 4.1 ``R``
times. Linearised about the unpolluted response, the same question has a closed answer:
the statistical-moment method of FBS (Voormeeren, de Klerk & Rixen, "Uncertainty
quantification in experimental frequency based substructuring", Mech. Syst. Signal
Process. 24 (2010) 106-118) propagates uncorrelated FRF uncertainties through the coupling
by a first-order Taylor expansion, ``Cov(v) = J Cov(e) J^T``.

For ``v = Y_ej^E Z^-1 v_j`` with ``Z = Y_jj^A + Y_jj^E``, ``g = Z^-1 v_j`` and
``T = Y_ej^E Z^-1``, the derivatives by the relative error of each element are

- ``Y_ej^E[a, b]``:  ``dv_a = Y_ej^E[a, b] g_b``  (only the row's own DOF ``a``)
- ``v_j[b]``:        ``dv = T[:, b] v_j[b]``
- ``Y_jj^A[c, d]`` and ``Y_jj^E[c, d]``:  ``dv = -T[:, c] Y[c, d] g_d``

(``d(Z^-1) = -Z^-1 dZ Z^-1``), and the magnitude moves by ``d|v_a| = Re(conj(v_a) dv_a) /
|v_a|``. The first-order covariance of the magnitudes is ``sigma^2 sum_e (d|v_a|/de)
(d|v_b|/de)`` over the elements that carry noise (``target``: tire, chassis or both, as
:func:`~fbs_core.scatter_band`); frequency dependence of the factors does not change it
(the marginal law at a line is the same).

Where it fails is measured, not assumed (:func:`compare_with_band`, ``bench/
bench_firstorder.py``): the linearisation of ``|v|`` breaks down where the response is
small against its spread (antiresonances: ``std / |v|`` of order one, the magnitude is
then closer to a Rayleigh variable than a Gaussian one), and the neglected second-order
terms of ``Z^-1`` grow with ``p ||Z^-1|| ||Y||`` (ill-conditioned interface matrices).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray
from ..errors import DataFormatError, FBSError, SingularInterfaceError
from ..frf import check_grid
from ..harmonics import Harmonic
from ..vocabulary import DIRECTIONS
from ..vocabulary import readonly as _ro
from . import _models
from ._finite import require_finite

__all__ = [
    "FirstOrderBand",
    "compare_with_band",
    "first_order_band",
    "first_order_band_arrays",
]

#: Coverage factor of the 5-95 % band of a Gaussian variable.
Z95 = 1.6448536269514722


@dataclass(frozen=True, eq=False)
class FirstOrderBand:
    """Linearised spread of the bushing response under the FRF noise of eqs. 5.2-5.4.

    Parameters
    ----------
    freq : ndarray, shape (n_f,)
    dofs : tuple of str
    reference : ndarray, shape (n_f, n_e)
        The unpolluted complex response.
    cov : ndarray, shape (n_f, n_e, n_e)
        First-order covariance of ``|v_e|`` between the DOFs at every line.
    condition : ndarray, shape (n_f,)
        2-norm condition number of the interface matrix ``Y_jj^A + Y_jj^E``.
    noise : float
        ``p`` (0.1 = factors in [0.9, 1.1]).
    target : {"tire", "chassis", "both"}
    harmonic : int or None
    """

    freq: FloatArray
    dofs: tuple[str, ...]
    reference: ComplexArray
    cov: FloatArray
    condition: FloatArray
    noise: float
    target: str
    harmonic: int | None = None

    @property
    def std(self) -> FloatArray:
        """Standard deviation of ``|v_e|``, shape (n_f, n_e)."""
        d: FloatArray = np.sqrt(np.maximum(np.einsum("fii->fi", self.cov), 0.0))
        return d

    @property
    def relative_std(self) -> FloatArray:
        """``std / |v|`` (n_f, n_e): where it approaches 1 the linearisation of ``|v|`` fails
        (a small response against its spread: antiresonances)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            r: FloatArray = self.std / np.abs(self.reference)
        return r

    def band(self, k: float = Z95) -> tuple[FloatArray, FloatArray]:
        """``(|v| - k std, |v| + k std)``, the lower edge clipped at 0; ``k = 1.645``: the
        5-95 % band of a Gaussian magnitude, to set beside the scatter band's percentiles."""
        m = np.abs(self.reference)
        s = k * self.std
        return np.maximum(m - s, 0.0), m + s


def _jacobians(
    YjjA: ComplexArray, vj: ComplexArray, YjjE: ComplexArray, YejE: ComplexArray
) -> tuple[ComplexArray, ComplexArray, ComplexArray, ComplexArray, ComplexArray]:
    """``v`` and the derivatives of ``v`` by the relative errors of each matrix element.

    Returns ``v (f, e)``, ``dB (f, e, j)`` (of ``Y_ej^E[e, j]``, on ``v_e`` only), ``dv
    (f, e, j)`` (of ``v_j[j]``), ``dA (f, e, c, d)`` and ``dE (f, e, c, d)``.
    """
    Z = YjjA + YjjE
    g = np.linalg.solve(Z, vj[..., None])[..., 0]  # (f, j)
    # T = Y_ej Z^-1 through the transpose: Z^T T^T = Y_ej^T
    T = np.swapaxes(np.linalg.solve(np.swapaxes(Z, 1, 2), np.swapaxes(YejE, 1, 2)), 1, 2)
    v = np.einsum("fej,fj->fe", YejE, g)
    dB = YejE * g[:, None, :]
    dv = T * vj[:, None, :]
    dA = -T[:, :, :, None] * (YjjA * g[:, None, :])[:, None]
    dE = -T[:, :, :, None] * (YjjE * g[:, None, :])[:, None]
    return v, dB, dv, dA, dE


def first_order_band_arrays(
    YjjA: ArrayLike,
    vj: ArrayLike,
    YjjE: ArrayLike,
    YejE: ArrayLike,
    noise: float = 0.1,
    target: str = "both",
    *,
    freq: ArrayLike | None = None,
    dofs: Sequence[str] | None = None,
    harmonic: int | None = None,
) -> FirstOrderBand:
    """The first-order band from the subsystem arrays (shapes as
    :func:`~fbs_core.studies.scatter_band_arrays`).

    Parameters
    ----------
    YjjA : array_like, shape (n_f, n_j, n_j)
    vj : array_like, shape (n_f, n_j)
    YjjE : array_like, shape (n_f, n_j, n_j)
    YejE : array_like, shape (n_f, n_e, n_j)
    noise : float
        ``p`` in [0, 1): factors uniform in ``[1 - p, 1 + p]``.
    target : {"tire", "chassis", "both"}
        Which subsystem carries the noise (eq. 5.2, 5.3 or 5.4).
    freq : array_like, optional
        Lines in Hz (default ``0, 1, ...``).
    dofs : sequence of str, optional
        Response labels (default ``bushing:x`` ...).
    harmonic : int, optional

    Returns
    -------
    FirstOrderBand

    Raises
    ------
    DataFormatError
        For shapes that do not agree or non-finite values.
    FBSError
        For a bad noise level or target.
    SingularInterfaceError
        When the interface matrix is singular at some line.
    """
    from .band_kernel import noise_flags, target_name

    A, b, E, B = (np.asarray(x, complex) for x in (YjjA, vj, YjjE, YejE))
    if A.ndim != 3 or A.shape[1] != A.shape[2]:
        raise DataFormatError(f"YjjA must have shape (n_f, n_j, n_j), got {A.shape}")
    nf, nj = A.shape[:2]
    if b.shape != (nf, nj) or E.shape != A.shape or B.ndim != 3 or B.shape[::2] != (nf, nj):
        raise DataFormatError(
            f"shapes do not agree: YjjA {A.shape}, vj {b.shape} (want {(nf, nj)}), YjjE "
            f"{E.shape}, YejE {B.shape} (want (n_f, n_e, n_j))"
        )
    for name, x in (("YjjA", A), ("vj", b), ("YjjE", E), ("YejE", B)):
        if not np.all(np.isfinite(x)):
            raise DataFormatError(f"{name} contains non-finite values")
    if not 0.0 <= noise < 1.0:
        raise FBSError(f"noise must be in [0, 1) (0.1 = +-10 %), got {noise!r}")
    target = target_name(target)
    tire, chassis = noise_flags(target)
    ne = B.shape[1]
    f = np.arange(nf, dtype=float) if freq is None else check_grid(freq)
    if f.size != nf:
        raise DataFormatError(f"{f.size} frequencies for {nf} lines")
    labels = tuple(f"bushing:{d}" for d in DIRECTIONS)[:ne]
    labels = labels if dofs is None else tuple(dofs)
    if len(labels) != ne:
        raise DataFormatError(f"{len(labels)} response labels for {ne} response DOFs")
    try:
        v, dB, dv, dA, dE = _jacobians(A, b, E, B)
    except np.linalg.LinAlgError as e:
        raise SingularInterfaceError(
            f"the interface matrix Y_jj^A + Y_jj^E is singular at some line: {e}"
        ) from None
    u = np.conj(v) / np.abs(v)  # d|v_a| = Re(u_a dv_a)
    var = noise**2 / 3.0
    cov = np.zeros((nf, ne, ne))
    if tire:
        Rv = np.real(u[:, :, None] * dv)  # (f, e, j)
        RA = np.real(u[:, :, None, None] * dA).reshape(nf, ne, -1)
        cov += np.einsum("fak,fbk->fab", Rv, Rv) + np.einsum("fak,fbk->fab", RA, RA)
    if chassis:
        RE = np.real(u[:, :, None, None] * dE).reshape(nf, ne, -1)
        RB = np.real(u[:, :, None] * dB)  # the element (a, b) moves v_a only
        cov += np.einsum("fak,fbk->fab", RE, RE)
        idx = np.arange(ne)
        cov[:, idx, idx] += np.einsum("fak,fak->fa", RB, RB)
    cov *= var
    require_finite(
        cov,
        f,
        "the first-order band",
        "a zero response or a singular interface matrix Y_jj^A + Y_jj^E",
    )
    return FirstOrderBand(
        freq=_ro(f),
        dofs=labels,
        reference=_ro(v),
        cov=_ro(cov),
        condition=_ro(np.linalg.cond(A + E)),
        noise=float(noise),
        target=target,
        harmonic=harmonic,
    )


def first_order_band(
    harmonic: int | Harmonic,
    noise: float = 0.1,
    target: str = "both",
    *,
    n_modes: int | None = None,
    freq: ArrayLike | None = None,
    df: float = 0.5,
    tire: Any = None,
    chassis: Any = None,
    coupling: str | Sequence[str] = "6dof",
) -> FirstOrderBand:
    """First-order band of the bushing response for one harmonic (the settings of
    :func:`fbs_core.scatter_band`, from the same subsystem arrays).

    Parameters
    ----------
    harmonic : int or Harmonic
    noise, target
        As :func:`first_order_band_arrays`.
    n_modes : int, optional
        Retained tire modes (default all).
    freq : array_like, optional
        Lines in Hz (default ``harmonic.frequencies(df)``).
    df : float
        Line spacing of the default grid.
    tire, chassis : optional
        Models (default the reference ones; ``chassis`` may be an FRF on ``freq``).
    coupling : {"6dof", "5dof"} or sequence of directions

    Returns
    -------
    FirstOrderBand

    Examples
    --------
    >>> fo = first_order_band(4, noise=0.05)          # doctest: +SKIP
    >>> lo, hi = fo.band()                            # doctest: +SKIP
    """
    from .scatter import _subsystem_arrays

    h = _models.resolve_harmonic(harmonic)
    tire = _models.resolve_tire(tire)
    dirs = _models.coupled_directions(coupling)
    f = h.frequencies(df) if freq is None else check_grid(freq)
    n_total = _models.total_modes(tire)
    n = n_total if n_modes is None else int(n_modes)
    if not 1 <= n <= n_total:
        raise FBSError(f"n_modes must be in 1..{n_total} (the tire's modes), got {n_modes!r}")
    YjjA, vj, YjjE, YejE, resp = _subsystem_arrays(tire, chassis, f, h, n, dirs)
    return first_order_band_arrays(
        YjjA, vj, YjjE, YejE, noise, target, freq=f, dofs=resp, harmonic=h.k
    )


def compare_with_band(
    first: FirstOrderBand, band: Any, max_rounds: int = 4000
) -> dict[str, FloatArray]:
    """The first-order standard deviation beside the Monte-Carlo one of a scatter band.

    Parameters
    ----------
    first : FirstOrderBand
    band : ScatterBand
        Of the same lines, noise level and target, with frequency-independent or dependent
        factors (the per-line law is the same).
    max_rounds : int
        Rounds regenerated for the Monte-Carlo moments (the first ``min(R, max_rounds)``;
        :meth:`~fbs_core.ScatterBand.rounds_response`).

    Returns
    -------
    dict of str to ndarray, each shape (n_f, n_e)
        ``mc_std`` and ``mc_mean`` of ``|v|`` over the rounds, ``ratio`` = first-order std /
        Monte-Carlo std, ``mc_relative_std`` = ``mc_std / |v|``, and ``condition`` (n_f,)
        of the interface matrix.

    Raises
    ------
    FBSError
        When the band's lines, noise level or target are not the first-order band's.
    """
    f = np.asarray(band.freq, float)
    if f.shape != first.freq.shape or not np.allclose(f, first.freq, rtol=1e-12, atol=0):
        raise FBSError("the scatter band's lines are not the first-order band's")
    if float(band.noise) != first.noise or band.target != first.target:
        raise FBSError(
            f"the scatter band (p = {band.noise:g}, {band.target}) and the first-order band "
            f"(p = {first.noise:g}, {first.target}) are for different noise"
        )
    r = int(min(band.rounds, max_rounds))
    mag = np.abs(band.rounds_response(np.arange(r)))  # (r, n_f, n_e)
    mc_std = mag.std(axis=0, ddof=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return {
            "mc_std": mc_std,
            "mc_mean": mag.mean(axis=0),
            "ratio": first.std / mc_std,
            "mc_relative_std": mc_std / np.abs(first.reference),
            "condition": first.condition,
        }
