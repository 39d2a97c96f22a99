"""The reference car without its tires: FE model, exact FRFs, and cars given by an FRF.

:class:`VehicleModel` is the structure of :mod:`.structure` (body, two strut
fronts, the thesis' rear axle) with its four suspension dampers. Its FRFs are
exact (no truncation):

- the hysteretic part ``K (1 + j eta) - omega^2 M`` is diagonalised once by
  complex modes (thesis table 2.1, as the single corner), in shifted-inverse form
  for accuracy at low frequencies: ``(K + s M)^-1 M = V diag(mu) V^-1`` and
  ``H_0 = V diag(1 / (1 - (omega^2 + s) mu)) V^-1 (K + s M)^-1`` (``lam = 1/mu - s``);
- the viscous dampers, ``C = B diag(c) B^T`` with one column of ``B`` per damper
  (its two end points' relative velocity along its axis), are joined to it by
  receptance coupling, i.e. the Woodbury identity
  ``H = H_0 - H_0 B (diag(1 / (j omega c)) + B^T H_0 B)^-1 B^T H_0``: the inverse
  of ``K - omega^2 M + j omega C`` with four extra unknowns per line.

The car is free-free (the tires carry it): six rigid-body modes with zero
eigenvalue, harmless at every positive frequency. :class:`FRFVehicle` is a car
given by an FRF (measured or computed elsewhere) with the same labels: hub inputs
``spindle_<w>:*`` and outputs ``spindle_<w>:*`` plus any response DOFs.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray
from ..chassis import ChassisParameters
from ..direct import SecondOrderSystem
from ..dofs import DIRECTIONS, index_of, node_labels, parse_label
from ..errors import DataFormatError, DOFError, FrequencyGridError
from ..fe import offset_transform
from ..frf import FRF, check_grid
from ..frf_model import FRFGiven, modal_sum, receptance_frf
from .layout import WHEELS, spindle_labels
from .structure import (
    RESPONSE_NODES,
    BodyParameters,
    Damper,
    FrontParameters,
    build_structure,
)

__all__ = [
    "VehicleParameters",
    "VehicleModel",
    "FRFVehicle",
    "reference_vehicle",
    "SPINDLES",
    "RESPONSES",
]

#: The hub coupling DOFs of the four wheels, ``spindle_fl:x`` ... ``spindle_rr:rz``.
SPINDLES: tuple[str, ...] = tuple(d for w in WHEELS for d in spindle_labels(w))
#: The response DOFs of the reference car (six per node of ``RESPONSE_NODES``).
RESPONSES: tuple[str, ...] = tuple(d for n in RESPONSE_NODES for d in node_labels(n))

#: Lines per chunk of the modal sums (bounds the memory of the (lines, modes, inputs) terms).
_CHUNK = 48


@dataclass(frozen=True)
class VehicleParameters:
    """Every number of the reference car (SI units, ISO 8855 vehicle axes).

    Attributes
    ----------
    body : BodyParameters
        The body grillage and its lumped masses.
    front : FrontParameters
        The two strut front corners (left given, right mirrored).
    rear : ChassisParameters
        The single corner's parameters unchanged (the thesis' corner on both sides of
        the rear subframe).
    wheel_z : float
        Height of the wheel centres above the ground (the loaded tire radius), m.
    rear_damper_offset : (float, float, float)
        Lower end of the rear damper on the carrier, from the wheel centre (left), m;
        its upper end is the body's rear tower.
    rear_damper : float
        Rear damper coefficient, N s/m.
    """

    body: BodyParameters = field(default_factory=BodyParameters)
    front: FrontParameters = field(default_factory=FrontParameters)
    rear: ChassisParameters = field(default_factory=ChassisParameters)
    wheel_z: float = 0.30
    rear_damper_offset: tuple[float, float, float] = (-0.05, -0.07, -0.08)
    rear_damper: float = 1500.0


@dataclass(frozen=True, eq=False)
class _Structure:
    system: SecondOrderSystem
    dampers: tuple[Damper, ...]
    B: FloatArray  # (n, n_d) damper directions
    c: FloatArray  # (n_d,)
    xyz: dict[str, tuple[float, float, float]]


@dataclass(frozen=True, eq=False)
class _Modal:
    lam: ComplexArray  # (n_m,) eigenvalues omega_r^2 (1 + j eta_r)
    mu: ComplexArray  # (n_m,) eigenvalues of (K + sigma M)^-1 M
    V: ComplexArray  # (n, n_m) right shapes
    W: ComplexArray  # (n_m, n) V^-1 (K + sigma M)^-1
    BV: ComplexArray  # (n_d, n_m)
    WB: ComplexArray  # (n_m, n_d)


def _damper_matrix(dofs: Sequence[str], dampers: Sequence[Damper]) -> FloatArray:
    """``B`` (n, n_d): column d maps the DOFs to damper d's relative velocity."""
    pos = {lab: i for i, lab in enumerate(dofs)}
    B = np.zeros((len(dofs), len(dampers)))
    for k, d in enumerate(dampers):
        e = np.asarray(d.axis, float)
        for node, offset, sign in ((d.a, d.offset_a, -1.0), (d.b, d.offset_b, 1.0)):
            idx = [pos[f"{node}:{x}"] for x in DIRECTIONS]
            B[idx, k] += sign * offset_transform(offset)[:3].T @ e
    return B


@functools.lru_cache(maxsize=4)
def _structure(p: VehicleParameters) -> _Structure:
    """The FE system ``M, C = B diag(c) B^T, K (1 + j eta)`` of the car without tires."""
    fe, dampers = build_structure(
        p.body, p.front, p.rear, p.wheel_z, p.rear_damper_offset, p.rear_damper
    )
    s0 = fe.system()
    B = _damper_matrix(s0.dofs, dampers)
    c = np.array([d.c for d in dampers])
    C = sp.csc_matrix(B @ np.diag(c) @ B.T)
    s = SecondOrderSystem(s0.M, C, s0.K, s0.dofs)
    for a in (B, c):
        a.setflags(write=False)
    xyz = {n: (float(v[0]), float(v[1]), float(v[2])) for n in fe.nodes for v in [fe.xyz(n)]}
    return _Structure(s, dampers, B, c, xyz)


#: Shift of the modal decomposition, (rad/s)^2: (2 pi 10 Hz)^2.
SHIFT = (2 * np.pi * 10.0) ** 2


@functools.lru_cache(maxsize=4)
def _modal(p: VehicleParameters) -> _Modal:
    """Complex modes of the shifted-inverse problem and the damper terms.

    With ``Z(w) = K (1 + j eta) - w^2 M = (K + s M) - (w^2 + s) M`` and
    ``(K + s M)^-1 M = V diag(mu) V^-1``,
    ``Z^-1 = V diag(1 / (1 - (w^2 + s) mu)) V^-1 (K + s M)^-1`` exactly. The low modes
    are the large ``mu`` of this problem, so their shapes come out as accurate as the
    stiffest modes' (in ``M^-1 K`` they are the smallest eigenvalues of a matrix whose
    norm the stiff short elements set: 3e-9 instead of 3e-11 at 14 Hz); ``s > 0`` makes
    ``K + s M`` regular although the car is free. ``lam_r = 1 / mu_r - s``.
    """
    st = _structure(p)
    K, M = st.system.K.toarray(), st.system.M.toarray()
    lu = sla.lu_factor(K + SHIFT * M)
    mu, V = np.linalg.eig(sla.lu_solve(lu, M))
    lam: ComplexArray = (1.0 / mu - SHIFT).astype(complex)
    order = np.argsort(lam.real)
    lam, mu, V = lam[order], mu[order], V[:, order]
    Vinv = np.linalg.inv(V)
    W = sla.lu_solve(lu, Vinv.T, trans=1).T  # V^-1 (K + s M)^-1
    BV: ComplexArray = (st.B.T @ V).astype(complex)
    WB: ComplexArray = (W @ st.B).astype(complex)
    for a in (lam, mu, V, W, BV, WB):
        a.setflags(write=False)
    return _Modal(lam, mu, V, W, BV, WB)


@functools.lru_cache(maxsize=32)
def _synth(
    p: VehicleParameters, fbytes: bytes, outputs: tuple[str, ...], inputs: tuple[str, ...]
) -> ComplexArray:
    """Receptance ``(n_f, n_out, n_in)``: modal sum plus the dampers (Woodbury)."""
    md, st = _modal(p), _structure(p)
    dofs = st.system.dofs
    oi = index_of(dofs, outputs, "vehicle output DOF")
    ii = index_of(dofs, inputs, "vehicle input DOF")
    w = 2 * np.pi * np.frombuffer(fbytes, float)
    no, ni, nd = len(oi), len(ii), st.c.size
    Vx = np.concatenate([md.V[oi], md.BV])  # (n_o + n_d, n_m)
    Wx = np.concatenate([md.W[:, ii], md.WB], axis=1)  # (n_m, n_i + n_d)
    out = np.empty((w.size, no, ni), complex)
    for a in range(0, w.size, _CHUNK):
        wc = w[a : a + _CHUNK]
        g = 1.0 / (1.0 - (wc[:, None] ** 2 + SHIFT) * md.mu[None, :])  # (n_c, n_m)
        G = modal_sum(g, Vx, Wx)  # (n_c, n_o + n_d, n_i + n_d)
        Hoi, HoB = G[:, :no, :ni], G[:, :no, ni:]
        HBi, HBB = G[:, no:, :ni], G[:, no:, ni:]
        S = HBB + np.eye(nd)[None] / (1j * wc[:, None, None] * st.c[None, None, :])
        out[a : a + _CHUNK] = Hoi - HoB @ np.linalg.solve(S, HBi)
    out.setflags(write=False)
    return out


class VehicleModel:
    """The reference car without tires: body, two strut fronts, the thesis' rear axle.

    Parameters
    ----------
    params : VehicleParameters, optional
        Default: the shipped reference car.

    Examples
    --------
    >>> car = VehicleModel()                      # doctest: +SKIP
    >>> Y = car.mobility([20.0, 40.0])            # doctest: +SKIP
    >>> Y.shape                                   # doctest: +SKIP
    (2, 84, 24)
    """

    def __init__(self, params: VehicleParameters | None = None) -> None:
        self._p = VehicleParameters() if params is None else params

    @property
    def params(self) -> VehicleParameters:
        return self._p

    def __repr__(self) -> str:
        return f"VehicleModel({self.system().n} DOFs, {len(self.dampers)} dampers)"

    @property
    def wheelbase(self) -> float:
        """Front minus rear hub x coordinate, m."""
        xyz = _structure(self._p).xyz
        return float(xyz["spindle_fl"][0] - xyz["spindle_rl"][0])

    @property
    def track(self) -> tuple[float, float]:
        """Front and rear track (distance of the wheel centres in y), m."""
        xyz = _structure(self._p).xyz
        return (2 * xyz["spindle_fl"][1], 2 * xyz["spindle_rl"][1])

    def xyz(self, node: str) -> tuple[float, float, float]:
        """Coordinates of a node in vehicle axes, m."""
        xyz = _structure(self._p).xyz
        if node not in xyz:
            raise DOFError(f"unknown vehicle node {node!r}; e.g. {', '.join(list(xyz)[:8])}")
        return xyz[node]

    @property
    def dampers(self) -> tuple[Damper, ...]:
        return _structure(self._p).dampers

    def system(self) -> SecondOrderSystem:
        """``M x'' + C x' + K (1 + j eta) x = f``: sparse, C the four dampers."""
        return _structure(self._p).system

    def eigenvalues(self) -> ComplexArray:
        """Complex eigenvalues ``lam_r = omega_r^2 (1 + j eta_r)`` of the undamped-by-
        dampers structure (hysteretic only), sorted by real part; six near zero."""
        return _modal(self._p).lam

    def eigenfrequencies(self) -> FloatArray:
        """``sqrt(Re lam_r) / 2 pi`` in Hz (rigid-body modes: 0)."""
        return np.sqrt(np.maximum(self.eigenvalues().real, 0.0)) / (2 * np.pi)

    def mobility(
        self,
        freq: ArrayLike,
        outputs: Iterable[str] | None = None,
        inputs: Iterable[str] | None = None,
        quantity: str = "mobility",
    ) -> FRF:
        """Exact FRFs of the car without tires on any grid of positive frequencies.

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz, strictly increasing and positive (the car is free).
        outputs, inputs : sequence of str, optional
            Default outputs :data:`SPINDLES` then :data:`RESPONSES`; inputs
            :data:`SPINDLES`.
        quantity : {"receptance", "mobility", "accelerance"}

        Returns
        -------
        FRF, shape (n_freq, n_out, n_in)

        Raises
        ------
        FrequencyGridError, DOFError, QuantityError
        """
        f = check_grid(freq)
        if f[0] <= 0:
            raise FrequencyGridError(
                "the car without tires is free (rigid-body modes): frequencies must be > 0 Hz"
            )
        outs = SPINDLES + RESPONSES if outputs is None else tuple(outputs)
        ins = SPINDLES if inputs is None else tuple(inputs)
        return receptance_frf(
            f, outs, ins, quantity, lambda: _synth(self._p, f.tobytes(), outs, ins)
        )

    def to_dict(self) -> dict[str, Any]:
        """The parameters as a plain nested dict (for storage)."""
        return asdict(self._p)


@functools.lru_cache(maxsize=1)
def reference_vehicle() -> VehicleModel:
    """The shipped reference car without tires (see :class:`VehicleParameters`)."""
    return VehicleModel()


def _hub_labels(labels: Iterable[str]) -> list[str]:
    """The labels of hub DOFs, ``spindle_<w>:<d>``, in their order."""
    return [lab for lab in labels if parse_label(lab)[0].startswith("spindle_")]


class FRFVehicle(FRFGiven):
    """A car without tires given by an FRF, used like :class:`VehicleModel`.

    The FRF must hold the hub inputs ``spindle_<w>:<d>`` of the four wheels (at least
    the coupled directions) and the same labels among its outputs, plus the response
    DOFs. Frequencies it has no line at are refused unless ``interpolate=True``
    (:meth:`FRF.interpolate`, explicit, as :class:`fbs_core.chassis.FRFChassis`).

    Parameters
    ----------
    frf : FRF
        E.g. ``fbs_core.load_frf("car.unv", nodes={1: "spindle_fl", ...})``.
    wheelbase : float
        Front minus rear axle position, m (the road delay of the rear wheels).
    track : float or (float, float)
        Track in m (front, rear); the coherence of an isotropic road uses it.
    interpolate : bool
        Interpolate onto frequencies the FRF has no line at.

    Raises
    ------
    DOFError
        When a hub DOF is missing, naming it.
    DataFormatError
        For a wheelbase or track that is not a positive length.
    """

    def __init__(
        self,
        frf: FRF,
        wheelbase: float,
        track: float | tuple[float, float],
        interpolate: bool = False,
    ) -> None:
        tr = (float(track), float(track)) if np.isscalar(track) else tuple(map(float, track))  # type: ignore[arg-type, unused-ignore]
        if not (np.isfinite(wheelbase) and wheelbase > 0) or len(tr) != 2 or min(tr) <= 0:
            raise DataFormatError(
                f"wheelbase and track must be positive lengths in m, got {wheelbase!r}, {track!r}"
            )
        hubs = _hub_labels(frf.inputs)
        wheels = {parse_label(lab)[0][len("spindle_") :] for lab in hubs}
        missing = [w for w in WHEELS if w not in wheels]
        if missing:
            raise DOFError(
                f"the vehicle FRF has no hub inputs of wheel(s) {', '.join(missing)}: expected "
                f"inputs spindle_<w>:x ... for w in {', '.join(WHEELS)}; inputs: "
                f"{', '.join(frf.inputs[:12])}{' ...' if len(frf.inputs) > 12 else ''}"
            )
        super().__init__(frf, interpolate)
        self.wheelbase = float(wheelbase)
        self.track: tuple[float, float] = (tr[0], tr[1])

    def __repr__(self) -> str:
        return f"FRFVehicle({self.frf!r}, wheelbase={self.wheelbase:g}, track={self.track})"

    @property
    def responses(self) -> tuple[str, ...]:
        """The outputs that are not hub DOFs."""
        return tuple(o for o in self.frf.outputs if not parse_label(o)[0].startswith("spindle_"))

    def mobility(
        self,
        freq: ArrayLike,
        outputs: Iterable[str] | None = None,
        inputs: Iterable[str] | None = None,
        quantity: str = "mobility",
    ) -> FRF:
        """The FRF on ``freq`` (Hz): its own lines, else interpolated if allowed.

        ``freq`` must be a valid grid (:func:`fbs_core.frf.check_grid`); by default every
        output and the hub inputs.

        Raises
        ------
        FrequencyGridError
            For an invalid grid, or when a frequency is not a line of the FRF and
            ``interpolate`` is False.
        """
        return super().mobility(check_grid(freq), outputs, inputs, quantity)

    def _refusal(self, f: FloatArray, missing: FloatArray) -> str:
        """Names the FRF's and the analysis' band and how to interpolate."""
        F = self.frf.freq
        return (
            f"the vehicle FRF ({F.size} lines, {F[0]:g}-{F[-1]:g} Hz) has no line at some "
            f"of the {f.size} analysis frequencies {f[0]:g}-{f[-1]:g} Hz; pass "
            "interpolate=True to interpolate it explicitly (linear in real and imaginary "
            "part) or analyse on its own lines"
        )

    def _default_dofs(self) -> tuple[Sequence[str], Sequence[str]]:
        """Every output of the FRF; its hub inputs ``spindle_<w>:*``."""
        return list(self.frf.outputs), _hub_labels(self.frf.inputs)
