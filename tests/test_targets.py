"""Target curves: closed-form evaluation, unit and quantity conversion, bad files refused.

Truth: straight lines in dB written out by hand (two-point forms), the SI value of
millimetres, the quantity relation of thesis table 2.1 (|a| = 2 pi f |v|) and the files
written here byte by byte.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.errors import DataFormatError, DOFError, FBSError, FrequencyGridError, QuantityError
from fbs_core.targets import IncumbentTarget, Target, read_targets

ROOT = Path(__file__).resolve().parents[1]


def _csv(text: str) -> bytes:
    return "\n".join(line.strip() for line in text.strip().splitlines()).encode() + b"\n"


# -- segments: closed form ----------------------------------------------------------------
def test_segments_on_a_log_axis_are_straight_lines_in_db_over_log_frequency():
    t = Target.segments("bushing:z", [(10.0, -20.0), (100.0, -40.0)], axis="log")
    f = np.array([10.0, 20.0, 50.0, 100.0])
    # two-point form over x = log10 f: L = -20 - 20 (log10 f - 1)
    expected = -20.0 - 20.0 * (np.log10(f) - 1.0)
    np.testing.assert_allclose(t.level_db_at(f), expected, rtol=0, atol=1e-12)
    assert t.level_db_at([20.0])[0] == pytest.approx(-20.0 - 20.0 * math.log10(2.0), abs=1e-12)


def test_segments_on_a_linear_axis_and_nothing_outside_the_range():
    pts = [(20.0, -10.0), (40.0, -30.0), (80.0, -30.0), (100.0, -20.0)]
    t = Target.segments("bushing:x", pts, axis="linear")
    f = np.array([10.0, 20.0, 30.0, 39.0, 60.0, 90.0, 100.0, 101.0])
    got = t.level_db_at(f)
    # by hand: 30 Hz halfway down the first segment; 39 Hz 19/20 of it; 90 Hz halfway up
    want = [np.nan, -10.0, -20.0, -29.0, -30.0, -25.0, -20.0, np.nan]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    assert t.freq_range == (20.0, 100.0)


def test_linear_level_and_db_reference():
    t = Target.segments("bushing:z", [(10.0, 0.0), (20.0, 0.0)], axis="linear", ref=1e-3)
    # 0 dB re 1e-3 (m/s)/m is 1e-3 (m/s)/m, i.e. -60 dB re 1
    assert t.level_at([15.0])[0] == pytest.approx(1e-3, rel=1e-12)
    assert t.level_db_at([15.0], ref=1.0)[0] == pytest.approx(-60.0, abs=1e-12)
    assert t.unit == "(m/s)/m"
    assert Target.segments("bushing:rz", [(10, 0), (20, 0)]).unit == "(rad/s)/m"


def test_quantity_conversion_is_exact_at_every_line():
    # a flat accelerance target of 1 (m/s^2)/m is 1 / (2 pi f) (m/s)/m in mobility
    t = Target.segments("bushing:z", [(10.0, 0.0), (200.0, 0.0)], quantity="accelerance")
    f = np.array([10.0, 33.3, 150.0, 200.0])
    np.testing.assert_allclose(t.level_at(f, "mobility"), 1.0 / (2 * np.pi * f), rtol=1e-12)
    np.testing.assert_allclose(t.level_at(f, "receptance"), 1.0 / (2 * np.pi * f) ** 2, rtol=1e-12)


def test_target_validation_names_the_problem():
    with pytest.raises(FBSError, match="not a finite dB value"):
        Target("bushing:z", [10.0, 20.0], [0.0, np.nan])
    with pytest.raises(FrequencyGridError, match="at least two points"):
        Target("bushing:z", [10.0], [0.0])
    with pytest.raises(FrequencyGridError, match="strictly increasing"):
        Target("bushing:z", [20.0, 10.0], [0.0, 0.0])
    with pytest.raises(FrequencyGridError, match="above 0 Hz"):
        Target.segments("bushing:z", [(0.0, 0.0), (10.0, 0.0)], axis="log")
    with pytest.raises(DOFError, match="hub:q"):
        Target("hub:q", [10.0, 20.0], [0.0, 0.0])
    with pytest.raises(QuantityError, match="velocity"):
        Target("bushing:z", [10.0, 20.0], [0.0, 0.0], quantity="velocity")
    with pytest.raises(FBSError, match="positive number"):
        Target.from_levels("bushing:z", [10.0, 20.0], [1.0, 0.0])
    with pytest.raises(FBSError, match="axis"):
        Target("bushing:z", [10.0, 20.0], [0.0, 0.0], axis="octave")
    with pytest.raises(fc.HarmonicError):
        Target("bushing:z", [10.0, 20.0], [0.0, 0.0], harmonic=9)


def test_incumbent_target_is_the_response_plus_the_margin():
    f = np.linspace(40.0, 80.0, 5)
    data = np.zeros((5, 2, 1), complex)
    data[:, 0, 0] = [0.1, 0.2j, -0.3, 0.4, 0.5]
    data[:, 1, 0] = 1.0
    Y = fc.FRF(f, data, ["bushing:x", "bushing:z"], ["patch"])
    (t,) = IncumbentTarget("A", margin_db=3.0, dofs=("bushing:x",)).resolve(Y, 4)
    expected = 20 * np.log10([0.1, 0.2, 0.3, 0.4, 0.5]) + 3.0
    np.testing.assert_allclose(t.level_db_at(f), expected, atol=1e-12)
    assert t.harmonic == 4 and t.quantity == "mobility" and t.input_kind == "road"


# -- files ----------------------------------------------------------------------------------
def test_csv_target_in_millimetres_is_converted_to_si():
    raw = _csv(
        """
        # tire-fbs target
        # quantity: mobility
        # units: (mm/s)/m
        freq [Hz],bushing:z,bushing:x
        20,5.0,2.0
        100,5.0,8.0
        """
    )
    tz, tx = read_targets(raw, filename="t.csv")
    assert (tz.dof, tx.dof) == ("bushing:z", "bushing:x")
    # 5 mm/s per metre of road is 5e-3 (m/s)/m
    np.testing.assert_allclose(tz.level_at([20.0, 60.0, 100.0]), 5e-3, rtol=1e-12)
    # linear in dB between 2 and 8 mm/s: at the middle frequency 4 mm/s (geometric mean)
    assert tx.level_at([60.0])[0] == pytest.approx(4e-3, rel=1e-12)
    # (mm/s)/mm is the SI ratio: factor 1
    raw2 = raw.replace(b"(mm/s)/m", b"(mm/s)/mm")
    assert read_targets(raw2, filename="t.csv")[0].level_at([20.0])[0] == pytest.approx(5.0)


def test_csv_target_in_db_with_a_reference_and_an_acceleration_quantity():
    raw = _csv(
        """
        # quantity: accelerance
        # units: (mm/s^2)/m
        # scale: dB
        # ref: 1
        # axis: log
        # harmonic: 4
        freq [Hz],bushing:z
        10,20.0
        1000,20.0
        """
    )
    (t,) = read_targets(raw, filename="acc.csv")
    assert t.harmonic == 4 and t.axis == "log" and t.quantity == "accelerance"
    f = np.array([40.0, 100.0])
    # 20 dB re 1 (mm/s^2)/m = 10 (mm/s^2)/m = 1e-2 (m/s^2)/m; as mobility / (2 pi f)
    np.testing.assert_allclose(t.level_at(f), 1e-2, rtol=1e-12)
    np.testing.assert_allclose(t.level_at(f, "mobility"), 1e-2 / (2 * np.pi * f), rtol=1e-12)


def test_uff_target_of_an_accelerance_is_read_as_a_level_and_converted():
    f = np.array([20.0, 50.0, 100.0, 200.0])
    a = np.zeros((4, 1, 1), complex)
    a[:, 0, 0] = 3.0 * np.exp(1j * np.array([0.1, 1.0, 2.0, -1.0]))  # |a| = 3
    Y = fc.FRF(f, a, ["1:z"], ["patch"], "accelerance")
    raw = fc.io.save_frf(Y, format="uff")
    (t,) = read_targets(raw, filename="target.uff", nodes={1: "bushing", 2: "patch"})
    assert t.dof == "bushing:z" and t.quantity == "accelerance"
    np.testing.assert_allclose(t.level_at(f, "mobility"), 3.0 / (2 * np.pi * f), rtol=1e-9)


def test_the_shipped_example_target_file_reads():
    ts = read_targets(ROOT / "data" / "targets" / "bushing_targets.csv")
    assert {t.dof for t in ts} == {"bushing:x", "bushing:y", "bushing:z"}
    assert all(t.unit == "(m/s)/m" for t in ts)


_GOOD = """
# quantity: mobility
# units: (m/s)/m
freq [Hz],bushing:z
20,1.0
100,1.0
"""


@pytest.mark.parametrize(
    ("edit", "error", "match"),
    [
        (("100,1.0", "100,nan"), DataFormatError, r"line 5, column 2 \('bushing:z'\).*NaN"),
        (("bushing:z", "hub:z"), DOFError, r"'hub:z'.*available: bushing:x"),
        (("bushing:z", "bushing:q"), DOFError, "q"),
        (("(m/s)/m", "furlong/s"), QuantityError, "'furlong/s' are not understood"),
        (("(m/s)/m", "N/m"), QuantityError, "dynamic stiffness"),
        (("(m/s)/m", "(mm/s)/N"), QuantityError, r"'\(mm/s\)/N' are a level per a force"),
        (("(m/s)/m", "mm/s"), QuantityError, "per no input"),
        (("(m/s)/m", "(rad/s)/m"), QuantityError, "rotation, but bushing:z is a translation"),
        (("(m/s)/m", "(m/s^2)/m"), QuantityError, "declares a mobility"),
        (("100,1.0", "10,1.0"), FrequencyGridError, "strictly increasing"),
        (("100,1.0", "100,0.0"), DataFormatError, "not positive"),
        (("freq [Hz]", "speed"), DataFormatError, "first column must be the frequency"),
        (("# quantity: mobility\n# units: (m/s)/m", ""), QuantityError, "receptance, mobility"),
    ],
)
def test_bad_target_files_are_refused_naming_the_problem(edit, error, match):
    raw = _csv(_GOOD.replace(*edit))
    with pytest.raises(error, match=match):
        read_targets(raw, filename="bad.csv")


def test_other_file_types_and_inputs_are_refused():
    with pytest.raises(DataFormatError, match=r"\.csv, \.txt, \.uff"):
        read_targets(b"anything", filename="t.xlsx")
    f = np.array([20.0, 100.0])
    Y = fc.FRF(f, np.ones((2, 1, 1)), ["1:z"], ["2:z"], "mobility")  # per force
    raw = fc.io.save_frf(Y, format="uff")
    with pytest.raises(QuantityError, match="per force"):
        read_targets(raw, filename="t.uff", nodes={1: "bushing"})
    Y2 = fc.FRF(f, np.ones((2, 1, 2)), ["1:z"], ["patch", "road_b"], "mobility")
    raw2 = fc.io.save_frf(Y2, format="uff")
    with pytest.raises(DataFormatError, match="one input"):
        read_targets(raw2, filename="t.uff", nodes={1: "bushing"})


def test_vehicle_scope_dofs_are_accepted_when_named():
    raw = _csv(_GOOD.replace("bushing:z", "seat_fl:z"))
    with pytest.raises(DOFError, match="seat_fl:z"):
        read_targets(raw, filename="t.csv")
    (t,) = read_targets(raw, filename="t.csv", dofs=["seat_fl:z", "seat_fl:x"])
    assert t.dof == "seat_fl:z"
