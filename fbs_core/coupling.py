"""Labelled coupling API: FRF objects in, FRF objects out (thesis chapter 2).

Every function here checks labels, grids and quantities, then calls an array
kernel of :mod:`fbs_core.kernels`. Interfaces are given by DOF labels: either a
label present in both subsystems (``"hub:z"``) or a pair
``(label_in_a, label_in_b)`` such as ``("hub:z", "spindle:z")``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from . import kernels
from ._typing import ComplexArray, FloatArray, IntArray
from .dofs import index_of, parse_label
from .errors import DataFormatError, DOFError, QuantityError
from .frf import FRF

__all__ = [
    "couple_receptance",
    "couple_impedance",
    "couple_lm",
    "couple_generalized",
    "couple_response",
    "interface_condition",
]

Pair = tuple[str, str]
#: Interface DOFs: one label, or labels and ``(label_in_a, label_in_b)`` pairs.
Interface = str | Sequence[str | Sequence[str]]


def _is_pair(item: object) -> bool:
    return isinstance(item, Sequence) and len(item) == 2 and all(isinstance(s, str) for s in item)


def _pairs(interface: Interface) -> list[Pair]:
    if isinstance(interface, str):
        interface = [interface]
    pairs: list[Pair] = []
    for item in interface:
        if isinstance(item, str):
            pairs.append((item, item))
        elif _is_pair(item) and not isinstance(item, str):
            pairs.append((item[0], item[1]))
        else:
            raise DOFError(
                f"interface entries must be labels or (label_a, label_b) pairs, got {item!r}"
            )
    if not pairs:
        raise DOFError("the interface is empty: give at least one DOF label")
    return pairs


def _check_same(frfs: Sequence[FRF], what: str) -> None:
    for f in frfs[1:]:
        frfs[0].require_grid(f, what)
        if f.quantity != frfs[0].quantity:
            raise QuantityError(
                f"{what} mix quantities ({frfs[0].quantity} and {f.quantity}); convert with "
                ".to(...) first"
            )


def _require_square(Y: FRF, name: str) -> None:
    if set(Y.outputs) != set(Y.inputs) or len(Y.outputs) != len(Y.inputs):
        raise DataFormatError(
            f"{name} must be square over its DOFs (same outputs and inputs) for this method; "
            f"outputs {list(Y.outputs)}, inputs {list(Y.inputs)}"
        )


def _split(Y: FRF, iface: list[str], name: str) -> tuple[IntArray, IntArray, IntArray, IntArray]:
    """Indices of internal outputs/inputs and of interface outputs/inputs."""
    jo = index_of(Y.outputs, iface, f"interface output DOF of {name}")
    ji = index_of(Y.inputs, iface, f"interface input DOF of {name}")
    s = set(iface)
    o = [k for k, lab in enumerate(Y.outputs) if lab not in s]
    i = [k for k, lab in enumerate(Y.inputs) if lab not in s]
    return np.array(o, int), np.array(i, int), np.array(jo, int), np.array(ji, int)


def _check_unique(*groups: Sequence[str]) -> None:
    seen: set[str] = set()
    for g in groups:
        clash = seen.intersection(g)
        if clash:
            raise DOFError(
                f"internal DOF labels {sorted(clash)} occur in both subsystems; rename them "
                "or list them in the interface"
            )
        seen.update(g)


def couple_receptance(
    a: FRF,
    b: FRF,
    interface: Interface,
    *,
    rcond: float | None = None,
    max_cond: float | None = kernels.MAX_COND,
) -> FRF:
    """Receptance (mobility) coupling of two subsystems, thesis eq. 2.44.

    The general form is used, with ``Y_ja`` and ``Y_je`` taken as they are, so
    non-reciprocal subsystems (rolling tires) are coupled correctly.

    Parameters
    ----------
    a, b : FRF
        Subsystems on the same frequency grid, of the same quantity. Each must
        contain the interface DOFs among its outputs and its inputs.
    interface : sequence of str or (str, str)
        Interface DOF labels present in both, or pairs ``(label_in_a, label_in_b)``.
    rcond : float, optional
        Truncated-SVD regularisation of the interface matrix (see
        :func:`fbs_core.kernels.solve_interface`).
    max_cond : float, optional
        Raise :class:`SingularInterfaceError` above this condition number.

    Returns
    -------
    FRF
        Outputs: a's internal outputs, the interface (a's labels), b's internal
        outputs; inputs likewise.

    Raises
    ------
    DOFError, FrequencyGridError, QuantityError, SingularInterfaceError
    """
    pairs = _pairs(interface)
    _check_same([a, b], "subsystems")
    ja, jb = [p[0] for p in pairs], [p[1] for p in pairs]
    a_o, a_i, ja_o, ja_i = _split(a, ja, "a")
    b_o, b_i, jb_o, jb_i = _split(b, jb, "b")
    outs = [a.outputs[k] for k in a_o] + ja + [b.outputs[k] for k in b_o]
    ins = [a.inputs[k] for k in a_i] + ja + [b.inputs[k] for k in b_i]
    _check_unique([a.outputs[k] for k in a_o] + ja, [b.outputs[k] for k in b_o])
    _check_unique([a.inputs[k] for k in a_i] + ja, [b.inputs[k] for k in b_i])
    data = kernels.receptance_coupling(
        a.data,
        b.data,
        a_o,
        a_i,
        ja_o,
        ja_i,
        b_o,
        b_i,
        jb_o,
        jb_i,
        rcond=rcond,
        max_cond=max_cond,
        freq=a.freq,
    )
    return FRF(a.freq, data, outs, ins, a.quantity)


def couple_impedance(a: FRF, b: FRF, interface: Interface) -> FRF:
    """Impedance coupling of two subsystems, thesis eqs. 2.18-2.19.

    Both FRFs must be square over all their DOFs. Three matrix inversions per
    line (``n_a``, ``n_b`` and ``n* = n_a + n_b - n_j``); prefer
    :func:`couple_receptance`, which gives the same result with one.

    Returns
    -------
    FRF
        DOFs ordered as a's internal, interface (a's labels), b's internal.
    """
    pairs = _pairs(interface)
    _check_same([a, b], "subsystems")
    _require_square(a, "a")
    _require_square(b, "b")
    ja, jb = [p[0] for p in pairs], [p[1] for p in pairs]
    a_o, _, ja_o, _ = _split(a, ja, "a")
    b_o, _, jb_o, _ = _split(b, jb, "b")
    # square: map the same labels to input positions
    ai = np.array(index_of(a.inputs, [a.outputs[k] for k in a_o]), int)
    bi = np.array(index_of(b.inputs, [b.outputs[k] for k in b_o]), int)
    jai = np.array(index_of(a.inputs, ja), int)
    jbi = np.array(index_of(b.inputs, jb), int)
    # reorder so outputs and inputs coincide
    YA = a.data[:, np.r_[a_o, ja_o]][:, :, np.r_[ai, jai]]
    YB = b.data[:, np.r_[b_o, jb_o]][:, :, np.r_[bi, jbi]]
    na, nj, nb = len(a_o), len(ja), len(b_o)
    labels = [a.outputs[k] for k in a_o] + ja + [b.outputs[k] for k in b_o]
    _check_unique([a.outputs[k] for k in a_o] + ja, [b.outputs[k] for k in b_o])
    data = kernels.impedance_coupling(
        YA, YB, np.arange(na), np.arange(na, na + nj), np.arange(nb), np.arange(nb, nb + nj)
    )
    return FRF(a.freq, data, labels, labels, a.quantity)


def _qualified(subsystems: Mapping[str, FRF]) -> tuple[list[str], list[FRF]]:
    if len(subsystems) < 2:
        raise DataFormatError("give at least two named subsystems to couple")
    labels: list[str] = []
    frfs = list(subsystems.values())
    _check_same(frfs, "subsystems")
    for name, Y in subsystems.items():
        if "/" in name or ":" in name or not name:
            raise DOFError(f"subsystem name {name!r} must be non-empty without '/' or ':'")
        _require_square(Y, f"subsystem {name!r}")
        if Y.inputs != Y.outputs:
            raise DataFormatError(f"subsystem {name!r}: list inputs in the same order as outputs")
        labels += [f"{name}/{d}" for d in Y.outputs]
    return labels, frfs


def _connection_pairs(
    labels: list[str], connections: Sequence[Sequence[str]]
) -> list[tuple[int, int]]:
    idx = []
    for c in connections:
        if not _is_pair(c) or isinstance(c, str):
            raise DOFError(f"connections are pairs of labels 'name/dof', got {c!r}")
        p, m = index_of(labels, list(c), "connection DOF")
        if p == m:
            raise DOFError(f"connection {c!r} joins a DOF to itself")
        if parse_label(labels[p])[1] != parse_label(labels[m])[1]:
            raise DOFError(
                f"connection {c!r} joins different directions; transform the coordinates first"
            )
        idx.append((p, m))
    if not idx:
        raise DOFError("no connections given")
    return idx


def couple_lm(
    subsystems: Mapping[str, FRF],
    connections: Sequence[Pair],
    *,
    rcond: float | None = None,
    max_cond: float | None = kernels.MAX_COND,
) -> FRF:
    """Lagrange-multiplier FBS (de Klerk, Rixen & Voormeeren, AIAA J. 46(5), 2008).

    ``Y* = Y - Y B^T (B Y B^T)^-1 B Y`` for any number of subsystems, with the
    signed Boolean matrix ``B`` built from the connections (one row per pair:
    +1 at the first DOF, -1 at the second).

    Parameters
    ----------
    subsystems : dict of name -> FRF
        Square FRFs (inputs in the same order as outputs), same grid and quantity.
    connections : sequence of (str, str)
        Pairs of qualified labels ``"name/node:dir"``, e.g.
        ``("tire/hub:z", "chassis/spindle:z")``.
    rcond, max_cond : float, optional
        Truncated-SVD regularisation and condition limit of the interface
        matrix ``B Y B^T`` (see :func:`couple_receptance`).

    Returns
    -------
    FRF
        Over all DOFs of all subsystems, labelled ``"name/node:dir"``; connected
        DOFs appear once per subsystem and carry equal responses.
    """
    labels, frfs = _qualified(subsystems)
    pm = np.array(_connection_pairs(labels, connections), int)
    Y = _block_diag([f.data for f in frfs])
    data = kernels.lm_fbs_pairs(
        Y, pm[:, 0], pm[:, 1], rcond=rcond, max_cond=max_cond, freq=frfs[0].freq
    )
    return FRF(frfs[0].freq, data, labels, labels, frfs[0].quantity)


def couple_generalized(
    subsystems: Mapping[str, FRF],
    connections: Sequence[Pair],
    *,
    rcond: float | None = None,
    max_cond: float | None = kernels.MAX_COND,
) -> FRF:
    """Jetmundsen's generalized receptance coupling, thesis eq. 2.46.

    The connections are grouped into interfaces, one per pair of subsystems
    (J, K, L, M in thesis fig. 2.6), and the Boolean mapping matrix ``M``
    (subsystems x interfaces, eq. 2.50) is built from them: +1 for the first
    subsystem of a pair, -1 for the second.

    Parameters
    ----------
    subsystems : dict of name -> FRF
        Square FRFs (inputs in the same order as outputs), same grid and quantity.
    connections : sequence of (str, str)
        Pairs of qualified labels ``"name/node:dir"``.
    rcond, max_cond : float, optional
        Truncated-SVD regularisation and condition limit of the summed interface
        matrix (see :func:`couple_receptance`).

    Returns
    -------
    FRF
        Same labels and values as :func:`couple_lm`.
    """
    labels, frfs = _qualified(subsystems)
    names = list(subsystems)
    pm = _connection_pairs(labels, connections)
    owner = np.repeat(np.arange(len(frfs)), [len(f.outputs) for f in frfs])
    start = np.r_[0, np.cumsum([len(f.outputs) for f in frfs])]
    groups: dict[tuple[int, int], list[tuple[int, int]]] = {}
    for p, m in pm:
        si, sj = int(owner[p]), int(owner[m])
        if si == sj:
            raise DOFError(
                f"connection ({labels[p]!r}, {labels[m]!r}) lies inside subsystem {names[si]!r}"
            )
        key = (si, sj) if si < sj else (sj, si)
        groups.setdefault(key, []).append((p, m) if si < sj else (m, p))
    keys = list(groups)
    Mbool = np.zeros((len(frfs), len(keys)), int)
    interfaces = [[np.array([], int) for _ in keys] for _ in frfs]
    for k, key in enumerate(keys):
        plus, minus = key
        Mbool[plus, k], Mbool[minus, k] = 1, -1
        interfaces[plus][k] = np.array([p - start[plus] for p, _ in groups[key]], int)
        interfaces[minus][k] = np.array([m - start[minus] for _, m in groups[key]], int)
    internal = [np.arange(len(f.outputs)) for f in frfs]
    data = kernels.generalized_receptance(
        [f.data for f in frfs],
        internal,
        interfaces,
        Mbool,
        rcond=rcond,
        max_cond=max_cond,
        freq=frfs[0].freq,
    )
    return FRF(frfs[0].freq, data, labels, labels, frfs[0].quantity)


def _block_diag(blocks: list[ComplexArray]) -> ComplexArray:
    nf = blocks[0].shape[0]
    n = sum(b.shape[1] for b in blocks)
    out = np.zeros((nf, n, n), complex)
    k = 0
    for b in blocks:
        m = b.shape[1]
        out[:, k : k + m, k : k + m] = b
        k += m
    return out


def _interface_pairs(tire: FRF, chassis: FRF, interface: Interface | None) -> list[Pair]:
    if interface is not None:
        return _pairs(interface)
    if len(tire.inputs) != len(chassis.inputs):
        raise DOFError(
            f"cannot pair interface DOFs by position: tire has {list(tire.inputs)}, chassis "
            f"has {list(chassis.inputs)}; pass interface=[(tire_label, chassis_label), ...]"
        )
    pairs = list(zip(tire.inputs, chassis.inputs, strict=True))
    for t, c in pairs:
        if parse_label(t)[1] != parse_label(c)[1]:
            raise DOFError(
                f"interface DOFs paired by position have different directions: {t!r} and {c!r}; "
                "pass interface=[(tire_label, chassis_label), ...]"
            )
    return pairs


def couple_response(
    Y_ej: FRF,
    Y_jj_A: FRF,
    Y_jj_E: FRF,
    v_j: FRF,
    *,
    interface: Interface | None = None,
    couple: Sequence[str] | None = None,
    rcond: float | None = None,
    max_cond: float | None = kernels.MAX_COND,
) -> FRF:
    """Response at the receiver for a load on the source, thesis eq. 4.1.

    ``v_e* = Y_ej^E (Y_jj^A + Y_jj^E)^-1 (Y_ja^A F_a)``: one batched solve of
    the interface system over all lines (no explicit inverse, no Python loop).

    Parameters
    ----------
    Y_ej : FRF
        Receiver (chassis) transfer mobility from its interface DOFs (inputs) to
        the response DOFs (outputs), e.g. spindle -> bushing.
    Y_jj_A : FRF
        Source (tire) driving-point mobility at its interface DOFs.
    Y_jj_E : FRF
        Receiver driving-point mobility at its interface DOFs.
    v_j : FRF
        Free interface velocity of the source under the load, ``Y_ja^A F_a``
        (outputs: source interface DOFs; inputs: the load(s), e.g. ``"patch"``).
    interface : sequence of (str, str), optional
        Pairs ``(source_label, receiver_label)``. Default: pair ``Y_jj_A`` and
        ``Y_jj_E`` inputs by position, requiring equal directions.
    couple : sequence of str, optional
        Subset of the source interface labels to couple; the others are released
        (no force is transmitted there). E.g. all hub DOFs but ``"hub:ry"`` for a
        free-rolling wheel (5-DOF coupling).
    rcond, max_cond : float, optional
        See :func:`couple_receptance`.

    Returns
    -------
    FRF
        Outputs ``Y_ej.outputs``, inputs ``v_j.inputs``.
    """
    pairs = _interface_pairs(Y_jj_A, Y_jj_E, interface)
    if couple is not None:
        couple = list(couple)
        known = [p[0] for p in pairs]
        index_of(known, couple, "coupled interface DOF")
        pairs = [p for p in pairs if p[0] in set(couple)]
        if not pairs:
            raise DOFError("couple= selects no interface DOF")
    _check_same([Y_ej, Y_jj_A, Y_jj_E, v_j], "FRFs of eq. 4.1")
    ta, tc = [p[0] for p in pairs], [p[1] for p in pairs]
    YjjA = Y_jj_A.sel(outputs=ta, inputs=ta).data
    YjjE = Y_jj_E.sel(outputs=tc, inputs=tc).data
    Yej = Y_ej.sel(inputs=tc).data
    vj = v_j.sel(outputs=ta).data
    data = kernels.couple_response_kernel(
        Yej, YjjA, YjjE, vj, rcond=rcond, max_cond=max_cond, freq=Y_ej.freq
    )
    return FRF(Y_ej.freq, data, Y_ej.outputs, v_j.inputs, Y_ej.quantity)


def interface_condition(a: FRF, b: FRF, interface: Interface | None = None) -> FloatArray:
    """Condition number of ``Y_jj^A + Y_jj^B`` at every line, shape ``(n_freq,)``.

    This is the matrix inverted by receptance coupling (eq. 2.44) and by the
    fast path (eq. 4.1); large values flag an interface that amplifies noise
    (thesis section 2.2.1, Urgueira).
    """
    pairs = _interface_pairs(a, b, interface)
    _check_same([a, b], "subsystems")
    ta, tb = [p[0] for p in pairs], [p[1] for p in pairs]
    M = a.sel(outputs=ta, inputs=ta).data + b.sel(outputs=tb, inputs=tb).data
    return kernels.condition_number(M)
