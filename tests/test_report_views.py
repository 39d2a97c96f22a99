"""The views the user looked at appear in the report (issue 29): the contributions, the
phase view's peaks, the Campbell diagram and the speed map, as the session published them
for the current settings, whichever tab is shown when the report is asked for; a view of
settings left behind does not.

Truth: the contributions' total is the coupled-response view's own curve (eq. 4.1 summed
term by term against the response computed by the core directly); the speed map's line at
the harmonic's speeds is ``f = v / lambda``.
"""

from __future__ import annotations

import io

import numpy as np
import pytest
from pypdf import PdfReader

import fbs_core
from app.report import build_html, build_pdf
from app.report.session import report_data
from app.report.summary import report_summary
from app.store import Results

TABS = ("contributions", "phase", "speed")
SECTIONS = ("contributions", "phase", "peak_modes", "speed_map", "campbell")


@pytest.fixture(scope="module")
def store():
    res = Results()
    res.state.case.param.update(harmonic=3, n_modes=40)
    res.state.noise.rounds = 30
    for tab in TABS:  # the user opens each tab, then closes the card
        res.state.analysis.tab = tab
    res.state.analysis.tab = ""
    yield res
    res.close()


def test_every_tab_looked_at_is_a_section_of_the_report_with_its_plot(store):
    data = report_data(store)
    keys = [e.key for e in data.extra]
    assert all(k in keys for k in SECTIONS), keys
    _, html = build_html(data)
    for key in ("contributions", "phase", "speed_map", "campbell"):
        assert f'id="figure-{key}"' in html, key
    assert 'id="peak_modes"' in html
    _, pdf = build_pdf(data)
    text = "\n".join(p.extract_text() for p in PdfReader(io.BytesIO(pdf)).pages)
    assert "Campbell diagram" in text and "Bushing level vs speed and frequency" in text
    assert "Contributions of the interface forces" in text


def test_the_reported_views_hold_the_published_numbers(store):
    data = report_data(store)
    ex = {e.key: e for e in data.extra}
    # the contributions' total is the coupled response (second path: the core directly)
    direct = fbs_core.bushing_response(3, n_modes=40).sel(outputs="bushing:z")
    want = 20 * np.log10(np.abs(direct.data[:, 0, 0]))
    np.testing.assert_allclose(ex["contributions"].curves["total"], want, atol=1e-8)
    assert data.contributions is store.contributions.core["contributions"]
    # the summary's peaks are those the page labels
    assert data.peaks == tuple(store.response.core["peaks"]) and data.peaks
    # the speed map's line is f = v / lambda of harmonic 3
    plot = ex["speed_map"].plot
    h = fbs_core.harmonic(3)
    lx, ly = plot["line"]
    np.testing.assert_allclose(ly, np.asarray(lx) / 3.6 / h.wavelength, rtol=1e-12)
    assert np.shape(plot["z"]) == (len(plot["x"]), len(plot["y"]))
    groups = ex["campbell"].plot["groups"]
    assert ex["campbell"].plot["highlight"] == "order line of harmonic 3"
    np.testing.assert_allclose(
        groups["order line of harmonic 3"][0],
        np.asarray(ex["campbell"].plot["x"]) / 3.6 / h.wavelength,
        rtol=1e-9,
    )
    assert sum(len(v) for k, v in groups.items() if k.startswith("tire modes")) > 10


def test_a_view_of_settings_left_behind_is_not_reported(store):
    store.state.case.n_modes = 60  # the tabs are closed: their results stay of N = 40
    try:
        data = report_data(store)
        keys = [e.key for e in data.extra]
        # those made of N leave; the Campbell diagram (the tire's, any N) stays
        assert not any(k in keys for k in SECTIONS if k != "campbell"), keys
        assert "campbell" in keys
        assert data.contributions is None
        rows = dict(report_summary(data).rows)
        key = "largest contributions at the highest level (share of the total)"
        assert "Contributions tab" in rows[key]
    finally:
        store.state.case.n_modes = 40
    assert "contributions" in [e.key for e in report_data(store).extra]  # of N = 40 again


@pytest.mark.parametrize(
    ("plot", "match"),
    [
        ({"kind": "bars"}, "plot kind 'bars'; allowed: lines, image"),
        ({"kind": "lines", "x": [1, 2], "groups": {"a": [[1, 2, 3]]}}, "a line of 'a'"),
        ({"kind": "image", "x": [1, 2], "y": [1, 2, 3], "z": np.zeros((3, 2))}, "the image"),
    ],
)
def test_a_section_plot_of_inconsistent_shapes_is_refused(plot, match):
    from app.report.data import ExtraSection, ReportError

    with pytest.raises(ReportError, match=match):
        ExtraSection("k", "K", plot=plot)
