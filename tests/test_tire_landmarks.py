"""The landmark table (thesis next to this tire, issue 14): structure and mechanisms.

Truth: the thesis' hub peaks (17 and 38 Hz, section 4.1.2) that this tire reproduces
from physics with the tread sticking; the variants measure what each addition does:
without asymmetry nothing lateral peaks, and the slip of the tread (not the stick
model) is what removes the 38 Hz peak of the free hub along case 1.
"""

import numpy as np

from fbs_core.tire.landmarks import THESIS, VARIANTS, landmark_table


def test_landmark_table():
    t = landmark_table()
    assert t.keys == tuple(THESIS)
    assert set(t.columns) == {"reference"} | set(VARIANTS)
    for col in t.columns.values():
        assert len(col) == len(t.keys)
    ref, sym, stick = (t.measured[k] for k in ("reference", "no asymmetry", "no slip"))
    for m in (ref, sym, stick):
        assert abs(m.hub_peaks["z"][0] - 17.0) < 1.5
        assert len(m.table_160) == 7 and all(n % 10 == 0 for n in m.table_160)
    assert np.any(np.abs(np.array(stick.hub_peaks["x"]) - 38.0) < 2.5)
    assert not np.any(np.abs(np.array(ref.hub_peaks["x"]) - 38.0) < 2.5)
    assert sym.hub_peaks["y"] == ()  # nothing physical to peak on a symmetric tire
    assert ref.hub_peaks["y"] != ()
    assert "thesis" in t.text() and "no slip" in t.text()


def test_mechanism_variants_switch_one_thing_each():
    """Each mechanism variant differs from the reference in the one physics it measures."""
    from fbs_core.tire import DEFAULT_PARAMETERS
    from fbs_core.tire.landmarks import MECHANISMS, MechanismTable, mechanism_variants
    from fbs_core.tire.ring import patch_length

    v = mechanism_variants()
    ref = v["loaded (reference)"]
    assert ref == DEFAULT_PARAMETERS and set(v) == {"loaded (reference)"} | set(MECHANISMS)
    assert v["round belt"].static_deflection == 0
    assert v["round belt, loaded L_c"].L_c == patch_length(ref) < ref.L_c
    assert v["lumped patch load"].patch_wave == 0
    assert v["orders x2"].n_belt > 1.9 * ref.n_belt
    row = {"table_130": (1,) * 7, "table_160": (2,) * 7, "case5_z_160": 3}
    text = MechanismTable({"x": row | {"n_modes": 400, "patch_length": 0.1}}).text()
    assert "thesis" in text and " 270 " in text and "0.100" in text
