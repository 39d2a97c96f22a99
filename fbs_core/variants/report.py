"""Plain-text tables of a corridor study for a meeting (the command line and the scripts).

The numbers are those of :meth:`.Corridor.beside`, :meth:`.Sensitivity.table` and
:meth:`.Sensitivity.leaders`; these functions only lay them out.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .corridor import Corridor
from .sensitivity import Sensitivity

__all__ = ["corridor_text", "sensitivity_text"]


def corridor_text(c: Corridor, band: Any = None) -> str:
    """One row per DOF: the corridor's width (median and largest over the lines, dB) and
    how far its edges lie above / below the nominal response; with a scatter ``band`` of
    the same lines also the band's width and the share of lines where the corridor is
    wider or leaves the band.

    Parameters
    ----------
    c : Corridor
    band : ScatterBand, optional
    """
    h = f"harmonic {c.harmonic}: " if c.harmonic is not None else ""
    out = [
        f"{h}corridor of {c.n_variants} variants, {c.freq.size} lines "
        f"{c.freq[0]:g}-{c.freq[-1]:g} Hz (dB; median / largest over the lines)"
    ]
    head = f"  {'dof':<11}{'width':>8}{'max':>7}{'above':>8}{'max':>7}{'below':>8}{'max':>7}"
    rows = {r["dof"]: r for r in c.beside(band)} if band is not None else {}
    if band is not None:
        out[0] += (
            f"; beside the {100 * band.noise:g} % noise band ({band.target}, R = {band.rounds})"
        )
        head += f"{'band':>8}{'max':>7}{'wider':>7}{'leaves':>8}"
    out.append(head)
    for i, d in enumerate(c.dofs):
        w, a, b = c.width_db[:, i], c.above_db[:, i], c.below_db[:, i]
        line = (
            f"  {d:<11}{np.median(w):>8.2f}{w.max():>7.1f}{np.median(a):>8.2f}{a.max():>7.1f}"
            f"{np.median(b):>8.2f}{b.max():>7.1f}"
        )
        if d in rows:
            r = rows[d]
            line += (
                f"{r['band_median_db']:>8.2f}{r['band_max_db']:>7.1f}{r['share_wider']:>7.0%}"
                f"{r['share_outside']:>8.0%}"
            )
        out.append(line)
    return "\n".join(out)


def sensitivity_text(s: Sensitivity, dofs: Sequence[str] | None = None) -> str:
    """Per DOF and third-octave band: the total Sobol' index of every parameter (first-order
    in brackets), the band level's standard deviation, and the leading parameter; then the
    convergence of the totals over the design's prefixes.

    Parameters
    ----------
    s : Sensitivity
    dofs : sequence of str, optional
        Default all.
    """
    h = "" if s.harmonic is None else f", harmonic {s.harmonic}"
    out = [
        f"Sobol' indices of the band levels{h}: total (first order); std: the band level's "
        "standard deviation in dB",
        "  convergence: largest change of a total index from N' = "
        + ", ".join(map(str, s.steps))
        + " base rows to all: "
        + ", ".join(f"{x:.3f}" for x in s.total_change),
    ]
    w = max(14, *(len(n) + 2 for n in s.names))
    for d in s.dofs if dofs is None else dofs:
        j = s.dofs.index(d)
        out.append(f"  {d}")
        out.append(
            f"    {'band Hz':<14}{'std':>6}  " + "".join(f"{n:>{w}}" for n in s.names) + "  leader"
        )
        lead = s.leaders(d)
        for b, (lo, hi) in enumerate(s.bands):
            cells = "".join(
                f"{f'{s.total[i, b, j]:.2f} ({s.first[i, b, j]:.2f})':>{w}}"
                for i in range(len(s.names))
            )
            band = f"{lo:.1f}-{hi:.1f}"
            out.append(f"    {band:<14}{s.std[b, j]:>6.2f}  {cells}  {lead[b]['parameter']}")
    return "\n".join(out)
