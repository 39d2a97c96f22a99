"""Every coupling method against the direct solution of the assembled structure."""

from __future__ import annotations

import numpy as np
import pytest
from discrete import build, frf_of, label

import fbs_core as fc

FREQ = np.linspace(0.5, 40.0, 120)
TWO = {"A": [0, 1, 2, 3], "B": [3, 4, 5, 6]}
# thesis fig. 2.6: four subsystems A-D on a fifth, E
FIVE = {
    "A": [0, 6, 7],
    "B": [1, 8, 9],
    "C": [3, 10, 11],
    "D": [5, 12, 13],
    "E": [0, 1, 2, 3, 4, 5],
}


def _rel(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


def _subfrfs(subs, freq=FREQ):
    return {name: frf_of(M, C, K, labs, freq) for name, (M, C, K, labs) in subs.items()}


@pytest.fixture(params=[0.0, 40.0], ids=["static", "gyroscopic"])
def two(request):
    subs, glob = build(TWO, gyro=request.param, seed=1)
    return _subfrfs(subs), frf_of(*glob, FREQ)


def test_gyroscopic_structure_is_not_reciprocal():
    subs, glob = build(TWO, gyro=40.0, seed=1)
    Y = frf_of(*glob, FREQ).data
    asym = np.max(np.abs(Y - np.swapaxes(Y, 1, 2))) / np.max(np.abs(Y))
    assert asym > 1e-2


@pytest.mark.parametrize("method", [fc.couple_receptance, fc.couple_impedance])
def test_two_subsystems_equal_direct(two, method):
    Y, Yd = two
    iface = [label(3, "x"), label(3, "y")]
    Ys = method(Y["A"], Y["B"], iface)
    ref = Yd.sel(outputs=Ys.outputs, inputs=Ys.inputs)
    assert _rel(Ys.data, ref.data) < 1e-10
    # outputs ordered a's internal, interface, b's internal
    assert Ys.outputs[:6] == tuple(label(n, d) for n in (0, 1, 2) for d in "xy")
    assert Ys.outputs[6:8] == tuple(iface)


def test_receptance_with_label_pairs_and_partial_columns(two):
    Y, Yd = two
    # rename B's interface node; a receiver FRF with only some outputs
    B = Y["B"]
    ren = {label(3, "x"): "s:x", label(3, "y"): "s:y"}
    B2 = B.replace(
        outputs=[ren.get(o, o) for o in B.outputs], inputs=[ren.get(i, i) for i in B.inputs]
    )
    A_part = Y["A"].sel(
        outputs=[label(0, "x"), label(3, "x"), label(3, "y")],
        inputs=[label(1, "y"), label(3, "x"), label(3, "y")],
    )
    Ys = fc.couple_receptance(A_part, B2, [(label(3, "x"), "s:x"), (label(3, "y"), "s:y")])
    assert Ys.inputs[0] == label(1, "y")
    ref = Yd.sel(outputs=Ys.outputs, inputs=Ys.inputs)
    assert _rel(Ys.data, ref.data) < 1e-10


@pytest.mark.parametrize("method", [fc.couple_lm, fc.couple_generalized])
@pytest.mark.parametrize("gyro", [0.0, 40.0])
def test_five_subsystems_equal_direct(method, gyro):
    subs, glob = build(FIVE, gyro=gyro, seed=3)
    Y = _subfrfs(subs)
    Yd = frf_of(*glob, FREQ)
    conns = []
    for name, node in (("A", 0), ("B", 1), ("C", 3), ("D", 5)):
        for d in "xy":
            conns.append((f"{name}/{label(node, d)}", f"E/{label(node, d)}"))
    Ys = method(Y, conns)
    # every qualified DOF equals the global DOF of its node
    plain = [lab.split("/", 1)[1] for lab in Ys.outputs]
    idx = [Yd.outputs.index(p) for p in plain]
    assert _rel(Ys.data, Yd.data[:, idx][:, :, idx]) < 1e-10


def test_lm_equals_generalized_and_chain_of_two():
    subs, glob = build(FIVE, gyro=25.0, seed=4)
    Y = _subfrfs(subs)
    conns = [
        (f"{n}/{label(k, d)}", f"E/{label(k, d)}")
        for n, k in (("A", 0), ("B", 1), ("C", 3), ("D", 5))
        for d in "xy"
    ]
    lm = fc.couple_lm(Y, conns)
    gr = fc.couple_generalized(Y, conns)
    assert lm.outputs == gr.outputs
    assert _rel(gr.data, lm.data) < 1e-11
    # sequential two-subsystem receptance coupling (thesis sec. 2.2.4) gives the same
    Yseq = Y["E"]
    for name, node in (("A", 0), ("B", 1), ("C", 3), ("D", 5)):
        iface = [label(node, "x"), label(node, "y")]
        Yseq = fc.couple_receptance(Yseq, Y[name], iface)
    ref = lm.sel(
        outputs=[f"E/{o}" if f"E/{o}" in lm.outputs else _owner(lm, o) for o in Yseq.outputs]
    )
    ref = ref.sel(inputs=ref.outputs)
    assert _rel(Yseq.data, ref.data) < 1e-10


def _owner(Y, plain):
    return next(o for o in Y.outputs if o.split("/", 1)[1] == plain)


def test_connection_matrix_signs_do_not_matter():
    subs, _ = build(TWO, gyro=10.0, seed=5)
    Y = _subfrfs(subs)
    c1 = [(f"A/{label(3, d)}", f"B/{label(3, d)}") for d in "xy"]
    c2 = [(f"B/{label(3, d)}", f"A/{label(3, d)}") for d in "xy"]
    assert fc.couple_lm(Y, c1).allclose(fc.couple_lm(Y, c2), rtol=1e-10)
    assert fc.couple_generalized(Y, c2).allclose(fc.couple_lm(Y, c1), rtol=1e-10)


@pytest.mark.parametrize("gyro", [0.0, 40.0])
def test_fast_path_equals_full_coupling(gyro):
    """Eq. 4.1 equals the (e, a) block of eq. 2.44 for a load at a's DOFs."""
    subs, glob = build(TWO, gyro=gyro, seed=6)
    Y = _subfrfs(subs)
    Yd = frf_of(*glob, FREQ)
    j = [label(3, d) for d in "xy"]
    load = np.zeros(len(Y["A"].inputs), complex)
    load[Y["A"].inputs.index(label(1, "x"))] = 1.0
    load[Y["A"].inputs.index(label(2, "y"))] = -0.5j
    vj = fc.FRF(FREQ, Y["A"].sel(outputs=j).data @ load[:, None], j, ["patch"])
    e = [label(5, "x"), label(6, "y"), label(4, "x")]
    ve = fc.couple_response(Y["B"].sel(outputs=e, inputs=j), Y["A"].sel(j, j), Y["B"].sel(j, j), vj)
    assert ve.outputs == tuple(e) and ve.inputs == ("patch",)
    direct = Yd.sel(outputs=e, inputs=[label(1, "x"), label(2, "y")]).data @ np.array(
        [[1.0], [-0.5j]]
    )
    assert _rel(ve.data, direct) < 1e-10


def test_fast_path_release_equals_direct_with_released_dof():
    """Coupling a subset of the interface (x only) equals a structure whose y
    DOFs at the interface node are not joined."""
    subs, _ = build(TWO, gyro=30.0, seed=7)
    Y = _subfrfs(subs)
    MA, CA, KA, la = subs["A"]
    MB, CB, KB, lb = subs["B"]
    # global structure: merge only n3:x
    lb2 = [lab if lab != label(3, "y") else "m3:y" for lab in lb]
    glabels = la + [lab for lab in lb2 if lab not in la]
    n = len(glabels)
    g = {lab: i for i, lab in enumerate(glabels)}
    Mg, Cg, Kg = (np.zeros((n, n)) for _ in range(3))
    for (M, C, K), labs in (((MA, CA, KA), la), ((MB, CB, KB), lb2)):
        ix = [g[lab] for lab in labs]
        Mg[np.ix_(ix, ix)] += M
        Cg[np.ix_(ix, ix)] += C
        Kg[np.ix_(ix, ix)] += K
    Yd = frf_of(Mg, Cg, Kg, glabels, FREQ)
    j = [label(3, "x"), label(3, "y")]
    vj = Y["A"].sel(outputs=j, inputs=[label(1, "y")])
    e = [label(5, "x"), label(6, "y")]
    ve = fc.couple_response(
        Y["B"].sel(outputs=e, inputs=j),
        Y["A"].sel(j, j),
        Y["B"].sel(j, j),
        vj,
        couple=[label(3, "x")],
    )
    ref = Yd.sel(outputs=e, inputs=[label(1, "y")])
    assert _rel(ve.data, ref.data) < 1e-10
    full = fc.couple_response(
        Y["B"].sel(outputs=e, inputs=j), Y["A"].sel(j, j), Y["B"].sel(j, j), vj
    )
    assert _rel(full.data, ref.data) > 1e-3  # releasing a DOF changes the answer


def test_fast_path_batched_over_leading_axes():
    rng = np.random.default_rng(0)
    shape = (3, 50)
    A = rng.normal(size=shape + (6, 6)) + 1j * rng.normal(size=shape + (6, 6))
    E = rng.normal(size=shape + (6, 6)) + 1j * rng.normal(size=shape + (6, 6))
    T = rng.normal(size=shape + (4, 6)) + 1j * rng.normal(size=shape + (4, 6))
    v = rng.normal(size=shape + (6,)) + 1j * rng.normal(size=shape + (6,))
    out = fc.kernels.couple_response_kernel(T, A, E, v)
    g = np.einsum("...jk,...k->...j", np.linalg.inv(A + E), v)
    ref = np.einsum("...ej,...j->...e", T, g)
    assert out.shape == shape + (4,)
    assert np.allclose(out, ref, rtol=1e-10, atol=0)


# --- free-free rods: closed form ---------------------------------------------------
def _rod(L, freq, E=2.1e11 * (1 + 0.01j), rho=7850.0, A=1e-4, names=("p", "q")):
    w = 2 * np.pi * freq
    k = w * np.sqrt(rho / E)
    a11 = -1 / np.tan(k * L) / (E * A * k)
    a12 = -1 / (E * A * k * np.sin(k * L))
    H = np.empty((freq.size, 2, 2), complex)
    H[:, 0, 0] = H[:, 1, 1] = a11
    H[:, 0, 1] = H[:, 1, 0] = a12
    labs = [f"{names[0]}:x", f"{names[1]}:x"]
    return fc.FRF(freq, H, labs, labs, "receptance")


@pytest.mark.parametrize("method", ["receptance", "impedance", "lm", "generalized"])
def test_rods_end_to_end_equal_closed_form(method):
    f = np.linspace(10.0, 8000.0, 400)  # several axial modes of the 1.7 m rod
    L1, L2 = 0.7, 1.0
    r1, r2 = _rod(L1, f, names=("a", "j")), _rod(L2, f, names=("k", "b"))
    ref = _rod(L1 + L2, f, names=("a", "b"))
    if method in ("receptance", "impedance"):
        fn = fc.couple_receptance if method == "receptance" else fc.couple_impedance
        Ys = fn(r1, r2, [("j:x", "k:x")]).sel(outputs=["a:x", "b:x"], inputs=["a:x", "b:x"])
    else:
        fn = fc.couple_lm if method == "lm" else fc.couple_generalized
        Ys = fn({"r1": r1, "r2": r2}, [("r1/j:x", "r2/k:x")]).sel(
            outputs=["r1/a:x", "r2/b:x"], inputs=["r1/a:x", "r2/b:x"]
        )
    err = np.abs(Ys.data - ref.data) / np.abs(ref.data)
    assert err.max() < 1e-8
    assert Ys.quantity == "receptance"


# --- diagnostics and bad input -------------------------------------------------------
def test_condition_number_and_singular_interface():
    subs, _ = build(TWO, gyro=0.0, seed=8)
    Y = _subfrfs(subs)
    j = [label(3, "x"), label(3, "y")]
    c = fc.interface_condition(Y["A"].sel(j, j), Y["B"].sel(j, j))
    ref = np.linalg.cond(Y["A"].sel(j, j).data + Y["B"].sel(j, j).data)
    assert c.shape == FREQ.shape and np.allclose(c, ref)
    # a rank-deficient interface: the same physical DOF offered twice
    labs = j + ["n3dup:x"]

    def dupl(Yf):  # the same physical DOF offered twice: rank-deficient interface
        X = Yf.sel(j, j).data
        d = np.zeros((FREQ.size, 3, 3), complex)
        d[:, :2, :2] = X
        d[:, 2, :2] = X[:, 0]
        d[:, :2, 2] = X[:, :, 0]
        d[:, 2, 2] = X[:, 0, 0]
        return fc.FRF(FREQ, d, labs, labs)

    Ad, Bd = dupl(Y["A"]), dupl(Y["B"])
    with pytest.raises(fc.SingularInterfaceError, match="Hz"):
        fc.couple_receptance(Ad, Bd, labs)
    with pytest.raises(np.linalg.LinAlgError):  # still an ordinary LinAlgError
        fc.couple_response(Bd, Ad, Bd, Ad)
    # truncated SVD regularisation gives the finite minimum-norm answer
    reg = fc.couple_response(Bd, Ad, Bd, Ad.sel(inputs=[labs[0]]), rcond=1e-8)
    assert np.all(np.isfinite(reg.data))
    ok = fc.couple_response(
        Y["B"].sel(j, j), Y["A"].sel(j, j), Y["B"].sel(j, j), Y["A"].sel(j, [j[0]])
    )
    assert _rel(reg.data[:, :2], ok.data) < 1e-6


def test_bad_inputs(two):
    Y, _ = two
    A, B = Y["A"], Y["B"]
    with pytest.raises(fc.DOFError, match="unknown interface output DOF of a 'n9:x'"):
        fc.couple_receptance(A, B, ["n9:x"])
    with pytest.raises(fc.DOFError, match="empty"):
        fc.couple_receptance(A, B, [])
    with pytest.raises(fc.DOFError, match="pairs"):
        fc.couple_receptance(A, B, [("n3:x", "n3:y", "n3:z")])
    with pytest.raises(fc.FrequencyGridError, match="never interpolated"):
        fc.couple_receptance(A, B.isel(freq=slice(0, 10)), ["n3:x"])
    with pytest.raises(fc.QuantityError, match="mix quantities"):
        fc.couple_receptance(A, B.to("receptance"), ["n3:x"])
    with pytest.raises(fc.DOFError, match="occur in both"):
        fc.couple_receptance(A, A, ["n3:x", "n3:y"])
    with pytest.raises(fc.DataFormatError, match="square"):
        fc.couple_impedance(A.sel(outputs=["n3:x"]), B, ["n3:x"])
    with pytest.raises(fc.DataFormatError, match="at least two"):
        fc.couple_lm({"A": A}, [])
    with pytest.raises(fc.DOFError, match="different directions"):
        fc.couple_lm({"A": A, "B": B}, [("A/n3:x", "B/n3:y")])
    with pytest.raises(fc.DOFError, match="unknown connection DOF 'B/n0:x'"):
        fc.couple_lm({"A": A, "B": B}, [("A/n3:x", "B/n0:x")])
    with pytest.raises(fc.DOFError, match="inside subsystem"):
        fc.couple_generalized({"A": A, "B": B}, [("A/n3:x", "A/n2:x")])
    with pytest.raises(fc.DOFError, match="must be non-empty"):
        fc.couple_lm({"A/1": A, "B": B}, [("A/1/n3:x", "B/n3:x")])
    j = ["n3:x", "n3:y"]
    with pytest.raises(fc.DOFError, match="unknown coupled interface DOF 'n3:rz'"):
        fc.couple_response(
            B.sel(inputs=j), A.sel(j, j), B.sel(j, j), A.sel(j, ["n1:x"]), couple=["n3:rz"]
        )
    with pytest.raises(fc.DOFError, match="different directions"):
        fc.couple_response(
            B.sel(inputs=j), A.sel(j, j), B.sel(j[::-1], j[::-1]), A.sel(j, ["n1:x"])
        )
