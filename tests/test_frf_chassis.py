"""A chassis given by an FRF (``fbs_core.FRFChassis``), grid matching, and the checks a model
pair must pass for the whole study (``fbs_core.io.checks.check_tire`` / ``check_pair``).

Truth: the reference chassis' own synthesis (an FRF cut from it must give back the same
numbers on its lines), linear functions of frequency (linear interpolation is exact on
them), the closed form of the quantity conversion (accelerance = j omega mobility), and a
chassis built to cancel the tire's hub mobility (a singular interface by construction).
"""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core
from fbs_core import FRF, FRFChassis
from fbs_core.chassis import match_grid
from fbs_core.errors import FBSError, FrequencyGridError, SingularInterfaceError
from fbs_core.io.checks import MIN_TIRE_MODES, check_pair, check_tire
from fbs_core.tire.model import TireModel

GRID = np.arange(13.0, 422.01, 0.5)


@pytest.fixture(scope="module")
def reference_frf():
    return fbs_core.reference_chassis().mobility(GRID)


def test_match_grid_finds_lines_despite_rounding_and_refuses_missing_ones():
    F = np.arange(10.0, 20.0, 0.5)
    wanted = np.array([12.5, 10.0, 19.5]) * (1 + 3e-12)  # digits lost in a file
    np.testing.assert_array_equal(match_grid(F, wanted), [5, 0, 19])
    assert match_grid(F, [12.25]) is None
    assert match_grid(F, [9.0]) is None and match_grid(F, [20.0]) is None
    assert match_grid([], []).size == 0 and match_grid([], [1.0]) is None


def test_frf_chassis_on_its_lines_is_the_reference_chassis(reference_frf):
    ch = FRFChassis(reference_frf)
    f = fbs_core.harmonic(3).frequencies()
    got = ch.mobility(f)
    want = fbs_core.reference_chassis().mobility(f)
    assert got.outputs == want.outputs and got.inputs == want.inputs
    np.testing.assert_allclose(got.data, want.data, rtol=1e-12)
    assert not ch.needs_interpolation(f)
    # the quantity conversion of the contract: accelerance = j omega mobility
    acc = ch.mobility(f, ["bushing:z"], ["spindle:x"], quantity="accelerance")
    jw = 2j * np.pi * f
    np.testing.assert_allclose(
        acc.data[:, 0, 0], jw * want.sel(outputs="bushing:z", inputs="spindle:x").data[:, 0, 0]
    )


def test_missing_lines_are_refused_unless_interpolation_was_chosen():
    f = np.arange(10.0, 30.0, 1.0)
    # data linear in frequency: linear interpolation is exact between the lines
    lab = [f"spindle:{d}" for d in fbs_core.DIRECTIONS]
    slope = np.arange(36).reshape(6, 6) + 1j
    data = f[:, None, None] * slope[None] + 2.0
    Y = FRF(f, data, lab, lab, "mobility")
    wanted = np.array([10.5, 11.0, 20.25])
    with pytest.raises(FrequencyGridError, match="first: 10.5 Hz.*interpolate"):
        FRFChassis(Y).on_grid(wanted)
    got = FRFChassis(Y, interpolate=True).on_grid(wanted)
    np.testing.assert_allclose(got.data, wanted[:, None, None] * slope[None] + 2.0)
    assert FRFChassis(Y).needs_interpolation(wanted)
    # never extrapolated
    with pytest.raises(FrequencyGridError):
        FRFChassis(Y, interpolate=True).on_grid([5.0])


def _sub_tire(n_modes=None, speeds=slice(None)):
    T = fbs_core.reference_tire()
    m = slice(None) if n_modes is None else slice(0, n_modes)
    return TireModel(
        T.speeds[speeds],
        T.poles[speeds, m],
        T.psi[speeds, m],
        T.chi[speeds, m],
        T.wavelengths,
        T.participation[speeds][:, :, m],
        meta={"source": "test"},
    )


def test_check_tire_accepts_the_reference_and_names_what_is_missing():
    assert check_tire(fbs_core.reference_tire()) == []
    assert "200 complex modes" in check_tire(_sub_tire(200))[0]
    with pytest.raises(FBSError, match=f"at least {MIN_TIRE_MODES}"):
        check_tire(_sub_tire(MIN_TIRE_MODES - 2))
    # operating points only up to ~80 km/h: the harmonics' lines need 30-120 km/h
    T = fbs_core.reference_tire()
    keep = slice(0, int(np.searchsorted(T.speeds, 80.0)) + 1)
    with pytest.raises(FBSError, match="harmonic 1"):
        check_tire(_sub_tire(speeds=keep))


def test_check_pair_refuses_a_singular_interface_and_names_the_harmonic():
    check_pair()  # the reference pair couples on every grid
    tire = fbs_core.reference_tire()
    h = fbs_core.harmonic(1)
    f = h.frequencies()
    hub = tuple(f"hub:{d}" for d in fbs_core.DIRECTIONS)
    Yjj = tire.truncations(f, h, [tire.n_modes])[0][0]
    sp = [f"spindle:{d}" for d in fbs_core.DIRECTIONS]
    bu = [f"bushing:{d}" for d in fbs_core.DIRECTIONS]
    data = np.concatenate([-Yjj, np.ones((f.size, 6, 6))], axis=1)  # Y_jj^E = -Y_jj^A
    chassis = FRFChassis(FRF(f, data, sp + bu, sp, "mobility"))
    with pytest.raises(SingularInterfaceError, match=r"harmonic 1 \(13-"):
        check_pair(tire, chassis)
    assert hub == tire.hub_dofs
