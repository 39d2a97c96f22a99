"""The reference car without tires: exact FRFs, mirror symmetry, the thesis' rear corner
inside it, its landmarks beside their sources, and the shipped file.

Truth: the direct solution of the car's matrices (``K - w^2 M + j w C``, the dampers
viscous), the mirror image as a permutation with the signs of ``MIRROR`` (an exact
change of coordinates), the single corner's own matrices, and published ranges.
"""

from __future__ import annotations

import inspect
import re
from pathlib import Path

import h5py
import numpy as np
import pytest

import fbs_core.vehicle as fv
from fbs_core import reference_chassis
from fbs_core.errors import DataFormatError, DOFError, FrequencyGridError, QuantityError
from fbs_core.io import load_frf
from fbs_core.vehicle import MIRROR, RESPONSES, SPINDLES, FRFVehicle, reference_vehicle
from fbs_core.vehicle.landmarks import landmark_table, mass_properties
from fbs_core.vehicle.storage import DATA_FILE, read_vehicle_frf

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def car():
    return reference_vehicle()


def test_frf_equals_the_direct_solution_with_the_dampers(car):
    f = np.array([0.8, 11.0, 31.0, 140.0])
    outs = ["spindle_fl:z", "spindle_rr:ry", "seat_fl:z", "bushing_rl:x", "strut_fr:y"]
    ins = ["spindle_fl:z", "spindle_rr:x", "spindle_fr:ry"]
    Y = car.mobility(f, outs, ins)
    D = car.system().frf(f, outs, ins)
    assert np.abs(Y.data - D.data).max() < 1e-8 * np.abs(D.data).max()
    # the dampers matter: without them the response differs
    s = car.system()
    from fbs_core import SecondOrderSystem

    undamped = SecondOrderSystem(s.M, None, s.K, s.dofs).frf(f[:2], outs, ins)
    assert np.abs(undamped.data - D.data[:2]).max() > 1e-2 * np.abs(D.data[:2]).max()
    assert len(car.dampers) == 4
    assert car.wheelbase == pytest.approx(2.70)
    assert car.track == pytest.approx((1.55, 1.50))


def _side_free(node):
    """A node's name with its side letter masked (``b.rail_l.x`` and ``b.rail_r.x`` alike)."""
    return re.sub(r"(^|[._])([fr]?)[lr](?=[.\-:]|$)", r"\1\2?", node)


def _mirror_permutation(car):
    """DOF i -> index of its mirror twin's DOF (the node at (x, -y, z) of the same name
    but for the side; several nodes may share a point, e.g. both ends of a bushing), and
    the sign (MIRROR) of the direction."""
    s = car.system()
    key = {}
    for i, lab in enumerate(s.dofs):
        node, d = lab.split(":")
        x, y, z = car.xyz(node)
        key[(round(x, 9), round(y, 9), round(z, 9), _side_free(node), d)] = i
    assert len(key) == s.n
    perm = np.empty(s.n, int)
    sign = np.empty(s.n)
    for i, lab in enumerate(s.dofs):
        node, d = lab.split(":")
        x, y, z = car.xyz(node)
        perm[i] = key[(round(x, 9), round(-y, 9), round(z, 9), _side_free(node), d)]
        sign[i] = MIRROR[("x", "y", "z", "rx", "ry", "rz").index(d)]
    return perm, sign


def test_right_side_is_the_exact_mirror_image_of_the_left(car):
    """T K T = K with T the mirror permutation and signs: the whole car (body, both strut
    fronts, the rear axle with the thesis' corner on both sides, dampers) is symmetric."""
    perm, sign = _mirror_permutation(car)
    s = car.system()
    for name in ("M", "K", "C"):
        A = getattr(s, name).toarray()
        B = sign[:, None] * A[np.ix_(perm, perm)] * sign[None, :]
        assert np.abs(B - A).max() <= 1e-12 * np.abs(A).max(), name
    # mirrored labels are the other side's
    i = s.dofs.index("spindle_fl:y")
    assert s.dofs[perm[i]] == "spindle_fr:y" and sign[i] == -1
    assert s.dofs[perm[s.dofs.index("bushing_rl:z")]] == "bushing_rr:z"


def test_rear_axle_carries_the_thesis_corner(car):
    """The carrier, its link bushing and the A-arm of the rear-left wheel are the single
    corner's (fbs_core.chassis), translated to the rear axle: same mass and stiffness blocks."""
    s, c = car.system(), reference_chassis().system()

    def block(sys, mat, a, b):
        ia = [sys.dofs.index(f"{a}:{d}") for d in ("x", "y", "z", "rx", "ry", "rz")]
        ib = [sys.dofs.index(f"{b}:{d}") for d in ("x", "y", "z", "rx", "ry", "rz")]
        return getattr(sys, mat).toarray()[np.ix_(ia, ib)]

    pairs = {"spindle": "spindle_rl", "apex": "r.apex_l"}
    for mat, a, b in (
        ("M", "spindle", "spindle"),
        ("K", "spindle", "apex"),
        ("K", "spindle", "spindle"),
    ):
        mine = block(s, mat, pairs[a], pairs[b])
        ref = block(c, mat, a, b)
        # the rear damper adds to the carrier's C, not to M or K
        assert np.abs(mine - ref).max() <= 1e-12 * np.abs(ref).max(), (mat, a, b)
    # the corner's wheel centre (0, 0.75, 0.08) moved to the rear axle at wheel height
    assert car.xyz("spindle_rl") == pytest.approx((-2.70, 0.75, 0.30))


def test_landmarks_lie_in_their_published_ranges(car):
    rows = landmark_table(car)
    names = [r.name for r in rows]
    for key in ("bounce", "pitch", "roll", "wheel hop front", "wheel hop rear"):
        assert key in names
    assert any("torsion" in n for n in names) and any("bending" in n for n in names)
    outside = [(r.name, round(r.frequency, 2), r.low, r.high) for r in rows if not r.inside]
    assert outside == []
    assert all(r.source for r in rows)
    by = {r.name: r.frequency for r in rows}
    # the ride modes are the slowest, then wheel hop, then the body's own modes
    assert max(by["bounce"], by["pitch"], by["roll"]) < min(by["wheel hop front"], 5.0) + 5.0
    assert by["wheel hop rear"] < by["body torsion (on suspension)"]
    mp = [(r.name, round(r.frequency, 3)) for r in mass_properties(car) if not r.inside]
    assert mp == []


def _stored_matrix(group) -> np.ndarray:
    """A CSR matrix of an HDF5 group (``data``, ``indices``, ``indptr``) as a dense array."""
    from scipy.sparse import csr_matrix

    data, indices, indptr = (group[k][()] for k in ("data", "indices", "indptr"))
    return csr_matrix((data, indices, indptr), shape=tuple(group.attrs["shape"])).toarray()


def test_shipped_file_regenerates(tmp_path, car):
    from importlib import util

    spec = util.spec_from_file_location("brv", ROOT / "scripts" / "build_reference_vehicle.py")
    mod = util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = tmp_path / "v.h5"
    assert mod.main(["--out", str(out)]) == 0
    new, old = read_vehicle_frf(out), read_vehicle_frf(DATA_FILE)
    assert new.outputs == old.outputs == SPINDLES + RESPONSES and new.inputs == SPINDLES
    np.testing.assert_array_equal(new.freq, old.freq)
    # LAPACK results vary at ~1e-9 with the thread count (as the chassis file)
    np.testing.assert_allclose(new.data, old.data, rtol=1e-6, atol=1e-9 * np.abs(old.data).max())
    with h5py.File(out) as a, h5py.File(DATA_FILE) as b:
        assert a["parameters"].attrs["json"] == b["parameters"].attrs["json"]
        assert a["dampers"].attrs["json"] == b["dampers"].attrs["json"]
        for name in ("M", "K", "C"):
            # the matrices, not their stored entries: an entry that is zero up to rounding
            # (1e-19 against entries of order 1) may differ from one BLAS to another
            new_, old_ = (_stored_matrix(f["system"][name]) for f in (a, b))
            scale = np.abs(old_).max()
            np.testing.assert_allclose(new_, old_, rtol=1e-12, atol=1e-13 * scale)
            assert scale > 0
    # the project's generic reader sees the same FRF: a vehicle FRF like any user's
    np.testing.assert_array_equal(load_frf(DATA_FILE).frf.data, old.data)


def test_bad_input(car, tmp_path):
    with pytest.raises(FrequencyGridError, match="> 0 Hz"):
        car.mobility([0.0, 1.0])
    with pytest.raises(DOFError, match="vehicle output DOF 'seat:z'"):
        car.mobility([1.0], outputs=["seat:z"])
    with pytest.raises(QuantityError, match="allowed"):
        car.mobility([1.0], quantity="velocity")
    with pytest.raises(DOFError, match="unknown vehicle node"):
        car.xyz("nowhere")
    Y = car.mobility([1.0, 2.0])
    with pytest.raises(DOFError, match="wheel.*rl, rr"):
        front_only = [i for i in Y.inputs if i.split(":")[0] in ("spindle_fl", "spindle_fr")]
        FRFVehicle(Y.sel(inputs=front_only), 2.7, 1.5)
    with pytest.raises(DataFormatError, match="positive lengths"):
        FRFVehicle(Y, -2.7, 1.5)
    with pytest.raises(FrequencyGridError, match="interpolate=True"):
        FRFVehicle(Y, 2.7, 1.5).mobility([1.5])
    assert FRFVehicle(Y, 2.7, 1.5, interpolate=True).mobility([1.5]).shape == (1, 84, 24)
    bad = tmp_path / "x.h5"
    with h5py.File(bad, "w") as h:
        h.attrs["format"] = "tire-fbs"
    with pytest.raises(DataFormatError, match="not a 'tire-fbs' reference vehicle"):
        read_vehicle_frf(bad)


@pytest.mark.parametrize("name", [n for n in fv.__all__ if callable(getattr(fv, n))])
def test_public_callable_is_documented(name):
    obj = getattr(fv, name)
    doc = inspect.getdoc(obj)
    assert doc and len(doc.strip()) > 20, f"fbs_core.vehicle.{name} has no docstring"
    target = obj.__init__ if inspect.isclass(obj) else obj
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return
    if inspect.isclass(obj) and target is object.__init__:
        return
    missing = [
        p
        for p in sig.parameters
        if p not in ("self", "cls")
        and sig.parameters[p].kind
        not in (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
        and p not in doc
    ]
    assert not missing, f"fbs_core.vehicle.{name}: parameters {missing} not in its docstring"
