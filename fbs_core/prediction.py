"""Coupled prediction: vibration at the bushing for a patch load (thesis eq. 4.1).

The reference tire (subsystem A) is coupled at its hub to the reference chassis
(subsystem E) at the spindle; the response at the chosen bushing is

``v_e* = Y_ej^E (Y_jj^A + Y_jj^E)^-1 (Y_ja^A F_a)``            (thesis eq. 4.1)

with ``Y_jj^A`` the tire's hub mobility and ``Y_ja^A F_a`` its free hub velocity
under the patch load of a harmonic case, both synthesised from the complex modes
along the harmonic's speed line ``v = f lambda`` (thesis section 4.1.2), and
``Y_jj^E``, ``Y_ej^E`` the chassis' spindle and spindle-to-bushing mobilities.
The tire's hub DOFs are already in vehicle coordinates (thesis fig. 4.5; the
transformation is documented in docs/chassis-model.md), so ``hub:d`` is joined
to ``spindle:d`` for each direction ``d``.

Two couplings: ``"6dof"`` joins all six hub DOFs (the thesis: a braked wheel,
spin tied to the knuckle); ``"5dof"`` releases the spin ``hub:ry`` (a free-rolling
wheel: no drive or brake torque passes the bearing).
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike

from ._typing import ComplexArray, FloatArray, IntArray
from .chassis import BUSHING, SPINDLE, ChassisModel, reference_chassis
from .coupling import couple_response
from .direct import SecondOrderSystem
from .dofs import node_labels
from .errors import CouplingOptionError
from .frf import FRF, check_grid
from .harmonics import Harmonic, renamed_argument
from .harmonics import harmonic as _harmonic
from .vocabulary import COUPLED_DIRECTIONS
from .vocabulary import COUPLINGS as _COUPLING_NAMES

__all__ = ["bushing_response", "direct_bushing_response", "coupled_dofs", "COUPLED_DOFS", "HUB"]

#: Hub DOF labels of the tire, in vehicle coordinates.
HUB: tuple[str, ...] = node_labels("hub")

#: The hub DOFs joined to the spindle for each coupling option
#: (:data:`fbs_core.vocabulary.COUPLINGS`).
COUPLED_DOFS: dict[str, tuple[str, ...]] = {
    c: node_labels("hub", dirs) for c, dirs in COUPLED_DIRECTIONS.items()
}


class ModalTire(Protocol):
    """What the prediction needs of a tire model (:class:`fbs_core.tire.TireModel`)."""

    @property
    def n_modes(self) -> int: ...

    def truncations(
        self, freq: Any, harmonic: Any = ..., n_modes_list: Any = ..., *, residual: bool = ...
    ) -> tuple[ComplexArray, ComplexArray]: ...

    def hub_mobility(
        self, freq: Any, speed_kmh: float, n_modes: int | None = ..., *, residual: bool = ...
    ) -> FRF: ...

    def patch_response(
        self,
        freq: Any,
        harmonic: Any = ...,
        n_modes: int | None = ...,
        speed_kmh: float | None = ...,
        *,
        residual: bool = ...,
    ) -> FRF: ...

    def system(self, speed_kmh: float) -> SecondOrderSystem: ...

    def patch_load(self, speed_kmh: float, wavelength: float) -> ComplexArray: ...


def __getattr__(name: str) -> dict[str, tuple[str, ...]]:
    if name == "COUPLINGS":  # the old name of COUPLED_DOFS (one release)
        warnings.warn(
            "fbs_core.prediction.COUPLINGS is deprecated: the option names are "
            "fbs_core.vocabulary.COUPLINGS, their hub DOFs fbs_core.prediction.COUPLED_DOFS",
            DeprecationWarning,
            stacklevel=2,
        )
        return COUPLED_DOFS
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def coupled_dofs(coupling: str) -> tuple[str, ...]:
    """Hub DOFs joined to the spindle for a coupling option.

    Parameters
    ----------
    coupling : {"6dof", "5dof"}

    Raises
    ------
    CouplingOptionError
        For any other value, naming the allowed ones.
    """
    if not isinstance(coupling, str) or coupling not in COUPLED_DOFS:
        raise CouplingOptionError(
            f"unknown coupling {coupling!r}; allowed: {', '.join(map(repr, _COUPLING_NAMES))} "
            "(all hub DOFs = braked wheel, or wheel spin hub:ry released = free rolling)"
        )
    return COUPLED_DOFS[coupling]


def _interface() -> list[tuple[str, str]]:
    return list(zip(HUB, node_labels("spindle"), strict=True))


def _tire_frfs(
    tire: ModalTire,
    h: Harmonic,
    f: FloatArray,
    n_modes: int | None,
    speed_kmh: float | None,
    residual: bool = False,
) -> tuple[FRF, FRF]:
    """Y_jj^A and Y_ja^A F_a as FRFs (along the harmonic line, or at a fixed speed)."""
    kw: dict[str, bool] = {"residual": True} if residual else {}
    if speed_kmh is None:
        n = [tire.n_modes if n_modes is None else n_modes]
        Yjj, vj = tire.truncations(f, h, n, **kw)
        Y_A = FRF(f, Yjj[0], HUB, HUB, "mobility")
        v_A = FRF(f, vj[0][:, :, None], HUB, ["patch"], "mobility")
    else:
        Y_A = tire.hub_mobility(f, speed_kmh, n_modes, **kw)
        v_A = tire.patch_response(f, h, n_modes, speed_kmh=speed_kmh, **kw)
    return Y_A, v_A


@functools.lru_cache(maxsize=64)
def _cached(
    k: int,
    n_modes: int | None,
    fbytes: bytes,
    coupling: str,
    speed_kmh: float | None,
    residual: bool = False,
) -> FRF:
    from . import reference_tire  # the tire package registers it at import

    return _compute(
        reference_tire(),
        reference_chassis(),
        _harmonic(k),
        np.frombuffer(fbytes, float),
        n_modes,
        coupling,
        speed_kmh,
        residual,
    )


def _compute(
    tire: ModalTire,
    chassis: ChassisModel,
    h: Harmonic,
    f: FloatArray,
    n_modes: int | None,
    coupling: str,
    speed_kmh: float | None,
    residual: bool = False,
) -> FRF:
    Y_A, v_A = _tire_frfs(tire, h, f, n_modes, speed_kmh, residual)
    Y_E = chassis.mobility(f, outputs=SPINDLE + BUSHING, inputs=SPINDLE)
    return couple_response(
        Y_E.sel(outputs=BUSHING),
        Y_A,
        Y_E.sel(outputs=SPINDLE),
        v_A,
        interface=_interface(),
        couple=coupled_dofs(coupling),
    )


def _assembled_index(
    tire_dofs: list[str], chassis_dofs: Sequence[str], coupled: Sequence[str]
) -> tuple[IntArray, IntArray, int]:
    """Primal assembly by index maps: global index of every tire and chassis DOF.

    Chassis ``spindle:d`` is merged into tire ``hub:d`` for every coupled ``hub:d``
    (the same DOF merging as :func:`fbs_core.direct.assemble`).
    """
    n_a = len(tire_dofs)
    g_e: list[int] = []
    nxt = n_a
    for d in chassis_dofs:
        node, _, direction = d.partition(":")
        hub = f"hub:{direction}"
        if node == "spindle" and hub in coupled:
            g_e.append(tire_dofs.index(hub))
        else:
            g_e.append(nxt)
            nxt += 1
    return np.arange(n_a), np.array(g_e), nxt


def direct_bushing_response(
    harmonic: int | Harmonic,
    freq: ArrayLike | None = None,
    coupling: str = "6dof",
    *,
    speed_kmh: float | None = None,
    tire: ModalTire | None = None,
    chassis: ChassisModel | None = None,
) -> FRF:
    """Ground truth of :func:`bushing_response`: the assembled matrices solved line by line.

    At every line the tire's own matrices at the exact speed of that line,
    ``v = 3.6 f lambda`` (``tire.system(v)``: ``M``, ``C = D + G(v)``, ``K(v)``;
    thesis section 4.1.2), are joined to the chassis' FE matrices at the coupled
    hub DOFs (primal assembly, as :func:`fbs_core.direct.assemble`) and the
    dynamic stiffness ``K - omega^2 M + j omega C`` (eq. 2.2) is solved for the
    physical patch load ``tire.patch_load(v, lambda)``. No modes, no
    interpolation between operating points, no FBS: what the modal model and
    eq. 4.1 approximate. Needs a tire with physical parameters.

    Parameters
    ----------
    harmonic : int or Harmonic
    freq : array_like, optional
        Lines in Hz inside the harmonic's band; default ``harmonic.frequencies()``.
    coupling : {"6dof", "5dof"}
    speed_kmh : float, optional
        Keyword only: one fixed speed instead of the harmonic line.
    tire, chassis : optional
        Keyword only; default the reference models.

    Returns
    -------
    FRF
        Outputs ``bushing:x`` ... ``bushing:rz``, input ``patch`` (mobility, per
        metre of road amplitude), like :func:`bushing_response`.
    """
    h = _harmonic(harmonic)
    coupled = coupled_dofs(coupling)
    f = h.frequencies() if freq is None else check_grid(freq)
    speeds = h.speed_at(f) if speed_kmh is None else np.full(f.size, float(speed_kmh))
    speeds = np.atleast_1d(speeds)
    if tire is None:
        from . import reference_tire

        tire = reference_tire()
    chassis = reference_chassis() if chassis is None else chassis
    cs = chassis.system()
    Ze_parts = [sp.csc_matrix(a) for a in (cs.K, cs.M, cs.C)]
    keep = [list(cs.dofs).index(d) for d in SPINDLE + BUSHING]  # 12 chassis DOFs kept
    out = np.empty((f.size, len(BUSHING), 1), complex)
    load = tire.patch_load(float(speeds[0]), h.wavelength)  # space-fixed: speed independent
    ia: IntArray | None = None
    ie: IntArray | None = None
    for i, (fi, v) in enumerate(zip(f, speeds, strict=True)):
        ts = tire.system(float(v))
        if ia is None:
            ia, ie, n = _assembled_index(list(ts.dofs), SPINDLE + BUSHING, coupled)
        assert ia is not None and ie is not None  # set on the first line
        w = 2 * np.pi * fi
        # block elimination of the chassis' inner DOFs (exact: Gaussian elimination of
        # the assembled matrix in another order): Z_E condensed onto spindle + bushing
        Ze = (Ze_parts[0] - w**2 * Ze_parts[1] + 1j * w * Ze_parts[2]).tocsc()
        rhs = np.zeros((cs.n, len(keep)), complex)
        rhs[keep, np.arange(len(keep))] = 1.0
        S = np.linalg.inv(spla.splu(Ze).solve(rhs)[keep])
        Z = np.zeros((n, n), complex)
        Z[np.ix_(ia, ia)] += ts.K - w**2 * ts.M + 1j * w * ts.C
        Z[np.ix_(ie, ie)] += S
        b = np.zeros(n, complex)
        b[ia] = load
        out[i, :, 0] = 1j * w * np.linalg.solve(Z, b)[ie[len(SPINDLE) :]]
    return FRF(f, out, BUSHING, ["patch"], "mobility")


def bushing_response(
    harmonic: int | Harmonic | None = None,
    n_modes: int | None = None,
    freq: ArrayLike | None = None,
    coupling: str = "6dof",
    *,
    speed_kmh: float | None = None,
    tire: ModalTire | None = None,
    chassis: ChassisModel | None = None,
    residual: bool = False,
    harmonic_case: int | Harmonic | None = None,
) -> FRF:
    """Velocity at the chosen bushing for the patch load of a harmonic case (eq. 4.1).

    Parameters
    ----------
    harmonic : int or Harmonic
        Excitation case 1..7 (thesis fig. 4.4, table 5.1).
    n_modes : int, optional
        Number of complex tire modes kept (even, pairs lowest first); ``None``
        keeps all.
    freq : array_like, shape (n_freq,), optional
        Frequencies in Hz; default ``harmonic.frequencies()``. Along the
        harmonic line they must lie inside the harmonic's band.
    coupling : {"6dof", "5dof"}
        All six hub DOFs joined (braked wheel, as the thesis), or the wheel spin
        ``hub:ry`` released (free-rolling wheel).
    speed_kmh : float, optional
        Keyword only: evaluate the tire at this fixed speed instead of along the
        harmonic line ``v = f lambda`` (any positive frequencies allowed).
    tire : TireModel, optional
        Keyword only; default ``fbs_core.reference_tire()``.
    chassis : ChassisModel, optional
        Keyword only; default :func:`fbs_core.reference_chassis`.
    residual : bool
        Keyword only: compensate the tire modes left out by ``n_modes`` with their
        quasi-static part (upper residual flexibility, docs/tire-model.md).
    harmonic_case : int or Harmonic, optional
        Deprecated name of ``harmonic`` (a ``DeprecationWarning``; removed in the next
        release).

    Returns
    -------
    FRF
        Mobility with outputs ``bushing:x`` ... ``bushing:rz`` and one input
        ``patch`` (m/s and rad/s per metre of road amplitude).

    Raises
    ------
    HarmonicError, CouplingOptionError, ModeCountError, FrequencyGridError,
    OperatingPointError

    Examples
    --------
    >>> v = bushing_response(1, n_modes=40)          # doctest: +SKIP
    >>> v.outputs[2], v.inputs                       # doctest: +SKIP
    ('bushing:z', ('patch',))
    """
    h = _harmonic(renamed_argument(harmonic, harmonic_case, "bushing_response"))
    coupled_dofs(coupling)
    f = h.frequencies() if freq is None else check_grid(freq)
    if speed_kmh is not None:
        speed_kmh = float(speed_kmh)
    if tire is None and chassis is None and h in _HARMONIC_SET:
        return _cached(h.k, n_modes, f.tobytes(), coupling, speed_kmh, bool(residual))
    if tire is None:
        from . import reference_tire

        tire = reference_tire()
    return _compute(
        tire,
        reference_chassis() if chassis is None else chassis,
        h,
        f,
        n_modes,
        coupling,
        speed_kmh,
        bool(residual),
    )


_HARMONIC_SET = {_harmonic(k) for k in range(1, 8)}
