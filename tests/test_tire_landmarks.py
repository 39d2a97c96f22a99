"""The landmark table (thesis next to this tire, issue 14): structure and the hub peaks.

Truth: the thesis' hub peaks (17 and 38 Hz, section 4.1.2) that the reference tire
reproduces from physics, and a variant whose asymmetry is switched off measures the
same in-plane landmarks (the asymmetry adds, it does not move the in-plane peaks).
"""

import numpy as np

from fbs_core.tire.landmarks import THESIS, VARIANTS, landmark_table


def test_landmark_table():
    t = landmark_table()
    assert t.keys == tuple(THESIS)
    assert set(t.columns) == {"reference"} | set(VARIANTS)
    for col in t.columns.values():
        assert len(col) == len(t.keys)
    ref = t.measured["reference"]
    assert abs(ref.hub_peaks["z"][0] - 17.0) < 1.5
    assert np.any(np.abs(np.array(ref.hub_peaks["x"]) - 38.0) < 2.5)
    assert len(ref.table_160) == 7 and all(n % 10 == 0 for n in ref.table_160)
    sym = t.measured["no asymmetry"]
    assert sym.hub_peaks["z"] == ref.hub_peaks["z"]
    assert sym.hub_peaks["y"] == ()  # nothing physical to peak on a symmetric tire
    assert ref.hub_peaks["y"] != ()
    assert "thesis" in t.text() and "no asymmetry" in t.text()
