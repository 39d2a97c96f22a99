"""The chassis in modal form and its truncation study (issue 30, thesis section 7).

Truth: the closed-form inverse of a 2-DOF hysteretic chain's dynamic stiffness, the
chassis' exact FRFs (all modes), its static flexibility (``K^-1``, the limit every
residual-compensated truncation must reach at 0 Hz), and the coupled response of
:func:`fbs_core.bushing_response` with the modal chassis (the ordinary path).
"""

import numpy as np
import pytest
import scipy.linalg as sla

from fbs_core import bushing_response, harmonic, reference_chassis
from fbs_core.chassis_modal import ModalChassis, modal_receptances
from fbs_core.errors import FBSError, ModeCountError
from fbs_core.studies import chassis_truncation_map


def _chain():
    M = np.diag([2.0, 1.0])
    K = np.array([[3e4 + 1e4, -1e4], [-1e4, 1e4]]) * (1 + 0.05j)
    lam, V = sla.eig(K, M)
    o = np.argsort(lam.real)
    lam, V = lam[o], V[:, o]
    W = np.linalg.solve(V, np.linalg.inv(M))
    return M, K, lam, V, W


def test_two_dof_chain_in_closed_form():
    M, K, lam, V, W = _chain()
    f = np.array([0.0, 5.0, 12.0, 30.0])
    exact = np.array([np.linalg.inv(K - (2 * np.pi * x) ** 2 * M) for x in f])
    H = modal_receptances(lam, V, W, f, [1, 2])
    np.testing.assert_allclose(H[1], exact, rtol=1e-10)  # all modes: the inverse
    Hr = modal_receptances(lam, V, W, f, [1, 2], residual=True)
    np.testing.assert_allclose(Hr[0, 0], np.linalg.inv(K), rtol=1e-10)  # static: exact
    np.testing.assert_allclose(Hr[1], exact, rtol=1e-10)
    # well below the second mode the residual brings one mode closer to the truth: the
    # error left is of order (omega / omega_2)^2 of the static term
    f2 = np.sqrt(lam[1].real) / (2 * np.pi)
    below = f < 0.25 * f2
    assert below.sum() >= 2
    e_plain = np.abs(H[0][below] - exact[below]).max()
    e_res = np.abs(Hr[0][below] - exact[below]).max()
    assert e_res < 0.1 * e_plain
    with pytest.raises(ModeCountError, match="increasing integers"):
        modal_receptances(lam, V, W, f, [2, 1])


def test_the_modal_chassis_with_all_modes_is_the_chassis():
    ch = reference_chassis()
    f = np.linspace(1.0, 400.0, 120)
    np.testing.assert_allclose(ModalChassis().mobility(f).data, ch.mobility(f).data, rtol=1e-9)
    # a truncated delivery: 15 modes (up to 234 Hz; the first left out at 286 Hz), with
    # and without residual: well below 286 Hz the residual leaves (f / 286 Hz)^2 of it
    full = ch.mobility(f, quantity="receptance").data
    plain = ModalChassis(n_modes=15, residual=False).mobility(f, quantity="receptance").data
    comp = ModalChassis(n_modes=15).mobility(f, quantity="receptance").data
    below = f < 80.0
    e_plain = np.abs(plain[below] - full[below]).max()
    e_comp = np.abs(comp[below] - full[below]).max()
    assert e_comp < 0.2 * e_plain
    # the static limit: the residual makes any truncation exact at 0 Hz
    s = ch.system()
    Kd = s.K.toarray()
    idx = [s.dofs.index(d) for d in ("spindle:x", "spindle:y", "spindle:z")]
    static = np.linalg.inv(Kd)[np.ix_(idx, idx)]
    lo = ModalChassis(n_modes=3).mobility(
        [1e-6], ["spindle:x", "spindle:y", "spindle:z"], ["spindle:x", "spindle:y", "spindle:z"],
        quantity="receptance",
    )  # fmt: skip
    np.testing.assert_allclose(lo.data[0], static, rtol=1e-6)
    assert repr(ModalChassis(n_modes=3)) == "ModalChassis(3 of 264 modes + residual)"


def test_chassis_truncation_map_rows_are_the_coupled_prediction_with_the_modal_chassis():
    m = chassis_truncation_map(2, [5, 15, 264], residual=True, df=1.0)
    assert m.n_modes_total == 264 and m.error.shape[0] == 3
    assert np.all(m.error[-1] < 1e-12)  # all modes: the reference
    f = harmonic(2).frequencies(1.0)
    want = bushing_response(2, freq=f, chassis=ModalChassis(n_modes=15)).data[:, :, 0]
    np.testing.assert_allclose(m.response[1], want, rtol=1e-9, atol=1e-12 * np.abs(want).max())
    ref = bushing_response(2, freq=f).data[:, :, 0]
    np.testing.assert_allclose(m.reference, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())
    # the error falls as modes are added (5 modes miss the 56-109 Hz subframe modes)
    assert m.max_error[0].max() > m.max_error[1].max()
    assert m.suggest(0.2, 130.0) <= 264


def test_bad_input():
    with pytest.raises(ModeCountError, match="1..264"):
        ModalChassis(n_modes=0)
    with pytest.raises(FBSError, match="FE model"):
        ModalChassis(chassis="not a chassis")  # type: ignore[arg-type]
    with pytest.raises(FBSError, match="FE model"):
        chassis_truncation_map(1, chassis=object())  # type: ignore[arg-type]
    with pytest.raises(ModeCountError):
        chassis_truncation_map(1, [10, 5])
