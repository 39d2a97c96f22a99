"""Names renamed for issue 16 (one name per concept): each old name still works for one
release, warns with a DeprecationWarning naming the new one, and gives what the new name
gives. The truth of the new names is tested where they live; here the old and new paths
are compared and checked against an independent source (the model the file was written
from)."""

from __future__ import annotations

import numpy as np
import pytest
from test_io_modal import small_tire

import fbs_core
from fbs_core import io as fio
from fbs_core import tire as ftire
from fbs_core.io.modal import write_tire_mat
from fbs_core.studies.scatter import scatter_band_arrays
from fbs_core.tire import storage


def _same_model(a, b):
    for name in ("speeds", "poles", "psi", "chi", "wavelengths", "participation"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_tire_load_tire_model_is_read_tire_h5(tmp_path):
    written = small_tire(seed=3)
    path = storage.save_tire_model(written, tmp_path / "t.h5")
    new = ftire.read_tire_h5(path)
    _same_model(new, written)
    with pytest.warns(DeprecationWarning, match="read_tire_h5"):
        old = ftire.load_tire_model(path)
    _same_model(old, new)
    with pytest.warns(DeprecationWarning, match="read_tire_h5"):
        storage.load_tire_model(path)


def test_io_load_tire_model_is_import_tire_model():
    written = small_tire(seed=4)
    raw = write_tire_mat(written)
    new = fio.import_tire_model(raw, filename="t.mat")
    _same_model(new.model, written)
    with pytest.warns(DeprecationWarning, match="import_tire_model"):
        old = fio.load_tire_model(raw, filename="t.mat")
    _same_model(old.model, new.model)
    assert (old.summary, old.format, old.source) == (new.summary, new.format, new.source)
    assert "import_tire_model" in fio.__all__ and "read_tire_h5" in fbs_core.tire.__all__


def test_scatter_band_lower_upper_are_minimum_maximum():
    rng = np.random.default_rng(5)
    f = np.linspace(10.0, 50.0, 12)

    def c(*shape):
        return rng.normal(size=shape) + 1j * rng.normal(size=shape)

    YjjA = c(12, 6, 6) + 8 * np.eye(6)  # well away from singular
    band = scatter_band_arrays(YjjA, c(12, 6), c(12, 6, 6), c(12, 3, 6), freq=f, rounds=60)
    z = band.rounds_response(np.arange(band.rounds))  # each round regenerated alone
    every = np.sqrt(z.real * z.real + z.imag * z.imag)  # |v_e| evaluated as the kernel does
    np.testing.assert_array_equal(band.minimum, every.min(0))
    np.testing.assert_array_equal(band.maximum, every.max(0))
    with pytest.warns(DeprecationWarning, match="ScatterBand.minimum"):
        np.testing.assert_array_equal(band.lower, band.minimum)
    with pytest.warns(DeprecationWarning, match="ScatterBand.maximum"):
        np.testing.assert_array_equal(band.upper, band.maximum)
    conv = band.convergence
    np.testing.assert_array_equal(conv.maximum[-1], band.maximum)
    with pytest.warns(DeprecationWarning, match="Convergence.minimum"):
        np.testing.assert_array_equal(conv.lower, conv.minimum)
    with pytest.warns(DeprecationWarning, match="Convergence.maximum"):
        np.testing.assert_array_equal(conv.upper, conv.maximum)


def test_noise_target_vehicle_is_the_chassis():
    rng = np.random.default_rng(6)
    f = np.linspace(10.0, 50.0, 8)

    def c(*shape):
        return rng.normal(size=shape) + 1j * rng.normal(size=shape)

    arrays = (c(8, 6, 6) + 8 * np.eye(6), c(8, 6), c(8, 6, 6), c(8, 3, 6))
    new = scatter_band_arrays(*arrays, target="chassis", freq=f, rounds=40, seed=2)
    tire = scatter_band_arrays(*arrays, target="tire", freq=f, rounds=40, seed=2)
    # noise in the chassis only: the tire's factors are all 1, the chassis' are not
    fc_, ft_ = new.factors(3, 2), tire.factors(3, 2)
    assert np.all(fc_["Yjj_A"] == 1.0) and not np.all(fc_["Yjj_E"] == 1.0)
    assert np.all(ft_["Yjj_E"] == 1.0)
    with pytest.warns(DeprecationWarning, match="'vehicle' is deprecated; use 'chassis'"):
        old = scatter_band_arrays(*arrays, target="vehicle", freq=f, rounds=40, seed=2)
    assert old.target == "chassis"
    np.testing.assert_array_equal(old.maximum, new.maximum)
    np.testing.assert_array_equal(old.round(7), new.round(7))


def test_campaign_target_spellings_keep_case_names_and_seeds(tmp_path):
    from fbs_core.campaign import parse_campaign

    def case(target):
        text = (
            f'[campaign]\nname = "t"\nseed = 7\noutput = "{(tmp_path / "o.h5").as_posix()}"\n'
            f'[scatter]\nharmonics = [1]\nnoise = [0.1]\ntargets = ["{target}"]\nrounds = 50\n'
        )
        (c,) = parse_campaign(text, tmp_path).band_cases
        return c

    chassis, vehicle = case("chassis"), case("vehicle")
    assert chassis.target == vehicle.target == "chassis"
    assert (chassis.name, chassis.seed, chassis.digest()) == (
        vehicle.name,
        vehicle.seed,
        vehicle.digest(),
    )
    # the first release's spelling in the name keeps the seed of every existing campaign
    assert "_vehicle_" in chassis.name


def test_percent_and_fraction_are_inverse_and_match_the_core_docs():
    from fbs_core.vocabulary import fraction, percent

    # the core's fractions: a 10 % noise draws factors in [0.9, 1.1] (checked on a band)
    rng = np.random.default_rng(8)
    f = np.linspace(10.0, 50.0, 4)
    z = rng.normal(size=(4, 6, 6)) + 8 * np.eye(6)
    band = scatter_band_arrays(
        z + 0j, z[:, :, 0] + 0j, z + 0j, z[:, :3] + 0j, noise=fraction(10.0), freq=f, rounds=30
    )
    s = np.concatenate([band.factors(r, 0)["Yjj_E"].ravel() for r in range(band.rounds)])
    assert 0.9 <= s.min() < 0.91 and 1.09 < s.max() <= 1.1
    assert percent(band.noise) == 10.0
    x = np.array([0.07, 0.2, 1.0])
    np.testing.assert_array_equal(fraction(percent(x)), x)


@pytest.mark.parametrize(
    "function, kwargs",
    [
        (fbs_core.analysis.speed_map, {"n_modes": 40, "speeds": [40.0, 60.0]}),
        (fbs_core.analysis.bushing_contributions, {"n_modes": 40}),
        (fbs_core.bushing_response, {"n_modes": 40}),
    ],
)
def test_harmonic_case_keyword_is_harmonic(function, kwargs):
    """``harmonic_case=`` (old) warns and gives what ``harmonic=`` gives; neither or both
    is a TypeError naming the function."""
    new = function(harmonic=1, **kwargs)
    with pytest.warns(DeprecationWarning, match="harmonic_case=.*use harmonic="):
        old = function(harmonic_case=1, **kwargs)
    for name in ("response", "terms", "data"):
        if hasattr(new, name):
            np.testing.assert_array_equal(getattr(old, name), getattr(new, name))
            break
    else:
        raise AssertionError(f"no data attribute on {type(new).__name__}")
    with pytest.raises(TypeError, match=function.__name__):
        function(**kwargs)
    with pytest.raises(TypeError, match="give 'harmonic' only"), pytest.warns(DeprecationWarning):
        function(1, harmonic_case=1, **kwargs)


def test_tire_truncated_is_subset_of_the_first_stored_pairs():
    """``TireModel.truncated(N)`` (issue 30: the name hid that it keeps the first N stored
    modes, not the lowest of each operating point) warns, naming ``subset``, and gives the
    first N stored modes plus the residual of the others, as ``subset(range(N // 2))``."""
    tire = fbs_core.reference_tire()
    with pytest.warns(DeprecationWarning, match=r"subset\(range\(N // 2\)\)"):
        old = tire.truncated(40)
    new = tire.subset(range(20))
    _same_model(old, new)
    np.testing.assert_array_equal(old.residual, new.residual)
    np.testing.assert_array_equal(old.poles, tire.poles[:, :40])  # the stored order
    # the residual is the static part of the modes left out, per operating point (psi
    # chi^T and psi p over -lambda; no zero poles among the modes left out)
    p = tire.poles[:, 40:]
    R = np.einsum("smi,smj->smij", tire.psi[:, 40:], tire.chi[:, 40:]).reshape(*p.shape, 36)
    np.testing.assert_allclose(old.residual[:, :36], -(R / p[..., None]).sum(axis=1), rtol=1e-9)


def test_analysis_level_db_is_magnitude_db_without_a_floor():
    from fbs_core.analysis import level_db
    from fbs_core.vocabulary import magnitude_db

    h = np.array([10.0, 0.1j, -2.0, 0.0])  # 20, -20, 20 log10 2, -inf (no floor)
    want = [20.0, -20.0, 20 * np.log10(2.0), -np.inf]
    with pytest.warns(DeprecationWarning, match="magnitude_db"):
        old = level_db(h, ref=1.0)
    np.testing.assert_allclose(old, want)
    np.testing.assert_array_equal(old, magnitude_db(h, floor=None))
    with pytest.warns(DeprecationWarning):
        np.testing.assert_allclose(level_db(h[:2], ref=10.0), [0.0, -40.0])
