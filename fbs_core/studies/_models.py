"""Plumbing between the reference models and the study kernels (arrays in, arrays out).

The studies need, on a frequency grid along one harmonic's speed line:

- from the tire (``tire.truncations``): ``Y_jj^A`` ``(n_N, n_f, 6, 6)`` and ``Y_ja^A F_a``
  ``(n_N, n_f, 6)`` for retained-mode counts ``n_N`` (cumulative modal sums);
- from the chassis (``chassis.mobility(freq)``, or an :class:`~fbs_core.frf.FRF` with
  inputs ``spindle:*`` and outputs ``spindle:*`` plus the response DOFs):
  ``Y_jj^E`` ``(n_f, 6, 6)`` and ``Y_ej^E`` ``(n_f, n_e, 6)``.

Tire hub DOFs and chassis spindle DOFs are paired by direction (``hub:z`` with
``spindle:z``). ``coupling`` selects the coupled directions: ``"6dof"`` (all, as in
the thesis), ``"5dof"`` (wheel spin ``ry`` released: a free-rolling wheel) or an
explicit sequence of directions; released DOFs transmit no force.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._typing import ComplexArray, FloatArray, IndexLike
from ..dofs import DIRECTIONS, parse_label
from ..errors import DOFError, FBSError, FrequencyGridError
from ..frf import FRF
from ..harmonics import Harmonic
from ..vocabulary import COUPLED_DIRECTIONS, COUPLINGS


def coupled_directions(coupling: str | Sequence[str]) -> tuple[str, ...]:
    """Directions coupled at the hub for ``coupling`` ("6dof", "5dof" or a sequence)."""
    if isinstance(coupling, str):
        if coupling in COUPLED_DIRECTIONS:
            return COUPLED_DIRECTIONS[coupling]
        raise FBSError(
            f"unknown coupling {coupling!r}; allowed: {', '.join(COUPLINGS)} or a sequence of "
            f"directions from {', '.join(DIRECTIONS)}"
        )
    dirs = tuple(coupling)
    bad = [d for d in dirs if d not in DIRECTIONS]
    if bad or not dirs or len(set(dirs)) != len(dirs):
        raise FBSError(
            f"coupling directions {list(dirs)} must be distinct and from {', '.join(DIRECTIONS)}"
        )
    return tuple(d for d in DIRECTIONS if d in dirs)


def resolve_tire(tire: Any) -> Any:
    if tire is None:
        from .. import reference_tire

        return reference_tire()
    if not hasattr(tire, "truncations"):
        raise FBSError(
            f"tire must be a modal tire model with truncations(freq, harmonic, n_modes_list), "
            f"got {type(tire).__name__}"
        )
    return tire


def resolve_harmonic(h: int | Harmonic) -> Harmonic:
    from ..harmonics import harmonic

    return harmonic(h)


def total_modes(tire: Any) -> int:
    """Number of (complex) modes of the tire model: the reference of the truncation study."""
    n = getattr(tire, "n_modes", None)
    if n is None:
        raise FBSError(f"tire model {type(tire).__name__} does not report its n_modes")
    return int(n)


def chassis_arrays(
    chassis: Any, freq: FloatArray, dirs: Sequence[str]
) -> tuple[ComplexArray, ComplexArray, tuple[str, ...]]:
    """``(Y_jj^E (n_f, n_c, n_c), Y_ej^E (n_f, n_e, n_c), response labels)``.

    ``chassis`` is a model with ``mobility(freq)`` (default: the reference chassis)
    or an FRF on exactly ``freq``. The interface is its ``spindle:*`` inputs in the
    coupled directions; the responses are all outputs that are not spindle DOFs.
    """
    if chassis is None:
        from .. import reference_chassis

        chassis = reference_chassis()
    if isinstance(chassis, FRF):
        Y = chassis
        if Y.freq.shape != freq.shape or not np.allclose(Y.freq, freq, rtol=1e-12, atol=0):
            raise FrequencyGridError(
                f"chassis FRF lines ({Y.freq.size} lines {Y.freq[0]:g}-{Y.freq[-1]:g} Hz) differ "
                f"from the study grid ({freq.size} lines {freq[0]:g}-{freq[-1]:g} Hz); "
                "interpolate it explicitly with .interpolate(freq)"
            )
    elif hasattr(chassis, "mobility"):
        Y = chassis.mobility(freq)
    else:
        raise FBSError(
            f"chassis must be a chassis model with mobility(freq) or an FRF, "
            f"got {type(chassis).__name__}"
        )
    Y = Y.to("mobility") if Y.quantity != "mobility" else Y
    spindle = [f"spindle:{d}" for d in dirs]
    missing = [s for s in spindle if s not in Y.inputs or s not in Y.outputs]
    if missing:
        raise DOFError(
            f"chassis FRF lacks interface DOF(s) {missing}; inputs: {', '.join(Y.inputs)}; "
            f"outputs: {', '.join(Y.outputs)}"
        )
    resp = [o for o in Y.outputs if parse_label(o)[0] != "spindle"]
    if not resp:
        raise DOFError(f"chassis FRF has no response DOFs besides the spindle: {Y.outputs}")
    YjjE = Y.sel(outputs=spindle, inputs=spindle).data
    YejE = Y.sel(outputs=resp, inputs=spindle).data
    return np.ascontiguousarray(YjjE), np.ascontiguousarray(YejE), tuple(resp)


def tire_arrays(
    tire: Any,
    freq: FloatArray,
    h: Harmonic,
    n_modes_list: IndexLike,
    dirs: Sequence[str],
    residual: bool = False,
) -> tuple[ComplexArray, ComplexArray]:
    """``(Y_jj^A (n_N, n_f, n_c, n_c), v_j (n_N, n_f, n_c))`` in the coupled directions.

    ``residual``: the tire compensates the modes left out (``truncations(...,
    residual=True)``; a tire model without that keyword raises :class:`FBSError`).
    """
    if residual:
        try:
            YjjA, vj = tire.truncations(freq, h, list(n_modes_list), residual=True)
        except TypeError as e:
            raise FBSError(
                f"tire model {type(tire).__name__} has no residual compensation "
                "(truncations(..., residual=True))"
            ) from e
    else:
        YjjA, vj = tire.truncations(freq, h, list(n_modes_list))
    YjjA = np.asarray(YjjA)
    vj = np.asarray(vj)
    n = len(n_modes_list)
    if YjjA.shape != (n, freq.size, 6, 6) or vj.shape != (n, freq.size, 6):
        raise FBSError(
            f"tire.truncations returned shapes {YjjA.shape}, {vj.shape}; expected "
            f"{(n, freq.size, 6, 6)} and {(n, freq.size, 6)}"
        )
    idx = [DIRECTIONS.index(d) for d in dirs]
    if len(idx) < 6:
        YjjA = YjjA[:, :, idx][:, :, :, idx]
        vj = vj[:, :, idx]
    return np.ascontiguousarray(YjjA), np.ascontiguousarray(vj)
