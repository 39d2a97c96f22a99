"""The thesis' studies on the car: truncation map (eq. 5.1) and scatter band (eqs. 5.2-5.4).

Truth: the response of every retained count and of the reference computed a second
way (``vehicle_response``: the car's fast path, not the studies' kernels); the noisy
response of a round recomputed from its factors with numpy (element-wise scaling of
the 24 x 24 tire block, the car's hub and transfer mobilities, the free velocities).
"""

from __future__ import annotations

import numpy as np
import pytest

from fbs_core.errors import FBSError
from fbs_core.vehicle import vehicle_response
from fbs_core.vehicle.studies import (
    vehicle_scatter_band,
    vehicle_suggest_modes,
    vehicle_truncation_map,
)

FREQ = np.arange(14.0, 50.0, 2.0)  # case 1, 2 Hz lines: small and enough for the physics


@pytest.fixture(scope="module")
def tmap():
    return vehicle_truncation_map(1, [20, 60, 200, 400], freq=FREQ, outputs="seat_fl")


def test_truncation_map_responses_are_the_car_responses(tmap):
    assert tmap.harmonic == 1 and tmap.n_modes_total == 400
    assert tmap.dofs == tuple(f"seat_fl:{d}" for d in ("x", "y", "z", "rx", "ry", "rz"))
    assert len(tmap.interface) == 24 and tmap.interface[0] == "hub_fl:x"
    ref = vehicle_response(1, freq=FREQ, outputs="seat_fl").response.data[:, :, 0]
    np.testing.assert_allclose(tmap.reference, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())
    for i, n in enumerate(tmap.n_modes):
        r = vehicle_response(1, int(n), freq=FREQ, outputs="seat_fl").response.data[:, :, 0]
        np.testing.assert_allclose(tmap.response[i], r, rtol=1e-10, atol=1e-12 * np.abs(r).max())
    assert np.all(tmap.error[-1] == 0)  # all modes: no error
    assert tmap.error[0].max() > tmap.error[-2].max()  # 20 modes are worse than 200
    # the terms of eq. 4.1 (transfer x forces) rebuild the reference: path contributions
    total = np.einsum("fej,fj->fe", tmap.transfer, tmap.forces_reference)
    np.testing.assert_allclose(total, tmap.reference, rtol=1e-10, atol=1e-14)


def test_suggested_modes_from_the_maps(tmap):
    s = vehicle_suggest_modes(0.2, 50.0, maps=[tmap])
    loose = vehicle_suggest_modes(0.5, 50.0, maps=[tmap])
    assert s.harmonics == (1,) and 0 < s.n_modes[0] <= 400
    assert loose.n_modes[0] <= s.n_modes[0]
    assert s.n_modes[0] == tmap.suggest(0.2, 50.0)
    assert np.isfinite(s.eigenfrequency[0]) and s.eigenfrequency[0] > 0


def test_scatter_band_rounds_are_the_noisy_car_responses():
    band = vehicle_scatter_band(
        1, 0.1, "both", rounds=200, freq=FREQ[::3], seed=4, outputs="seat_fl:z"
    )
    nominal = vehicle_response(1, freq=FREQ[::3], outputs="seat_fl:z").response.data[:, :, 0]
    np.testing.assert_allclose(band.reference, nominal, rtol=1e-10)
    assert np.all(band.minimum <= np.abs(nominal) + 1e-15)
    assert np.all(band.maximum >= np.abs(nominal) - 1e-15)
    assert np.all(band.maximum > band.minimum)
    # round 17 recomputed from its factors with numpy
    arrays, _ = band._inputs
    A = arrays[0] + 1j * arrays[1]
    a = arrays[2] + 1j * arrays[3]
    E = arrays[4] + 1j * arrays[5]
    B = arrays[6] + 1j * arrays[7]
    assert A.shape[1:] == (24, 24) and B.shape[1:] == (1, 24)
    # the tires' block: zero between wheels (they meet only through the car)
    assert np.all(A[:, :6, 6:] == 0) and np.all(A[:, 12:18, :12] == 0)
    s = band.factors(17)
    want = (s["Yej_E"] * B) @ np.linalg.solve(
        s["Yjj_A"] * A + s["Yjj_E"] * E, (s["vj_A"] * a)[..., None]
    )
    np.testing.assert_allclose(band.round(17), want[:, :, 0], rtol=1e-9)
    # per wheel: the factors of the four tire blocks are drawn independently
    blocks = [s["Yjj_A"][6 * k : 6 * k + 6, 6 * k : 6 * k + 6] for k in range(4)]
    assert all(np.any(blocks[0] != b) for b in blocks[1:])
    quiet = vehicle_scatter_band(1, 0.0, "both", rounds=10, freq=FREQ[::3], outputs="seat_fl:z")
    np.testing.assert_allclose(quiet.maximum, np.abs(nominal), rtol=1e-12)
    np.testing.assert_allclose(quiet.minimum, np.abs(nominal), rtol=1e-12)


def test_studies_need_a_coherent_road():
    with pytest.raises(FBSError, match="coherent road"):
        vehicle_truncation_map(1, [20, 400], freq=FREQ, tracks=0.5)
    with pytest.raises(FBSError, match="ascending counts"):
        vehicle_truncation_map(1, [60, 20], freq=FREQ)


def test_a_map_split_in_chunks_is_the_map_in_one(monkeypatch):
    """Counts that stop short of the tire's total, in chunks (the all-modes count is
    appended as the reference: it must not slip into the last chunk)."""
    from fbs_core.vehicle import studies

    f = np.arange(13.0, 16.0, 0.5)
    kw = {"outputs": "seat_fl:z", "freq": f}
    whole = vehicle_truncation_map(1, [10, 20, 30], **kw)
    n_j, per = 24, 2  # two counts per chunk: chunks [10, 20], [30]
    monkeypatch.setattr(studies, "_CHUNK_BYTES", per * 3 * 16 * f.size * n_j * n_j)
    split = vehicle_truncation_map(1, [10, 20, 30], **kw)
    np.testing.assert_array_equal(split.n_modes, whole.n_modes)
    np.testing.assert_allclose(split.error, whole.error, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(split.response, whole.response, rtol=1e-12)
