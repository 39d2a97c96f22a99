"""The truncation map hands out the coupled response of any of its rows (``response_for``)."""

from __future__ import annotations

import numpy as np

import fbs_core
from fbs_core import studies


def test_response_for_a_row_is_the_direct_prediction():
    m = studies.truncation_map(2, n_modes=[20, 40, 60])
    order = [m.dofs.index(f"bushing:{d}") for d in fbs_core.DIRECTIONS]
    # a second path: eq. 4.1 computed directly for that N
    want = fbs_core.bushing_response(2, n_modes=40, freq=m.freq).data[:, :, 0]
    np.testing.assert_allclose(m.response_for(40)[:, order], want, rtol=1e-9)
    ref = fbs_core.bushing_response(2, freq=m.freq).data[:, :, 0]
    np.testing.assert_allclose(m.response_for(None)[:, order], ref, rtol=1e-9)
    assert m.response_for(m.n_modes_total) is m.reference
    assert m.response_for(50) is None  # not a row: compute it directly
