"""The FRF data object: construction, selection, conversion, immutability, errors."""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core as fc
from fbs_core import FRF

F = np.array([1.0, 2.0, 5.0, 10.0])
OUT = ["hub:x", "hub:z", "bushing:rx"]
IN = ["hub:x", "patch"]


def _frf(quantity="mobility"):
    rng = np.random.default_rng(0)
    d = rng.normal(size=(4, 3, 2)) + 1j * rng.normal(size=(4, 3, 2))
    return FRF(F, d, OUT, IN, quantity)


def test_sel_and_isel_are_label_and_position_views_of_the_same_data():
    Y = _frf()
    a = Y.sel(outputs=["bushing:rx", "hub:x"], inputs="patch")
    b = Y.isel(outputs=[2, 0], inputs=[1])
    assert a.outputs == ("bushing:rx", "hub:x") and a.inputs == ("patch",)
    assert np.array_equal(a.data, b.data)
    assert np.array_equal(a.data[:, 0, 0], Y.data[:, 2, 1])
    assert Y.isel(freq=slice(1, 3)).freq.tolist() == [2.0, 5.0]
    assert Y.isel(outputs=-1).outputs == ("bushing:rx",)


def test_conversion_between_quantities_follows_j_omega():
    """A single-DOF mass m: receptance -1/(w^2 m), mobility 1/(j w m), accelerance 1/m."""
    m = 3.0
    w = 2 * np.pi * F
    H = FRF(F, (-1 / (w**2 * m))[:, None, None], ["m:z"], ["m:z"], "receptance")
    assert np.allclose(H.to("mobility").data[:, 0, 0], 1 / (1j * w * m))
    assert np.allclose(H.to("accelerance").data[:, 0, 0], 1 / m)
    A = H.to("accelerance")
    assert np.allclose(A.to("receptance").data, H.data)
    assert H.to("receptance") is H


def test_immutable():
    Y = _frf()
    with pytest.raises(ValueError):
        Y.data[0, 0, 0] = 1.0
    with pytest.raises(ValueError):
        Y.freq[0] = 0.5
    with pytest.raises(AttributeError):
        Y.quantity = "receptance"
    d = np.ones((4, 1, 1))
    Z = FRF(F, d, ["a:x"], ["a:x"])
    d[0, 0, 0] = 7.0  # the object owns a copy
    assert Z.data[0, 0, 0] == 1.0


def test_pickle_round_trip_rebuilds_an_equal_immutable_frf():
    """An FRF crosses to another process (a report's data to the report process) whole."""
    import pickle

    Y = FRF(
        F,
        np.arange(8.0).reshape(4, 2, 1) * (1 + 2j),
        ["patch", "b:rz"],
        ["a:x"],
        quantity="receptance",
        kinds={"patch": "road"},
    )
    Z = pickle.loads(pickle.dumps(Y))
    np.testing.assert_array_equal(Z.data, Y.data)
    np.testing.assert_array_equal(Z.freq, Y.freq)
    assert (Z.outputs, Z.inputs, Z.quantity) == (Y.outputs, Y.inputs, Y.quantity)
    assert (Z.units == Y.units).all()  # the kinds travel too
    with pytest.raises(ValueError):
        Z.data[0, 0, 0] = 1.0


def test_crop_interpolate_transpose_db():
    Y = _frf()
    assert Y.crop(2.0, 5.0).freq.tolist() == [2.0, 5.0]
    lin = FRF(F, (F * (1 + 2j))[:, None, None], ["a:x"], ["a:x"])
    assert np.allclose(lin.interpolate([1.5, 7.5]).data[:, 0, 0], np.array([1.5, 7.5]) * (1 + 2j))
    T = Y.transpose()
    assert T.outputs == tuple(IN) and np.array_equal(T.data[:, 1, 2], Y.data[:, 2, 1])
    db = FRF(F, np.full((4, 1, 1), 10.0), ["a:x"], ["a:x"]).magnitude_db()
    assert np.allclose(db, 20.0)
    assert "mobility 3x2 at 4 lines" in repr(Y)


@pytest.mark.parametrize(
    "kwargs, err, match",
    [
        (dict(freq=[2.0, 1.0]), fc.FrequencyGridError, "strictly increasing"),
        (dict(freq=[1.0, np.nan]), fc.FrequencyGridError, "finite"),
        (dict(freq=[-1.0, 1.0]), fc.FrequencyGridError, ">= 0"),
        (dict(freq=[[1.0, 2.0]]), fc.FrequencyGridError, "1-D"),
        (dict(freq=[1.0, 2.0], data=np.ones((2, 2, 1))), fc.DataFormatError, "expected"),
        (dict(data=np.full((2, 1, 1), np.inf)), fc.DataFormatError, "non-finite"),
        (dict(data=np.array([[["a"]], [["b"]]])), fc.DataFormatError, "numeric"),
        (dict(outputs=["hub:q"]), fc.DOFError, "unknown direction 'q'.*allowed: x, y, z"),
        (dict(outputs=["hub z"]), fc.DOFError, "malformed"),
        (dict(outputs=[":z"]), fc.DOFError, "malformed"),
        (dict(outputs=[3]), fc.DOFError, "string"),
        (dict(quantity="velocity"), fc.QuantityError, "allowed: receptance, mobility"),
    ],
)
def test_bad_construction(kwargs, err, match):
    base = dict(freq=[1.0, 2.0], data=np.ones((2, 1, 1)), outputs=["a:x"], inputs=["a:x"])
    base.update(kwargs)
    with pytest.raises(err, match=match):
        FRF(**base)


def test_duplicate_labels_and_unknown_selection():
    with pytest.raises(fc.DOFError, match="duplicate output labels: a:x"):
        FRF([1.0], np.ones((1, 2, 1)), ["a:x", "a:x"], ["a:x"])
    with pytest.raises(fc.DOFError, match="unknown output DOF 'hub:y'; available: hub:x, hub:z"):
        _frf().sel(outputs="hub:y")
    with pytest.raises(KeyError):  # DOFError is also a KeyError
        _frf().sel(inputs="hub:q")
    with pytest.raises(IndexError):
        _frf().isel(outputs=[5])


def test_grid_errors():
    Y = _frf()
    with pytest.raises(fc.FrequencyGridError, match="never interpolated"):
        Y.require_grid(Y.isel(freq=[0, 1]))
    with pytest.raises(fc.FrequencyGridError, match="never extrapolated"):
        Y.interpolate([0.5, 2.0])
    with pytest.raises(fc.FrequencyGridError, match="no lines"):
        Y.crop(20.0, 30.0)
    at0 = FRF([0.0, 1.0], np.ones((2, 1, 1)), ["a:x"], ["a:x"])
    with pytest.raises(fc.QuantityError, match="0 Hz"):
        at0.to("receptance")
    with pytest.raises(TypeError, match="unknown field"):
        Y.replace(speed=3)


def test_second_order_system_frf_matches_closed_form_sdof():
    m, c, k = 2.0, 3.0, 5e4
    sys = fc.SecondOrderSystem([[m]], [[c]], [[k]], ["m:z"])
    f = np.linspace(1, 60, 50)
    w = 2 * np.pi * f
    Y = sys.frf(f, quantity="mobility")
    assert np.allclose(Y.data[:, 0, 0], 1j * w / (k - w**2 * m + 1j * w * c))
    # a named load vector as generalised input
    Yl = sys.frf(f, ["m:z"], [], loads={"patch": np.array([2.0])})
    assert Yl.inputs == ("patch",) and np.allclose(Yl.data, 2 * Y.data)
    with pytest.raises(fc.DataFormatError, match="expected \\(1, 1\\)"):
        fc.SecondOrderSystem(np.eye(2), None, [[k]], ["m:z"])
