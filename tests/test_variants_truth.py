"""Corridor and Sobol' indices against truths by hand (issue 32).

A 2-DOF chain, ground -(k1 (1 + j eta))- m1 -(k2)- m2, force on m2, response at m1,
split for FBS into the "tire" (spring k2 and mass m2, free at the interface node) and the
"chassis" (m1 on k1):

- the coupled response of eq. 4.1 (``fbs_core.couple_response``) equals the closed form
  ``x1 = k2 F / ((k1' + k2 - w^2 m1)(k2 - w^2 m2) - k2^2)`` (the assembled system);
- well below its resonances ``x1 = F / k1'``: the percentiles of the corridor are those of
  ``1 / k1`` with ``k1`` uniform, in closed form;
- well above them ``x1 = k2 F / (w^4 m1 m2)``: the band level in dB is linear in ``ln k2,
  ln m1, ln m2``, so its Sobol' indices follow from the variance of the log of a uniform
  variable; in between, tensor Gauss-Legendre quadrature of the closed form gives them.

And the Ishigami function, whose indices are known analytically (Ishigami & Homma 1990;
Saltelli et al. 2010).
"""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core
import fbs_core.variants as fv

ETA = 0.05
RANGES = {"k1": (0.8e5, 1.2e5), "k2": (1.5e5, 2.5e5), "m1": (8.0, 12.0), "m2": (4.0, 6.0)}
SPACE = fv.ParameterSpace(
    tuple(
        fv.Parameter(n, "custom", "SI", lo, hi, (0.0, np.inf), "2-DOF chain", "test")
        for n, (lo, hi) in RANGES.items()
    )
)


def x1_closed(f, k1, k2, m1, m2):
    """Receptance of the assembled chain at m1 for a unit force on m2 (by hand)."""
    w2 = (2 * np.pi * np.asarray(f)) ** 2
    k1c = k1 * (1 + 1j * ETA)
    return k2 / ((k1c + k2 - w2 * m1) * (k2 - w2 * m2) - k2**2)


def test_chain_by_fbs_equals_the_closed_form():
    f = np.linspace(1.0, 200.0, 60)
    k1, k2, m1, m2 = 1.0e5, 2.0e5, 10.0, 5.0
    w2 = (2 * np.pi * f) ** 2
    YA = (1 / k2 - 1 / (w2 * m2)).reshape(-1, 1, 1)  # tire: spring + free mass, from node j
    vA = (-1 / (w2 * m2)).reshape(-1, 1, 1)  # its free interface displacement
    YE = (1 / (k1 * (1 + 1j * ETA) - w2 * m1)).reshape(-1, 1, 1)
    frf = lambda d, o, i: fbs_core.FRF(f, d, o, i, "receptance")  # noqa: E731
    x = fbs_core.couple_response(
        frf(YE, ["e:z"], ["s:z"]),
        frf(YA, ["j:z"], ["j:z"]),
        frf(YE, ["s:z"], ["s:z"]),
        frf(vA, ["j:z"], ["patch"]),
        interface=[("j:z", "s:z")],
    )
    np.testing.assert_allclose(x.data[:, 0, 0], x1_closed(f, k1, k2, m1, m2), rtol=1e-10)


def _responses(design, f):
    v = design.values  # (n, 4): k1, k2, m1, m2
    return x1_closed(f[None, :], *(v[:, i, None] for i in range(4)))[:, :, None]


def test_corridor_percentiles_and_edges_by_hand():
    """At 0.2 Hz (w^2 m / k ~ 1e-4) the response is F / k1': its percentiles over the
    design are those of 1 / k1, k1 uniform: q-quantile 1 / (a + (1 - q) (b - a))."""
    f = np.array([0.2, 0.3])
    d = fv.sample_design(SPACE, 1024, "sobol", seed=7)
    c = fv.corridor(
        f, _responses(d, f), x1_closed(f, 1e5, 2e5, 10, 5)[:, None], percentiles=[5, 50, 95]
    )
    a, b = RANGES["k1"]
    k = abs(1 + 1j * ETA)
    for qi, q in enumerate((0.05, 0.5, 0.95)):
        assert c.percentiles[qi, 0, 0] == pytest.approx(1 / (a + (1 - q) * (b - a)) / k, rel=2e-3)
    # the edges: monotone in k1 -> at the range's ends, approached from inside
    assert 1 / (b * k) * (1 - 1e-3) <= c.minimum[0, 0] <= 1 / (b * k) * 1.01
    assert 1 / (a * k) * 0.99 <= c.maximum[0, 0] <= 1 / (a * k) * (1 + 1e-3)
    row = d.values[c.argmax_variant[0, 0]]
    assert row[0] == d.values[:, 0].min()  # the stiffest ... softest k1 gives the maximum
    assert c.width_db[0, 0] == pytest.approx(20 * np.log10(b / a), abs=0.1)


def _log_uniform_var(a, b):
    """Variance of ln X, X uniform on [a, b] (by hand: the moments of ln)."""
    m1 = (b * np.log(b) - b - a * np.log(a) + a) / (b - a)
    F = lambda x: x * (np.log(x) ** 2 - 2 * np.log(x) + 2)  # noqa: E731
    m2 = (F(b) - F(a)) / (b - a)
    return m2 - m1**2


def _quadrature_indices(f, band, n=8):
    """First-order and total indices of the band level by tensor Gauss-Legendre quadrature."""
    x, w = np.polynomial.legendre.leggauss(n)
    nodes = [lo + (x + 1) / 2 * (hi - lo) for lo, hi in RANGES.values()]
    w = w / 2
    K1, K2, M1, M2 = np.meshgrid(*nodes, indexing="ij")
    lines = f[(f >= band[0]) & (f < band[1])]  # band_levels' lines of an inner band
    p = np.abs(x1_closed(lines, K1[..., None], K2[..., None], M1[..., None], M2[..., None])) ** 2
    Y = 10 * np.log10(p.mean(axis=-1))  # (n, n, n, n)
    W = np.einsum("i,j,k,l->ijkl", w, w, w, w)
    mean = (W * Y).sum()
    V = (W * (Y - mean) ** 2).sum()
    S1, ST = [], []
    for i in range(4):
        others = tuple(j for j in range(4) if j != i)
        wi = W.sum(axis=others)  # weights of X_i alone
        cond = (W * Y).sum(axis=others) / wi  # E[Y | X_i]
        S1.append((wi * (cond - mean) ** 2).sum() / V)
        ci = (W * Y).sum(axis=i, keepdims=True) / W.sum(axis=i, keepdims=True)  # E[Y | X_~i]
        ST.append((W * (Y - ci) ** 2).sum() / V)
    return np.array(S1), np.array(ST)


def test_sobol_indices_of_the_chain_by_hand_and_by_quadrature():
    f = np.concatenate(
        [np.linspace(0.2, 0.4, 9), np.linspace(10, 40, 61), np.linspace(3e3, 4e3, 9)]
    )
    bands = np.array([[0.2, 0.4], [20.0, 30.0], [3e3, 4e3]])
    d = fv.sample_design(SPACE, 2048, "saltelli", seed=11)
    s = fv.sensitivity(d, f, _responses(d, f), bands=bands, dofs=["m1:z"], n_bootstrap=50)
    # low band: only k1 matters
    np.testing.assert_allclose(s.first[:, 0, 0], [1, 0, 0, 0], atol=0.01)
    np.testing.assert_allclose(s.total[:, 0, 0], [1, 0, 0, 0], atol=0.01)
    # high band: L = 20 log10(k2) - 20 log10(m1) - 20 log10(m2) + C, additive
    v = np.array([0.0] + [_log_uniform_var(*RANGES[n]) for n in ("k2", "m1", "m2")])
    np.testing.assert_allclose(s.first[:, 2, 0], v / v.sum(), atol=0.02)
    np.testing.assert_allclose(s.total[:, 2, 0], v / v.sum(), atol=0.02)
    # around the resonances: quadrature of the closed form
    S1, ST = _quadrature_indices(f, bands[1])
    np.testing.assert_allclose(s.first[:, 1, 0], S1, atol=0.01)
    np.testing.assert_allclose(s.total[:, 1, 0], ST, atol=0.01)
    # the bootstrap intervals hold the estimates, the checkpoints converge to them
    assert np.all(s.total_ci[0] <= s.total + 1e-12) and np.all(s.total <= s.total_ci[1] + 1e-12)
    assert list(s.steps) == [256, 512, 1024, 2048] and s.total_change[-1] == 0.0
    assert s.total_change[0] < 0.1
    # a meeting's table: the band's leader is the parameter of largest total index
    lead = s.leaders("m1:z")
    assert lead[0]["parameter"] == "k1" and lead[2]["parameter"] == SPACE.names[np.argmax(v)]
    rows = s.table()
    assert len(rows) == 3 * 4 and {r["rank"] for r in rows} == {1, 2, 3, 4}


def test_ishigami_indices():
    a, b = 7.0, 0.1
    space = fv.ParameterSpace(
        tuple(
            fv.Parameter(f"x{i}", "custom", "1", -np.pi, np.pi, (-np.inf, np.inf), "", "")
            for i in (1, 2, 3)
        )
    )
    d = fv.sample_design(space, 2**13, "saltelli", seed=3)
    x = d.values
    y = np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])
    V = a**2 / 8 + b * np.pi**4 / 5 + b**2 * np.pi**8 / 18 + 0.5
    V1 = 0.5 * (1 + b * np.pi**4 / 5) ** 2
    V2 = a**2 / 8
    V13 = 8 * b**2 * np.pi**8 / 225
    S1, ST = fv.sobol_indices(d, y)
    np.testing.assert_allclose(S1, [V1 / V, V2 / V, 0.0], atol=0.02)
    np.testing.assert_allclose(ST, [(V1 + V13) / V, V2 / V, V13 / V], atol=0.02)
    with pytest.raises(fbs_core.DataFormatError, match="one per variant"):
        fv.sobol_indices(d, y[:-1])


def test_third_octave_bands_and_band_levels():
    e = fv.third_octave_bands(34.8, 139.0)
    # 40 ... 125 Hz (nominal); the 31.5 Hz band's sliver above 34.8 Hz joins the 40 Hz band
    assert e.shape == (6, 2) and e[0, 0] == 34.8 and e[-1, 1] == 139.0
    c = 1000 * 2 ** (np.arange(-13, -9) / 3)  # 50, 63, 80, 100 Hz: exact base-2 centres
    np.testing.assert_allclose(np.sqrt(e[1:-1, 0] * e[1:-1, 1]), c, rtol=1e-12)
    np.testing.assert_allclose(e[1:, 0], e[:-1, 1], rtol=1e-12)  # contiguous
    f = np.array([1.0, 2.0, 3.0, 4.0])
    v = np.ones((1, 4, 1)) * np.array([1, 1, 2, 2])[None, :, None]
    L = fv.band_levels(f, v, [[1.0, 2.5], [2.5, 4.0]])
    np.testing.assert_allclose(L[0, :, 0], [0.0, 20 * np.log10(2)], atol=1e-12)
    with pytest.raises(fbs_core.FBSError, match="holds no line"):
        fv.band_levels(f, v, [[5.0, 6.0]])


def test_corridor_beside_a_noise_band_by_hand():
    from types import SimpleNamespace

    f = np.array([10.0, 20.0, 30.0, 40.0])
    # variants spread by factors 0.5 .. 2 (12.04 dB wide) at every line, nominal 1
    v = np.array([0.5, 1.0, 2.0])[:, None, None] * np.ones((3, 4, 1))
    c = fv.corridor(f, v, np.ones((4, 1)), dofs=["bushing:z"])
    band = SimpleNamespace(
        freq=f,
        dofs=("bushing:z",),
        minimum=np.array([[0.4], [0.6], [0.9], [0.5]]),
        maximum=np.array([[2.5], [1.5], [1.1], [2.0]]),
    )
    (row,) = c.beside(band)
    w = 20 * np.log10(np.array([2.5 / 0.4, 1.5 / 0.6, 1.1 / 0.9, 2.0 / 0.5]))
    assert row["corridor_median_db"] == pytest.approx(20 * np.log10(4))
    assert row["band_median_db"] == pytest.approx(np.median(w))
    assert row["share_wider"] == 0.5  # lines 2 and 3 (line 4 equal width: not wider)
    assert row["share_outside"] == 0.5  # lines 2 and 3 leave the band
    np.testing.assert_allclose(c.above_db, 20 * np.log10(2))
    band.freq = f + 1
    with pytest.raises(fbs_core.FBSError, match="not the corridor's"):
        c.beside(band)


def test_additive_function_indices_by_hand():
    """``y = 1.5 x1 + 4 x2^2 + sin(x3) - 100`` with a fourth, inert parameter: additive, so
    ``S_i = S_Ti = V_i / sum V`` with ``V_1 = 1.5^2 2^2 / 12`` (x1 ~ U(0, 2)), ``V_2 = 4^2
    (1/5 - 1/9)`` (the moments of x2^2, x2 ~ U(0, 1)), ``V_3 = 1/2`` (sin over a period),
    ``V_4 = 0``; the first-order indices sum to one."""
    ranges = {"x1": (0.0, 2.0), "x2": (0.0, 1.0), "x3": (-np.pi, np.pi), "x4": (5.0, 9.0)}
    space = fv.ParameterSpace(
        tuple(
            fv.Parameter(n, "custom", "1", lo, hi, (-np.inf, np.inf), "", "")
            for n, (lo, hi) in ranges.items()
        )
    )
    d = fv.sample_design(space, 2**10, "saltelli", seed=5)
    x = d.values
    y = 1.5 * x[:, 0] + 4.0 * x[:, 1] ** 2 + np.sin(x[:, 2]) + 0.0 * x[:, 3] - 100.0
    V = np.array([1.5**2 * 4 / 12, 4.0**2 * (1 / 5 - 1 / 9), 0.5, 0.0])
    S1, ST = fv.sobol_indices(d, y)
    np.testing.assert_allclose(S1, V / V.sum(), atol=0.005)
    np.testing.assert_allclose(ST, V / V.sum(), atol=0.005)
    assert S1.sum() == pytest.approx(1.0, abs=0.005)
    # the same function as a band level: a response |v| = 10^(y / 20) on one line
    v = (10 ** (y / 20))[:, None, None] * np.ones((1, 2, 1))
    s = fv.sensitivity(d, [1.0, 2.0], v, bands=[[1.0, 2.0]], dofs=["e:z"], n_bootstrap=0)
    np.testing.assert_allclose(s.total[:, 0, 0], V / V.sum(), atol=0.005)
    assert [r["parameter"] for r in s.ranking("e:z", 0)] == ["x2", "x1", "x3", "x4"]
