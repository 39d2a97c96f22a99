"""The physical reference tire: matrices, complex modes and plausibility targets.

Truth from physics: the rotating ring's closed form (Huang & Soedel 1987;
reference-models.md sec. 2.1), rigid-body motions free of strain energy, the
direct solution of the matrices, the reciprocity rule Y(Omega)^T = Y(-Omega)
(sec. 2.4), and the targets of the thesis' tire (sec. 2.3).
"""

from functools import lru_cache

import numpy as np
import pytest
import scipy.linalg as sla

from fbs_core.tire import (
    DEFAULT_PARAMETERS,
    HUB_DOFS,
    ModalError,
    TireParameters,
    build_tire_system,
    complex_modes,
    patch_load,
    reference_tire,
    ring_closed_form,
    system_matrices,
)
from fbs_core.tire.modes import receptance
from fbs_core.tire.ring import belt_labels


@lru_cache(maxsize=8)
def system_and_modes(speed):
    """The tire at ``speed`` and its complex modes (computed once per test session)."""
    s = build_tire_system(speed)
    return s, complex_modes(s.M, s.C, s.K)


RING_ONLY = TireParameters(
    orders=(10, -1, -1, -1, -1, -1, -1, -1), k_cx=0, k_cy=0, k_cz=0, slip_zones=0
)
#: the tire with its tread sticking to the road (no slip states): every mode has zeta
STICK = TireParameters(slip_zones=0)


def state_frequencies(M, C, K):
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam = np.linalg.eigvals(A)
    return np.sort(lam.imag[lam.imag > 0]) / (2 * np.pi)


@pytest.mark.parametrize("speed", [0.0, 40.0, 100.0, 120.0])
def test_ring_reproduces_closed_form(speed):
    """Rim fixed, no contact, in-plane ring only: every order n = 0..10 exactly."""
    M, D, G, K = system_matrices(speed, RING_ONLY)
    b = slice(6, None)  # clamp the hub
    f = state_frequencies(M[b, b], G[b, b], K[b, b])
    expected = [ring_closed_form(0, speed, RING_ONLY)[0]]
    for n in range(1, 11):
        expected += list(ring_closed_form(n, speed, RING_ONLY))
    np.testing.assert_allclose(f, np.sort(expected), rtol=1e-9)


def test_closed_form_split_tends_to_doppler():
    p = DEFAULT_PARAMETERS
    om = 100 / 3.6 / p.R
    fp, fm = ring_closed_form(8, 100.0)
    split = 2 * om * 8 * (64 - 1) / (64 + 1) / (2 * np.pi)
    assert fp - fm == pytest.approx(split, rel=0.05)


@pytest.mark.parametrize("speed", [60.0, 100.0])
def test_full_model_forward_backward_split(speed):
    """In the full tire the ring-dominated modes of orders 4..8 split like the ring."""
    s, md = system_and_modes(speed)
    labels = belt_labels()
    fam = np.array([lab.split(".")[1] for lab in labels])
    order = np.array([int(lab.split(".")[2][1:3]) for lab in labels])
    psi = md.psi[:, 0::2]
    e = np.abs(psi) ** 2 * np.diag(s.M)[:, None]
    e /= e.sum(0)
    for n in range(4, 9):
        share = e[6 : 6 + len(labels)][(fam == "ip") & (order == n)].sum(0)
        cf_plus, cf_minus = ring_closed_form(n, speed)
        mid = 0.5 * (cf_plus + cf_minus)
        hi = md.frequencies > mid
        f_plus = md.frequencies[hi][np.argmax(share[hi])]
        f_minus = md.frequencies[~hi][np.argmax(share[~hi])]
        assert f_plus - f_minus == pytest.approx(cf_plus - cf_minus, rel=0.1), n
        assert f_plus == pytest.approx(cf_plus, rel=0.12)
        assert f_minus == pytest.approx(cf_minus, rel=0.12)


def test_rigid_body_motions_cost_no_energy():
    """Without road contact the whole tire has exactly 6 zero-frequency modes."""
    free = TireParameters(k_cx=0, k_cy=0, k_cz=0, slip_zones=0)
    M, _, _, K = system_matrices(0.0, free)
    w2 = sla.eigh(K, M, eigvals_only=True)
    assert np.all(np.abs(w2[:6]) < 1e-6 * w2[6])
    assert np.sqrt(w2[6]) / (2 * np.pi) > 1.0


def test_matrix_structure():
    M, D, G, K = system_matrices(80.0)
    p = DEFAULT_PARAMETERS
    n = 6 + p.n_belt + p.n_slip
    assert M.shape == (n, n) == (202, 202)  # 198 DOFs with mass, 4 first-order slip states
    assert np.all(M[-4:] == 0) and np.all(D[-4:, -4:] > 0 - 1e-300)
    np.testing.assert_allclose(M, M.T)
    np.testing.assert_allclose(D, D.T)
    np.testing.assert_allclose(G, -G.T, atol=1e-12)
    np.testing.assert_allclose(K, K.T)
    m = 6 + p.n_belt
    assert np.all(np.linalg.eigvalsh(M[:m, :m]) > 0)
    # the tire slides freely on its slip dampers: exactly two motions (x, y along the
    # road) cost no strain energy, the rest is positive definite
    k = np.linalg.eigvalsh(K)
    assert np.all(np.abs(k[:2]) < 1e-9 * k[-1]) and np.all(k[2:] > 1e-6)
    M2, D2, G2, K2 = system_matrices(-80.0)
    np.testing.assert_allclose(G2, -G, atol=1e-12)  # odd in Omega
    np.testing.assert_allclose(K2, K)  # even in Omega
    np.testing.assert_allclose(D2, D)
    s = build_tire_system(80.0)
    assert s.dofs[:6] == HUB_DOFS and len(s.dofs) == 202 and s.dofs[-1] == "slip.z1.y"
    np.testing.assert_allclose(s.C, D + G)


@pytest.mark.parametrize("speed", [0.0, 100.0])
def test_modal_synthesis_equals_direct_solution(speed):
    s, md = system_and_modes(speed)
    assert md.poles.size == 400
    osc = md.poles[0::2].imag > 0
    np.testing.assert_allclose(md.poles[1::2][osc], np.conj(md.poles[0::2][osc]))
    assert np.all(md.poles.imag[:4] == 0)  # the first-order slip modes lead
    assert np.all(np.diff(md.frequencies) >= 0)
    f = np.r_[np.linspace(3.0, 60.0, 12), np.linspace(80.0, 700.0, 14)]
    load = patch_load(0.166)
    Yd = s.frf(f, HUB_DOFS, HUB_DOFS, loads={"patch": load})
    jw = 2j * np.pi * f
    H = receptance(jw, md, np.arange(6))  # (n_f, 6, 200)
    Ym = np.concatenate([H[:, :, :6], (H @ load)[:, :, None]], axis=2) * jw[:, None, None]
    err = np.abs(Ym - Yd.data).max(axis=(1, 2)) / np.abs(Yd.data).max(axis=(1, 2))
    assert err.max() < 1e-6


def test_reciprocity_rules():
    f = np.linspace(5.0, 300.0, 25)
    Y0 = build_tire_system(0.0).frf(f, HUB_DOFS, HUB_DOFS).data
    Yp = build_tire_system(100.0).frf(f, HUB_DOFS, HUB_DOFS).data
    Ym = build_tire_system(-100.0).frf(f, HUB_DOFS, HUB_DOFS).data
    T = np.swapaxes
    assert np.abs(Y0 - T(Y0, 1, 2)).max() < 1e-10 * np.abs(Y0).max()
    asym = np.abs(Yp - T(Yp, 1, 2)).max(axis=(1, 2)) / np.abs(Yp).max(axis=(1, 2))
    assert asym.max() > 1e-2  # not reciprocal at speed
    assert np.abs(T(Yp, 1, 2) - Ym).max() < 1e-9 * np.abs(Yp).max()


@pytest.mark.parametrize("speed", [0.0, 60.0, 100.0])
def test_damping_and_conjugate_pairs(speed):
    _, md = system_and_modes(speed)
    osc = md.poles[0::2].imag > 0
    assert np.sum(~osc) == 2  # two pairs of real poles: slip relaxation and free sliding
    z = md.damping_ratios[osc]
    # the slip dampers add to the fore-aft / wind-up modes (test_tire_slip.py)
    assert np.all((z > 0.01) & (z < 0.5))
    assert np.median(z) == pytest.approx(DEFAULT_PARAMETERS.zeta, rel=0.05)
    if speed == 0.0:  # tread sticking: every mode has exactly zeta at 0 km/h
        s = build_tire_system(0.0, STICK)
        zs = complex_modes(s.M, s.C, s.K).damping_ratios
        np.testing.assert_allclose(zs, STICK.zeta, rtol=1e-6)


def test_overdamped_system_is_rejected():
    M = np.eye(2)
    K = np.diag([1.0, 4.0])
    with pytest.raises(ModalError, match="overdamped"):
        complex_modes(M, 10 * np.eye(2), K)


def test_mode_count_and_highest_mode():
    tire = reference_tire()
    assert tire.n_modes == 400
    for v in tire.speeds:
        f = tire.eigenfrequencies(v)
        assert f.size == 198 and np.all(f > 0) and np.all(np.diff(f) >= 0)
        assert np.sum(f < 800.0) >= 150
        assert 600.0 < f[-1] < 1200.0  # of the order of 800 Hz


def test_first_belt_radial_modes_between_80_and_100_hz():
    """Lowest modes whose energy sits mostly in the ring's radial orders n >= 1."""
    M, _, _, K = system_matrices(0.0, STICK)
    w2, phi = sla.eigh(K, M)
    labels = belt_labels()
    ring_cols = 6 + np.flatnonzero(
        [lab.startswith("belt.ip.") and not lab.endswith("n00") for lab in labels]
    )
    e = phi**2 * np.diag(M)[:, None]
    share = e[ring_cols].sum(0) / e.sum(0)
    f = np.sqrt(w2) / (2 * np.pi)
    first = f[share > 0.5][:4]
    assert np.all((first >= 80.0) & (first <= 100.0)), first


def local_peaks(f, a):
    i = np.flatnonzero((a[1:-1] > a[:-2]) & (a[1:-1] > a[2:])) + 1
    return f[i]


def test_case_1_hub_response_peaks_near_17_and_38_hz():
    tire = reference_tire()
    f = np.arange(13.0, 51.5, 0.25)
    v = np.abs(tire.patch_response(f, 1).data[:, :, 0])
    z = v[:, HUB_DOFS.index("hub:z")]
    assert abs(f[np.argmax(z)] - 17.0) < 1.5
    # the fore-aft / wind-up mode is at 37-39 Hz at every operating point; the slip of
    # the tread damps it (zeta 0.09 at 20 km/h to 0.3 at 120 km/h, test_tire_slip.py),
    # so along case 1 (38 Hz at 88 km/h) its peak shows only with the tread sticking
    for speed in tire.speeds:
        pol = tire.poles_at(speed)[0::2]
        f_m = pol.imag / (2 * np.pi)
        x = np.abs(tire.psi[list(tire.speeds).index(speed), 0::2, HUB_DOFS.index("hub:x")])
        sel = np.flatnonzero((f_m > 25) & (f_m < 60))
        assert abs(f_m[sel[np.argmax(x[sel])]] - 38.0) < 2.5
    s = build_tire_system(88.0, STICK)
    vs = np.abs(s.frf(f, HUB_DOFS, [], loads={"p": patch_load(0.646, STICK)}).data[:, :, 0])
    for dof in ("hub:x", "hub:ry"):
        peaks = local_peaks(f, vs[:, HUB_DOFS.index(dof)])
        assert np.any(np.abs(peaks - 38.0) < 2.5), (dof, peaks)
    # camber, toe and their lateral force give a physical lateral response (issue 14:
    # it was numerical noise, -210 dB, on the symmetric tire); camber projects about
    # sin(1.5 deg) of the vertical motion onto y
    y = v[:, HUB_DOFS.index("hub:y")]
    assert 0.01 * z.max() < y.max() < 0.1 * z.max()


def test_short_wavelengths_excite_higher_orders():
    """The road wave modulating the patch load shifts its circumferential spectrum.

    A long wave loads the patch almost uniformly, like a point load, whose
    spectrum is flat and decays beyond n ~ 2 pi R / L_c; a wave of wavelength
    lambda shorter than the patch puts most of the load on orders near
    n = 2 pi R / lambda (reference-models.md sec. 1).
    """
    from fbs_core.harmonics import HARMONICS

    labels = belt_labels()
    radial = [
        (i, int(lab.split(".")[2][1:3]))
        for i, lab in enumerate(labels)
        if lab.startswith("belt.w2.")
    ]
    R = DEFAULT_PARAMETERS.R
    dominant, high_share = [], []
    for h in HARMONICS[:6]:
        f = patch_load(h.wavelength)[6:]
        spec = np.zeros(max(n for _, n in radial) + 1)
        for i, n in radial:
            spec[n] += abs(f[i]) ** 2
        dominant.append(int(np.argmax(spec)))
        high_share.append(spec[8:].sum() / spec.sum())
    assert dominant[0] <= 2 and dominant[1] <= 2
    assert abs(dominant[4] - 2 * np.pi * R / HARMONICS[4].wavelength) <= 2
    assert dominant[5] >= 13
    assert np.all(np.diff(high_share) > 0)
