"""The virtual point transformation of a measured FRF set (de Klerk, Rixen & Voormeeren
2008; van der Seijs, van den Bosch, Rixen & de Klerk, IMAC 2015).

Responses ``u`` (n_s sensor channels) and forces ``f`` (n_i impacts) are projected on the
interface displacement modes (IDMs) ``R_u``, ``R_f`` (:mod:`.geometry`) by weighted least
squares (IMAC 2015 eqs. 5-9):

    ``q = T_u u``,  ``T_u = (R_u^T W_u R_u)^-1 R_u^T W_u``
    ``f = T_f^T m``, ``T_f = (R_f^T W_f R_f)^-1 R_f^T W_f``

so that the virtual point's mobility (or receptance, accelerance: the quantity of the
measured set) is ``Y_qm = T_u Y T_f^T`` (IMAC 2015 eq. 10), 6 x 6 per line for the rigid
IDMs, and the transfer from the virtual point to any other measured channel ``b`` (a
bushing) is ``Y_bm T_f^T``. A point that is observed but cannot be measured directly (the
bushing's rotations) gets a second virtual point on the response side only,
``q_b = T_u,b Y_sb`` over whatever inputs the set has (IMAC 2015 eqs. 5-6 and 10 with
``T_f = I``), so that its transfer from the spindle is ``T_u,b Y_sb,m T_f^T``. The result
is an :class:`~fbs_core.frf.FRF` labelled ``spindle:x`` .. ``spindle:rz`` (and the other
channels), ready for
:class:`~fbs_core.chassis.FRFChassis` and :func:`~fbs_core.coupling.couple_response`.

:func:`transformation` and :func:`vpt_kernel` are the array kernels; :func:`virtual_point`
the labelled API that checks the geometry, the channels and their units first;
:func:`response_kernel` and :func:`response_point` the same for the response side alone.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray
from ..dofs import parse_label
from ..errors import DataFormatError, DOFError, GeometryError, QuantityError
from ..frf import FRF
from ..vocabulary import readonly
from .geometry import Channels, Layout, check_observable, displacement_modes
from .quality import Consistency, consistency, leverage, response_consistency

__all__ = [
    "transformation",
    "vpt_kernel",
    "virtual_point",
    "VirtualPoint",
    "response_kernel",
    "response_point",
    "ResponsePoint",
]


def _weights(w: ArrayLike | None, n: int, what: str) -> FloatArray:
    if w is None:
        return np.eye(n)
    a = np.asarray(w, float)
    if a.ndim == 1:
        a = np.diag(a)
    if a.shape != (n, n):
        raise DataFormatError(
            f"{what} weights have shape {a.shape}; give {n} values (one per channel) or an "
            f"{n} x {n} matrix"
        )
    if not np.all(np.isfinite(a)) or not np.allclose(a, a.T):
        raise DataFormatError(f"{what} weights must be finite and symmetric")
    if np.linalg.eigvalsh(a).min() <= 0:
        raise DataFormatError(f"{what} weights must be positive definite (all weights > 0)")
    return a


def transformation(R: ArrayLike, weights: ArrayLike | None = None) -> FloatArray:
    """Weighted least-squares transformation ``T = (R^T W R)^-1 R^T W`` (IMAC 2015 eq. 6).

    Parameters
    ----------
    R : array_like, shape (n, m)
        Interface displacement modes of the channels (m = 6 rigid, plus extra ones).
    weights : array_like, shape (n,) or (n, n), optional
        Channel weights ``W`` (default identity: ordinary least squares).

    Returns
    -------
    ndarray, shape (m, n)
        ``T`` with ``T R = I``: a response that is exactly ``R q`` gives back ``q``.

    Examples
    --------
    >>> import numpy as np
    >>> R = np.vstack([np.eye(2), [[1.0, 1.0]]])
    >>> (transformation(R) @ R).round(12).tolist()
    [[1.0, 0.0], [0.0, 1.0]]
    """
    Ra = np.asarray(R, float)
    W = _weights(weights, Ra.shape[0], "channel")
    RtW = Ra.T @ W
    T: FloatArray = np.linalg.solve(RtW @ Ra, RtW)
    return T


def vpt_kernel(Y: ArrayLike, Tu: ArrayLike, Tf: ArrayLike) -> ComplexArray:
    """``Y_qm = T_u Y T_f^T`` on every line (IMAC 2015 eq. 10).

    Parameters
    ----------
    Y : array_like, shape (n_freq, n_s, n_i)
        Measured FRFs, sensor channels by impacts.
    Tu : array_like, shape (m_u, n_s)
        Response transformation (rows: virtual DOFs; or any other output mapping).
    Tf : array_like, shape (m_f, n_i)
        Force transformation.

    Returns
    -------
    ndarray, shape (n_freq, m_u, m_f)
    """
    Ya = np.asarray(Y)
    # one (n_freq * n_s, n_i) x (n_i, m_f) product, then the left one: two BLAS calls
    n_f, n_s, n_i = Ya.shape
    right = (Ya.reshape(n_f * n_s, n_i) @ np.asarray(Tf).T).reshape(n_f, n_s, -1)
    out: ComplexArray = np.matmul(np.asarray(Tu, float), right)
    return out


@dataclass(frozen=True, eq=False)
class VirtualPoint:
    """A transformed measurement: the virtual point's FRF and how consistent it was.

    Attributes
    ----------
    frf : FRF
        Outputs ``node:x .. node:rz`` then the transfer channels; inputs ``node:x ..
        node:rz``; the quantity of the measured set.
    layout : Layout
    Tu, Tf : ndarray
        The transformations (6 x n_s, 6 x n_i; more rows with extra IDMs).
    consistency : Consistency
        Sensor and impact consistency, overall and per channel, per line.
    extra : FRF or None
        With extra (flexible) IDMs: the whole transformed FRF over all IDMs.
    """

    frf: FRF
    layout: Layout
    Tu: FloatArray
    Tf: FloatArray
    consistency: Consistency
    extra: FRF | None = None

    @property
    def sensor_leverage(self) -> dict[str, float]:
        """Leverage of each sensor channel (:func:`.quality.leverage`): near 1, the channel
        alone observes a rigid-body motion and no indicator can check it."""
        Ru = displacement_modes(
            self.layout.sensors.positions, self.layout.sensors.directions, self.layout.origin
        )
        return dict(zip(self.layout.sensors.labels, leverage(Ru, self.Tu[:6]), strict=True))

    @property
    def impact_leverage(self) -> dict[str, float]:
        """Leverage of each impact channel (see :attr:`sensor_leverage`)."""
        Rf = displacement_modes(
            self.layout.impacts.positions, self.layout.impacts.directions, self.layout.origin
        )
        return dict(zip(self.layout.impacts.labels, leverage(Rf, self.Tf[:6]), strict=True))


def response_kernel(Y: ArrayLike, Tu: ArrayLike) -> ComplexArray:
    """``q = T_u Y`` on every line: the response side of IMAC 2015 eq. 10 (``T_f = I``).

    Parameters
    ----------
    Y : array_like, shape (n_freq, n_s, n_i)
        Measured FRFs, the point's sensor channels by any inputs.
    Tu : array_like, shape (m, n_s)
        Response transformation (:func:`transformation` of the sensors' IDMs).

    Returns
    -------
    ndarray, shape (n_freq, m, n_i)
        The virtual point's responses to the same inputs.

    Examples
    --------
    >>> import numpy as np
    >>> response_kernel(np.ones((1, 2, 3)), [[0.5, 0.5]]).shape
    (1, 1, 3)
    """
    out: ComplexArray = np.matmul(np.asarray(Tu, float), np.asarray(Y))
    return out


def _check_kinds(Y: FRF, sensors: list[str], impacts: list[str]) -> None:
    kinds_o = dict(zip(Y.outputs, Y.output_kinds, strict=True))
    kinds_i = dict(zip(Y.inputs, Y.input_kinds, strict=True))
    for s in sensors:
        if kinds_o[s] != "translation":
            raise QuantityError(
                f"sensor channel {s!r} is a {kinds_o[s]} output (unit "
                f"{Y.unit(s, Y.inputs[0])}); the virtual point transformation takes "
                "translational responses (accelerometers) in one unit"
            )
    for i in impacts:
        if kinds_i[i] != "force":
            raise QuantityError(
                f"impact channel {i!r} is a {kinds_i[i]} input; the virtual point "
                "transformation takes forces (N)"
            )


def virtual_point(
    frf: FRF,
    layout: Layout,
    *,
    transfers: Iterable[str] | None = None,
    sensor_weights: ArrayLike | None = None,
    impact_weights: ArrayLike | None = None,
    extra_sensor_modes: ArrayLike | None = None,
    extra_impact_modes: ArrayLike | None = None,
) -> VirtualPoint:
    """Transform a measured FRF set to the 6 DOFs of a virtual point (IMAC 2015 eq. 10).

    Parameters
    ----------
    frf : FRF
        Measured set, ``(n_freq, n_out, n_in)``: its outputs include every sensor channel
        of ``layout``, its inputs every impact.
    layout : Layout
        Positions and directions of the sensors and impacts, and the virtual point.
    transfers : sequence of str, optional
        Other outputs of ``frf`` (e.g. ``bushing:x .. bushing:rz``) whose transfer from
        the virtual point is wanted (``Y_bm T_f^T``). Default: every output that is not a
        sensor channel.
    sensor_weights, impact_weights : array_like, optional
        Least-squares weights per channel (n,) or (n, n) (default equal).
    extra_sensor_modes, extra_impact_modes : array_like, shape (n_s, k) / (n_i, k), optional
        Flexible IDMs appended to the six rigid ones (both or neither, same k).

    Returns
    -------
    VirtualPoint
        ``.frf`` labelled ``node:x .. node:rz`` (+ transfers), ``.consistency``.

    Raises
    ------
    DOFError
        A sensor (impact) channel of the layout that the FRF lacks, or a transfer channel
        that is not an output.
    GeometryError
        Channels that do not observe the six DOFs (named), bad extra modes.
    QuantityError
        Sensor channels that are not translations, impacts that are not forces.
    """
    sensors, impacts = list(layout.sensors.labels), list(layout.impacts.labels)
    miss_o = [s for s in sensors if s not in frf.outputs]
    miss_i = [s for s in impacts if s not in frf.inputs]
    if miss_o or miss_i:
        which = (
            f"sensor channel {miss_o[0]!r} is not an output"
            if miss_o
            else f"impact channel {miss_i[0]!r} is not an input"
        )
        raise DOFError(
            f"{which} of the measured FRF ({len(miss_o)} sensor and {len(miss_i)} impact "
            f"channels of the geometry missing; the FRF has outputs {', '.join(frf.outputs[:9])}"
            f"{' ...' if len(frf.outputs) > 9 else ''})"
        )
    _check_kinds(frf, sensors, impacts)
    if transfers is None:
        others = [o for o in frf.outputs if o not in set(sensors)]
    else:
        others = list(transfers)
        bad = [o for o in others if o not in frf.outputs or o in set(sensors)]
        if bad:
            raise DOFError(f"transfer channel {bad[0]!r} is not a non-sensor output of the FRF")
    check_observable(layout.sensors, layout.origin, "sensor", layout.node)
    check_observable(layout.impacts, layout.origin, "impact", layout.node)
    Ru = displacement_modes(layout.sensors.positions, layout.sensors.directions, layout.origin)
    Rf = displacement_modes(layout.impacts.positions, layout.impacts.directions, layout.origin)
    k = 0
    if (extra_sensor_modes is None) != (extra_impact_modes is None):
        raise GeometryError("extra IDMs are needed for both the sensors and the impacts")
    if extra_sensor_modes is not None and extra_impact_modes is not None:
        Eu, Ef = np.asarray(extra_sensor_modes, float), np.asarray(extra_impact_modes, float)
        Eu = Eu[:, None] if Eu.ndim == 1 else Eu
        Ef = Ef[:, None] if Ef.ndim == 1 else Ef
        if Eu.shape[0] != len(sensors) or Ef.shape[0] != len(impacts) or Eu.shape[1] != Ef.shape[1]:
            raise GeometryError(
                f"extra IDMs of shape {Eu.shape} (sensors) and {Ef.shape} (impacts) do not fit "
                f"{len(sensors)} sensor and {len(impacts)} impact channels with the same count"
            )
        k = Eu.shape[1]
        Ru, Rf = np.hstack([Ru, Eu]), np.hstack([Rf, Ef])
        for R, n, what in ((Ru, len(sensors), "sensor"), (Rf, len(impacts), "impact")):
            if np.linalg.matrix_rank(R) < 6 + k:
                raise GeometryError(
                    f"the {n} {what} channels cannot separate the {6 + k} IDMs (6 rigid + "
                    f"{k} extra): too few channels or extra modes that are rigid motions"
                )
    Tu = transformation(Ru, sensor_weights)
    Tf = transformation(Rf, impact_weights)
    Ymeas = frf.sel(outputs=sensors, inputs=impacts)
    Y = Ymeas.data
    q = vpt_kernel(Y, Tu, Tf)
    labels = list(layout.labels)
    data = q[:, :6, :6]
    outputs = labels + others
    if others:
        Yb = frf.sel(outputs=others, inputs=impacts).data
        tb = vpt_kernel(Yb, np.eye(len(others)), Tf)
        data = np.concatenate([data, tb[:, :, :6]], axis=1)
    out = FRF(frf.freq, data, outputs, labels, frf.quantity)
    extra = None
    if k:
        names = labels + [f"{layout.node}_idm{j + 7}" for j in range(k)]
        extra = FRF(frf.freq, q, names, names, frf.quantity)
    cons = consistency(Y, Ru, Tu, Rf, Tf, sensors, impacts, frf.freq)
    return VirtualPoint(out, layout, readonly(Tu), readonly(Tf), cons, extra)


@dataclass(frozen=True, eq=False)
class ResponsePoint:
    """A virtual point on the response side only: sensors around a point, its six DOFs.

    Attributes
    ----------
    frf : FRF
        The measured set with the point's sensor channels replaced by ``node:x ..
        node:rz`` (appended after the other outputs); inputs and quantity unchanged.
    sensors : Channels
        The sensor channels transformed (positions, directions).
    origin : ndarray, shape (3,)
        The virtual point (m).
    node : str
    Tu : ndarray, shape (6, n_s)
    consistency : Consistency
        Sensor consistency, overall and per channel, over the set's inputs (no impact
        indicators: :func:`.quality.response_consistency`).
    """

    frf: FRF
    sensors: Channels
    origin: FloatArray
    node: str
    Tu: FloatArray
    consistency: Consistency

    @property
    def labels(self) -> tuple[str, ...]:
        """``node:x`` .. ``node:rz``."""
        return tuple(self.frf.outputs[-6:])

    @property
    def sensor_leverage(self) -> dict[str, float]:
        """Leverage of each sensor channel (see :attr:`VirtualPoint.sensor_leverage`)."""
        Ru = displacement_modes(self.sensors.positions, self.sensors.directions, self.origin)
        return dict(zip(self.sensors.labels, leverage(Ru, self.Tu), strict=True))


def response_point(
    frf: FRF,
    sensors: Channels,
    origin: ArrayLike,
    node: str,
    *,
    sensor_weights: ArrayLike | None = None,
) -> ResponsePoint:
    """Transform sensor channels around a point to that point's six DOFs (response side).

    The sensors around a point (e.g. three tri-axial accelerometers 5-10 cm around a
    bushing) see its rigid motion, ``u_s = R_u q + mu`` (IMAC 2015 eq. 2); the weighted
    least-squares ``q = T_u u``, ``T_u = (R_u^T W_u R_u)^-1 R_u^T W_u`` (eqs. 5-6) gives its
    translations and the rotations no sensor measures directly, for every input of the set
    (``q_b = T_u,b Y_sb,m``, eq. 10 with the inputs untransformed).

    Parameters
    ----------
    frf : FRF
        Measured set, ``(n_freq, n_out, n_in)``; its outputs include every channel of
        ``sensors`` and none at ``node``.
    sensors : Channels
        Positions and directions of the point's sensor channels.
    origin : array_like, shape (3,)
        The point (m).
    node : str
        Its node name: the result's outputs ``node:x .. node:rz``.
    sensor_weights : array_like, optional
        Least-squares weights per channel (n,) or (n, n) (default equal).

    Returns
    -------
    ResponsePoint

    Raises
    ------
    DOFError
        A sensor channel that is not an output of the FRF, or outputs already at ``node``
        (measured directly and by sensors around it: one or the other).
    GeometryError
        Channels that do not observe the six DOFs (named, with the DOFs they miss).
    QuantityError
        Sensor channels that are not translations.
    """
    labels = list(sensors.labels)
    o = np.asarray(origin, float)
    probe = Layout(sensors, sensors, o, node)  # checks the point and the node name
    miss = [s for s in labels if s not in frf.outputs]
    if miss:
        raise DOFError(
            f"sensor channel {miss[0]!r} of the virtual point {node!r} is not an output of "
            f"the measured FRF ({len(miss)} missing; the FRF has outputs "
            f"{', '.join(frf.outputs[:9])}{' ...' if len(frf.outputs) > 9 else ''})"
        )
    direct = [x for x in frf.outputs if parse_label(x)[0] == node]
    if direct:
        raise DOFError(
            f"the measured FRF has outputs at {node!r} itself ({', '.join(direct)}) and "
            f"{len(labels)} sensor channels around it ({', '.join(labels[:6])}"
            f"{' ...' if len(labels) > 6 else ''}): give one or the other, not both"
        )
    _check_kinds(frf, labels, [])
    check_observable(sensors, o, "sensor", node)
    Ru = displacement_modes(sensors.positions, sensors.directions, o)
    Tu = transformation(Ru, sensor_weights)
    Y = frf.sel(outputs=labels).data
    q = response_kernel(Y, Tu)
    keep = [x for x in frf.outputs if x not in set(labels)]
    data = np.concatenate([frf.sel(outputs=keep).data, q], axis=1) if keep else q
    out = FRF(frf.freq, data, keep + list(probe.labels), frf.inputs, frf.quantity)
    cons = response_consistency(Y, Ru, Tu, labels, frf.freq)
    return ResponsePoint(out, sensors, readonly(o), node, readonly(Tu), cons)
