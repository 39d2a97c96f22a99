"""UFF dataset 58 written by other tools: pyuff's own writer, and a file typed by hand
from the format's specification (records 1-11, then the data, between '-1' lines)."""

from __future__ import annotations

import numpy as np
import pytest

from fbs_core.errors import DataFormatError, DOFError, FrequencyGridError, QuantityError
from fbs_core.io import load_frf


def pyuff_file(tmp_path, records, name="pyuff.uff", force_double=True):
    """Write dataset-58 records with pyuff's public API only."""
    import pyuff

    path = tmp_path / name
    uff = pyuff.UFF(str(path))
    for r in records:
        base = dict(
            func_type=4,
            abscissa_spacing=1,
            abscissa_spec_data_type=18,
            ordinate_spec_data_type=12,
            orddenom_spec_data_type=13,
            binary=0,
        )
        base.update(r)
        uff.write_sets(pyuff.prepare_58(**base), mode="add", force_double=force_double)
    return path


def sdof_accelerance(f):
    m, k, c = 1.5, 6e4, 12.0
    w = 2 * np.pi * f
    return -(w**2) / (k - w**2 * m + 1j * w * c)


def test_pyuff_written_accelerances(tmp_path):
    f = np.arange(0, 50) * 2.0 + 2.0
    A = sdof_accelerance(f)
    recs = []
    for node, d, scale in ((1, 3, 1.0), (2, 1, 0.5), (2, 5, 0.25)):
        recs.append(
            dict(
                rsp_node=node, rsp_dir=d, ref_node=1, ref_dir=3, data=A * scale, x=f, id1="measured"
            )
        )
    p = pyuff_file(tmp_path, recs)
    r = load_frf(p, nodes={1: "spindle", 2: "bushing"})
    assert r.frf.quantity == "accelerance"
    assert r.frf.outputs == ("spindle:z", "bushing:x", "bushing:ry")
    assert r.frf.inputs == ("spindle:z",)
    np.testing.assert_allclose(r.frf.freq, f)
    np.testing.assert_allclose(
        r.frf.data[:, :, 0], np.stack([A, 0.5 * A, 0.25 * A], axis=1), rtol=1e-10
    )


def test_pyuff_uneven_binary_and_negative_directions(tmp_path):
    f = np.array([1.0, 1.5, 3.0, 7.5, 12.0])
    A = sdof_accelerance(f)
    p = pyuff_file(
        tmp_path,
        [
            dict(
                rsp_node=4,
                rsp_dir=-2,
                ref_node=4,
                ref_dir=2,
                data=A,
                x=f,
                abscissa_spacing=0,
                binary=1,
            )
        ],
    )
    r = load_frf(p)
    assert r.frf.outputs == ("4:y",) and r.frf.inputs == ("4:y",)
    np.testing.assert_allclose(r.frf.data[:, 0, 0], -A, rtol=1e-12)
    assert any("sign was flipped" in n for n in r.notes)


def test_pyuff_single_precision(tmp_path):
    f = np.arange(1, 21) * 1.0
    A = sdof_accelerance(f)
    p = pyuff_file(
        tmp_path,
        [dict(rsp_node=1, rsp_dir=3, ref_node=1, ref_dir=3, data=A, x=f, ord_data_type=5)],
        force_double=False,
    )
    r = load_frf(p)
    np.testing.assert_allclose(r.frf.data[:, 0, 0], A, rtol=1e-5)


def test_pyuff_scalar_direction_gives_generalised_dof(tmp_path):
    f = np.arange(1, 6) * 1.0
    p = pyuff_file(
        tmp_path,
        [dict(rsp_node=1, rsp_dir=3, ref_node=9, ref_dir=0, data=sdof_accelerance(f), x=f)],
    )
    assert load_frf(p, nodes={9: "patch", 1: "hub"}).frf.inputs == ("patch",)


# Typed by hand from the dataset 58 specification: record 6 is
# Format(2(I5,I10),2(1X,10A1,I10,I4)), record 7 Format(3I10,3E13.5), records 8-11
# Format(I10,3I5,2(1X,20A1)). Record 1: complex single precision, even spacing
# (data case 3, 6E13.5: re im re im ...). Record 2: complex double precision, uneven
# (case 8, E13.5,2E20.12: x re im). Response node 2 (+Z, then +X), reference node 1 in
# direction -Z, so both functions change sign. Velocity over excitation force: mobility.
HAND_WRITTEN = """\
    -1
    58
Hand-typed mobility, record 1
NONE
22-NOV-26 01:00:00
NONE
NONE
    4         1    1         0 NONE               2   3 NONE               1  -3
         5         3         1  1.00000E+01  5.00000E+00  0.00000E+00
        18    0    0    0 Frequency            Hz
        11    0    0    0 Velocity             m/s
        13    0    0    0 Force                N
         0    0    0    0 NONE                 NONE
  1.00000E+00 -2.00000E+00  3.00000E-01  4.00000E-01 -5.00000E-02  6.00000E+00
    -1
    -1
    58
Hand-typed mobility, record 2
NONE
22-NOV-26 01:00:00
NONE
NONE
    4         2    1         0 NONE               2   1 NONE               1  -3
         6         3         0  0.00000E+00  0.00000E+00  0.00000E+00
        18    0    0    0 Frequency            Hz
        11    0    0    0 Velocity             m/s
        13    0    0    0 Force                N
         0    0    0    0 NONE                 NONE
  1.00000E+01  1.000000000000E-03 -2.000000000000E-03
  1.50000E+01  2.500000000000E-03  0.000000000000E+00
  2.00000E+01 -7.000000000000E-04  1.250000000000E-02
    -1
"""


def test_hand_written_from_the_specification():
    r = load_frf(HAND_WRITTEN.encode(), filename="hand.uff", nodes={1: "spindle", 2: "bushing"})
    frf = r.frf
    assert frf.quantity == "mobility"
    assert frf.outputs == ("bushing:z", "bushing:x") and frf.inputs == ("spindle:z",)
    np.testing.assert_array_equal(frf.freq, [10.0, 15.0, 20.0])
    z = np.array([1 - 2j, 0.3 + 0.4j, -0.05 + 6j])
    x = np.array([1e-3 - 2e-3j, 2.5e-3, -7e-4 + 1.25e-2j])
    np.testing.assert_allclose(frf.data[:, 0, 0], -z, rtol=1e-12)
    np.testing.assert_allclose(frf.data[:, 1, 0], -x, rtol=1e-12)
    assert r.metadata["id1"] == "Hand-typed mobility, record 1"


def _edit(text, old, new):
    assert old in text
    return text.replace(old, new, 1).encode()


def test_hand_written_variants_are_refused_with_reasons():
    # direction code 7 does not exist
    bad = _edit(HAND_WRITTEN, "  2   3 NONE", "  2   7 NONE")
    with pytest.raises(DOFError, match="direction code 7"):
        load_frf(bad, filename="x.uff")
    # force over displacement is a dynamic stiffness
    bad = _edit(
        HAND_WRITTEN,
        "        11    0    0    0 Velocity             m/s\n"
        "        13    0    0    0 Force                N",
        "        13    0    0    0 Force                N\n"
        "         8    0    0    0 Displacement         m",
    )
    with pytest.raises(QuantityError, match="inverse FRF"):
        load_frf(bad, filename="x.uff")
    # a velocity whose units say acceleration
    bad = HAND_WRITTEN.replace("Velocity             m/s", "Velocity             m/s^2")
    with pytest.raises(QuantityError, match="declares a mobility"):
        load_frf(bad.encode(), filename="x.uff")
    # ... or only in one record
    bad = _edit(HAND_WRITTEN, "Velocity             m/s", "Velocity             m/s^2")
    with pytest.raises(QuantityError, match="mixes units"):
        load_frf(bad, filename="x.uff")
    # the second record on another grid
    bad = _edit(HAND_WRITTEN, "  2.00000E+01 -7.0", "  2.10000E+01 -7.0")
    with pytest.raises(FrequencyGridError, match="pass freq="):
        load_frf(bad, filename="x.uff")
    # ... which is accepted when the common grid is given explicitly
    r = load_frf(bad, filename="x.uff", freq=[10.0, 12.5, 15.0])
    assert r.frf.freq.size == 3 and any("interpolated" in n for n in r.notes)
    # a header announcing more values than there are (truncated data)
    bad = _edit(HAND_WRITTEN, "         5         3         1", "         5         4         1")
    with pytest.raises(DataFormatError, match="announces 4 values"):
        load_frf(bad, filename="x.uff")
    # time data is not an FRF
    bad = _edit(
        HAND_WRITTEN, "        18    0    0    0 Frequency", "        17    0    0    0 Time     "
    )
    with pytest.raises(DataFormatError, match="frequency"):
        load_frf(bad, filename="x.uff")
    # a coherence record alone: no FRF
    bad = HAND_WRITTEN.split("    -1\n    -1\n")[0] + "    -1\n"
    bad = _edit(bad, "    4         1    1", "    6         1    1")
    with pytest.raises(DataFormatError, match="no FRF records"):
        load_frf(bad, filename="x.uff")


def test_missing_pair_is_named(tmp_path):
    f = np.arange(1, 6) * 1.0
    A = sdof_accelerance(f)
    p = pyuff_file(
        tmp_path,
        [
            dict(rsp_node=1, rsp_dir=3, ref_node=1, ref_dir=3, data=A, x=f),
            dict(rsp_node=2, rsp_dir=3, ref_node=1, ref_dir=1, data=A, x=f),
        ],
    )
    with pytest.raises(DataFormatError, match="1:z/1:x"):
        load_frf(p)


def test_units_in_mm_are_converted_to_si_per_entry():
    text = HAND_WRITTEN.replace("Velocity             m/s ", "Velocity             mm/s")
    text = text.replace("Velocity             m/s\n", "Velocity             mm/s\n")
    r = load_frf(text.encode(), filename="mm.uff")
    si = load_frf(HAND_WRITTEN.encode(), filename="si.uff")
    # translational output over force input: mm -> m
    np.testing.assert_allclose(r.frf.data, 1e-3 * si.frf.data, rtol=1e-12)
    assert any("converted from" in n for n in r.notes)


def test_node_map_entries_missing_from_the_file_are_reported():
    r = load_frf(HAND_WRITTEN.encode(), filename="hand.uff", nodes={1: "spindle", 7: "bushing"})
    assert r.frf.outputs == ("2:z", "2:x")
    assert any("node numbers 7" in n and "nodes in the file: 1, 2" in n for n in r.notes)


def test_node_map_must_map_numbers_to_names():
    with pytest.raises(DataFormatError, match="maps UFF node numbers to names"):
        load_frf(HAND_WRITTEN.encode(), filename="hand.uff", nodes={"spindle": 1})
