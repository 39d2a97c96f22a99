"""What a tire mode looks like: the belt's geometry from the physical DOFs.

The tire's physical DOFs (:mod:`.ring`) are the rim's 6 hub DOFs (vehicle axes), the
belt's Ritz coordinates (family ``f``, circumferential order ``n``, ``cos`` or ``sin``;
labels ``belt.<family>.n<nn><c|s>``) and the tread's slip states. This module turns a
vector of them into the displaced belt surface in wheel axes and measures the vector's
content per family and order:

* belt surface point at ``(theta, y)``: ``R e_r(theta) + y e_y``, displaced by the
  tangential, lateral and radial fields ``u e_theta + v e_y + w e_r`` of the Ritz
  expansion (``e_r = (cos theta, 0, -sin theta)``, ``e_theta = (-sin theta, 0,
  -cos theta)``, wheel axes x forward, y left, z up; the patch centre at
  ``theta = pi / 2``). The belt coordinates are absolute displacements (the sidewall
  springs act on belt minus rim);
* the rigid rim at radius ``rim_radius`` moves with the hub:
  ``t + r x p`` with the hub's translation ``t`` and rotation ``r`` in wheel axes
  (``Q^T`` of the vehicle-axes hub DOFs, :func:`.ring.wheel_rotation`);
* content of order ``n`` of family ``f``: the share of ``sum m_i |q_i|^2`` (``m_i`` the
  belt coordinate's generalised mass) in its ``cos`` / ``sin`` pair; its travelling
  index ``2 Im(conj(q_c) q_s) / (|q_c|^2 + |q_s|^2)`` is -1 for a wave running with the
  spin (forward), +1 against it (:func:`fbs_core.analysis.travelling_index`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray, IntArray
from ..errors import FBSError
from ..vocabulary import DIRECTIONS
from .params import DEFAULT_PARAMETERS, FAMILIES, TireParameters
from .ring import _basis, _fields, wheel_rotation

__all__ = ["BeltCoordinates", "belt_coordinates", "belt_surface", "dominant", "order_content"]

_LABEL = re.compile(r"^belt\.(\w+)\.n(\d+)([cs]?)$")


@dataclass(frozen=True, eq=False)
class BeltCoordinates:
    """Where the belt's Ritz coordinates sit among a system's DOFs.

    Attributes
    ----------
    index : ndarray of int, shape (n_b,)
        Rows of the belt coordinates in the DOF vector.
    family : ndarray of int, shape (n_b,)
        Index into :data:`fbs_core.tire.FAMILIES`.
    order : ndarray of int, shape (n_b,)
        Circumferential order ``n``.
    kind : ndarray of int, shape (n_b,)
        0 for ``cos n theta`` (and ``n = 0``), 1 for ``sin n theta``.
    hub : ndarray of int, shape (6,)
        Rows of ``hub:x`` ... ``hub:rz`` (vehicle axes).
    """

    index: IntArray
    family: IntArray
    order: IntArray
    kind: IntArray
    hub: IntArray


def belt_coordinates(dofs: ArrayLike, prefix: str = "") -> BeltCoordinates:
    """Find the belt coordinates and the hub DOFs among labelled DOFs.

    Parameters
    ----------
    dofs : sequence of str
        DOF labels, e.g. of ``tire.system(v)``, or of an assembled system with
        ``prefix="tire/"``.
    prefix : str
        Prefix of the tire's labels.

    Raises
    ------
    FBSError
        If there are no belt coordinates or not all six hub DOFs.
    """
    labels = [str(d) for d in np.asarray(dofs, dtype=object)]
    idx, fam, order, kind = [], [], [], []
    for i, d in enumerate(labels):
        if not d.startswith(prefix):
            continue
        m = _LABEL.match(d[len(prefix) :])
        if m and m.group(1) in FAMILIES:
            idx.append(i)
            fam.append(FAMILIES.index(m.group(1)))
            order.append(int(m.group(2)))
            kind.append(1 if m.group(3) == "s" else 0)
    pos = {d: i for i, d in enumerate(labels)}
    hub = [pos.get(f"{prefix}hub:{d}", -1) for d in DIRECTIONS]
    if not idx or min(hub) < 0:
        raise FBSError(
            f"no belt coordinates ('{prefix}belt.<family>.n<order>c|s') or not all six "
            f"'{prefix}hub:*' DOFs among the DOFs"
        )
    a = (np.array(x, np.intp) for x in (idx, fam, order, kind, hub))
    return BeltCoordinates(*a)


def order_content(
    x: ArrayLike, coords: BeltCoordinates, mass: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """Share of every (family, order) in the belt part of vectors, and its travelling index.

    Parameters
    ----------
    x : array_like, shape (n_dof,) or (n_dof, n_v)
        Complex DOF vectors (e.g. mode shapes as columns).
    coords : BeltCoordinates
    mass : array_like, shape (n_dof,), optional
        Generalised masses (the diagonal of ``M``); default 1.

    Returns
    -------
    content : ndarray, shape (n_v, n_families, n_max + 1)
        ``sum m |q|^2`` of each family and order over that of the belt (sums to 1).
    travelling : ndarray, shape (n_v, n_families, n_max + 1)
        Travelling index of each order's cos / sin pair (0 where it has no content or
        for ``n = 0``).
    """
    X = np.asarray(x)
    X = X[:, None] if X.ndim == 1 else X
    q = X[coords.index]  # (n_b, n_v)
    m = np.ones(coords.index.size) if mass is None else np.asarray(mass, float)[coords.index]
    e = m[:, None] * np.abs(q) ** 2
    n_max = int(coords.order.max())
    flat = np.zeros((len(FAMILIES) * (n_max + 1), X.shape[1]))
    np.add.at(flat, coords.family * (n_max + 1) + coords.order, e)  # per (family, order)
    content = flat.T.reshape(X.shape[1], len(FAMILIES), n_max + 1)
    tot = content.sum(axis=(1, 2), keepdims=True)
    content = content / np.where(tot > 0, tot, 1.0)
    trav = np.zeros_like(content)
    trip = zip(coords.family, coords.order, coords.kind, strict=True)
    key = {(f, n, k): i for i, (f, n, k) in enumerate(trip)}
    for (f, n, k), i in key.items():
        j = key.get((f, n, 1))
        if k != 0 or n == 0 or j is None:
            continue
        qc, qs = q[i], q[j]
        den = np.abs(qc) ** 2 + np.abs(qs) ** 2
        trav[:, f, n] = np.where(
            den > 0, 2 * np.imag(np.conj(qc) * qs) / np.where(den > 0, den, 1), 0
        )
    return content, trav


def belt_surface(
    x: ArrayLike,
    coords: BeltCoordinates,
    theta: ArrayLike,
    y: ArrayLike,
    params: TireParameters = DEFAULT_PARAMETERS,
    rim_radius: float | None = None,
) -> tuple[FloatArray, ComplexArray, FloatArray, ComplexArray]:
    """Undeformed belt and rim points and their complex displacements, wheel axes.

    Parameters
    ----------
    x : array_like, shape (n_dof,)
        Complex DOF vector (a mode shape, an operating deflection shape).
    coords : BeltCoordinates
    theta : array_like, shape (n_t,)
        Angles (rad, from forward about +y; the patch centre at ``pi / 2``).
    y : array_like, shape (n_y,)
        Lateral positions across the belt width (m).
    params : TireParameters
        The tire's parameters (radius, width, families and orders).
    rim_radius : float, optional
        Radius of the rim circle drawn (default 0.6 R).

    Returns
    -------
    belt : ndarray, shape (n_t, n_y, 3)
        Undeformed belt points (m, wheel axes, from the wheel centre).
    d_belt : ndarray, shape (n_t, n_y, 3)
        Their complex displacements (same units as ``x``).
    rim : ndarray, shape (n_t, 3)
        Undeformed rim circle.
    d_rim : ndarray, shape (n_t, 3)
        Its complex displacement (rigid with the hub).
    """
    X = np.asarray(x)
    th = np.asarray(theta, float).ravel()
    yy = np.asarray(y, float).ravel()
    b = _basis(params)
    if b.size != coords.index.size:
        raise FBSError(
            f"{coords.index.size} belt coordinates among the DOFs, the parameters' basis "
            f"has {b.size}"
        )
    F = _fields(params, b, th, yy)  # rows theta-major: (n_t * n_y, n_b)
    # the basis of the parameters is in the order of the system's belt labels
    q = X[coords.index]
    u, v, w = (F[k] @ q for k in ("u", "v", "w"))
    c, s = np.cos(th)[:, None], np.sin(th)[:, None]
    shape = (th.size, yy.size)
    u, v, w = (a.reshape(shape) for a in (u, v, w))
    d = np.stack([u * -s + w * c, v, u * -c + w * -s], axis=-1)
    R = params.R
    belt = np.stack(
        [
            np.broadcast_to(R * c, shape),
            np.broadcast_to(yy[None, :], shape),
            np.broadcast_to(-R * s, shape),
        ],
        axis=-1,
    )
    Q = wheel_rotation(params)
    hub = X[coords.hub]
    t_w, r_w = Q.T @ hub[:3], Q.T @ hub[3:]
    rr = 0.6 * R if rim_radius is None else float(rim_radius)
    rim = np.stack([rr * np.cos(th), np.zeros_like(th), -rr * np.sin(th)], axis=-1)
    d_rim = t_w[None, :] + np.cross(r_w[None, :], rim)
    return belt, d, rim, d_rim


def dominant(content: FloatArray, travelling: FloatArray) -> tuple[Any, Any, Any, Any]:
    """Dominant family, order, its content share and the label of its direction.

    Parameters
    ----------
    content, travelling : ndarray, shape (n_v, n_families, n_max + 1)
        From :func:`order_content`.

    Returns
    -------
    family : ndarray of str, shape (n_v,)
    order : ndarray of int, shape (n_v,)
    share : ndarray, shape (n_v,)
    direction : ndarray of str, shape (n_v,)
        ``"forward"`` (tau < -0.2), ``"backward"`` (> 0.2), else ``"standing"``.
    """
    n_v = content.shape[0]
    flat = content.reshape(n_v, -1)
    k = np.argmax(flat, axis=1)
    f, n = np.unravel_index(k, content.shape[1:])
    tau = travelling.reshape(n_v, -1)[np.arange(n_v), k]
    direction = np.where(tau < -0.2, "forward", np.where(tau > 0.2, "backward", "standing"))
    return np.array(FAMILIES, dtype=object)[f].astype(str), n, flat[np.arange(n_v), k], direction
