"""Residual compensation of a truncated complex-mode tire model (issue 15).

Truth: the all-modes response, which equals the direct inverse of the dynamic stiffness
(closed form) for the small gyroscopic system and the direct solution of the matrices for
the reference tire; for the FRF-fitted residual also the direct solution.
"""

import numpy as np
import pytest

import fbs_core as fc
from fbs_core import harmonic, reference_tire
from fbs_core.studies import truncation_map
from fbs_core.tire import TireModel, complex_modes, track_modes
from fbs_core.tire.residual import fit_residual


def _rotors(omega):
    """Four coupled gyroscopic rotor pairs (8 DOFs, non-reciprocal): M, C, K."""
    w0 = 2 * np.pi * np.array([40.0, 90.0, 160.0, 260.0])
    n = 2 * w0.size
    M, K, G = np.eye(n), np.zeros((n, n)), np.zeros((n, n))
    for i, w in enumerate(w0):
        x, y = 2 * i, 2 * i + 1
        K[x, x] = K[y, y] = w**2 - omega**2
        G[x, y], G[y, x] = -2 * omega, 2 * omega
    for a, b, k in ((0, 2, 2e4), (2, 4, 3e4), (4, 6, 5e4), (1, 5, 1e4)):
        K[[a, b], [a, b]] += k
        K[a, b] -= k
        K[b, a] -= k
    return M, 20.0 * np.eye(n) + G, K


def _small_model():
    spin = np.array([5.0, 7.5, 10.0])  # Hz of spin: the "speeds"
    modes, _ = track_modes([complex_modes(*_rotors(2 * np.pi * F)) for F in spin])
    load = np.linspace(1.0, 2.0, 8)
    return TireModel(
        spin,
        np.array([m.poles for m in modes]),
        np.array([m.psi[:6].T for m in modes]),
        np.array([m.chi[:6].T for m in modes]),
        np.array([harmonic(1).wavelength]),
        np.array([[load @ m.chi] for m in modes]),
    )


def test_small_gyroscopic_system_residual_converges_faster_and_is_exact_with_all_modes():
    tire = _small_model()
    f = np.linspace(5.0, 60.0, 56)  # below the higher modes
    M, C, K = _rotors(2 * np.pi * 7.5)
    w = 2 * np.pi * f
    direct = np.array([1j * x * np.linalg.inv(K - x**2 * M + 1j * x * C)[:6, :6] for x in w])
    full = tire.hub_mobility(f, 7.5).data
    np.testing.assert_allclose(full, direct, rtol=1e-9, atol=1e-12 * np.abs(direct).max())
    nonrec = np.abs(direct - np.swapaxes(direct, 1, 2)).max() / np.abs(direct).max()
    assert nonrec > 1e-2  # gyroscopic: not reciprocal, the residuals are not symmetric
    err_plain, err_res = [], []
    for n in (10, 12, 14):
        plain = tire.hub_mobility(f, 7.5, n_modes=n).data
        comp = tire.hub_mobility(f, 7.5, n_modes=n, residual=True).data
        err_plain.append(np.abs(plain - direct).max() / np.abs(direct).max())
        err_res.append(np.abs(comp - direct).max() / np.abs(direct).max())
    # 4x closer with 5 of 8 pairs kept (the first mode left out is at 171 Hz, the band
    # ends at 60 Hz), 15x and more with 6 and 7
    assert err_res[0] < 0.3 * err_plain[0]
    assert all(r < 0.1 * p for r, p in zip(err_res[1:], err_plain[1:], strict=True))
    comp = tire.hub_mobility(f, 7.5, n_modes=16, residual=True).data
    np.testing.assert_allclose(comp, full, rtol=1e-9, atol=1e-12 * np.abs(full).max())


def test_reference_tire_truncation_with_residual_converges_faster():
    """Case 5, 6 DOFs: once the modes left out lie well above the band (N = 160), the
    eq. 5.1 error up to 160 Hz is several times smaller when they enter with their
    residual flexibility, and 0 with all modes. (With modes left out inside the
    band their static part is no substitute: it can be worse, see docs/tire-model.md.)"""
    ns = [20, 40, 80, 160, 400]
    plain = truncation_map(5, ns, df=1.0)
    res = truncation_map(5, ns, df=1.0, residual=True)
    below = plain.centres <= 160.0
    e_p = plain.max_error[:, below].max(axis=1)
    e_r = res.max_error[:, below].max(axis=1)
    assert e_r[3] < 0.25 * e_p[3]
    assert e_r[-1] == 0.0 and e_p[-1] == 0.0
    np.testing.assert_allclose(res.reference, plain.reference)


def test_residual_fitted_from_frfs_matches_the_modal_one():
    """A car maker with measured FRFs of the full tire and the delivered N modes fits
    constant + 1/omega^2 over a band; the fitted constant compensates like the modal
    residual and brings the truncated response close to the direct solution."""
    tire = _small_model()
    f = np.linspace(5.0, 60.0, 56)
    v = 7.5
    M, C, K = _rotors(2 * np.pi * v)
    w = 2 * np.pi * f
    H_true = np.array([np.linalg.inv(K - x**2 * M + 1j * x * C)[:6, :6] for x in w])
    n = 10
    H_trunc = tire.hub_mobility(f, v, n_modes=n).data / (1j * w[:, None, None])
    A, B = fit_residual(f, H_true, H_trunc)
    assert A.shape == (6, 6) and B.shape == (6, 6)
    comp = H_trunc + A[None] + B[None] / w[:, None, None] ** 2
    H_mod = tire.hub_mobility(f, v, n_modes=n, residual=True).data / (1j * w[:, None, None])
    e_fit = np.abs(comp - H_true).max() / np.abs(H_true).max()
    e_mod = np.abs(H_mod - H_true).max() / np.abs(H_true).max()
    e_plain = np.abs(H_trunc - H_true).max() / np.abs(H_true).max()
    assert e_fit < 0.25 * e_plain and e_fit < 2 * e_mod + 1e-3
    with pytest.raises(ValueError, match="shape"):
        fit_residual(f, H_true, H_trunc[:-1])


def test_truncated_delivery_with_residual_is_stored_and_compensates(tmp_path):
    """A supplier delivers the first 120 of 400 modes plus the residual of the others
    (file format 2, optional /residual); the compensated synthesis is closer to the full
    model than the plain truncated one, and version-1 files still load."""
    import h5py

    from fbs_core.tire import read_tire_h5, save_tire_model

    tire = reference_tire()
    small = tire.subset(range(60))
    assert small.n_modes == 120 and small.residual.shape == (tire.speeds.size, 36 + 6 * 7)
    back = read_tire_h5(save_tire_model(small, tmp_path / "t.h5"))
    np.testing.assert_array_equal(back.residual, small.residual)
    f = np.linspace(10.0, 120.0, 23)
    v = 61.3
    full = tire.hub_mobility(f, v).data
    plain = back.hub_mobility(f, v).data
    comp = back.hub_mobility(f, v, residual=True).data
    e_plain = np.abs(plain - full).max() / np.abs(full).max()
    e_comp = np.abs(comp - full).max() / np.abs(full).max()
    assert e_comp < 0.5 * e_plain
    h = harmonic(3)
    fh = h.frequencies(2.0)
    vf = tire.patch_response(fh, h).data
    vc = back.patch_response(fh, h, residual=True).data
    vp = back.patch_response(fh, h).data
    assert np.linalg.norm(vc - vf) < np.linalg.norm(vp - vf)
    # a format-1 file (no residual) still loads
    bare = TireModel(
        tire.speeds, tire.poles, tire.psi, tire.chi, tire.wavelengths, tire.participation
    )
    old = save_tire_model(bare, tmp_path / "v1.h5")
    with h5py.File(old, "a") as fh5:
        fh5.attrs["format_version"] = 1
    m1 = read_tire_h5(old)
    assert m1.residual is None and m1.n_modes == 400
    with pytest.raises(ValueError, match="residual has shape"):
        TireModel(
            small.speeds,
            small.poles,
            small.psi,
            small.chi,
            small.wavelengths,
            small.participation,
            residual=small.residual[:, :36],
        )


@pytest.mark.parametrize("k", [5, 7])
def test_one_mode_count_with_residuals_equals_its_row_of_the_whole_study(k):
    """A single N with residuals (what bushing_response asks for) is the same sum as that
    N's row when all counts are computed at once (the study's path), and finite: the
    zero poles of the tread-slip states have no static part on either path."""
    tire = fc.reference_tire()
    f = fc.harmonic(k).frequencies()
    counts = list(range(10, tire.n_modes + 1, 10))
    Y_all, v_all = tire.truncations(f, k, counts, residual=True)
    for n in (60, 200):
        Y, v = tire.truncations(f, k, [n], residual=True)
        assert np.all(np.isfinite(Y)) and np.all(np.isfinite(v))
        row = counts.index(n)
        np.testing.assert_allclose(Y[0], Y_all[row], rtol=0, atol=1e-11 * np.abs(Y_all[row]).max())
        np.testing.assert_allclose(v[0], v_all[row], rtol=0, atol=1e-11 * np.abs(v_all[row]).max())
    assert np.all(np.isfinite(fc.bushing_response(k, n_modes=60, residual=True).data))
