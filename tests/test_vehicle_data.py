"""A car of your own: a vehicle FRF file with four hubs and response points replaces the
reference car. Truth: the reference car's own response, computed from its model."""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.errors import DOFError, FrequencyGridError
from fbs_core.vehicle import WHEELS, FRFVehicle, reference_vehicle, vehicle_response
from fbs_core.vehicle.model import SPINDLES
from fbs_core.vehicle.storage import DATA_FILE

F = np.arange(14.0, 51.0, 3.0)  # whole-Hz lines inside case 1 (the shipped file's grid)


@pytest.fixture(scope="module")
def reference():
    return vehicle_response(1, freq=F, outputs=["seat_fl", "bushing_rr:z"], tracks="anti-phase")


@pytest.mark.parametrize("fmt", ["uff", "hdf5"])
def test_vehicle_frf_file_with_node_numbers(tmp_path, reference, fmt):
    car = reference_vehicle()
    outs = SPINDLES + tuple(reference.outputs)
    Y = car.mobility(F, outputs=outs)
    # a test lab numbers its nodes: hubs 1-4, seat rail 11, rear bushing 21
    names = {
        **{k + 1: f"spindle_{w}" for k, w in enumerate(WHEELS)},
        11: "seat_fl",
        21: "bushing_rr",
    }
    path = tmp_path / f"car.{'unv' if fmt == 'uff' else 'h5'}"
    if fmt == "uff":
        fc.save_frf(Y, path, nodes=names)
        loaded = fc.load_frf(path, nodes=names).frf
    else:
        number = {v: str(k) for k, v in names.items()}
        rename = [f"{number[o.split(':')[0]]}:{o.split(':')[1]}" for o in Y.outputs]
        fc.save_frf(Y.replace(outputs=rename, inputs=rename[:24]), path)
        loaded = fc.load_frf(path, nodes={str(k): v for k, v in names.items()}).frf
    assert set(SPINDLES) <= set(loaded.inputs)
    mine = vehicle_response(
        1,
        freq=F,
        outputs=list(reference.outputs),
        tracks="anti-phase",
        vehicle=FRFVehicle(loaded, wheelbase=car.wheelbase, track=car.track),
    )
    tol = 1e-5 if fmt == "uff" else 1e-12  # UFF stores 13 significant digits in text
    got, want = mine.response.data, reference.response.data
    assert np.abs(got - want).max() < tol * np.abs(want).max()


def test_shipped_reference_file_as_user_data():
    frf = fc.load_frf(DATA_FILE).frf
    car = reference_vehicle()
    r = vehicle_response(1, freq=F, outputs="strut_fl:z", vehicle=FRFVehicle(frf, 2.7, (1.55, 1.5)))
    want = vehicle_response(1, freq=F, outputs="strut_fl:z", vehicle=car)
    np.testing.assert_allclose(r.response.data, want.response.data, rtol=1e-6)
    with pytest.raises(FrequencyGridError, match="interpolate=True"):
        vehicle_response(1, freq=[14.5], vehicle=FRFVehicle(frf, 2.7, 1.5))
    with pytest.raises(DOFError, match="lacks the hub DOF"):
        no_rz = frf.sel(outputs=[o for o in frf.outputs if o != "spindle_rl:rz"])
        vehicle_response(1, freq=F, vehicle=FRFVehicle(no_rz, 2.7, 1.5))
    # 5-DOF coupling needs no ry at the hubs
    no_ry = [i for i in frf.inputs if not i.endswith(":ry")]
    five = FRFVehicle(
        frf.sel(inputs=no_ry, outputs=[o for o in frf.outputs if o not in ("spindle_fl:ry",)]),
        2.7,
        1.5,
    )
    r5 = vehicle_response(1, freq=F, coupling="5dof", outputs="strut_fl:z", vehicle=five)
    w5 = vehicle_response(1, freq=F, coupling="5dof", outputs="strut_fl:z", vehicle=car)
    np.testing.assert_allclose(r5.response.data, w5.response.data, rtol=1e-6)
