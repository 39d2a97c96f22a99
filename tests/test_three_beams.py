"""The thesis' three-beam validation case (chapter 3, fig. 3.1-3.2).

Three free-free steel beams, cross-section 10 mm x 40 mm, lengths 2000 / 1000 /
2000 mm, E = 210 GPa, nu = 0.3, rho = 8000 kg/m^3, 10 mm Euler-Bernoulli
elements, joined at shared nodes (all 6 DOFs). Layout: a planar Z-frame in the
x-y plane, the 40 mm height vertical (global z), so that both bending planes,
axial and torsional motion take part::

        j2 (2,1,0) ----------- c0 (4,1,0)     beam c, 2000 mm
         |
         |  beam b, 1000 mm
         |
    a0 (0,0,0) ----------- j1 (2,0,0)         beam a, 2000 mm

Thesis node numbers: a0 = node 5 (excitation), j1 = node 205, j2 = node 307,
c0 = node 490. Structural damping through a complex modulus ``E (1 + 0.01 j)``
keeps the peaks finite. The FRFs of the three separate beams between their end
nodes (direct solutions of each beam) are coupled two at a time, by receptance
coupling (eq. 2.44) and by impedance coupling (eq. 2.19), and compared with the
direct solution of the frame meshed as one FE model (the truth).

All FRFs are solved with iterative refinement: a double-precision sparse LU
solve followed by two correction steps with the residual computed in extended
precision (Wilkinson 1963; Moler, J. ACM 14(2), 1967). With 10 mm elements the
dynamic stiffness has condition numbers of order (omega_max / omega)^2 ~ 1e10 at
low frequencies, so a plain double solve is only good to ~1e-7 there, which is
too coarse a truth for a 1e-8 check.
"""

import functools

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from fbs_core import FRF, couple_impedance, couple_receptance, node_labels
from fbs_core.dofs import index_of
from fbs_core.fe import FEModel, Material, Section

STEEL = Material(E=210e9, nu=0.3, rho=8000.0, eta=0.01)
SECTION = Section.rectangle(0.010, 0.040)  # width along local y, height along local z = global z
ELEMENT = 0.010
POINTS = {"a0": (0, 0, 0), "j1": (2, 0, 0), "j2": (2, 1, 0), "c0": (4, 1, 0)}
BEAMS = {"a": ("a0", "j1"), "b": ("j1", "j2"), "c": ("j2", "c0")}
FREQ = np.linspace(5.0, 200.0, 40)


def _model(beams):
    m = FEModel()
    for name in beams:
        for node in BEAMS[name]:
            if node not in m.nodes:
                m.add_node(node, POINTS[node])
    for name in beams:
        p, q = BEAMS[name]
        n = round(np.linalg.norm(np.subtract(POINTS[q], POINTS[p])) / ELEMENT)
        m.add_beam(p, q, SECTION, STEEL, n, up=(0, 0, 1), prefix=f"{name}")
    return m.system()


def _refined_frf(system, dofs, iters=2):
    """Receptance between ``dofs`` by sparse LU plus extended-precision refinement."""
    K, M = sp.csr_matrix(system.K), sp.csr_matrix(system.M)
    idx = index_of(system.dofs, dofs)
    B = np.zeros((system.n, len(idx)), complex)
    B[idx, np.arange(len(idx))] = 1.0
    out = np.empty((FREQ.size, len(idx), len(idx)), complex)
    for k, f in enumerate(FREQ):
        Z = (K - (2 * np.pi * f) ** 2 * M).tocsr()
        lu = spla.splu(Z.tocsc())
        x = lu.solve(B).astype(np.clongdouble)
        z = Z.data.astype(np.clongdouble)
        for _ in range(iters):  # residual B - Z x in extended precision, row by row
            r = B - np.add.reduceat(z[:, None] * x[Z.indices], Z.indptr[:-1], axis=0)
            x = x + lu.solve(r.astype(complex))
        out[k] = x[idx].astype(complex)
    return FRF(FREQ, out, dofs, dofs, "receptance")


def _labels(*nodes):
    return [lab for n in nodes for lab in node_labels(n)]


@functools.cache
def _separate():
    out = {}
    for name, (p, q) in BEAMS.items():
        dofs = _labels(p, q)
        out[name] = _refined_frf(_model([name]), dofs)
    return out


@functools.cache
def _direct():
    dofs = _labels("a0", "j1", "j2", "c0")
    return _refined_frf(_model(list(BEAMS)), dofs)


def _rel_error(Y, truth):
    """Largest relative error over lines and entries, each entry scaled by the
    geometric mean of its two driving-point magnitudes (unit-consistent)."""
    Yt = truth.sel(outputs=Y.outputs, inputs=Y.inputs).data
    d = np.abs(np.einsum("fii->fi", Yt))
    scale = np.sqrt(d[:, :, None] * d[:, None, :])
    return float(np.max(np.abs(Y.data - Yt) / scale))


def test_frame_has_several_modes_well_inside_the_range():
    s = _model(list(BEAMS))
    w2 = spla.eigsh(s.K.real, k=30, M=s.M, sigma=-1.0, return_eigenvectors=False)
    f = np.sort(np.sqrt(np.abs(w2)) / (2 * np.pi))
    elastic = f[f > 1.0]
    inside = elastic[(elastic > FREQ[0] + 5) & (elastic < FREQ[-1] - 5)]
    assert np.sum(f < 1.0) == 6  # free-free: six rigid-body modes
    assert inside.size >= 8


@pytest.mark.parametrize("method", [couple_receptance, couple_impedance])
def test_three_beams_coupled_equal_direct_solution(method):
    Y = _separate()
    ab = method(Y["a"], Y["b"], node_labels("j1"))
    abc = method(ab, Y["c"], node_labels("j2"))
    assert set(abc.outputs) == set(_labels("a0", "j1", "j2", "c0"))
    err = _rel_error(abc, _direct())
    assert err < 1e-8, err


def test_fig_3_2_transfer_node_5_to_307():
    """Fig. 3.2: transfer from node 5 (a0) to node 307 (j2), both methods and direct."""
    Y = _separate()
    rc = couple_receptance(
        couple_receptance(Y["a"], Y["b"], node_labels("j1")), Y["c"], node_labels("j2")
    ).sel(outputs="j2:z", inputs="a0:z")
    ic = couple_impedance(
        couple_impedance(Y["a"], Y["b"], node_labels("j1")), Y["c"], node_labels("j2")
    ).sel(outputs="j2:z", inputs="a0:z")
    d = _direct().sel(outputs="j2:z", inputs="a0:z")
    scale = np.abs(d.data)
    assert np.max(np.abs(rc.data - d.data) / scale) < 1e-8
    assert np.max(np.abs(ic.data - d.data) / scale) < 1e-8
    # the coupling changes the response: the frame is not the first beam alone
    alone = Y["a"].sel(outputs="j1:z", inputs="a0:z").data
    assert np.max(np.abs(alone - d.data)) > 0.1 * np.max(np.abs(d.data))


def test_refined_truth_agrees_with_plain_direct_solve():
    """The refined solve is the project's direct solve, only more accurate."""
    dofs = _labels("a0", "c0")
    plain = _model(list(BEAMS)).frf(FREQ[::8], dofs, dofs, quantity="receptance")
    ref = _direct().sel(outputs=dofs, inputs=dofs).isel(freq=slice(None, None, 8))
    err = np.abs(plain.data - ref.data) / np.abs(ref.data).max(axis=(1, 2), keepdims=True)
    assert err.max() < 1e-5
