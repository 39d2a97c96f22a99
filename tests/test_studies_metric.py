"""Floating-band error metric (thesis eq. 5.1) on cases with known answers."""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.studies.metric import band_centres, floating_band_error


def _sdof(f, f0, zeta=0.02):
    """Mobility of a unit-mass SDOF oscillator (closed form)."""
    w, w0 = 2 * np.pi * f, 2 * np.pi * f0
    return 1j * w / (w0**2 - w**2 + 2j * zeta * w0 * w)


F = np.arange(1.0, 200.0, 0.5)


def test_identical_curves_give_zero():
    rng = np.random.default_rng(0)
    v = rng.normal(size=(F.size, 6)) + 1j * rng.normal(size=(F.size, 6))
    c, e = floating_band_error(F, v, v.copy())
    assert e.shape == (c.size, 6)
    assert np.all(e == 0.0)


@pytest.mark.parametrize("a", [0.5, 0.9, 1.1, 2.0])
def test_scaled_curve_gives_one_minus_a_squared(a):
    # | |v|^2 - a^2 |v|^2 | / |v|^2 = |1 - a^2| in every band, whatever the curve
    v = _sdof(F, 40.0) + 0.3 * _sdof(F, 90.0)
    _, e = floating_band_error(F, v, a * v)
    np.testing.assert_allclose(e, abs(1 - a**2), rtol=1e-12)


def test_phase_alone_is_not_an_error():
    # eq. 5.1 compares magnitudes only (thesis 5.1.2)
    v = _sdof(F, 40.0)
    _, e = floating_band_error(F, v, v * np.exp(1j * 0.7))
    np.testing.assert_allclose(e, 0.0, atol=1e-14)


def test_single_line_mismatch_counted_by_hand():
    # unit curve; one line (5 Hz) with power 3: mismatch 2 there.
    f = np.arange(0.0, 11.0)
    vt = np.ones(f.size)
    vm = vt.copy()
    vm[5] = np.sqrt(3.0)
    c, e = floating_band_error(f, vt, vm, width=4.0, step=1.0)
    np.testing.assert_array_equal(c, f)
    # band of centre c: lines c-2 .. c+2, clipped at 0 and 10 Hz
    n_lines = np.minimum(c + 2, 10) - np.maximum(c - 2, 0) + 1
    expected = np.where(np.abs(c - 5) <= 2, 2.0 / n_lines, 0.0)
    np.testing.assert_allclose(e, expected, rtol=1e-14)
    assert e[5] == pytest.approx(2 / 5)


def test_resonance_shift_large_near_small_far():
    vt = _sdof(F, 40.0)
    vm = _sdof(F, 42.0)
    c, e = floating_band_error(F, vt, vm)
    near = e[np.abs(c - 41.0) <= 2]
    far = e[c >= 100.0]
    assert near.min() > 0.5
    assert far.max() < 0.05
    assert abs(c[np.argmax(e)] - 41.0) <= 6.0 + 1.0  # within half a band of the peaks


def test_batch_axes_broadcast_like_a_loop():
    rng = np.random.default_rng(1)
    vt = rng.normal(size=(F.size, 3)) + 1j * rng.normal(size=(F.size, 3))
    vm = vt[None] * rng.uniform(0.8, 1.2, size=(4, F.size, 3))
    c, e = floating_band_error(F, vt, vm, width=8.0, step=2.0)
    assert e.shape == (4, c.size, 3)
    for n in range(4):
        for d in range(3):
            np.testing.assert_allclose(
                e[n, :, d], floating_band_error(F, vt[:, d], vm[n, :, d], 8.0, 2.0)[1], rtol=1e-13
            )


def test_width_and_step_are_settable_and_default_to_thesis():
    v = _sdof(F, 40.0)
    c, _ = floating_band_error(F, v, v)
    np.testing.assert_array_equal(c, np.arange(1.0, 200.0))  # 1 Hz steps over the range
    c2, _ = floating_band_error(F, v, v, width=20.0, step=5.0)
    np.testing.assert_array_equal(c2, np.arange(5.0, 200.0, 5.0))


def test_valid_edges_keep_full_bands_only():
    v = _sdof(F, 40.0)
    c, _ = floating_band_error(F, v, 1.1 * v, edges="valid")
    assert c[0] == 7.0 and c[-1] == 193.0  # 1 + 6, 199.5 - 6 rounded down
    assert band_centres([0.0, 10.0], width=12.0, edges="valid").size == 0
    with pytest.raises(fc.FBSError, match="leaves the range"):
        floating_band_error(F, v, v, edges="valid", centres=[3.0])


def test_zero_reference_power():
    f = np.arange(0.0, 10.0)
    vt = np.zeros(f.size)
    _, e0 = floating_band_error(f, vt, vt)
    assert np.all(e0 == 0)
    _, e1 = floating_band_error(f, vt, np.ones(f.size))
    assert np.all(np.isinf(e1))


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(width=0.0), "band width"),
        (dict(step=-1.0), "band step"),
        (dict(edges="wrap"), "allowed: clip, valid"),
        (dict(centres=np.ones((2, 2))), "1-D"),
    ],
)
def test_bad_band_settings_raise(kw, match):
    v = _sdof(F, 40.0)
    with pytest.raises(fc.FBSError, match=match):
        floating_band_error(F, v, v, **kw)


def test_bad_shapes_and_grids_raise():
    v = _sdof(F, 40.0)
    with pytest.raises(fc.DataFormatError, match="frequency first"):
        floating_band_error(F, v[:-1], v[:-1])
    with pytest.raises(fc.DataFormatError, match="broadcast"):
        floating_band_error(F, v, np.ones((F.size, 2)))
    with pytest.raises(fc.FrequencyGridError):
        floating_band_error(F[::-1], v, v)
