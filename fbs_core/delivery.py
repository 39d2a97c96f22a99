"""Is a candidate's delivery good enough to judge? Modes, speeds and quality warnings.

A supplier's modal tire model is judged by what it predicts; whether it can be trusted
follows from three things the thesis' studies give:

* **modes**: the suggested number of modes of thesis table 5.1 (the smallest ``N`` from
  which the eq. 5.1 floating-band error stays below the meeting's threshold up to its
  ``f_max``, :func:`fbs_core.studies.suggest_modes` computed with the candidate's own
  tire). The delivery is *converged* when, for every harmonic, that ``N`` is below the
  modes it holds: its all-modes prediction no longer changes by more than the threshold
  when modes are added. When a required table is given (e.g. the incumbent's or the
  reference tire's table 5.1 at the same threshold and ``f_max``), the delivery must also
  hold at least the largest ``N`` it asks for.
* **speeds**: the operating points must cover the speed range of every harmonic judged
  (30-120 km/h, thesis fig. 4.4; the model is interpolated between its points, never
  extrapolated);
* **quality warnings**: the notes of :func:`fbs_core.io.checks.check_tire` kept with the
  candidate.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ._typing import IntArray
from .errors import FBSError
from .vocabulary import HARMONIC_CASES, readonly

if TYPE_CHECKING:
    from .candidates import Candidate
    from .studies import SuggestedModes

__all__ = ["Delivery", "assess_delivery"]


@dataclass(frozen=True)
class Delivery:
    """Adequacy of one candidate's delivery.

    Attributes
    ----------
    candidate, digest : str
    n_modes : int
        Complex modes the delivery holds.
    harmonics : tuple of int, length n_h
    suggested : ndarray of int, shape (n_h,)
        Table 5.1's ``N`` per harmonic computed with this tire (0: no centre up to f_max).
    required : ndarray of int, shape (n_h,)
        ``N`` of the required table per harmonic (zeros when none was given).
    threshold, f_max : float
        The meeting's eq. 5.1 threshold (fraction) and highest frequency (Hz).
    converged : bool
        ``suggested < n_modes`` for every harmonic.
    enough_modes : bool
        ``n_modes >= max(required)``.
    speeds : (float, float)
        The delivery's lowest and highest operating point, km/h.
    uncovered : tuple of int
        Harmonics whose speed range the operating points do not cover.
    warnings : tuple of str
        The import's quality notes, then one line per shortfall above.
    """

    candidate: str
    digest: str
    n_modes: int
    harmonics: tuple[int, ...]
    suggested: IntArray
    required: IntArray
    threshold: float
    f_max: float
    converged: bool
    enough_modes: bool
    speeds: tuple[float, float]
    uncovered: tuple[int, ...]
    warnings: tuple[str, ...]

    @property
    def adequate(self) -> bool:
        """Converged, enough modes and every harmonic's speeds covered."""
        return self.converged and self.enough_modes and not self.uncovered


def assess_delivery(
    candidate: Candidate,
    suggested: SuggestedModes | None = None,
    *,
    required: SuggestedModes | None = None,
    threshold: float = 0.2,
    f_max: float = 160.0,
    harmonics: Sequence[int] = HARMONIC_CASES,
) -> Delivery:
    """Whether a candidate's delivery is adequate (module notes for the rules).

    Parameters
    ----------
    candidate : Candidate
    suggested : SuggestedModes, optional
        Table 5.1 computed with ``candidate.model`` (``suggest_modes(threshold, f_max,
        tire=candidate.model)``); computed here when not given (the truncation maps of
        every harmonic: seconds to minutes).
    required : SuggestedModes, optional
        A table whose ``N`` the delivery must hold (e.g. the incumbent's); same threshold
        and ``f_max``.
    threshold, f_max : float
        Used when ``suggested`` is not given (fraction, Hz).
    harmonics : sequence of int
        Cases judged when ``suggested`` is not given.

    Returns
    -------
    Delivery

    Raises
    ------
    FBSError
        For tables of other thresholds, ``f_max`` or harmonics than each other.
    """
    tire = candidate.model
    if suggested is None:
        from .studies import suggest_modes

        suggested = suggest_modes(threshold, f_max, harmonics=tuple(harmonics), tire=tire)
    hs = tuple(int(k) for k in suggested.harmonics)
    n = int(tire.n_modes)
    sug = np.asarray(suggested.n_modes, int)
    req = np.zeros(len(hs), int)
    if required is not None:
        if (required.threshold, required.f_max) != (suggested.threshold, suggested.f_max):
            raise FBSError(
                f"the required table is at threshold {required.threshold:g}, f_max "
                f"{required.f_max:g} Hz, the candidate's at {suggested.threshold:g}, "
                f"{suggested.f_max:g} Hz; compare tables of one meeting"
            )
        rmap = dict(zip(required.harmonics, np.asarray(required.n_modes, int), strict=True))
        missing = [k for k in hs if k not in rmap]
        if missing:
            raise FBSError(f"the required table has no harmonic {missing[0]}")
        req = np.array([rmap[k] for k in hs], int)
    notes = list(candidate.notes)
    short = [k for k, s in zip(hs, sug, strict=True) if s >= n]
    if short:
        notes.append(
            f"not converged: table 5.1 needs all {n} modes for harmonic(s) "
            f"{', '.join(map(str, short))} (threshold {suggested.threshold * 100:g} %, "
            f"f_max {suggested.f_max:g} Hz); a delivery with more modes may predict otherwise"
        )
    need = int(req.max()) if req.size else 0
    if need > n:
        notes.append(f"too few modes: {n} delivered, the required table asks for {need}")
    from .harmonics import harmonic

    s0, s1 = float(tire.speeds[0]), float(tire.speeds[-1])
    unc = []
    for k in hs:
        lo, hi = harmonic(k).speed_range
        if s0 > lo + 1e-9 or s1 < hi - 1e-9:
            unc.append(k)
            notes.append(
                f"harmonic {k}: speeds {lo:g}-{hi:g} km/h needed, the delivery covers "
                f"{s0:g}-{s1:g} km/h (lines outside are not predicted)"
            )
    return Delivery(
        candidate.name,
        candidate.digest,
        n,
        hs,
        readonly(sug, int),
        readonly(req, int),
        float(suggested.threshold),
        float(suggested.f_max),
        not short,
        need <= n,
        (s0, s1),
        tuple(unc),
        tuple(notes),
    )
