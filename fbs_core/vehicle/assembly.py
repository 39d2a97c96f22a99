"""The five subsystems (four tires and the car) coupled whole, and assembled directly.

Two second ways to the response of :mod:`.response` (eq. 4.1 with the four hubs as
one interface), used by the tests:

- :func:`couple_vehicle`: the five subsystems' FRFs coupled by LM-FBS (``couple_lm``;
  de Klerk, Rixen & Voormeeren 2008) or by Jetmundsen's generalized receptance
  coupling (``couple_generalized``, thesis eq. 2.46), 24 (or 20) interface DOFs,
  giving the coupled FRF of the whole car on its tires; the road response follows
  from it with each tire's blocked force ``Y_hh^-1 v_h`` at its hub
  (:func:`blocked_force_response`: the tire's internal patch load acts on the
  coupled car as that force at its hub, since the tire meets the rest only there);
- :func:`direct_transfer`: no FBS at all: the car's matrices (``M``, the dampers'
  ``C``, the hysteretic ``K``) and the four tires' matrices at the speed of every
  line (the right ones the physical mirror image, :func:`~.tires.mirror_tire`)
  joined at the hubs by primal assembly, and the dynamic stiffness solved for the
  four patch loads (the ground truth, as :func:`fbs_core.prediction.
  direct_bushing_response` for the corner).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike

from .._typing import ComplexArray
from ..coupling import couple_generalized, couple_lm
from ..dofs import node_labels
from ..errors import FBSError
from ..frf import FRF, check_grid
from .layout import WHEELS, spindle_labels
from .model import VehicleModel, reference_vehicle
from .response import coupled_directions
from .tires import mirror_tire, wheel_models

__all__ = ["couple_vehicle", "blocked_force_response", "direct_transfer", "METHODS"]

#: Coupling methods of :func:`couple_vehicle`.
METHODS: tuple[str, ...] = ("lm", "generalized")


def couple_vehicle(
    vehicle: FRF,
    tires: Mapping[str, FRF],
    coupling: str | Mapping[str, str] = "6dof",
    method: str = "lm",
) -> FRF:
    """The car on its four tires: five FRFs coupled at once.

    Parameters
    ----------
    vehicle : FRF
        The car's mobility, square (outputs = inputs, same order), holding the hub
        DOFs ``spindle_<w>:*``.
    tires : mapping wheel -> FRF
        Hub mobility ``hub:x`` ... ``hub:rz`` (6 x 6) of each wheel's tire, in its
        wheel's vehicle axes.
    coupling : {"6dof", "5dof"} or mapping wheel -> option
    method : {"lm", "generalized"}
        LM-FBS or generalized receptance coupling (eq. 2.46).

    Returns
    -------
    FRF
        Over ``vehicle/<dof>`` and ``tire_<w>/hub:<d>``; connected DOFs carry equal
        responses.

    Raises
    ------
    FBSError
        For an unknown method or a wheel without a tire.
    """
    if method not in METHODS:
        raise FBSError(f"unknown coupling method {method!r}; allowed: {', '.join(METHODS)}")
    if set(tires) != set(WHEELS):
        raise FBSError(f"give a tire for each wheel {', '.join(WHEELS)}, got {list(tires)}")
    dirs = coupled_directions(coupling)
    subs = {"vehicle": vehicle, **{f"tire_{w}": tires[w] for w in WHEELS}}
    conn = [(f"tire_{w}/hub:{d}", f"vehicle/spindle_{w}:{d}") for w in WHEELS for d in dirs[w]]
    fn = couple_lm if method == "lm" else couple_generalized
    return fn(subs, conn)


def blocked_force_response(
    coupled: FRF, tires: Mapping[str, tuple[FRF, FRF]], outputs: Sequence[str]
) -> ComplexArray:
    """Road response from the coupled FRF and each tire's blocked force at its hub.

    ``v_e = Y*_(e, hub_w) (Y^A_w)^-1 v^A_w`` per wheel, shape ``(n_f, n_e, 4)``
    (``outputs`` are the car's labels, without the ``vehicle/`` prefix).
    """
    hub = node_labels("hub")
    out = []
    for w in WHEELS:
        Y, v = tires[w]
        fb = np.linalg.solve(Y.sel(outputs=hub, inputs=hub).data, v.sel(outputs=hub).data)
        Ys = coupled.sel(
            outputs=[f"vehicle/{o}" for o in outputs], inputs=[f"tire_{w}/{h}" for h in hub]
        ).data
        out.append((Ys @ fb)[:, :, 0])
    return np.stack(out, axis=-1)


def direct_transfer(
    freq: ArrayLike,
    speed_kmh: float | ArrayLike,
    wavelength: float | None = None,
    coupling: str | Mapping[str, str] = "6dof",
    *,
    outputs: Sequence[str] = ("seat_fl:z",),
    vehicle: VehicleModel | None = None,
    tire: Any = None,
) -> ComplexArray:
    """Ground truth: the assembled matrices of the car and four tires, solved line by line.

    Parameters
    ----------
    freq : array_like, shape (n_f,)
        Lines in Hz.
    speed_kmh : float or array_like, shape (n_f,)
        Speed of every line (a harmonic line: ``3.6 f lambda``).
    wavelength : float, optional
        Road wavelength of every line (a harmonic case); default ``v / f`` (a fixed
        speed, every wavelength).
    coupling : {"6dof", "5dof"} or mapping wheel -> option
    outputs : sequence of str
        Response DOFs of the car.
    vehicle : VehicleModel, optional
    tire : TireModel with physical parameters, optional
        A left tire, mirrored on the right wheels (physically: flipped camber, toe and
        conicity), or a mapping wheel -> model.

    Returns
    -------
    ndarray, shape (n_f, n_e, 4)
        Velocity (mobility) per metre of road at each wheel.
    """
    f = check_grid(freq)
    speeds = np.broadcast_to(np.asarray(speed_kmh, float), f.shape)
    car = reference_vehicle() if vehicle is None else vehicle
    dirs = coupled_directions(coupling)
    models = {w: (mirror_tire(m) if mir else m) for w, (m, mir) in wheel_models(tire).items()}
    cs = car.system()
    Zparts = [sp.csc_matrix(a) for a in (cs.K, cs.M, cs.C)]
    keep = [lab for w in WHEELS for lab in spindle_labels(w)] + list(outputs)
    kidx = [cs.dofs.index(lab) for lab in keep]
    out = np.empty((f.size, len(outputs), len(WHEELS)), complex)
    systems: dict[tuple[int, float], Any] = {}
    for i, (fi, v) in enumerate(zip(f, speeds, strict=True)):
        w_ = 2 * np.pi * fi
        # the car condensed exactly onto its hubs and responses (Gaussian elimination
        # of its other DOFs)
        Ze = (Zparts[0] - w_**2 * Zparts[1] + 1j * w_ * Zparts[2]).tocsc()
        rhs = np.zeros((cs.n, len(kidx)), complex)
        rhs[kidx, np.arange(len(kidx))] = 1.0
        S = np.linalg.inv(spla.splu(Ze).solve(rhs)[kidx])
        # global numbering: the four tires, then the car's kept DOFs not merged
        blocks: list[tuple[np.ndarray, ComplexArray]] = []
        loads: list[tuple[np.ndarray, ComplexArray]] = []
        where: dict[str, int] = {}
        n = 0
        for w in WHEELS:
            key = (id(models[w]), float(v))
            if key not in systems:  # one build per model and speed (a fixed speed: one)
                systems[key] = models[w].system(float(v))
            ts = systems[key]
            idx = np.arange(n, n + ts.n)
            blocks.append((idx, ts.K - w_**2 * ts.M + 1j * w_ * ts.C))
            lam = float(wavelength) if wavelength is not None else float(v) / 3.6 / fi
            loads.append((idx, models[w].patch_load(float(v), lam)))
            for k, d in enumerate(ts.dofs[:6]):
                if d.split(":")[1] in dirs[w]:
                    where[f"spindle_{w}:{d.split(':')[1]}"] = n + k
            n += ts.n
        ie = []
        for lab in keep:
            if lab not in where:
                where[lab] = n
                n += 1
            ie.append(where[lab])
        Z = np.zeros((n, n), complex)
        for idx, Zt in blocks:
            Z[np.ix_(idx, idx)] += Zt
        ie_a = np.asarray(ie)
        Z[np.ix_(ie_a, ie_a)] += S
        B = np.zeros((n, len(WHEELS)), complex)
        for k, (idx, load) in enumerate(loads):
            B[idx, k] = load
        x = np.linalg.solve(Z, B)
        out[i] = 1j * w_ * x[[where[o] for o in outputs]]
    return out
