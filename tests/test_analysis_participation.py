"""Mode participation and selected modes (issue 30).

Truth: the coupled response is linear in the free hub velocity, so the direct
contributions add up to the total (and to ``bushing_response``); the response without a
mode is the prediction of a model that does not have it (``tire.subset`` synthesised and
coupled the ordinary way); the responses of a selection are those of the tire restricted
to the selected pairs. Linear interpolation between operating points makes "the model
without mode r" exactly "the model minus mode r's term" (no clusters re-formed).
"""

import functools

import numpy as np
import pytest

import fbs_core as fc
from fbs_core import bushing_response, harmonic, reference_tire
from fbs_core.analysis import mode_participation, prefix_responses, select_modes
from fbs_core.analysis.participation import RANKINGS
from fbs_core.errors import DOFError, FBSError, ModeCountError
from fbs_core.studies import _models
from fbs_core.tire import TireModel, complex_modes, track_modes
from fbs_core.tire.terms import mode_terms


@functools.cache
def linear_tire() -> TireModel:
    t = reference_tire()
    return TireModel(
        t.speeds, t.poles, t.psi, t.chi, t.wavelengths, t.participation, interpolation="linear"
    )


def _close(a, b, tol=1e-9):
    np.testing.assert_allclose(a, b, rtol=0, atol=tol * np.abs(b).max())


def test_contributions_add_up_to_the_coupled_response():
    p = mode_participation(1)
    ref = bushing_response(1).data[:, :, 0]
    _close(p.total, ref, 1e-10)
    _close(p.contributions.sum(axis=0), p.total, 1e-10)
    np.testing.assert_allclose(p.share.sum(axis=0), 1.0, atol=1e-9)
    assert np.all(p.level >= 0) and np.all(p.loo >= 0)
    # the hub mode on the vertical contact springs (16.5 Hz) carries bushing z in case 1
    top = p.modes[p.ranking("share", "bushing:z")[0]]
    assert 15.5 < p.mode_freq[top] < 17.5
    assert p.first_order[:2].all() and not p.first_order[2:].any()  # the tread slip states
    text = p.table("bushing:z", top=5)
    assert "bushing:z" in text and len(text.splitlines()) == 7
    assert len(p.table(None, by="level", top=3).splitlines()) == 5


def test_leave_one_out_is_the_model_without_that_mode():
    tire = linear_tire()
    p = mode_participation(1, tire=tire)
    n_p = tire.n_modes // 2
    for m in (0, int(p.ranking("loo", "bushing:z")[0]), 5, 150):
        rest = np.setdiff1d(np.arange(n_p), [m])
        without = bushing_response(1, freq=p.freq, tire=tire.subset(rest, residual=False))
        _close(p.loo_response[m], without.data[:, :, 0])
    # the mode of largest loo error changes the prediction visibly; a high one does not
    assert p.loo[int(p.ranking("loo", "bushing:z")[0]), 2] > 0.1
    assert p.loo[150].max() < 1e-3


def test_mode_terms_split_clusters_into_members_that_add_up():
    """Cubic model with veering clusters: the members' partial fractions add up to the
    model's rational form, line by line (hub mobility and free velocity)."""
    tire = reference_tire()
    h = harmonic(7)
    f = h.frequencies(2.0)
    t = mode_terms(tire, f, h.speed_at(f), tire._harmonic_index(h))
    Y, v = tire.truncations(f, h, [tire.n_modes])
    s = 2j * np.pi * f[:, None]
    _close(t.dynamic.sum(axis=0)[:, :36] * s, Y[0].reshape(f.size, 36), 1e-10)
    _close(t.dynamic.sum(axis=0)[:, 36:] * s, v[0], 1e-10)
    with pytest.raises(FBSError, match="1-D of one length"):
        mode_terms(tire, f, h.speed_at(f)[:-1])
    with pytest.raises(FBSError, match="no columns"):
        mode_terms(tire, f, h.speed_at(f), hub=False)


def _rotor_tire() -> TireModel:
    """Four coupled gyroscopic rotor pairs (8 DOFs, 6 of them at the hub) at three
    speeds; the patch load does not reach pair 3 (its participation is zero)."""
    speeds = np.array([20.0, 70.0, 120.0])
    w0 = 2 * np.pi * np.array([30.0, 45.0, 60.0, 150.0])

    def matrices(v):
        om = v / 3.6 / 0.3
        M, K, G = np.eye(8), np.zeros((8, 8)), np.zeros((8, 8))
        for i, w in enumerate(w0):
            x, y = 2 * i, 2 * i + 1
            K[x, x] = K[y, y] = w**2 - om**2
            G[x, y], G[y, x] = -0.02 * om, 0.02 * om
        for a, b, k in ((0, 2, 2e4), (2, 4, 3e4), (4, 6, 5e4), (1, 5, 1e4)):
            K[[a, b], [a, b]] += k
            K[a, b] -= k
            K[b, a] -= k
        return M, 8.0 * np.eye(8) + G, K

    modes, _ = track_modes([complex_modes(*matrices(v)) for v in speeds])
    load = np.linspace(1.0, 2.0, 8) * 1e3
    part = np.array([[load @ m.chi] for m in modes])
    part[:, :, 6:8] = 0.0  # pair 3 is not excited by the patch
    return TireModel(
        speeds,
        np.array([m.poles for m in modes]),
        np.array([m.psi[:6].T for m in modes]),
        np.array([m.chi[:6].T for m in modes]),
        np.array([harmonic(1).wavelength]),
        part,
        interpolation="linear",
    )


def test_a_mode_the_load_does_not_excite_matters_through_the_mobility():
    tire = _rotor_tire()
    p = mode_participation(1, tire=tire)
    assert np.all(p.contributions[3] == 0) and np.all(p.share[3] == 0)
    assert np.all(p.loo_direct[3] == 0)
    assert p.loo[3].max() > 1e-3  # removing it changes the hub mobility, hence the response
    rest = tire.subset(np.setdiff1d(np.arange(8), [3]), residual=False)
    _close(p.loo_response[3], bushing_response(1, freq=p.freq, tire=rest).data[:, :, 0])
    assert set(RANKINGS) >= {"loo", "share", "level"}


def test_selected_pairs_give_the_response_of_the_tire_restricted_to_them():
    tire = linear_tire()
    h = harmonic(2)
    f = h.frequencies(1.0)
    dirs = _models.coupled_directions("6dof")
    YjjE, YejE, _ = _models.chassis_arrays(None, f, dirs)
    t = mode_terms(tire, f, h.speed_at(f), tire._harmonic_index(h))
    order = np.random.default_rng(0).permutation(tire.n_modes // 2)
    resp = prefix_responses(t, order, [10, 40], YjjE, YejE, dirs)
    for i, n in enumerate((10, 40)):
        sub = tire.subset(order[: n // 2], residual=False)
        _close(resp[i], bushing_response(2, freq=f, tire=sub).data[:, :, 0])
    with pytest.raises(FBSError, match="even"):
        prefix_responses(t, order, [11], YjjE, YejE, dirs)
    with pytest.raises(FBSError, match="static"):
        prefix_responses(t, order, [10], YjjE, YejE, dirs, residual=True)


def test_selected_pairs_with_residual_at_the_operating_points():
    """At lines whose speeds are operating points the per-line static parts are the
    stored ones: a selection with residual equals ``tire.subset`` (which stores the
    residual of the pairs left out per operating point) synthesised with residual."""
    tire = reference_tire()
    h = harmonic(3)
    v = tire.speeds[(tire.speeds >= 40) & (tire.speeds <= 110)]
    f = v / 3.6 / h.wavelength
    dirs = _models.coupled_directions("5dof")
    YjjE, YejE, _ = _models.chassis_arrays(None, f, dirs)
    t = mode_terms(tire, f, v, tire._harmonic_index(h), static=True)
    order = np.r_[np.arange(40, 0, -1), np.arange(41, 200)]
    resp = prefix_responses(t, order, [30, 60], YjjE, YejE, dirs, residual=True)
    for i, n in enumerate((30, 60)):
        sub = tire.subset(order[: n // 2])
        want = bushing_response(3, freq=f, tire=sub, coupling="5dof", residual=True)
        _close(resp[i], want.data[:, :, 0], 1e-8)


def test_select_modes_meets_the_criterion_and_reads_like_table_5_1():
    s = select_modes(1, 0.2, 130.0, by="greedy")
    k = np.flatnonzero(s.counts == s.n_first)[0]
    assert np.all(s.error[k] < 0.2) and s.n_first <= s.n_modes
    assert np.all(s.error[-1] < 1e-12)  # all modes: the reference itself
    assert s.selected.size == s.n_modes // 2 and np.unique(s.order).size == s.order.size
    # independently: the selection delivered as a (linear) model, coupled and judged
    lin = select_modes(1, 0.2, 130.0, by="loo_floating", tire=linear_tire())
    sub = linear_tire().subset(lin.selected, residual=False)
    f = harmonic(1).frequencies()
    f = f[f <= 136.0 + 1e-9]
    ref = bushing_response(1, freq=f, tire=linear_tire()).data[:, :, 0]
    got = bushing_response(1, freq=f, tire=sub).data[:, :, 0]
    _, err = fc.floating_band_error(f, ref, got, centres=lin.centres)
    row = np.flatnonzero(lin.counts == lin.n_modes)[0]
    np.testing.assert_allclose(err.max(axis=-1), lin.error[row], rtol=1e-7, atol=1e-12)
    assert select_modes(7, f_max=100.0).n_modes == 0  # no centre up to 100 Hz


def test_bad_input():
    p = mode_participation(1, band=(20.0, 40.0))
    assert p.freq[0] == 20.0 and p.freq[-1] == 40.0
    with pytest.raises(FBSError, match="allowed: loo"):
        p.ranking("size")
    with pytest.raises(DOFError, match="available: bushing:x"):
        p.table("bushing:q")
    with pytest.raises(FBSError, match="at least 3"):
        mode_participation(1, band=(20.0, 20.5))
    with pytest.raises(FBSError, match="low < high"):
        mode_participation(1, band=(40.0, 20.0))
    with pytest.raises(FBSError, match="allowed: level"):
        select_modes(1, by="random")
    with pytest.raises(FBSError, match="step"):
        select_modes(1, step=5)
    with pytest.raises(FBSError, match="threshold"):
        select_modes(1, threshold=-0.1)
    with pytest.raises(DOFError):
        select_modes(1, dof="bushing:q")
    tire = reference_tire()
    for bad in ([], [0, 0], [200], [1.5]):
        with pytest.raises(ModeCountError, match="distinct stored pair indices"):
            tire.subset(bad)
    assert tire.subset([3, 1]).meta["pairs"] == [1, 3]  # kept in the stored order
