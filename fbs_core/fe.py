"""Small 3D finite-element toolkit: Euler-Bernoulli beams, rigid bodies, springs.

Used to build the physics behind the reference models: the thesis' three-beam
validation case (chapter 3) and the flexible rear-corner chassis (chapter 4).
Every node has the six DOFs ``x y z rx ry rz`` (:data:`fbs_core.dofs.DIRECTIONS`),
labelled ``"node:dir"``. Damping is hysteretic (structural): a loss factor
``eta`` turns a stiffness ``k`` into ``k (1 + j eta)``, which is exact at every
frequency for a hysteretic material (no ``omega`` in the damping term).

The beam element is the classical two-node, 12-DOF Euler-Bernoulli element with
linear axial and torsional shape functions and cubic Hermitian bending shape
functions; stiffness and consistent mass as tabulated by Przemieniecki, *Theory
of Matrix Structural Analysis* (1968), eqs. 5.116 and 11.42 (also Cook et al.,
*Concepts and Applications of FE Analysis*, 4th ed., sections 2.4 and 11.3).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ._typing import AnyArray, ComplexArray, FloatArray
from .direct import SecondOrderSystem
from .dofs import DIRECTIONS, parse_label
from .errors import DataFormatError, DOFError

__all__ = [
    "Material",
    "Section",
    "beam_local_matrices",
    "beam_rotation",
    "beam_element",
    "rigid_body_mass",
    "offset_transform",
    "FEModel",
]


@dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material with a hysteretic loss factor.

    Parameters
    ----------
    E : float
        Young's modulus (Pa).
    nu : float
        Poisson's ratio; ``G = E / (2 (1 + nu))``.
    rho : float
        Density (kg/m^3).
    eta : float
        Structural loss factor: ``E -> E (1 + j eta)``.
    """

    E: float
    nu: float
    rho: float
    eta: float = 0.0

    def __post_init__(self) -> None:
        if self.E <= 0 or self.rho <= 0 or not -1 < self.nu < 0.5 or self.eta < 0:
            raise DataFormatError(
                f"invalid material E={self.E}, nu={self.nu}, rho={self.rho}, eta={self.eta}; "
                "need E > 0, rho > 0, -1 < nu < 0.5, eta >= 0"
            )

    @property
    def G(self) -> float:
        """Shear modulus ``E / (2 (1 + nu))`` (Pa)."""
        return self.E / (2 * (1 + self.nu))


@dataclass(frozen=True)
class Section:
    """Beam cross-section properties (SI units).

    ``A`` area, ``Iy`` and ``Iz`` second moments about the local y and z axes,
    ``J`` torsion constant.
    """

    A: float
    Iy: float
    Iz: float
    J: float

    def __post_init__(self) -> None:
        if min(self.A, self.Iy, self.Iz, self.J) <= 0:
            raise DataFormatError(f"section properties must be positive, got {self}")

    @classmethod
    def rectangle(cls, b: float, h: float) -> Section:
        """Solid rectangle, width ``b`` along local y, height ``h`` along local z.

        The torsion constant uses Roark's series approximation
        ``J = a b^3 (1/3 - 0.21 (b/a) (1 - (b/a)^4 / 12))`` with ``a >= b``
        (Young & Budynas, *Roark's Formulas*, 7th ed., table 10.7 case 4).
        """
        a, t = max(b, h), min(b, h)
        J = a * t**3 * (1 / 3 - 0.21 * (t / a) * (1 - (t / a) ** 4 / 12))
        return cls(A=b * h, Iy=b * h**3 / 12, Iz=h * b**3 / 12, J=J)

    @classmethod
    def box(cls, b: float, h: float, t: float) -> Section:
        """Thin-walled rectangular hollow section ``b`` (local y) x ``h`` (local z), wall ``t``.

        Torsion constant by Bredt's formula ``J = 4 A_m^2 t / p_m`` on the wall's
        mid-line (area ``A_m``, perimeter ``p_m``).
        """
        if not 0 < 2 * t < min(b, h):
            raise DataFormatError(f"box wall t={t} must be positive and < min(b, h)/2")
        bi, hi = b - 2 * t, h - 2 * t
        Am, pm = (b - t) * (h - t), 2 * (b + h - 2 * t)
        return cls(
            A=b * h - bi * hi,
            Iy=(b * h**3 - bi * hi**3) / 12,
            Iz=(h * b**3 - hi * bi**3) / 12,
            J=4 * Am**2 * t / pm,
        )

    @classmethod
    def tube(cls, d: float, t: float) -> Section:
        """Thin or thick circular tube of outer diameter ``d`` and wall ``t``."""
        if not 0 < t <= d / 2:
            raise DataFormatError(f"tube wall t={t} must be in (0, d/2] for d={d}")
        di = d - 2 * t
        I = np.pi / 64 * (d**4 - di**4)
        return cls(A=np.pi / 4 * (d**2 - di**2), Iy=I, Iz=I, J=2 * I)


def beam_local_matrices(
    length: float, section: Section, material: Material
) -> tuple[ComplexArray, FloatArray]:
    """Stiffness and consistent mass of a 3D Euler-Bernoulli beam in local axes.

    DOF order: ``u1 v1 w1 tx1 ty1 tz1 u2 v2 w2 tx2 ty2 tz2`` with x along the
    beam. Bending in the x-y plane uses ``Iz``, in the x-z plane ``Iy``.

    Returns
    -------
    K : ndarray, shape (12, 12), complex
        Stiffness times ``(1 + j eta)``.
    M : ndarray, shape (12, 12), real
        Consistent mass (translational inertia; torsional inertia ``rho (Iy + Iz)``).
    """
    L = float(length)
    if L <= 0:
        raise DataFormatError(f"beam length must be positive, got {L}")
    E, G, rho = material.E, material.G, material.rho
    A, Iy, Iz, J = section.A, section.Iy, section.Iz, section.J
    K = np.zeros((12, 12))
    M = np.zeros((12, 12))
    bar = np.array([[1.0, -1.0], [-1.0, 1.0]])
    bar_m = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6
    for i, (k, m) in enumerate([(E * A / L, rho * A * L), (G * J / L, rho * (Iy + Iz) * L)]):
        idx = np.ix_([3 * i, 6 + 3 * i], [3 * i, 6 + 3 * i])
        K[idx] += k * bar
        M[idx] += m * bar_m
    # bending: (v, tz) uses Iz with +L terms; (w, ty) uses Iy with -L terms
    for I, dofs, s in ((Iz, [1, 5, 7, 11], 1.0), (Iy, [2, 4, 8, 10], -1.0)):
        kb = (
            E
            * I
            / L**3
            * np.array(
                [
                    [12, 6 * L * s, -12, 6 * L * s],
                    [6 * L * s, 4 * L**2, -6 * L * s, 2 * L**2],
                    [-12, -6 * L * s, 12, -6 * L * s],
                    [6 * L * s, 2 * L**2, -6 * L * s, 4 * L**2],
                ]
            )
        )
        mb = (
            rho
            * A
            * L
            / 420
            * np.array(
                [
                    [156, 22 * L * s, 54, -13 * L * s],
                    [22 * L * s, 4 * L**2, 13 * L * s, -3 * L**2],
                    [54, 13 * L * s, 156, -22 * L * s],
                    [-13 * L * s, -3 * L**2, -22 * L * s, 4 * L**2],
                ]
            )
        )
        K[np.ix_(dofs, dofs)] += kb
        M[np.ix_(dofs, dofs)] += mb
    return K * (1 + 1j * material.eta), M


def beam_rotation(
    p1: Sequence[float] | FloatArray,
    p2: Sequence[float] | FloatArray,
    up: Sequence[float] | FloatArray | None = None,
) -> FloatArray:
    """Direction cosines of a beam's local axes.

    Parameters
    ----------
    p1, p2 : array_like, shape (3,)
        End points; local x runs from ``p1`` to ``p2``.
    up : array_like, shape (3,), optional
        A vector in the local x-z plane that fixes local z (the section's
        height direction). Default: global z, or global y for vertical beams.

    Returns
    -------
    ndarray, shape (3, 3)
        Rows are the local x, y, z unit vectors in global coordinates, so that
        ``u_local = R @ u_global``.
    """
    d = np.asarray(p2, float) - np.asarray(p1, float)
    L = np.linalg.norm(d)
    if L == 0:
        raise DataFormatError(f"beam end points coincide: {tuple(p1)}")
    ex = d / L
    if up is None:
        up = [0.0, 0.0, 1.0] if abs(ex[2]) < 0.99 else [0.0, 1.0, 0.0]
    upv = np.asarray(up, float)
    ey = np.cross(upv, ex)
    if np.linalg.norm(ey) < 1e-9 * np.linalg.norm(upv):
        raise DataFormatError(f"'up' vector {tuple(upv)} is parallel to the beam axis")
    ey /= np.linalg.norm(ey)
    ez = np.cross(ex, ey)
    return np.vstack([ex, ey, ez])


def beam_element(
    p1: Sequence[float] | FloatArray,
    p2: Sequence[float] | FloatArray,
    section: Section,
    material: Material,
    up: Sequence[float] | FloatArray | None = None,
) -> tuple[ComplexArray, FloatArray]:
    """Global 12x12 stiffness and mass ``T^T K_local T`` of one beam element."""
    R = beam_rotation(p1, p2, up)
    T = np.kron(np.eye(4), R)
    K, M = beam_local_matrices(float(np.linalg.norm(np.subtract(p2, p1))), section, material)
    return T.T @ K @ T, T.T @ M @ T


def _skew(r: FloatArray) -> FloatArray:
    x, y, z = r
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def offset_transform(offset: Sequence[float] | FloatArray) -> FloatArray:
    """Rigid-link map from a reference node's 6 DOFs to a point at ``offset``.

    ``u_point = u_ref + theta x r`` (small rotations), ``theta_point = theta_ref``.

    Returns
    -------
    ndarray, shape (6, 6)
    """
    T = np.eye(6)
    T[:3, 3:] = -_skew(np.asarray(offset, float))
    return T


def rigid_body_mass(
    mass: float, inertia: ArrayLike, offset: Sequence[float] | FloatArray = (0.0, 0.0, 0.0)
) -> FloatArray:
    """6x6 mass matrix of a rigid body referred to a node.

    Parameters
    ----------
    mass : float
        Mass (kg).
    inertia : array_like, shape (3,) or (3, 3)
        Inertia tensor about the centre of gravity (kg m^2), or its diagonal.
    offset : array_like, shape (3,)
        Position of the centre of gravity relative to the node (m).

    Returns
    -------
    ndarray, shape (6, 6)
        ``T^T diag(m, m, m, I) T`` with :func:`offset_transform`.
    """
    I = np.asarray(inertia, float)
    I = np.diag(I) if I.shape == (3,) else I
    if mass <= 0 or I.shape != (3, 3) or np.any(np.linalg.eigvalsh(I) <= 0):
        raise DataFormatError(f"rigid body needs mass > 0 and a positive inertia, got {mass}, {I}")
    Mc = np.zeros((6, 6))
    Mc[:3, :3] = mass * np.eye(3)
    Mc[3:, 3:] = I
    T = offset_transform(offset)
    return T.T @ Mc @ T


class FEModel:
    """Incremental builder of a labelled finite-element model.

    Nodes carry 6 DOFs. Elements are added as dense blocks on node lists and
    assembled into sparse ``M`` and complex ``K`` by :meth:`system`.

    Examples
    --------
    >>> m = FEModel()
    >>> a, b = m.add_node("a", (0, 0, 0)), m.add_node("b", (1, 0, 0))
    >>> s = m.add_spring("a", None, [1e3] * 6)
    >>> s = m.add_beam("a", "b", Section.rectangle(0.01, 0.04), Material(210e9, 0.3, 8000), 4)
    >>> m.system().n
    30
    """

    def __init__(self) -> None:
        self._xyz: dict[str, FloatArray] = {}
        self._blocks: list[tuple[list[str], AnyArray, AnyArray]] = []

    @property
    def nodes(self) -> tuple[str, ...]:
        return tuple(self._xyz)

    def xyz(self, node: str) -> FloatArray:
        """Coordinates of a node."""
        if node not in self._xyz:
            raise DOFError(f"unknown node {node!r}; available: {', '.join(self._xyz)}")
        return self._xyz[node].copy()

    def add_node(self, name: str, xyz: Sequence[float] | FloatArray) -> str:
        """Add a node (its label must be valid, see :func:`fbs_core.dofs.parse_label`)."""
        if parse_label(name)[1] is not None:
            raise DOFError(f"node name {name!r} must not contain a direction")
        if name in self._xyz:
            raise DOFError(f"duplicate node {name!r}")
        p = np.asarray(xyz, float)
        if p.shape != (3,):
            raise DataFormatError(f"node {name!r} needs 3 coordinates, got shape {p.shape}")
        self._xyz[name] = p
        return name

    def add_block(
        self, nodes: Sequence[str], K: ArrayLike | None = None, M: ArrayLike | None = None
    ) -> None:
        """Add dense stiffness / mass blocks of size ``6 len(nodes)``."""
        for n in nodes:
            self.xyz(n)
        size = 6 * len(nodes)
        Ka = np.zeros((size, size)) if K is None else np.asarray(K)
        Ma = np.zeros((size, size)) if M is None else np.asarray(M)
        if Ka.shape != (size, size) or Ma.shape != (size, size):
            raise DataFormatError(f"blocks on {len(nodes)} nodes must be {size}x{size}")
        self._blocks.append((list(nodes), Ka, Ma))

    def add_beam(
        self,
        start: str,
        end: str,
        section: Section,
        material: Material,
        n_elements: int,
        up: Sequence[float] | FloatArray | None = None,
        prefix: str | None = None,
    ) -> list[str]:
        """Mesh a straight beam from node ``start`` to ``end`` with equal elements.

        Intermediate nodes are created as ``f"{prefix}{i}"``, i = 1 .. n-1
        (prefix defaults to ``f"{start}-{end}."``).

        Returns
        -------
        list of str
            All node names along the beam, ``start`` to ``end``.
        """
        if int(n_elements) < 1:
            raise DataFormatError(f"n_elements must be >= 1, got {n_elements}")
        n = int(n_elements)
        p1, p2 = self.xyz(start), self.xyz(end)
        prefix = f"{start}-{end}." if prefix is None else prefix
        names = [start]
        for i in range(1, n):
            names.append(self.add_node(f"{prefix}{i}", p1 + (p2 - p1) * i / n))
        names.append(end)
        K, M = beam_element(p1, p1 + (p2 - p1) / n, section, material, up)
        for a, b in zip(names[:-1], names[1:], strict=True):
            self.add_block([a, b], K, M)
        return names

    def add_mass(self, node: str, mass6: ArrayLike) -> None:
        """Add a 6x6 mass block (e.g. :func:`rigid_body_mass`) at a node."""
        self.add_block([node], M=mass6)

    def add_spring(
        self,
        a: str,
        b: str | None,
        k: ArrayLike,
        eta: float = 0.0,
        offset_a: Sequence[float] | FloatArray | None = None,
        offset_b: Sequence[float] | FloatArray | None = None,
    ) -> ComplexArray:
        """Add a 6x6 spring (``k`` diagonal of 6 or 6x6) between nodes or to ground.

        The spring acts between a point rigidly attached to ``a`` (at
        ``offset_a``) and one attached to ``b`` (``b=None``: ground). Its
        stiffness is multiplied by ``(1 + j eta)`` (hysteretic damping).

        Returns
        -------
        ndarray
            The complex stiffness block that was added.
        """
        ka = np.asarray(k, float)
        ka = np.diag(ka) if ka.shape == (6,) else ka
        if ka.shape != (6, 6):
            raise DataFormatError(f"spring stiffness must be 6 values or 6x6, got {ka.shape}")
        kc = ka * (1 + 1j * eta)
        Ta = offset_transform(np.zeros(3) if offset_a is None else offset_a)
        if b is None:
            blk = Ta.T @ kc @ Ta
            self.add_block([a], K=blk)
            return blk
        Tb = offset_transform(np.zeros(3) if offset_b is None else offset_b)
        T = np.hstack([-Ta, Tb])  # relative displacement of the two points
        blk = T.T @ kc @ T
        self.add_block([a, b], K=blk)
        return blk

    def labels(self) -> tuple[str, ...]:
        return tuple(f"{n}:{d}" for n in self._xyz for d in DIRECTIONS)

    def edges(self) -> tuple[tuple[str, str], ...]:
        """Node pairs joined by a two-node block (a beam element or a spring), in the
        order they were added: the lines that draw the model."""
        return tuple((b[0][0], b[0][1]) for b in self._blocks if len(b[0]) == 2)

    def system(self) -> SecondOrderSystem:
        """Assemble sparse ``M`` and complex ``K`` into a :class:`SecondOrderSystem`."""
        pos = {n: 6 * i for i, n in enumerate(self._xyz)}
        rows, cols, kv, mv = [], [], [], []
        for nodes, K, M in self._blocks:
            idx = np.concatenate([pos[n] + np.arange(6) for n in nodes])
            r, c = np.meshgrid(idx, idx, indexing="ij")
            rows.append(r.ravel())
            cols.append(c.ravel())
            kv.append(np.asarray(K, complex).ravel())
            mv.append(np.asarray(M, float).ravel())
        n = 6 * len(self._xyz)
        r, c = np.concatenate(rows), np.concatenate(cols)
        K = sp.csc_matrix((np.concatenate(kv), (r, c)), shape=(n, n))
        M = sp.csc_matrix((np.concatenate(mv), (r, c)), shape=(n, n))
        K.eliminate_zeros()
        M.eliminate_zeros()
        return SecondOrderSystem(M, None, K, self.labels())
