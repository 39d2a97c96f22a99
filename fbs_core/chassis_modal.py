"""The chassis in modal form: its own lowest modes plus the residual of the others.

The reference chassis is an FE model whose FRFs are an exact sum over all its complex
modes (hysteretic damping, :mod:`fbs_core.chassis`):
``H(omega) = sum_r V_r W_r / (lambda_r - omega^2)``, ``lambda_r = omega_r^2 (1 + j eta_r)``.
A car maker who delivers the vehicle side as a modal model keeps only its lowest ``N``
modes; the thesis suggests running its truncation study "in a similar way with the
vehicle data" (section 7). Below their eigenfrequencies the modes left out still add
their static flexibility, ``V_r W_r / lambda_r`` (exact at ``omega = 0``), the upper
residual flexibility of the chassis (the analogue of the tire's, docs/tire-model.md):

    H_N(omega) = sum_(r <= N) V_r W_r / (lambda_r - omega^2)  [+ sum_(r > N) V_r W_r / lambda_r]

and the mobility is ``j omega H_N`` (thesis table 2.1). :class:`ModalChassis` is that
delivery, used wherever a chassis model is (``bushing_response(chassis=...)``, the
studies); :func:`modal_receptances` computes every ``N`` at once (block sums followed
by a cumulative sum). The truncation study itself: :mod:`fbs_core.studies.chassis`.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._typing import ComplexArray, FloatArray
from .chassis import BUSHING, SPINDLE, ChassisModel, _modal, reference_chassis
from .dofs import index_of
from .errors import FBSError, ModeCountError
from .frf import FRF, check_grid
from .frf_model import modal_factors, modal_sum, receptance_frf

__all__ = ["ModalChassis", "modal_receptances"]


def modal_receptances(
    lam: ComplexArray,
    V_out: ComplexArray,
    W_in: ComplexArray,
    freq: ArrayLike,
    n_modes: Sequence[int] | np.ndarray,
    residual: bool = False,
) -> ComplexArray:
    """Receptances of the first ``N`` modes for every ``N`` (the array kernel).

    Parameters
    ----------
    lam : ndarray, shape (n_m,)
        ``lambda_r`` (rad^2/s^2), in the order of truncation (lowest first).
    V_out : ndarray, shape (n_out, n_m)
        Mode shapes at the outputs.
    W_in : ndarray, shape (n_m, n_in)
        Left factors at the inputs (``V^-1 M^-1``), so that
        ``H = V diag(1 / (lambda - omega^2)) W`` with all modes.
    freq : array_like, shape (n_f,)
        Frequencies in Hz.
    n_modes : sequence of int, shape (n_N,)
        Increasing counts, 1 .. n_m.
    residual : bool
        Add the static part ``V_r W_r / lambda_r`` of every mode left out.

    Returns
    -------
    ndarray, shape (n_N, n_f, n_out, n_in)

    Raises
    ------
    ModeCountError
        For counts that are not increasing integers in 1 .. n_m.
    """
    f = np.asarray(freq, float)
    n = np.asarray(n_modes)
    n_m = lam.size
    if (
        n.ndim != 1
        or n.size == 0
        or not np.issubdtype(n.dtype, np.integer)
        or np.any(np.diff(n) <= 0)
        or n[0] < 1
        or n[-1] > n_m
    ):
        raise ModeCountError(
            f"chassis mode counts must be increasing integers in 1..{n_m}, got "
            f"{np.asarray(n_modes).tolist()}"
        )
    edges = np.r_[0, n]
    out = np.zeros((n.size, f.size, V_out.shape[0], W_in.shape[1]), complex)
    for b, (a, e) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        out[b] = modal_sum(modal_factors(lam[a:e], f), V_out[:, a:e], W_in[a:e])
    out = np.cumsum(out, axis=0)
    if residual:
        static = (V_out / lam[None, :])[None] * W_in.T[:, None, :]  # (n_in, n_out, n_m)
        tail = np.cumsum(static[..., ::-1], axis=-1)[..., ::-1]  # sum over r >= k
        for b, k in enumerate(n):
            if k < n_m:
                out[b] += tail[..., k].T[None]
    return out


class ModalChassis:
    """A chassis FE model delivered as its lowest ``n_modes`` modes (plus residual).

    Parameters
    ----------
    chassis : ChassisModel, optional
        Default the reference chassis.
    n_modes : int, optional
        Modes kept, lowest eigenfrequency first; default all (then exact).
    residual : bool
        Keyword only: add the static flexibility of the modes left out (default True).

    Raises
    ------
    ModeCountError
        For a count outside 1 .. the chassis' modes.
    FBSError
        For a chassis without an FE model.

    Examples
    --------
    >>> ch = ModalChassis(n_modes=20)
    >>> ch.mobility([14.0, 37.0]).shape
    (2, 12, 6)
    """

    def __init__(
        self,
        chassis: ChassisModel | None = None,
        n_modes: int | None = None,
        *,
        residual: bool = True,
    ) -> None:
        chassis = reference_chassis() if chassis is None else chassis
        if not isinstance(chassis, ChassisModel):
            raise FBSError(
                f"a modal form needs the chassis' FE model (a ChassisModel), got "
                f"{type(chassis).__name__}"
            )
        total = chassis.eigenvalues().size
        n = total if n_modes is None else n_modes
        if isinstance(n, bool) or int(n) != n or not 1 <= n <= total:
            raise ModeCountError(f"n_modes must be an integer 1..{total} or None, got {n_modes!r}")
        self._chassis = chassis
        self.n_modes = int(n)
        self.n_modes_total = int(total)
        self.residual = bool(residual)

    @property
    def params(self) -> Any:
        """The FE model's parameters (as :attr:`ChassisModel.params`)."""
        return self._chassis.params

    def __repr__(self) -> str:
        r = " + residual" if self.residual and self.n_modes < self.n_modes_total else ""
        return f"ModalChassis({self.n_modes} of {self.n_modes_total} modes{r})"

    def eigenfrequencies(self) -> FloatArray:
        """Natural frequencies of the kept modes in Hz, ascending."""
        f: FloatArray = self._chassis.eigenfrequencies()[: self.n_modes]
        return f

    def mobility(
        self,
        freq: ArrayLike,
        outputs: Iterable[str] | None = None,
        inputs: Iterable[str] | None = None,
        quantity: str = "mobility",
    ) -> FRF:
        """FRFs of the modal form, same signature as :meth:`ChassisModel.mobility`.

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz.
        outputs, inputs : sequence of str, optional
            Default outputs ``spindle:*`` then ``bushing:*``; inputs ``spindle:*``.
        quantity : {"receptance", "mobility", "accelerance"}
        """
        f = check_grid(freq)
        outs = SPINDLE + BUSHING if outputs is None else tuple(outputs)
        ins = SPINDLE if inputs is None else tuple(inputs)
        return receptance_frf(f, outs, ins, quantity, lambda: self._receptance(f, outs, ins))

    def _receptance(
        self, f: FloatArray, outputs: tuple[str, ...], inputs: tuple[str, ...]
    ) -> ComplexArray:
        """Receptance ``(n_freq, n_out, n_in)`` of the kept modes (plus residual)."""
        s, lam, V, W = _modal(self._chassis.params)
        oi = index_of(s.dofs, outputs, "chassis output DOF")
        ii = index_of(s.dofs, inputs, "chassis input DOF")
        by_count = modal_receptances(lam, V[oi], W[:, ii], f, [self.n_modes], self.residual)
        H: ComplexArray = by_count[0]
        return H
