"""Mode shapes and operating deflection shapes as data to draw (issue 30).

Truth: the eigenproblem of the tire's matrices (``(lambda^2 M + lambda C + K) x = 0``) and
the modal model's stored poles at an operating point; the ring's closed form for the
direction a wave runs (its ``+`` branch with the spin); the coupled eigenvalues of
:func:`coupled_modes_near` (an independent solve); and the bushing motion of the
assembled system solved by :func:`fbs_core.prediction.direct_bushing_response`.
"""

import functools

import numpy as np
import pytest

from fbs_core import harmonic, reference_tire
from fbs_core.analysis import (
    chassis_geometry,
    coupled_mode_shapes,
    coupled_modes_near,
    operating_shape,
    tire_mode_shape,
)
from fbs_core.errors import DataFormatError, FBSError
from fbs_core.prediction import direct_bushing_response
from fbs_core.tire import TireParameters, build_modal_model, ring_closed_form


def _residual(s, lam, x):
    Z = lam**2 * s.M + lam * s.C + s.K
    return np.linalg.norm(Z @ x) / (np.linalg.norm(s.K) * np.linalg.norm(x))


def test_a_stored_mode_drawn_at_an_operating_point():
    tire = reference_tire()
    v = float(tire.speeds[16])  # 60 km/h
    sh = tire_mode_shape(5, v)
    assert sh.pole == pytest.approx(complex(tire.poles[16, 10]), rel=1e-8)
    assert 15.5 < sh.freq < 17.5  # the hub on the vertical contact springs
    assert sh.hub_share > 0.3
    b = sh.shape
    assert b.belt.shape == (24, 96, 9, 3) and b.rim.shape == (24, 96, 3)
    d = b.belt - b.rest_belt[None]
    # the scale: the largest complex displacement is 0.1 R; the frames sample its phase
    assert 0.08 * tire.params.R < np.abs(d).max() <= 0.1 * tire.params.R * (1 + 1e-12)
    assert b.ring.shape == (24, 96, 3) and b.section(np.pi / 2).shape == (24, 9, 3)
    # the rest belt is the round belt of radius R in the wheel plane
    np.testing.assert_allclose(np.hypot(b.rest_belt[..., 0], b.rest_belt[..., 2]), 0.30)
    with pytest.raises(FBSError, match="stored pair index"):
        tire_mode_shape(200, v)
    with pytest.raises(FBSError, match="n_theta"):
        tire_mode_shape(5, v, n_theta=3)


@functools.cache
def ring_tire():
    """A small physical tire whose belt is the in-plane ring (orders up to 5) on the road."""
    p = TireParameters(
        orders=(5, -1, -1, -1, -1, -1, -1, -1),
        static_deflection=0,
        slip_zones=0,
        camber=0.0,
        toe=0.0,
    )
    return build_modal_model(p, speeds=(20.0, 70.0, 120.0), wavelengths=(0.646,))


def test_a_forward_wave_runs_with_the_spin_and_a_backward_one_against_it():
    tire = ring_tire()
    for i, v, n in ((1, 70.0, 3), (2, 120.0, 4)):  # orders whose waves lie apart from others
        f = tire.poles[i, 0::2].imag / (2 * np.pi)
        fp, fm = ring_closed_form(n, v, tire.params)
        for truth, want, sign in ((fp, "forward", 1.0), (fm, "backward", -1.0)):
            mode = int(np.argmin(np.abs(f - truth)))
            sh = tire_mode_shape(mode, v, tire)
            assert sh.order == n and sh.family == "ip" and sh.direction == want
            # one crest travels 2 pi / n per period, in the spin direction when forward
            adv = sh.shape.crest[-1] - sh.shape.crest[0]
            per = 2 * np.pi / n * (len(sh.shape.crest) - 1) / len(sh.shape.crest)
            assert adv == pytest.approx(sign * per, rel=0.05)  # the road makes it not pure
    # the eigenvector itself: residual of the quadratic eigenproblem
    from fbs_core.analysis.shapes import _modes_near

    s = tire.system(70.0)
    lam, X = _modes_near(s, 2j * np.pi * 150.0, 4)
    assert _residual(s, lam[0], X[:, 0]) < 1e-10


def test_a_model_without_matrices_has_no_shape():
    t = reference_tire()
    from fbs_core.tire import TireModel

    bare = TireModel(t.speeds, t.poles, t.psi, t.chi, t.wavelengths, t.participation)
    with pytest.raises(DataFormatError, match="physical parameters"):
        tire_mode_shape(5, 60.0, bare)


def test_coupled_modes_are_the_coupled_systems_eigenvalues():
    shapes = coupled_mode_shapes(37.0, 60.0, n=3)
    want = coupled_modes_near(37.0, 60.0, n=3)
    np.testing.assert_allclose([s.pole for s in shapes], [m.pole for m in want], rtol=1e-8)
    nodes, xyz, edges = chassis_geometry()
    c = shapes[0].chassis
    assert c.points.shape == (24, len(nodes), 3) and c.edges.shape[1] == 2
    i = nodes.index("spindle")
    # the spindle moves with the tire's hub (joined): rest + scaled hub translation
    hub_move = shapes[0].tire.rim.mean(axis=1) - shapes[0].tire.rim.mean(axis=(0, 1))
    spindle_move = c.points[:, i] - c.rest[i]
    np.testing.assert_allclose(spindle_move, hub_move, atol=1e-12)
    assert all(0 <= s.tire_share <= 1 for s in shapes)
    with pytest.raises(FBSError, match="freq_hz"):
        coupled_mode_shapes(-1.0, 60.0)


def test_operating_shape_moves_the_bushing_as_the_direct_solution():
    h = harmonic(4)
    f = 80.0
    od = operating_shape(4, f, "5dof")
    assert od.kind == "ods" and od.speed_kmh == pytest.approx(h.speed_at(f))
    nodes = od.chassis.nodes
    i = nodes.index("bushing")
    n_k = od.chassis.points.shape[0]
    p0 = od.chassis.points[0, i] - od.chassis.rest[i]  # Re(s d)
    p90 = od.chassis.points[n_k // 4, i] - od.chassis.rest[i]  # Re(j s d) = -Im(s d)
    d = (p0 - 1j * p90) / od.tire.scale
    v = direct_bushing_response(4, freq=[f], coupling="5dof").data[0, :3, 0]
    np.testing.assert_allclose(d, v / (2j * np.pi * f), rtol=1e-6)
