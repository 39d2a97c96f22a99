"""Reference rear-corner chassis: a flexible FE model built from physics (thesis ch. 4.1.1).

The thesis coupled its tire to a proprietary Volvo rear-chassis FE model whose
spindle-to-bushing mobility shows eigenfrequencies at about 14, 37 and 47 Hz
(thesis fig. 4.2). This module ships a replacement that can be derived and
checked: a left rear corner in vehicle coordinates (ISO 8855: x forward, y left,
z up; origin at the subframe centre), made of

- a rigid wheel carrier (knuckle) whose reference node is the wheel centre
  ``spindle`` (the hub coupling node, 6 DOFs);
- a 6x6 link bushing (compliance of the links, the coil spring and their
  rubber mounts, hysteretic) between the carrier and the apex of a flexible
  A-arm (two steel tubes, Euler-Bernoulli beams) that is welded to the subframe;
- a flexible subframe: a rectangular frame of steel box sections with two
  lumped masses (mounting brackets) on the cross members;
- four rubber bushings with hysteretic damping from the subframe corners to the
  body, which is taken as rigid (grounded). The front-left corner is the
  chosen bushing node ``bushing`` (thesis fig. 4.1).

The link-bushing stiffnesses were tuned (``scripts/build_reference_chassis.py``)
so that the three eigenfrequencies of the thesis are hit within 0.1 Hz; the
flexible arm and subframe add modes from about 100 Hz up. The layout started
from the rigid-body model of ``docs/chassis-model.md``. Hysteretic damping has no
``omega`` in its damping term, so ``(K (1 + j eta) - omega^2 M)`` is diagonalised
once by complex modes and every FRF is an exact modal sum (no truncation).
"""

from __future__ import annotations

import functools
import os
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike

from ._typing import ComplexArray, FloatArray
from .direct import SecondOrderSystem
from .dofs import DIRECTIONS, index_of, node_labels
from .errors import DataFormatError
from .fe import FEModel, Material, Section, rigid_body_mass
from .frf import FRF, check_grid
from .frf_model import (
    FRFGiven,
    match_grid,
    modal_factors,
    modal_sum,
    read_model_frf,
    receptance_frf,
)

__all__ = [
    "ChassisParameters",
    "ChassisVariantParameters",
    "ChassisModel",
    "reference_chassis",
    "carrier_mode_table",
    "modal_energy",
    "read_chassis_frf",
    "FRFChassis",
    "match_grid",
    "SPINDLE",
    "BUSHING",
]

#: DOF labels of the hub coupling node and of the chosen bushing node.
SPINDLE: tuple[str, ...] = node_labels("spindle")
BUSHING: tuple[str, ...] = node_labels("bushing")


@dataclass(frozen=True)
class ChassisParameters:
    """Every number of the reference chassis (SI units, vehicle coordinates).

    The defaults are the shipped, tuned model. Stiffness tuples are
    ``(x, y, z, rx, ry, rz)`` in N/m and N m/rad.
    """

    # wheel carrier (knuckle + hub bearing + brake disc/caliper)
    carrier_mass: float = 18.0
    carrier_inertia: tuple[float, float, float] = (0.25, 0.20, 0.25)
    spindle_xyz: tuple[float, float, float] = (0.0, 0.75, 0.08)
    # link bushing between carrier and A-arm apex: stiffness in its own axes, which are
    # pitched about y by link_pitch_deg, acting at spindle_xyz + link_offset
    link_offset: tuple[float, float, float] = (-0.10, -0.05, -0.06)
    link_pitch_deg: float = 30.0
    link_stiffness: tuple[float, ...] = (1.624e5, 6.369e6, 3.0e4, 2.124e5, 2.217e4, 8.066e4)
    link_loss: float = 0.10
    arm_apex_xyz: tuple[float, float, float] = (0.0, 0.70, 0.0)
    arm_tube: tuple[float, float] = (0.035, 0.003)  # outer diameter, wall
    arm_elements: int = 4
    # subframe: rectangular frame of box sections, corners at the bushings
    subframe_half: tuple[float, float] = (0.35, 0.45)  # half length (x), half width (y)
    arm_roots_x: float = 0.20  # the arm roots sit on the left side member at x = +/- this
    side_box: tuple[float, float, float] = (0.050, 0.080, 0.003)  # b (local y), h (z), wall
    cross_box: tuple[float, float, float] = (0.050, 0.080, 0.003)
    element_length: float = 0.09
    bracket_mass: float = 8.0  # lumped at each cross-member midpoint
    bracket_inertia: tuple[float, float, float] = (0.02, 0.02, 0.02)
    steel_loss: float = 0.005
    # body bushings (each of the four), hysteretic
    bushing_stiffness: tuple[float, ...] = (1.2e6, 1.2e6, 1.6e6, 300.0, 300.0, 300.0)
    bushing_loss: float = 0.15


@dataclass(frozen=True)
class ChassisVariantParameters(ChassisParameters):
    """:class:`ChassisParameters` plus the scales of a parameter variant.

    The reference chassis is a plain :class:`ChassisParameters` (its stored parameters and
    numbers are unchanged); a variant of the corridor study (:mod:`fbs_core.variants`) may
    also change the A-arm alone:

    Attributes
    ----------
    arm_mass_scale : float
        Factor on the density of the A-arm tubes (their mass; the cross-section and so the
        stiffness unchanged), > 0.
    arm_stiffness_scale : float
        Factor on the Young's (and shear) modulus of the A-arm tubes (their axial, bending
        and torsional stiffness; the mass unchanged), > 0.
    """

    arm_mass_scale: float = 1.0
    arm_stiffness_scale: float = 1.0

    def __post_init__(self) -> None:
        for name in ("arm_mass_scale", "arm_stiffness_scale"):
            v = getattr(self, name)
            if not np.isfinite(v) or v <= 0:
                raise DataFormatError(f"chassis parameter {name} must be finite and > 0, got {v}")


STEEL_E, STEEL_NU, STEEL_RHO = 210e9, 0.3, 7850.0


def _n_el(p: ArrayLike, q: ArrayLike, h: float) -> int:
    return max(1, round(float(np.linalg.norm(np.subtract(q, p))) / h))


def build_chassis(p: ChassisParameters) -> FEModel:
    """Build the FE model of the reference chassis from its parameters."""
    steel = Material(STEEL_E, STEEL_NU, STEEL_RHO, p.steel_loss)
    m = FEModel()
    L, W = p.subframe_half
    h = p.element_length
    m.add_node("spindle", p.spindle_xyz)
    m.add_node("apex", p.arm_apex_xyz)
    corners = {
        "bushing": (L, W, 0),
        "bush_rl": (-L, W, 0),
        "bush_rr": (-L, -W, 0),
        "bush_fr": (L, -W, 0),
    }
    for name, xyz in corners.items():
        m.add_node(name, xyz)
    m.add_node("root_f", (p.arm_roots_x, W, 0))
    m.add_node("root_r", (-p.arm_roots_x, W, 0))
    m.add_node("bracket_f", (L, 0, 0))
    m.add_node("bracket_r", (-L, 0, 0))
    side, cross = Section.box(*p.side_box), Section.box(*p.cross_box)
    up = (0, 0, 1)
    # left side member (front to rear) through the arm roots, right side member
    for a, b in (
        ("bushing", "root_f"),
        ("root_f", "root_r"),
        ("root_r", "bush_rl"),
        ("bush_fr", "bush_rr"),
    ):
        m.add_beam(a, b, side, steel, _n_el(m.xyz(a), m.xyz(b), h), up, prefix=f"{a}-{b}.")
    for a, b in (
        ("bushing", "bracket_f"),
        ("bracket_f", "bush_fr"),
        ("bush_rl", "bracket_r"),
        ("bracket_r", "bush_rr"),
    ):
        m.add_beam(a, b, cross, steel, _n_el(m.xyz(a), m.xyz(b), h), up, prefix=f"{a}-{b}.")
    tube = Section.tube(*p.arm_tube)
    arm = steel
    sm, sk = getattr(p, "arm_mass_scale", 1.0), getattr(p, "arm_stiffness_scale", 1.0)
    if (sm, sk) != (1.0, 1.0):  # a variant (ChassisVariantParameters); the reference: steel
        arm = Material(STEEL_E * sk, STEEL_NU, STEEL_RHO * sm, p.steel_loss)
    for root in ("root_f", "root_r"):
        m.add_beam("apex", root, tube, arm, p.arm_elements, up, prefix=f"arm-{root}.")
    # masses
    m.add_mass("spindle", rigid_body_mass(p.carrier_mass, p.carrier_inertia))
    for b in ("bracket_f", "bracket_r"):
        m.add_mass(b, rigid_body_mass(p.bracket_mass, p.bracket_inertia))
    # springs: the link bushing acts at its elastic centre between carrier and arm apex
    c, s = np.cos(np.radians(p.link_pitch_deg)), np.sin(np.radians(p.link_pitch_deg))
    R = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])  # rows: link axes (global)
    Rb = np.kron(np.eye(2), R)
    k_link = Rb.T @ np.diag(p.link_stiffness) @ Rb
    centre = np.add(p.spindle_xyz, p.link_offset)
    m.add_spring(
        "spindle",
        "apex",
        k_link,
        p.link_loss,
        offset_a=p.link_offset,
        offset_b=centre - np.asarray(p.arm_apex_xyz),
    )
    for name in corners:
        m.add_spring(name, None, p.bushing_stiffness, p.bushing_loss)
    return m


@functools.lru_cache(maxsize=8)
def _modal(
    p: ChassisParameters,
) -> tuple[SecondOrderSystem, ComplexArray, ComplexArray, ComplexArray]:
    """Complex modes of ``M^-1 K`` (hysteretic K): ``K V = M V diag(lam)``."""
    s = build_chassis(p).system()
    K, M = s.K.toarray(), s.M.toarray()
    # M = L L^T turns K v = lam M v into the standard problem A u = lam u with
    # A = L^-1 K L^-T (complex symmetric), v = L^-T u: much cheaper than QZ.
    L = np.linalg.cholesky(M)
    A = sla.solve_triangular(L, sla.solve_triangular(L, K, lower=True).T, lower=True).T
    lam, U = np.linalg.eig(A)
    V = sla.solve_triangular(L.T, U, lower=False)
    # Rayleigh quotients on the original matrices (complex symmetric: left = right
    # vector): second-order accurate, they restore the relative accuracy of the low
    # eigenvalues that the reduction spends on the stiff high ones.
    lam = np.einsum("ir,ir->r", V, K @ V) / np.einsum("ir,ir->r", V, M @ V)
    order = np.argsort(lam.real)
    lam, U, V = lam[order], U[:, order], V[:, order]
    # left factor V^-1 M^-1 = U^-1 L^-1, so that
    # (K - w^2 M)^-1 = V diag(1 / (lam - w^2)) V^-1 M^-1
    W = np.linalg.solve(U, sla.solve_triangular(L, np.eye(s.n), lower=True))
    for a in (lam, V, W):
        a.setflags(write=False)
    return s, lam, V, W


class ChassisModel:
    """Rear-corner chassis with FRFs at the spindle and the chosen bushing.

    Parameters
    ----------
    params : ChassisParameters, optional
        Default: the shipped reference model.

    Examples
    --------
    >>> ch = ChassisModel()
    >>> Y = ch.mobility([14.0, 37.0])
    >>> Y.shape
    (2, 12, 6)
    """

    def __init__(self, params: ChassisParameters | None = None) -> None:
        self._p = ChassisParameters() if params is None else params

    @property
    def params(self) -> ChassisParameters:
        return self._p

    def __repr__(self) -> str:
        return f"ChassisModel({len(self.system().dofs)} DOFs)"

    def system(self) -> SecondOrderSystem:
        """The FE model ``M x'' + K (1 + j eta) x = f`` (sparse; DOFs include
        ``spindle:*`` and ``bushing:*``; no viscous damping)."""
        return _modal(self._p)[0]

    def eigenvalues(self) -> ComplexArray:
        """Complex eigenvalues ``lam_r = omega_r^2 (1 + j eta_r)``, sorted by real part."""
        return _modal(self._p)[1]

    def eigenfrequencies(self) -> FloatArray:
        """Natural frequencies ``sqrt(Re lam_r) / 2 pi`` in Hz, ascending."""
        return np.sqrt(self.eigenvalues().real) / (2 * np.pi)

    def loss_factors(self) -> FloatArray:
        """Modal loss factors ``Im lam_r / Re lam_r``."""
        lam = self.eigenvalues()
        return lam.imag / lam.real

    def mobility(
        self,
        freq: ArrayLike,
        outputs: Iterable[str] | None = None,
        inputs: Iterable[str] | None = None,
        quantity: str = "mobility",
    ) -> FRF:
        """FRFs by exact complex-mode synthesis on any grid.

        ``H(omega) = V_o diag(1 / (lam_r - omega^2)) (V^-1 M^-1)_i`` is the
        inverse of ``K (1 + j eta) - omega^2 M`` (all modes, no truncation);
        mobility is ``j omega H`` (thesis table 2.1).

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz, strictly increasing.
        outputs, inputs : sequence of str, optional
            Default outputs ``spindle:*`` then ``bushing:*``; inputs ``spindle:*``.
        quantity : {"receptance", "mobility", "accelerance"}

        Returns
        -------
        FRF, shape (n_freq, n_out, n_in)
            ``Y_jj^E`` is ``.sel(outputs=SPINDLE)``, ``Y_ej^E`` ``.sel(outputs=BUSHING)``.
        """
        f = check_grid(freq)
        outs = SPINDLE + BUSHING if outputs is None else tuple(outputs)
        ins = SPINDLE if inputs is None else tuple(inputs)
        return receptance_frf(
            f, outs, ins, quantity, lambda: _synth(self._p, f.tobytes(), outs, ins)
        )

    def driving_point(self, freq: ArrayLike) -> FRF:
        """``Y_jj^E``: spindle mobility, 6 x 6 (``spindle:*`` to ``spindle:*``).

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz.
        """
        return self.mobility(freq, outputs=SPINDLE, inputs=SPINDLE)

    def transfer(self, freq: ArrayLike) -> FRF:
        """``Y_ej^E``: spindle-to-bushing mobility, 6 x 6 (``spindle:*`` to ``bushing:*``).

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz.
        """
        return self.mobility(freq, outputs=BUSHING, inputs=SPINDLE)

    def to_dict(self) -> dict[str, Any]:
        """The parameters as a plain dict (for storage)."""
        return asdict(self._p)


@functools.lru_cache(maxsize=32)
def _synth(
    p: ChassisParameters, fbytes: bytes, outputs: tuple[str, ...], inputs: tuple[str, ...]
) -> ComplexArray:
    """Receptance ``(n_freq, n_out, n_in)`` by the exact modal sum (cached per grid)."""
    s, lam, V, W = _modal(p)
    oi = index_of(s.dofs, outputs, "chassis output DOF")
    ii = index_of(s.dofs, inputs, "chassis input DOF")
    H = modal_sum(modal_factors(lam, np.frombuffer(fbytes, float)), V[oi], W[:, ii])
    H.setflags(write=False)
    return H


def read_chassis_frf(path: str | os.PathLike[str]) -> FRF:
    """Read the FRF stored by ``scripts/build_reference_chassis.py`` (HDF5, no pickle).

    The file follows the project's HDF5 layout (``fbs_core.io.hdf5``), so
    ``fbs_core.io`` reads its ``/frf`` group as well.

    Parameters
    ----------
    path : str or pathlib.Path
        An HDF5 file in the format of docs/chassis-model.md.

    Raises
    ------
    DataFormatError
        If the file is not a chassis file of a known version.
    """
    return read_model_frf(path, "reference chassis")


@functools.lru_cache(maxsize=1)
def reference_chassis() -> ChassisModel:
    """The shipped reference rear-corner chassis (see :class:`ChassisParameters`).

    Returns
    -------
    ChassisModel
    """
    return ChassisModel()


def modal_energy(chassis: ChassisModel, node: str = "spindle") -> FloatArray:
    """Share of each mode's kinetic energy in the six DOFs of ``node``.

    Returns
    -------
    ndarray, shape (n_modes, 6)
        ``Re(conj(v_d) (M v)_d) / Re(v^H M v)`` for d = x .. rz.
    """
    s, lam, V, _ = _modal(chassis.params)
    MV: ComplexArray = s.M @ V  # s.M is scipy.sparse (untyped)
    e = np.real(np.conj(V) * MV)
    idx = index_of(s.dofs, node_labels(node), "chassis DOF")
    share: FloatArray = (e[idx] / e.sum(axis=0)).T
    return share


def carrier_mode_table(chassis: ChassisModel, fmax: float = 100.0) -> dict[str, float]:
    """Frequency of the carrier mode dominated by each direction (below ``fmax``).

    For each direction, the mode below ``fmax`` with the largest carrier kinetic
    energy in that direction (thesis fig. 4.2 modes: x 14, y 37, ry 47 Hz).
    """
    f = chassis.eigenfrequencies()
    e = modal_energy(chassis)
    keep = f < fmax
    return {d: float(f[keep][np.argmax(e[keep, k])]) for k, d in enumerate(DIRECTIONS)}


class FRFChassis(FRFGiven):
    """A chassis given by a measured or computed mobility FRF, used like :class:`ChassisModel`.

    The FRF is used on its own lines; frequencies it does not hold are refused unless the
    user chose ``interpolate=True`` (then :meth:`FRF.interpolate`: linear in real and
    imaginary part, never extrapolated). No silent interpolation (docs/file-formats.md).

    Parameters
    ----------
    frf : FRF
        Mobility with inputs ``spindle:*`` and outputs ``spindle:*`` and ``bushing:*``
        (as returned by :func:`fbs_core.io.prepare_chassis`).
    interpolate : bool
        Interpolate onto frequencies the FRF has no line at (an explicit choice).

    Examples
    --------
    >>> import numpy as np
    >>> from fbs_core import FRF
    >>> Y = FRF([1.0, 2.0], np.ones((2, 1, 1)), ["spindle:z"], ["spindle:z"], "mobility")
    >>> FRFChassis(Y).mobility([2.0], ["spindle:z"], ["spindle:z"]).freq.tolist()
    [2.0]
    """

    def __repr__(self) -> str:
        return f"FRFChassis({self.frf!r}, interpolate={self.interpolate})"

    def _refusal(self, f: FloatArray, missing: FloatArray) -> str:
        """Names the first missing line and the dashboard's choice that interpolates."""
        F = self.frf.freq
        return (
            f"the chassis FRF ({F.size} lines, {F[0]:g}-{F[-1]:g} Hz) has no line at "
            f"{missing.size} of the {f.size} analysis frequencies {f[0]:g}-{f[-1]:g} Hz "
            f"(first: {missing[0]:g} Hz); tick 'interpolate onto the analysis grid' to "
            "interpolate it explicitly (linear in real and imaginary part)"
        )

    def _default_dofs(self) -> tuple[Sequence[str], Sequence[str]]:
        """Outputs ``spindle:*`` then ``bushing:*``; inputs ``spindle:*``."""
        return SPINDLE + BUSHING, SPINDLE
