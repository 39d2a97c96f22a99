"""Export of coupled and study results with metadata (CSV, UFF 58, HDF5)."""

from __future__ import annotations

import io
from pathlib import Path

import h5py
import numpy as np
import pytest

import fbs_core
from fbs_core import FRF
from fbs_core.errors import DataFormatError
from fbs_core.io import as_result_data, export_result, load_frf
from fbs_core.studies import Convergence, ScatterBand, SuggestedModes, TruncationMap

DOFS = ("bushing:x", "bushing:z")
F = np.arange(20, 41) * 1.0


def truncation_map() -> TruncationMap:
    rng = np.random.default_rng(1)
    n = np.array([10, 20, 30])
    centres = np.array([26.0, 30.0, 34.0])
    resp = rng.normal(size=(3, F.size, 2)) + 1j * rng.normal(size=(3, F.size, 2))
    return TruncationMap(
        harmonic=3,
        n_modes=n,
        n_modes_total=30,
        centres=centres,
        dofs=DOFS,
        error=rng.uniform(size=(3, 3, 2)),
        freq=F,
        response=resp,
        reference=resp[-1],
        width=12.0,
        step=4.0,
        edges="clip",
    )


def scatter() -> ScatterBand:
    rng = np.random.default_rng(2)
    ref = rng.normal(size=(F.size, 2)) + 1j * rng.normal(size=(F.size, 2))
    lo, hi = 0.8 * abs(ref), 1.2 * abs(ref)
    conv = Convergence(np.array([10, 100]), np.stack([lo, lo]), np.stack([hi, hi]))
    arg = np.zeros((F.size, 2), int)
    return ScatterBand(
        freq=F,
        dofs=DOFS,
        reference=ref,
        minimum=lo,
        maximum=hi,
        argmin_round=arg,
        argmax_round=arg,
        q=np.array([5.0, 95.0]),
        percentiles=np.stack([lo, hi]),
        convergence=conv,
        noise=0.1,
        target="both",
        rounds=100,
        frequency_dependent=True,
        seed=42,
        harmonic=1,
        _inputs=(),
    )


def test_study_result_is_flattened_with_named_axes():
    res = as_result_data(truncation_map(), {"speed_kmh": 80})
    dims, err = res.arrays["error"]
    assert dims == ("n_modes", "centres", "dofs") and err.shape == (3, 3, 2)
    assert res.arrays["response"][0] == ("n_modes", "freq", "dofs")
    np.testing.assert_array_equal(res.coords["n_modes"], [10, 20, 30])
    md = res.metadata
    assert md["harmonic"] == 3 and md["width"] == 12.0 and md["speed_kmh"] == 80
    assert md["fbs_core_version"] == fbs_core.__version__ and md["kind"] == "TruncationMap"
    band = as_result_data(scatter())
    assert band.arrays["percentiles"][0] == ("q", "freq", "dofs")
    assert band.arrays["convergence/minimum"][0] == ("convergence/rounds", "freq", "dofs")
    assert band.metadata["seed"] == 42 and band.metadata["noise"] == 0.1


def test_hdf5_export_holds_arrays_axes_and_metadata():
    tm = truncation_map()
    raw = export_result(tm, format="hdf5", metadata={"seed": 5})
    with h5py.File(io.BytesIO(raw), "r") as h:
        assert list(h["arrays/error"].attrs["dims"]) == ["n_modes", "centres", "dofs"]
        np.testing.assert_array_equal(h["arrays/error"][()], tm.error)
        np.testing.assert_array_equal(h["coords/dofs"].asstr()[()], DOFS)
        assert h.attrs["harmonic"] == 3 and h.attrs["seed"] == 5
        assert h.attrs["fbs_core_version"] == fbs_core.__version__
        assert '"width": 12.0' in h.attrs["metadata"]


def test_csv_export_tables_and_metadata_header():
    tm = truncation_map()
    text = export_result(tm, format="csv", metadata={"N": 40}).decode()
    assert "# harmonic: 3" in text and "# N: 40" in text
    assert f"# fbs_core_version: {fbs_core.__version__}" in text
    block = text.split("# table: error\n")[1].split("\n\n")[0].splitlines()
    assert block[0] == "n_modes,centres,dofs,value"
    assert len(block) == 1 + tm.error.size
    first = block[1].split(",")
    assert first[:3] == ["10", "26.0", "bushing:x"] and float(first[3]) == tm.error[0, 0, 0]
    resp = text.split("# table: response\n")[1].splitlines()
    assert resp[0] == "n_modes,freq,dofs,re,im"


def test_uff_export_of_functions_of_frequency(tmp_path):
    import pyuff

    tm = truncation_map()
    p = export_result(tm, tmp_path / "r.uff", metadata={"seed": 1})
    sets = pyuff.UFF(str(p)).read_sets()
    ids = [s["id1"] for s in sets]
    # error over centres (3 x 2), response (3 x 2), reference (2)
    assert len(sets) == 6 + 6 + 2
    k = ids.index("response [n_modes=20, dofs=bushing:z]")
    np.testing.assert_allclose(sets[k]["data"], tm.response[1, :, 1], rtol=1e-10)
    np.testing.assert_allclose(sets[k]["x"], F)
    assert sets[k]["rsp_dir"] == 3
    assert any("seed=1" in s["id3"] + s["id4"] for s in sets)  # whole pairs, lines 3-4
    assert all(s["id5"].startswith("nodes: ") and "=bushing" in s["id5"] for s in sets)


def test_coupled_frf_result_round_trips_through_every_export():
    w = 2 * np.pi * F
    Y = FRF(
        F, (1j * w / (5e4 - 2 * w**2 + 3j * w))[:, None, None], ["bushing:z"], ["patch"], "mobility"
    )
    for fmt, end in (("csv", "csv"), ("uff", "uff"), ("hdf5", "h5")):
        raw = export_result(Y, format=fmt, metadata={"harmonic": 1, "N": 40})
        if fmt == "csv":  # a result CSV holds one table per item; the FRF table loads
            raw = raw.split(b"# table: frf\n")[1]
        r = load_frf(raw, filename=f"r.{end}")
        assert r.frf.allclose(Y, rtol=1e-10)


def test_mapping_results_and_refusals(tmp_path):
    res = {
        "error": (("n_modes", "freq"), np.ones((2, 3))),
        "coords": {"n_modes": [10, 20], "freq": [1.0, 2.0, 3.0]},
        "metadata": {"noise": 0.1},
    }
    res["labels"] = (("n_modes", "k"), np.array([["a", "b"], ["c", "d"]]))
    p = export_result(res, tmp_path / "m.h5")
    with h5py.File(p, "r") as h:
        assert h.attrs["noise"] == 0.1
        assert h["arrays/labels"].asstr()[1, 0] == "c"
    with pytest.raises(DataFormatError, match="cannot export a object"):
        export_result(object(), format="csv")
    with pytest.raises(DataFormatError, match="coordinate has 4"):
        export_result({"e": (("a",), np.ones(3)), "coords": {"a": [1, 2, 3, 4]}}, format="csv")
    with pytest.raises(DataFormatError, match="no function of frequency"):
        export_result({"e": (("a",), np.ones(3))}, format="uff")
    with pytest.raises(DataFormatError, match="not 'mat'"):
        export_result(res, format="mat")
    with pytest.raises(DataFormatError, match="no arrays"):
        export_result({"metadata": {"a": 1}}, format="csv")


def test_suggested_modes_table_is_indexed_by_harmonic():
    sm = SuggestedModes(
        harmonics=(1, 2, 3),
        n_modes=np.array([40, 70, 130]),
        eigenfrequency=np.array([144.0, 236.0, 347.0]),
        freq_range=np.array([[12.9, 51.5], [16.7, 67.0], [24.6, 97.9]]),
        threshold=0.2,
        f_max=160.0,
        speed=80.0,
        dof=None,
        maps=(),
    )
    res = as_result_data(sm)
    assert res.arrays["n_modes"][0] == ("harmonics",)
    assert res.arrays["freq_range"][0] == ("harmonics", "freq_range_dim1")
    text = export_result(sm, format="csv").decode()
    assert "# table: n_modes\nharmonics,value\n1,40\n2,70\n3,130\n" in text
    assert text.count("fbs_core_version") == 1 and "# threshold: 0.2" in text


def test_hdf5_result_reads_back_with_axes_and_metadata(tmp_path):
    from fbs_core.io import load_result

    band = scatter()
    p = export_result(band, tmp_path / "band.h5", metadata={"note": "run 7"})
    res = load_result(p)
    assert res.kind == "ScatterBand" and res.metadata["seed"] == 42
    assert res.metadata["note"] == "run 7"
    dims, v = res.arrays["percentiles"]
    assert dims == ("q", "freq", "dofs")
    np.testing.assert_array_equal(v, band.percentiles)
    np.testing.assert_array_equal(res.coords["dofs"], DOFS)
    w = 2 * np.pi * F
    Y = FRF(
        F, (1j * w / (5e4 - 2 * w**2 + 3j * w))[:, None, None], ["bushing:z"], ["patch"], "mobility"
    )
    back = load_result(
        export_result({"coupled": Y, "metadata": {"N": 40}}, format="hdf5"), filename="r.h5"
    )
    assert back.frfs["coupled"].allclose(Y) and back.metadata["N"] == 40
    b = io.BytesIO()
    with h5py.File(b, "w") as h:
        h["x"] = np.ones(3)
    with pytest.raises(DataFormatError, match="not written by tire-fbs"):
        load_result(b.getvalue(), filename="foreign.h5")
    chassis = load_result(Path(__file__).parents[1] / "data" / "reference_chassis.h5")
    assert "spindle:z" in chassis.frfs["frf"].inputs


def test_csv_cells_cannot_start_a_formula():
    """A file name or setting beginning with = + - @ is text in the exported CSV."""
    import csv as _csv
    import io as _io

    Y = FRF([10.0, 20.0], np.ones((2, 1, 1)), ["a:z"], ["b:z"], "mobility")
    hostile = {
        "chassis_file": '=HYPERLINK("http://x","y")',
        "note": "ok,=1+2;@SUM(A1);\t-3+4",
        "tire_file": "+cmd|' /C calc'!A0",
    }
    for raw in (
        export_result(Y, format="csv", metadata=hostile),
        fbs_core.io.save_frf(Y, format="csv", metadata=hostile),
    ):
        text = raw.decode()
        for delim in (",", ";", "\t"):
            for row in _csv.reader(_io.StringIO(text), delimiter=delim):
                for cell in row:
                    assert not cell.lstrip(" ").startswith(("=", "+", "-", "@")), (delim, cell)
        # the content is kept, readable after the apostrophe
        assert "'=1+2" in text and "'@SUM(A1)" in text
    # numbers (also negative) are still numbers
    Z = Y.replace(data=-np.ones((2, 1, 1)))
    assert ",-1.0," in fbs_core.io.save_frf(Z, format="csv").decode()
