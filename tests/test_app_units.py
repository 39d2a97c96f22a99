"""The dashboard's level labels say the unit of the FRF they show (issue 12: one source).

Truth: the unit that the plotted FRF object itself carries (``FRF.unit``), which follows
the kind of its output (translation / rotation) and input (force / moment / road).
"""

from __future__ import annotations

import pytest

import fbs_core as fc
from app import compute
from app.report import figures
from app.results import main as store
from fbs_core.vocabulary import DIRECTIONS


@pytest.fixture(scope="module")
def bushing():
    return fc.bushing_response(1, n_modes=40)


@pytest.mark.parametrize("d", DIRECTIONS)
def test_bushing_level_labels_follow_the_response_frf(bushing, d):
    want = f"dB re 1 {bushing.unit(f'bushing:{d}', 'patch')}"
    assert compute.level_unit(d) == want
    assert figures.level_unit(f"bushing:{d}") == want
    assert want.endswith(("(m/s)/m", "(rad/s)/m"))


@pytest.mark.parametrize("d", DIRECTIONS)
@pytest.mark.parametrize("i", DIRECTIONS)
def test_chassis_mobility_label_follows_the_chassis_frf(d, i):
    Y = fc.reference_chassis().mobility([20.0], outputs=[f"bushing:{d}"], inputs=[f"spindle:{i}"])
    assert store.chassis_label(d, i) == f"Mobility (dB re 1 {Y.unit()})"
