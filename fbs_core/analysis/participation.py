"""Which tire modes matter: the share of every tire mode in the coupled bushing response.

The coupled response of eq. 4.1,

``v_e* = Y_ej^E (Y_jj^A + Y_jj^E)^-1 v_j``,   ``v_j = Y_ja^A F_a = sum_r v_r``,

is linear in the tire's free hub velocity ``v_j`` for a fixed interface matrix
``A = Y_jj^A + Y_jj^E``, and ``v_j`` is a modal sum (thesis eq. 2.5). So every mode
``r`` has a **direct contribution** ``c_r = Y_ej^E A^-1 v_r``: the bushing response to
that mode's share of the free hub velocity, passed through the coupled interface of
all modes. The contributions add up to the total exactly (``sum_r c_r = v_e*``). Over a
band their **share** ``s_r = sum_band Re(c_r conj(v_e*)) / sum_band |v_e*|^2`` adds up
to 1 (a contribution in anti-phase with the total counts negative), and their
**level** ``sqrt(sum_band |c_r|^2 / sum_band |v_e*|^2)`` says how large each is.

A mode also enters through the tire's hub mobility inside the inverse
(``Y_jj^A = sum_r Y_r``), which the direct contributions hold fixed. The
**leave-one-out** error captures both paths: the response without mode ``r``,
``Y_ej^E (A - Y_r)^-1 (v_j - v_r)`` (the prediction of a model that lacks that mode,
exactly: tested against a direct solve with the mode removed), compared with the full
response by eq. 5.1 over the band (and, as the truncation study judges, the largest
error over the floating band's centres). Its first-order part, the error of
``v_e* - c_r``, is the direct path alone (``loo_direct``); where the two differ the
mode matters through the mobility.

A "mode" here is a stored (tracked) mode pair of the tire model (both members of a
conjugate pair, or a pair of real poles of the tread's first-order slip states), the
unit the truncation keeps or drops (thesis section 5.1). Derivation and measured
tables: docs/modes.md.

Not every pair is a vibration. A pair of real poles is a first-order state of the tread's
slip law (docs/tire-model.md, "Slip in the contact"): a pair of poles at 0 is the whole
tire **sliding** on its slip dampers (a rigid translation in x and in y that strains no
spring, ``K x = 0``; its term is the frequency-independent hub mobility of the dampers,
``v / C_kappa`` and ``v / C_alpha``), a pair of negative real poles the tread's
**relaxation** (``lambda = -v / sigma``, time constants ``sigma / v``). They have no
eigenfrequency and no period, and they are part of the synthesis at every ``N``: their
measures are real (without the sliding pair the tire cannot slide on the road), but they
are no candidates of a vibration-mode ranking (:meth:`Participation.ranking` with
``vibration=True``, :attr:`Participation.kind`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import BoolArray, ComplexArray, FloatArray, IntArray
from ..errors import DOFError, FBSError
from ..frf import check_grid
from ..harmonics import Harmonic
from ..studies import _models
from ..studies.metric import floating_band_error
from ..tire.terms import ModeTerms, mode_terms
from ..vocabulary import readonly as _ro

__all__ = [
    "KINDS",
    "Participation",
    "pair_kinds",
    "mode_participation",
    "participation_from_terms",
    "coupled_mode_arrays",
    "RANKINGS",
]

#: Measures a ranking can be sorted by (:meth:`Participation.ranking`).
RANKINGS = ("loo", "share", "level", "loo_direct", "loo_floating")
#: What a stored pair is (:attr:`Participation.kind`): an oscillation (a conjugate pair),
#: the tread sliding (two real poles at 0) or its relaxation (two negative real poles).
KINDS = {
    "vibration": "vibration mode (a conjugate pair of poles)",
    "sliding": "tread sliding: the whole tire slides on its slip dampers (two real poles "
    "at 0, x and y; no deformation, a constant hub mobility v / C)",
    "relaxation": "tread relaxation (two real poles -v / sigma: the slip law's first-order "
    "lag, no oscillation)",
}
#: A real pole slower than this (rad/s; a time constant above ~12 days) is a zero pole.
ZERO_RATE = 1e-6


def pair_kinds(poles: ArrayLike) -> tuple[BoolArray, BoolArray]:
    """Which stored pairs are first-order and which of those are the sliding states.

    Parameters
    ----------
    poles : array_like, shape (n_s, n_m)
        The modal model's poles at its operating points, pairs ``[2 m, 2 m + 1]``.

    Returns
    -------
    first_order, sliding : ndarray of bool, shape (n_m // 2,)
        ``first_order``: both members real at every operating point; ``sliding``: and
        both zero (slower than :data:`ZERO_RATE`) at every operating point.
    """
    lam = np.asarray(poles, complex)
    a, b = lam[:, 0::2], lam[:, 1::2]
    first: BoolArray = np.all((a.imag == 0) & (b.imag == 0), axis=0)
    zero = np.all((np.abs(a) < ZERO_RATE) & (np.abs(b) < ZERO_RATE), axis=0)
    sliding: BoolArray = first & zero
    return first, sliding


def coupled_mode_arrays(
    terms: ModeTerms, YjjE: ComplexArray, dirs: Sequence[str]
) -> tuple[ComplexArray, ComplexArray, ComplexArray, ComplexArray]:
    """Per-pair hub mobility and free velocity in the coupled directions, and the totals.

    Parameters
    ----------
    terms : ModeTerms
        With the hub receptance and one patch response (42 columns).
    YjjE : ndarray, shape (n_f, n_c, n_c)
        Chassis mobility at the coupled interface DOFs.
    dirs : sequence of str
        The coupled directions (``x`` ... ``rz``).

    Returns
    -------
    Yp : ndarray, shape (n_p, n_f, n_c, n_c)
        Tire hub mobility term of every pair.
    vp : ndarray, shape (n_p, n_f, n_c)
        Free hub velocity term of every pair.
    A : ndarray, shape (n_f, n_c, n_c)
        The interface matrix ``Y_jj^A + Y_jj^E`` with all modes.
    v : ndarray, shape (n_f, n_c)
        The free hub velocity of all modes.
    """
    from ..dofs import DIRECTIONS

    if terms.cols.size != 42:
        raise FBSError("mode terms need the hub receptance and one patch response (42 columns)")
    idx = np.array([DIRECTIONS.index(d) for d in dirs])
    s = 2j * np.pi * terms.freq
    n_p, n_f = terms.dynamic.shape[:2]
    # one pass over the (n_p, n_f, 36) terms each (they are large): mobility = j omega H
    Y = np.multiply(terms.dynamic[:, :, :36], s[None, :, None]).reshape(n_p, n_f, 6, 6)
    vp = np.multiply(terms.dynamic[:, :, 36:], s[None, :, None])
    if idx.size == 6:
        Yp = Y
    else:
        Yp = Y[:, :, idx[:, None], idx[None, :]]
        vp = vp[:, :, idx]
    return Yp, vp, Yp.sum(axis=0) + YjjE, vp.sum(axis=0)


@dataclass(frozen=True, eq=False)
class Participation:
    """The share of every tire mode in the coupled bushing response over a band.

    Attributes
    ----------
    harmonic : int
        Case 1..7.
    coupling : tuple of str
        Coupled hub directions.
    band : tuple of float
        Lowest and highest line of the band in Hz.
    freq : ndarray, shape (n_f,)
        Lines of the band (Hz); every line at its own speed ``speeds``.
    speeds : ndarray, shape (n_f,)
    dofs : tuple of str, length n_e
        Response DOFs (``bushing:x`` ...).
    modes : ndarray of int, shape (n_p,)
        Stored pair index of every mode (``2 m`` and ``2 m + 1`` are its members).
    first_order : ndarray of bool, shape (n_p,)
        A pair of real poles (tread slip state): no eigenfrequency.
    mode_freq : ndarray, shape (n_p,)
        The mode's eigenfrequency (Hz) where the harmonic line comes closest to it in the
        band (``mode_speed`` km/h there): where the case excites it.
    mode_speed : ndarray, shape (n_p,)
    total : ndarray, shape (n_f, n_e)
        Coupled response with all modes (eq. 4.1).
    contributions : ndarray, shape (n_p, n_f, n_e)
        Direct contribution of every mode; ``contributions.sum(0) == total``.
    share, level : ndarray, shape (n_p, n_e)
        Band share (sums to 1 over modes) and relative RMS level of the contributions.
    loo : ndarray, shape (n_p, n_e)
        Leave-one-out error: eq. 5.1 over the band between the response without the mode
        and the total (0.2 = 20 %).
    loo_direct : ndarray, shape (n_p, n_e)
        The same for ``total - contribution`` (direct path only).
    loo_floating : ndarray, shape (n_p, n_e)
        Leave-one-out error as the truncation study judges it: the largest eq. 5.1 error
        over the floating band's centres (``width``, 1 Hz steps) in the band.
    loo_response : ndarray, shape (n_p, n_f, n_e)
        The response without each mode (exact, both paths).
    width : float
        Floating band width in Hz (eq. 5.1; the step is 1 Hz).
    sliding : ndarray of bool, shape (n_p,)
        The first-order pairs whose poles are 0: the tread sliding (:data:`KINDS`).
    """

    harmonic: int
    coupling: tuple[str, ...]
    band: tuple[float, float]
    freq: FloatArray
    speeds: FloatArray
    dofs: tuple[str, ...]
    modes: IntArray
    first_order: Any
    mode_freq: FloatArray
    mode_speed: FloatArray
    total: ComplexArray
    contributions: ComplexArray
    share: FloatArray
    level: FloatArray
    loo: FloatArray
    loo_direct: FloatArray
    loo_floating: FloatArray
    loo_response: ComplexArray
    width: float
    sliding: Any = None

    def __post_init__(self) -> None:
        if self.sliding is None:
            object.__setattr__(self, "sliding", _ro(np.zeros(len(self.modes), bool), bool))

    @property
    def kind(self) -> tuple[str, ...]:
        """What every pair is: ``"vibration"``, ``"sliding"`` or ``"relaxation"``
        (:data:`KINDS`)."""
        return tuple(
            "sliding" if sl else ("relaxation" if fo else "vibration")
            for fo, sl in zip(self.first_order, self.sliding, strict=True)
        )

    def _dof(self, dof: str | None) -> int | None:
        if dof is None:
            return None
        if dof not in self.dofs:
            raise DOFError(f"unknown response DOF {dof!r}; available: {', '.join(self.dofs)}")
        return self.dofs.index(dof)

    def measure(self, by: str = "loo", dof: str | None = None) -> FloatArray:
        """One measure per mode, shape (n_p,): ``by`` of DOF ``dof`` (None: the largest
        over the DOFs, as thesis table 5.1 judges; for ``share`` the largest magnitude).

        Raises
        ------
        FBSError
            For an unknown measure.
        DOFError
            For an unknown DOF.
        """
        if by not in RANKINGS:
            raise FBSError(f"unknown ranking {by!r}; allowed: {', '.join(RANKINGS)}")
        a = np.asarray(getattr(self, by), float)
        if by == "share":
            a = np.abs(a)
        i = self._dof(dof)
        out: FloatArray = a.max(axis=1) if i is None else a[:, i]
        return out

    def ranking(self, by: str = "loo", dof: str | None = None, vibration: bool = False) -> IntArray:
        """Positions (into :attr:`modes`) from the mode that matters most, shape (n_p,);
        ``vibration=True``: of the vibration modes only (the first-order slip states, no
        oscillation, left out: :attr:`first_order`)."""
        m = self.measure(by, dof)
        order: IntArray = np.argsort(-m, kind="stable")
        if vibration:
            order = order[~np.asarray(self.first_order, bool)[order]]
        return order

    def table(self, dof: str | None = None, by: str = "loo", top: int = 15) -> str:
        """Plain-text ranking: mode, eigenfrequency and speed where excited, share, level,
        leave-one-out error (both paths) and direct path, for DOF ``dof``."""
        i = self._dof(dof)
        head = (
            f"harmonic {self.harmonic}, {self.dofs[i] if i is not None else 'max over DOFs'}, "
            f"{self.band[0]:g}-{self.band[1]:g} Hz, ranked by {by}\n"
            f"{'rank':>4} {'mode':>5} {'f (Hz)':>8} {'at km/h':>8} {'share %':>8} "
            f"{'level %':>8} {'loo %':>8} {'direct %':>8}"
        )
        rows = []
        for rank, p in enumerate(self.ranking(by, dof)[:top], 1):
            if i is None:  # largest over the DOFs (the share with its sign)
                sh = self.share[p][np.argmax(abs(self.share[p]))]
                lv, lo, di = self.level[p].max(), self.loo[p].max(), self.loo_direct[p].max()
            else:
                sh, lv, lo, di = (x[p, i] for x in (self.share, self.level, self.loo,
                                                     self.loo_direct))  # fmt: skip
            f = (
                self.kind[p].replace("relaxation", "relax")
                if self.first_order[p]
                else f"{self.mode_freq[p]:8.1f}"
            )
            rows.append(
                f"{rank:4d} {int(self.modes[p]):5d} {f:>8} {self.mode_speed[p]:8.1f} "
                f"{100 * sh:8.1f} {100 * lv:8.1f} {100 * lo:8.1f} {100 * di:8.1f}"
            )
        return "\n".join([head, *rows])

    def export_mapping(self) -> dict[str, Any]:
        """The per-mode measures as arrays with axes (:func:`fbs_core.io.export_result`)."""
        return {
            "share": (("mode", "dof"), self.share),
            "level": (("mode", "dof"), self.level),
            "loo_error": (("mode", "dof"), self.loo),
            "loo_direct_error": (("mode", "dof"), self.loo_direct),
            "loo_floating_error": (("mode", "dof"), self.loo_floating),
            "mode_freq": (("mode",), self.mode_freq),
            "mode_speed": (("mode",), self.mode_speed),
            "coords": {"mode": self.modes, "dof": list(self.dofs)},
            "metadata": {
                "harmonic": self.harmonic,
                "coupling": ",".join(self.coupling),
                "band_hz": f"{self.band[0]:g}-{self.band[1]:g}",
                "band_width_hz": self.width,
            },
        }


def _band_lines(h: Harmonic, band: tuple[float, float] | None, df: float) -> FloatArray:
    f = h.frequencies(df)
    if band is None:
        return f
    lo, hi = (float(b) for b in band)
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise FBSError(f"band must be (low, high) in Hz with low < high, got {band!r}")
    sel = f[(f >= lo - 1e-9) & (f <= hi + 1e-9)]
    if sel.size < 3:
        raise FBSError(
            f"band {lo:g}-{hi:g} Hz holds {sel.size} lines of {h.name} "
            f"({h.freq_range[0]:g}-{h.freq_range[1]:g} Hz); at least 3 are needed"
        )
    return check_grid(sel)


def mode_participation(
    harmonic: int | Harmonic,
    band: tuple[float, float] | None = None,
    *,
    df: float = 0.5,
    width: float = 12.0,
    coupling: str | Sequence[str] = "6dof",
    tire: Any = None,
    chassis: Any = None,
) -> Participation:
    """Share of every tire mode in the coupled bushing response (all six DOFs at once).

    Parameters
    ----------
    harmonic : int or Harmonic
        Excitation case 1..7; the lines run along its speed line ``v = 3.6 f lambda``.
    band : (float, float), optional
        Band in Hz (default the harmonic's whole band).
    df : float
        Line spacing in Hz (the harmonic's grid, as the truncation study).
    width : float
        Floating band of the leave-one-out error (eq. 5.1), Hz; 1 Hz steps.
    coupling : {"6dof", "5dof"} or sequence of directions
    tire, chassis : optional
        Default the reference models (the tire must be a :class:`~fbs_core.tire.TireModel`).

    Returns
    -------
    Participation

    Raises
    ------
    FBSError
        For a bad band or coupling.
    HarmonicError
        For an unknown case.

    Examples
    --------
    >>> p = mode_participation(1)                        # doctest: +SKIP
    >>> print(p.table("bushing:z", top=3))               # doctest: +SKIP
    """
    h = _models.resolve_harmonic(harmonic)
    tire = _models.resolve_tire(tire)
    dirs = _models.coupled_directions(coupling)
    f = _band_lines(h, band, df)
    speeds = np.asarray(h.speed_at(f), float)
    YjjE, YejE, resp = _models.chassis_arrays(chassis, f, dirs)
    terms = mode_terms(tire, f, speeds, tire._harmonic_index(h))
    first, sliding = pair_kinds(tire.poles)
    return participation_from_terms(
        h.k, terms, YjjE, YejE, resp, dirs, first, width, sliding=sliding
    )


def participation_from_terms(
    harmonic: int,
    terms: ModeTerms,
    YjjE: ComplexArray,
    YejE: ComplexArray,
    dofs: Sequence[str],
    dirs: Sequence[str],
    first_order: Any,
    width: float = 12.0,
    *,
    sliding: Any = None,
) -> Participation:
    """:func:`mode_participation` from per-mode terms and chassis arrays (the kernel).

    Parameters
    ----------
    harmonic : int
        Case number (a label).
    terms : ModeTerms
        Per-pair terms on the band's lines (hub receptance and the case's patch response).
    YjjE, YejE : ndarray, shapes (n_f, n_c, n_c), (n_f, n_e, n_c)
        Chassis mobilities at the coupled interface and to the responses.
    dofs, dirs : sequence of str
        Response labels and coupled directions.
    first_order : ndarray of bool, shape (n_p,)
        Pairs of real poles.
    width : float
        Floating band of ``loo_floating`` in Hz.
    sliding : ndarray of bool, shape (n_p,), optional
        Pairs of zero poles (:func:`pair_kinds`); default none.

    Returns
    -------
    Participation
    """
    f, speeds = terms.freq, terms.speeds
    Yp, vp, A, v = coupled_mode_arrays(terms, YjjE, dirs)
    # direct contributions: c_r = Y_ej A^-1 v_r  (the interface of all modes held fixed)
    W = np.linalg.solve(np.swapaxes(A, -1, -2), np.swapaxes(YejE, -1, -2))  # (n_f, n_c, n_e)
    W = np.swapaxes(W, -1, -2)  # Y_ej A^-1, (n_f, n_e, n_c)
    contrib = np.einsum("fec,pfc->pfe", W, vp)  # W (n_f, n_e, n_c), vp (n_p, n_f, n_c)
    total = np.einsum("fec,fc->fe", W, v)
    # leave one out: the response of a model without mode r, both paths
    g = np.linalg.solve(A[None] - Yp, (v[None] - vp)[..., None])[..., 0]  # (n_p, n_f, n_c)
    loo_resp = np.einsum("fec,pfc->pfe", YejE, g)
    # eq. 5.1 over the whole band, and the largest over the floating band's centres
    centre = [0.5 * (f[0] + f[-1])]
    span = f[-1] - f[0] + 1.0
    _, e_loo = floating_band_error(f, total, loo_resp, span, centres=centre)  # (n_p, 1, n_e)
    _, e_dir = floating_band_error(f, total, total[None] - contrib, span, centres=centre)
    _, e_flt = floating_band_error(f, total, loo_resp, width, 1.0)  # (n_p, n_c, n_e)
    den = (np.abs(total) ** 2).sum(axis=0)  # (n_e,)
    den = np.where(den > 0, den, 1.0)
    share = np.real(contrib * np.conj(total)[None]).sum(axis=1) / den
    level = np.sqrt((np.abs(contrib) ** 2).sum(axis=1) / den)
    # where the line comes closest to every mode: its eigenfrequency and speed there
    near = np.argmin(np.abs(terms.frequency - f[None, :]), axis=1)
    pairs = np.arange(terms.n_pairs)
    return Participation(
        harmonic=int(harmonic),
        coupling=tuple(dirs),
        band=(float(f[0]), float(f[-1])),
        freq=_ro(f),
        speeds=_ro(speeds),
        dofs=tuple(dofs),
        modes=_ro(pairs, int),
        first_order=_ro(first_order, bool),
        mode_freq=_ro(terms.frequency[pairs, near]),
        mode_speed=_ro(speeds[near]),
        total=_ro(total),
        contributions=_ro(contrib),
        share=_ro(share),
        level=_ro(level),
        loo=_ro(e_loo[:, 0]),
        loo_direct=_ro(e_dir[:, 0]),
        loo_floating=_ro(e_flt.max(axis=1)),
        loo_response=_ro(loo_resp),
        width=float(width),
        sliding=_ro(np.zeros(terms.n_pairs, bool) if sliding is None else sliding, bool),
    )
