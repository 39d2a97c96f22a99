"""Universal Files written by other programs, and cut ones (issue 12.3).

The truth of the values is a second reader, pyuff; the files and their origin are
listed in ``tests/data/uff/README.md``.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from fbs_core.errors import DataFormatError
from fbs_core.io import load_frf, save_frf
from fbs_core.io._textparse import ParseError, parse_uff

DATA = Path(__file__).parent / "data" / "uff"
READABLE = [
    "non_ascii_header.uff",
    "measurement.uff",
    "sample_dataset58_psd.uff",
    "time-history-not-all-columns-filled.uff",
    "Sample_UFF58b_bin.uff",
    "binary8byte.uff",
]


def pyuff_58(path: Path) -> list[dict]:
    import pyuff

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sets = pyuff.UFF(str(path)).read_sets()
    sets = [sets] if isinstance(sets, dict) else sets
    return [s for s in sets if s["type"] == 58]


@pytest.mark.parametrize("name", READABLE)
def test_every_record_reads_as_pyuff_reads_it(name):
    meta, arrays = parse_uff((DATA / name).read_bytes())
    mine = [s for s in meta["sets"] if s["type"] == 58]
    ref = pyuff_58(DATA / name)
    assert len(mine) == len(ref) > 0
    for a, b in zip(mine, ref, strict=True):
        y = arrays[a["data"]]
        x = (
            arrays[a["x"]]
            if "x" in a
            else a["abscissa_min"] + np.arange(y.size) * a["abscissa_inc"]
        )
        np.testing.assert_array_equal(y, b["data"])
        np.testing.assert_allclose(x, b["x"], rtol=1e-12, atol=1e-12)
        for key in ("func_type", "rsp_node", "rsp_dir", "ref_node", "ref_dir", "num_pts"):
            assert a[key] == b[key], key
        for key in ("ordinate_spec_data_type", "orddenom_spec_data_type"):
            assert a[key] == b[key], key


def test_frf_of_a_measurement_system_with_a_latin1_unit_label():
    r = load_frf(DATA / "non_ascii_header.uff")
    ref = pyuff_58(DATA / "non_ascii_header.uff")[0]
    # '(1/N)*(m/s²)' with the superscript as Latin-1 byte 0xB2: an accelerance in SI
    assert r.frf.quantity == "accelerance"
    # record 6 gives node 0, direction 0 (scalar) for both: generalised DOFs "0"
    assert r.frf.outputs == ("0",) and r.frf.inputs == ("0",)
    np.testing.assert_array_equal(r.frf.data[:, 0, 0], ref["data"])
    np.testing.assert_allclose(r.frf.freq, ref["x"], rtol=1e-12)
    assert any("'(1/N)*(m/s²)' read as accelerance" in n for n in r.notes)


def test_frfs_written_by_pyuff():
    ref = pyuff_58(DATA / "measurement.uff")
    r = load_frf(DATA / "measurement.uff")
    assert r.frf.quantity == "accelerance" and r.frf.shape == (1001, 1, 3)
    for k, s in enumerate(ref):
        np.testing.assert_array_equal(r.frf.data[:, 0, k], s["data"])
        np.testing.assert_allclose(r.frf.freq, s["x"], rtol=1e-12)


@pytest.mark.parametrize(
    "name,holds",
    [
        ("sample_dataset58_psd.uff", "1 PSDs"),
        ("time-history-not-all-columns-filled.uff", "1 time responses"),
        ("Sample_UFF58b_bin.uff", "1 time responses"),
    ],
)
def test_files_without_frfs_say_what_they_hold(name, holds):
    with pytest.raises(DataFormatError, match=f"holds no FRF records .* it holds {holds}"):
        load_frf(DATA / name)


def test_a_record_announcing_more_values_than_present_is_refused():
    with pytest.raises(DataFormatError, match="announces 2508876 values .* truncated"):
        load_frf(DATA / "dataset_milestone_in_header.uff", quantity="mobility")


# -- cut files ------------------------------------------------------------------------------
def _three_records() -> bytes:
    import fbs_core as fc

    f = np.arange(1, 41) * 0.5
    rng = np.random.default_rng(3)
    d = rng.normal(size=(40, 3, 1)) + 1j * rng.normal(size=(40, 3, 1))
    return save_frf(fc.FRF(f, d, ["1:x", "1:y", "1:z"], ["2:z"]), format="uff")


@pytest.mark.parametrize("keep", [0.99, 0.97, 0.9, 0.75, 0.5])
def test_a_cut_file_is_an_error_saying_where_it_ends(keep):
    raw = _three_records()
    cut = raw[: int(len(raw) * keep)]
    n_lines = cut.count(b"\n") + 1
    with pytest.raises(DataFormatError, match=f"(line {n_lines}|lines .*-{n_lines - 1}|ends)"):
        load_frf(cut, filename="cut.uff")


def test_dropping_the_final_minus_one_loses_nothing_silently():
    raw = _three_records()
    assert raw.endswith(b"    -1\n")
    cut = raw[: -len(b"    -1\n")]
    with pytest.raises(
        DataFormatError, match="no closing '    -1' line: the file ends at its line"
    ):
        load_frf(cut, filename="cut.uff")
    # the complete file has all three records
    assert load_frf(raw, filename="ok.uff").frf.shape == (40, 3, 1)


def test_binary_58b_cut_inside_its_data():
    import fbs_core as fc

    Y = fc.FRF([1.0, 2.0, 3.0], np.ones((3, 1, 1)), ["a:z"], ["b:z"])
    raw = save_frf(Y, format="uff", binary=True)
    assert load_frf(raw, filename="b.uff").frf.allclose(Y)
    with pytest.raises(DataFormatError, match="binary data need 48 bytes but the file ends"):
        load_frf(raw[:-30], filename="b.uff")


def test_a_file_of_minus_one_lines_is_refused_fast_by_counting():
    """2.8 MB of '-1' lines (issue 12): linear, refused as empty; here checked through
    the parser's own count of empty datasets rather than a timing."""
    raw = b"    -1\n" * 400_000
    meta, _ = parse_uff(raw)
    assert meta["empty"] == 200_000 and meta["sets"] == []
    with pytest.raises(DataFormatError, match="no UFF datasets .*200000 empty"):
        load_frf(raw, filename="minus.uff", timeout=10)


def test_text_outside_datasets_is_refused():
    raw = _three_records() + b"garbage\n"
    with pytest.raises(ParseError, match="text after the last dataset at line"):
        parse_uff(raw)
