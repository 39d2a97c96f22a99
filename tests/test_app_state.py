"""Dashboard state without a browser: widgets -> state, bounds, URL keys, CSV export."""

import numpy as np
import pytest

from app.export import read_csv, to_csv
from app.state import (
    DIRECTIONS,
    MODE_COUNTS,
    URL_KEYS,
    CaseState,
    DashboardState,
    NoiseState,
    TruncationState,
)
from app.views.controls import Controls


@pytest.fixture
def controls():
    return Controls(state=DashboardState())


def test_every_control_of_the_issue_exists_with_its_range():
    c, n, t = CaseState(), NoiseState(), TruncationState()
    assert c.param.harmonic.bounds == (1, 7)
    assert MODE_COUNTS == tuple(range(10, 401, 10))
    assert list(c.param.n_modes.objects) == list(MODE_COUNTS)
    assert list(c.param.dof.objects) == ["x", "y", "z", "rx", "ry", "rz"]
    assert set(c.param.coupling.objects) == {"6dof", "5dof"}
    # noise: slider 0-10 %, typed values finer (0.01) and wider (up to 100 %) allowed
    assert n.param.noise.softbounds == (0.0, 10.0)
    n.noise = 0.25
    n.noise = 25.0
    assert set(n.param.target.objects) == {"tire", "chassis", "both"}
    n.frequency_dependent = True
    n.rounds = 100
    assert t.threshold == 20.0 and t.f_max == 160.0


@pytest.mark.parametrize(
    ("obj", "name", "value"),
    [
        (CaseState, "harmonic", 0),
        (CaseState, "harmonic", 8),
        (CaseState, "n_modes", 55),
        (CaseState, "n_modes", 410),
        (CaseState, "dof", "q"),
        (CaseState, "coupling", "4dof"),
        (NoiseState, "noise", -1.0),
        (NoiseState, "noise", 101.0),
        (NoiseState, "noise", 100.0),  # fbs_core needs p < 1: a factor 1 - p of zero
        (NoiseState, "seed", -1),
        (NoiseState, "seed", 2**32),
        (NoiseState, "target", "road"),
        (NoiseState, "rounds", 0),
        (TruncationState, "threshold", 0.0),
    ],
)
def test_out_of_range_values_are_rejected(obj, name, value):
    with pytest.raises(ValueError):
        setattr(obj(), name, value)


def test_every_accepted_noise_level_and_seed_runs_in_the_library():
    import fbs_core
    from app.state import MAX_NOISE_PCT, MAX_SEED

    n = NoiseState(noise=MAX_NOISE_PCT, seed=MAX_SEED)  # the largest values a user can set
    band = fbs_core.scatter_band(1, noise=n.noise / 100, rounds=5, seed=n.seed)
    assert band.rounds == 5 and np.all(band.maximum >= band.minimum)


def test_one_bad_url_value_keeps_the_valid_ones():
    from panel.io.location import Location

    from app.main import sync_url

    s = DashboardState()
    # h=9 is out of range and comes first; the values after it must still apply
    sync_url(s, Location(search="?h=9&N=150&dof=x&noise=100&seed=5&thr=12&map=nonsense"))
    assert (s.case.harmonic, s.case.n_modes, s.case.dof) == (1, 150, "x")
    assert (s.noise.noise, s.noise.seed) == (10.0, 5)
    assert s.truncation.threshold == 12.0 and s.truncation.map_mode == "selected DOF"


def test_a_link_made_before_the_rename_opens_the_chassis_target():
    from panel.io.location import Location

    from app.main import sync_url

    s = DashboardState()
    sync_url(s, Location(search="?target=vehicle&seed=5"))
    assert (s.noise.target, s.noise.seed) == ("chassis", 5)
    with pytest.raises(ValueError):
        s.noise.target = "wheel"
    assert s.noise.target == "chassis"


def test_single_round_stays_inside_the_batch():
    n = NoiseState(rounds=1000, single_round=999)
    n.rounds = 100
    assert n.single_round == 99
    assert n.param.single_round.bounds == (0, 99)
    with pytest.raises(ValueError):
        n.single_round = 100


@pytest.mark.parametrize(
    ("key", "value", "group", "name"),
    [
        ("case.harmonic", 5, "case", "harmonic"),
        ("case.n_modes", 150, "case", "n_modes"),
        ("case.dof", "rx", "case", "dof"),
        ("case.coupling", "5dof", "case", "coupling"),
        ("case.show_uncoupled", True, "case", "show_uncoupled"),
        ("truncation.threshold", 10.0, "truncation", "threshold"),
        ("truncation.f_max", 130.0, "truncation", "f_max"),
        ("truncation.map_mode", "max over 6 DOFs", "truncation", "map_mode"),
        ("noise.noise", 2.5, "noise", "noise"),
        ("noise.target", "tire", "noise", "target"),
        ("noise.frequency_dependent", True, "noise", "frequency_dependent"),
        ("noise.rounds", 500, "noise", "rounds"),
        ("noise.seed", 7, "noise", "seed"),
        ("noise.single_round", 42, "noise", "single_round"),
        ("noise.percentile", 50, "noise", "percentile"),
        ("plot.overlay", ["x", "rz"], "plot", "overlay"),
        ("plot.level_scale", "linear", "plot", "level_scale"),
        ("plot.cursor1", 42.5, "plot", "cursor1"),
        ("plot.cursor2", 61.0, "plot", "cursor2"),
        ("plot.snap", True, "plot", "snap"),
    ],
)
def test_widgets_drive_the_state(controls, key, value, group, name):
    w = controls.widgets()[key]
    # a typed number's widget is a text field: the text a person types
    w.value = f"{value:g}" if key in controls.fields else value
    assert getattr(getattr(controls.state, group), name) == value


def test_state_drives_the_widgets(controls):
    controls.state.case.dof = "ry"
    assert controls.widgets()["case.dof"].value == "ry"


def test_url_keys_cover_every_state_parameter_once():
    s = DashboardState()
    seen = []
    for group, keys in URL_KEYS.items():
        obj = getattr(s, group)
        # negative precedence: not a control (the session's models), not in the URL
        params = {p for p in obj.param if p != "name" and (obj.param[p].precedence or 0) >= 0}
        assert set(keys) == params, group
        seen += list(keys.values())
    assert len(seen) == len(set(seen))


def test_sessions_do_not_share_state():
    a, b = DashboardState(), DashboardState()
    a.case.harmonic = 3
    assert b.case.harmonic == 1
    assert DIRECTIONS == ("x", "y", "z", "rx", "ry", "rz")


def test_csv_round_trip_with_metadata_header():
    f = np.array([10.0, 10.5, 11.0])
    v = np.array([1 + 2j, 3 - 1j, 1e-9j])
    db = np.array([-93.123456789012345, 1.0 / 3.0, 0.0])
    text = to_csv(
        {"freq_Hz": f, "level_dB": db, "v": v}, {"harmonic": 1, "N": 50, "seed": 0}, "coupled"
    )
    assert text.startswith("# tire-fbs dashboard export (coupled)\n")
    meta, cols = read_csv(text)
    units = meta.pop("Re/Im columns")  # complex columns state their parts and unit (issue 29)
    assert meta == {"harmonic": "1", "N": "50", "seed": "0"}
    assert "v_re, v_im" in units and "unit" in units
    assert list(cols) == ["freq_Hz", "level_dB", "v_re", "v_im"]
    np.testing.assert_array_equal(cols["level_dB"], db)  # 17 digits: exact round trip
    np.testing.assert_array_equal(cols["v_re"] + 1j * cols["v_im"], v)


def test_csv_rejects_bad_columns_and_headers():
    with pytest.raises(ValueError, match="'b' has 2 rows, expected 3"):
        to_csv({"a": np.zeros(3), "b": np.zeros(2)}, {}, "x")
    with pytest.raises(ValueError, match="must be 1-D"):
        to_csv({"a": np.zeros((3, 2))}, {}, "x")
    with pytest.raises(ValueError, match="single line"):
        to_csv({"a": np.zeros(3)}, {"note": "two\nlines"}, "x")


def test_shared_cache_computes_a_missing_entry_once_for_all_threads():
    """Concurrent sessions asking for the same missing result: one computation, and every
    caller gets that same (immutable) object; a failure is not cached."""
    import threading
    import time

    from app.compute import shared_cache

    calls = []

    @shared_cache(maxsize=4)
    def slow(x):
        calls.append(x)
        time.sleep(0.2)
        if x < 0:
            raise ValueError("negative")
        return object()

    results = [None] * 8
    start = threading.Barrier(8)

    def ask(i):
        start.wait()
        results[i] = slow(1)

    threads = [threading.Thread(target=ask, args=(i,)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert calls == [1]
    assert all(r is results[0] for r in results)
    assert slow(2) is not results[0] and calls == [1, 2]
    for _ in range(2):
        with pytest.raises(ValueError, match="negative"):
            slow(-1)
    assert calls.count(-1) == 2
