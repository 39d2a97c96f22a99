"""Contributions of the interface forces to the coupled response (terms of eq. 4.1).

Truths: the force in a connecting spring (closed form of a 3-mass chain); the
direct solution of a randomly split gyroscopic structure, where the interface
force is the receiver's dynamic stiffness times its displacements; and the
directly assembled tire + chassis at an operating point.
"""

import functools

import numpy as np
import pytest
from discrete import build, frf_of, label

from fbs_core import FRF, assemble, bushing_response, harmonic, reference_chassis, reference_tire
from fbs_core.analysis import bushing_contributions, interface_contributions
from fbs_core.chassis import BUSHING, SPINDLE
from fbs_core.errors import DOFError, FrequencyGridError
from fbs_core.prediction import coupled_dofs


def test_chain_interface_force_is_the_spring_force():
    """A: mass m_a --k1-- massless node j; E: node j (m_j) --k2-- mass m_e --k3-- ground.
    The force A exerts on E is the spring force k1 (x_a - x_j)."""
    ma, k1, mj, k2, me, k3 = 2.0, 4e4, 0.5, 1e5, 3.0, 2e4
    f = np.linspace(1.0, 100.0, 60)
    w = 2 * np.pi * f
    ZA = np.zeros((f.size, 2, 2), complex)
    k1c = k1 * (1 + 1e-3j)  # hysteretic spring
    ZA[:, 0, 0] = k1c - w**2 * ma
    ZA[:, 0, 1] = ZA[:, 1, 0] = -k1c
    ZA[:, 1, 1] = k1c
    YA = FRF(f, np.linalg.inv(ZA) * (1j * w)[:, None, None], ["a:x", "j:x"], ["a:x", "j:x"])
    ZE = np.zeros((f.size, 2, 2), complex)
    ZE[:, 0, 0] = k2 - w**2 * mj
    ZE[:, 0, 1] = ZE[:, 1, 0] = -k2
    ZE[:, 1, 1] = k2 + k3 - w**2 * me
    YE = FRF(f, np.linalg.inv(ZE) * (1j * w)[:, None, None], ["j:x", "e:x"], ["j:x", "e:x"])
    c = interface_contributions(
        YE.sel(outputs="e:x", inputs="j:x"),
        YA.sel(outputs="j:x", inputs="j:x"),
        YE.sel(outputs="j:x", inputs="j:x"),
        YA.sel(outputs="j:x", inputs="a:x"),
    )
    # assembled 3-DOF chain [a, j, e], unit force at a, solved directly
    Z = np.zeros((f.size, 3, 3), complex)
    Z[:, :2, :2] += ZA
    Z[:, 1:, 1:] += ZE
    x = np.linalg.solve(Z, np.broadcast_to([1.0, 0, 0], (f.size, 3))[..., None])[..., 0]
    spring = k1c * (x[:, 0] - x[:, 1])
    np.testing.assert_allclose(c.forces[:, 0], spring, rtol=1e-9)
    np.testing.assert_allclose(c.total.data[:, 0, 0], 1j * w * x[:, 2], rtol=1e-9)
    assert c.interface == ("j:x",) and c.load == "a:x"


@pytest.mark.parametrize("gyro", [0.0, 40.0])
def test_split_structure_terms_add_up_and_forces_match_direct(gyro):
    """Interface of two nodes (4 DOFs): the terms add up to the coupled response, which
    equals the direct solution; the forces equal Z_E x_E at the interface."""
    subs, (M, C, K, glab) = build({"A": [0, 1, 2, 3], "E": [3, 4, 2, 5]}, gyro, seed=3)
    f = np.linspace(2.0, 40.0, 50)
    MA, CA, KA, la = subs["A"]
    ME, CE, KE, le = subs["E"]
    YA, YE = frf_of(MA, CA, KA, la, f), frf_of(ME, CE, KE, le, f)
    jn = [label(n, d) for n in (3, 2) for d in "xy"]
    en = [label(n, d) for n in (4, 5) for d in "xy"]
    load = label(0, "x")
    c = interface_contributions(
        YE.sel(outputs=en, inputs=jn),
        YA.sel(outputs=jn, inputs=jn),
        YE.sel(outputs=jn, inputs=jn),
        YA.sel(outputs=jn, inputs=load),
    )
    w = 2 * np.pi * f
    Z = K[None] - w[:, None, None] ** 2 * M[None] + 1j * w[:, None, None] * C[None]
    F = np.zeros(len(glab))
    F[glab.index(load)] = 1.0
    x = np.linalg.solve(Z, np.broadcast_to(F, (f.size, F.size))[..., None])[..., 0]
    v_e = 1j * w[:, None] * x[:, [glab.index(e) for e in en]]
    total = c.terms.sum(-1)
    assert np.max(np.abs(total - c.total.data[:, :, 0])) == 0.0
    np.testing.assert_allclose(total, v_e, rtol=1e-8, atol=1e-12 * np.abs(v_e).max())
    ZE = KE[None] - w[:, None, None] ** 2 * ME[None] + 1j * w[:, None, None] * CE[None]
    gE = np.einsum("fij,fj->fi", ZE, x[:, [glab.index(d) for d in le]])
    np.testing.assert_allclose(
        c.forces, gE[:, [le.index(j) for j in jn]], rtol=1e-8, atol=1e-10 * np.abs(gE).max()
    )
    # E's internal DOFs carry no external force (a check of the truth itself)
    assert np.abs(gE[:, [le.index(e) for e in en]]).max() < 1e-8 * np.abs(gE).max()
    # the shares of one response add up to 1
    np.testing.assert_allclose(c.shares(en[0]).sum(-1), 1.0, atol=1e-12)


SPEED = 60.0


@functools.cache
def _assembled(k: int, coupling: str, freq_key: tuple):
    tire, ch = reference_tire(), reference_chassis()
    ts, cs = tire.system(SPEED), ch.system()
    joined = [(f"tire/{d}", f"chassis/spindle:{d.split(':')[1]}") for d in coupled_dofs(coupling)]
    S = assemble({"tire": ts, "chassis": cs}, joined)
    pos = {d: i for i, d in enumerate(S.dofs)}
    load = np.zeros(S.n, complex)
    load[[pos[f"tire/{d}"] for d in ts.dofs]] = tire.patch_load(SPEED, harmonic(k).wavelength)
    X = S.frf(np.array(freq_key), S.dofs, [], "receptance", loads={"patch": load})
    # the chassis' displacements, its spindle DOFs merged into the hub where coupled
    cpos = []
    for d in cs.dofs:
        merged = d.startswith("spindle:") and f"hub:{d.split(':')[1]}" in coupled_dofs(coupling)
        cpos.append(pos[f"tire/hub:{d.split(':')[1]}"] if merged else pos[f"chassis/{d}"])
    xE = X.data[:, cpos, 0]
    g = np.stack(
        [cs.dynamic_stiffness(w) @ xe for w, xe in zip(2 * np.pi * X.freq, xE, strict=True)]
    )
    w = 2 * np.pi * X.freq
    vb = 1j * w[:, None] * xE[:, [cs.dofs.index(b) for b in BUSHING]]
    return vb, g[:, [cs.dofs.index(s) for s in SPINDLE]]


@pytest.mark.parametrize("coupling", ["6dof", "5dof"])
def test_tire_chassis_contributions_match_assembled_system(coupling):
    f = np.linspace(8.0, 300.0, 12)
    c = bushing_contributions(2, None, f, coupling, speed_kmh=SPEED)
    assert c.outputs == BUSHING and c.interface == coupled_dofs(coupling)
    vb, g = _assembled(2, coupling, tuple(f))
    scale = np.linalg.norm(vb, axis=1)[:, None]
    assert np.max(np.abs(c.terms.sum(-1) - vb) / scale) < 1e-6
    ref = bushing_response(2, None, f, coupling, speed_kmh=SPEED).data[:, :, 0]
    assert np.max(np.abs(c.total.data[:, :, 0] - ref) / scale) < 1e-12
    gc = g[:, [SPINDLE.index("spindle:" + d.split(":")[1]) for d in c.interface]]
    gs = np.linalg.norm(g, axis=1)[:, None]
    assert np.max(np.abs(c.forces - gc) / gs) < 1e-6
    if coupling == "5dof":  # the released spin passes no moment
        assert np.max(np.abs(g[:, SPINDLE.index("spindle:ry")]) / gs[:, 0]) < 1e-6


def test_along_the_harmonic_line_and_accessors():
    c = bushing_contributions(1, n_modes=40)
    ref = bushing_response(1, n_modes=40)
    np.testing.assert_allclose(c.total.data, ref.data, rtol=1e-12, atol=0)
    z = c.at("bushing:z")
    assert z.inputs == c.interface and z.outputs == ("bushing:z",)
    np.testing.assert_allclose(z.data.sum(-1)[:, 0], ref.sel(outputs="bushing:z").data[:, 0, 0])
    t = c.term("hub:z")
    assert t.outputs == BUSHING and t.inputs == ("patch",)
    lv = c.levels_db("bushing:z")
    np.testing.assert_allclose(lv[:, 2], 20 * np.log10(np.abs(t.data[:, 2, 0])))
    dom = c.dominant("bushing:z")
    k = np.argmax(np.abs(z.data[:, 0, :]), axis=1)
    assert dom == tuple(c.interface[i] for i in k)
    with pytest.raises(DOFError, match="available"):
        c.term("hub:q")
    with pytest.raises(DOFError):
        c.at("spindle:z")
    with pytest.raises(DOFError):
        bushing_contributions(1, 40, coupling="5dof").term("hub:ry")


def test_bad_input():
    f = np.linspace(1.0, 10.0, 5)
    Y = FRF(f, np.ones((5, 1, 1)), ["j:x"], ["j:x"])
    two = FRF(f, np.ones((5, 1, 2)), ["j:x"], ["a:x", "a:y"])
    with pytest.raises(DOFError, match="one input"):
        interface_contributions(Y, Y, Y, two)
    other = FRF(f + 0.5, np.ones((5, 1, 1)), ["j:x"], ["a:x"])
    with pytest.raises(FrequencyGridError):
        interface_contributions(Y, Y, Y, other)
    with pytest.raises(DOFError, match="selects no"):
        interface_contributions(Y, Y, Y, Y, couple=[])


@pytest.mark.parametrize("coupling", ["6dof", "5dof"])
def test_contributions_read_from_the_truncation_map_are_the_direct_ones(coupling):
    """The map keeps the interface forces of its solve: its contributions for a count it
    holds (and for all modes) are those of a separate tire synthesis and coupling."""
    from fbs_core.analysis import map_contributions
    from fbs_core.studies import truncation_map

    m = truncation_map(2, n_modes=[20, 40, 60], coupling=coupling)
    for n in (40, None):
        c = map_contributions(m, n)
        d = bushing_contributions(2, n_modes=n, coupling=coupling)
        assert c.interface == d.interface and c.outputs == d.outputs
        scale = np.abs(d.terms).max()
        np.testing.assert_allclose(c.terms, d.terms, rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(
            c.forces, d.forces, rtol=1e-9, atol=1e-9 * np.abs(d.forces).max()
        )
        # and their sum is the map's own response for that count
        np.testing.assert_allclose(
            c.total.data[:, :, 0], m.response_for(n), rtol=0, atol=1e-12 * scale
        )


def test_map_contributions_refuse_a_count_the_map_does_not_hold():
    from fbs_core.analysis import map_contributions
    from fbs_core.errors import FBSError
    from fbs_core.studies import truncation_map

    m = truncation_map(1, n_modes=[20, 40])
    with pytest.raises(FBSError, match=r"no interface forces for N = 30 \(counts 20, 40"):
        map_contributions(m, 30)
