"""Monte-Carlo noise scatter band (thesis 5.2, eqs. 5.2-5.4)."""

from __future__ import annotations

import threading
import tracemalloc

import numpy as np
import pytest

import fbs_core as fc
from fbs_core import kernels
from fbs_core.studies.scatter import scatter_band_arrays, split_factors

NF, NJ, NE = 40, 6, 6
FREQ = np.linspace(10.0, 60.0, NF)


def _mag(z):
    # the band's magnitude: sqrt(re^2 + im^2), evaluated like the kernel
    return np.sqrt(z.real * z.real + z.imag * z.imag)


@pytest.fixture(scope="module")
def arrays():
    """Mobilities of two damped mass-spring structures meeting at 6 DOFs (direct solve)."""
    rng = np.random.default_rng(7)

    def structure(n, n_out):
        m = rng.uniform(1.0, 3.0, n)
        Kc = rng.uniform(0.5, 1.5, (n, n)) * 1e4
        K = np.diag(Kc.sum(1) + 2e4) - (Kc + Kc.T) / 2 * (1 - np.eye(n))
        K = (K + K.T) / 2 * (1 + 0.05j)
        w = 2 * np.pi * FREQ
        Z = K[None] - w[:, None, None] ** 2 * np.diag(m)[None]
        return 1j * w[:, None, None] * np.linalg.inv(Z)  # mobility (NF, n, n)

    YA = structure(9, NJ)
    YE = structure(14, NE)
    YjjA = YA[:, :NJ, :NJ]
    vj = YA[:, :NJ, NJ:] @ np.array([1.0, -0.5, 0.3])  # load on A's internal DOFs
    YjjE = YE[:, :NJ, :NJ]
    YejE = YE[:, NJ : NJ + NE, :NJ]
    return YjjA, vj, YjjE, YejE


def _band(arrays, **kw):
    kw = {"rounds": 200, "freq": FREQ, **kw}
    return scatter_band_arrays(*arrays, **kw)


def test_zero_noise_reproduces_the_reference_exactly(arrays):
    b = _band(arrays, noise=0.0, frequency_dependent=True)
    ref = _mag(b.reference)
    np.testing.assert_array_equal(b.minimum, ref)
    np.testing.assert_array_equal(b.maximum, ref)
    np.testing.assert_array_equal(b.percentiles, np.broadcast_to(ref, b.percentiles.shape))
    # the reference is eq. 4.1 (second method: numpy batched solve)
    YjjA, vj, YjjE, YejE = arrays
    np.testing.assert_allclose(
        b.reference, kernels.couple_response_kernel(YejE, YjjA, YjjE, vj), rtol=1e-10
    )


@pytest.mark.parametrize("fd", [False, True], ids=["freq-independent", "freq-dependent"])
@pytest.mark.parametrize("target", ["tire", "chassis", "both"])
def test_every_round_inside_band_and_band_is_the_extremes(arrays, fd, target):
    b = _band(arrays, target=target, frequency_dependent=fd, percentiles=(5, 50, 95))
    all_rounds = _mag(b.rounds_response(np.arange(b.rounds)))  # (R, NF, NE)
    assert np.all(all_rounds >= b.minimum) and np.all(all_rounds <= b.maximum)
    np.testing.assert_array_equal(b.minimum, all_rounds.min(0))
    np.testing.assert_array_equal(b.maximum, all_rounds.max(0))
    np.testing.assert_allclose(
        b.percentiles, np.percentile(all_rounds, (5, 50, 95), axis=0), rtol=1e-13
    )
    # the recorded rounds attain the extremes
    li, di = np.meshgrid(np.arange(NF), np.arange(NE), indexing="ij")
    np.testing.assert_array_equal(all_rounds[b.argmax_round, li, di], b.maximum)
    np.testing.assert_array_equal(all_rounds[b.argmin_round, li, di], b.minimum)
    assert np.all(b.minimum < b.maximum)


def test_regenerated_round_equals_the_batch(arrays):
    b = _band(arrays, rounds=300, frequency_dependent=True)
    r = b.peak_round(35.0, "bushing:z")
    line = int(np.argmin(np.abs(FREQ - 35.0)))
    one = b.round(r)
    assert one.shape == (NF, NE)
    assert _mag(one)[line, 2] == b.maximum[line, 2]  # bit for bit the batch's maximum
    batch = b.rounds_response(np.arange(b.rounds))
    np.testing.assert_array_equal(one, batch[r])
    np.testing.assert_array_equal(b.round(299), batch[299])
    # and it is eq. 5.4 with the documented factors of that round (numpy, second method)
    YjjA, vj, YjjE, YejE = arrays
    S = [b.factors(r, line=k) for k in range(NF)]
    st = {k: np.stack([s[k] for s in S]) for k in S[0]}
    x = np.linalg.solve(st["Yjj_A"] * YjjA + st["Yjj_E"] * YjjE, (st["vj_A"] * vj)[..., None])
    np.testing.assert_allclose(
        one, np.einsum("fek,fk->fe", st["Yej_E"] * YejE, x[..., 0]), rtol=1e-9
    )


def test_tire_noise_leaves_chassis_untouched_and_vice_versa(arrays):
    both = _band(arrays, target="both", seed=3, frequency_dependent=True)
    tire = _band(arrays, target="tire", seed=3, frequency_dependent=True)
    veh = _band(arrays, target="chassis", seed=3, frequency_dependent=True)
    for r, line in [(0, 0), (17, 5), (199, 39)]:
        fb, ft, fv = both.factors(r, line), tire.factors(r, line), veh.factors(r, line)
        for k in ("Yjj_E", "Yej_E"):
            assert np.all(ft[k] == 1.0)
            np.testing.assert_array_equal(fv[k], fb[k])
        for k in ("Yjj_A", "vj_A"):
            assert np.all(fv[k] == 1.0)
            np.testing.assert_array_equal(ft[k], fb[k])
        for k in fb:
            assert np.all(np.abs(fb[k] - 1) <= 0.1) and np.any(fb[k] != 1.0)
    # physically: tire-only noise computed by hand with clean chassis FRFs
    YjjA, vj, YjjE, YejE = arrays
    S = [tire.factors(17, k) for k in range(NF)]
    SA = np.stack([s["Yjj_A"] for s in S])
    sa = np.stack([s["vj_A"] for s in S])
    ref = kernels.couple_response_kernel(YejE, SA * YjjA, YjjE, sa * vj)
    np.testing.assert_allclose(tire.round(17), ref, rtol=1e-9)


def test_frequency_independent_noise_is_one_set_per_round(arrays):
    fi = _band(arrays, frequency_dependent=False)
    fd = _band(arrays, frequency_dependent=True)
    np.testing.assert_array_equal(fi.factors(5, 0)["Yjj_A"], fi.factors(5, 30)["Yjj_A"])
    assert not np.array_equal(fd.factors(5, 0)["Yjj_A"], fd.factors(5, 30)["Yjj_A"])
    # one set per round: every curve is the reference with fixed scaled matrices
    YjjA, vj, YjjE, YejE = arrays
    S = fi.factors(8)
    ref = kernels.couple_response_kernel(
        S["Yej_E"] * YejE, S["Yjj_A"] * YjjA, S["Yjj_E"] * YjjE, S["vj_A"] * vj
    )
    np.testing.assert_allclose(fi.round(8), ref, rtol=1e-9)


def test_same_seed_same_band_other_seed_other_band(arrays):
    a = _band(arrays, seed=11, frequency_dependent=True)
    b = _band(arrays, seed=11, frequency_dependent=True)
    c = _band(arrays, seed=12, frequency_dependent=True)
    for name in ("minimum", "maximum", "percentiles", "argmax_round"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert not np.array_equal(a.maximum, c.maximum)
    g = _band(arrays, seed=np.random.default_rng(4))
    h = _band(arrays, seed=np.random.default_rng(4))
    np.testing.assert_array_equal(g.maximum, h.maximum)
    assert g.seed == h.seed


def test_chunking_gives_identical_results_and_bounds_memory(arrays):
    whole = _band(arrays, rounds=4000, frequency_dependent=True, max_chunk_seconds=None)
    tracemalloc.start()
    small = _band(arrays, rounds=4000, frequency_dependent=True, max_chunk_bytes=8 * 6 * 4000 * 3)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    for name in ("minimum", "maximum", "percentiles", "argmin_round"):
        np.testing.assert_array_equal(getattr(whole, name), getattr(small, name))
    np.testing.assert_array_equal(whole.convergence.maximum, small.convergence.maximum)
    all_rounds_bytes = 4000 * NF * NE * 8
    assert peak < all_rounds_bytes / 4  # chunks of 3 lines, never all rounds at once


def test_regenerated_rounds_are_kept_read_only_and_stay_the_batchs(arrays):
    """A page redraws the same round for every DOF and percentile change: the band keeps
    the last few regenerated rounds. Kept or regenerated, a round is the batch's."""
    b = _band(arrays, rounds=40, frequency_dependent=True)
    batch = b.rounds_response(np.arange(b.rounds))
    first = b.round(3)
    assert b.round(3) is first  # kept
    with pytest.raises(ValueError):
        first[0, 0] = 0  # read-only: a caller cannot change what the next one gets
    for r in range(10, 10 + b.ROUND_CACHE):  # evicts round 3
        np.testing.assert_array_equal(b.round(r), batch[r])
    again = b.round(3)
    assert again is not first
    np.testing.assert_array_equal(again, batch[3])


def test_convergence_report(arrays):
    b = _band(arrays, rounds=1000, frequency_dependent=True)
    conv = b.convergence
    np.testing.assert_array_equal(conv.rounds, [10, 20, 50, 100, 200, 500, 1000])
    assert np.all(np.diff(conv.maximum, axis=0) >= 0) and np.all(np.diff(conv.minimum, axis=0) <= 0)
    np.testing.assert_array_equal(conv.maximum[-1], b.maximum)
    np.testing.assert_array_equal(conv.minimum[-1], b.minimum)
    up, lo = conv.upper_change_db, conv.lower_change_db
    assert up[-1] == 0 and lo[-1] == 0 and np.all(np.diff(up) <= 0) and np.all(up >= 0)
    # running extremes over the first 100 rounds, by the second method
    first = _mag(b.rounds_response(np.arange(100)))
    np.testing.assert_array_equal(conv.maximum[3], first.max(0))
    assert conv.step_change_db.shape == (6,)
    assert conv.step_change_db is conv.step_change_db  # once per band, read-only
    assert not conv.step_change_db.flags.writeable
    # the largest change of either edge between neighbouring checkpoints (second method)
    with np.errstate(divide="ignore", invalid="ignore"):
        up = 20 * np.log10(conv.maximum[1:] / conv.maximum[:-1])
        lo = 20 * np.log10(conv.minimum[:-1] / conv.minimum[1:])
    want = np.maximum(np.nanmax(up, axis=(1, 2)), np.nanmax(lo, axis=(1, 2)))
    np.testing.assert_array_equal(conv.step_change_db, want)
    assert "rounds" in conv.summary()
    custom = _band(arrays, rounds=50, checkpoints=[5, 25])
    np.testing.assert_array_equal(custom.convergence.rounds, [5, 25, 50])


def test_results_are_frozen_and_carry_axes(arrays):
    b = _band(arrays)
    np.testing.assert_array_equal(b.freq, FREQ)
    assert b.dofs == tuple(f"bushing:{d}" for d in ("x", "y", "z", "rx", "ry", "rz"))
    with pytest.raises(ValueError):
        b.maximum[0, 0] = 1.0
    with pytest.raises(AttributeError):
        b.noise = 0.2


def test_singular_interface_raises(arrays):
    YjjA, vj, YjjE, YejE = arrays
    A = YjjA.copy()
    A[3] = -YjjE[3]
    with pytest.raises(fc.SingularInterfaceError, match="Hz"):
        scatter_band_arrays(A, vj, YjjE, YejE, noise=0.0, rounds=4, freq=FREQ)


@pytest.mark.parametrize(
    "kw, err, match",
    [
        (dict(noise=-0.1), fc.FBSError, "noise"),
        (dict(noise=1.0), fc.FBSError, "noise"),
        (dict(target="car"), fc.FBSError, "allowed: tire, chassis, both"),
        (dict(rounds=0), fc.FBSError, "rounds"),
        (dict(rounds=2.5), fc.FBSError, "rounds"),
        (dict(percentiles=(5, 120)), fc.FBSError, "percentiles"),
        (dict(checkpoints=[50, 10]), fc.FBSError, "checkpoints"),
        (dict(freq=FREQ[:-1]), fc.DataFormatError, "frequencies"),
        (dict(dofs=("a:x",)), fc.DataFormatError, "labels"),
        (dict(seed=-3), fc.FBSError, "seed"),
    ],
)
def test_bad_settings_raise(arrays, kw, err, match):
    with pytest.raises(err, match=match):
        _band(arrays, **{"rounds": 20, **kw})


def test_bad_arrays_and_queries_raise(arrays):
    YjjA, vj, YjjE, YejE = arrays
    with pytest.raises(fc.DataFormatError, match="vj"):
        scatter_band_arrays(YjjA, vj[:, :5], YjjE, YejE, rounds=5)
    with pytest.raises(fc.DataFormatError, match="YejE"):
        scatter_band_arrays(YjjA, vj, YjjE, YejE[:, :, :5], rounds=5)
    bad = vj.copy()
    bad[0, 0] = np.nan
    with pytest.raises(fc.DataFormatError, match="non-finite"):
        scatter_band_arrays(YjjA, bad, YjjE, YejE, rounds=5)
    b = _band(arrays, rounds=10)
    with pytest.raises(fc.FBSError, match="0..9"):
        b.round(10)
    with pytest.raises(fc.DOFError, match="available"):
        b.peak_round(30.0, "bushing:q")
    with pytest.raises(fc.FBSError, match="which"):
        b.peak_round(30.0, "bushing:z", which="median")


def test_split_factors_layout():
    s = np.arange(114.0)
    S = split_factors(s, 6, 6)
    assert S["Yjj_A"][0, 1] == 1 and S["vj_A"][0] == 36 and S["Yjj_E"][0, 0] == 42
    assert S["Yej_E"][5, 5] == 113


def test_concurrent_bands_from_threads_agree(arrays):
    """A dashboard may compute bands from several threads at once."""
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(3) as ex:
        bands = list(
            ex.map(lambda s: _band(arrays, seed=s % 2, frequency_dependent=True), range(4))
        )
    np.testing.assert_array_equal(bands[0].maximum, bands[2].maximum)
    np.testing.assert_array_equal(bands[1].maximum, bands[3].maximum)


def _chunks(arrays, **kw):
    """The band and the number of lines of each of its chunks (from the progress calls)."""
    done = []
    band = _band(arrays, progress=lambda d, n: done.append(d), **kw)
    return band, np.diff(done).tolist()


def test_chunks_are_bounded_in_time_and_change_no_number(arrays):
    """A chunk lasts at most ``max_chunk_seconds`` (sized by the measured time per line): with
    a bound shorter than any line, every chunk after the first is one line; without a
    bound one chunk holds every line memory allows. The numbers are the same."""
    kw = {"rounds": 3000, "frequency_dependent": True, "seed": 4}
    whole, sizes = _chunks(arrays, max_chunk_seconds=None, **kw)
    assert sizes == [NF]
    short, sizes = _chunks(arrays, max_chunk_seconds=1e-9, **kw)
    assert len(sizes) >= NF - sizes[0] + 1 and set(sizes[1:]) == {1}
    for name in ("minimum", "maximum", "percentiles", "argmin_round", "argmax_round"):
        np.testing.assert_array_equal(getattr(whole, name), getattr(short, name))
    np.testing.assert_array_equal(whole.convergence.minimum, short.convergence.minimum)
    # the default bound (0.1 s): a 200,000-round band whose memory bound would allow all
    # its lines in one chunk (about 1.4 s of work on 2 cores) runs in several
    _, sizes = _chunks(arrays, rounds=200_000, max_chunk_bytes=8 * NE * 200_000 * NF)
    assert len(sizes) > 1


def test_single_rounds_need_no_kernel_lock(arrays):
    """A page regenerates single rounds while another thread's band holds the parallel
    kernel: they run on the calling thread without its lock."""
    from fbs_core.studies import scatter

    band = _band(arrays, rounds=500, frequency_dependent=True, seed=9)
    want, want_7 = band.rounds_response([3, 499]), band.round(7)
    got = {}

    def regenerate():
        got["rounds"] = band.rounds_response([3, 499])
        got["round"] = band.round(7)

    with scatter._LOCK:  # another band's chunk is running
        t = threading.Thread(target=regenerate, daemon=True)
        t.start()
        t.join(120)  # liveness, not speed: with the lock needed it never ends
        alive = t.is_alive()
    t.join()
    assert not alive, "regenerating a round waited for another band's kernel"
    np.testing.assert_array_equal(got["rounds"], want)
    np.testing.assert_array_equal(got["round"], want_7)


class _CountingTire:
    """The reference tire, counting its modal syntheses."""

    def __init__(self):
        self._tire = fc.reference_tire()
        self.n_modes = self._tire.n_modes
        self.calls = 0

    def truncations(self, *args, **kw):
        self.calls += 1
        return self._tire.truncations(*args, **kw)


def test_a_new_seed_reuses_the_subsystem_arrays():
    """Bands that differ in their noise settings only (a dashboard user changing the seed,
    one request after the other) synthesise the tire once; N or the harmonic again."""
    tire = _CountingTire()
    kw = {"rounds": 64, "n_modes": 20, "tire": tire}
    a = fc.scatter_band(2, seed=1, **kw)
    b = fc.scatter_band(2, seed=2, noise=0.2, frequency_dependent=True, **kw)
    assert tire.calls == 1
    fc.scatter_band(2, seed=1, **{**kw, "n_modes": 30})
    fc.scatter_band(3, seed=1, **kw)
    assert tire.calls == 3
    # the same numbers as with the tire synthesised afresh
    fresh = fc.scatter_band(2, seed=2, noise=0.2, frequency_dependent=True, **{
        **kw, "tire": _CountingTire()
    })  # fmt: skip
    np.testing.assert_array_equal(b.maximum, fresh.maximum)
    np.testing.assert_array_equal(b.reference, fresh.reference)
    assert not np.array_equal(a.maximum, b.maximum)
