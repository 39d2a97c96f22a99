"""Every check on the way in ends in the project's error type with a clear message."""

from __future__ import annotations

import io

import h5py
import numpy as np
import pytest
import scipy.io
import scipy.sparse
from scipy.io.matlab import MatlabObject

from fbs_core import FRF
from fbs_core.errors import (
    DataFormatError,
    DOFError,
    FBSError,
    FrequencyGridError,
    QuantityError,
    SingularInterfaceError,
)
from fbs_core.io import common_grid, interface_check, load_frf, require_dofs, save_frf
from fbs_core.io.checks import normalize_label, parse_units, si_factors, sniff

F = np.arange(1, 41) * 0.5


def sdof(f=F, quantity="mobility", labels=("hub:z",)):
    """Grounded mass-spring-damper, closed form, every entry the same."""
    w = 2 * np.pi * np.asarray(f)
    H = 1.0 / (3e4 - 1.2 * w**2 + 1j * w * 6.0)
    n = len(labels)
    frf = FRF(f, H[:, None, None] * np.ones((1, n, n)), labels, labels, "receptance")
    return frf.to(quantity)


def mat5(**variables) -> bytes:
    b = io.BytesIO()
    scipy.io.savemat(b, variables)
    return b.getvalue()


GOOD = dict(freq=F, H=sdof().data, outputs="hub:z", inputs="hub:z", quantity="mobility")


# -- files: size, emptiness, type ----------------------------------------------------
def test_size_limit_and_empty(tmp_path):
    raw = save_frf(sdof(), format="csv")
    with pytest.raises(DataFormatError, match="larger than the limit"):
        load_frf(raw, filename="a.csv", max_bytes=100)
    p = tmp_path / "big.csv"
    p.write_bytes(raw)
    with pytest.raises(DataFormatError, match="larger than the limit"):
        load_frf(p, max_bytes=100)
    with pytest.raises(DataFormatError, match="empty"):
        load_frf(b"", filename="a.csv")
    with pytest.raises(DataFormatError, match="cannot read"):
        load_frf(tmp_path / "missing.csv")
    with pytest.raises(DataFormatError, match="path or the file's bytes"):
        load_frf(12345)


@pytest.mark.parametrize(
    "raw,name,found",
    [
        (b"PK\x03\x04" + b"\x00" * 100, "a.uff", "ZIP"),
        (b"\x80\x04\x95" + b"\x00" * 50, "a.mat", "pickle"),
        (b"\x89HDF\r\n\x1a\n" + b"\x00" * 100, "a.csv", "HDF5"),
        (b"freq,Re(a:x / a:x)\n1,2\n", "a.mat", "text"),
        (b"%PDF-1.4 ...", "a.h5", "PDF"),
        (bytes(range(256)) * 4, "a.csv", "binary"),
    ],
)
def test_content_must_match_the_ending(raw, name, found):
    with pytest.raises(DataFormatError, match=found):
        load_frf(raw, filename=name)


def test_unknown_ending_and_format():
    with pytest.raises(DataFormatError, match="known endings"):
        load_frf(b"abc", filename="a.xlsx")
    with pytest.raises(DataFormatError, match="unknown format"):
        load_frf(b"abc", filename="a.csv", format="xls")
    with pytest.raises(DataFormatError, match="pass format"):
        save_frf(sdof())


def test_sniff_kinds():
    assert sniff(save_frf(sdof(), format="mat")) == "mat5"
    assert sniff(save_frf(sdof(), format="mat", mat_version="7.3")) == "mat73"
    assert sniff(save_frf(sdof(), format="hdf5")) == "hdf5"
    assert sniff(save_frf(sdof(), format="uff", binary=True)) == "uff"


# -- labels and directions -----------------------------------------------------------
def test_labels_are_normalised_with_sign():
    assert normalize_label(" Spindle:RZ ") == ("Spindle:rz", 1)
    assert normalize_label("hub:-tz") == ("hub:z", -1)
    with pytest.raises(DOFError, match="unknown direction 'w'.*allowed: x, y, z"):
        normalize_label("hub:w")
    with pytest.raises(DOFError, match="malformed"):
        normalize_label("hub wheel:x")


def test_unknown_direction_in_mat_and_csv():
    with pytest.raises(DOFError, match="unknown direction 'q'"):
        load_frf(mat5(**dict(GOOD, outputs="hub:q")), filename="a.mat")
    text = save_frf(sdof(), format="csv").decode().replace("hub:z / hub:z", "hub:zz / hub:z")
    with pytest.raises(DOFError, match="unknown direction 'zz'"):
        load_frf(text.encode(), filename="a.csv")


def test_required_dofs_are_listed():
    with pytest.raises(DOFError, match="lacks outputs bushing:z"):
        load_frf(save_frf(sdof(), format="csv"), filename="a.csv", require_outputs=["bushing:z"])
    with pytest.raises(DOFError, match="inputs spindle:x"):
        require_dofs(sdof(), inputs=["spindle:x"])


def test_negative_direction_flips_sign_in_csv():
    Y = sdof()
    text = save_frf(Y, format="csv").decode().replace("(hub:z / hub:z)", "(hub:-z / hub:z)")
    r = load_frf(text.encode(), filename="a.csv")
    np.testing.assert_allclose(r.frf.data, -Y.data, rtol=1e-15)


# -- shapes and values ---------------------------------------------------------------
def test_wrong_shapes():
    with pytest.raises(DataFormatError, match="expected n_freq x n_out x n_in = 40x2x1"):
        load_frf(mat5(**dict(GOOD, outputs=np.array(["a:x", "b:y"]))), filename="a.mat")
    with pytest.raises(DataFormatError, match="'freq' must be a vector"):
        load_frf(mat5(**dict(GOOD, freq=np.ones((2, 20)))), filename="a.mat")
    with pytest.raises(DataFormatError, match="exactly one FRF variable"):
        load_frf(mat5(**dict(GOOD, Y=GOOD["H"])), filename="a.mat")
    with pytest.raises(DataFormatError, match="lacks the variable 'freq'"):
        load_frf(mat5(H=GOOD["H"]), filename="a.mat")


def test_non_finite_values():
    H = GOOD["H"].copy()
    H[3, 0, 0] = np.nan
    with pytest.raises(DataFormatError, match="non-finite"):
        load_frf(mat5(**dict(GOOD, H=H)), filename="a.mat")
    text = save_frf(sdof(), format="csv").decode().splitlines()
    text[-1] = text[-1].rsplit(",", 1)[0] + ",inf"
    with pytest.raises(DataFormatError, match="non-finite"):
        load_frf("\n".join(text).encode(), filename="a.csv")


def test_csv_layout_errors_name_line_and_column():
    good = save_frf(sdof(), format="csv").decode()
    lines = good.splitlines()
    bad = lines[:-1] + [lines[-1].replace(",", ",x", 1)]
    with pytest.raises(DataFormatError, match=r"line \d+ column 2.*not a number"):
        load_frf("\n".join(bad).encode(), filename="a.csv")
    bad = lines[:-1] + [lines[-1] + ",1.0"]
    with pytest.raises(DataFormatError, match="fields, the header has 3"):
        load_frf("\n".join(bad).encode(), filename="a.csv")
    with pytest.raises(DataFormatError, match="first column must be the frequency"):
        load_frf(good.replace("freq [Hz]", "speed").encode(), filename="a.csv")
    with pytest.raises(DataFormatError, match="needs Re and Im"):
        load_frf(
            good.replace("Im(hub:z / hub:z)", "Phase(hub:z / hub:z)").encode(), filename="a.csv"
        )
    with pytest.raises(DataFormatError, match="content is binary data"):
        load_frf(b"freq,Re(a:x / a:x)\n\xff\xfe1,2\n", filename="a.csv")
    with pytest.raises(DataFormatError, match="not UTF-8"):
        load_frf(good.encode() + b"\xff\xfe1,2\n", filename="a.csv")


def test_csv_magnitude_phase_layout():
    Y = sdof()
    d = Y.data[:, 0, 0]
    rows = "\n".join(
        f"{float(f)!r},{float(abs(z))!r},{float(np.degrees(np.angle(z)))!r}"
        for f, z in zip(Y.freq, d, strict=True)
    )
    text = (
        "# quantity: mobility\n# layout: mag-phase\n# phase_unit: deg\n"
        "freq [Hz],Mag(hub:z / hub:z),Phase(hub:z / hub:z)\n" + rows
    )
    r = load_frf(text.encode(), filename="a.csv")
    assert r.frf.allclose(Y, rtol=1e-12)


def test_grids_that_do_not_match_are_put_together_only_explicitly():
    a, b = sdof(), sdof(np.arange(1, 30) * 0.7)
    with pytest.raises(FrequencyGridError, match="interpolate"):
        common_grid([a, b])
    grid = np.arange(1, 28) * 0.7
    a2, b2 = common_grid([a, b], grid)
    assert a2.same_grid(b2)
    with pytest.raises(FrequencyGridError, match="never extrapolated"):
        common_grid([a, b], np.arange(1, 60) * 0.5)


# -- quantities and units ------------------------------------------------------------
def test_quantity_must_be_known_and_consistent():
    v = dict(GOOD)
    del v["quantity"]
    with pytest.raises(QuantityError, match="pass quantity"):
        load_frf(mat5(**v), filename="a.mat")
    assert load_frf(mat5(**v), filename="a.mat", quantity="mobility").frf.quantity == "mobility"
    with pytest.raises(QuantityError, match="requested"):
        load_frf(mat5(**GOOD), filename="a.mat", quantity="receptance")
    with pytest.raises(QuantityError, match="units 'm/N' are those of a receptance"):
        load_frf(mat5(**dict(GOOD, units="m/N")), filename="a.mat")
    with pytest.raises(QuantityError, match="dynamic stiffness"):
        load_frf(mat5(**dict(GOOD, units="N/m")), filename="a.mat")
    with pytest.raises(QuantityError, match="impedance"):
        load_frf(mat5(**dict(GOOD, units="N s/m")), filename="a.mat")
    with pytest.raises(QuantityError, match="apparent mass"):
        load_frf(mat5(**dict(GOOD, units="kg")), filename="a.mat")
    with pytest.raises(QuantityError, match="unknown quantity"):
        load_frf(mat5(**GOOD), filename="a.mat", quantity="velocity")


@pytest.mark.parametrize(
    "label,quantity,length,force,g",
    [
        ("m/N", "receptance", 1.0, 1.0, False),
        ("m/(N s)", "mobility", 1.0, 1.0, False),
        ("m/s/N", "mobility", 1.0, 1.0, False),
        ("(m/s)/N", "mobility", 1.0, 1.0, False),
        ("mm/s/N", "mobility", 1e-3, 1.0, False),
        ("m s^-2 N^-1", "accelerance", 1.0, 1.0, False),
        ("m/s2/kN", "accelerance", 1.0, 1e3, False),
        ("g/N", "accelerance", 1.0, 1.0, True),
    ],
)
def test_units_parser(label, quantity, length, force, g):
    u = parse_units(label)
    assert (u.quantity, u.length, u.force, u.g) == (quantity, length, force, g)


def test_unit_factors_per_entry():
    u = parse_units("mm/N")
    fac = si_factors(u, ["a:x", "a:rx"], ["a:x", "a:rx"])
    # x/F: mm -> m; x/M: mm/(N mm) = 1/N; rx/F: rad/N; rx/M: rad/(N mm) -> *1e3
    np.testing.assert_allclose(fac, [[1e-3, 1.0], [1.0, 1e3]])
    assert parse_units("V/V") is None and parse_units("NONE") is None


def test_mm_units_in_a_mat_file_are_converted_and_reported():
    r = load_frf(mat5(**dict(GOOD, units="mm/(N s)")), filename="a.mat")
    np.testing.assert_allclose(r.frf.data, 1e-3 * GOOD["H"], rtol=1e-15)
    assert "converted from mm/(N s)" in r.summary


def test_receptance_declared_as_mobility_gets_a_note():
    R = sdof(quantity="receptance")
    r = load_frf(mat5(**dict(GOOD, H=R.data)), filename="a.mat")  # declared mobility
    assert any("check the quantity" in n and "receptance" in n for n in r.notes)
    assert not load_frf(mat5(**GOOD), filename="a.mat").notes


# -- MATLAB: nothing but plain arrays --------------------------------------------------
def test_mat5_objects_structs_sparse_are_refused():
    arr = np.zeros((1, 1), dtype=[("a", object)])
    arr[0, 0]["a"] = np.array([[1.0]])
    for extra, cls in (
        ({"o": MatlabObject(arr, "evil")}, "object"),
        ({"s": {"a": 1.0}}, "struct"),
        ({"sp": scipy.sparse.eye(3)}, "sparse"),
    ):
        with pytest.raises(DataFormatError, match=f"class '{cls}'"):
            load_frf(mat5(**GOOD, **extra), filename="a.mat")
    cell = np.empty((1, 2), dtype=object)
    cell[0, 0], cell[0, 1] = "a:x", np.array([1.0])
    with pytest.raises(DataFormatError, match="only hold character strings"):
        load_frf(mat5(**dict(GOOD, outputs=cell)), filename="a.mat")


def mat73(build) -> bytes:
    """A v7.3 file made by save_frf, then changed by ``build(h5file)``."""
    raw = bytearray(save_frf(sdof(), format="mat", mat_version="7.3"))
    b = io.BytesIO(bytes(raw))
    with h5py.File(b, "r+") as h:
        build(h)
    return b.getvalue()


def test_mat73_function_handles_structs_and_links_are_refused(tmp_path):
    def handle(h):
        d = h.create_dataset("fh", data=np.zeros((1, 1), np.uint32))
        d.attrs["MATLAB_class"] = np.bytes_("function_handle")

    def struct(h):
        g = h.create_group("s")
        g.attrs["MATLAB_class"] = np.bytes_("struct")

    def obj(h):
        d = h.create_dataset("o", data=np.zeros((1, 6), np.uint32))
        d.attrs["MATLAB_class"] = np.bytes_("evil")
        d.attrs["MATLAB_object_decode"] = np.int32(3)

    secret = tmp_path / "other_session.h5"
    with h5py.File(secret, "w") as s:
        s["H"] = np.ones(3)

    def external(h):
        h["ext"] = h5py.ExternalLink(str(secret), "/H")

    def soft(h):
        h["alias"] = h5py.SoftLink("/freq")

    for build, match in (
        (handle, "function_handle"),
        (struct, "struct"),
        (obj, "evil"),
        (external, "ExternalLink"),
        (soft, "SoftLink"),
    ):
        with pytest.raises(DataFormatError, match=match):
            load_frf(mat73(build), filename="a.mat")


def test_hdf5_data_stored_in_other_files_is_refused(tmp_path):
    ext = tmp_path / "raw.bin"
    ext.write_bytes(np.arange(40.0).tobytes())
    b = io.BytesIO()
    with h5py.File(b, "w") as h:
        g = h.create_group("frf")
        g.create_dataset("freq", shape=(40,), dtype="<f8", external=[(str(ext), 0, 320)])
        g.create_dataset("data", data=sdof().data)
        g.attrs["outputs"] = ["hub:z"]
        g.attrs["inputs"] = ["hub:z"]
    with pytest.raises(DataFormatError, match="other files"):
        load_frf(b.getvalue(), filename="a.h5")


def test_hdf5_group_choice():
    raw = save_frf(sdof(), format="hdf5")
    with pytest.raises(DataFormatError, match="no FRF group 'nope'"):
        load_frf(raw, filename="a.h5", name="nope")
    with pytest.raises(DataFormatError, match="HDF5 files only"):
        load_frf(save_frf(sdof(), format="csv"), filename="a.csv", name="frf")


# -- interface ---------------------------------------------------------------------------
def test_interface_check_flags_a_singular_interface():
    labels = ("hub:x", "hub:z")
    A = sdof(labels=labels)  # every entry equal: rank 1
    with pytest.raises(SingularInterfaceError, match="singular or ill-conditioned"):
        interface_check(A, A)
    w = 2 * np.pi * F
    diag = np.stack([np.eye(2) / (3e4 - w_**2 + 5j * w_) for w_ in w]) * (1j * w)[:, None, None]
    B = FRF(F, diag, labels, labels, "mobility")
    cond = interface_check(B, B)
    assert cond.shape == F.shape and np.all(cond < 10)


def test_all_errors_are_value_errors_too():
    with pytest.raises(ValueError):
        load_frf(b"junk", filename="a.mat")
    assert issubclass(DataFormatError, FBSError)


def test_named_nodes_are_renamed_to_spindle_and_bushing():
    Y = sdof(labels=("knuckle:z", "mount3:z"))
    r = load_frf(
        save_frf(Y, format="csv"),
        filename="a.csv",
        nodes={"knuckle": "spindle", "mount3": "bushing"},
    )
    assert r.frf.outputs == ("spindle:z", "bushing:z") == r.frf.inputs
    np.testing.assert_array_equal(r.frf.data, Y.data)


def test_prepare_chassis_renames_selects_and_converts():
    from fbs_core.dofs import node_labels
    from fbs_core.io import prepare_chassis

    outs = node_labels("knuckle") + ("mount:z", "mount:x")
    ins = node_labels("knuckle")
    rng = np.random.default_rng(0)
    A = FRF(F, rng.normal(size=(F.size, 8, 6)) + 0j, outs, ins, "accelerance")
    Y, notes = prepare_chassis(A, spindle="knuckle", bushing="mount")
    assert Y.inputs == node_labels("spindle") and Y.quantity == "mobility"
    assert Y.outputs == node_labels("spindle") + ("bushing:x", "bushing:z")
    np.testing.assert_allclose(Y.data[:, 6], A.data[:, 7] / (2j * np.pi * F)[:, None])
    assert len(notes) == 2
    with pytest.raises(DOFError, match="no node 'hub'"):
        prepare_chassis(A, spindle="hub", bushing="mount")
    with pytest.raises(DOFError, match="no bushing output"):
        prepare_chassis(Y.sel(outputs=node_labels("spindle")))
    with pytest.raises(DOFError, match="lacks outputs spindle:rz"):
        prepare_chassis(A.sel(outputs=outs[:5] + outs[6:]), spindle="knuckle", bushing="mount")
