"""Coupled tire-chassis prediction at the bushing (thesis eq. 4.1) against ground truth.

Truth: the tire's matrices (``tire.system(v)``: M, C = D + G, K) and the
chassis' matrices (M, K (1 + j eta)) joined at the hub by primal assembly and
solved directly for the patch load. The prediction instead couples separately
synthesised FRFs: the tire's complex-mode synthesis with all modes and the
chassis' complex-mode FRFs.
"""

import functools

import numpy as np
import pytest

from fbs_core import assemble, bushing_response, harmonic, reference_chassis, reference_tire
from fbs_core.chassis import BUSHING
from fbs_core.errors import FBSError, FrequencyGridError
from fbs_core.prediction import COUPLED_DOFS, CouplingOptionError, coupled_dofs

SPEED = 60.0  # km/h, one of the tire's operating points


@functools.cache
def _direct(k: int, coupling: str, speed: float, freq_key: tuple) -> np.ndarray:
    """Patch -> bushing mobility of the assembled tire + chassis, solved directly."""
    tire, ch = reference_tire(), reference_chassis()
    h = harmonic(k)
    ts, cs = tire.system(speed), ch.system()
    joined = [(f"tire/{d}", f"chassis/spindle:{d.split(':')[1]}") for d in COUPLED_DOFS[coupling]]
    S = assemble({"tire": ts, "chassis": cs}, joined).to_dense()
    pos = {d: i for i, d in enumerate(S.dofs)}
    load = np.zeros(S.n, complex)
    load[[pos[f"tire/{d}"] for d in ts.dofs]] = tire.patch_load(speed, h.wavelength)
    D = S.frf(np.array(freq_key), [f"chassis/{b}" for b in BUSHING], [], loads={"patch": load})
    return D.data


def _rel(a, b):
    return float(np.max(np.linalg.norm(a - b, axis=(1, 2)) / np.linalg.norm(b, axis=(1, 2))))


@pytest.mark.parametrize("coupling", ["6dof", "5dof"])
@pytest.mark.parametrize("k", [1, 6])
def test_receptance_coupling_equals_assembled_direct_solution(coupling, k):
    """Fixed speed, all modes: eq. 4.1 on synthesised FRFs == direct solve (< 1e-6)."""
    f = np.linspace(5.0, 450.0, 20)
    v = bushing_response(k, None, f, coupling, speed_kmh=SPEED)
    assert v.outputs == BUSHING and v.inputs == ("patch",)
    truth = _direct(k, coupling, SPEED, tuple(f))
    assert _rel(v.data, truth) < 1e-6


def test_along_the_harmonic_line_at_the_operating_points():
    """On the line v = f lambda, lines at 40/60/80/100 km/h equal the direct solution
    of the assembly at that speed (no interpolation is involved there)."""
    h = harmonic(2)
    speeds = np.array([40.0, 60.0, 80.0, 100.0])
    f = speeds / 3.6 / h.wavelength
    v = bushing_response(h, freq=f)
    for i, s in enumerate(speeds):
        truth = _direct(2, "6dof", float(s), (f[i],))
        assert _rel(v.data[i : i + 1], truth) < 1e-6


def test_defaults_truncation_and_couplings_differ():
    h = harmonic(1)
    full = bushing_response(1)
    np.testing.assert_array_equal(full.freq, h.frequencies())
    assert full.outputs == BUSHING and full.quantity == "mobility"
    assert bushing_response(1) is full  # cached: the same immutable object
    few = bushing_response(1, n_modes=20)
    many = bushing_response(1, n_modes=reference_tire().n_modes - 20)
    err_few = np.abs(few.data - full.data).max() / np.abs(full.data).max()
    err_many = np.abs(many.data - full.data).max() / np.abs(full.data).max()
    assert err_many < err_few
    free = bushing_response(1, coupling="5dof")
    assert np.abs(free.data - full.data).max() > 1e-3 * np.abs(full.data).max()
    # the whole point: the tire changes the chassis' response (fig. 4.2 vs fig. 4.8)
    assert free.data.shape == full.data.shape == (h.frequencies().size, 6, 1)


def test_coupling_options():
    assert coupled_dofs("6dof") == tuple(f"hub:{d}" for d in ("x", "y", "z", "rx", "ry", "rz"))
    assert "hub:ry" not in coupled_dofs("5dof") and len(coupled_dofs("5dof")) == 5


def test_bad_input():
    with pytest.raises(CouplingOptionError, match="allowed: '6dof', '5dof'"):
        bushing_response(1, coupling="4dof")
    with pytest.raises(ValueError, match="unknown coupling"):
        bushing_response(1, coupling=6)
    with pytest.raises(FBSError, match="unknown harmonic 8"):
        bushing_response(8)
    with pytest.raises(FBSError, match="unknown harmonic"):
        bushing_response("1")
    with pytest.raises(FBSError, match="n_modes"):
        bushing_response(1, n_modes=21)
    with pytest.raises(FrequencyGridError):
        bushing_response(1, freq=[10.0, 5.0])
    with pytest.raises(FBSError):
        bushing_response(1, freq=[100.0, 200.0])  # outside the 1st harmonic's band
    with pytest.raises(FBSError):
        bushing_response(1, freq=[10.0, 20.0], speed_kmh=200.0)  # beyond the operating points


def test_peak_listing_of_the_appendix_a_script():
    """scripts/print_bushing_peaks.py finds the maxima of two resonances, strongest first."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "scripts" / "print_bushing_peaks.py"
    spec = importlib.util.spec_from_file_location("print_bushing_peaks", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    f = np.arange(10.0, 100.0, 0.25)
    v = 2.0 / (1 - (f / 30) ** 2 + 0.05j * f / 30) + 1.0 / (1 - (f / 70) ** 2 + 0.05j * f / 70)
    (f1, db1), (f2, db2) = mod.peaks(f, v, 2)
    assert f1 == pytest.approx(30.0, abs=0.5) and f2 == pytest.approx(70.0, abs=0.5)
    assert db1 == pytest.approx(20 * np.log10(np.abs(v).max()))
    assert db1 > db2
    assert mod.peaks(f, 1.0 / f, 3) == [(10.0, pytest.approx(-20.0))]  # monotonic: band maximum
