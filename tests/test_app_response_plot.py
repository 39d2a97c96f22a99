"""The coupled-response plot as a test lab's FRF display (issue 29): overlaid DOFs, the
level axis, two cursors with a readout and snap-to-peak, all in the link.

Truth: the overlaid curve of a DOF is the response view's curve when that DOF is the
selected one (a second state of the store); the linear axis is the modulus of the
exported complex response; a cursor on a grid line reads that line's level; a snapped
cursor stands on a local maximum of the curve, next to the nearest peak line that
``scipy.signal.find_peaks`` finds on the grid.
"""

from __future__ import annotations

import numpy as np
import pytest
from panel.io.location import Location
from scipy.signal import find_peaks

from app.main import sync_url
from app.results.response_plot import PEAK_PROMINENCE_DB
from app.state import DashboardState
from app.store import Results

H = 3  # 24.6-98.3 Hz


@pytest.fixture(scope="module")
def store():
    s = Results(background=False)
    s.state.case.param.update(harmonic=H, n_modes=60, dof="z")
    return s


def _plot(store, **plot):
    store.state.plot.param.update(**plot)
    return store.response_plot


def test_an_overlaid_dof_is_that_dofs_own_response(store):
    p = _plot(store, overlay=["x", "z"], level_scale="dB", cursor1=0.0, cursor2=0.0)
    curves = {c["key"]: c for c in p.draw["curves"]}
    assert set(curves) == {"reference", "truncated", "overlay_x"}  # z is shown already
    store.state.case.dof = "x"
    try:
        own = store.response.columns["truncated_dB"]
    finally:
        store.state.case.dof = "z"
    np.testing.assert_array_equal(curves["overlay_x"]["y"], own)
    assert p.meta["overlaid DOFs (N modes)"] == "bushing:x"
    np.testing.assert_array_equal(p.columns["bushing_x_dB"], own)


def test_the_linear_axis_is_the_modulus_of_the_response(store):
    p = _plot(store, overlay=[], level_scale="linear", cursor1=0.0, cursor2=0.0)
    r = store.response.columns
    ys = {c["key"]: c["y"] for c in p.draw["curves"]}
    np.testing.assert_allclose(ys["truncated"], np.abs(r["truncated"]), rtol=1e-12)
    np.testing.assert_allclose(ys["reference"], np.abs(r["reference"]), rtol=1e-12)
    assert p.draw["y_label"].startswith("|v| (") and "dB" not in p.draw["y_label"]
    assert p.meta["level axis"].startswith("linear")


def test_cursors_on_grid_lines_read_those_lines(store):
    f = store.response.columns["freq_Hz"]
    lv = store.response.columns["truncated_dB"]
    i, j = 20, 90
    p = _plot(store, level_scale="dB", overlay=[], snap=False, cursor1=f[i], cursor2=f[j])
    rows = {row[0]: row for row in p.draw["readout"]["rows"]}
    row = rows["bushing:z, N modes"]
    assert row[1] == f"{lv[i]:.2f} dB" and row[2] == f"{lv[j]:.2f} dB"
    assert row[3] == f"{lv[j] - lv[i]:+.2f} dB"
    assert f"f2 - f1 = {f[j] - f[i]:.2f} Hz" in p.draw["readout"]["header"]
    assert [c["y"] for c in p.draw["cursors"]] == pytest.approx([lv[i], lv[j]], abs=1e-9)
    # the linear readout: magnitudes and their ratio
    p = _plot(store, level_scale="linear")
    row = {row[0]: row for row in p.draw["readout"]["rows"]}["bushing:z, N modes"]
    mag = np.abs(store.response.columns["truncated"])
    assert float(row[1]) == pytest.approx(mag[i], rel=1e-3)
    assert float(row[3].removeprefix("× ")) == pytest.approx(mag[j] / mag[i], rel=1e-3)


def test_a_snapped_cursor_stands_on_the_nearest_peak(store):
    f = store.response.columns["freq_Hz"]
    lv = store.response.columns["truncated_dB"]
    lines, _ = find_peaks(lv, prominence=PEAK_PROMINENCE_DB)
    assert lines.size >= 2
    for asked in (f[5], 0.5 * (f[lines[0]] + f[lines[1]]) + 0.3, f[-3]):
        p = _plot(store, level_scale="dB", snap=True, cursor1=float(asked), cursor2=0.0)
        (cur,) = p.draw["cursors"]
        nearest = lines[np.argmin(np.abs(f[lines] - asked))]
        step = f[1] - f[0]
        assert abs(cur["f"] - f[nearest]) <= step, (asked, cur["f"], f[nearest])
        # a local maximum: at least the level of the lines two steps either side
        assert cur["y"] >= max(lv[nearest - 2], lv[nearest + 2])
        assert "snapped to the peak nearest" in p.meta["cursor 1"]
    _plot(store, snap=False)


def test_a_cursor_outside_the_band_says_so(store):
    p = _plot(store, level_scale="dB", snap=False, cursor1=300.0, cursor2=0.0)
    assert "outside" in p.meta["cursor 1"] and "Hz" in p.meta["cursor 1"]
    assert p.draw["cursors"][0]["y"] is None
    _plot(store, cursor1=0.0)


def test_the_plot_settings_are_in_the_link():
    s = DashboardState()
    loc = Location(search="?over=%5B%22x%22%2C%22rz%22%5D&lvl=linear&mc1=30&mc2=40.5&snap=true")
    sync_url(s, loc)
    p = s.plot
    assert (p.overlay, p.level_scale, p.cursor1, p.cursor2, p.snap) == (
        ["x", "rz"],
        "linear",
        30.0,
        40.5,
        True,
    )
    p.param.update(overlay=["y"], cursor1=12.5)
    other = DashboardState()
    sync_url(other, Location(search=loc.search))
    assert other.plot.overlay == ["y"] and other.plot.cursor1 == 12.5
    # a bad value of a link is ignored, the others apply
    third = DashboardState()
    sync_url(third, Location(search="?over=%5B%22w%22%5D&lvl=log&mc1=35"))
    assert (third.plot.overlay, third.plot.level_scale, third.plot.cursor1) == ([], "dB", 35.0)


def test_clicks_place_cursor_1_then_2_rounded_and_within_range():
    from app.views.common import tap_cursor

    p = DashboardState().plot
    k = tap_cursor(p, 40.004, 1)
    assert (p.cursor1, k) == (40.0, 2)
    k = tap_cursor(p, None, k)  # a click on no frequency places nothing
    assert (p.cursor2, k) == (0.0, 2)
    k = tap_cursor(p, 5000.0, k)
    assert (p.cursor2, k) == (1000.0, 1)
    assert tap_cursor(p, -3.0, k) == 2 and p.cursor1 == 0.01
