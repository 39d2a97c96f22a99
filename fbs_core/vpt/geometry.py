"""Where the sensors and impacts of a virtual-point measurement are, and what they see.

A measured channel is a point ``r`` on the interface (a knuckle, a wheel carrier) and a unit
direction ``e`` in the vehicle's axes (ISO 8855: x forward, y left, z up). A sensor channel
measures ``e . u(r)``; an impact channel applies a force ``f e`` at ``r``. Near the virtual
point ``r_0`` the interface moves as a rigid body (its six interface displacement modes,
IDMs, van der Seijs et al., IMAC 2015, eq. 2): ``u(r) = u_0 + theta x (r - r_0)``, so a
channel sees

    ``e . u(r) = e . u_0 + ((r - r_0) x e) . theta``,

one row ``[e, (r - r_0) x e]`` of the matrix ``R`` (``u = R q + mu``, residual ``mu``). The
same row, read as a column, maps an impact force to the force and moment it exerts at the
virtual point (``m = R_f^T f``). Optional extra IDMs (flexible interface modes) append
columns given per channel.

:class:`Layout` holds the channels of one measurement (immutable, SI units, checked);
:func:`displacement_modes` is the array kernel of ``R``; :func:`check_observable` refuses a
layout whose channels do not see all six rigid-body DOFs of the virtual point, naming the
channels and what they miss.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from ..dofs import node_labels, parse_label
from ..errors import DataFormatError, DOFError, GeometryError
from ..vocabulary import DIRECTIONS, readonly

__all__ = [
    "Channels",
    "Layout",
    "displacement_modes",
    "check_observable",
    "OBSERVABILITY_RCOND",
]

#: Smallest singular value of the scaled IDM matrix, relative to its largest, below which
#: the channels are taken not to observe a rigid-body motion. A layout spread over a few
#: centimetres on a knuckle reaches 0.1-0.5; collinear sensors give 1e-16.
OBSERVABILITY_RCOND = 1e-3


def _unit_rows(d: FloatArray, labels: Sequence[str], what: str) -> FloatArray:
    n = np.linalg.norm(d, axis=1)
    bad = np.flatnonzero(~(n > 1e-9))
    if bad.size:
        raise GeometryError(
            f"{what} channel {labels[bad[0]]!r} has no direction (direction cosines "
            f"{tuple(float(v) for v in d[bad[0]])}); every channel needs a unit vector in "
            "the vehicle's axes"
        )
    off = np.flatnonzero(np.abs(n - 1.0) > 1e-3)
    if off.size:
        raise GeometryError(
            f"{what} channel {labels[off[0]]!r}: direction cosines "
            f"{tuple(round(float(v), 6) for v in d[off[0]])} are not a unit vector "
            f"(length {n[off[0]]:.4g}); give cosines, not a scaled vector"
        )
    out: FloatArray = d / n[:, None]
    return out


@dataclass(frozen=True, eq=False)
class Channels:
    """Measured channels: labels, positions (m) and unit directions, vehicle axes.

    Parameters
    ----------
    labels : sequence of str
        Channel labels as in the measured FRF (e.g. ``"s1:x"`` outputs, ``"h4:z"``
        inputs); unique.
    positions : array_like, shape (n, 3)
        Point of each channel in metres.
    directions : array_like, shape (n, 3)
        Unit direction of each channel (direction cosines in the vehicle's axes).
    """

    labels: tuple[str, ...]
    positions: FloatArray
    directions: FloatArray

    def __init__(
        self,
        labels: Iterable[str],
        positions: ArrayLike,
        directions: ArrayLike,
        what: str = "sensor",
    ) -> None:
        lab = tuple(str(s) for s in labels)
        for s in lab:
            parse_label(s)
        dup = sorted({s for s in lab if lab.count(s) > 1})
        if dup:
            raise DOFError(f"{what} channel {dup[0]!r} is listed more than once")
        p = np.asarray(positions, float)
        d = np.asarray(directions, float)
        for name, a in (("positions", p), ("directions", d)):
            if a.shape != (len(lab), 3):
                raise DataFormatError(
                    f"{what} {name} have shape {a.shape}, expected ({len(lab)}, 3) for "
                    f"{len(lab)} channels"
                )
        for name, a in (("position", p), ("direction", d)):
            bad = np.flatnonzero(~np.isfinite(a).all(axis=1))
            if bad.size:
                raise GeometryError(f"{what} channel {lab[bad[0]]!r} has no {name} (not finite)")
        object.__setattr__(self, "labels", lab)
        object.__setattr__(self, "positions", readonly(p))
        object.__setattr__(self, "directions", readonly(_unit_rows(d, lab, what)))

    def __len__(self) -> int:
        return len(self.labels)

    def subset(self, labels: Iterable[str], what: str = "channel") -> Channels:
        """The channels ``labels`` in that order (DOFError naming a missing one)."""
        want = list(labels)
        pos = {s: i for i, s in enumerate(self.labels)}
        missing = [s for s in want if s not in pos]
        if missing:
            raise DOFError(
                f"{what} {missing[0]!r} has no position and direction in the geometry "
                f"({len(missing)} missing in all: {', '.join(missing[:6])}"
                f"{' ...' if len(missing) > 6 else ''})"
            )
        idx = [pos[s] for s in want]
        return Channels(want, self.positions[idx], self.directions[idx])


@dataclass(frozen=True, eq=False)
class Layout:
    """Sensors and impacts of one virtual point measurement (immutable).

    Parameters
    ----------
    sensors, impacts : Channels
        Response channels (the FRF's outputs) and impact channels (its inputs).
    origin : array_like, shape (3,)
        Position of the virtual point (m), e.g. the wheel centre.
    node : str
        Node name of the virtual point: the transformed FRF is labelled
        ``node:x .. node:rz`` (default ``"spindle"``, what the chassis coupling expects).
    """

    sensors: Channels
    impacts: Channels
    origin: FloatArray
    node: str = "spindle"

    def __init__(
        self, sensors: Channels, impacts: Channels, origin: ArrayLike, node: str = "spindle"
    ) -> None:
        o = np.asarray(origin, float)
        if o.shape != (3,) or not np.all(np.isfinite(o)):
            raise GeometryError(f"the virtual point {node!r} needs 3 finite coordinates, got {o}")
        if parse_label(node)[1] is not None:
            raise DOFError(f"virtual point node {node!r} must not contain a direction")
        object.__setattr__(self, "sensors", sensors)
        object.__setattr__(self, "impacts", impacts)
        object.__setattr__(self, "origin", readonly(o))
        object.__setattr__(self, "node", node)

    @property
    def labels(self) -> tuple[str, ...]:
        """``node:x`` .. ``node:rz``: the virtual point's DOFs."""
        return node_labels(self.node)

    def modes(self, kind: str) -> FloatArray:
        """``R_u`` (``kind="sensors"``) or ``R_f`` (``"impacts"``), shape (n, 6)."""
        if kind not in ("sensors", "impacts"):
            raise DataFormatError(f"modes of {kind!r}; allowed: 'sensors', 'impacts'")
        ch = self.sensors if kind == "sensors" else self.impacts
        return displacement_modes(ch.positions, ch.directions, self.origin)


def displacement_modes(
    positions: ArrayLike, directions: ArrayLike, origin: ArrayLike
) -> FloatArray:
    """Rigid interface displacement modes seen by channels: ``R = [e, (r - r_0) x e]``.

    Parameters
    ----------
    positions, directions : array_like, shape (n, 3)
        Channel points (m) and unit directions.
    origin : array_like, shape (3,)
        The virtual point ``r_0``.

    Returns
    -------
    ndarray, shape (n, 6)
        Row ``k`` maps the virtual point's ``(u_x, u_y, u_z, theta_x, theta_y, theta_z)``
        to channel ``k``'s response (IMAC 2015 eq. 2); for impacts, column ``k`` of
        ``R^T`` is the force and moment at the virtual point of a unit impact.

    Examples
    --------
    >>> displacement_modes([[0.1, 0.0, 0.0]], [[0.0, 1.0, 0.0]], [0, 0, 0]).round(3).tolist()
    [[0.0, 1.0, 0.0, 0.0, 0.0, 0.1]]
    """
    r = np.asarray(positions, float) - np.asarray(origin, float)
    e = np.asarray(directions, float)
    out: FloatArray = np.hstack([e, np.cross(r, e)])
    return out


def _length_scale(R: FloatArray) -> float:
    """Characteristic lever arm of the channels (m): rotations are scaled by it so that the
    singular values compare translations and rotations in the same unit."""
    arm = float(np.sqrt(np.mean(np.sum(R[:, 3:] ** 2, axis=1))))
    return arm if arm > 0 else 1.0


def _describe(v: FloatArray, node: str) -> str:
    """A rigid-body motion of the null space in words: its leading DOFs."""
    w = np.abs(v) / np.abs(v).max()
    lead = [f"{node}:{DIRECTIONS[k]}" for k in np.argsort(-w) if w[k] > 0.2]
    return " + ".join(lead[:3])


def _why(positions: FloatArray, directions: FloatArray) -> str:
    """What in the layout loses a DOF: points on a line, or too few directions."""
    c = positions - positions.mean(axis=0)
    sp = np.linalg.svd(c, compute_uv=False) if len(c) > 1 else np.zeros(3)
    scale = max(float(sp[0]), 1e-12)
    reasons = []
    if int(np.sum(sp > 1e-3 * scale)) <= 1 or scale < 1e-6:
        reasons.append("the points are coincident or lie on one line")
    nd = int(np.linalg.matrix_rank(directions, tol=1e-3))
    if nd < 3:
        reasons.append(f"the directions span only {nd} axis{'es' if nd != 1 else ''}")
    return "; ".join(reasons) if reasons else "the points and directions are too close"


def check_observable(
    channels: Channels,
    origin: ArrayLike,
    what: str,
    node: str = "spindle",
    rcond: float = OBSERVABILITY_RCOND,
) -> None:
    """Refuse channels that cannot observe (or excite) all six rigid-body DOFs.

    The six rigid IDMs are observable when ``R`` (rotations scaled by the channels' lever
    arm) has full column rank: a least-squares virtual point (IMAC 2015 eq. 5) needs
    ``R^T W R`` invertible.

    Parameters
    ----------
    channels : Channels
    origin : array_like, shape (3,)
        The virtual point.
    what : str
        ``"sensor"`` or ``"impact"`` (for the message).
    node : str
        The virtual point's node name (for the message).
    rcond : float
        Smallest relative singular value accepted (:data:`OBSERVABILITY_RCOND`).

    Raises
    ------
    GeometryError
        Fewer than six channels, or channels that all lie on one line, measure in too few
        directions, ...: the message names the channels and the DOFs they cannot see.
    """
    labels = channels.labels
    n = len(labels)
    names = f"{', '.join(labels[:12])}{' ...' if n > 12 else ''}"
    if n < 6:
        raise GeometryError(
            f"{n} {what} channel{'s' if n != 1 else ''} ({names}) cannot observe the six "
            f"DOFs of the virtual point {node!r}: at least 6 channels are needed (e.g. 2 "
            "tri-axial sensors, better 3, not on one line)"
        )
    R = displacement_modes(channels.positions, channels.directions, origin)
    L = _length_scale(R)
    Rs = R * np.r_[np.ones(3), np.full(3, 1.0 / L)]
    _, s, Vt = np.linalg.svd(Rs)
    weak = np.flatnonzero(s < rcond * s[0])
    if weak.size:
        blind = "; ".join(_describe(Vt[k], node) for k in weak)
        raise GeometryError(
            f"the {n} {what} channels ({names}) do not observe {weak.size} of the six DOFs "
            f"of the virtual point {node!r}: {blind} (smallest singular value "
            f"{s[-1] / s[0]:.2g} of the largest; {_why(channels.positions, channels.directions)}"
            "); add channels off that line, in other directions"
        )
