"""The dashboard in vehicle scope (issue 31): state and link, published numbers, exports.

Truth: the library called here on its own (:func:`fbs_core.vehicle.vehicle_response`,
:func:`~fbs_core.vehicle.vehicle_truncation_map`, :func:`~fbs_core.vehicle.
vehicle_scatter_band`), never the app's caches; a corner's results from a fresh session.
"""

from __future__ import annotations

import urllib.parse

import numpy as np
import pytest
from panel.io.location import Location

import fbs_core
from app.main import sync_url
from app.report.session import report_data
from app.state import CORNER_ROUNDS, VEHICLE_ROUNDS, DashboardState
from app.store import Results
from fbs_core.vehicle import (
    WHEELS,
    vehicle_response,
    vehicle_scatter_band,
    vehicle_truncation_map,
)
from fbs_core.vocabulary import magnitude_db


def _state_of(query: dict) -> DashboardState:
    s = DashboardState()
    sync_url(s, Location(search="?" + urllib.parse.urlencode(query)))
    return s


def test_a_link_sets_the_car():
    c = _state_of(
        {"scope": "vehicle", "wheels": '["rr","fl"]', "tracks": "coherence", "coh": "-0.3",
         "point": "seat_fl"}
    ).case  # fmt: skip
    assert (c.scope, c.wheels, c.tracks, c.coherence, c.point) == (
        "vehicle", ["fl", "rr"], "coherence", -0.3, "seat_fl"
    )  # fmt: skip


HOSTILE = [
    ("scope", "truck"),
    ("scope", "<img src=x>"),
    ("wheels", "fl"),  # not a list
    ("wheels", '["fl","fl"]'),  # repeated
    ("wheels", '["fl","xx"]'),
    ("wheels", "[1]"),
    ("wheels", '{"fl": 1}'),
    ("tracks", "sideways"),
    ("coh", "2"),
    ("coh", "-1.5"),
    ("coh", "true"),
    ("coh", "nan"),
    ("point", "seat_xx"),
    ("point", "<script>"),
]


@pytest.mark.parametrize(("key", "value"), HOSTILE)
def test_hostile_values_of_the_car_in_a_link_are_refused(key, value):
    c = _state_of({key: value, "h": "3"}).case
    assert (c.scope, c.wheels, c.tracks, c.coherence, c.point) == (
        "corner", list(WHEELS), "in phase", 0.5, "bushing_rl"
    )  # fmt: skip
    assert c.harmonic == 3  # the link's valid values still apply


def test_the_scope_moves_a_default_round_count_to_the_other_scopes():
    s = DashboardState()
    s.case.scope = "vehicle"
    assert s.noise.rounds == VEHICLE_ROUNDS
    s.case.scope = "corner"
    assert s.noise.rounds == CORNER_ROUNDS
    s.noise.rounds = 400  # a count of the user's stays
    s.case.scope = "vehicle"
    assert s.noise.rounds == 400


def _level(r, out: str) -> np.ndarray:
    return r.level[:, list(r.outputs).index(out)]


@pytest.fixture(scope="module")
def car():
    store = Results(background=False)
    c = store.state.case
    store.state.noise.rounds = 30
    c.param.update(
        scope="vehicle", harmonic=2, n_modes=60, dof="y", point="seat_fl", wheels=["fl", "rr"]
    )
    return store


def test_the_published_response_is_the_librarys(car):
    f = fbs_core.harmonic(2).frequencies()
    kw = {"outputs": "seat_fl", "wheels": ("fl", "rr")}
    ref, tr = vehicle_response(2, None, f, **kw), vehicle_response(2, 60, f, **kw)
    cols = car.response.columns
    np.testing.assert_allclose(cols["freq_Hz"], f)
    np.testing.assert_allclose(
        cols["reference_dB"], magnitude_db(_level(ref, "seat_fl:y")), rtol=1e-12
    )
    np.testing.assert_allclose(
        cols["truncated_dB"], magnitude_db(_level(tr, "seat_fl:y")), rtol=1e-12
    )
    j = list(tr.outputs).index("seat_fl:y")
    np.testing.assert_allclose(cols["truncated_in_phase"], tr.response.data[:, j, 0], rtol=1e-12)
    # the per-wheel view: the two driven wheels' contributions add up to the response
    w = car.wheel_contributions.columns
    np.testing.assert_allclose(w["total_dB"], cols["truncated_dB"], rtol=1e-12)
    total = sum(w[f"{x}_in_phase"] for x in WHEELS)
    np.testing.assert_allclose(total, cols["truncated_in_phase"], rtol=1e-10, atol=1e-15)
    assert np.all(w["fr_in_phase"] == 0) and np.all(w["rl_in_phase"] == 0)
    assert car.response.meta["wheels (road input on)"] == "FL RR"
    for r in (car.response, car.error_map, car.wheel_contributions):
        assert "seat_fl" in r.filename and "wflrr_inphase" in r.filename


def test_the_published_map_and_band_are_the_librarys(car):
    m = vehicle_truncation_map(
        2, np.arange(10, 400, 10), outputs="seat_fl", wheels=("fl", "rr"), tracks="in phase"
    )
    d = car.error_map.draw["map"]
    np.testing.assert_allclose(d["error_pct"], 100 * m.dof_error("seat_fl:y"), rtol=1e-12)
    assert car.error_map.draw["suggested_n"] == m.suggest(0.2, 160.0, "seat_fl:y")
    band = car.band_now()
    lib = vehicle_scatter_band(
        2, 0.1, "both", 30, seed=0, outputs="seat_fl", wheels=("fl", "rr"), n_modes=60,
        percentiles=band.result.q,
    )  # fmt: skip
    j = lib.dofs.index("seat_fl:y")
    np.testing.assert_allclose(
        car.band_curves.columns["maximum_dB"], magnitude_db(lib.maximum[:, j]), rtol=1e-12
    )
    assert car.band_curves.filename.startswith("vehicle_scatter_band_h2_N60_seat_fl_y")


def test_a_partial_coherence_gives_two_components_and_keeps_the_studies_to_coherent_roads():
    store = Results(background=False)
    store.state.noise.rounds = 20
    c = store.state.case
    c.param.update(scope="vehicle", tracks="coherence", coherence=0.25, point="bushing_rl")
    f = fbs_core.harmonic(1).frequencies()
    r = vehicle_response(1, 50, f, tracks=0.25, outputs="bushing_rl")
    cols = store.response.columns
    np.testing.assert_allclose(
        cols["truncated_dB"], magnitude_db(_level(r, "bushing_rl:z")), rtol=1e-12
    )
    assert {"truncated_in_phase", "truncated_anti_phase"} <= set(cols)
    assert "coherent road" in store.message
    assert store.response.meta["tracks (right against left)"] == "coherence 0.25"
    rep = report_data(store, url="http://127.0.0.1/main")
    assert rep.truncation is None and rep.response_dof == "bushing_rl:z"
    assert rep.settings["coherence"] == 0.25


def test_the_corner_is_bit_identical_after_the_car():
    fresh = Results(background=False)
    store = Results(background=False)
    c = store.state.case
    c.param.update(scope="vehicle", wheels=["rl"], tracks="anti-phase", point="seat_rr")
    c.scope = "corner"
    for name in ("response", "error_map", "suggested"):
        a, b = getattr(fresh, name), getattr(store, name)
        assert a.filename == b.filename and list(a.columns) == list(b.columns)
        for k in a.columns:
            np.testing.assert_array_equal(a.columns[k], b.columns[k])
    assert "wheels" not in report_data(store).settings
