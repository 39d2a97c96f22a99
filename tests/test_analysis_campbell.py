"""Campbell diagram: branches, forward / backward labels, order lines, crossings.

Truth: the rotating ring's closed form (reference-models.md sec. 2.1, Huang & Soedel
1987), ``omega_n(+/-) = (+/- g_n + sqrt(g_n^2 + M_n K_n)) / M_n``: the ``+`` branch is
the forward wave. A modal model is built here from 2-DOF gyroscopic systems per order
(cos / sin coordinates) whose eigenvalues are that closed form.
"""

import functools

import numpy as np
import pytest

from fbs_core import reference_tire
from fbs_core.analysis import campbell, classify_branches, harmonic_lines, travelling_index
from fbs_core.errors import DataFormatError, FBSError
from fbs_core.harmonics import HARMONICS
from fbs_core.tire import (
    DEFAULT_PARAMETERS,
    OperatingPointError,
    TireModel,
    TireParameters,
    build_modal_model,
    build_tire_system,
    complex_modes,
    ring_closed_form,
    track_modes,
)

P = DEFAULT_PARAMETERS
SPEEDS = np.array([20.0, 40.0, 60.0, 80.0, 100.0, 120.0])
ORDERS = (1, 2, 3)  # n = 1: no gyroscopic split (g_1 = 0)


def ring_matrices(speed):
    """Block-diagonal 2-DOF systems (a_cos, a_sin) per order: M_n, G = 2 g_n J, K_n."""
    Om = speed / 3.6 / P.R
    M, G, K = (np.zeros((6, 6)) for _ in range(3))
    for i, n in enumerate(ORDERS):
        b = slice(2 * i, 2 * i + 2)
        Mn = P.rhoA * (n**2 + 1)
        Kn = (
            P.EI * n**2 * (n**2 - 1) ** 2 / P.R**4
            + P.T_p * n**2 * (n**2 - 1) / P.R**2
            + P.k_w * n**2
            + P.k_v
        )
        g = P.rhoA * Om * n * (n**2 - 1)
        M[b, b] = Mn * np.eye(2)
        K[b, b] = Kn * np.eye(2)
        G[b, b] = 2 * g * np.array([[0.0, 1.0], [-1.0, 0.0]])
    return M, G, K


@functools.cache
def ring_model() -> TireModel:
    modes = [complex_modes(*ring_matrices(v)) for v in SPEEDS]
    tracked, _ = track_modes(modes)
    n_m = tracked[0].poles.size
    return TireModel(
        SPEEDS,
        np.array([m.poles for m in tracked]),
        np.array([m.psi.T for m in tracked]),
        np.array([m.chi.T for m in tracked]),
        np.array([0.646]),
        np.zeros((SPEEDS.size, 1, n_m)),
    )


def test_ring_branches_and_labels_match_the_closed_form():
    cb = campbell(ring_model(), speeds=SPEEDS)
    assert cb.method == "slope" and np.all(np.isnan(cb.travelling))
    for n in ORDERS:
        fp, fm = np.array([ring_closed_form(n, v) for v in SPEEDS]).T
        for truth, want in ((fp, "forward"), (fm, "backward")):
            b = np.argmin(np.abs(cb.freq - truth[:, None]).max(axis=0))
            np.testing.assert_allclose(cb.freq[:, b], truth, rtol=1e-9)
            assert cb.direction[b] == (want if n > 1 else "standing")
            if n > 1:  # mean slope of the branch: its Doppler shift per km/h
                exact = np.polyfit(SPEEDS, truth, 1)[0]
                assert cb.slope[b] == pytest.approx(exact, rel=1e-9)


def test_travelling_index_sign_on_the_ring_without_contact():
    """Physical tire, in-plane ring only, no contact, hub clamped: the closed form's
    + branch is a pure wave with tau = -1, the - branch tau = +1."""
    ring = TireParameters(orders=(6, -1, -1, -1, -1, -1, -1, -1), k_cx=0, k_cy=0, k_cz=0)
    s = build_tire_system(100.0, ring)
    b = slice(6, None)
    md = complex_modes(s.M[b, b], s.C[b, b], s.K[b, b])
    tau = travelling_index(md.psi[:, 0::2], s.dofs[6:])
    for n in (2, 3, 4):
        fp, fm = ring_closed_form(n, 100.0, ring)
        i = np.argmin(np.abs(md.frequencies - fp))
        j = np.argmin(np.abs(md.frequencies - fm))
        assert md.frequencies[i] == pytest.approx(fp, rel=2e-3)  # damped vs undamped
        assert tau[i] == pytest.approx(-1.0, abs=1e-6)
        assert tau[j] == pytest.approx(1.0, abs=1e-6)
    with pytest.raises(FBSError, match="cos / sin"):
        travelling_index(md.psi, [f"n{i}:x" for i in range(md.psi.shape[0])])


def test_shape_and_slope_criteria_agree_on_strongly_split_branches():
    """A small physical tire (few orders, with contact): the two independent criteria
    give the same label where a branch shifts by more than 5 Hz over the range."""
    small = TireParameters(orders=(5, 2, 2, -1, -1, -1, -1, -1))
    model = build_modal_model(small, speeds=(20.0, 70.0, 120.0), wavelengths=(0.646,))
    by_shape = campbell(model, method="shape")
    by_slope = campbell(model, method="slope")
    strong = np.abs(by_slope.slope * 100) > 5
    assert strong.sum() >= 4
    agree = by_shape.direction[strong] == by_slope.direction[strong]
    assert agree.mean() >= 0.75
    assert np.all(np.abs(by_shape.travelling) <= 1 + 1e-12)
    with pytest.raises(DataFormatError, match="physical parameters"):
        campbell(ring_model(), method="shape")


def test_order_lines_and_crossings_on_the_reference_tire():
    tire = reference_tire()
    cb = campbell(tire)
    v = cb.speeds
    assert v[0] == 20.0 and v[-1] == 120.0
    for k, h in enumerate(HARMONICS):
        np.testing.assert_allclose(cb.lines[:, k], v / 3.6 / h.wavelength, rtol=1e-14)
    assert not cb.in_band[v < 30].any() and cb.in_band[v >= 30].all()
    np.testing.assert_allclose(harmonic_lines([36.0], [0.5]), [[20.0]])
    cr = cb.crossings()
    assert len(cr) > 20
    for c in cr[::7]:  # the line meets the branch: check against the model itself
        f_branch = tire.poles_at(c.speed_kmh)[0::2][c.branch].imag / (2 * np.pi)
        assert f_branch == pytest.approx(c.freq, rel=5e-3)  # cubic model, linear crossing
        assert c.freq == pytest.approx(c.speed_kmh / 3.6 / HARMONICS[c.harmonic - 1].wavelength)
        assert 30 - 1e-9 <= c.speed_kmh <= 120 + 1e-9
    assert len(cb.crossings(in_band=False)) >= len(cr)
    assert np.all(cb.freq.min(axis=0) <= 450.0)
    assert np.all(cb.freq > 0) and np.all(np.isfinite(cb.damping))  # vibration modes only
    real = np.flatnonzero(np.abs(tire.poles[0, 0::2].imag) == 0)
    assert not set(real) & set(cb.branch.tolist())
    assert set(cb.direction) <= {"forward", "backward", "standing"}
    few = campbell(tire, n_modes=40)
    assert few.branch.max() < 20


def test_classify_and_campbell_bad_input():
    with pytest.raises(FBSError, match="increasing"):
        classify_branches([20.0], np.ones((1, 2)))
    with pytest.raises(FBSError, match="shape"):
        classify_branches([20.0, 40.0], np.ones((3, 2)))
    with pytest.raises(OperatingPointError):
        campbell(speeds=[10.0, 50.0])
    with pytest.raises(FBSError, match="allowed: slope, shape"):
        campbell(method="doppler")
    with pytest.raises(FBSError, match="fmax"):
        campbell(fmax=0.0)
    with pytest.raises(FBSError, match="n_modes"):
        campbell(n_modes=41)
