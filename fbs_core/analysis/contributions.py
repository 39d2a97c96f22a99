"""Interface-force contributions to the coupled response (the terms of thesis eq. 4.1).

The receiver response of eq. 4.1,

``v_e* = Y_ej^E g``,   ``g = (Y_jj^A + Y_jj^E)^-1 (Y_ja^A F_a)``      (thesis eqs. 4.1, 2.37)

is a sum over the coupled interface DOFs: ``v_e* = sum_k Y_ej^E[:, k] g_k``.
Term ``k`` is the response the interface force ``g_k`` alone would cause in the
receiver (chassis), so the terms answer "which hub DOF carries the vibration to
the bushing". ``g`` is the force the source (tire) exerts on the receiver at
the interface; the compatibility condition (equal interface velocities) fixes
it. The terms are complex: they can cancel, so the sum of their magnitudes may
exceed the magnitude of the total. A released DOF (5-DOF coupling) carries no
force and has no term.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .. import kernels
from ..chassis import BUSHING, SPINDLE, ChassisModel, reference_chassis
from ..coupling import _check_same, _interface_pairs
from ..dofs import index_of
from ..errors import DOFError, FBSError
from ..frf import FRF, check_grid
from ..harmonics import harmonic as _harmonic
from ..harmonics import renamed_argument
from ..prediction import coupled_dofs
from ..vocabulary import magnitude_db, readonly

__all__ = [
    "Contributions",
    "contribution_kernel",
    "interface_contributions",
    "bushing_contributions",
    "map_contributions",
]


def contribution_kernel(
    Yej: np.ndarray, YjjA: np.ndarray, YjjE: np.ndarray, vj: np.ndarray, **solve_kw: Any
) -> tuple[np.ndarray, np.ndarray]:
    """Interface forces and the per-DOF terms of eq. 4.1 (pure arrays).

    ``g = (Y_jj^A + Y_jj^E)^-1 v_j`` and ``T[..., e, k] = Y_ej[..., e, k] g[..., k]``
    (thesis eqs. 2.37, 4.1), so that ``T.sum(-1) == Y_ej @ g == v_e*``.

    Parameters
    ----------
    Yej : ndarray, shape (..., n_e, n_j)
        Receiver transfer mobility from the interface to the responses.
    YjjA, YjjE : ndarray, shape (..., n_j, n_j)
        Source and receiver driving-point mobilities at the interface.
    vj : ndarray, shape (..., n_j)
        Free interface velocity of the source, ``Y_ja^A F_a`` (one load).
    **solve_kw
        ``rcond``, ``max_cond``, ``freq`` of :func:`fbs_core.kernels.solve_interface`.

    Returns
    -------
    g : ndarray, shape (..., n_j)
        Interface force on the receiver.
    terms : ndarray, shape (..., n_e, n_j)
        Contribution of each interface force to each response.
    """
    g = kernels.solve_interface(YjjA + YjjE, vj[..., None], **solve_kw)[..., 0]
    return g, Yej * g[..., None, :]


@dataclass(frozen=True, eq=False)
class Contributions:
    """The coupled response split into the contributions of the interface forces.

    Attributes
    ----------
    freq : ndarray, shape (n_f,)
        Frequencies in Hz.
    outputs : tuple of str, length n_out
        Response DOFs (e.g. ``bushing:x`` ... ``bushing:rz``).
    interface : tuple of str, length n_j
        Coupled source interface DOFs (e.g. ``hub:x`` ...), one term each.
    load : str
        Name of the load input (e.g. ``"patch"``).
    terms : ndarray, shape (n_f, n_out, n_j)
        Complex contribution of each interface force to each response.
    forces : ndarray, shape (n_f, n_j)
        Interface force on the receiver per unit load.
    quantity : str
        FRF quantity of the response (``"mobility"``).

    Notes
    -----
    ``terms.sum(-1)`` is the coupled response of eq. 4.1 (:attr:`total`).
    """

    freq: np.ndarray
    outputs: tuple[str, ...]
    interface: tuple[str, ...]
    load: str
    terms: np.ndarray
    forces: np.ndarray
    quantity: str = "mobility"

    def __post_init__(self) -> None:
        for name in ("freq", "terms", "forces"):
            object.__setattr__(self, name, readonly(getattr(self, name)))

    @property
    def total(self) -> FRF:
        """The coupled response ``sum_k terms[..., k]`` (eq. 4.1), outputs x ``load``."""
        return FRF(
            self.freq, self.terms.sum(-1)[:, :, None], self.outputs, [self.load], self.quantity
        )

    def term(self, dof: str) -> FRF:
        """Contribution of the interface force at ``dof`` to every response, as an FRF.

        Parameters
        ----------
        dof : str
            A coupled interface DOF, e.g. ``"hub:z"``.

        Returns
        -------
        FRF
            Outputs :attr:`outputs`, one input :attr:`load`.

        Raises
        ------
        DOFError
            For a DOF that is not coupled, naming the coupled ones.
        """
        k = index_of(self.interface, dof, "coupled interface DOF")[0]
        return FRF(self.freq, self.terms[:, :, k : k + 1], self.outputs, [self.load], self.quantity)

    def at(self, output: str) -> FRF:
        """All contributions to one response DOF: an FRF whose inputs are the interface DOFs.

        ``at("bushing:z").data[:, 0, k]`` is the part of ``bushing:z`` carried by the
        force at ``interface[k]``; the input labels name the interface DOF whose
        force the column is (per unit ``load``).

        Raises
        ------
        DOFError
            For an unknown response DOF.
        """
        i = index_of(self.outputs, output, "response DOF")[0]
        return FRF(self.freq, self.terms[:, i : i + 1, :], [output], self.interface, self.quantity)

    def export_mapping(self) -> dict[str, Any]:
        """Arrays with axes for :func:`fbs_core.io.export_result`: the complex terms, the
        total and the interface forces."""
        return {
            "terms": (("freq", "output", "interface"), self.terms),
            "total": (("freq", "output"), self.terms.sum(-1)),
            "forces": (("freq", "interface"), self.forces),
            "coords": {
                "freq": self.freq,
                "output": list(self.outputs),
                "interface": list(self.interface),
            },
            "metadata": {"load": self.load, "quantity": self.quantity},
        }

    def levels_db(self, output: str, ref: float = 1.0) -> np.ndarray:
        """``20 log10 |term| / ref`` of every term at one response, shape ``(n_f, n_j)``."""
        i = index_of(self.outputs, output, "response DOF")[0]
        return magnitude_db(self.terms[:, i, :], ref, floor=None)

    def dominant(self, output: str) -> tuple[str, ...]:
        """Interface DOF with the largest term magnitude at every line for one response."""
        i = index_of(self.outputs, output, "response DOF")[0]
        k = np.argmax(np.abs(self.terms[:, i, :]), axis=1)
        return tuple(self.interface[j] for j in k)

    def shares(self, output: str) -> np.ndarray:
        """Projection of each term on the total, ``Re(term conj(total)) / |total|^2``.

        Shape ``(n_f, n_j)``; the shares add up to 1 at every line (a term in
        phase with the total counts positive, one in anti-phase negative), so
        they answer "how much of the total does each force make" even where the
        terms cancel each other.
        """
        i = index_of(self.outputs, output, "response DOF")[0]
        t = self.terms[:, i, :]
        tot = t.sum(-1, keepdims=True)
        den = np.abs(tot) ** 2
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(den > 0, (t * np.conj(tot)).real / den, 0.0)


def interface_contributions(
    Y_ej: FRF,
    Y_jj_A: FRF,
    Y_jj_E: FRF,
    v_j: FRF,
    *,
    interface: Any = None,
    couple: str | Sequence[str] | None = None,
    rcond: float | None = None,
    max_cond: float | None = kernels.MAX_COND,
) -> Contributions:
    """Split the coupled response of eq. 4.1 into the terms of the interface forces.

    Same inputs as :func:`fbs_core.couple_response`; the sum of the terms is its
    result: ``v_e* = sum_k Y_ej^E[:, k] g_k`` with
    ``g = (Y_jj^A + Y_jj^E)^-1 (Y_ja^A F_a)`` (thesis eqs. 2.37, 4.1).

    Parameters
    ----------
    Y_ej : FRF
        Receiver transfer mobility, inputs = receiver interface DOFs.
    Y_jj_A, Y_jj_E : FRF
        Source and receiver driving-point mobilities at the interface.
    v_j : FRF
        Free interface velocity of the source, one input (the load).
    interface : sequence of (str, str), optional
        Pairs ``(source_label, receiver_label)``; default pairs by position.
    couple : sequence of str, optional
        Source interface labels to couple (the others carry no force).
    rcond, max_cond : float, optional
        See :func:`fbs_core.couple_receptance`.

    Returns
    -------
    Contributions
        ``interface`` holds the source labels of the coupled DOFs.

    Raises
    ------
    DOFError
        Unknown labels, or a ``v_j`` with more than one load input.
    FrequencyGridError, QuantityError, SingularInterfaceError
    """
    pairs = _interface_pairs(Y_jj_A, Y_jj_E, interface)
    if couple is not None:
        couple = [couple] if isinstance(couple, str) else list(couple)
        index_of([p[0] for p in pairs], couple, "coupled interface DOF")
        pairs = [p for p in pairs if p[0] in set(couple)]
        if not pairs:
            raise DOFError("couple= selects no interface DOF")
    _check_same([Y_ej, Y_jj_A, Y_jj_E, v_j], "FRFs of eq. 4.1")
    if len(v_j.inputs) != 1:
        raise DOFError(
            f"contributions are per load: v_j must have one input, got {list(v_j.inputs)}; "
            "select one with v_j.sel(inputs=...)"
        )
    ta, tc = [p[0] for p in pairs], [p[1] for p in pairs]
    g, terms = contribution_kernel(
        Y_ej.sel(inputs=tc).data,
        Y_jj_A.sel(outputs=ta, inputs=ta).data,
        Y_jj_E.sel(outputs=tc, inputs=tc).data,
        v_j.sel(outputs=ta).data[:, :, 0],
        rcond=rcond,
        max_cond=max_cond,
        freq=Y_ej.freq,
    )
    return Contributions(Y_ej.freq, Y_ej.outputs, tuple(ta), v_j.inputs[0], terms, g, Y_ej.quantity)


def bushing_contributions(
    harmonic: Any = None,
    n_modes: int | None = None,
    freq: npt.ArrayLike | None = None,
    coupling: str = "6dof",
    *,
    speed_kmh: float | None = None,
    tire: Any = None,
    chassis: ChassisModel | None = None,
    harmonic_case: Any = None,
) -> Contributions:
    """Contributions of the hub forces to the bushing response of a harmonic case.

    The terms of eq. 4.1 for the tire + chassis of :func:`fbs_core.bushing_response`
    (same arguments; their sum is its result): term ``hub:d`` is the bushing
    response to the force the tire exerts on the spindle in direction ``d``.

    Parameters
    ----------
    harmonic : int or Harmonic
        Excitation case 1..7.
    n_modes : int, optional
        Retained complex tire modes; ``None`` keeps all.
    freq : array_like, shape (n_freq,), optional
        Frequencies in Hz; default the harmonic's grid.
    coupling : {"6dof", "5dof"}
        Coupled hub DOFs (5dof: spin ``hub:ry`` released, no term for it).
    speed_kmh : float, optional
        Fixed speed instead of the harmonic line ``v = f lambda``.
    tire : TireModel, optional
        Default the reference tire.
    chassis : ChassisModel, optional
        Default the reference chassis.
    harmonic_case : int or Harmonic, optional
        Deprecated name of ``harmonic`` (a ``DeprecationWarning``; removed in the next
        release).

    Returns
    -------
    Contributions
        Outputs ``bushing:*``, interface ``hub:*`` (coupled ones), load ``patch``.

    Examples
    --------
    >>> c = bushing_contributions(1, n_modes=40)          # doctest: +SKIP
    >>> c.at("bushing:z").inputs                          # doctest: +SKIP
    ('hub:x', 'hub:y', 'hub:z', 'hub:rx', 'hub:ry', 'hub:rz')
    """
    h = _harmonic(renamed_argument(harmonic, harmonic_case, "bushing_contributions"))
    dofs = coupled_dofs(coupling)
    f = h.frequencies() if freq is None else check_grid(np.asarray(freq))
    if tire is None:
        from .. import reference_tire

        tire = reference_tire()
    chassis = reference_chassis() if chassis is None else chassis
    if speed_kmh is None:
        Yjj, vj = tire.truncations(f, h, [tire.n_modes if n_modes is None else n_modes])
        Y_A = FRF(f, Yjj[0], tire.hub_dofs, tire.hub_dofs, "mobility")
        v_A = FRF(f, vj[0][:, :, None], tire.hub_dofs, ["patch"], "mobility")
    else:
        Y_A = tire.hub_mobility(f, float(speed_kmh), n_modes)
        v_A = tire.patch_response(f, h, n_modes, speed_kmh=float(speed_kmh))
    Y_E = chassis.mobility(f, outputs=SPINDLE + BUSHING, inputs=SPINDLE)
    return interface_contributions(
        Y_E.sel(outputs=BUSHING),
        Y_A,
        Y_E.sel(outputs=SPINDLE),
        v_A,
        interface=[(f"hub:{d.split(':')[1]}", f"spindle:{d.split(':')[1]}") for d in SPINDLE],
        couple=dofs,
    )


def map_contributions(
    truncation_map: Any, n_modes: int | None, load: str = "patch"
) -> Contributions:
    """The contributions of one retained-mode count, read from a truncation map.

    :func:`fbs_core.studies.truncation_map` keeps the interface forces ``g`` of every
    retained count (the solve that gives its responses, eqs. 2.37 and 4.1) and the
    chassis transfer mobility ``Y_ej^E``; the terms are ``Y_ej^E[:, :, k] g_k``, so the
    contributions of a count in the map cost a product, no tire synthesis and no
    solve. They are those of :func:`bushing_contributions` for the same harmonic,
    count, coupling and models (non-residual map: the same eq. 4.1).

    Parameters
    ----------
    truncation_map : TruncationMap
        Made with its interface forces (``truncation_map``, ``truncation_map_arrays``).
    n_modes : int or None
        A count of the map; ``None`` (or the tire's total) is the all-modes reference.
    load : str
        Name of the load input of the result.

    Returns
    -------
    Contributions
        Outputs the map's response DOFs, interface its coupled source DOFs.

    Raises
    ------
    FBSError
        When the map holds no forces for that count (compute it with
        :func:`bushing_contributions`).
    """
    m = truncation_map
    g = m.forces_for(n_modes)
    if g is None or m.transfer is None:
        held = ", ".join(str(int(n)) for n in m.n_modes)
        raise FBSError(
            f"the truncation map holds no interface forces for N = {n_modes} (counts {held}"
            f"{'' if m.forces is not None else '; made without the forces'})"
        )
    terms = m.transfer * g[:, None, :]
    return Contributions(m.freq, tuple(m.dofs), tuple(m.interface), load, terms, g, "mobility")
