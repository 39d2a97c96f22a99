"""The Compare tab's difference map has an honest colour range and every plot of the tab has
a title.

The eq. 5.1 error of a truncation is a ratio of errors to the response: at low N in a band
where the response is small it runs to hundreds (tens of thousands of percent), so the
difference of two maps holds a few cells of +-30,000 pp among thousands of a few pp. A colour
range set by the largest cell leaves every other cell white: the range must not follow one
cell, and the cells it clips must be said.

Truth: the two error maps from :mod:`app.compute` (the eq. 5.1 maps of the core) subtracted
here, and order statistics of that difference counted here.
"""

import numpy as np
import pytest

from app import compute
from app.store import Results
from app.views.analysis_compare import CompareView


@pytest.fixture(scope="module")
def compared():
    """Harmonic 4, 6-DOF: the current state with residual compensation against a pin
    without (the difference map of the report: up to ~33,000 pp in a few cells)."""
    r = Results(background=False)
    r.state.noise.rounds = 20
    r.state.case.param.update(harmonic=4, coupling="6dof", residual=False)
    r.pin("plain")
    r.state.case.residual = True
    r.state.analysis.tab = "compare"
    view = CompareView(store=r)
    view.__panel__()
    view._apply()
    return r, view


def test_no_single_cell_sets_the_colour_range_and_the_clipping_is_said(compared):
    r, view = compared
    d = (
        compute.error_map_data(4, "6dof", "z", residual=True)["error_pct"]
        - compute.error_map_data(4, "6dof", "z", residual=False)["error_pct"]
    )
    np.testing.assert_allclose(view._img.data["image"][0], d, atol=1e-9)  # the map is drawn
    a = np.abs(d[np.isfinite(d)])
    largest = a.max()
    assert largest > 1e4  # the case of the review: one extreme cell
    lo, hi = view._mapper.low, view._mapper.high
    assert lo == -hi and hi > 0
    # the range is not set by the extreme cells: it is well inside the largest difference,
    # and at most 5 % of the cells that differ lie beyond it ...
    differ = a[a > 1e-9]
    beyond = int(np.count_nonzero(a > hi))
    assert hi < 0.01 * largest, (hi, largest)
    assert 0 < beyond <= 0.05 * differ.size + 1
    # ... while it still spans most of them (not a scale of noise)
    assert np.count_nonzero(differ <= hi) >= 0.9 * differ.size
    # the clipping is shown: the colour bar's end labels and the map's title
    labels = view._bar.major_label_overrides
    assert any("\u2265" in str(v) for v in labels.values()), labels
    assert any("\u2264" in str(v) for v in labels.values()), labels
    title = view._mp.title.text
    assert "clipped" in title and f"{beyond} cells beyond" in title, title


def test_every_plot_of_the_compare_tab_has_a_title(compared):
    _, view = compared
    from bokeh.models import Title

    for fig in (view._lv, view._df, view._bd, view._mp):
        # a figure's own title, or the title block the first plot of a view carries
        texts = [fig.title.text if fig.title is not None else ""]
        texts += [t.text for t in fig.above if isinstance(t, Title)]
        assert any(str(t).strip() for t in texts), fig.name
    assert "minus" in view._df.title.text
