"""The words of the whole car: wheels, their hub and spindle labels, the mirror image.

Vehicle axes are ISO 8855 (x forward, y left, z up), as for the single corner
(docs/chassis-model.md). The four wheels are ``fl`` (front left), ``fr``, ``rl``,
``rr``. On the vehicle side the hub coupling node of wheel ``w`` is
``spindle_<w>``; the tire mounted there has its hub DOFs labelled ``hub_<w>:*``.

The mirror image in the vehicle's x-z plane (y -> -y) is an exact change of
coordinates of every node's six DOFs: translations transform as vectors,
``(x, y, z) -> (x, -y, z)``, rotations as pseudovectors (a reflection has
determinant -1), ``(rx, ry, rz) -> (-rx, ry, -rz)``. So the signs are
:data:`MIRROR` ``= (1, -1, 1, -1, 1, -1)`` for ``(x, y, z, rx, ry, rz)``, and a
6 x 6 mobility of the mirrored part is ``T Y T`` with ``T = diag(MIRROR)``.
A forward-rolling wheel spins about +y on both sides (``ry`` keeps its sign).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from .._typing import FloatArray
from ..dofs import DIRECTIONS, node_labels
from ..errors import DOFError

__all__ = [
    "WHEELS",
    "FRONT",
    "REAR",
    "LEFT",
    "RIGHT",
    "MIRROR",
    "hub_labels",
    "spindle_labels",
    "road_label",
    "mirror_signs",
    "check_wheels",
    "side_of",
]

#: The four wheels: front left, front right, rear left, rear right.
WHEELS: tuple[str, ...] = ("fl", "fr", "rl", "rr")
FRONT: tuple[str, ...] = ("fl", "fr")
REAR: tuple[str, ...] = ("rl", "rr")
LEFT: tuple[str, ...] = ("fl", "rl")
RIGHT: tuple[str, ...] = ("fr", "rr")

#: Signs of ``(x, y, z, rx, ry, rz)`` under the mirror image y -> -y.
MIRROR: tuple[float, ...] = (1.0, -1.0, 1.0, -1.0, 1.0, -1.0)


def check_wheels(wheels: Iterable[str] | str, what: str = "wheel") -> tuple[str, ...]:
    """Validate wheel names; returns them in the order of :data:`WHEELS`.

    Raises
    ------
    DOFError
        For an unknown or repeated name, naming the allowed ones.
    """
    if isinstance(wheels, str):
        wheels = [wheels]
    given = list(wheels)
    bad = [w for w in given if w not in WHEELS]
    if bad or len(set(given)) != len(given):
        raise DOFError(
            f"unknown or repeated {what} {bad or given!r}; allowed: {', '.join(WHEELS)} "
            "(front/rear, left/right)"
        )
    return tuple(w for w in WHEELS if w in given)


def side_of(wheel: str) -> int:
    """+1 for a left wheel, -1 for a right one (the sign of its y coordinate)."""
    check_wheels(wheel)
    return 1 if wheel in LEFT else -1


def hub_labels(wheel: str, directions: Sequence[str] = DIRECTIONS) -> tuple[str, ...]:
    """Tire-side hub DOFs of a wheel, ``hub_<w>:x`` ... (vehicle axes), in ``directions``."""
    check_wheels(wheel)
    return node_labels(f"hub_{wheel}", directions)


def spindle_labels(wheel: str, directions: Sequence[str] = DIRECTIONS) -> tuple[str, ...]:
    """Vehicle-side hub coupling DOFs of a wheel, ``spindle_<w>:x`` ..., in ``directions``."""
    check_wheels(wheel)
    return node_labels(f"spindle_{wheel}", directions)


def road_label(wheel: str) -> str:
    """The road input under a wheel's contact patch, ``road_<w>`` (per metre of road)."""
    check_wheels(wheel)
    return f"road_{wheel}"


def mirror_signs(directions: Sequence[str] = DIRECTIONS) -> FloatArray:
    """The signs of :data:`MIRROR` for the given directions, shape ``(len(directions),)``."""
    return np.array([MIRROR[DIRECTIONS.index(d)] for d in directions])
