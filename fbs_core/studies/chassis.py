"""Modal truncation of the vehicle side (thesis section 7: "the modal truncation
investigation can be also performed in a similar way with the vehicle data").

The tire keeps all its modes; the chassis is its modal form with the lowest ``N`` modes
(:class:`fbs_core.chassis_modal.ModalChassis`, optionally with the residual of the
others), and the coupled bushing response of eq. 4.1 with ``N`` chassis modes is judged
against the response with all of them by the floating-band error of eq. 5.1, exactly as
the tire's study (:func:`fbs_core.studies.truncation_map`): the same
:class:`~fbs_core.studies.TruncationMap` (``n_modes`` now counts chassis modes), the same
``suggest`` rule for a table 5.1 of the chassis. Every ``N`` comes from one
cumulative modal sum of the chassis and one batched interface solve.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import IntArray
from ..chassis import BUSHING, ChassisModel, _modal, reference_chassis
from ..chassis_modal import modal_receptances
from ..dofs import index_of
from ..errors import FBSError
from ..frf import check_grid
from ..harmonics import Harmonic
from ..vocabulary import readonly as _ro
from . import _models
from .metric import floating_band_error
from .truncation import TruncationMap

__all__ = ["chassis_truncation_map", "default_chassis_counts"]


def default_chassis_counts(n_total: int) -> IntArray:
    """``1 .. 30`` one by one, then every 10 up to all modes (the chassis' first modes
    are few and far apart, its high ones many and dense)."""
    n = np.unique(np.r_[np.arange(1, min(30, n_total) + 1), np.arange(40, n_total, 10), n_total])
    out: IntArray = n.astype(np.intp)
    return out


def chassis_truncation_map(
    harmonic: int | Harmonic,
    n_modes: ArrayLike | None = None,
    *,
    residual: bool = False,
    freq: ArrayLike | None = None,
    df: float = 0.5,
    width: float = 12.0,
    step: float = 1.0,
    edges: str = "clip",
    centres: ArrayLike | None = None,
    tire: Any = None,
    chassis: ChassisModel | None = None,
    coupling: str | Sequence[str] = "6dof",
) -> TruncationMap:
    """Truncation error map of the chassis for one harmonic (tire with all its modes).

    Parameters
    ----------
    harmonic : int or Harmonic
        Excitation case 1..7.
    n_modes : array_like of int, optional
        Increasing chassis mode counts (default :func:`default_chassis_counts`).
    residual : bool
        Keyword only: the chassis modes left out enter with their static flexibility.
    freq, df, width, step, edges, centres, tire, coupling
        As :func:`fbs_core.studies.truncation_map`.
    chassis : ChassisModel, optional
        The FE chassis (default the reference one).

    Returns
    -------
    TruncationMap
        ``n_modes`` counts chassis modes; ``n_modes_total`` is the chassis' number of
        modes; made without the interface forces (the transfer changes with ``N``).

    Raises
    ------
    FBSError
        For a chassis without an FE model.
    ModeCountError
        For bad counts.
    """
    h = _models.resolve_harmonic(harmonic)
    tire = _models.resolve_tire(tire)
    dirs = _models.coupled_directions(coupling)
    chassis = reference_chassis() if chassis is None else chassis
    if not isinstance(chassis, ChassisModel):
        raise FBSError(
            "the chassis truncation needs the chassis' FE model (a ChassisModel), got "
            f"{type(chassis).__name__}"
        )
    f = h.frequencies(df) if freq is None else check_grid(freq)
    s, lam, V, W = _modal(chassis.params)
    n_total = lam.size
    n = default_chassis_counts(n_total) if n_modes is None else np.asarray(n_modes)
    spindle = [f"spindle:{d}" for d in dirs]
    oi = index_of(s.dofs, list(spindle) + list(BUSHING), "chassis output DOF")
    ii = index_of(s.dofs, spindle, "chassis input DOF")
    counts = n if n[-1] == n_total else np.r_[n, n_total]
    H = modal_receptances(lam, V[oi], W[:, ii], f, counts, residual)
    Y = H * (2j * np.pi * f)[None, :, None, None]  # mobility
    n_c = len(dirs)
    YjjE, YejE = Y[:, :, :n_c], Y[:, :, n_c:]
    YjjA, vj = _models.tire_arrays(tire, f, h, [tire.n_modes], dirs)
    g = np.linalg.solve(YjjA[0][None] + YjjE, vj[0][None, ..., None])  # (n_N, n_f, n_c, 1)
    resp = (YejE @ g)[..., 0]  # (n_N, n_f, n_e)
    ref = resp[-1]
    k = n.size
    c, err = floating_band_error(f, ref, resp[:k], width, step, edges, centres)
    return TruncationMap(
        harmonic=h.k,
        n_modes=_ro(n, int),
        n_modes_total=int(n_total),
        centres=_ro(c),
        dofs=tuple(BUSHING),
        error=_ro(err),
        freq=_ro(f),
        response=_ro(resp[:k]),
        reference=_ro(ref),
        width=float(width),
        step=float(step),
        edges=edges,
    )
