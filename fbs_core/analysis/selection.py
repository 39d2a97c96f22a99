"""Selected tire modes instead of the lowest ``N``: how many does a case need?

Thesis table 5.1 keeps the ``N / 2`` pairs of lowest eigenfrequency and asks from which
``N`` the eq. 5.1 error of the coupled bushing response stays below a threshold at every
floating-band centre up to ``f_max`` (:func:`fbs_core.suggest_modes`). If a supplier
delivered the modes that matter for the case instead, how many would it take?

:func:`select_modes` orders the stored mode pairs by a measure of
:mod:`.participation` over the lines that the criterion reads (up to ``f_max`` plus half
a band): ``"level"`` (the size of the mode's direct contribution: "by participation"),
``"share"``, ``"loo"`` / ``"loo_direct"`` (the leave-one-out error over the band, both
paths or the direct one) or ``"loo_floating"`` (its largest floating-band value, as the
criterion reads it); or ``"greedy"``: greedy elimination by the leave-one-out error,
which starts from all pairs and repeatedly drops those whose removal raises the
criterion's error least while it stays below the threshold (the leave-one-out errors
recomputed for the pairs still kept after every drop). It then keeps the first pairs of
that order and reads the count with the truncation study's rule (the smallest count
from which the error stays below the threshold, counts in steps of ``step`` modes).
With ``residual=True`` every pair left out enters with its quasi-static part (upper
residual flexibility, docs/tire-model.md), as :meth:`fbs_core.tire.TireModel.subset`
delivers it.

(A forward greedy selection, adding at every step the pair that lowers the error most,
was tried and dropped: from few modes the eq. 5.1 error is near or above 1 in many
bands whichever pair is added, and the choices it makes there stall it above the
threshold on every case measured.)

All counts come from one per-mode synthesis (:func:`fbs_core.tire.terms.mode_terms`)
and cumulative sums in the ranked order; the responses of a count equal the coupled
response of the tire restricted to those pairs (tested against the direct synthesis of
``tire.subset``). Measured side by side with table 5.1: docs/modes.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._typing import ComplexArray, FloatArray, IntArray
from ..errors import FBSError
from ..harmonics import Harmonic
from ..studies import _models
from ..studies.metric import floating_band_error
from ..studies.truncation import suggest_n_modes
from ..tire.terms import ModeTerms, mode_terms
from ..vocabulary import readonly as _ro
from .participation import (
    RANKINGS,
    coupled_mode_arrays,
    pair_kinds,
    participation_from_terms,
)

__all__ = ["ModeSelection", "select_modes", "prefix_responses", "SELECTIONS"]

#: How :func:`select_modes` orders the pairs.
SELECTIONS = ("level", "share", "loo", "loo_direct", "loo_floating", "greedy")


def prefix_responses(
    terms: ModeTerms,
    order: Sequence[int] | IntArray,
    counts: Sequence[int] | IntArray,
    YjjE: ComplexArray,
    YejE: ComplexArray,
    dirs: Sequence[str],
    residual: bool = False,
) -> ComplexArray:
    """Coupled responses (eq. 4.1) with the first ``counts[i] / 2`` pairs of ``order``.

    Parameters
    ----------
    terms : ModeTerms
        Per-pair terms with the hub receptance and one patch response (and ``static``
        for ``residual``).
    order : sequence of int, shape (n_p,)
        Pair indices, most important first.
    counts : sequence of int, shape (n_N,)
        Increasing even mode counts (2 .. 2 n_p).
    YjjE, YejE : ndarray, shapes (n_f, n_c, n_c), (n_f, n_e, n_c)
        Chassis mobilities at the coupled interface and to the responses.
    dirs : sequence of str
        Coupled directions.
    residual : bool
        Pairs left out enter with their quasi-static part.

    Returns
    -------
    ndarray, shape (n_N, n_f, n_e)
    """
    o = np.asarray(order, int)
    n = np.asarray(counts, int)
    if n.ndim != 1 or n.size == 0 or np.any(n % 2) or np.any(np.diff(n) <= 0):
        raise FBSError(f"counts must be increasing even mode counts, got {n.tolist()}")
    if n[0] < 2 or n[-1] > 2 * o.size:
        raise FBSError(f"counts must lie in 2..{2 * o.size}, got {n.tolist()}")
    if residual and terms.static is None:
        raise FBSError("residual=True needs mode terms with their static parts (static=True)")
    Yp, vp, _, _ = coupled_mode_arrays(terms, YjjE, dirs)
    if residual:
        assert terms.static is not None
        st = ModeTerms(
            terms.freq, terms.speeds, terms.cols, terms.static, None, terms.frequency, terms.damping
        )
        Ys, vs, _, _ = coupled_mode_arrays(st, YjjE, dirs)
        Yp, vp = Yp - Ys, vp - vs  # kept pairs swap their static part for the dynamic one
        Y0, v0 = Ys.sum(axis=0), vs.sum(axis=0)
    else:
        Y0, v0 = np.zeros_like(Yp[0]), np.zeros_like(vp[0])
    edges = np.r_[0, n // 2]
    Yb = np.stack([Yp[o[a:b]].sum(axis=0) for a, b in zip(edges[:-1], edges[1:], strict=True)])
    vb = np.stack([vp[o[a:b]].sum(axis=0) for a, b in zip(edges[:-1], edges[1:], strict=True)])
    YN = np.cumsum(Yb, axis=0) + Y0 + YjjE
    vN = np.cumsum(vb, axis=0) + v0
    g = np.linalg.solve(YN, vN[..., None])[..., 0]
    out: ComplexArray = np.einsum("fec,nfc->nfe", YejE, g)
    return out


@dataclass(frozen=True, eq=False)
class ModeSelection:
    """The modes a case needs, chosen by a measure instead of the lowest ``N``.

    Attributes
    ----------
    harmonic : int
    by : str
        The ordering (:data:`SELECTIONS`).
    residual : bool
        Pairs left out compensated by their quasi-static part.
    threshold, f_max : float
        Criterion: eq. 5.1 below ``threshold`` at every centre up to ``f_max`` Hz.
    dof : str or None
        The judged response DOF (None: the largest error over the DOFs).
    order : ndarray of int, shape (n_p,)
        Stored pair indices, most important first.
    counts : ndarray of int, shape (n_N,)
        Mode counts evaluated.
    centres : ndarray, shape (n_cen,)
        Floating-band centres up to ``f_max``.
    error : ndarray, shape (n_N, n_cen)
        Eq. 5.1 error (largest over the DOFs, or of ``dof``) of every count.
    n_modes : int
        Suggested count, table 5.1's rule: the smallest from which the error stays below
        the threshold for every larger count too (0 when the harmonic has no centre up
        to ``f_max``).
    n_first : int
        The smallest count whose selection meets the criterion (what a supplier
        delivering exactly that selection needs; ``<= n_modes``).
    """

    harmonic: int
    by: str
    residual: bool
    threshold: float
    f_max: float
    dof: str | None
    order: IntArray
    counts: IntArray
    centres: FloatArray
    error: FloatArray
    n_modes: int
    n_first: int

    @property
    def selected(self) -> IntArray:
        """The stored pair indices of the suggested count, sorted."""
        s: IntArray = np.sort(self.order[: self.n_modes // 2])
        return s


def _errors(
    resp: ComplexArray,
    ref: ComplexArray,
    f: FloatArray,
    centres: FloatArray,
    width: float,
    dof: int | None,
) -> FloatArray:
    """Largest eq. 5.1 error over the centres (and the DOFs, or of ``dof``) per response."""
    _, err = floating_band_error(f, ref, resp, width, centres=centres)  # (n, n_cen, n_e)
    e: FloatArray = err.max(axis=(1, 2)) if dof is None else err[..., dof].max(axis=1)
    return e


def _backward(
    Yp: ComplexArray,
    vp: ComplexArray,
    Y0: ComplexArray,
    v0: ComplexArray,
    YjjE: ComplexArray,
    YejE: ComplexArray,
    ref: ComplexArray,
    f: FloatArray,
    centres: FloatArray,
    width: float,
    dof: int | None,
    stop: float,
) -> IntArray:
    """Greedy elimination by the leave-one-out error: from all pairs, drop the pairs whose
    removal raises the criterion's error least, as long as it stays below ``stop``.

    Every round computes the leave-one-out error of every pair still kept and tries to
    drop the ``m`` best together (``m`` a quarter of the kept pairs, halved until the
    error of the rest stays below ``stop``); it ends when not even one can go. Returns
    the kept pairs (the most important first) followed by the dropped ones, the last
    dropped first.
    """
    keep = np.arange(Yp.shape[0])
    dropped: list[int] = []
    A, v = Y0 + YjjE + Yp.sum(axis=0), v0 + vp.sum(axis=0)
    last = np.zeros(keep.size)
    while keep.size > 1:
        g = np.linalg.solve(A[None] - Yp[keep], (v[None] - vp[keep])[..., None])[..., 0]
        e = _errors(np.einsum("fec,pfc->pfe", YejE, g), ref, f, centres, width, dof)
        last = e
        rank = np.argsort(e, kind="stable")
        m = max(1, keep.size // 4)
        while m >= 1:
            out = keep[rank[:m]]
            A1, v1 = A - Yp[out].sum(axis=0), v - vp[out].sum(axis=0)
            g1 = np.linalg.solve(A1, v1[..., None])[..., 0]
            if (
                _errors(np.einsum("fec,fc->fe", YejE, g1)[None], ref, f, centres, width, dof)[0]
                < stop
            ):
                break
            m //= 2
        if m == 0:
            break
        dropped += [int(p) for p in out]
        A, v = A1, v1
        keep = np.setdiff1d(keep, out)
        last = np.zeros(keep.size)
    kept = keep[np.argsort(-last, kind="stable")] if last.size == keep.size else keep
    order: IntArray = np.concatenate([kept, np.array(dropped[::-1], np.intp)]).astype(np.intp)
    return order


def select_modes(
    harmonic: int | Harmonic,
    threshold: float = 0.2,
    f_max: float = 160.0,
    *,
    by: str = "level",
    residual: bool = False,
    dof: str | None = None,
    step: int = 10,
    df: float = 0.5,
    width: float = 12.0,
    coupling: str | Sequence[str] = "6dof",
    tire: Any = None,
    chassis: Any = None,
) -> ModeSelection:
    """The tire modes one case needs, chosen by importance rather than frequency.

    Parameters
    ----------
    harmonic : int or Harmonic
        Excitation case 1..7.
    threshold : float
        Largest acceptable eq. 5.1 error (0.2 = 20 %, thesis table 5.1).
    f_max : float
        Upper frequency of the predictions in Hz (130 and 160 in the thesis).
    by : {"level", "share", "loo", "loo_direct", "loo_floating", "greedy"}
        Ordering of the pairs (module notes); ``"greedy"`` recomputes the leave-one-out
        errors after every round of drops (about 1-3 s per case).
    residual : bool
        Keyword only: the pairs left out enter with their quasi-static part.
    dof : str, optional
        Judge one response DOF (default the largest error over the DOFs, as table 5.1).
    step : int
        Even step of the counts (modes), as the thesis' 10.
    df, width, coupling, tire, chassis
        As :func:`fbs_core.studies.truncation_map`.

    Returns
    -------
    ModeSelection

    Raises
    ------
    FBSError
        For an unknown ordering, a negative threshold or an odd step.
    DOFError
        For an unknown response DOF.
    """
    if by not in SELECTIONS:
        raise FBSError(f"unknown selection {by!r}; allowed: {', '.join(SELECTIONS)}")
    if not threshold >= 0:
        raise FBSError(f"threshold must be >= 0 (0.2 = 20 %), got {threshold!r}")
    if isinstance(step, bool) or int(step) != step or step < 2 or step % 2:
        raise FBSError(f"step must be an even number of modes >= 2, got {step!r}")
    h = _models.resolve_harmonic(harmonic)
    tire = _models.resolve_tire(tire)
    dirs = _models.coupled_directions(coupling)
    f_all = h.frequencies(df)
    f = f_all[f_all <= f_max + width / 2 + 1e-9]
    n_p = tire.n_modes // 2
    counts = np.arange(step, 2 * n_p + 1, step)
    if counts[-1] != 2 * n_p:
        counts = np.r_[counts, 2 * n_p]
    if f.size < 3 or f[0] > f_max:  # no centre up to f_max: nothing to judge
        empty = np.zeros((counts.size, 0))
        return ModeSelection(
            h.k, by, bool(residual), float(threshold), float(f_max), dof,
            _ro(np.arange(n_p), int), _ro(counts, int), _ro(np.zeros(0)), _ro(empty), 0, 0,
        )  # fmt: skip
    YjjE, YejE, resp = _models.chassis_arrays(chassis, f, dirs)
    d_idx = None
    if dof is not None:
        from ..dofs import index_of

        d_idx = index_of(resp, [dof], "response DOF")[0]
    terms = mode_terms(tire, f, h.speed_at(f), tire._harmonic_index(h), static=bool(residual))
    cen = np.arange(np.ceil(f[0] - 1e-9), np.floor(min(f_max, f[-1]) + 1e-9) + 1.0)
    Yp, vp, A, v = coupled_mode_arrays(terms, YjjE, dirs)
    ref = np.einsum("fec,fc->fe", YejE, np.linalg.solve(A, v[..., None])[..., 0])
    first, sliding = pair_kinds(tire.poles)
    part = participation_from_terms(
        h.k, terms, YjjE, YejE, resp, dirs, first, width, sliding=sliding
    )
    if by == "greedy":
        Y0, v0 = np.zeros_like(A), np.zeros_like(v)
        if residual:  # a pair not (yet) chosen is there with its static part
            assert terms.static is not None
            st = ModeTerms(f, terms.speeds, terms.cols, terms.static, None, terms.frequency,
                           terms.damping)  # fmt: skip
            Ys, vs, _, _ = coupled_mode_arrays(st, YjjE, dirs)
            Y0, v0, Yp, vp = Ys.sum(axis=0), vs.sum(axis=0), Yp - Ys, vp - vs
        order = _backward(Yp, vp, Y0, v0, YjjE, YejE, ref, f, cen, width, d_idx, threshold)
    else:
        assert by in RANKINGS
        order = part.ranking(by, dof)
    resp_n = prefix_responses(terms, order, counts, YjjE, YejE, dirs, bool(residual))
    _, err = floating_band_error(f, ref, resp_n, width, centres=cen)  # (n_N, n_cen, n_e)
    e = err.max(axis=-1) if d_idx is None else err[..., d_idx]
    n = suggest_n_modes(e, cen, counts, threshold, f_max, 2 * n_p)
    ok = np.all(e < threshold, axis=1)
    return ModeSelection(
        h.k,
        by,
        bool(residual),
        float(threshold),
        float(f_max),
        dof,
        _ro(order, int),
        _ro(counts, int),
        _ro(cen),
        _ro(e),
        int(n),
        int(counts[np.argmax(ok)]),
    )
