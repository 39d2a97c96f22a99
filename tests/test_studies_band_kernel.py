"""The public band kernel (fbs_core.studies.band_kernel): blocks of lines, single rounds."""

from __future__ import annotations

import numpy as np
import pytest

from fbs_core.errors import DataFormatError, FBSError
from fbs_core.studies import band_kernel as bk
from fbs_core.studies.scatter import Convergence, ScatterBand, scatter_band_arrays

NF, NJ, NE, R = 11, 6, 3, 150  # R > LANES: the parallel kernel runs several blocks
Q = np.array([5.0, 50.0, 95.0])


@pytest.fixture(scope="module")
def mats():
    """Interface mobilities of two small damped structures (direct inverse, 6 DOFs)."""
    rng = np.random.default_rng(3)
    w = 2 * np.pi * np.linspace(20.0, 80.0, NF)

    def structure(n):
        m = rng.uniform(1.0, 3.0, n)
        Kc = rng.uniform(0.5, 1.5, (n, n)) * 1e5
        K = (np.diag(Kc.sum(1) + 2e5) - (Kc + Kc.T) / 2 * (1 - np.eye(n))) * (1 + 0.04j)
        return 1j * w[:, None, None] * np.linalg.inv(K[None] - w[:, None, None] ** 2 * np.diag(m))

    YA, YE = structure(8), structure(10)
    vj = YA[:, :NJ, NJ:] @ np.array([1.0, -0.4])
    return YA[:, :NJ, :NJ], vj, YE[:, :NJ, :NJ], YE[:, NJ : NJ + NE, :NJ]


def _mag(z):
    return np.sqrt(z.real * z.real + z.imag * z.imag)


def test_blocks_in_any_order_and_split_are_the_whole_band_and_numpy_statistics(mats):
    arrays = bk.kernel_arrays(*mats)
    key, rids = bk.seed_key(11), np.arange(R, dtype=np.int64)
    ck = np.array([10, 100, R], np.int64)
    tire, chassis = bk.noise_flags("both")
    whole = scatter_band_arrays(*mats, 0.2, "both", R, True, 11, percentiles=Q, checkpoints=ck)
    st = bk.BandStats.empty(NF, NE, Q.size, ck.size)
    work = np.empty((5, NE, R))  # one buffer for all blocks (the largest has 5 lines)
    for a, b in ((7, NF), (0, 2), (2, 7)):  # uneven and out of order
        spent = bk.band_lines(arrays, a, b, key, rids, 0.2, tire, chassis, True, Q, ck, st, a, work)
        assert spent >= 0.0
    for mine, band in (
        (st.minimum, whole.minimum),
        (st.maximum, whole.maximum),
        (st.argmax_round, whole.argmax_round),
        (st.percentiles, whole.percentiles),
        (st.conv_maximum, whole.convergence.maximum),
    ):
        np.testing.assert_array_equal(mine, band)
    # second method: numpy statistics over the rounds the kernel regenerates one by one
    every = _mag(
        np.stack([bk.responses(arrays, key, [r], 0.2, tire, chassis, True)[0] for r in rids])
    )
    np.testing.assert_array_equal(st.minimum, every.min(0))
    np.testing.assert_array_equal(st.conv_minimum[0], every[:10].min(0))
    np.testing.assert_allclose(st.percentiles, np.percentile(every, Q, axis=0), rtol=1e-13)


def test_responses_are_eq_5_2_with_the_rounds_factors_and_the_reference_is_eq_4_1(mats):
    YjjA, vj, YjjE, YejE = mats
    arrays = bk.kernel_arrays(*mats)
    ref = bk.reference_response(arrays)
    x = np.linalg.solve(YjjA + YjjE, vj[..., None])[..., 0]
    np.testing.assert_allclose(ref, np.einsum("fek,fk->fe", YejE, x), rtol=1e-10)
    band = ScatterBand.of_kernel(
        arrays,
        5,
        freq=np.arange(NF, dtype=float),
        dofs=("e0", "e1", "e2"),
        reference=ref,
        minimum=np.zeros((NF, NE)),
        maximum=np.zeros((NF, NE)),
        argmin_round=np.zeros((NF, NE), np.int64),
        argmax_round=np.zeros((NF, NE), np.int64),
        q=Q,
        percentiles=np.zeros((Q.size, NF, NE)),
        convergence=Convergence(np.array([R]), np.zeros((1, NF, NE)), np.zeros((1, NF, NE))),
        noise=0.3,
        target="tire",
        rounds=R,
        frequency_dependent=False,
        harmonic=None,
    )
    r = 77
    got = bk.responses(arrays, bk.seed_key(5), np.array([r]), 0.3, True, False, False)[0]
    np.testing.assert_array_equal(band.round(r), got)
    S = band.factors(r)  # one set for every line (frequency independent), tire only
    assert np.all(S["Yjj_E"] == 1.0) and np.all(S["Yej_E"] == 1.0)
    x = np.linalg.solve(S["Yjj_A"] * YjjA + YjjE, (S["vj_A"] * vj)[..., None])[..., 0]
    np.testing.assert_allclose(got, np.einsum("fek,fk->fe", YejE, x), rtol=1e-9)


def test_refusals_name_the_problem(mats):
    arrays = bk.kernel_arrays(*mats)
    st = bk.BandStats.empty(4, NE, 1, 1)
    args = (bk.seed_key(0), np.arange(10, dtype=np.int64), 0.1, True, True, False)
    stats = (np.array([50.0]), np.array([10], np.int64), st)
    with pytest.raises(FBSError, match=r"line block 5..20 outside 0..11"):
        bk.band_lines(arrays, 5, 20, *args, *stats)
    with pytest.raises(FBSError, match=r"rows 2..6 outside the 4"):
        bk.band_lines(arrays, 0, 4, *args, *stats, row=2)
    with pytest.raises(FBSError, match=r"work must have shape \(>= 4, 3, 10\)"):
        bk.band_lines(arrays, 0, 4, *args, *stats, work=np.empty((4, NE, 9)))
    with pytest.raises(FBSError, match="allowed: tire, chassis, both"):
        bk.noise_flags("wheel")
    assert bk.noise_flags("vehicle") == (False, True)  # the deprecated name of "chassis"
    bad = mats[0].copy()
    bad[3, 1, 1] = np.nan
    with pytest.raises(DataFormatError, match="YjjA contains non-finite values"):
        bk.kernel_arrays(bad, *mats[1:])
    with pytest.raises(DataFormatError, match="vj must have shape"):
        bk.kernel_arrays(mats[0], mats[1][:, :5], *mats[2:])
