"""The first-order band overlaid on the dashboard's scatter band (issue 32): computed only
while switched on, of the shown band's settings, drawn with its own legend, reported.

Truth: :func:`fbs_core.first_order_band` called directly with the band's settings, and the
edges ``|v| -+ k std`` with ``k`` the Gaussian quantile written here (not scipy's)."""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core
from app.report.session import report_data
from app.state import URL_KEYS
from app.store import Results, depends
from app.views.scatter import FIRST_ORDER_LEGEND, ScatterBandView

#: Gaussian quantiles: the 10-90 % and 5-95 % bands (standard tables)
Z = {80: 1.2815515655446004, 90: 1.6448536269514722}


@pytest.fixture(scope="module")
def store():
    s = Results(background=False)
    st = s.state
    st.case.param.update(harmonic=1, n_modes=60, dof="x")
    st.noise.param.update(noise=5.0, target="tire", rounds=40, seed=3, percentile=80)
    s.request_band(wait=True)
    return s


def test_the_overlay_is_the_core_first_order_band_of_the_shown_band(store):
    st = store.state
    assert store.first_order is None  # off: never computed
    view = ScatterBandView(store=store)
    view.__panel__()
    assert list(view._first.data["freq"]) == []
    st.noise.first_order = True
    r = store.first_order
    fo = fbs_core.first_order_band(1, noise=0.05, target="tire", n_modes=60, coupling="6dof")
    j = fo.dofs.index("bushing:x")
    v, std = np.abs(fo.reference[:, j]), fo.std[:, j]
    np.testing.assert_array_equal(r.columns["freq_Hz"], store.band.result.freq)
    np.testing.assert_allclose(r.columns["std"], std, rtol=1e-12)
    low = 20 * np.log10(np.maximum(v - Z[80] * std, 0))
    np.testing.assert_allclose(r.columns["first_order_low_dB"], low, rtol=1e-9)
    np.testing.assert_allclose(r.columns["first_order_high_dB"], 20 * np.log10(v + Z[80] * std))
    # the reference of the linearisation is the band's unpolluted response
    np.testing.assert_allclose(v, np.abs(store.band.result.reference[:, j]), rtol=1e-12)
    # drawn on the band's plot, the legend saying which is which
    np.testing.assert_allclose(view._first.data["high"], r.columns["first_order_high_dB"])
    items = {i.label.value: i.visible for i in view._fig.legend[0].items}
    (label,) = [k for k in items if k.startswith("first order")]
    assert items[label] and "1.282 std" in label and "10-90 %" in label
    assert any(k.startswith("min-max over 40 rounds") for k in items)
    # another percentile band: another k
    st.noise.percentile = 90
    np.testing.assert_allclose(
        store.first_order.columns["first_order_high_dB"], 20 * np.log10(v + Z[90] * std)
    )
    assert "5-95" in store.first_order.meta["percentiles"]
    # the report holds it as a section of its own, with the state's switch in its settings
    rep = report_data(store)
    (sec,) = [x for x in rep.extra if x.key == "first_order"]
    np.testing.assert_allclose(sec.curves["first order high"], 20 * np.log10(v + Z[90] * std))
    assert rep.settings["first_order"] is True
    # switched off: the overlay and its legend go, the report leaves the section out
    st.noise.first_order = False
    assert list(view._first.data["freq"]) == []
    items = {i.label.value: i.visible for i in view._fig.legend[0].items}
    assert items[FIRST_ORDER_LEGEND] is False
    assert all(x.key != "first_order" for x in report_data(store).extra)
    st.noise.percentile = 80


def test_the_switch_is_state_in_the_link_and_declared():
    assert URL_KEYS["noise"]["first_order"] == "fo"
    assert "first_order" in depends("first_order")
    assert {"noise", "target", "harmonic", "n_modes", "coupling"} <= depends("first_order")
    assert "rounds" in depends("first_order")  # through the band it is made of
