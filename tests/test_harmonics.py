"""The seven harmonic excitation cases (thesis fig. 4.4, table 5.1)."""

import numpy as np
import pytest

from fbs_core.errors import FBSError, FrequencyGridError
from fbs_core.harmonics import HARMONICS, Harmonic, HarmonicError, harmonic

# band edges of thesis table 5.1 (Hz)
TABLE_5_1 = [
    (12.9, 51.5),
    (16.7, 67.0),
    (24.6, 97.9),
    (34.8, 139.0),
    (50.2, 200.0),
    (72.1, 288.1),
    (105.6, 422.3),
]


@pytest.mark.parametrize("k", range(1, 8))
def test_band_edges_match_table_5_1(k):
    h = harmonic(k)
    lo, hi = h.freq_range
    assert lo == pytest.approx(TABLE_5_1[k - 1][0], rel=0.005)
    assert hi == pytest.approx(TABLE_5_1[k - 1][1], rel=0.005)
    assert hi / lo == pytest.approx(4.0)  # 30 -> 120 km/h
    assert h.speed_range == (30.0, 120.0)


@pytest.mark.parametrize("k", range(1, 8))
def test_speed_line_v_equals_f_lambda(k):
    h = harmonic(k)
    f = h.frequencies()
    v = h.speed_at(f)
    np.testing.assert_allclose(v / 3.6, f * h.wavelength)
    assert 30.0 - 1e-9 <= v.min() and v.max() <= 120.0 + 1e-9
    assert h.speed_at(h.freq_range[0]) == pytest.approx(30.0)
    assert h.speed_at(h.freq_range[1]) == pytest.approx(120.0)


def test_grid_is_common_lattice():
    f1, f2 = harmonic(1).frequencies(), harmonic(2).frequencies()
    np.testing.assert_allclose(np.intersect1d(f1, f2), f2[f2 <= f1[-1]])
    assert np.all(np.diff(harmonic(7).frequencies(1.0)) == 1.0)


def test_objects_are_frozen_and_listed():
    assert len(HARMONICS) == 7 and all(isinstance(h, Harmonic) for h in HARMONICS)
    assert harmonic(3) is HARMONICS[2]
    assert harmonic(HARMONICS[4]) is HARMONICS[4]
    with pytest.raises(AttributeError):
        harmonic(1).wavelength = 1.0
    assert harmonic(1).name == "1st harmonic"


@pytest.mark.parametrize("bad", [0, 8, -1, 1.0, "1", None, True])
def test_unknown_harmonic(bad):
    with pytest.raises(HarmonicError, match="allowed: 1, 2, 3, 4, 5, 6, 7"):
        harmonic(bad)
    assert issubclass(HarmonicError, FBSError)


def test_frequency_outside_band():
    with pytest.raises(FrequencyGridError, match="outside the 1st harmonic band"):
        harmonic(1).speed_at(60.0)
    with pytest.raises(FrequencyGridError):
        harmonic(1).speed_at([20.0, 5.0])
    with pytest.raises(FrequencyGridError, match="df must be"):
        harmonic(1).frequencies(0.0)
    with pytest.raises(FrequencyGridError, match="fewer than two"):
        harmonic(1).frequencies(100.0)
