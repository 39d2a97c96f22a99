"""What the report and the exports say about the noise and the band is what was computed.

The scatter band of eqs. 5.2-5.4 is computed for the plain truncation to N modes: residual
compensation (the page's switch) acts on the coupled response, the error map and the
suggested N, not on the band. Truth: ``fbs_core.bushing_response`` with and without
residual, called here; the published band's unpolluted curve is the plain one, so the
band's title must say so when the switch is on. The noise target reads as words.
"""

import numpy as np
import pytest

import fbs_core
from app.page.titles import view_title
from app.report.session import report_data
from app.report.titles import title_block
from app.results import Snapshot
from app.results.pins import _describe_settings
from app.state import DashboardState
from app.store import Results
from fbs_core.vocabulary import magnitude_db


@pytest.mark.parametrize(
    ("target", "words"),
    [("tire", "in the tire"), ("chassis", "in the chassis"), ("both", "in tire and chassis")],
)
def test_the_noise_target_reads_as_words(target, words):
    st = DashboardState()
    st.noise.param.update(target=target, noise=5.5)
    text = _describe_settings(Snapshot.of(st))
    assert f"noise 5.5 % {words}" in text, text
    assert "the both" not in text and "on the" not in text


@pytest.fixture(scope="module")
def residual_on():
    r = Results(background=False)
    r.state.noise.param.update(rounds=20, noise=5.0)
    r.state.case.param.update(harmonic=2, n_modes=40, residual=True)
    r.band_now()
    return r


def test_the_band_is_the_plain_truncation_and_its_titles_say_so(residual_on):
    r = residual_on
    f = fbs_core.harmonic(2).frequencies()
    plain = bushing = fbs_core.bushing_response(2, 40, f, residual=False)
    with_res = fbs_core.bushing_response(2, 40, f, residual=True)
    ref = r.band_curves.columns["reference_dB"]
    z = list(bushing.outputs).index("bushing:z")
    np.testing.assert_allclose(ref, magnitude_db(plain.data[:, z, 0]), atol=1e-9)
    assert np.max(np.abs(ref - magnitude_db(with_res.data[:, z, 0]))) > 0.01  # not it
    # the report's band title and the page's live title say what the band is
    snap = report_data(r, url="http://127.0.0.1/main")
    for tb in (title_block(snap, "scatter-band"), view_title("scatter", r.band_curves.snapshot)[0]):
        text = " ".join(tb.lines)
        assert "plain truncation (residual compensation not applied to the band)" in text, text
        assert "+ residual" not in text
    # the coupled response's title keeps its residual
    assert "+ residual" in " ".join(title_block(snap, "coupled-response").lines)
