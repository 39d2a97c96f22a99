"""The registry of file formats (fbs_core.io.formats) and the one assembly step
(fbs_core.io.assembly) that every FRF reader ends with.

Truth: FRFs built here from a closed-form system (test_io_roundtrip.two_dof) and from
known factors (a '-' direction is x-1, mm is x1e-3); the registry is checked against
what the entry points do with every row, never against itself.
"""

from __future__ import annotations

import io as _io
import json
import re

import numpy as np
import pytest
from test_io_modal import small_tire
from test_io_roundtrip import FREQ, two_dof

import fbs_core
from fbs_core import FRF
from fbs_core.errors import DataFormatError, QuantityError
from fbs_core.io import (
    FORMATS,
    REGISTRY,
    export_result,
    import_tire_model,
    load_frf,
    load_result,
    save_frf,
)
from fbs_core.io import _sandbox as sandbox
from fbs_core.io.matlab import write_mat_vars
from fbs_core.io.modal import write_tire_mat
from fbs_core.io.uff import frf_records, write_uff_records

ALL_ENDINGS = [(f.name, s) for f in REGISTRY.values() for s in f.suffixes]


def _rotations() -> FRF:
    """Translations and rotations per force and moment: entries of four different kinds."""
    Y = two_dof(FREQ[:12])
    outs, ins = ["spindle:z", "bushing:rx"], ["spindle:z", "bushing:ry"]
    return FRF(Y.freq, Y.data, outs, ins, "mobility")


def test_the_registry_is_the_table_of_formats():
    assert list(REGISTRY) == ["uff", "mat", "csv", "hdf5"]
    assert {k: v for k, v in FORMATS.items()} == {f.name: f.suffixes for f in REGISTRY.values()}
    endings = [s for _, s in ALL_ENDINGS]
    assert len(endings) == len(set(endings)), "an ending selects one format"
    for f in REGISTRY.values():
        assert all(s.startswith(".") and s == s.lower() for s in f.suffixes)
        assert f.contents and f.label and f.title


@pytest.mark.parametrize("fmt, suffix", ALL_ENDINGS)
def test_every_registered_format_round_trips_through_save_and_load(tmp_path, fmt, suffix):
    """Through a path with each ending (the format from the ending), and as bytes."""
    Y = _rotations()
    p = save_frf(Y, tmp_path / f"y{suffix}", metadata={"seed": 3})
    r = load_frf(p)
    assert r.frf.allclose(Y, rtol=1e-10) and r.frf.quantity == "mobility"
    assert r.format in REGISTRY[fmt].contents.values()
    raw = save_frf(Y, format=fmt)
    assert load_frf(raw, filename=f"upload{suffix.upper()}").frf.allclose(Y, rtol=1e-10)


@pytest.mark.parametrize(
    "option, value, fmt, content",
    [("mat_version", "7.3", "mat", "MATLAB v7.3"), ("binary", True, "uff", "UFF 58")],
)
def test_write_options_reach_their_format_only(option, value, fmt, content):
    Y = _rotations()
    raw = save_frf(Y, format=fmt, **{option: value})
    r = load_frf(raw, filename=f"y{REGISTRY[fmt].suffixes[0]}")
    assert r.format == content and r.frf.allclose(Y, rtol=1e-10)
    if option == "binary":
        assert raw != save_frf(Y, format="uff")  # 58b, not the text records
    other = "csv"
    assert save_frf(Y, format=other, **{option: value}) == save_frf(Y, format=other)


@pytest.mark.parametrize(
    "call",
    [
        lambda: load_frf(b"1,2\n", filename="data.xlsx"),
        lambda: import_tire_model(b"1,2\n", filename="tire.xlsx"),
        lambda: save_frf(_rotations(), "out.xlsx"),
        lambda: export_result(_rotations(), "out.xlsx"),
    ],
    ids=["load_frf", "import_tire_model", "save_frf", "export_result"],
)
def test_an_unknown_suffix_names_every_supported_one(call):
    with pytest.raises(DataFormatError, match="known endings") as e:
        call()
    for fmt, suffix in ALL_ENDINGS:
        assert suffix in str(e.value) and fmt in str(e.value)


def test_an_unknown_format_name_lists_the_registered_ones():
    with pytest.raises(DataFormatError, match="unknown format 'xls'; allowed: uff, mat, csv, hdf5"):
        save_frf(_rotations(), format="xls")


def test_content_that_is_not_what_the_ending_says_names_the_format_expected():
    raw = save_frf(_rotations(), format="csv")
    for f in REGISTRY.values():
        if "text" in f.contents:
            continue
        with pytest.raises(
            DataFormatError, match=f"should be a {re.escape(f.title)} .*a text file"
        ):
            load_frf(raw, filename=f"y{f.suffixes[0]}")


@pytest.mark.parametrize("key, value", [("freq", FREQ[:4]), ("name", "frf")])
def test_a_read_option_of_another_format_names_the_formats_that_take_it(key, value):
    having = [f for f in REGISTRY.values() if key in f.read_options]
    assert having
    for f in REGISTRY.values():
        if f in having:
            continue
        raw = save_frf(_rotations(), format=f.name)
        want = " or ".join(h.label for h in having)
        with pytest.raises(DataFormatError, match=f"{key}= applies to {want} files only"):
            load_frf(raw, filename=f"y{f.suffixes[0]}", **{key: value})


def test_every_exporter_writes_and_the_others_name_them():
    Y = _rotations()
    exporters = [f for f in REGISTRY.values() if f.export is not None]
    assert {f.name for f in exporters} == {"uff", "csv", "hdf5"}
    for f in exporters:
        raw = export_result(Y, format=f.name, metadata={"seed": 5})
        if f.name == "hdf5":
            assert load_result(raw, filename="r.h5").frfs["frf"].allclose(Y, rtol=1e-12)
        else:  # the FRF table / records read back as an FRF
            assert load_frf(raw, filename=f"r{f.suffixes[0]}").frf.allclose(Y, rtol=1e-10)
    for f in REGISTRY.values():
        if f.export is None:
            with pytest.raises(DataFormatError, match=f"not {f.name!r}") as e:
                export_result(Y, format=f.name)
            assert all(x.name in str(e.value) for x in exporters)


def test_every_tire_reader_reads_the_model_and_the_others_name_them(tmp_path):
    from fbs_core.tire import storage

    written = small_tire(seed=11)
    files = {
        "mat": write_tire_mat(written),
        "hdf5": storage.save_tire_model(written, tmp_path / "t.h5").read_bytes(),
    }
    readers = [f for f in REGISTRY.values() if f.read_tire is not None]
    assert {f.name for f in readers} == set(files)
    for f in readers:
        r = import_tire_model(files[f.name], filename=f"t{f.suffixes[0]}")
        np.testing.assert_array_equal(r.model.poles, written.poles)
        assert r.format == (f.tire_label or next(iter(f.contents.values())))
    for f in REGISTRY.values():
        if f.read_tire is None:
            raw = save_frf(_rotations(), format=f.name)
            with pytest.raises(DataFormatError, match="tire models are read from MATLAB") as e:
                import_tire_model(raw, filename=f"t{f.suffixes[0]}")
            assert all(x.suffixes[0] in str(e.value) for x in readers)


def test_sandboxed_formats_are_parsed_in_the_sandbox_process(monkeypatch):
    """Every read of a format marked ``sandboxed`` sends the file to the parser process."""
    sent: list[str] = []
    request = sandbox._Worker.request

    def spy(self, kind, raw, *args, **kwargs):
        sent.append(kind)
        return request(self, kind, raw, *args, **kwargs)

    monkeypatch.setattr(sandbox._Worker, "request", spy)
    Y = _rotations()
    for f in REGISTRY.values():
        sent.clear()
        load_frf(save_frf(Y, format=f.name), filename=f"y{f.suffixes[0]}")
        assert bool(sent) == f.sandboxed, f.name


# -- the assembly step: the same content assembles to the same FRF in every format ------------
#: SI value of one unit of "mm/(kN s)" for the entries of _rotations() (outputs spindle:z,
#: bushing:rx; inputs spindle:z, bushing:ry), from 1 mm = 1e-3 m, 1 kN = 1e3 N, angles in
#: rad: (m/s)/N 1e-6, (m/s)/(N m) 1e-3 (a moment of 1 kN mm = 1 N m), (rad/s)/N 1e-3,
#: (rad/s)/(N m) 1.
SI_PER_FILE_UNIT = np.array([[1e-6, 1e-3], [1e-3, 1.0]])


def _file_values(Y: FRF) -> np.ndarray:
    """Y as the files below give it: 'bushing:rx' written for the opposite direction, in
    mm/(kN s)."""
    d = Y.data / SI_PER_FILE_UNIT[None]
    d[:, 1, :] *= -1.0  # '-rx' in the file
    return d


def _mat(Y: FRF, units: str) -> bytes:
    return write_mat_vars(
        {
            "freq": Y.freq,
            "H": _file_values(Y),
            "outputs": ["spindle:z", "bushing:-RX"],
            "inputs": list(Y.inputs),
            "units": units,
            "metadata": json.dumps({"seed": 1}),
        }
    )


def _h5(Y: FRF, units: str) -> bytes:
    import h5py

    b = _io.BytesIO()
    with h5py.File(b, "w") as h:
        g = h.create_group("frf")
        g["freq"], g["data"] = Y.freq, _file_values(Y)
        g.attrs["units"] = units
        s = h5py.string_dtype()
        g.attrs.create("outputs", np.array(["spindle:z", "bushing:-RX"], dtype=object), dtype=s)
        g.attrs.create("inputs", np.array(list(Y.inputs), dtype=object), dtype=s)
    return b.getvalue()


def _csv(Y: FRF, units: str) -> bytes:
    d = _file_values(Y)
    outs = ["spindle:z", "bushing:-RX"]
    cols = ["freq [Hz]"] + [f"{p}({o} / {i})" for o in outs for i in Y.inputs for p in ("Re", "Im")]
    rows = [",".join(cols)]
    for k, f in enumerate(Y.freq):
        vals = [x for z in d[k].ravel() for x in (z.real, z.imag)]
        rows.append(",".join(repr(float(x)) for x in [f, *vals]))
    return (f"# units: {units}\n" + "\n".join(rows) + "\n").encode()


def _uff(Y: FRF, units: str) -> bytes:
    recs = frf_records(Y.replace(data=_file_values(Y)))
    for r in recs:
        if r["rsp_ent_name"] == "bushing":
            r["rsp_dir"] = -r["rsp_dir"]
        r["ordinate_axis_units_lab"], r["orddenom_axis_units_lab"] = units, "NONE"
        r["ordinate_spec_data_type"] = 0  # only the units say the quantity
    return write_uff_records(recs)


WRITERS = {"mat": _mat, "hdf5": _h5, "csv": _csv, "uff": _uff}


@pytest.mark.parametrize("fmt", list(REGISTRY))
def test_signs_units_and_quantity_are_assembled_alike_in_every_format(fmt):
    assert set(WRITERS) == set(REGISTRY)
    Y = _rotations()
    raw = WRITERS[fmt](Y, "mm/(kN s)")
    r = load_frf(raw, filename=f"y{REGISTRY[fmt].suffixes[0]}")
    assert r.frf.outputs == ("spindle:z", "bushing:rx") and r.frf.quantity == "mobility"
    np.testing.assert_allclose(r.frf.data, Y.data, rtol=1e-10)  # UFF: 12 digits
    flipped = [n for n in r.notes if "sign was flipped" in n]
    assert flipped and flipped[0].startswith("2 of 4 entries")
    assert any(n.startswith("converted from mm/(kN s) to SI") for n in r.notes)
    # a label nothing understands is quoted, and the quantity must then be given
    raw = WRITERS[fmt](Y, "furlong/kN")
    with pytest.raises(QuantityError, match="'furlong/kN' is not understood"):
        load_frf(raw, filename=f"y{REGISTRY[fmt].suffixes[0]}")
    r = load_frf(raw, filename=f"y{REGISTRY[fmt].suffixes[0]}", quantity="mobility")
    assert any("'furlong/kN' not understood" in n for n in r.notes)
    np.testing.assert_allclose(r.frf.data, Y.data / SI_PER_FILE_UNIT[None], rtol=1e-10)


def test_a_quantity_contradicting_the_units_is_refused_in_every_format():
    Y = _rotations()
    for fmt, write in WRITERS.items():
        with pytest.raises(QuantityError, match="receptance.*requested|requested"):
            load_frf(
                write(Y, "mm/(kN s)"),
                filename=f"y{REGISTRY[fmt].suffixes[0]}",
                quantity="receptance",
            )


def test_the_package_exports_the_registry():
    assert fbs_core.io.REGISTRY is REGISTRY
    assert "REGISTRY" in fbs_core.io.__all__ and "FileFormat" in fbs_core.io.__all__
