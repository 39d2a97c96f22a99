"""Bad arguments to the core library end in domain errors, never in a silent wrong result.

Findings of the attack on the dashboard (issue 20, item 9) that belong to ``fbs_core``.
"""

from __future__ import annotations

import numpy as np
import pytest
from discrete import build, frf_of, label

import fbs_core as fc
from fbs_core.errors import FBSError, SingularInterfaceError

FREQ = np.linspace(0.5, 40.0, 30)


@pytest.fixture(scope="module")
def two():
    subs, glob = build({"A": [0, 1, 2, 3], "B": [3, 4, 5, 6]}, gyro=0.0, seed=1)
    return {name: frf_of(M, C, K, labs, FREQ) for name, (M, C, K, labs) in subs.items()}


@pytest.mark.parametrize("rcond", [float("nan"), 1.0, 5.0, -1e-3, float("inf"), "1e-6", True])
def test_rcond_outside_0_1_is_refused(two, rcond):
    iface = [label(3, "x"), label(3, "y")]
    with pytest.raises(FBSError, match=r"rcond must be a number in \[0, 1\)"):
        fc.couple_receptance(two["A"], two["B"], iface, rcond=rcond)


def test_rcond_inside_0_1_still_couples(two):
    iface = [label(3, "x"), label(3, "y")]
    ref = fc.couple_receptance(two["A"], two["B"], iface)
    reg = fc.couple_receptance(two["A"], two["B"], iface, rcond=1e-12)
    np.testing.assert_allclose(reg.data, ref.data, rtol=1e-8)
    # the coupled response differs from the uncoupled one: what rcond >= 1 returned
    a0 = two["A"].sel(outputs=label(0, "x"), inputs=label(0, "x")).data
    c0 = ref.sel(outputs=label(0, "x"), inputs=label(0, "x")).data
    assert np.max(np.abs(c0 - a0)) > 1e-3 * np.max(np.abs(a0))


def test_impedance_coupling_of_a_singular_subsystem_is_a_domain_error():
    f = np.array([1.0, 2.0, 3.0])
    # rank-one (singular) 2x2 mobility at every line: cannot be inverted to an impedance
    v = np.array([1.0, 2.0])
    data = np.broadcast_to(np.outer(v, v), (3, 2, 2)).astype(complex)
    A = fc.FRF(f, data, ["a:x", "j:x"], ["a:x", "j:x"])
    B = fc.FRF(f, np.broadcast_to(np.eye(2), (3, 2, 2)), ["j:x", "b:x"], ["j:x", "b:x"])
    with pytest.raises(SingularInterfaceError, match="singular"):
        fc.couple_impedance(A, B, ["j:x"])
    with pytest.raises(SingularInterfaceError):
        fc.couple_impedance(B.replace(outputs=["b:x", "j:x"], inputs=["b:x", "j:x"]), A, ["j:x"])


def test_scatter_band_rounds_are_bounded_before_any_allocation():
    from fbs_core.studies.scatter import MAX_ROUNDS

    with pytest.raises(FBSError, match="rounds must be at most"):
        fc.scatter_band(4, noise=0.1, rounds=10**12, n_modes=20)
    with pytest.raises(FBSError, match="rounds must be at most"):
        fc.scatter_band(4, noise=0.1, rounds=MAX_ROUNDS + 1, n_modes=20)


def test_a_study_result_not_finite_names_its_first_line():
    from fbs_core.studies._finite import require_finite

    f = np.array([10.0, 12.5, 15.0, 17.5])
    x = np.ones((4, 2, 2))
    require_finite(x, f, "the band", "why")  # finite: nothing
    x[2, 1, 0] = np.nan
    x[3, 0, 0] = np.inf
    with pytest.raises(SingularInterfaceError, match=r"^the band is not finite at 15 Hz \(why\)$"):
        require_finite(x, f, "the band", "why")
