"""The tire on the right wheels: the mirror image of the left one, an exact change of coordinates.

Truth: the tire's own matrices (``fbs_core.tire.ring``) built with the signs of its
lateral asymmetry flipped (camber and toe "towards the car" on the other side, the
conicity force ``mu_y0`` the other way): their hub mobility and free hub velocity must
be ``T Y T`` and ``T v`` of the left tire's, ``T = diag(1, -1, 1, -1, 1, -1)``
(translations y, rotations rx, rz change sign; the spin ry does not: both wheels roll
forward). And the tire at one speed with a wavelength per line, against the direct
solution of its matrices.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.errors import DataFormatError, FBSError
from fbs_core.tire import DEFAULT_PARAMETERS, HUB_DOFS, build_tire_system, patch_load
from fbs_core.vehicle import MIRROR, mirror_arrays, mirror_tire
from fbs_core.vehicle.tires import tire_at_speed

T = np.asarray(MIRROR)


def test_mirrored_physical_tire_is_the_change_of_coordinates():
    left = dataclasses.replace(DEFAULT_PARAMETERS, mu_y0=0.02)  # conicity too
    right = dataclasses.replace(left, camber=-left.camber, toe=-left.toe, mu_y0=-left.mu_y0)
    f = np.array([8.0, 37.0, 95.0, 260.0])
    out = {}
    for name, p in (("left", left), ("right", right)):
        s = build_tire_system(80.0, p)
        out[name] = s.frf(f, HUB_DOFS, HUB_DOFS, loads={"road": patch_load(0.166, p)}).data
    Yl, vl = out["left"][:, :, :6], out["left"][:, :, 6]
    Yr, vr = out["right"][:, :, :6], out["right"][:, :, 6]
    Ym, vm = mirror_arrays(Yl, vl)
    assert np.abs(Yr - Ym).max() < 1e-11 * np.abs(Yl).max()
    assert np.abs(vr - vm).max() < 1e-11 * np.abs(vl).max()
    # and it is a change: the asymmetric tire's lateral response flips sign
    assert np.abs(Yr - Yl).max() > 1e-2 * np.abs(Yl).max()
    y = HUB_DOFS.index("hub:y")
    assert np.abs(vl[:, y]).max() > 1e-2 * np.abs(vl).max()  # a lateral response to flip


def test_mirrored_modal_model():
    tire = fc.reference_tire()
    m = mirror_tire(tire)
    assert m.meta["mirrored"] is True and mirror_tire(m).meta["mirrored"] is False
    assert m.params.camber == -tire.params.camber and m.params.toe == -tire.params.toe
    f = fc.harmonic(2).frequencies(df=4.0)
    Yl, vl = tire.truncations(f, 2, [60, 400])
    Yr, vr = m.truncations(f, 2, [60, 400])
    Ym, vm = mirror_arrays(Yl, vl)
    np.testing.assert_array_equal(Yr, Ym)  # sign flips only: exact
    np.testing.assert_array_equal(vr, vm)
    # a supplier's truncated delivery keeps its residual consistent under the mirror
    t60 = tire.subset(range(30))
    a = mirror_tire(t60).truncations(f, 2, [60], residual=True)
    b = mirror_arrays(*t60.truncations(f, 2, [60], residual=True))
    np.testing.assert_allclose(a[0], b[0], rtol=1e-12, atol=0)
    np.testing.assert_allclose(a[1], b[1], rtol=1e-12, atol=0)
    with pytest.raises(FBSError, match="needs a TireModel"):
        mirror_tire(object())


def test_tire_at_one_speed_with_a_wavelength_per_line():
    tire = fc.reference_tire()
    f = np.array([0.8, 6.0, 45.0])
    Y, v = tire_at_speed(tire, f, 72.0)
    s = tire.system(72.0)
    for i, fi in enumerate(f):
        w = 2 * np.pi * fi
        Z = s.K - w**2 * s.M + 1j * w * s.C
        rhs = np.zeros((s.n, 7), complex)
        rhs[:6, :6] = np.eye(6)
        rhs[:, 6] = tire.patch_load(72.0, 20.0 / fi)  # 72 km/h = 20 m/s: lambda = v / f
        X = 1j * w * np.linalg.solve(Z, rhs)
        assert np.abs(Y[i] - X[:6, :6]).max() < 1e-9 * np.abs(X[:6, :6]).max()
        assert np.abs(v[i] - X[:6, 6]).max() < 1e-9 * np.abs(X[:6, 6]).max()
    with pytest.raises(DataFormatError, match="positive speed"):
        tire_at_speed(tire, f, 0.0)
    with pytest.raises(DataFormatError, match="physical parameters"):
        tire_at_speed(dataclasses.replace(tire, params=None), f, 72.0)
