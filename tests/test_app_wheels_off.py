"""A wheel whose road input is off contributes exactly nothing: it has no level (20 log10 0
is not a number), so no curve, no legend entry and no level column shows it; the driven
wheels' levels are the library's ``by_wheel`` and the axis spans only real levels.

Truth: ``fbs_core.vehicle.vehicle_response(...).by_wheel`` called directly.
"""

import numpy as np
import pytest

import fbs_core
from app.report.data import ExtraSection
from app.store import Results
from app.views.wheels import WheelContributionsView
from fbs_core.vehicle import WHEELS, vehicle_response
from fbs_core.vocabulary import magnitude_db

ON = ("fl", "rr")


@pytest.fixture(scope="module")
def car():
    store = Results(background=False)
    store.state.noise.rounds = 20
    store.state.case.param.update(
        scope="vehicle", harmonic=2, n_modes=60, dof="z", point="bushing_rl", wheels=list(ON)
    )
    return store


def test_an_off_wheel_has_no_level_column_and_the_driven_ones_are_the_librarys(car):
    r = car.wheel_contributions
    cols = r.columns
    for w in WHEELS:
        assert (f"{w}_dB" in cols) == (w in ON), w
    f = fbs_core.harmonic(2).frequencies()
    lib = vehicle_response(2, 60, f, outputs="bushing_rl", wheels=ON)
    e = list(lib.outputs).index("bushing_rl:z")
    bw = lib.by_wheel(lib.components[0])
    for w in ON:
        k = WHEELS.index(w)
        np.testing.assert_allclose(cols[f"{w}_dB"], magnitude_db(bw.data[:, e, k]), rtol=1e-10)
    # the off wheels' complex terms stay (exact zeros: the four add up to the response)
    assert all(np.all(cols[f"{w}_in_phase"] == 0) for w in WHEELS if w not in ON)


def test_the_report_section_draws_no_level_of_an_off_wheel(car):
    sec = ExtraSection.of_result("wheel_contributions", car.wheel_contributions)
    assert sorted(sec.curves) == sorted(["total", *ON])
    lowest = min(float(np.min(c)) for c in sec.curves.values())
    assert lowest > -300.0, lowest  # a level, not the -600 dB floor of an exact zero


def test_the_view_hides_an_off_wheel_and_its_legend_entry(car):
    view = WheelContributionsView(store=car)
    view.__panel__()
    view._apply()
    fig = view._fig
    data = view._src.data
    for w in WHEELS:
        y = np.asarray(data[w], float)
        if w in ON:
            assert np.all(np.isfinite(y)) and y.min() > -300.0
        else:
            assert not np.any(np.isfinite(y)), w  # nothing for the axis to reach
    shown = {i.label.value for i in fig.legend[0].items if i.visible}
    assert shown == {"road under FL", "road under RR", "total (N modes)"}
    for rdr in fig.renderers:
        col = rdr.glyph.y
        if col in WHEELS:
            assert rdr.visible == (col in ON), col
