"""A measured chassis from two files: the FRF set around the knuckle and its geometry.

One call does what a test engineer's data needs before the coupling (docs/vpt.md): read the
measured FRFs (:func:`fbs_core.io.load_frf`: outputs the sensor channels and the bushing's,
inputs the impacts) and the channels' positions and directions
(:func:`fbs_core.io.load_geometry`), transform to the virtual point at the wheel centre
(:func:`fbs_core.vpt.virtual_point`), and make the chassis the coupling takes
(:func:`fbs_core.io.prepare_chassis`, :class:`fbs_core.FRFChassis`). Every check of those
steps applies; a refused input changes nothing.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..chassis import FRFChassis
from ..dofs import parse_label
from ..errors import DataFormatError, DOFError
from ..vpt.transform import VirtualPoint, virtual_point

__all__ = ["MeasuredChassis", "load_measured_chassis"]

Source = str | os.PathLike[str] | bytes | bytearray | memoryview


@dataclass(frozen=True, eq=False)
class MeasuredChassis:
    """A chassis measured at the knuckle and transformed to the spindle.

    Attributes
    ----------
    chassis : FRFChassis
        Mobility with outputs ``spindle:*`` and ``bushing:*``, inputs ``spindle:*``.
    vpt : VirtualPoint
        The transformation: its FRF, layout, consistency and leverage.
    summary : str
        What was read and how consistent it was (for an import summary).
    """

    chassis: FRFChassis
    vpt: VirtualPoint
    summary: str


def load_measured_chassis(
    frf_source: Source,
    geometry_source: Source,
    *,
    frf_filename: str | None = None,
    geometry_filename: str | None = None,
    nodes: Mapping[Any, Any] | None = None,
    origin: str = "spindle",
    bushing: str = "bushing",
    quantity: str | None = None,
    interpolate: bool = False,
) -> MeasuredChassis:
    """Read a measured FRF set and its geometry and transform it to the spindle's six DOFs.

    Parameters
    ----------
    frf_source, geometry_source : path or bytes
        The measured FRFs (UFF 58, MATLAB, CSV, HDF5) and the geometry (UFF 15/2411, CSV,
        HDF5 table); with bytes pass the file names.
    frf_filename, geometry_filename : str, optional
    nodes : mapping, optional
        UFF node numbers to names, for both files.
    origin : str
        The virtual point: a point of the geometry file (default ``"spindle"``).
    bushing : str
        The response node: its outputs are carried as transfers, every other output is a
        sensor channel.
    quantity : str, optional
        What the FRF file holds when it does not say.
    interpolate : bool
        Passed to :class:`FRFChassis`.

    Returns
    -------
    MeasuredChassis

    Raises
    ------
    DataFormatError, DOFError, GeometryError, QuantityError, FrequencyGridError
        From the readers and the transformation, naming the file, channel or node; also a
        set without outputs at ``bushing``.
    """
    from . import load_frf, load_geometry, prepare_chassis

    res = load_frf(frf_source, filename=frf_filename, nodes=nodes, quantity=quantity)
    frf = res.frf
    if frf is None:  # an FRF import always holds one; a tire import does not
        raise DataFormatError(f"{frf_filename or 'the FRF file'} holds no FRF")
    geo = load_geometry(geometry_source, filename=geometry_filename, nodes=nodes)
    transfers = [o for o in frf.outputs if parse_label(o)[0] == bushing]
    if not transfers:
        nodes_out = sorted({parse_label(o)[0] for o in frf.outputs})
        raise DOFError(
            f"{res.summary.splitlines()[0] if res.summary else 'the FRF'}: no outputs at the "
            f"bushing node {bushing!r} (output nodes: {', '.join(nodes_out)})"
        )
    sensors = [o for o in frf.outputs if o not in set(transfers)]
    layout = geo.layout(sensors, frf.inputs, origin=origin, node="spindle")
    vp = virtual_point(frf, layout, transfers=transfers)
    Y, notes = prepare_chassis(vp.frf, spindle="spindle", bushing=bushing)
    cs = vp.consistency
    so, io = cs.overall()
    worst, wv = cs.worst()
    lev = max({**vp.sensor_leverage, **vp.impact_leverage}.items(), key=lambda kv: kv[1])
    lines = [
        res.summary,
        f"virtual point {origin!r} from {len(sensors)} sensor channels and {len(frf.inputs)} "
        f"impacts ({geo.source}); consistency: sensors {so:.4f}, impacts {io:.4f} overall, "
        f"lowest channel {worst} {wv:.3f}; highest leverage {lev[0]} {lev[1]:.2f}"
        + (" (that channel cannot be checked)" if lev[1] > 0.9 else ""),
    ]
    if notes:
        lines.append("chassis: " + "; ".join(notes))
    return MeasuredChassis(FRFChassis(Y, interpolate=interpolate), vp, "\n".join(lines))
