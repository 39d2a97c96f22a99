"""Modal truncation study (thesis 5.1) on a mass-spring 'tire' whose modal sums are built here.

The truth is the direct solution of the assembled structure (tire + chassis merged
at the hub), never the code's own output.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

import fbs_core as fc
from fbs_core.dofs import DIRECTIONS
from fbs_core.studies.truncation import (
    suggest_modes,
    suggest_n_modes,
    truncation_map,
    truncation_map_arrays,
)

HARM = 1
FREQ = fc.harmonic(HARM).frequencies(0.5)  # 13 .. 51.5 Hz
N_A, N_E, BETA = 26, 18, 2e-4  # tire DOFs (6 hub first), chassis DOFs, damping C = BETA K


def _spring_net(rng, n, ground):
    kc = rng.uniform(0.3, 1.0, (n, n)) * 4e5 * (rng.uniform(size=(n, n)) < 0.5)
    kc = np.triu(kc, 1)
    kc = kc + kc.T  # symmetric spring network between the DOFs
    K = np.diag(kc.sum(1) + ground) - kc
    M = np.diag(rng.uniform(0.5, 2.0, n))
    return M, K


@pytest.fixture(scope="module")
def structures():
    rng = np.random.default_rng(3)
    MA, KA = _spring_net(rng, N_A, ground=np.r_[np.zeros(6), np.full(N_A - 6, 2e5)])
    ME, KE = _spring_net(rng, N_E, ground=np.full(N_E, 3e5))
    return MA, KA, ME, KE


class ModalTire:
    """Proportionally damped structure as a modal model: N complex modes = N/2 real modes."""

    def __init__(self, M, K):
        w2, phi = sla.eigh(K, M)
        self.wr = np.sqrt(w2)
        self.phi = phi  # mass normalised, ascending
        self.n_modes = 2 * w2.size
        self.M, self.K = M, K

    def load(self, h):
        x = np.linspace(-0.1, 0.1, N_A - 6)
        return np.r_[np.zeros(6), np.cos(2 * np.pi * x / h.wavelength)]

    def truncations(self, freq, h, n_list):
        w = 2 * np.pi * np.asarray(freq)
        g = 1j * w[:, None] / (self.wr**2 - w[:, None] ** 2 + 1j * w[:, None] * BETA * self.wr**2)
        hub = self.phi[:6]  # (6, n_r)
        pa = self.phi.T @ self.load(fc.harmonic(h))  # modal participation of the patch load
        Y = np.einsum("ir,fr,jr->frij", hub, g, hub)
        v = np.einsum("ir,fr,r->fri", hub, g, pa)
        cY, cv = np.cumsum(Y, axis=1), np.cumsum(v, axis=1)
        idx = np.asarray(n_list) // 2 - 1
        return np.moveaxis(cY[:, idx], 1, 0), np.moveaxis(cv[:, idx], 1, 0)

    def eigenfrequencies(self, speed):
        return self.wr / (2 * np.pi)


def _chassis_frf(ME, KE, freq):
    w = 2 * np.pi * freq
    Z = KE[None] * (1 + 1j * w[:, None, None] * BETA) - w[:, None, None] ** 2 * ME[None]
    Y = 1j * w[:, None, None] * np.linalg.inv(Z)
    outs = [f"spindle:{d}" for d in DIRECTIONS] + [f"bushing:{d}" for d in DIRECTIONS]
    return fc.FRF(freq, Y[:, :12, :6], outs, outs[:6])


def _assembled_bushing_response(structures, tire, freq, coupled):
    """Direct solve of tire + chassis with the coupled hub DOFs merged (primal assembly)."""
    MA, KA, ME, KE = structures
    n = N_A + N_E - len(coupled)
    # global index of each chassis DOF: coupled spindle DOFs map onto the tire hub DOFs
    gE, nxt = [], N_A
    for i in range(N_E):
        if i < 6 and DIRECTIONS[i] in coupled:
            gE.append(i)
        else:
            gE.append(nxt)
            nxt += 1
    gE = np.array(gE)
    M = np.zeros((n, n))
    K = np.zeros((n, n))
    M[:N_A, :N_A] += MA
    K[:N_A, :N_A] += KA
    M[np.ix_(gE, gE)] += ME
    K[np.ix_(gE, gE)] += KE
    F = np.zeros(n, complex)
    F[:N_A] = tire.load(fc.harmonic(HARM))
    w = 2 * np.pi * freq
    Z = K[None] * (1 + 1j * w[:, None, None] * BETA) - w[:, None, None] ** 2 * M[None]
    x = np.linalg.solve(Z, np.broadcast_to(F, (freq.size, n))[..., None])[..., 0]
    return 1j * w[:, None] * x[:, gE[6:12]]


@pytest.fixture(scope="module")
def tire(structures):
    return ModalTire(structures[0], structures[1])


@pytest.fixture(scope="module")
def chassis(structures):
    return _chassis_frf(structures[2], structures[3], FREQ)


@pytest.mark.parametrize("coupling", ["6dof", "5dof"])
def test_reference_equals_direct_solution_of_assembly(structures, tire, chassis, coupling):
    m = truncation_map(HARM, [10, 20, 30], tire=tire, chassis=chassis, coupling=coupling)
    coupled = DIRECTIONS if coupling == "6dof" else tuple(d for d in DIRECTIONS if d != "ry")
    truth = _assembled_bushing_response(structures, tire, FREQ, coupled)
    np.testing.assert_allclose(m.reference, truth, rtol=1e-8, atol=1e-10 * np.abs(truth).max())
    assert m.dofs == tuple(f"bushing:{d}" for d in DIRECTIONS)


def test_all_modes_give_zero_map_and_error_falls_with_modes(tire, chassis):
    n = np.arange(4, tire.n_modes + 1, 4)
    m = truncation_map(HARM, n, tire=tire, chassis=chassis)
    assert m.error.shape == (n.size, m.centres.size, 6)
    assert np.all(m.error[-1] == 0.0)  # all modes: the reference itself
    worst = m.max_error.max(axis=1)
    assert worst[0] > 0.2 and worst[-2] < 0.01
    assert worst[0] == worst.max() and np.all(np.diff(worst[:4]) < 0)
    # not monotone in between (adding a mode can spoil the sum, thesis 5.1.2), but falls overall
    assert worst[: n.size // 2].mean() > 10 * worst[-3:].mean()
    np.testing.assert_array_equal(m.max_error, m.error.max(axis=-1))
    np.testing.assert_array_equal(m.dof_error("bushing:z"), m.error[:, :, 2])


def test_map_equals_metric_of_direct_truncated_couplings(tire, chassis):
    """Second method: couple every truncated tire with the labelled eq. 4.1 API, then eq. 5.1."""
    n = [10, 24]
    m = truncation_map(HARM, n, tire=tire, chassis=chassis, width=8.0, step=2.0)
    Y, v = tire.truncations(FREQ, HARM, n + [tire.n_modes])
    hub = [f"hub:{d}" for d in DIRECTIONS]
    Yej = chassis.sel(outputs=[f"bushing:{d}" for d in DIRECTIONS])
    YjjE = chassis.sel(outputs=[f"spindle:{d}" for d in DIRECTIONS])
    pairs = list(zip(hub, YjjE.inputs, strict=True))
    out = []
    for k in range(3):
        r = fc.coupling.couple_response(
            Yej,
            fc.FRF(FREQ, Y[k], hub, hub),
            YjjE,
            fc.FRF(FREQ, v[k][..., None], hub, ["patch"]),
            interface=pairs,
        )
        out.append(r.data[..., 0])
    np.testing.assert_allclose(m.response, np.stack(out[:2]), rtol=1e-9)
    c, e = fc.studies.floating_band_error(FREQ, out[2], np.stack(out[:2]), 8.0, 2.0)
    np.testing.assert_allclose(m.error, e, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(m.centres, c)


def test_arrays_entry_point_carries_axes(tire, chassis):
    Y, v = tire.truncations(FREQ, HARM, [10, 20, tire.n_modes])
    E = chassis.data
    m = truncation_map_arrays(FREQ, Y[:2], v[:2], Y[2], v[2], E[:, :6], E[:, 6:], [10, 20])
    np.testing.assert_array_equal(m.n_modes, [10, 20])
    np.testing.assert_array_equal(m.freq, FREQ)
    assert m.response.shape == (2, FREQ.size, 6) and m.reference.shape == (FREQ.size, 6)
    with pytest.raises(ValueError):
        m.error[0, 0, 0] = 1.0
    with pytest.raises(AttributeError):
        m.width = 3.0


def test_suggest_reads_the_stays_below_rule():
    c = np.array([20.0, 40.0, 60.0])
    n = np.array([10, 20, 30, 40])
    err = np.array(
        [
            [0.5, 0.5, 0.9],
            [0.1, 0.1, 0.9],  # fine up to 40 Hz
            [0.1, 0.3, 0.1],  # rises again at 40 Hz
            [0.1, 0.1, 0.1],
        ]
    )
    assert suggest_n_modes(err, c, n, 0.2, f_max=40.0) == 40  # 20 fails to stay below
    assert suggest_n_modes(err, c, n, 0.35, f_max=40.0) == 20
    assert suggest_n_modes(err, c, n, 0.2, f_max=20.0) == 20
    assert suggest_n_modes(err, c, n, 0.05, f_max=60.0, n_total=50) == 50  # only the reference
    assert suggest_n_modes(err, c, n, 0.2, f_max=10.0) == 0  # nothing below f_max
    with pytest.raises(fc.FBSError, match="threshold"):
        suggest_n_modes(err, c, n, -0.1)
    with pytest.raises(fc.FBSError, match="ascending"):
        suggest_n_modes(err, c, n[::-1])
    with pytest.raises(fc.FBSError, match="shape"):
        suggest_n_modes(err[:2], c, n)


def test_suggested_modes_monotone_in_threshold(tire, chassis):
    maps = [truncation_map(HARM, np.arange(4, tire.n_modes + 1, 4), tire=tire, chassis=chassis)]
    prev = None
    for thr in (0.01, 0.05, 0.1, 0.2, 0.4, 0.8):
        s = suggest_modes(thr, 45.0, maps=maps, tire=tire)
        assert s.harmonics == (HARM,)
        if prev is not None:
            assert np.all(s.n_modes <= prev)
        prev = s.n_modes
        k = int(s.n_modes[0])
        # highest eigenfrequency among the retained modes (k / 2 real modes)
        assert s.eigenfrequency[0] == pytest.approx(tire.wr[k // 2 - 1] / (2 * np.pi))
    assert "modes to 45 Hz" in s.table()


@pytest.mark.parametrize(
    "kw, err, match",
    [
        (dict(n_modes=[20, 10]), fc.FBSError, "ascending"),
        (dict(n_modes=[10, 1000]), fc.FBSError, "ascending counts"),
        (dict(coupling="4dof"), fc.FBSError, "allowed: 6dof, 5dof"),
        (dict(coupling=["x", "q"]), fc.FBSError, "directions"),
        (dict(edges="none"), fc.FBSError, "clip, valid"),
    ],
)
def test_bad_arguments_raise(tire, chassis, kw, err, match):
    with pytest.raises(err, match=match):
        truncation_map(HARM, **{"tire": tire, "chassis": chassis, **kw})


def test_bad_models_raise(tire, chassis):
    with pytest.raises(fc.FrequencyGridError, match="interpolate"):
        truncation_map(HARM, [10], tire=tire, chassis=chassis.isel(freq=slice(1, None)))
    with pytest.raises(fc.DOFError, match="interface"):
        truncation_map(HARM, [10], tire=tire, chassis=chassis.sel(inputs=["spindle:x"]))
    with pytest.raises(fc.FBSError, match="tire must be"):
        truncation_map(HARM, [10], tire=object(), chassis=chassis)
    with pytest.raises(fc.FBSError, match="chassis must be"):
        truncation_map(HARM, [10], tire=tire, chassis=object())
    m = truncation_map(HARM, [10], tire=tire, chassis=chassis)
    with pytest.raises(fc.DOFError, match="available"):
        m.dof_error("hub:z")
