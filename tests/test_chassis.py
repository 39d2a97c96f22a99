"""Reference rear-corner chassis: targets of thesis fig. 4.2 and truth from physics."""

from pathlib import Path

import numpy as np
import pytest
from scipy.signal import find_peaks

from fbs_core import reference_chassis
from fbs_core.chassis import (
    BUSHING,
    SPINDLE,
    STEEL_RHO,
    ChassisModel,
    ChassisParameters,
    carrier_mode_table,
    modal_energy,
    read_chassis_frf,
)
from fbs_core.errors import DataFormatError, DOFError, FrequencyGridError, QuantityError
from fbs_core.fe import Section

TARGETS = (14.0, 37.0, 47.0)  # thesis fig. 4.2
DATA = Path(__file__).resolve().parents[1] / "data" / "reference_chassis.h5"


@pytest.fixture(scope="module")
def chassis():
    return reference_chassis()


def test_eigenfrequencies_hit_thesis_targets_and_flexible_modes_exist(chassis):
    f = chassis.eigenfrequencies()
    for target in TARGETS:
        assert np.min(np.abs(f - target)) < 1.0, (target, f[:8])
    # no other mode crowds the thesis' 12-52 Hz band
    band = f[(f > 12) & (f < 52)]
    assert band.size == 3
    # flexible arm / subframe modes fill the band of harmonic cases 5-7 and beyond
    assert np.sum((f > 100) & (f < 450)) >= 5
    assert f.max() > 450
    eta = chassis.loss_factors()
    assert np.all(eta[:4] > 0.05) and np.all(eta < 0.2)


def test_uncoupled_spindle_to_bushing_mobility_peaks_at_the_targets(chassis):
    """Fig. 4.2: the eigenfrequencies appear as peaks of Y_ej^E, also for a z input."""
    f = np.arange(8.0, 60.0, 0.05)
    Yej = chassis.mobility(f).sel(outputs=BUSHING).data
    for amp in (np.linalg.norm(Yej, axis=(1, 2)), np.linalg.norm(Yej[:, :, 2], axis=1)):
        peaks = f[find_peaks(amp)[0]]
        for target in TARGETS:
            assert np.min(np.abs(peaks - target)) < 1.0, (target, peaks)


def test_modal_synthesis_equals_direct_solution(chassis):
    f = np.array([3.0, 14.0, 37.3, 47.0, 120.0, 286.0, 450.0, 600.0])
    Y = chassis.mobility(f)
    D = chassis.system().frf(f, Y.outputs, Y.inputs, quantity="mobility")
    err = np.abs(Y.data - D.data).max(axis=(1, 2)) / np.abs(D.data).max(axis=(1, 2))
    assert err.max() < 1e-8


def test_reciprocal_and_labelled(chassis):
    f = np.array([20.0, 200.0])
    Y = chassis.mobility(f, outputs=SPINDLE + BUSHING, inputs=SPINDLE + BUSHING)
    np.testing.assert_allclose(
        Y.data, np.swapaxes(Y.data, 1, 2), rtol=1e-8, atol=1e-10 * np.abs(Y.data).max()
    )
    Y = chassis.mobility(f)
    assert Y.outputs == SPINDLE + BUSHING and Y.inputs == SPINDLE
    assert Y.quantity == "mobility"
    np.testing.assert_array_equal(chassis.driving_point(f).data, Y.sel(outputs=SPINDLE).data)
    np.testing.assert_array_equal(chassis.transfer(f).data, Y.sel(outputs=BUSHING).data)
    assert chassis.transfer(f).outputs == BUSHING
    R = chassis.mobility(f, quantity="receptance")
    np.testing.assert_allclose(R.to("mobility").data, Y.data, rtol=1e-12)


def test_mass_equals_sum_of_parts(chassis):
    p = chassis.params
    L, W = p.subframe_half
    frame = 2 * (2 * L) * Section.box(*p.side_box).A + 2 * (2 * W) * Section.box(*p.cross_box).A
    arm = (
        2
        * np.hypot(
            np.hypot(*np.subtract(p.arm_apex_xyz[:2], (p.arm_roots_x, W))), p.arm_apex_xyz[2]
        )
        * Section.tube(*p.arm_tube).A
    )
    expected = p.carrier_mass + 2 * p.bracket_mass + STEEL_RHO * (frame + arm)
    s = chassis.system()
    u = np.zeros(s.n)
    u[[i for i, d in enumerate(s.dofs) if d.endswith(":z")]] = 1.0
    assert u @ (s.M @ u) == pytest.approx(expected, rel=1e-12)


def test_static_loads_at_the_bushings_go_straight_to_ground(chassis):
    """Equal vertical forces at the four subframe corners: a rigid translation of
    subframe, arm and carrier (the link carries no force) is in equilibrium, so
    every corner moves F / k_z and the frame is not bent."""
    s = chassis.system()
    K = s.K.toarray()
    corners = ["bushing", "bush_rl", "bush_rr", "bush_fr"]
    f = np.zeros(s.n)
    for c in corners:
        f[s.dofs.index(f"{c}:z")] = 1.0
    x = np.linalg.solve(K, f)
    kz = chassis.params.bushing_stiffness[2] * (1 + 1j * chassis.params.bushing_loss)
    got = [x[s.dofs.index(f"{c}:z")] for c in corners]
    np.testing.assert_allclose(got, np.full(4, 1.0 / kz), rtol=1e-9)
    np.testing.assert_allclose(x[s.dofs.index("spindle:z")], 1.0 / kz, rtol=1e-9)


def test_stored_file_matches_the_model(chassis):
    Y = read_chassis_frf(DATA)
    # a regression check of the file (LAPACK results vary at ~1e-9 with the thread count)
    np.testing.assert_allclose(
        Y.data, chassis.mobility(Y.freq).data, rtol=1e-6, atol=1e-9 * np.abs(Y.data).max()
    )
    assert Y.outputs == SPINDLE + BUSHING
    # the project's generic reader (sandboxed HDF5 import) sees the same FRF
    from fbs_core.io import load_frf

    np.testing.assert_array_equal(load_frf(DATA).frf.data, Y.data)


def test_bad_input(chassis, tmp_path):
    with pytest.raises(DOFError, match="spindle:q|unknown"):
        chassis.mobility([10.0], outputs=["spindle:q"])
    with pytest.raises(DOFError, match="chassis output DOF 'hub:z'"):
        chassis.mobility([10.0], outputs=["hub:z"])
    with pytest.raises(FrequencyGridError):
        chassis.mobility([20.0, 10.0])
    with pytest.raises(QuantityError, match="allowed"):
        chassis.mobility([10.0], quantity="velocity")
    bad = tmp_path / "x.h5"
    import h5py

    with h5py.File(bad, "w") as h:
        h.attrs["format"] = "something else"
    with pytest.raises(DataFormatError, match="not a 'tire-fbs' reference chassis"):
        read_chassis_frf(bad)


def test_parameters_make_a_different_model():
    soft = ChassisModel(ChassisParameters(bushing_stiffness=(3e5, 3e5, 4e5, 300.0, 300.0, 300.0)))
    assert soft.eigenfrequencies()[4] < reference_chassis().eigenfrequencies()[4]


def test_target_modes_are_carrier_fore_aft_lateral_and_pitch(chassis):
    table = carrier_mode_table(chassis)
    assert table["x"] == pytest.approx(14.0, abs=1.0)
    assert table["y"] == pytest.approx(37.0, abs=1.0)
    assert table["ry"] == pytest.approx(47.0, abs=1.0)
    e = modal_energy(chassis)  # carrier kinetic energy share per direction
    assert e[:4].sum(axis=1).min() > 0.8  # the four lowest modes are carrier modes
    assert e[15:].sum(axis=1).max() < 0.2  # modes from ~230 Hz up are arm / subframe modes
