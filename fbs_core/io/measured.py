"""A measured chassis from two files: the FRF set around the knuckle and its geometry.

One call does what a test engineer's data needs before the coupling (docs/vpt.md): read the
measured FRFs (:func:`fbs_core.io.load_frf`: outputs the sensor channels and the bushing's,
inputs the impacts) and the channels' positions and directions
(:func:`fbs_core.io.load_geometry`), transform to the virtual point at the wheel centre
(:func:`fbs_core.vpt.virtual_point`), and make the chassis the coupling takes
(:func:`fbs_core.io.prepare_chassis`, :class:`fbs_core.FRFChassis`). Every check of those
steps applies; a refused input changes nothing.

The bushing's outputs come one of two ways: measured directly at the bushing node
(``bushing:x`` ..., translations from a tri-axial sensor there), or from sensors glued around
it, transformed on the response side to a second virtual point at the geometry's point
``bushing`` (:func:`fbs_core.vpt.response_point`, IMAC 2015 eqs. 5-6 and 10), which gives
its rotations too. The rule: outputs whose node is named ``<bushing>_<anything>`` (e.g.
``bushing_a:x``) are the sensors around the bushing, unless ``bushing_sensors=`` names them.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from ..chassis import FRFChassis
from ..dofs import node_labels, parse_label
from ..errors import DataFormatError, DOFError, GeometryError
from ..vpt.transform import ResponsePoint, VirtualPoint, response_point, virtual_point

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
    bushing_vp : ResponsePoint or None
        The second virtual point at the bushing, from the sensors around it (its
        consistency and leverage); None when the bushing's outputs were measured directly.
    """

    chassis: FRFChassis
    vpt: VirtualPoint
    summary: str
    bushing_vp: ResponsePoint | None = None


def load_measured_chassis(
    frf_source: Source,
    geometry_source: Source,
    *,
    frf_filename: str | None = None,
    geometry_filename: str | None = None,
    nodes: Mapping[Any, Any] | None = None,
    origin: str = "spindle",
    bushing: str = "bushing",
    bushing_sensors: Sequence[str] | None = None,
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
        The response node. Its outputs are carried as transfers (measured directly), or,
        from sensors around it, it is the second virtual point: a point of the geometry
        file of that name.
    bushing_sensors : sequence of str, optional
        The output channels of the sensors around the bushing. Default: every output whose
        node is named ``<bushing>_<anything>`` (``bushing_a:x``, ``bushing_b:z`` ...); give
        ``()`` to take none. Every other output is a sensor of the spindle's virtual point.
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
        From the readers and the transformations, naming the file, channel or node; also a
        set without outputs at ``bushing`` or sensors around it, or with both (DOFError
        naming the two), and bushing sensors without the point ``bushing`` in the geometry.
    """
    from . import load_frf, load_geometry, prepare_chassis

    res = load_frf(frf_source, filename=frf_filename, nodes=nodes, quantity=quantity)
    frf = res.frf
    if frf is None:  # an FRF import always holds one; a tire import does not
        raise DataFormatError(f"{frf_filename or 'the FRF file'} holds no FRF")
    geo = load_geometry(geometry_source, filename=geometry_filename, nodes=nodes)
    direct = [o for o in frf.outputs if parse_label(o)[0] == bushing]
    if bushing_sensors is None:
        around = [o for o in frf.outputs if parse_label(o)[0].startswith(f"{bushing}_")]
    else:
        around = list(bushing_sensors)
    if direct and around:
        raise DOFError(
            f"{res.summary.splitlines()[0] if res.summary else 'the FRF'}: outputs measured "
            f"at the bushing node {bushing!r} itself ({', '.join(direct)}) and sensors around "
            f"it ({', '.join(around[:6])}{' ...' if len(around) > 6 else ''}): give one or "
            f"the other (drop the direct channels to transform the sensors to "
            f"{bushing}:x .. {bushing}:rz, or rename the sensors' nodes)"
        )
    bvp = None
    if around:
        if bushing not in geo.points:
            raise GeometryError(
                f"{len(around)} sensor channels around the bushing ({', '.join(around[:3])} "
                f"...) need the second virtual point {bushing!r} as a point of "
                f"{geo.source!r}: add a row '{bushing},point,x,y,z'"
            )
        chans = geo.channels_of(around, "bushing sensor")
        bvp = response_point(frf, chans, geo.points[bushing], bushing)
        frf = bvp.frf
        transfers = list(node_labels(bushing))
    else:
        transfers = direct
    if not transfers:
        nodes_out = sorted({parse_label(o)[0] for o in frf.outputs})
        raise DOFError(
            f"{res.summary.splitlines()[0] if res.summary else 'the FRF'}: no outputs at the "
            f"bushing node {bushing!r} and no sensors around it ({bushing}_*) (output nodes: "
            f"{', '.join(nodes_out)})"
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
    if bvp is not None:
        bo = float(bvp.consistency.sensor_overall.mean())
        bw, bwv = bvp.consistency.worst()
        blev = max(bvp.sensor_leverage.items(), key=lambda kv: kv[1])
        lines.append(
            f"second virtual point {bushing!r} ({bushing}:x .. {bushing}:rz) from "
            f"{len(around)} sensor channels around it; consistency: sensors {bo:.4f} "
            f"overall, lowest channel {bw} {bwv:.3f}; highest leverage {blev[0]} "
            f"{blev[1]:.2f}" + (" (that channel cannot be checked)" if blev[1] > 0.9 else "")
        )
    if notes:
        lines.append("chassis: " + "; ".join(notes))
    return MeasuredChassis(FRFChassis(Y, interpolate=interpolate), vp, "\n".join(lines), bvp)
