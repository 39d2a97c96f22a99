"""Speed-frequency map of the bushing response (eq. 4.1 at each fixed speed).

Truths: the harmonic line is a cut through the map (there it equals
``bushing_response`` along the line, which synthesises the tire along
``v = f lambda``); every row equals ``bushing_response`` at that fixed speed (the
tire model's own synthesis); at an operating point with all modes a row equals the
direct solution of the assembled tire + chassis.
"""

import numpy as np
import pytest

from fbs_core import assemble, bushing_response, harmonic, reference_chassis, reference_tire
from fbs_core.analysis import speed_map
from fbs_core.chassis import BUSHING
from fbs_core.errors import DOFError, FBSError
from fbs_core.prediction import coupled_dofs
from fbs_core.tire import ModeCountError, OperatingPointError


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize("k, n", [(1, 40), (6, None)])
def test_the_harmonic_line_is_a_cut_through_the_map(k, n):
    h = harmonic(k)
    speeds = np.arange(30.0, 120.1, 7.5)
    line = speeds / 3.6 / h.wavelength
    grid = np.union1d(np.round(np.linspace(line[0] - 5, line[-1] + 5, 97), 6), line)
    m = speed_map(k, n, speeds=speeds, freq=grid)
    assert m.response.shape == (speeds.size, grid.size, 6)
    np.testing.assert_allclose(m.line_freq, line)
    cut = m.response[np.arange(speeds.size), np.searchsorted(grid, line)]
    along = bushing_response(k, n, line).data[:, :, 0]
    assert _rel(cut, along) < 1e-10


@pytest.mark.parametrize("coupling", ["6dof", "5dof"])
def test_rows_equal_bushing_response_at_fixed_speed(coupling):
    f = np.linspace(5.0, 250.0, 40)
    speeds = [20.0, 47.5, 100.0, 120.0]  # operating points and between them
    m = speed_map(3, 100, speeds=speeds, freq=f, coupling=coupling)
    for i, v in enumerate(speeds):
        ref = bushing_response(3, 100, f, coupling, speed_kmh=v).data[:, :, 0]
        assert _rel(m.response[i], ref) < 1e-10


def test_row_at_an_operating_point_equals_the_assembled_system():
    tire, ch = reference_tire(), reference_chassis()
    h, v = harmonic(5), 80.0
    f = np.array([12.0, 55.0, 140.0, 333.0])
    m = speed_map(5, speeds=[60.0, v], freq=f)
    ts, cs = tire.system(v), ch.system()
    joined = [(f"tire/{d}", f"chassis/spindle:{d.split(':')[1]}") for d in coupled_dofs("6dof")]
    S = assemble({"tire": ts, "chassis": cs}, joined)
    pos = {d: i for i, d in enumerate(S.dofs)}
    load = np.zeros(S.n, complex)
    load[[pos[f"tire/{d}"] for d in ts.dofs]] = tire.patch_load(v, h.wavelength)
    D = S.frf(f, [f"chassis/{b}" for b in BUSHING], [], loads={"patch": load})
    assert _rel(m.response[1], D.data[:, :, 0]) < 1e-6


def test_defaults_levels_export_and_errors():
    m = speed_map(2, 40)
    h = harmonic(2)
    np.testing.assert_allclose(m.speeds, np.arange(20.0, 120.1, 5.0))
    assert m.freq[0] >= 20 / 3.6 / h.wavelength - 1e-9
    assert m.freq[-1] <= 120 / 3.6 / h.wavelength + 1e-9
    np.testing.assert_allclose(np.diff(m.freq), 0.5)
    lv = m.level_db("bushing:z")
    np.testing.assert_allclose(lv, 20 * np.log10(np.abs(m.response[:, :, 2])))
    assert speed_map(2, 40) is m  # cached for the reference models
    mp = m.export_mapping("bushing:z")
    assert mp["level_db"][1].shape == (m.speeds.size, m.freq.size, 1)
    with pytest.raises(DOFError, match="available"):
        m.level_db("spindle:z")
    with pytest.raises(OperatingPointError, match="outside"):
        speed_map(2, 40, speeds=[10.0, 50.0])
    with pytest.raises(ModeCountError):
        speed_map(2, 41)
    with pytest.raises(FBSError, match="increasing"):
        speed_map(2, 40, speeds=[50.0, 40.0])
