"""Four rolling tires on one car: the response to the road under every wheel.

The thesis' eq. 4.1 with the four hubs as one interface (24 DOFs with 6-DOF hubs,
20 with the spin released):

``v_e* = Y_ej^E (Y_jj^A + Y_jj^E)^-1 V_j^A``

with ``Y_jj^A = blockdiag(Y^A_fl, Y^A_fr, Y^A_rl, Y^A_rr)`` the four tires' hub
mobilities (no coupling between tires but through the car), ``Y_jj^E`` the car's
mobility between its four hubs, ``Y_ej^E`` from the hubs to the responses, and
``V_j^A`` ``(n_j, 4)`` the free hub velocity of each tire under 1 m of road at its
own patch (column ``w`` nonzero in wheel ``w``'s block only). This is the
generalized receptance coupling of the five subsystems (thesis eq. 2.46) read at
the responses: one solve of the 24 x 24 interface per line, for all four wheels
(:mod:`.assembly` couples the five FRFs with ``couple_lm`` / ``couple_generalized``
and solves the assembled matrices directly, for the tests). The result,
:class:`WheelTransfer`, is the response per metre of road under each wheel; a
:class:`~.road.Road` combines the wheels (:class:`VehicleResponse`).

Contributions: by wheel (which wheel's road causes it, ``H[:, :, w] u_w``) and by
path (which hub DOF carries it into the car, ``Y_ej^E[:, k] g_k`` with the
interface forces ``g``: eq. 4.1 term by term, as the single corner's
:func:`fbs_core.analysis.bushing_contributions`).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .. import kernels
from .._typing import ComplexArray, FloatArray
from ..analysis.contributions import Contributions
from ..dofs import DIRECTIONS, node_labels, parse_label
from ..errors import DOFError, FBSError, QuantityError
from ..frf import FRF, check_grid
from ..harmonics import Harmonic
from ..harmonics import harmonic as _harmonic
from ..prediction import coupled_dofs
from ..vocabulary import readonly
from .layout import WHEELS, hub_labels, road_label, spindle_labels
from .model import FRFVehicle, VehicleModel, reference_vehicle
from .road import Road, RoadProfile
from .tires import tire_at_speed, wheel_arrays

__all__ = [
    "WheelTransfer",
    "VehicleResponse",
    "couple_wheels",
    "vehicle_transfer",
    "vehicle_response",
    "road_transfer",
    "random_road_response",
    "coupled_directions",
    "interface_arrays",
    "solve_checked",
    "transfer_kernel",
]

Vehicle = VehicleModel | FRFVehicle


def coupled_directions(coupling: str | Mapping[str, str]) -> dict[str, tuple[str, ...]]:
    """Coupled hub directions per wheel: one option for all (``"6dof"`` / ``"5dof"``) or a
    mapping wheel -> option (e.g. driven front wheels braked, rear ones free rolling)."""
    per = {w: coupling for w in WHEELS} if isinstance(coupling, str) else dict(coupling)
    if set(per) != set(WHEELS):
        raise FBSError(f"coupling per wheel needs exactly {', '.join(WHEELS)}, got {list(per)}")
    return {w: tuple(d.split(":")[1] for d in coupled_dofs(per[w])) for w in WHEELS}


def interface_arrays(
    YA: ComplexArray, vA: ComplexArray, blocks: Sequence[Sequence[int]]
) -> tuple[ComplexArray, ComplexArray]:
    """The tires as one source: block-diagonal hub mobility and free hub velocities.

    Parameters
    ----------
    YA : ndarray, shape (n_w, ..., 6, 6)
        Hub mobility of every tire (all six DOFs).
    vA : ndarray, shape (n_w, ..., 6)
        Free hub velocity of every tire per unit road at its patch.
    blocks : sequence of index sequences
        For tire ``w``, its coupled directions (indices 0..5); the interface is their
        concatenation, tire by tire.

    Returns
    -------
    A : ndarray, shape (..., n_j, n_j)
        ``blockdiag(Y^A_w)`` over the coupled DOFs.
    V : ndarray, shape (..., n_j, n_w)
        Column ``w``: tire ``w``'s free hub velocity in its block, zero elsewhere.
    """
    n_j = sum(len(b) for b in blocks)
    lead = YA.shape[1:-2]
    A = np.zeros(lead + (n_j, n_j), complex)
    V = np.zeros(lead + (n_j, len(blocks)), complex)
    k = 0
    for w, idx in enumerate(blocks):
        ix = np.asarray(idx)
        sl = slice(k, k + ix.size)
        A[..., sl, sl] = YA[w][..., ix[:, None], ix[None, :]]
        V[..., sl, w] = vA[w][..., ix]
        k += ix.size
    return A, V


def transfer_kernel(
    YjjE: ComplexArray,
    YejE: ComplexArray,
    YA: ComplexArray,
    vA: ComplexArray,
    blocks: Sequence[Sequence[int]],
    freq: FloatArray | None = None,
) -> tuple[ComplexArray, ComplexArray]:
    """Eq. 4.1 with the hubs of several tires as one interface (pure arrays).

    Parameters
    ----------
    YjjE : ndarray, shape (..., n_j, n_j)
        Car mobility between its coupled hub DOFs.
    YejE : ndarray, shape (..., n_e, n_j)
        Car transfer mobility from the hubs to the responses.
    YA, vA, blocks
        The tires, see :func:`interface_arrays`.

    Returns
    -------
    H : ndarray, shape (..., n_e, n_w)
        Response per unit road at each tire.
    g : ndarray, shape (..., n_j, n_w)
        Interface forces on the car.
    """
    A, V = interface_arrays(YA, vA, blocks)
    if A.shape[-1] != YjjE.shape[-1]:
        raise FBSError(
            f"the tires' coupled DOFs ({A.shape[-1]}) do not match the car's hub DOFs "
            f"({YjjE.shape[-1]})"
        )
    g = solve_checked(A + YjjE, V, freq)
    return YejE @ g, g


def _sq_frobenius(X: ComplexArray) -> FloatArray:
    """``||X||_F^2`` of every matrix of a stack (real and imaginary parts as reals)."""
    r = np.ascontiguousarray(X).view(np.float64)
    out: FloatArray = np.einsum("...ij,...ij->...", r, r)
    return out


def solve_checked(A: ComplexArray, B: ComplexArray, freq: FloatArray | None = None) -> ComplexArray:
    """``A^-1 B`` for a stack of interface matrices, refusing ill-conditioned ones.

    The same refusal as :func:`fbs_core.kernels.solve_interface` with ``max_cond=
    MAX_COND`` (a :class:`SingularInterfaceError` above a 2-norm condition number of
    1e13), certified more cheaply for a large interface: the inverse gives the
    Frobenius condition number ``||A||_F ||A^-1||_F >= cond_2(A)``, and only the lines
    where it exceeds the limit get the singular values (for 24 x 24 matrices the
    singular values of every line cost about three inverses).
    """
    try:
        inv = np.linalg.inv(A)
    except np.linalg.LinAlgError:  # exactly singular somewhere: the kernel's error names it
        with np.errstate(divide="ignore", invalid="ignore"):  # its condition numbers: inf
            return kernels.solve_interface(A, B, max_cond=kernels.MAX_COND, freq=freq)
    cf = np.sqrt(_sq_frobenius(A) * _sq_frobenius(inv))
    bad = ~(cf <= kernels.MAX_COND)
    if np.any(bad):
        kernels.solve_interface(
            A[bad], B[bad], max_cond=kernels.MAX_COND, freq=None if freq is None else freq[bad]
        )
    out: ComplexArray = inv @ B
    return out


@dataclass(frozen=True, eq=False)
class WheelTransfer:
    """The car's response per metre of road under each wheel (eq. 4.1, all hubs at once).

    Attributes
    ----------
    freq : ndarray, shape (n_f,)
    outputs : tuple of str
        Response DOFs (n_e).
    interface : tuple of str
        Coupled tire hub DOFs, ``hub_fl:x`` ... (n_j).
    data : ndarray, shape (n_f, n_e, 4)
        Response per metre of road amplitude at wheel ``WHEELS[w]`` (its own phase).
    forces : ndarray, shape (n_f, n_j, 4)
        Interface forces on the car per metre of road at each wheel.
    Yej : ndarray, shape (n_f, n_e, n_j)
        The car's transfer mobility hubs -> responses.
    wheelbase, track : float
        Geometry the road delay and the track coherency use (m).
    quantity : str
    """

    freq: FloatArray
    outputs: tuple[str, ...]
    interface: tuple[str, ...]
    data: ComplexArray
    forces: ComplexArray
    Yej: ComplexArray
    wheelbase: float
    track: float
    quantity: str = "mobility"

    def __post_init__(self) -> None:
        for name in ("freq", "data", "forces", "Yej"):
            object.__setattr__(self, name, readonly(getattr(self, name)))

    def frf(self) -> FRF:
        """As an FRF: outputs x inputs ``road_fl`` ... ``road_rr``."""
        return FRF(
            self.freq,
            self.data,
            self.outputs,
            [road_label(w) for w in WHEELS],
            self.quantity,
            kinds={road_label(w): "road" for w in WHEELS},
        )

    def apply(self, road: Road) -> VehicleResponse:
        """The response to a road (:class:`~.road.Road`) on this car."""
        labels, U = road.components(self.freq, self.wheelbase, self.track)
        return VehicleResponse(self, road, labels, U)


@dataclass(frozen=True, eq=False)
class VehicleResponse:
    """The response to a road: per uncorrelated track component, and its level.

    Attributes
    ----------
    transfer : WheelTransfer
    road : Road
    components : tuple of str
        ``road_in_phase`` / ``road_anti_phase`` (those not identically zero).
    inputs : ndarray, shape (n_f, 4, n_c)
        Road input of every wheel per component (:meth:`Road.components`).
    """

    transfer: WheelTransfer
    road: Road
    components: tuple[str, ...]
    inputs: ComplexArray

    @property
    def freq(self) -> FloatArray:
        return self.transfer.freq

    @property
    def outputs(self) -> tuple[str, ...]:
        return self.transfer.outputs

    @property
    def response(self) -> FRF:
        """Complex response per component, outputs x components (per metre of road
        amplitude, or per sqrt(Hz) of a random road: an amplitude spectral density)."""
        t = self.transfer
        data = t.data @ self.inputs  # (n_f, n_e, 4) @ (n_f, 4, n_c)
        return FRF(
            t.freq,
            data,
            t.outputs,
            self.components,
            t.quantity,
            kinds=dict.fromkeys(self.components, "road"),
        )

    @property
    def level(self) -> FloatArray:
        """``sqrt(sum_c |response_c|^2)`` per line and output, shape ``(n_f, n_e)``: the
        amplitude of a coherent road, the root of the PSD of a random one."""
        d = self.response.data
        out: FloatArray = np.sqrt(np.sum(np.abs(d) ** 2, axis=-1))
        return out

    @property
    def psd(self) -> FloatArray:
        """Response PSD (one-sided) per line and output, ``(n_f, n_e)``: with a random
        road profile in (m/s)^2/Hz (mobility), else the squared amplitude."""
        return self.level**2

    def rms(self, fmin: float | None = None, fmax: float | None = None) -> FloatArray:
        """RMS of each output over ``[fmin, fmax]`` (trapezoidal integral of the PSD).

        Raises
        ------
        FBSError
            Without a random road profile (a harmonic response has no RMS over a band).
        """
        if self.road.profile is None:
            raise FBSError(
                "RMS levels need a random road (Road(speed_kmh=..., profile=RoadProfile(...)))"
            )
        f = self.freq
        sel = (f >= (f[0] if fmin is None else fmin)) & (f <= (f[-1] if fmax is None else fmax))
        if sel.sum() < 2:
            raise FBSError(f"the band {fmin}-{fmax} Hz holds fewer than two lines")
        out: FloatArray = np.sqrt(np.trapezoid(self.psd[sel], f[sel], axis=0))
        return out

    def _component(self, component: str | None) -> int:
        if component is None:
            if len(self.components) > 1:
                raise FBSError(
                    f"this road has {len(self.components)} uncorrelated components "
                    f"({', '.join(self.components)}): name one"
                )
            return 0
        if component not in self.components:
            raise DOFError(
                f"unknown road component {component!r}; available: {', '.join(self.components)}"
            )
        return self.components.index(component)

    def by_wheel(self, component: str | None = None) -> FRF:
        """Contribution of each wheel's road, outputs x ``road_fl`` ... (sum: the response).

        Parameters
        ----------
        component : str, optional
            Needed when the road has two components (partial track coherence).
        """
        c = self._component(component)
        t = self.transfer
        data = t.data * self.inputs[:, None, :, c]
        return FRF(
            t.freq,
            data,
            t.outputs,
            [road_label(w) for w in WHEELS],
            t.quantity,
            kinds={road_label(w): "road" for w in WHEELS},
        )

    def by_path(self, component: str | None = None) -> Contributions:
        """Contribution of every coupled hub DOF of every wheel (eq. 4.1 term by term).

        ``terms[:, e, k] = Y_ej^E[:, e, k] g_k`` with ``g`` the interface forces of this
        road; the terms sum to the response (:attr:`Contributions.total`).
        """
        c = self._component(component)
        t = self.transfer
        g = (t.forces @ self.inputs[:, :, c : c + 1])[..., 0]  # (n_f, n_j)
        return Contributions(
            t.freq, t.outputs, t.interface, self.components[c], t.Yej * g[:, None, :], g, t.quantity
        )

    def by_hub(self, component: str | None = None) -> FRF:
        """The path contributions summed per wheel hub, outputs x ``hub_fl`` ... ``hub_rr``."""
        p = self.by_path(component)
        nodes = [parse_label(lab)[0] for lab in p.interface]
        hubs = [f"hub_{w}" for w in WHEELS]
        data = np.stack(
            [p.terms[:, :, [k for k, n in enumerate(nodes) if n == h]].sum(-1) for h in hubs],
            axis=-1,
        )
        return FRF(p.freq, data, p.outputs, hubs, p.quantity, kinds=dict.fromkeys(hubs, "road"))


def _outputs(requested: Sequence[str] | str | None, available: Sequence[str]) -> tuple[str, ...]:
    """Response labels: all non-hub outputs, labels, or node names (six DOFs each)."""
    if requested is None:
        return tuple(o for o in available if not parse_label(o)[0].startswith("spindle_"))
    items = [requested] if isinstance(requested, str) else list(requested)
    out: list[str] = []
    for item in items:
        if ":" in item or item in available:
            out.append(item)
        else:
            labs = [lab for lab in node_labels(item) if lab in available]
            if not labs:
                raise DOFError(
                    f"unknown response {item!r}: neither a DOF label nor a node with DOFs among "
                    f"the car's outputs ({', '.join(available[:8])} ...)"
                )
            out += labs
    missing = [o for o in out if o not in available]
    if missing:
        raise DOFError(f"unknown response DOF {missing[0]!r}; e.g. {', '.join(available[:8])}")
    return tuple(out)


def _car(vehicle: Vehicle | None) -> Vehicle:
    v = reference_vehicle() if vehicle is None else vehicle
    if not isinstance(v, VehicleModel | FRFVehicle):
        raise FBSError(
            f"vehicle must be a VehicleModel or an FRFVehicle, got {type(v).__name__} (wrap an "
            "FRF as FRFVehicle(frf, wheelbase=..., track=...))"
        )
    return v


def _car_arrays(
    car: Vehicle, f: FloatArray, dirs: Mapping[str, Sequence[str]], outputs: Any
) -> tuple[ComplexArray, ComplexArray, tuple[str, ...], tuple[str, ...]]:
    """``(Y_jj^E, Y_ej^E, response labels, car hub labels)`` on ``f`` (read-only)."""
    hubs = tuple(lab for w in WHEELS for lab in spindle_labels(w, dirs[w]))
    if isinstance(car, VehicleModel):
        from .model import RESPONSES

        resp = _outputs(outputs, RESPONSES)
        YjjE, YejE = _model_arrays(car.params, f.tobytes(), hubs, resp)
        return YjjE, YejE, resp, hubs
    Yall = car.mobility(f)
    resp = _outputs(outputs, Yall.outputs)
    missing = [h for h in hubs if h not in Yall.inputs or h not in Yall.outputs]
    if missing:
        raise DOFError(
            f"the vehicle FRF lacks the hub DOF(s) {', '.join(missing[:6])} (inputs and "
            "outputs spindle_<w>:<d> of every coupled direction)"
        )
    Y = Yall.sel(outputs=hubs + resp, inputs=hubs)
    if Y.quantity != "mobility":
        Y = Y.to("mobility")
    n = len(hubs)
    return Y.data[:, :n], Y.data[:, n:], resp, hubs


@functools.lru_cache(maxsize=32)
def _model_arrays(
    p: Any, fbytes: bytes, hubs: tuple[str, ...], resp: tuple[str, ...]
) -> tuple[ComplexArray, ComplexArray]:
    """The reference car's hub and transfer mobilities on a grid, cached (read-only)."""
    Y = VehicleModel(p).mobility(np.frombuffer(fbytes, float), outputs=hubs + resp, inputs=hubs)
    n = len(hubs)
    YjjE, YejE = np.ascontiguousarray(Y.data[:, :n]), np.ascontiguousarray(Y.data[:, n:])
    for a in (YjjE, YejE):
        a.setflags(write=False)
    return YjjE, YejE


def _geometry(car: Vehicle) -> tuple[float, float]:
    tr = car.track
    return float(car.wheelbase), float(0.5 * (tr[0] + tr[1]))


def _transfer(
    car: Vehicle,
    f: FloatArray,
    dirs: Mapping[str, Sequence[str]],
    outputs: Any,
    YA: ComplexArray,
    vA: ComplexArray,
) -> WheelTransfer:
    YjjE, YejE, resp, _ = _car_arrays(car, f, dirs, outputs)
    blocks = [[DIRECTIONS.index(d) for d in dirs[w]] for w in WHEELS]
    H, g = transfer_kernel(YjjE, YejE, YA, vA, blocks, f)
    iface = tuple(lab for w in WHEELS for lab in hub_labels(w, dirs[w]))
    L, B = _geometry(car)
    return WheelTransfer(f, resp, iface, H, g, YejE, L, B)


def couple_wheels(
    vehicle: FRF,
    tires: Mapping[str, tuple[FRF, FRF]],
    coupling: str | Mapping[str, str] = "6dof",
    *,
    wheelbase: float,
    track: float,
    outputs: Sequence[str] | str | None = None,
) -> WheelTransfer:
    """Couple four tires given by FRFs to a car given by an FRF (eq. 4.1, all hubs).

    Parameters
    ----------
    vehicle : FRF
        Mobility with inputs and outputs ``spindle_<w>:<d>`` (the coupled directions
        of the four wheels) and further outputs (the responses).
    tires : mapping wheel -> (FRF, FRF)
        Per wheel its hub mobility (outputs = inputs ``hub:x`` ... ``hub:rz``) and its
        free hub velocity per metre of road (outputs ``hub:*``, one input), both in
        the vehicle axes of that wheel (mirror a left tire with
        :func:`~.tires.mirror_arrays` for a right wheel); same grid as ``vehicle``.
    coupling : {"6dof", "5dof"} or mapping wheel -> option
    wheelbase, track : float
        Keyword only, m (for :meth:`WheelTransfer.apply`).
    outputs : labels or node names, optional
        Default every output that is not a hub DOF.

    Returns
    -------
    WheelTransfer
    """
    dirs = coupled_directions(coupling)
    if set(tires) != set(WHEELS):
        raise FBSError(f"give a tire for each wheel {', '.join(WHEELS)}, got {list(tires)}")
    car = FRFVehicle(vehicle, wheelbase, track)
    f = vehicle.freq
    hub = node_labels("hub")
    YA, vA = [], []
    for w in WHEELS:
        Y, v = tires[w]
        for x, what in ((Y, "hub mobility"), (v, "free hub velocity")):
            vehicle.require_grid(x, f"the car and the {what} of tire {w}")
            if x.quantity != "mobility":
                raise QuantityError(f"the {what} of tire {w} must be a mobility")
        if v.shape[2] != 1:
            raise DOFError(f"the free hub velocity of tire {w} must have one input (the road)")
        YA.append(Y.sel(outputs=hub, inputs=hub).data)
        vA.append(v.sel(outputs=hub).data[:, :, 0])
    return _transfer(car, f, dirs, outputs, np.stack(YA), np.stack(vA))


def vehicle_transfer(
    harmonic: int | Harmonic,
    n_modes: int | None = None,
    freq: ArrayLike | None = None,
    coupling: str | Mapping[str, str] = "6dof",
    *,
    outputs: Sequence[str] | str | None = None,
    vehicle: Vehicle | None = None,
    tire: Any = None,
    residual: bool = False,
) -> WheelTransfer:
    """Response per metre of road under each wheel along a harmonic line.

    The tire's modes are synthesised once per line (the four wheels roll at the
    same speed over the same wavelength) and mirrored for the right wheels.

    Parameters
    ----------
    harmonic : int or Harmonic
        Case 1..7 (thesis table 5.1).
    n_modes : int, optional
        Retained tire modes (even; default all).
    freq : array_like, optional
        Lines in Hz inside the harmonic's band; default ``harmonic.frequencies()``.
    coupling : {"6dof", "5dof"} or mapping wheel -> option
    outputs : labels or node names, optional
        Default all response DOFs of the car.
    vehicle : VehicleModel or FRFVehicle, optional
        Default the reference car.
    tire : TireModel or mapping wheel -> TireModel, optional
        One (left-side) model on every wheel, mirrored on the right (default the
        reference tire), or one per wheel in that wheel's vehicle axes.
    residual : bool
        Compensate the tire modes left out by their quasi-static part.

    Returns
    -------
    WheelTransfer
    """
    h = _harmonic(harmonic)
    f = h.frequencies() if freq is None else check_grid(freq)
    h.speed_at(f)  # inside the band
    dirs = coupled_directions(coupling)
    car = _car(vehicle)
    models_n = None if n_modes is None else [n_modes]
    n_list = models_n or [_n_total(tire)]
    YA, vA = wheel_arrays(tire, f, h, n_list, residual)
    return _transfer(car, f, dirs, outputs, YA[:, 0], vA[:, 0])


def _n_total(tire: Any) -> int:
    from .tires import wheel_models

    return int(min(getattr(m, "n_modes", 0) for m, _ in wheel_models(tire).values()))


def vehicle_response(
    harmonic: int | Harmonic,
    n_modes: int | None = None,
    freq: ArrayLike | None = None,
    coupling: str | Mapping[str, str] = "6dof",
    *,
    tracks: str | float = "in phase",
    wheels: Sequence[str] = WHEELS,
    outputs: Sequence[str] | str | None = None,
    vehicle: Vehicle | None = None,
    tire: Any = None,
    residual: bool = False,
) -> VehicleResponse:
    """The car's response to a harmonic road case on both tracks (four wheels).

    The rear wheels see the front's road a wheelbase later (phase ``2 pi L / lambda``
    at every line); the right track is in phase, in anti-phase or partially coherent
    with the left (``tracks``, :class:`~.road.Road`).

    Parameters
    ----------
    harmonic, n_modes, freq, coupling, outputs, vehicle, tire, residual
        As :func:`vehicle_transfer`.
    tracks : {"in phase", "anti-phase", "isotropic"} or float
        Relation of the right track to the left (coherency in [-1, 1]).
    wheels : sequence of str
        Wheels whose road input is on.

    Returns
    -------
    VehicleResponse

    Examples
    --------
    >>> r = vehicle_response(4, tracks="anti-phase", outputs="seat_fl")  # doctest: +SKIP
    >>> r.by_wheel().sel(inputs="road_rl")                               # doctest: +SKIP
    """
    h = _harmonic(harmonic)
    t = vehicle_transfer(
        h,
        n_modes,
        freq,
        coupling,
        outputs=outputs,
        vehicle=vehicle,
        tire=tire,
        residual=residual,
    )
    return t.apply(Road(wavelength=h.wavelength, tracks=tracks, wheels=tuple(wheels)))


def road_transfer(
    speed_kmh: float,
    freq: ArrayLike,
    coupling: str | Mapping[str, str] = "6dof",
    *,
    outputs: Sequence[str] | str | None = None,
    vehicle: Vehicle | None = None,
    tire: Any = None,
) -> WheelTransfer:
    """Response per metre of road under each wheel at a fixed speed (every wavelength).

    Line ``f`` is excited by the road wavelength ``v / f``; the tire comes from its
    own matrices at that speed (:func:`~.tires.tire_at_speed`, needs physics).

    Parameters
    ----------
    speed_kmh : float
        Vehicle speed.
    freq : array_like, shape (n_f,)
        Positive lines in Hz.
    coupling : {"6dof", "5dof"} or mapping wheel -> option
    outputs, vehicle, tire
        As :func:`vehicle_transfer`.

    Returns
    -------
    WheelTransfer
    """
    f = check_grid(freq)
    dirs = coupled_directions(coupling)
    car = _car(vehicle)
    from .tires import mirror_arrays, wheel_models

    models = wheel_models(tire)
    done: dict[int, tuple[ComplexArray, ComplexArray]] = {}
    YA, vA = [], []
    for w in WHEELS:
        model, mirrored = models[w]
        if id(model) not in done:
            done[id(model)] = tire_at_speed(model, f, speed_kmh)
        Y, v = done[id(model)]
        if mirrored:
            Y, v = mirror_arrays(Y, v)
        YA.append(Y)
        vA.append(v)
    return _transfer(car, f, dirs, outputs, np.stack(YA), np.stack(vA))


def random_road_response(
    speed_kmh: float,
    road_class: str = "C",
    freq: ArrayLike | None = None,
    coupling: str | Mapping[str, str] = "6dof",
    *,
    tracks: str | float = "isotropic",
    wheels: Sequence[str] = WHEELS,
    outputs: Sequence[str] | str | None = None,
    vehicle: Vehicle | None = None,
    tire: Any = None,
    gd0: float | None = None,
) -> VehicleResponse:
    """Response spectra of the car on an ISO 8608 random road at a fixed speed.

    Parameters
    ----------
    speed_kmh : float
        Vehicle speed; line ``f`` is excited by the wavelength ``v / f``.
    road_class : {"A", ..., "H"}
        ISO 8608 class (:data:`~.road.ISO_8608`).
    freq : array_like, optional
        Lines in Hz (default 0.5 to 60 Hz every 0.25 Hz: ride, wheel hop, body modes).
    coupling : {"6dof", "5dof"} or mapping wheel -> option
    tracks : str or float
        Default ``"isotropic"`` (coherency of an isotropic road across the track).
    wheels : sequence of str
        Wheels whose road input is on.
    outputs, vehicle, tire
        As :func:`vehicle_transfer` (the tire needs physical parameters:
        :func:`~.tires.tire_at_speed`).
    gd0 : float, optional
        ``G_d(n_0)`` in m^3 instead of a class.

    Returns
    -------
    VehicleResponse
        ``psd`` in (m/s)^2/Hz, ``rms()`` in m/s (``response.to("accelerance")``
        for accelerations).
    """
    f = np.arange(0.5, 60.0 + 1e-9, 0.25) if freq is None else check_grid(freq)
    t = road_transfer(speed_kmh, f, coupling, outputs=outputs, vehicle=vehicle, tire=tire)
    profile = RoadProfile(road_class=None if gd0 is not None else road_class, gd0=gd0)
    return t.apply(Road(speed_kmh=speed_kmh, tracks=tracks, profile=profile, wheels=tuple(wheels)))
