"""Parameter variants of the reference models (issue 32): parameters, designs, rebuilt models.

Truths: the ring's closed form (reference-models.md 2.1) with the pressure entering as
``T_p = p b R`` and the tread mass as ``rhoA = m / (2 pi R)``; the chassis' mass by hand
(tube geometry, knuckle) and the springs' matrices by their definition; the coupled response
of a rebuilt variant against the direct solution of its own matrices; the stratification
of a Latin hypercube and the pick-freeze structure of a Saltelli design.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg

import fbs_core
import fbs_core.variants as fv
from fbs_core.chassis import STEEL_RHO, ChassisModel, ChassisParameters
from fbs_core.prediction import direct_bushing_response
from fbs_core.tire import DEFAULT_PARAMETERS, TireParameters, ring_closed_form, system_matrices
from fbs_core.tire.storage import reference_tire, save_tire_model

#: A tire that rebuilds in a fraction of a second: few orders, one slip zone, six speeds.
CHEAP = TireParameters(orders=(6, 3, 4, 3, -1, -1, -1, -1), slip_zones=1)
SPEEDS = (20.0, 40.0, 60.0, 80.0, 100.0, 120.0)
SETTINGS = fv.VariantSettings(harmonics=(4,), speeds=SPEEDS, tire=CHEAP)


# ---- parameters ---------------------------------------------------------------------------


def test_nominal_values_return_the_reference_models_themselves():
    values = {n: p.nominal() for n, p in fv.PARAMETERS.items()}
    t, c = fv.apply_values(values)
    assert t is DEFAULT_PARAMETERS and c == ChassisParameters()
    assert type(c) is ChassisParameters  # the reference's own parameters, no variant fields
    # the nominal variant is the shipped tire itself and the reference chassis' parameters
    tire, chassis = fv.variant_models({}, fv.VariantSettings())
    assert tire is reference_tire() and chassis.params == fbs_core.reference_chassis().params
    # by hand: p = T_p / (b R) = 10.6 kN / (0.16 m x 0.30 m)
    assert fv.PARAMETERS["inflation_pressure"].nominal() == pytest.approx(10.6e3 / 0.048)
    d, t_ = 0.035, 0.003
    arm = STEEL_RHO * np.pi / 4 * (d**2 - (d - 2 * t_) ** 2) * 2 * np.hypot(0.20, 0.25)
    assert fv.PARAMETERS["arm_mass"].nominal() == pytest.approx(arm, rel=1e-12)


def _ring_frequencies(params, speed=0.0):
    M, D, G, K = system_matrices(speed, params)
    b = slice(6, None)  # rim clamped
    n = M.shape[0] - 6
    A = np.block(
        [
            [np.zeros((n, n)), np.eye(n)],
            [-np.linalg.solve(M[b, b], K[b, b]), -np.linalg.solve(M[b, b], G[b, b])],
        ]
    )
    lam = np.linalg.eigvals(A)
    return np.sort(lam.imag[lam.imag > 0]) / (2 * np.pi)


def test_tire_parameters_enter_the_ring_as_its_closed_form():
    """In-plane ring alone (rim clamped, no contact): every order follows Huang & Soedel's
    closed form written here by hand with ``T_p = p b R`` and ``rhoA = m / (2 pi R)``."""
    base = TireParameters(
        orders=(8, -1, -1, -1, -1, -1, -1, -1), k_cx=0, k_cy=0, k_cz=0, slip_zones=0
    )
    p, EI, kw, kv, m = 190e3, 3.0, 1.3e6, 5.0e5, 6.0
    values = {
        "inflation_pressure": p,
        "belt_bending_stiffness": EI,
        "sidewall_radial_stiffness": kw,
        "sidewall_tangential_stiffness": kv,
        "tread_mass": m,
    }
    t, _ = fv.apply_values(values, base)
    R, b = base.R, base.b
    Tp, rhoA = p * b * R, m / (2 * np.pi * R)
    expected = []
    for n in range(9):
        Kn = EI * n**2 * (n**2 - 1) ** 2 / R**4 + Tp * n**2 * (n**2 - 1) / R**2 + kw * n**2 + kv
        f = np.sqrt(Kn / (rhoA * (n**2 + 1))) / (2 * np.pi)
        expected += [f] if n == 0 else [f, f]  # standing still: both waves at one frequency
    np.testing.assert_allclose(_ring_frequencies(t), np.sort(expected), rtol=1e-9)
    # and the library's closed form agrees with the variant's own fields
    assert ring_closed_form(3, 0.0, t)[0] == pytest.approx(expected[5], rel=1e-12)
    assert t.n_y == pytest.approx(base.n_y * p / (base.T_p / (b * R)), rel=1e-12)
    assert t.zeta == base.zeta and t.F_z0 == base.F_z0  # untouched


def _total_mass(ch):
    s = ch.system()
    u = np.zeros(s.n)
    u[[i for i, d in enumerate(s.dofs) if d.endswith(":z")]] = 1.0
    return u @ (s.M @ u)


def test_chassis_masses_by_hand():
    ref = ChassisModel()
    m0 = _total_mass(ref)
    _, c = fv.apply_values({"knuckle_mass": 20.5})
    assert _total_mass(ChassisModel(c)) - m0 == pytest.approx(2.5, rel=1e-9)
    assert c.carrier_inertia == pytest.approx(tuple(i * 20.5 / 18.0 for i in (0.25, 0.20, 0.25)))
    arm0 = fv.PARAMETERS["arm_mass"].nominal()
    _, c = fv.apply_values({"arm_mass": 1.7})
    assert _total_mass(ChassisModel(c)) - m0 == pytest.approx(1.7 - arm0, rel=1e-9)
    assert fv.PARAMETERS["arm_mass"].nominal(c) == pytest.approx(1.7, rel=1e-12)
    # the arm's mass alone: its stiffness is the reference's
    np.testing.assert_array_equal(ChassisModel(c).system().K.toarray(), ref.system().K.toarray())


def _K(values):
    _, c = fv.apply_values(values)
    return ChassisModel(c).system()


def test_chassis_stiffnesses_change_where_they_act():
    ref = ChassisModel().system()
    K0, M0 = ref.K.toarray(), ref.M.toarray()
    dofs = ref.dofs
    p = ChassisParameters()
    corners = ("bushing", "bush_rl", "bush_rr", "bush_fr")
    # body bushings: a grounded spring k (1 + j eta) on each corner's six DOFs, by definition
    s = _K({"body_bushing_stiffness": 1.2})
    dK = s.K.toarray() - K0
    want = np.zeros_like(K0)
    for c in corners:
        for d, k in zip(fbs_core.DIRECTIONS, p.bushing_stiffness, strict=True):
            i = dofs.index(f"{c}:{d}")
            want[i, i] = 0.2 * k * (1 + 1j * p.bushing_loss)
    np.testing.assert_allclose(dK, want, rtol=1e-9, atol=1e-9 * np.abs(K0).max())
    dK = _K({"body_bushing_loss": 0.19}).K.toarray() - K0
    want = np.zeros_like(K0)
    for c in corners:
        for d, k in zip(fbs_core.DIRECTIONS, p.bushing_stiffness, strict=True):
            i = dofs.index(f"{c}:{d}")
            want[i, i] = 0.04j * k
    np.testing.assert_allclose(dK, want, rtol=1e-9, atol=1e-9 * np.abs(K0).max())
    # the link bushing joins the carrier and the arm apex: nothing else changes
    dK = _K({"link_stiffness": 0.9}).K.toarray() - K0
    touched = {dofs[i].split(":")[0] for i in np.flatnonzero(np.abs(dK).sum(axis=0))}
    assert touched == {"spindle", "apex"}
    # the arm's modulus: its own DOFs only, linear in the factor, mass unchanged
    a, b = _K({"arm_stiffness": 1.1}), _K({"arm_stiffness": 0.85})
    dA, dB = a.K.toarray() - K0, b.K.toarray() - K0
    touched = {dofs[i].split(":")[0] for i in np.flatnonzero(np.abs(dA).sum(axis=0))}
    assert touched and all(n.startswith(("arm-", "apex", "root_")) for n in touched)
    np.testing.assert_allclose(dB, -1.5 * dA, rtol=1e-9, atol=1e-9 * np.abs(K0).max())
    np.testing.assert_array_equal(a.M.toarray(), M0)


def test_bad_parameters_are_refused_by_name():
    with pytest.raises(fv.ParameterError, match="unknown parameter 'tyre_pressure'.*known"):
        fv.parameter("tyre_pressure")
    with pytest.raises(fv.ParameterError, match="knuckle_mass = -1.*allowed: 0 < knuckle_mass"):
        fv.apply_values({"knuckle_mass": -1.0})
    with pytest.raises(fv.ParameterError, match="body_bushing_loss = 1.5.*< 1"):
        fv.apply_values({"body_bushing_loss": 1.5})
    with pytest.raises(fv.ParameterError, match="low < high"):
        fv.ParameterSpace.from_names(["wheel_load"], {"wheel_load": [5000, 3000]})
    with pytest.raises(fv.ParameterError, match="not varied"):
        fv.ParameterSpace.from_names(["wheel_load"], {"tread_mass": [6, 7]})
    with pytest.raises(fv.ParameterError, match="distinct"):
        fv.ParameterSpace.from_names(["wheel_load", "wheel_load"])
    with pytest.raises(fv.ParameterError, match="unknown chassis parameter 'tread_mass'"):
        fv.Parameter("tread_mass", "chassis", "kg", 1, 2, (0, 9), "", "")
    custom = fv.Parameter("k1", "custom", "N/m", 1.0, 2.0, (0.0, np.inf), "", "")
    with pytest.raises(fv.ParameterError, match="custom parameter"):
        custom.apply(CHEAP, 1.5)
    assert issubclass(fv.ParameterError, ValueError)


# ---- designs -------------------------------------------------------------------------------

SPACE = fv.ParameterSpace.from_names(["inflation_pressure", "knuckle_mass", "link_loss"])


def test_latin_hypercube_and_sobol_designs():
    d = fv.sample_design(SPACE, 10, "lhs", seed=3)
    for col in d.unit.T:  # one point in each of the 10 strata of every parameter
        assert sorted(np.floor(col * 10).astype(int)) == list(range(10))
    assert np.all((d.values >= SPACE.low) & (d.values <= SPACE.high))
    np.testing.assert_array_equal(d.unit, fv.sample_design(SPACE, 10, "lhs", seed=3).unit)
    assert not np.array_equal(d.unit, fv.sample_design(SPACE, 10, "lhs", seed=4).unit)
    s = fv.sample_design(SPACE, 16, "sobol", seed=1)
    for col in s.unit.T:  # a scrambled Sobol' net: balanced in every coordinate too
        assert sorted(np.floor(col * 16).astype(int)) == list(range(16))
    assert s.row(0) == dict(zip(SPACE.names, s.values[0], strict=True))
    with pytest.raises(fv.ParameterError, match="power of two"):
        fv.sample_design(SPACE, 12, "sobol")
    with pytest.raises(fv.ParameterError, match="unknown design 'grid'; allowed: sobol, lhs"):
        fv.sample_design(SPACE, 8, "grid")
    with pytest.raises(fv.ParameterError, match="seed"):
        fv.sample_design(SPACE, 8, "lhs", seed=-1)
    with pytest.raises(fv.ParameterError, match="no Saltelli blocks"):
        s.blocks()


def test_saltelli_design_is_pick_freeze_and_its_prefix_is_the_smaller_design():
    d = fv.sample_design(SPACE, 8, "saltelli", seed=2)
    assert d.n == 8 * (3 + 2) and d.n_base == 8
    blk = d.blocks()
    A, B = d.unit[blk["A"]], d.unit[blk["B"]]
    for i, name in enumerate(SPACE.names):
        ABi = d.unit[blk[f"AB_{name}"]]
        np.testing.assert_array_equal(ABi[:, i], B[:, i])
        np.testing.assert_array_equal(np.delete(ABi, i, axis=1), np.delete(A, i, axis=1))
    small = fv.sample_design(SPACE, 4, "saltelli", seed=2)
    for key, rows in small.blocks().items():
        np.testing.assert_array_equal(small.unit[rows], d.unit[blk[key][:4]])


# ---- rebuilt models ------------------------------------------------------------------------


def test_tire_cache_is_keyed_by_content_in_memory_and_on_disk(tmp_path):
    k = fv.tire_key(CHEAP, SPEEDS)
    assert k == fv.tire_key(dataclasses.replace(CHEAP), [int(v) for v in SPEEDS])
    assert k != fv.tire_key(dataclasses.replace(CHEAP, EI=5.000001), SPEEDS)
    assert k != fv.tire_key(CHEAP, SPEEDS[:-1])
    cache = fv.TireCache(maxsize=1, directory=tmp_path)
    t1 = cache.get(CHEAP, SPEEDS)
    assert cache.get(CHEAP, SPEEDS) is t1 and cache.builds == 1
    assert (tmp_path / f"{k}.h5").is_file() and t1.meta["variant_key"] == k
    other = fv.TireCache(directory=tmp_path)  # another process: reads, does not build
    t2 = other.get(CHEAP, SPEEDS)
    assert other.builds == 0
    for name in ("speeds", "poles", "psi", "chi", "participation"):
        np.testing.assert_array_equal(getattr(t2, name), getattr(t1, name))
    # a file under the key that holds another tire is not trusted: rebuilt
    wrong = fv.TireCache(maxsize=0).get(dataclasses.replace(CHEAP, EI=4.0), SPEEDS)
    save_tire_model(wrong, tmp_path / f"{k}.h5")
    third = fv.TireCache(directory=tmp_path)
    t3 = third.get(CHEAP, SPEEDS)
    assert third.builds == 1 and t3.params == CHEAP
    # deterministic: a rebuild gives the same numbers
    np.testing.assert_array_equal(t3.poles, t1.poles)


def test_a_variants_response_is_the_physics_of_its_own_parameters():
    """At lines whose speed on the harmonic line is an operating point the modal model is
    exact: the coupled response equals the direct solution of the variant's own tire and
    chassis matrices (no modes, no FBS), and differs from the base's."""
    values = {"inflation_pressure": 190e3, "tread_mass": 6.2, "knuckle_mass": 16.0}
    tire, chassis = fv.variant_models(values, SETTINGS, fv.TireCache())
    tp, cp = fv.apply_values(values, CHEAP)
    assert tire.params == tp and chassis.params == cp
    h = fbs_core.harmonic(4)
    f = np.array([v / 3.6 / h.wavelength for v in (40.0, 60.0, 80.0)])
    modal = fbs_core.bushing_response(4, freq=f, tire=tire, chassis=chassis).data
    direct = direct_bushing_response(4, freq=f, tire=tire, chassis=chassis).data
    np.testing.assert_allclose(modal, direct, rtol=1e-6, atol=1e-9 * np.abs(direct).max())
    base_tire, base_chassis = fv.variant_models({}, SETTINGS)
    base = direct_bushing_response(4, freq=f, tire=base_tire, chassis=base_chassis).data
    assert np.max(np.abs(base - direct) / np.abs(direct)) > 0.01


def test_study_builds_each_tire_once_and_is_deterministic():
    space = fv.ParameterSpace.from_names(["inflation_pressure", "knuckle_mass", "link_loss"])
    design = fv.sample_design(space, 2, "saltelli", seed=5)
    cache = fv.TireCache(maxsize=1)
    seen = []
    study = fv.run_variants(design, SETTINGS, cache=cache, progress=lambda d, n: seen.append(d))
    # the chassis columns of AB_i share A's tire; AB_pressure takes B's only tire column
    assert len(set(study.tire_keys)) == 4 and cache.builds == 4 + 1  # + the nominal tire
    assert seen[0] == 0 and seen[-1] == design.n
    assert study.responses[4].shape == (design.n, study.freq(4).size, 6)
    i = 7
    again = fv.variant_responses(design.row(i), SETTINGS, fv.TireCache())
    np.testing.assert_array_equal(again[4], study.responses[4][i])
    np.testing.assert_array_equal(
        study.nominal[4], fv.variant_responses({}, SETTINGS, fv.TireCache())[4]
    )
    c = study.corridor(4)
    mag = np.abs(study.responses[4])
    np.testing.assert_array_equal(c.maximum, mag.max(axis=0))
    assert np.all(c.minimum <= c.percentiles[0]) and np.all(c.percentiles[-1] <= c.maximum)
    s = study.sensitivity(4, n_bootstrap=20)
    assert s.first.shape == (3, s.bands.shape[0], 6) and s.names == space.names
    with pytest.raises(fbs_core.DataFormatError, match="no harmonic 5"):
        study.corridor(5)
    with pytest.raises(fbs_core.StudyCancelled):
        fv.run_variants(design, SETTINGS, cancel=lambda: True)


def test_nominal_study_of_the_reference_models_is_the_shipped_prediction():
    """Chassis parameters only: the tire is the shipped one, and the nominal response is
    fbs_core.bushing_response's."""
    study = fv.corridor_study(["knuckle_mass", "body_bushing_loss"], n=4, method="lhs", seed=1)
    np.testing.assert_array_equal(study.nominal[4], fbs_core.bushing_response(4).data[:, :, 0])
    # one tire for every row: the base's (the key of the points the harmonic reads)
    speeds = fv.VariantSettings().tire_speeds()
    assert set(study.tire_keys) == {fv.tire_key(DEFAULT_PARAMETERS, speeds)}
    assert speeds == tuple(float(v) for v in reference_tire().speeds if v >= 27.5)


@pytest.mark.parametrize("name", [n for n in fv.__all__ if callable(getattr(fv, n))])
def test_public_callables_are_documented(name):
    """Every public name of fbs_core.variants has a docstring naming all its parameters
    (the check of tests/test_docstrings.py)."""
    import inspect

    obj = getattr(fv, name)
    doc = inspect.getdoc(obj)
    assert doc and len(doc.strip()) > 20, f"fbs_core.variants.{name} has no docstring"
    if inspect.isclass(obj) and issubclass(obj, BaseException):
        return
    sig = inspect.signature(obj.__init__ if inspect.isclass(obj) else obj)
    missing = [
        p
        for p, v in sig.parameters.items()
        if p not in ("self", "cls")
        and v.kind not in (v.VAR_POSITIONAL, v.VAR_KEYWORD)
        and p not in doc
    ]
    assert not missing, f"fbs_core.variants.{name}: parameters {missing} not in its docstring"


# ---- the rebuild's cost: fewer points, real arithmetic, workers ---------------------------


def test_left_eigenvectors_in_real_arithmetic_are_the_inverse_of_the_right_ones():
    from fbs_core.tire.modes import _inverse_of_eigenvectors
    from fbs_core.tire.ring import build_tire_system

    rng = np.random.default_rng(3)
    s = build_tire_system(50.0, CHEAP)
    n = s.M.shape[0]
    keep = np.flatnonzero(np.any(s.M != 0, axis=0))
    nm = keep.size
    A = np.zeros((n + nm, n + nm))
    A[:n, n:] = np.eye(n)[:, keep]
    A[n:, :n] = rng.standard_normal((nm, n))  # any real matrix: real and complex eigenvalues
    A[n:, n:] = rng.standard_normal((nm, nm))
    for B in (A, rng.standard_normal((40, 40))):
        lam, vr = scipy.linalg.eig(B)
        assert np.any(lam.imag == 0) and np.any(lam.imag != 0)
        W = _inverse_of_eigenvectors(lam, vr)
        truth = np.linalg.solve(vr, np.eye(lam.size))  # the complex inverse
        assert np.abs(W @ vr - np.eye(lam.size)).max() < 1e-9
        assert np.abs(W - truth).max() < 1e-9 * np.abs(truth).max()


def test_needed_speeds_keep_the_stencils_of_the_lines():
    sp = tuple(10.0 + 5 * i for i in range(23))  # 10 .. 120
    assert fv.needed_speeds(sp, 30.0, 120.0) == sp[3:]  # 25 .. 120: the cubic stencil of 30
    assert fv.needed_speeds(sp, 10.0, 120.0) == sp
    assert fv.needed_speeds(sp, 31.0, 44.0) == sp[3:9]  # 25 .. 50
    assert fv.needed_speeds(sp, 12.0, 118.0) == sp  # first and last interval: linear
    assert fv.needed_speeds(sp, 116.0, 118.0) == sp[-3:]  # last interval: linear, 110 kept
    assert fv.needed_speeds(SPEEDS, 30.0, 120.0) == SPEEDS


def test_a_tire_rebuilt_at_the_needed_points_responds_as_one_built_at_all():
    from fbs_core.prediction import bushing_response
    from fbs_core.tire.build import build_modal_model

    sp = tuple(10.0 + 10 * i for i in range(12))  # 10 .. 120: 10 km/h is not needed
    s = fv.VariantSettings(harmonics=(4, 7), speeds=sp, tire=CHEAP)
    assert s.tire_speeds() == sp[1:]
    values = {"inflation_pressure": 2.0e5, "tread_mass": 6.0}
    got = fv.variant_responses(values, s, fv.TireCache())
    tp, cp = fv.apply_values(values, CHEAP, s.chassis)
    whole = build_modal_model(tp, speeds=sp)  # all the points, as before
    for k in s.harmonics:
        ref = bushing_response(k, None, s.freq(k), tire=whole, chassis=ChassisModel(cp)).data[
            :, :, 0
        ]
        np.testing.assert_allclose(got[k], ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())


def test_workers_and_a_dask_cluster_give_the_numbers_of_this_process():
    from distributed import Client, LocalCluster

    design = fv.sample_design(fv.ParameterSpace.from_names(["tread_mass", "knuckle_mass"]), 4)
    here = fv.run_variants(design, SETTINGS, cache=fv.TireCache())
    seen: list[tuple[int, int]] = []
    pooled = fv.run_variants(
        design, SETTINGS, processes=2, progress=lambda d, t: seen.append((d, t))
    )
    assert seen[0] == (0, design.n) and seen[-1] == (design.n, design.n)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
    with (
        LocalCluster(
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address="127.0.0.1:0"
        ) as cluster,
        Client(cluster) as client,
    ):
        on_dask = fv.run_variants(design, SETTINGS, client=client)
    # other processes may run BLAS on another number of threads: the tires' eigensolutions
    # round differently (up to 5e-8 relative seen on a 2-core Xeon); a variant given another
    # variant's tire or parameters differs by O(1)
    for other in (pooled, on_dask):
        assert other.tire_keys == here.tire_keys
        np.testing.assert_allclose(other.responses[4], here.responses[4], rtol=1e-6, atol=0)
        np.testing.assert_allclose(other.nominal[4], here.nominal[4], rtol=1e-6, atol=0)
