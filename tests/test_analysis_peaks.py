"""Peak labels, phase views and delta cursors against closed forms of oscillators.

SDOF ``m x'' + c x' + k x = F``: the mobility ``j w / (k - m w^2 + j w c)`` peaks
exactly at ``w_n = sqrt(k/m)`` with ``|Y| = 1/c``; the receptance peaks at
``w_n sqrt(1 - 2 zeta^2)`` with ``|H| = 1 / (2 zeta sqrt(1 - zeta^2) k)``; its phase
is -90 degrees at ``w_n``. The eigenvalues are ``-zeta w_n +- j w_n sqrt(1 - zeta^2)``.
"""

import numpy as np
import pytest

from fbs_core import FRF, SecondOrderSystem, reference_tire
from fbs_core.analysis import (
    bode,
    coupled_modes_near,
    coupled_system,
    delta_cursor,
    find_peaks_db,
    parabolic_vertex,
    peak_labels,
    real_imag,
    system_modes_near,
)
from fbs_core.errors import DOFError, FBSError, FrequencyGridError

M1, K1, ZETA = 2.0, 2.0 * (2 * np.pi * 37.3) ** 2, 0.02
C1 = 2 * ZETA * np.sqrt(K1 * M1)
FN = np.sqrt(K1 / M1) / (2 * np.pi)


def sdof(f, quantity="mobility"):
    w = 2 * np.pi * np.asarray(f)
    h = 1.0 / (K1 - M1 * w**2 + 1j * w * C1)
    p = {"receptance": 0, "mobility": 1}[quantity]
    return FRF(f, (h * (1j * w) ** p)[:, None, None], ["m:x"], ["m:x"], quantity)


def test_parabolic_vertex_exact_on_a_parabola():
    x = np.array([1.0, 1.7, 3.1])
    y = -2.0 * (x - 1.9) ** 2 + 5.0
    xv, yv = parabolic_vertex(x, y)
    assert xv == pytest.approx(1.9, abs=1e-12) and yv == pytest.approx(5.0, abs=1e-12)
    assert parabolic_vertex([0, 1, 2], [0, 1, 2]) == (1.0, 1.0)  # no curvature: middle


@pytest.mark.parametrize("offset", np.linspace(0.0, 0.95, 7))
def test_sdof_mobility_peak_interpolated_between_lines(offset):
    """1 Hz grid, half-power bandwidth 1.5 Hz: the interpolated peak is far nearer the
    exact f_n, 1/c than the grid line."""
    f = np.arange(20.0, 60.0, 1.0) + offset
    lv = 20 * np.log10(np.abs(sdof(f).data[:, 0, 0]))
    exact_db = 20 * np.log10(1 / C1)
    fp, lp, idx, _ = find_peaks_db(f, lv)
    assert fp.size == 1
    assert abs(fp[0] - FN) < 0.02 and abs(lp[0] - exact_db) < 0.1
    fd, ld, _, _ = find_peaks_db(f, lv, method="db")
    assert abs(fd[0] - FN) < 0.1 and abs(ld[0] - exact_db) < 1.0
    assert abs(fd[0] - FN) <= abs(f[idx[0]] - FN) + 1e-12
    assert lv[idx[0]] <= ld[0] <= exact_db + 1e-9


def _worst_sdof_error(fn, method="inverse_power"):
    """Worst peak error over 101 offsets of a 1 Hz grid, SDOF mobility, 1.5 Hz bandwidth."""
    zeta = 0.75 / fn
    m, k = 2.0, 2.0 * (2 * np.pi * fn) ** 2
    c = 2 * zeta * np.sqrt(k * m)
    worst = np.zeros(2)
    for off in np.linspace(0.0, 1.0, 101):
        f = np.arange(fn - 15.0, fn + 15.0, 1.0) + off
        w = 2 * np.pi * f
        lv = 20 * np.log10(np.abs(1j * w / (k - m * w**2 + 1j * w * c)))
        fp, lp, _, _ = find_peaks_db(f, lv, method=method)
        worst = np.maximum(worst, [abs(fp[0] - fn), abs(lp[0] - 20 * np.log10(1 / c))])
    return worst


def test_sdof_peak_accuracy_grows_with_the_relative_bandwidth():
    """The figures of docs/analysis.md: the parabola through -1/|H|^2 is exact in the
    limit of a narrow peak; its error grows with bandwidth / frequency."""
    e25, e37, e100 = (_worst_sdof_error(fn) for fn in (25.0, 37.3, 100.0))
    assert e37[0] < 0.014 and e37[1] < 0.085
    assert e25[0] < 0.021 and e25[1] < 0.13
    assert e100[0] < 0.0051 and e100[1] < 0.031
    assert np.all(e25 > e37) and np.all(e37 > e100)
    e_db = _worst_sdof_error(37.3, "db")
    assert 0.08 < e_db[0] < 0.09 and 0.9 < e_db[1] < 0.95


def test_sdof_receptance_peak_and_phase():
    f = np.arange(20.0, 60.0, 0.5)
    H = sdof(f, "receptance")
    P = peak_labels(H)
    assert len(P) == 1
    assert P[0].freq == pytest.approx(FN * np.sqrt(1 - 2 * ZETA**2), abs=0.02)
    peak = 1 / (2 * ZETA * np.sqrt(1 - ZETA**2) * K1)
    assert P[0].level_db == pytest.approx(20 * np.log10(peak), abs=0.05)
    b = bode(H)
    # phase -90 degrees at f_n (interpolated), 0 below, -180 above
    assert np.interp(FN, f, b.phase_deg[:, 0, 0]) == pytest.approx(-90, abs=1.0)
    assert b.phase_deg[0, 0, 0] > -10 and b.phase_deg[-1, 0, 0] < -170
    re, im = real_imag(H)
    np.testing.assert_allclose(re + 1j * im, H.data)
    assert np.all(im <= 0)  # a passive receptance has a negative imaginary part


def test_unwrapped_phase_of_a_two_mass_transfer_reaches_minus_360():
    """x2 / F1 of the chain ground-k-m1-k-m2: phase 0 -> -180 -> -360 (two poles)."""
    m, k, c = 1.0, 1e4, 2.0
    f = np.linspace(1.0, 60.0, 600)
    w = 2 * np.pi * f
    Z = np.zeros((f.size, 2, 2), complex)
    Z[:, 0, 0] = 2 * k - m * w**2 + 2j * w * c
    Z[:, 1, 1] = k - m * w**2 + 1j * w * c
    Z[:, 0, 1] = Z[:, 1, 0] = -k - 1j * w * c
    H = FRF(f, np.linalg.inv(Z), ["a:x", "b:x"], ["a:x", "b:x"], "receptance")
    ph = bode(H).phase_deg[:, 1, 0]
    assert ph[0] == pytest.approx(0, abs=1) and ph[-1] == pytest.approx(-360, abs=10)
    assert np.all(np.abs(np.diff(ph)) < 90)  # continuous
    wrapped = bode(H, unwrap=False).phase_deg[:, 1, 0]
    assert np.all((wrapped > -180) & (wrapped <= 180))
    # two peaks at the closed-form eigenfrequencies of the chain
    w2 = np.sort(np.linalg.eigvals(np.array([[2 * k, -k], [-k, k]]) / m).real)
    P = peak_labels(H, "a:x", "a:x", prominence_db=3)
    np.testing.assert_allclose([p.freq for p in P], np.sqrt(w2) / 2 / np.pi, rtol=3e-3)


def test_delta_cursor_on_the_sdof():
    f = np.arange(10.0, 80.0, 0.25)
    Y = sdof(f)
    d = delta_cursor(Y, FN, 2 * FN)
    exact = lambda x: 20 * np.log10(np.abs(sdof(np.array([x])).data[0, 0, 0]))  # noqa: E731
    assert d.df == pytest.approx(FN)
    assert d.ratio == pytest.approx(2.0)
    assert d.level2 == pytest.approx(exact(2 * FN), abs=0.01)  # smooth there
    assert d.level1 == pytest.approx(exact(FN), abs=0.3)  # linear between lines at the peak
    assert d.d_db == pytest.approx(d.level2 - d.level1)
    with pytest.raises(FrequencyGridError, match="never extrapolated"):
        delta_cursor(Y, 5.0, 20.0)
    two = FRF(f, np.ones((f.size, 2, 1)), ["a:x", "b:x"], ["a:x"])
    with pytest.raises(DOFError, match="name one of"):
        delta_cursor(two, 20.0, 30.0)
    with pytest.raises(DOFError, match="available"):
        delta_cursor(two, 20.0, 30.0, output="c:x")


def test_find_peaks_prominence_and_bad_input():
    f = np.arange(1.0, 100.0)
    y = np.sin(f / 3.0) * 10 + 0.3 * np.sin(3 * f)  # ripple below 3 dB
    fp, *_ = find_peaks_db(f, y, prominence_db=3.0)
    assert fp.size == 5  # the five big maxima only
    fp2, *_ = find_peaks_db(f, y, prominence_db=3.0, max_peaks=2)
    assert fp2.size == 2 and np.all(np.diff(fp2) > 0)
    with pytest.raises(FBSError, match="prominence"):
        find_peaks_db(f, y, prominence_db=-1)
    with pytest.raises(FBSError, match="allowed: inverse_power, db"):
        find_peaks_db(f, y, method="cubic")
    with pytest.raises(FBSError, match="equal length"):
        find_peaks_db(f, y[:-1])


def test_modes_near_sdof_and_proportional_2dof():
    s = SecondOrderSystem([[M1]], [[C1]], [[K1]], ["m:x"])
    (m,) = system_modes_near(s, 30.0, 1)
    wn = np.sqrt(K1 / M1)
    assert m.pole == pytest.approx(complex(-ZETA * wn, wn * np.sqrt(1 - ZETA**2)), rel=1e-10)
    assert m.damping == pytest.approx(ZETA, rel=1e-10)
    M = np.diag([1.0, 2.0])
    K = np.array([[3e4, -1e4], [-1e4, 1e4]])
    a, b = 0.5, 2e-5
    two = SecondOrderSystem(M, a * M + b * K, K, ["a:x", "b:x"])
    wr = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real))
    zr = a / (2 * wr) + b * wr / 2
    modes = system_modes_near(two, 1.0, 2)  # nearest first: the lower one
    poles = np.array([md.pole for md in modes])
    np.testing.assert_allclose(poles, -zr * wr + 1j * wr * np.sqrt(1 - zr**2), rtol=1e-10)
    with pytest.raises(FBSError, match="positive"):
        system_modes_near(two, 0.0)
    with pytest.raises(FBSError, match="at least 1"):
        system_modes_near(two, 10.0, 0)


def test_tire_modes_by_shift_invert_match_the_modal_model():
    """The sparse shift-invert path (400 states) against the tire's stored modes (dense
    complex_modes at the operating point)."""
    tire = reference_tire()
    fr = tire.eigenfrequencies(60.0)
    target = fr[(fr > 90) & (fr < 110)]
    got = system_modes_near(tire.system(60.0), 100.0, target.size)
    np.testing.assert_allclose(np.sort([m.freq for m in got]), target, rtol=1e-8)


def test_coupled_modes_are_eigenvalues_of_the_assembled_system():
    S = coupled_system(60.0, "6dof")
    modes = coupled_modes_near(38.0, 60.0, "6dof", 3)
    assert len(modes) == 3
    M, C, K = (getattr(S, k).toarray() for k in "MCK")
    for m in modes:
        lam = m.pole
        s = np.linalg.svd(lam**2 * M + lam * C + K, compute_uv=False)
        assert s[-1] / s[0] < 1e-10
        assert 20 < m.freq < 60


def test_peak_labels_speed_and_errors():
    f = np.arange(20.0, 60.0, 0.5)
    (p,) = peak_labels(sdof(f), harmonic=1)
    assert p.speed_kmh == pytest.approx(3.6 * p.freq * 0.646)
    (q,) = peak_labels(sdof(f), speed_kmh=80.0)
    assert q.speed_kmh == 80.0 and "Hz" in q.label()
    with pytest.raises(FBSError, match="not both"):
        peak_labels(sdof(f), harmonic=1, speed_kmh=80.0)
    with pytest.raises(FBSError, match="speed"):
        peak_labels(sdof(f), n_nearby=2)
