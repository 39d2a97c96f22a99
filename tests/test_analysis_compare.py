"""Comparison of states, pinned states with provenance, and CSV export.

Truth for the level difference: two SDOF oscillators differing only in damping
have mobility peaks ``1/c`` at the same ``w_n``, so the difference at ``f_n`` is
``20 log10(c_b / c_a)`` and tends to 0 dB far below resonance (mobility ``j w / k``).
"""

import json

import numpy as np
import pytest

from fbs_core import FRF, bushing_response, reference_chassis, reference_tire, truncation_map
from fbs_core.analysis import (
    MAX_PINS,
    PinnedState,
    add_pin,
    bode,
    bushing_contributions,
    campbell,
    db_difference,
    delta_cursor,
    digest,
    peak_labels,
    pin_state,
    remove_pin,
    speed_map,
    to_csv,
    truncation_map_difference,
)
from fbs_core.errors import DataFormatError, DOFError, FBSError, FrequencyGridError, QuantityError

M, K = 2.0, 1.1e5
FN = np.sqrt(K / M) / (2 * np.pi)


def sdof(f, c, quantity="mobility"):
    w = 2 * np.pi * np.asarray(f)
    h = 1j * w / (K - M * w**2 + 1j * w * c)
    frf = FRF(f, h[:, None, None], ["m:x"], ["m:x"], "mobility")
    return frf.to(quantity)


def test_db_difference_of_two_dampings():
    f = np.r_[0.01, np.linspace(10.0, 80.0, 141), FN]
    f.sort()
    ca, cb = 20.0, 50.0
    d = db_difference(sdof(f, ca), sdof(f, cb))
    i = int(np.argmin(np.abs(f - FN)))
    assert d.db[i, 0, 0] == pytest.approx(20 * np.log10(cb / ca), abs=1e-9)
    assert d.phase_deg[i, 0, 0] == pytest.approx(0.0, abs=1e-9)  # both real at w_n
    assert abs(d.db[0, 0, 0]) < 1e-6  # stiffness line: same k
    assert d.max_abs_db() == pytest.approx(20 * np.log10(cb / ca), abs=1e-6)
    a = sdof(f, ca)
    twice = db_difference(a.replace(data=2j * a.data), a)
    np.testing.assert_allclose(twice.db, 20 * np.log10(2))
    np.testing.assert_allclose(twice.phase_deg, 90.0)


def test_db_difference_refuses_mismatches():
    f = np.linspace(10.0, 80.0, 50)
    a = sdof(f, 20.0)
    with pytest.raises(FrequencyGridError, match="interpolate"):
        db_difference(a, sdof(f + 0.1, 20.0))
    with pytest.raises(DOFError, match="different outputs"):
        db_difference(a, a.replace(outputs=["n:x"]))
    with pytest.raises(QuantityError, match="quantities"):
        db_difference(a, sdof(f, 20.0, "accelerance"))


def test_truncation_map_difference():
    a = truncation_map(1, [10, 20, 40])
    b = truncation_map(1, [10, 20, 40], coupling="5dof")
    d = truncation_map_difference(a, b)
    np.testing.assert_array_equal(d.diff, a.error - b.error)
    np.testing.assert_array_equal(d.max_diff, a.max_error - b.max_error)
    assert np.abs(d.diff).max() > 0
    assert np.all(truncation_map_difference(a, a).diff == 0)
    np.testing.assert_array_equal(truncation_map_difference(b, a).diff, -d.diff)
    with pytest.raises(FBSError, match="retained-mode counts"):
        truncation_map_difference(a, truncation_map(1, [10, 20]))
    with pytest.raises(FrequencyGridError, match="centre"):
        truncation_map_difference(a, truncation_map(1, [10, 20, 40], step=2.0))
    csv = to_csv(d, {"state_a": "6dof", "state_b": "5dof"}).decode()
    assert "# state_b: 5dof" in csv and "# table: max_diff" in csv


def test_pinned_state_json_round_trip_is_lossless():
    r = bushing_response(1, 40)
    tire, ch = reference_tire(), reference_chassis()
    sources = {"tire": digest(tire), "chassis": digest(ch)}
    p = pin_state("N=40", r, {"harmonic": 1, "n_modes": 40, "coupling": "6dof"}, sources)
    q = PinnedState.from_json(p.to_json())
    assert q.name == "N=40" and q.settings == p.settings and q.sources == sources
    assert q.frfs["result"].allclose(r, rtol=0, atol=0)  # bit-exact
    assert q.created == p.created
    cb = pin_state("campbell", campbell(), {"tire": "reference"})
    cq = PinnedState.from_json(cb.to_json().encode())
    np.testing.assert_array_equal(cq.arrays["freq"][1], cb.arrays["freq"][1])
    assert list(cq.arrays["direction"][1]) == list(cb.arrays["direction"][1])
    assert cq.settings["direction_method"] == "slope"
    assert np.all(np.isnan(cq.arrays["travelling_index"][1]))  # NaN survives JSON
    csv = p.to_csv().decode()
    assert "# setting.n_modes: 40" in csv and f"# source.tire: {sources['tire']}" in csv
    assert "# pin: N=40" in csv


def test_pinned_state_refuses_bad_documents():
    good = json.loads(pin_state("a", bushing_response(1, 40)).to_json())
    for bad, match in [
        ("not json", "not valid JSON"),
        (json.dumps({"format": "other"}), "not a"),
        (json.dumps({**good, "version": 99}), "version 99"),
        (json.dumps({**good, "frfs": {"r": {**good["frfs"]["result"], "freq": [1.0]}}}), "shape"),
        (json.dumps({**good, "name": 3}), "malformed"),
        (b"\xff\xfe", "UTF-8"),
    ]:
        with pytest.raises(DataFormatError, match=match):
            PinnedState.from_json(bad)
    with pytest.raises(FBSError, match="non-empty name"):
        pin_state(" ", bushing_response(1, 40))
    with pytest.raises(FBSError, match="JSON-compatible"):
        pin_state("a", bushing_response(1, 40), {"x": object()})
    with pytest.raises(FBSError, match="cannot pin"):
        pin_state("a", 3.0)


def test_digests_follow_the_content():
    r = bushing_response(1, 40)
    assert digest(r) == digest(r.replace(data=r.data.copy()))
    assert digest(r) != digest(r.replace(data=r.data * (1 + 1e-15)))
    assert digest(b"abc") == digest(bytearray(b"abc")) != digest(b"abd")
    assert digest(reference_tire()).startswith("sha256:")
    with pytest.raises(FBSError, match="cannot digest"):
        digest(3.0)


def test_up_to_four_pins():
    r = bushing_response(1, 40)
    pins = ()
    for i in range(MAX_PINS):
        pins = add_pin(pins, pin_state(f"s{i}", r))
    assert len(pins) == 4
    with pytest.raises(FBSError, match="at most 4"):
        add_pin(pins, pin_state("s9", r))
    with pytest.raises(FBSError, match="already named"):
        add_pin(pins[:3], pin_state("s0", r))
    pins = remove_pin(pins, "s1")
    assert [p.name for p in pins] == ["s0", "s2", "s3"]
    with pytest.raises(FBSError, match="no pinned state named"):
        remove_pin(pins, "s1")


def test_csv_export_of_every_dataset():
    r = bushing_response(1, 40)
    prov = {"harmonic": 1, "source.tire": digest(reference_tire())}
    c = bushing_contributions(1, 40)
    for ds, table in [
        (c, "# table: terms"),
        (campbell(), "# table: harmonic_line"),
        (speed_map(1, 40, speeds=[30.0, 60.0]), "# table: level_db"),
        (bode(r), "# table: phase_deg"),
        (delta_cursor(r.sel(outputs="bushing:z"), 20.0, 30.0), "# table: cursor_level_db"),
        (peak_labels(r, "bushing:z", harmonic=1), "# table: freq"),
        (db_difference(r, r), "# table: db"),
        (r, "# table: frf"),
    ]:
        text = to_csv(ds, prov).decode()
        assert "# harmonic: 1" in text and "# source.tire: sha256:" in text, type(ds)
        assert table in text, type(ds)
    # the exported terms add up to the exported total (read back from the CSV)
    text = to_csv(c).decode()
    terms = text.split("# table: terms\n")[1].split("\n\n")[0].splitlines()[1:]
    row = [ln.split(",") for ln in terms[:6]]  # first line, bushing:x, six interface DOFs
    s = sum(float(x[3]) + 1j * float(x[4]) for x in row)
    assert s == pytest.approx(r.data[0, 0, 0], rel=1e-12)
    with pytest.raises(FBSError, match="cannot export"):
        to_csv(3.0)
