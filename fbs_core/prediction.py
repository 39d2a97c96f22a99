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

import numpy as np

from .chassis import BUSHING, SPINDLE, ChassisModel, reference_chassis
from .coupling import couple_response
from .dofs import DIRECTIONS, node_labels
from .errors import FBSError
from .frf import FRF, check_grid
from .harmonics import Harmonic, harmonic

__all__ = ["bushing_response", "coupled_dofs", "COUPLINGS", "HUB"]

#: Hub DOF labels of the tire, in vehicle coordinates.
HUB: tuple[str, ...] = node_labels("hub")

#: Coupling options: the hub DOFs joined to the spindle.
COUPLINGS: dict[str, tuple[str, ...]] = {
    "6dof": HUB,
    "5dof": tuple(d for d in HUB if d != "hub:ry"),
}


class CouplingOptionError(FBSError):
    """An unknown coupling option."""


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
    if not isinstance(coupling, str) or coupling not in COUPLINGS:
        raise CouplingOptionError(
            f"unknown coupling {coupling!r}; allowed: {', '.join(map(repr, COUPLINGS))} "
            "(all hub DOFs = braked wheel, or wheel spin hub:ry released = free rolling)"
        )
    return COUPLINGS[coupling]


def _interface() -> list[tuple[str, str]]:
    return [(f"hub:{d}", f"spindle:{d}") for d in DIRECTIONS]


def _tire_frfs(tire, h: Harmonic, f: np.ndarray, n_modes, speed_kmh):
    """Y_jj^A and Y_ja^A F_a as FRFs (along the harmonic line, or at a fixed speed)."""
    if speed_kmh is None:
        Yjj, vj = tire.truncations(f, h, [tire.n_modes if n_modes is None else n_modes])
        Y_A = FRF(f, Yjj[0], HUB, HUB, "mobility")
        v_A = FRF(f, vj[0][:, :, None], HUB, ["patch"], "mobility")
    else:
        Y_A = tire.hub_mobility(f, speed_kmh, n_modes)
        v_A = tire.patch_response(f, h, n_modes, speed_kmh=speed_kmh)
    return Y_A, v_A


@functools.lru_cache(maxsize=64)
def _cached(k: int, n_modes, fbytes: bytes, coupling: str, speed_kmh) -> FRF:
    from . import reference_tire  # the tire package registers it at import

    return _compute(
        reference_tire(),
        reference_chassis(),
        harmonic(k),
        np.frombuffer(fbytes, float),
        n_modes,
        coupling,
        speed_kmh,
    )


def _compute(tire, chassis: ChassisModel, h: Harmonic, f, n_modes, coupling, speed_kmh):
    Y_A, v_A = _tire_frfs(tire, h, f, n_modes, speed_kmh)
    Y_E = chassis.mobility(f, outputs=SPINDLE + BUSHING, inputs=SPINDLE)
    return couple_response(
        Y_E.sel(outputs=BUSHING),
        Y_A,
        Y_E.sel(outputs=SPINDLE),
        v_A,
        interface=_interface(),
        couple=coupled_dofs(coupling),
    )


def bushing_response(
    harmonic_case,
    n_modes: int | None = None,
    freq=None,
    coupling: str = "6dof",
    *,
    speed_kmh: float | None = None,
    tire=None,
    chassis: ChassisModel | None = None,
) -> FRF:
    """Velocity at the chosen bushing for the patch load of a harmonic case (eq. 4.1).

    Parameters
    ----------
    harmonic_case : int or Harmonic
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
    h = harmonic(harmonic_case)
    coupled_dofs(coupling)
    f = h.frequencies() if freq is None else check_grid(freq)
    if speed_kmh is not None:
        speed_kmh = float(speed_kmh)
    if tire is None and chassis is None and h in _HARMONIC_SET:
        return _cached(h.k, n_modes, f.tobytes(), coupling, speed_kmh)
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
    )


_HARMONIC_SET = {harmonic(k) for k in range(1, 8)}
