"""Every frequency line at its own speed (issue 13): the interpolated modal tire against
the physics at the exact speed of every line.

Truth: the tire's own matrices at ``v = 3.6 f lambda`` assembled with the chassis' FE
matrices and solved directly (no modes, no interpolation, no FBS). Tracking across a
crossing is checked on a small gyroscopic system with closed-form eigenfrequencies.
"""

import numpy as np
import pytest

from fbs_core import assemble, bushing_response, harmonic, reference_chassis, reference_tire
from fbs_core.chassis import BUSHING
from fbs_core.prediction import coupled_dofs, direct_bushing_response
from fbs_core.tire import TireModel, complex_modes, track_modes
from fbs_core.tire.quality import level_errors


def _lines(k: int) -> np.ndarray:
    """A dozen lines across the band plus the lines where the former 20 km/h model was
    worst (issue 13), where cubic weights without clusters miss by 2 dB, and where the
    2.5 km/h points without refinement missed by 3.5 dB (case 7, 116.3 km/h)."""
    h = harmonic(k)
    lo, hi = h.freq_range
    extra = {
        4: [110.0 / 3.6 / h.wavelength],
        5: [90.0 / 3.6 / h.wavelength],
        7: [232.0, 236.0, 238.5, 239.5, 240.0, 241.0, 409.0, 409.5, 410.0],
    }.get(k, [])
    f = np.r_[np.linspace(lo * 1.001, hi * 0.999, 12), extra]
    return np.unique(np.round(f, 3))


def test_direct_truth_equals_primal_assembly():
    """The block-eliminated direct solution equals fbs_core.direct.assemble + solve."""
    tire, ch = reference_tire(), reference_chassis()
    h = harmonic(5)
    for coupling in ("6dof", "5dof"):
        f = np.array([80.0, 155.5])
        d = direct_bushing_response(h, f, coupling).data
        for i, fi in enumerate(f):
            v = h.speed_at(fi)
            ts = tire.system(v)
            joined = [
                (f"tire/{x}", f"chassis/spindle:{x.split(':')[1]}") for x in coupled_dofs(coupling)
            ]
            S = assemble({"tire": ts, "chassis": ch.system()}, joined)
            pos = {x: j for j, x in enumerate(S.dofs)}
            load = np.zeros(S.n, complex)
            load[[pos[f"tire/{x}"] for x in ts.dofs]] = tire.patch_load(v, h.wavelength)
            ref = S.frf([fi], [f"chassis/{b}" for b in BUSHING], [], loads={"p": load}).data
            np.testing.assert_allclose(d[i], ref[0], rtol=1e-8, atol=1e-12 * np.abs(ref).max())


@pytest.mark.parametrize("coupling", ["6dof", "5dof"])
def test_shipped_prediction_follows_the_physics_between_operating_points(coupling):
    """< 1 dB where the level is within 30 dB of the DOF's peak, < 3 dB anywhere above the
    floor, at lines between the operating points of all seven harmonics."""
    for k in range(1, 8):
        f = _lines(k)
        true = direct_bushing_response(k, f, coupling).data[:, :, 0]
        pred = bushing_response(k, freq=f, coupling=coupling).data[:, :, 0]
        e = level_errors(pred, true)
        assert e.near_peak < 1.0, (k, e)
        assert e.anywhere < 3.0, (k, e)


def _rotor_pairs(omega, kc=0.0):
    """Three isotropic rotors in a rotating frame: eigenfrequencies sqrt(k_i) +/- Omega
    (closed form for kc = 0); kc couples x1 and x2 (a veering instead of a crossing)."""
    w0 = 2 * np.pi * np.array([100.0, 130.0, 170.0])
    M, K, G = np.eye(6), np.zeros((6, 6)), np.zeros((6, 6))
    for i, w in enumerate(w0):
        x, y = 2 * i, 2 * i + 1
        K[x, x] = K[y, y] = w**2 - omega**2
        G[x, y], G[y, x] = -2 * omega, 2 * omega
    K[0, 0] += kc
    K[2, 2] += kc
    K[0, 2] -= kc
    K[2, 0] -= kc
    return M, 30.0 * np.eye(6) + G, K, w0 / (2 * np.pi)


def test_tracking_follows_branches_through_a_crossing():
    """Forward branch of rotor 1 (100 + F Hz) crosses the backward branch of rotor 2
    (130 - F Hz) at F = 15 Hz: every tracked mode stays on one closed-form branch."""
    spin = np.array([2.0, 6.0, 10.0, 13.0, 14.5, 15.5, 17.0, 20.0, 24.0])  # Hz
    modes = [complex_modes(*_rotor_pairs(2 * np.pi * F)[:3]) for F in spin]
    tracked, _ = track_modes(modes)
    f0 = _rotor_pairs(0.0)[3]
    branches = np.array([[a + sg * F for a in f0 for sg in (-1, 1)] for F in spin])  # (n_s, 6)
    fr = np.array([m.frequencies for m in tracked])  # (n_s, 6)
    for r in range(6):
        d = np.abs(fr[:, r, None] - branches)  # (n_s, 6): distance to every branch
        b = np.argmin(d[0])
        assert np.all(d[:, b] < 0.05), (r, fr[:, r], branches[:, b])
    # without the frequency term MAC alone pairs them; both members of a crossing kept
    assert np.any(np.diff(np.sign(fr[:, 1] - fr[:, 2])) != 0) or np.any(
        np.diff(np.argsort(fr, axis=1), axis=0) != 0
    )


def test_interpolation_on_a_veering_pair():
    """Coupled rotors veer near 115-125 Hz. A model delivered every 2.5 Hz of spin
    interpolates the hub mobility between its points within 1 % of the direct solution
    (cubic in speed), several times closer than plain linear weights, and exactly at them."""
    spin = np.arange(8.0, 23.0, 2.5)  # the "speeds": spin in Hz
    kc = 1e5
    modes = [complex_modes(*_rotor_pairs(2 * np.pi * F, kc)[:3]) for F in spin]
    tracked, _ = track_modes(modes)
    load = np.linspace(1.0, 2.0, 6)
    data = (
        spin,
        np.array([m.poles for m in tracked]),
        np.array([m.psi.T for m in tracked]),
        np.array([m.chi.T for m in tracked]),
        np.array([harmonic(1).wavelength]),
        np.array([[load @ m.chi] for m in tracked]),
    )
    cubic, linear = TireModel(*data), TireModel(*data, interpolation="linear")
    f = np.linspace(90.0, 150.0, 121)
    w = 2 * np.pi * f
    for F in (spin[2], 13.7, 14.9, 16.2):
        M, C, K, _ = _rotor_pairs(2 * np.pi * F, kc)
        D = np.array([1j * x * np.linalg.inv(K - x**2 * M + 1j * x * C) for x in w])
        e_cub = np.abs(cubic.hub_mobility(f, F).data - D).max() / np.abs(D).max()
        e_lin = np.abs(linear.hub_mobility(f, F).data - D).max() / np.abs(D).max()
        if F == spin[2]:
            assert e_cub < 1e-9 and e_lin < 1e-9
        else:
            assert e_cub < 0.01 and e_lin > 3 * e_cub, (F, e_cub, e_lin)


def test_leave_one_out_estimate_flags_a_coarse_model():
    """The data-only estimate is small for the shipped model and grows when every other
    operating point is dropped (twice the spacing), where the direct solution confirms
    that the interpolation is worse."""
    from fbs_core.tire.quality import interpolation_quality

    tire = reference_tire()
    idx = np.flatnonzero((tire.speeds >= 55.0) & (tire.speeds <= 80.0))
    part = TireModel(
        tire.speeds[idx],
        tire.poles[idx],
        tire.psi[idx],
        tire.chi[idx],
        tire.wavelengths,
        tire.participation[idx],
    )
    fine = interpolation_quality(part, harmonics=(7,))
    coarse_idx = idx[::2]
    coarse = TireModel(
        tire.speeds[coarse_idx],
        tire.poles[coarse_idx],
        tire.psi[coarse_idx],
        tire.chi[coarse_idx],
        tire.wavelengths,
        tire.participation[coarse_idx],
    )
    rough = interpolation_quality(coarse, harmonics=(7,))
    assert fine.worst_db[0] < rough.worst_db[0]
    assert fine.to_dict()["worst_db"]["7"] == round(float(fine.worst_db[0]), 3)
    # the true error of the coarse model at a left-out speed, from the matrices
    h = harmonic(7)
    v = float(tire.speeds[idx[1]])
    f = np.array([v / 3.6 / h.wavelength])
    s = tire.system(v)
    true = s.frf(f, s.dofs[:6], [], loads={"p": tire.patch_load(v, h.wavelength)}).data
    pc = coarse.patch_response(f, h, speed_kmh=v).data
    pf = tire.patch_response(f, h, speed_kmh=v).data
    assert np.linalg.norm(pf - true) < np.linalg.norm(pc - true)


def test_speed_coverage_warns_outside_the_operating_points():
    from fbs_core.tire import OperatingPointError
    from fbs_core.tire.quality import SpeedRangeWarning, speed_coverage

    tire = reference_tire()
    idx = np.flatnonzero((tire.speeds >= 40.0) & (tire.speeds <= 100.0))
    part = TireModel(
        tire.speeds[idx],
        tire.poles[idx],
        tire.psi[idx],
        tire.chi[idx],
        tire.wavelengths,
        tire.participation[idx],
    )
    h = harmonic(3)
    with pytest.warns(SpeedRangeWarning, match="covers 40-100 km/h"):
        lo, hi = speed_coverage(part, h)
    assert lo == pytest.approx(40.0 / 3.6 / h.wavelength)
    assert hi == pytest.approx(100.0 / 3.6 / h.wavelength)
    with pytest.raises(OperatingPointError):
        part.patch_response(h.frequencies(), h)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert speed_coverage(tire, h) == pytest.approx(h.freq_range)


def test_refinement_adds_points_where_the_interpolation_misses_the_physics():
    """``build_modal_model(refine_tol=...)`` halves exactly the intervals whose interpolated
    model misses the direct solution by more than the tolerance; at the operating points
    the check itself is exact (all-modes synthesis = direct solution of the matrices)."""
    from fbs_core.tire.build import build_modal_model, interval_errors

    params = reference_tire().params
    coarse = build_modal_model(params, speeds=(100.0, 110.0, 120.0))
    assert np.all(interval_errors(coarse, fractions=(0.0, 1.0)) < 1e-6)
    err = interval_errors(coarse)
    assert err.max() > 0.01  # 10 km/h steps at high speed: too coarse
    fine = build_modal_model(params, speeds=(100.0, 110.0, 120.0), refine_tol=0.01, min_step=5.0)
    want = [v for v, e in zip((105.0, 115.0), err, strict=True) if e > 0.01]
    assert fine.meta["refinement"]["added_kmh"] == want
    np.testing.assert_array_equal(fine.speeds, sorted({100.0, 110.0, 120.0, *want}))
    new = interval_errors(fine)
    assert new.max() < err.max()
