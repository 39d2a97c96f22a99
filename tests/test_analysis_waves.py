"""The Campbell diagram that follows the waves (issue 30).

Truth: the rotating ring's closed form (reference-models.md sec. 2.1, Huang & Soedel
1987), ``omega_n(+/-) = (+/- g_n + sqrt(g_n^2 + M_n K_n)) / M_n``; the ``+`` branch runs
with the spin (forward).
"""

import dataclasses
import functools

import numpy as np
import pytest

from fbs_core import reference_tire
from fbs_core.analysis import wave_campbell, waves
from fbs_core.errors import FBSError
from fbs_core.tire import TireParameters, ring_closed_form

#: The ring alone: in-plane family up to order 8, no road, no slip, round belt, upright
#: wheel, undamped.
RING = TireParameters(
    orders=(8, -1, -1, -1, -1, -1, -1, -1),
    k_cx=0.0,
    k_cy=0.0,
    k_cz=0.0,
    slip_zones=0,
    static_deflection=0,
    zeta=0.0,
    camber=0.0,
    toe=0.0,
)
#: Where the loaded tire's waves of orders 2..8 lie relative to the closed form (the
#: static deflection lowers the mean hoop force, the road and the other families pull
#: them down): measured -15.1 % .. -1.5 % (docs/modes.md).
TOLERANCE = 0.16


def test_with_the_additions_switched_off_the_branches_are_the_closed_form():
    speeds = np.array([20.0, 50.0, 80.0, 120.0])
    cb = wave_campbell(params=RING, speeds=speeds, hub="fixed", fmax=None)
    assert cb.freq.shape == (4, 17)  # orders 0..8 of one family: 1 + 2 * 8 waves
    for n in range(2, 9):
        fp, fm = np.array([ring_closed_form(n, v, RING) for v in speeds]).T
        for d, truth in (("forward", fp), ("backward", fm)):
            b = cb.find("ip", n, d)
            np.testing.assert_allclose(cb.freq[:, b], truth, rtol=1e-9)
            np.testing.assert_allclose(cb.closed_form[:, b], truth, rtol=1e-12)
            tau = -1.0 if d == "forward" else 1.0
            np.testing.assert_allclose(cb.travelling[:, b], tau, atol=1e-6)
    # pure waves, one per mode (order 1 does not split, g_1 = 0: its pair is degenerate and
    # any combination of its two waves is a mode)
    np.testing.assert_allclose(cb.purity[:, cb.order != 1], 1.0, atol=1e-6)
    assert not cb.veering[:, cb.order != 1].any()  # the same mode carries every wave
    assert np.all(cb.excitation == 0)  # the hub is clamped


@functools.cache
def loaded():
    return wave_campbell(reference_tire(), speeds=[20.0, 40.0, 60.0, 80.0, 100.0, 120.0])


def test_on_the_loaded_tire_every_ring_order_has_both_waves_near_the_closed_form():
    cb = loaded()
    for n in range(2, 9):
        fp, fm = np.array([ring_closed_form(n, v) for v in cb.speeds]).T
        for d, truth in (("forward", fp), ("backward", fm)):
            b = cb.find("ip", n, d)
            rel = cb.freq[:, b] / truth - 1
            assert np.all(np.abs(rel) < TOLERANCE), (n, d, rel)
            # the wave shifts with speed like the closed form (the Doppler split)
            slope = np.polyfit(cb.speeds, cb.freq[:, b], 1)[0]
            exact = np.polyfit(cb.speeds, truth, 1)[0]
            assert slope == pytest.approx(exact, rel=0.25, abs=0.05), (n, d, slope, exact)
    labels = cb.labels()
    assert len(set(labels)) == len(labels) and "hub:z" in labels


def test_branches_are_the_modal_models_modes_at_the_operating_points():
    cb = loaded()
    tire = reference_tire()
    for i, v in enumerate(cb.speeds):
        k = int(np.flatnonzero(tire.speeds == v)[0])
        ok = cb.stored[i] >= 0
        assert ok.all()  # every speed is an operating point: every branch has its mode
        f_model = tire.poles[k, 2 * cb.stored[i, ok]].imag / (2 * np.pi)
        np.testing.assert_allclose(cb.freq[i, ok], f_model, rtol=1e-8)


def test_default_selection_reads_the_harmonic_band():
    cb = loaded()
    for k in (1, 4):
        sel = cb.selection(k, n_orders=3, top=10)
        assert 1 <= sel.size <= 10
        assert cb.in_band(k)[sel].all()
        w = cb.order_weight(k)
        carry = list(w)[:3]
        assert all((cb.family[b], int(cb.order[b])) in carry for b in sel)
        ex = np.nan_to_num(cb.excitation[:, sel, k - 1]).max(axis=0)
        assert np.all(np.diff(ex) <= 0)  # most excited first
    with pytest.raises(FBSError, match=">= 1"):
        cb.selection(1, top=0)
    with pytest.raises(FBSError, match="no branch"):
        cb.find("ip", 40, "forward")


def test_bad_input():
    with pytest.raises(FBSError, match="allowed: free, fixed"):
        wave_campbell(hub="clamped")
    with pytest.raises(FBSError, match="veer_mac"):
        wave_campbell(veer_mac=1.5)
    with pytest.raises(FBSError, match="increasing"):
        wave_campbell(params=RING, speeds=[50.0, 20.0])
    with pytest.raises(FBSError, match="speeds are required"):
        wave_campbell(params=RING)
    with pytest.raises(FBSError, match="fmax"):
        wave_campbell(fmax=-1.0)


def test_the_stored_reference_result_is_the_one_computed_now():
    """The reference tire's diagram is read from data/reference_waves.npz (the dense solves
    take 12 s on an idle core): it must be what the tracking computes today, field by
    field, and be used only for the very tire, speeds, hub and veer_mac it was made of."""
    tire = reference_tire()
    speeds = tuple(float(v) for v in tire.speeds)
    stored = waves.load_stored(tire, speeds, "free", 0.8)
    assert stored is not None, "data/reference_waves.npz is missing or stale"
    fresh = waves._track(tire, speeds, "free", 0.8)
    for f in dataclasses.fields(fresh):
        a, b = getattr(stored, f.name), getattr(fresh, f.name)
        if isinstance(b, np.ndarray) and b.dtype.kind in "fc":
            np.testing.assert_allclose(a, b, rtol=1e-7, atol=1e-9, err_msg=f.name)
        elif isinstance(b, np.ndarray):
            np.testing.assert_array_equal(a, b, err_msg=f.name)
        else:
            assert a == b, f.name
    # what the library returns for the reference tire is that result (below 450 Hz)
    cb = wave_campbell()
    low = np.nanmin(np.where(np.isfinite(fresh.freq), fresh.freq, np.inf), axis=0) <= 450.0
    np.testing.assert_allclose(cb.freq, fresh.freq[:, low], rtol=1e-9)
    assert cb.labels() == tuple(np.asarray(fresh.labels())[low])
    # another hub condition, veer_mac or speed grid: not the stored result
    assert waves.load_stored(tire, speeds, "fixed", 0.8) is None
    assert waves.load_stored(tire, speeds, "free", 0.7) is None
    assert waves.load_stored(tire, speeds[:-1], "free", 0.8) is None
    other = dataclasses.replace(tire.params, zeta=tire.params.zeta * 1.01)
    assert waves.load_stored(other, speeds, "free", 0.8) is None


def test_progress_reports_every_speed_and_can_stop_the_solve():
    seen = []
    speeds = [20.0, 50.0, 80.0]
    cb = wave_campbell(
        params=RING, speeds=speeds, hub="fixed", progress=lambda d, n: seen.append((d, n))
    )
    assert seen == [(0, 3), (1, 3), (2, 3), (3, 3)] and cb.freq.shape[0] == 3

    class Stop(Exception):
        pass

    def stop(done, total):
        if done == 1:
            raise Stop

    with pytest.raises(Stop):
        wave_campbell(params=RING, speeds=[20.0, 60.0, 90.0], hub="fixed", progress=stop)
