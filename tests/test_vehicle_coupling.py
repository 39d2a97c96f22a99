"""Four tires on one car: the coupled response equals the directly assembled five subsystems.

Truth: the car's matrices (mass, the dampers' viscous C, hysteretic K) and the four
tires' own matrices at the speed of every line (the right ones built with flipped
camber, toe and conicity: the physical mirror image) joined at the hubs by primal
assembly and solved directly (``assembly.direct_transfer``); and a second coupling,
the five FRFs coupled whole by LM-FBS and by generalized receptance coupling (thesis
eq. 2.46) with the tires' blocked forces at their hubs.
"""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.errors import DOFError, FBSError
from fbs_core.vehicle import (
    SPINDLES,
    WHEELS,
    couple_wheels,
    mirror_arrays,
    reference_vehicle,
    road_transfer,
    vehicle_response,
    vehicle_transfer,
)
from fbs_core.vehicle.assembly import blocked_force_response, couple_vehicle, direct_transfer
from fbs_core.vehicle.tires import tire_at_speed

OUTS = ["seat_fl:z", "bushing_rl:x", "bushing_fr:y", "strut_fr:rz", "bushing_rr:z"]
F = np.array([2.5, 14.0, 37.0, 120.0])
SPEED = 60.0


@pytest.fixture(scope="module")
def direct():
    return {c: direct_transfer(F, SPEED, None, c, outputs=OUTS) for c in ("6dof", "5dof")}


def _rel(a, b):
    """Largest error of every output/wheel column relative to that column's largest value."""
    return float((np.abs(a - b).max(axis=0) / np.abs(b).max(axis=0)).max())


@pytest.mark.parametrize("coupling", ["6dof", "5dof"])
def test_four_tire_response_equals_the_direct_assembly(direct, coupling):
    T = road_transfer(SPEED, F, coupling, outputs=OUTS)
    assert T.data.shape == (F.size, len(OUTS), 4)
    assert len(T.interface) == (24 if coupling == "6dof" else 20)
    assert _rel(T.data, direct[coupling]) < 1e-8
    # the four wheels are not interchangeable: the car is not the same seen from each
    assert np.abs(T.data[:, :, 0] - T.data[:, :, 2]).max() > 0.1 * np.abs(T.data).max()


def test_lm_fbs_and_generalized_receptance_of_the_five_subsystems(direct):
    car, tire = reference_vehicle(), fc.reference_tire()
    dofs = SPINDLES + tuple(OUTS)
    Yv = car.mobility(F, outputs=dofs, inputs=dofs)  # square, as LM-FBS needs
    Y, v = tire_at_speed(tire, F, SPEED)
    hub = fc.node_labels("hub")
    tires = {}
    for w in WHEELS:
        Yw, vw = mirror_arrays(Y, v) if w in ("fr", "rr") else (Y, v)
        tires[w] = (fc.FRF(F, Yw, hub, hub), fc.FRF(F, vw[:, :, None], hub, ["patch"]))
    lm = couple_vehicle(Yv, {w: t[0] for w, t in tires.items()}, "6dof", "lm")
    gr = couple_vehicle(Yv, {w: t[0] for w, t in tires.items()}, "6dof", "generalized")
    assert lm.outputs == gr.outputs and len(lm.outputs) == len(dofs) + 24
    assert np.abs(lm.data - gr.data).max() < 1e-10 * np.abs(lm.data).max()
    # connected DOFs move together
    np.testing.assert_allclose(
        lm.sel(outputs="tire_rl/hub:z").data, lm.sel(outputs="vehicle/spindle_rl:z").data,
        rtol=1e-9, atol=1e-12 * np.abs(lm.data).max(),
    )  # fmt: skip
    for coupled in (lm, gr):
        assert _rel(blocked_force_response(coupled, tires, OUTS), direct["6dof"]) < 1e-8
    # the labelled fast path with the same tire FRFs
    W = couple_wheels(
        car.mobility(F, outputs=dofs), tires, wheelbase=2.7, track=1.525, outputs=OUTS
    )
    assert _rel(W.data, direct["6dof"]) < 1e-8
    with pytest.raises(FBSError, match="allowed: lm, generalized"):
        couple_vehicle(Yv, {w: t[0] for w, t in tires.items()}, method="jetmundsen")


def test_modal_tire_along_a_harmonic_line():
    """Along case 1 the modal tire (interpolated between operating points) on all four
    wheels, at lines whose speed is an operating point, equals the direct solution."""
    h = fc.harmonic(1)
    speeds = np.array([40.0, 80.0])
    f = speeds / 3.6 / h.wavelength
    T = vehicle_transfer(1, freq=f, outputs=OUTS[:3])
    D = direct_transfer(f, speeds, h.wavelength, outputs=OUTS[:3])
    assert _rel(T.data, D) < 1e-6


def test_contributions_by_wheel_and_by_path_sum_to_the_response():
    r = vehicle_response(3, freq=np.arange(30.0, 60.0, 2.0), tracks="anti-phase", outputs="seat_fl")
    total = r.response.data[:, :, 0]
    assert r.components == ("road_anti_phase",)
    np.testing.assert_allclose(r.by_wheel().data.sum(-1), total, rtol=1e-12, atol=1e-16)
    p = r.by_path()
    assert len(p.interface) == 24 and p.load == "road_anti_phase"
    np.testing.assert_allclose(p.total.data[:, :, 0], total, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(r.by_hub().data.sum(-1), total, rtol=1e-10, atol=1e-14)
    # one hub DOF's term is the car's transfer times the interface force there
    k = p.interface.index("hub_rl:z")
    np.testing.assert_allclose(p.term("hub_rl:z").data[:, :, 0], p.terms[:, :, k])
    # wheels off: their road contributes nothing, their tire still carries the car
    rl = vehicle_response(3, freq=np.arange(30.0, 60.0, 2.0), wheels=("rl",), outputs="seat_fl")
    bw = rl.by_wheel().data
    assert np.all(bw[:, :, [0, 1, 3]] == 0)
    np.testing.assert_allclose(rl.response.data[:, :, 0], bw[:, :, 2])
    # partial coherence: two uncorrelated components, their powers add up
    half = vehicle_response(3, freq=np.arange(30.0, 40.0, 2.0), tracks=0.5, outputs="seat_fl")
    ip = vehicle_response(3, freq=np.arange(30.0, 40.0, 2.0), tracks="in phase", outputs="seat_fl")
    ap = vehicle_response(
        3, freq=np.arange(30.0, 40.0, 2.0), tracks="anti-phase", outputs="seat_fl"
    )
    np.testing.assert_allclose(half.level**2, 0.75 * ip.level**2 + 0.25 * ap.level**2, rtol=1e-10)
    with pytest.raises(FBSError, match="name one"):
        half.by_wheel()
    with pytest.raises(DOFError, match="available: road_in_phase"):
        half.by_path("road_x")
    with pytest.raises(FBSError, match="random road"):
        half.rms()


def test_single_corner_results_unchanged_by_the_car():
    """The car shares the tire's syntheses and caches with the corner: the thesis'
    results stay bit for bit what they were before a vehicle computation."""
    before = {k: fc.bushing_response(k, n_modes=60).data.copy() for k in (1, 4)}
    vehicle_response(4, n_modes=60)
    vehicle_response(1)
    for k, b in before.items():
        np.testing.assert_array_equal(fc.bushing_response(k, n_modes=60).data, b)


def test_bad_input():
    with pytest.raises(fc.CouplingOptionError, match="allowed"):
        vehicle_transfer(1, freq=[20.0], coupling="4dof")
    with pytest.raises(FBSError, match="exactly fl, fr, rl, rr"):
        vehicle_transfer(1, freq=[20.0], coupling={"fl": "6dof"})
    with pytest.raises(fc.FrequencyGridError, match="outside the 1st harmonic band"):
        vehicle_transfer(1, freq=[5.0])
    with pytest.raises(DOFError, match="unknown response 'seat'"):
        vehicle_transfer(1, freq=[20.0], outputs="seat")
    with pytest.raises(FBSError, match="VehicleModel or an FRFVehicle"):
        vehicle_transfer(1, freq=[20.0], vehicle=fc.reference_chassis())
    with pytest.raises(FBSError, match="exactly the wheels"):
        vehicle_transfer(1, freq=[20.0], tire={"fl": fc.reference_tire()})


def test_ill_conditioned_interface_is_refused_like_the_corners():
    """The car's solve certifies the 2-norm condition number with the Frobenius bound and
    refuses what fbs_core.kernels.solve_interface(max_cond=1e13) refuses."""
    from fbs_core.kernels import solve_interface
    from fbs_core.vehicle.response import solve_checked

    rng = np.random.default_rng(1)
    A = rng.standard_normal((3, 24, 24)) + 1j * rng.standard_normal((3, 24, 24))
    B = rng.standard_normal((3, 24, 4)) + 0j
    f = np.array([10.0, 20.0, 30.0])
    np.testing.assert_allclose(solve_checked(A, B, f), np.linalg.solve(A, B), rtol=1e-9)
    U, s, Vh = np.linalg.svd(A[1])
    s[-1] = s[0] * 1e-14  # cond 1e14: solvable, but refused
    A[1] = (U * s) @ Vh
    with pytest.raises(fc.SingularInterfaceError, match="20 Hz"):
        solve_checked(A, B, f)
    with pytest.raises(fc.SingularInterfaceError, match="20 Hz"):
        solve_interface(A, B, max_cond=1e13, freq=f)
    A[1] = 0.0
    with pytest.raises(fc.SingularInterfaceError, match="20 Hz"):
        solve_checked(A, B, f)
    s[-1] = s[0] * 1e-11  # cond 1e11: accepted by both (the Frobenius bound may exceed 1e13)
    A[1] = (U * s) @ Vh
    np.testing.assert_allclose(solve_checked(A, B, f)[0], np.linalg.solve(A[0], B[0]), rtol=1e-9)
