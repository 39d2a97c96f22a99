"""The shipped reference car: ``data/reference_vehicle.h5`` (HDF5, no pickle).

Written by ``scripts/build_reference_vehicle.py`` in the project's HDF5 FRF layout
(``fbs_core.io.hdf5``, so :func:`fbs_core.load_frf` reads its ``/frf`` group like any
user's vehicle FRF), plus the model itself::

    /                     attrs: format = "tire-fbs", model = "reference vehicle", ...
    /frf/freq             (200,) float64, Hz: 1, 2, ..., 200
    /frf/data             (200, 84, 24) complex128, mobility
    /frf                  attrs: quantity, units, outputs (spindle_<w>:*, responses),
                                 inputs (spindle_<w>:*)
    /parameters           attr json: every field of VehicleParameters (nested)
    /system/dofs          attr: the DOF labels
    /system/M, /K, /C     CSR arrays data, indices, indptr; attr shape (K complex)
    /dampers              attr json: the four dampers (nodes, offsets, axis, c)
    /modes/eigenvalues    complex128, lam_r = omega_r^2 (1 + j eta_r) (no dampers)
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import numpy as np

from ..frf import FRF
from ..frf_model import read_model_frf
from .model import VehicleModel

__all__ = ["DATA_FILE", "write_vehicle_h5", "read_vehicle_frf", "FILE_GRID"]

#: The shipped file.
DATA_FILE = Path(__file__).resolve().parents[2] / "data" / "reference_vehicle.h5"
#: Lines of its FRF, Hz (harmonic cases 1-5 lie inside).
FILE_GRID = np.arange(1.0, 200.0 + 1e-9, 1.0)

COORDINATES = (
    "ISO 8855 vehicle axes: x forward, y left, z up; origin on the ground below the "
    "centre of the front axle"
)


def write_vehicle_h5(
    car: VehicleModel, path: str | os.PathLike[str], freq: np.ndarray = FILE_GRID
) -> None:
    """Write the car's FRF and model (layout in the module doc)."""
    import h5py

    from ..io.hdf5 import write_model_hdf5

    meta = {
        "model": "reference vehicle (body, strut fronts, the thesis' rear axle; no tires)",
        "coordinates": COORDINATES,
        "script": "scripts/build_reference_vehicle.py",
        "wheelbase_m": car.wheelbase,
        "track_m": list(car.track),
    }
    Y = car.mobility(freq)
    write_model_hdf5(path, Y, meta, "reference vehicle", car.system(), ("M", "K", "C"))
    with h5py.File(path, "a") as h:
        h.create_group("parameters").attrs["json"] = json.dumps(
            dataclasses.asdict(car.params), sort_keys=True
        )
        h.create_group("dampers").attrs["json"] = json.dumps(
            [dataclasses.asdict(d) for d in car.dampers]
        )
        h.create_group("modes")["eigenvalues"] = car.eigenvalues()


def read_vehicle_frf(path: str | os.PathLike[str] = DATA_FILE) -> FRF:
    """The FRF of a file written by :func:`write_vehicle_h5`.

    Raises
    ------
    DataFormatError
        If the file is not a reference vehicle file.
    """
    return read_model_frf(path, "reference vehicle")
