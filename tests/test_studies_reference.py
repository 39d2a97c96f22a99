"""The studies on the shipped reference tire and chassis (thesis chapter 5)."""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core as fc


@pytest.fixture(scope="module")
def table():
    return fc.suggest_modes(0.2, 160.0)


def test_map_of_harmonic_1_is_zero_with_all_modes_and_falls_with_n(table):
    m = table.maps[0]
    assert m.harmonic == 1
    np.testing.assert_array_equal(m.n_modes, np.arange(10, 401, 10))
    assert m.n_modes_total == 400
    assert m.error.shape == (40, m.centres.size, 6)
    assert m.dofs == tuple(f"bushing:{d}" for d in fc.DIRECTIONS)
    assert np.all(m.error[-1] == 0.0)
    worst = m.max_error.max(axis=1)
    # falls by orders of magnitude from 10 to 100 modes, then stays small
    assert worst[0] > 1.0 and worst[9] < 0.02 and worst[19:].max() < 0.01
    assert worst[0] > worst[2] > worst[4] > worst[9]
    assert m.centres[0] >= m.freq[0] and m.centres[-1] <= m.freq[-1]


def test_suggested_modes_table_and_monotone_in_threshold(table):
    assert table.harmonics == (1, 2, 3, 4, 5, 6, 7)
    assert np.all(table.n_modes >= 10) and np.all(table.n_modes <= 400)
    assert np.all(table.eigenfrequency > 0)
    prev = None
    for thr in (0.02, 0.05, 0.1, 0.2, 0.5, 1.0):
        s = fc.suggest_modes(thr, 160.0, maps=table.maps)
        if prev is not None:
            assert np.all(s.n_modes <= prev)
        prev = s.n_modes
    # a lower upper frequency never needs more modes
    s130 = fc.suggest_modes(0.2, 130.0, maps=table.maps)
    assert np.all(s130.n_modes <= table.n_modes)
    # the highest retained eigenfrequency at 80 km/h, from the tire's own poles
    tire = fc.reference_tire()
    for n, ef in zip(table.n_modes, table.eigenfrequency, strict=True):
        p = tire.poles_at(80.0)[:n]
        assert ef == pytest.approx(np.abs(p.imag).max() / (2 * np.pi))


def test_mode_frequencies_rise_with_mode_count():
    mf = fc.studies.mode_frequencies()
    np.testing.assert_array_equal(mf.speeds, [20.0, 80.0, 120.0])
    assert mf.frequency.shape == (3, 40)
    assert np.all(np.diff(mf.frequency, axis=1) >= 0)
    eig80 = fc.reference_tire().eigenfrequencies(80.0)
    assert mf.frequency[1, -1] == pytest.approx(eig80.max())


def test_scatter_band_on_reference_models():
    b0 = fc.scatter_band(4, noise=0.0, rounds=8, frequency_dependent=True)
    mag = np.sqrt(b0.reference.real**2 + b0.reference.imag**2)
    np.testing.assert_array_equal(b0.maximum, mag)
    np.testing.assert_array_equal(b0.minimum, mag)
    # the reference is eq. 4.1 through the labelled coupling API (second method)
    h = fc.harmonic(4)
    f = h.frequencies()
    tire = fc.reference_tire()
    Y, v = tire.truncations(f, h, [400])
    hub = list(tire.hub_dofs)
    C = fc.reference_chassis().mobility(f)
    spindle = [f"spindle:{d}" for d in fc.DIRECTIONS]
    r = fc.coupling.couple_response(
        C.sel(outputs=[f"bushing:{d}" for d in fc.DIRECTIONS]),
        fc.FRF(f, Y[0], hub, hub),
        C.sel(outputs=spindle),
        fc.FRF(f, v[0][..., None], hub, ["patch"]),
        interface=list(zip(hub, spindle, strict=True)),
    )
    np.testing.assert_allclose(b0.reference, r.data[..., 0], rtol=1e-9)
    b = fc.scatter_band(4, noise=0.1, rounds=500, frequency_dependent=True, seed=1)
    assert np.all(b.minimum <= mag) and np.all(mag <= b.maximum)
    assert b.percentiles.shape == (2, f.size, 6)
    assert np.all(b.minimum <= b.percentiles[0]) and np.all(b.percentiles[1] <= b.maximum)
    r = b.peak_round(42.0, "bushing:z")
    line = int(np.argmin(np.abs(f - 42.0)))
    z = b.round(r)[line, 2]
    assert np.sqrt(z.real**2 + z.imag**2) == b.maximum[line, 2]


def test_five_dof_coupling_changes_the_prediction():
    m6 = fc.truncation_map(1, [10, 400])
    m5 = fc.truncation_map(1, [10, 400], coupling="5dof")
    assert not np.allclose(m6.reference, m5.reference)
    assert np.all(m5.error[-1] == 0.0)
