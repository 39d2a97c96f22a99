"""Export then import gives the same FRF, in every format (fbs_core.io).

The FRFs are closed-form: a grounded two-DOF mass-spring-damper system solved
directly, so the data are physical (mobility rising at low frequency).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fbs_core import FRF
from fbs_core.io import load_frf, save_frf

ENDING = {"uff": "uff", "mat": "mat", "csv": "csv", "hdf5": "h5"}


def two_dof(freq, quantity="mobility") -> FRF:
    """Grounded chain k1 - m1 - k2 - m2 with viscous damping, solved directly."""
    m1, m2, k1, k2, c1, c2 = 2.0, 1.0, 4e4, 2e4, 8.0, 4.0
    M = np.diag([m1, m2])
    K = np.array([[k1 + k2, -k2], [-k2, k2]])
    C = np.array([[c1 + c2, -c2], [-c2, c2]])
    w = 2 * np.pi * np.asarray(freq)
    H = np.linalg.inv(-(w**2)[:, None, None] * M + 1j * w[:, None, None] * C + K)
    frf = FRF(freq, H, ["spindle:z", "bushing:z"], ["spindle:z", "bushing:z"], "receptance")
    return frf.to(quantity)


FREQ = np.arange(1, 161) * 0.5


@pytest.mark.parametrize("fmt", ["uff", "mat", "csv", "hdf5"])
@pytest.mark.parametrize("quantity", ["receptance", "mobility", "accelerance"])
def test_round_trip_bytes(fmt, quantity):
    Y = two_dof(FREQ, quantity)
    raw = save_frf(Y, format=fmt, metadata={"harmonic": 1, "seed": 7})
    assert isinstance(raw, bytes)
    r = load_frf(raw, filename=f"upload.{ENDING[fmt]}")
    assert r.frf.allclose(Y, rtol=1e-10)
    assert r.frf.quantity == quantity
    assert "spindle:z" in r.summary and "0.5 to 80 Hz" in r.summary


@pytest.mark.parametrize(
    "fmt, mat_version, label",
    [
        ("uff", "5", "UFF 58"),
        ("csv", "5", "CSV"),
        ("hdf5", "5", "HDF5"),
        ("mat", "5", "MATLAB v5"),
        ("mat", "7.3", "MATLAB v7.3"),
    ],
)
def test_the_import_names_the_format_it_read(fmt, mat_version, label):
    raw = save_frf(two_dof(FREQ[:8]), format=fmt, mat_version=mat_version)
    r = load_frf(raw, filename=f"up.{ENDING[fmt]}")
    assert r.format == label and r.summary.startswith(f"up.{ENDING[fmt]} ({label}): ")


def test_round_trip_mat73_and_binary_uff(tmp_path):
    Y = two_dof(FREQ)
    p = save_frf(Y, tmp_path / "y73.mat", mat_version="7.3", metadata={"N": 40})
    r = load_frf(p)
    assert r.format == "MATLAB v7.3"
    assert r.frf.allclose(Y, rtol=1e-15)
    assert r.metadata["N"] == 40
    p = save_frf(Y, tmp_path / "y.uff", binary=True)
    assert load_frf(p).frf.allclose(Y, rtol=1e-14)


def test_round_trip_metadata_hdf5_and_mat5(tmp_path):
    Y = two_dof(FREQ)
    for name in ("a.h5", "a.mat"):
        p = save_frf(Y, tmp_path / name, metadata={"noise": 0.1, "seed": 3})
        md = load_frf(p).metadata
        assert md["noise"] == 0.1 and md["seed"] == 3


def test_uneven_grid_round_trip_uff():
    f = np.array([1.0, 2.0, 4.0, 8.0, 16.0, 32.5])
    Y = two_dof(f)
    r = load_frf(save_frf(Y, format="uff"), filename="x.uff")
    assert r.frf.allclose(Y, rtol=1e-10)


def test_uff_grid_not_representable_is_refused_unless_asked():
    from fbs_core.errors import DataFormatError

    Y = two_dof(np.linspace(10.0, 20.0, 7) + 1e-4 / 3)
    with pytest.raises(DataFormatError, match="6 significant digits"):
        save_frf(Y, format="uff")
    r = load_frf(save_frf(Y, format="uff", round_abscissa=True), filename="x.uff")
    assert np.allclose(r.frf.freq, Y.freq, rtol=1e-5)


def test_node_mapping_uff_numbers_to_names():
    Y = two_dof(FREQ).replace(outputs=["1:z", "2:z"], inputs=["1:z", "2:z"])
    raw = save_frf(Y, format="uff")
    r = load_frf(raw, filename="x.uff", nodes={1: "spindle", 2: "bushing"})
    assert r.frf.outputs == ("spindle:z", "bushing:z")
    r = load_frf(raw, filename="x.uff")
    assert r.frf.outputs == ("1:z", "2:z")


def test_uff_names_survive_as_entity_names_and_numbers_are_chosen():
    Y = two_dof(FREQ)
    raw = save_frf(Y, format="uff", nodes={101: "spindle", 202: "bushing"})
    text = raw.decode()
    assert "spindle" in text and "       101" in text
    assert load_frf(raw, filename="x.uff").frf.outputs == ("spindle:z", "bushing:z")
    assert load_frf(raw, filename="x.uff", nodes={101: "hub"}).frf.outputs == ("hub:z", "202:z")


def test_path_or_bytes_give_the_same(tmp_path):
    Y = two_dof(FREQ)
    p = save_frf(Y, tmp_path / "y.csv")
    assert isinstance(p, Path)
    a = load_frf(p).frf
    b = load_frf(p.read_bytes(), filename="y.csv").frf
    assert a.allclose(b, rtol=0)


def test_frf_unpacks_as_frf_and_summary():
    Y = two_dof(FREQ)
    frf, summary = load_frf(save_frf(Y, format="hdf5"), filename="y.h5")
    assert frf.allclose(Y) and summary.startswith("y.h5 (HDF5)")


def test_reads_the_shipped_reference_chassis_file_without_changing_it():
    p = Path(__file__).parents[1] / "data" / "reference_chassis.h5"
    before = p.read_bytes()
    r = load_frf(p)
    assert r.frf.quantity == "mobility"
    assert "spindle:z" in r.frf.inputs and any(o.startswith("bushing:") for o in r.frf.outputs)
    assert p.read_bytes() == before


def test_mat73_cell_array_labels_as_matlab_writes_them():
    """MATLAB v7.3 stores a cell array as object references into '#refs#', each a
    uint16 char dataset; arrays are column-major (h5py sees the axes reversed)."""
    import io

    import h5py

    Y = two_dof(FREQ)
    raw = bytearray(save_frf(Y, format="mat", mat_version="7.3"))
    b = io.BytesIO(bytes(raw))
    with h5py.File(b, "r+") as h:
        for var in ("outputs", "inputs"):
            del h[var]
            refs = []
            for k, lab in enumerate(getattr(Y, var)):
                d = h.create_dataset(
                    f"#refs#/{var}{k}", data=np.array([[ord(c)] for c in lab], np.uint16)
                )
                d.attrs["MATLAB_class"] = np.bytes_("char")
                d.attrs["MATLAB_int_decode"] = np.int32(2)
                refs.append(d.ref)
            c = h.create_dataset(var, data=np.array([refs]).T, dtype=h5py.ref_dtype)
            c.attrs["MATLAB_class"] = np.bytes_("cell")
    r = load_frf(b.getvalue(), filename="cells.mat")
    assert r.frf.allclose(Y, rtol=1e-15)
