"""Positions and directions of measured channels: UFF 15 / 2411, CSV and HDF5 tables.

A virtual point transformation (:mod:`fbs_core.vpt`) needs, for every sensor and impact
channel of a measured FRF set, the point it sits on and the direction it measures or
excites, in the vehicle's axes. Engineers have them in one of three forms, all read here
through the parser sandbox (:mod:`._sandbox`, as every file of :mod:`fbs_core.io`):

- a Universal File with node coordinates (dataset 15 or 2411, units from dataset 164):
  a channel ``"<node>:x"`` of the FRF (UFF 58 direction code +-1..3, read by
  :func:`fbs_core.io.load_frf` with the sign applied) then points along the vehicle's x
  axis at its node; nodes whose displacements are given in a local coordinate system are
  refused (give their channels' direction cosines in a table);
- a CSV table (docs/vpt.md), one row per channel or point::

      # length unit: mm
      channel,role,x,y,z,dx,dy,dz
      sa:x,sensor,90,720,120,0.866,0.5,0
      ma:y,impact,45,735,100,0,1,0
      spindle,point,0,750,80,,,

  ``role`` is ``sensor``, ``impact`` or ``point`` (a node, e.g. the virtual point; its
  channels ``node:x`` .. ``node:z`` point along the vehicle's axes); an optional ``unit``
  column (``m``, ``mm``) per row; one length unit per file;
- an HDF5 file with a group ``/geometry`` holding the same columns as datasets
  ``channel``, ``role`` (strings), ``position`` and ``direction`` (n x 3) and the
  attribute ``length_unit``.

:func:`load_geometry` returns a :class:`Geometry`; :meth:`Geometry.layout` picks the
channels of a measured FRF and makes the :class:`fbs_core.vpt.Layout`, refusing a channel
without coordinates or direction by name. Nothing is kept from a refused file.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from ..dofs import parse_label
from ..errors import DataFormatError, DOFError, GeometryError
from ..vocabulary import readonly
from ..vpt.geometry import Channels, Layout
from ._sandbox import DEFAULT_TIMEOUT, parse_isolated
from .checks import DEFAULT_MAX_BYTES, Source, read_source
from .formats import detect_format

__all__ = ["Geometry", "load_geometry", "geometry_csv", "LENGTH_UNITS", "ROLES"]

#: Length units a geometry may be given in, and their size in metres.
LENGTH_UNITS: Mapping[str, float] = MappingProxyType({"m": 1.0, "mm": 1e-3, "cm": 1e-2})
#: What a row of a geometry table is.
ROLES = ("sensor", "impact", "point")
_AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True, eq=False)
class Geometry:
    """Points and channels of a measurement, SI units, vehicle axes (immutable).

    Attributes
    ----------
    points : mapping of str to ndarray (3,)
        Nodes by name: their channels ``node:x/y/z`` point along the vehicle's axes.
    channels : mapping of str to (ndarray (3,), ndarray (3,))
        Channels with their own position and unit direction.
    roles : mapping of str to str
        ``sensor`` or ``impact`` of each entry of ``channels``.
    source : str
        The file name, for messages.
    """

    points: Mapping[str, FloatArray]
    channels: Mapping[str, tuple[FloatArray, FloatArray]]
    roles: Mapping[str, str]
    source: str

    def channel(self, label: str, what: str = "channel") -> tuple[FloatArray, FloatArray]:
        """Position and direction of one channel (its own row, else its node's axis).

        Raises
        ------
        GeometryError
            Naming the channel: no coordinates for its node, a rotation channel, no
            direction.
        """
        if label in self.channels:
            return self.channels[label]
        node, d = parse_label(label)
        if node not in self.points:
            known = ", ".join(sorted(self.points)[:8]) or "none"
            raise GeometryError(
                f"{what} {label!r}: node {node!r} has no coordinates in {self.source!r} "
                f"(nodes there: {known}; channels with their own row: {len(self.channels)})"
            )
        if d not in _AXES:
            raise GeometryError(
                f"{what} {label!r} has no direction: "
                + (
                    "a rotation channel cannot enter the virtual point transformation"
                    if d
                    else "a node name alone names no direction; give the channel's row"
                )
            )
        e = np.zeros(3)
        e[_AXES[d]] = 1.0
        return self.points[node], readonly(e)

    def channels_of(self, labels: Iterable[str], what: str) -> Channels:
        """:class:`fbs_core.vpt.Channels` of ``labels`` in that order."""
        lab = list(labels)
        pd = [self.channel(s, f"{what} channel") for s in lab]
        return Channels(lab, [p for p, _ in pd], [d for _, d in pd], what)

    def layout(
        self,
        sensors: Iterable[str],
        impacts: Iterable[str],
        origin: str | ArrayLike = "spindle",
        node: str = "spindle",
    ) -> Layout:
        """The layout of a measured FRF: its sensor channels (outputs) and impacts (inputs).

        Parameters
        ----------
        sensors, impacts : sequence of str
            Channel labels as in the FRF.
        origin : str or array_like (3,)
            The virtual point: a point of the file by name, or coordinates in metres.
        node : str
            Node name of the transformed FRF's DOFs (``node:x .. node:rz``).

        Raises
        ------
        GeometryError
            Naming the first channel or point that the file does not place.
        """
        if isinstance(origin, str):
            if origin not in self.points:
                raise GeometryError(
                    f"the virtual point {origin!r} is not a point of {self.source!r}: add a "
                    f"row '{origin},point,x,y,z' or pass its coordinates as origin="
                )
            o = self.points[origin]
        else:
            o = np.asarray(origin, float)
        return Layout(
            self.channels_of(sensors, "sensor"), self.channels_of(impacts, "impact"), o, node
        )


def load_geometry(
    source: str | os.PathLike[str] | bytes | bytearray | memoryview,
    *,
    filename: str | None = None,
    format: str | None = None,
    nodes: Mapping[Any, Any] | None = None,
    max_bytes: int = DEFAULT_MAX_BYTES,
    timeout: float = DEFAULT_TIMEOUT,
) -> Geometry:
    """Read the positions and directions of measured channels (UFF 15/2411, CSV, HDF5).

    Parameters
    ----------
    source : path or bytes
        A file path, or an upload's content (then pass ``filename``).
    filename : str, optional
        The upload's name; its ending selects the format.
    format : {"uff", "csv", "hdf5"}, optional
        Overrides the ending; the content must match it.
    nodes : mapping, optional
        UFF node numbers to names, as for :func:`fbs_core.io.load_frf` (the same mapping
        gives the same channel labels).
    max_bytes, timeout : see :func:`fbs_core.io.load_frf`

    Returns
    -------
    Geometry

    Raises
    ------
    DataFormatError
        Unreadable file, missing columns or datasets, unknown roles, no geometry in it.
    GeometryError
        Unknown or mixed length units, a channel without coordinates or direction (named).

    Examples
    --------
    >>> text = b"channel,role,x,y,z,dx,dy,dz\\nspindle,point,0,0.75,0.08,,,\\n"
    >>> g = load_geometry(text, filename="g.csv")
    >>> g.channel("spindle:z")[1].tolist()
    [0.0, 0.0, 1.0]
    """
    src = read_source(source, filename, max_bytes)
    fmt, _ = detect_format(src, format)
    if fmt.name == "uff":
        return _from_uff(src, nodes, timeout)
    if fmt.name == "csv":
        meta, _ = parse_isolated("table", src.raw, f"CSV file {src.name!r}", timeout=timeout)
        return _from_table(
            src.name,
            meta["header"],
            meta["rows"],
            meta["lines"],
            _unit_comment(meta["comments"], src.name),
        )
    if fmt.name == "hdf5":
        return _from_hdf5(src, timeout)
    raise DataFormatError(
        f"{src.name!r}: a geometry is read from UFF (datasets 15/2411), CSV or HDF5, not "
        f"from a {fmt.title}"
    )


def geometry_csv(
    layout: Layout,
    unit: str = "m",
    *,
    sensors: Channels | None = None,
    points: Mapping[str, ArrayLike] | None = None,
) -> bytes:
    """A layout as the CSV geometry table that :func:`load_geometry` reads.

    Parameters
    ----------
    layout : Layout
    unit : {"m", "mm", "cm"}
        Length unit of the coordinates written (declared in a ``# length unit`` line).
    sensors : Channels, optional
        More sensor rows (e.g. the sensors around the bushing, a second virtual point).
    points : mapping of str to array_like (3,), optional
        More points by name (m), e.g. ``{"bushing": xyz}``.

    Examples
    --------
    >>> from fbs_core.vpt import Channels, Layout
    >>> ch = Channels(["a:x"], [[0.1, 0.0, 0.0]], [[1.0, 0.0, 0.0]])
    >>> print(geometry_csv(Layout(ch, ch, [0, 0, 0]), "mm").decode().splitlines()[3])
    a:x,sensor,100,0,0,1,0,0
    """
    f = _unit(unit, "geometry_csv")
    out = [
        "# tire-fbs geometry (docs/vpt.md)",
        f"# length unit: {unit}",
        "channel,role,x,y,z,dx,dy,dz",
    ]
    seen = set()
    groups = [("sensor", layout.sensors), ("impact", layout.impacts)]
    if sensors is not None:
        groups.append(("sensor", sensors))
    for role, ch in groups:
        for lab, p, d in zip(ch.labels, ch.positions, ch.directions, strict=True):
            if lab in seen:
                continue
            seen.add(lab)
            cells = [lab, role, *(f"{v / f:.12g}" for v in p), *(f"{v:.15g}" for v in d)]
            out.append(",".join(cells))
    pts = {layout.node: layout.origin, **(points or {})}
    for name, xyz in pts.items():
        o = ",".join(f"{v / f:.12g}" for v in np.asarray(xyz, float))
        out.append(f"{name},point,{o},,,")
    return ("\n".join(out) + "\n").encode()


def _unit(value: str, where: str) -> float:
    u = value.strip().lower()
    if u not in LENGTH_UNITS:
        raise GeometryError(
            f"{where}: unknown length unit {value!r}; allowed: {', '.join(LENGTH_UNITS)}"
        )
    return LENGTH_UNITS[u]


def _unit_comment(comments: list[str], name: str) -> str | None:
    for c in comments:
        key, _, val = c.partition(":")
        if key.strip().lower() in ("length unit", "length_unit", "unit") and val.strip():
            return val.strip()
    return None


def _number(cell: str, where: str, missing_ok: bool) -> float:
    if not cell.strip():
        if missing_ok:
            return float("nan")
        raise GeometryError(f"{where} is empty")
    try:
        v = float(cell)
    except ValueError:
        raise GeometryError(f"{where}: {cell[:40]!r} is not a number") from None
    if not np.isfinite(v):
        raise GeometryError(f"{where}: {cell[:40]!r} is not a finite number")
    return v


def _from_table(
    name: str,
    header: list[str],
    rows: list[list[str]],
    lines: list[int] | None,
    unit: str | None,
) -> Geometry:
    cols = {h.strip().lower(): k for k, h in enumerate(header)}
    need = ("channel", "role", "x", "y", "z", "dx", "dy", "dz")
    missing = [c for c in need if c not in cols]
    if missing:
        raise DataFormatError(
            f"{name!r}: a geometry table needs the columns {', '.join(need)} (optional: "
            f"unit); missing: {', '.join(missing)}"
        )
    default = _unit(unit, f"{name!r}") if unit else None
    used: tuple[str, float] | None = None
    points: dict[str, FloatArray] = {}
    channels: dict[str, tuple[FloatArray, FloatArray]] = {}
    roles: dict[str, str] = {}
    for k, row in enumerate(rows):
        label = row[cols["channel"]]
        line = f"line {lines[k]}" if lines else f"row {k + 1}"
        where = f"{name!r} {line}, channel {label!r}"
        try:
            parse_label(label)
        except DOFError as e:
            raise DOFError(f"{where}: {e}") from None
        if label in channels or label in points:
            raise DOFError(f"{where}: listed twice")
        role = row[cols["role"]].strip().lower()
        if role not in ROLES:
            raise DataFormatError(f"{where}: role {role!r}; allowed: {', '.join(ROLES)}")
        if "unit" in cols and row[cols["unit"]].strip():
            u = row[cols["unit"]].strip()
            f = _unit(u, where)
        elif default is not None:
            u, f = str(unit), default
        else:
            u, f = "m", 1.0
        if used is None:
            used = (u.lower(), f)
        elif f != used[1]:
            raise GeometryError(
                f"{where} is in {u!r}, the rows before it in {used[0]!r}: one length unit "
                "per file (a mixed table is usually a copy error)"
            )
        xyz = np.array([_number(row[cols[c]], f"{where}, column {c}", False) for c in "xyz"])
        if role == "point":
            if parse_label(label)[1] is not None:
                raise DOFError(f"{where}: a point is a node name, without a direction")
            points[label] = readonly(xyz * f)
            continue
        d = np.array(
            [_number(row[cols[c]], f"{where}, column {c}", True) for c in ("dx", "dy", "dz")]
        )
        if not np.all(np.isfinite(d)) or np.linalg.norm(d) == 0:
            raise GeometryError(
                f"{where} has no direction (dx, dy, dz empty or zero); every sensor and "
                "impact needs its direction cosines in the vehicle's axes"
            )
        n = np.linalg.norm(d)
        if abs(n - 1.0) > 1e-3:
            raise GeometryError(
                f"{where}: direction cosines {tuple(d.tolist())} are not a unit vector "
                f"(length {n:.4g})"
            )
        channels[label] = (readonly(xyz * f), readonly(d / n))
        roles[label] = role
    if not points and not channels:
        raise DataFormatError(f"{name!r} holds no rows of geometry")
    return Geometry(
        MappingProxyType(points), MappingProxyType(channels), MappingProxyType(roles), name
    )


def _from_hdf5(src: Source, timeout: float) -> Geometry:
    meta, arrays = parse_isolated("hdf5", src.raw, f"HDF5 file {src.name!r}", timeout=timeout)
    ds = meta["datasets"]
    need = ("channel", "role", "position", "direction")
    missing = [k for k in need if f"/geometry/{k}" not in ds]
    if missing:
        raise DataFormatError(
            f"{src.name!r}: a geometry file has a group /geometry with datasets "
            f"{', '.join(need)}; missing: {', '.join('/geometry/' + k for k in missing)}"
        )
    labels, roles = ds["/geometry/channel"].get("strings"), ds["/geometry/role"].get("strings")
    if labels is None or roles is None:
        raise DataFormatError(f"{src.name!r}: /geometry/channel and /role must be strings")
    mats = []
    for k in ("position", "direction"):
        e = ds[f"/geometry/{k}"]
        a = np.asarray(arrays[e["array"]], float) if "array" in e else None
        if a is None or a.shape != (len(labels), 3) or np.iscomplexobj(arrays[e["array"]]):
            raise DataFormatError(
                f"{src.name!r}: /geometry/{k} must be real numbers of shape "
                f"({len(labels)}, 3), one row per channel"
            )
        mats.append(a)
    if len(roles) != len(labels):
        raise DataFormatError(f"{src.name!r}: /geometry/role needs {len(labels)} entries")
    unit = meta["groups"].get("/geometry", {}).get("length_unit", "m")
    rows = [
        [
            lab,
            role,
            *(repr(float(v)) for v in mats[0][k]),
            *("" if not np.isfinite(v) else repr(float(v)) for v in mats[1][k]),
        ]
        for k, (lab, role) in enumerate(zip(labels, roles, strict=True))
    ]
    header = ["channel", "role", "x", "y", "z", "dx", "dy", "dz"]
    return _from_table(src.name, header, rows, None, str(unit))


def _from_uff(src: Source, nodes: Mapping[Any, Any] | None, timeout: float) -> Geometry:
    meta, arrays = parse_isolated("uff", src.raw, f"Universal File {src.name!r}", timeout=timeout)
    sets = meta["sets"]
    node_sets = [s for s in sets if s.get("type") in (15, 2411)]
    if not node_sets:
        raise DataFormatError(
            f"{src.name!r} holds no node coordinates (datasets 15 or 2411); found: "
            f"{', '.join(sorted(meta.get('contents', {}))) or 'nothing'}"
        )
    u164 = [s for s in sets if s.get("type") == 164]
    scale = 1.0
    if u164:
        lf = float(u164[0].get("length", 0.0))
        if not (lf > 0 and np.isfinite(lf)):
            raise GeometryError(f"{src.name!r}: dataset 164 has an invalid length factor {lf}")
        scale = 1.0 / lf  # dataset 164: file units per SI unit (1000 for mm)
    points: dict[str, FloatArray] = {}
    for s in node_sets:
        ids, cs, xyz = arrays[s["nodes"]], arrays[s["cs"]], arrays[s["xyz"]]
        for n, (def_cs, disp_cs), p in zip(ids.tolist(), cs.tolist(), xyz, strict=True):
            name = str(n)
            if nodes and (n in nodes or str(n) in nodes):
                name = str(nodes.get(n, nodes.get(str(n))))
            where = f"{src.name!r} node {n}" + (f" ({name!r})" if name != str(n) else "")
            if not np.all(np.isfinite(p)):
                raise GeometryError(f"{where} has no finite coordinates")
            for what, c in (("coordinates", def_cs), ("displacements", disp_cs)):
                if c not in (0, 1):
                    raise GeometryError(
                        f"{where} gives its {what} in coordinate system {c}, which this "
                        "reader does not transform: export them in the global system, or "
                        "give the channels' direction cosines in a geometry table"
                    )
            if name in points:
                raise DOFError(f"{where} is defined twice")
            points[name] = readonly(np.asarray(p, float) * scale)
    return Geometry(MappingProxyType(points), MappingProxyType({}), MappingProxyType({}), src.name)
