"""Discrete mass-spring-damper test structures, split into subsystems.

A structure is a set of nodes with DOFs x and y. Each subsystem owns some
nodes, springs between its nodes, grounding springs and dampers, and a share
of the mass and gyroscopic coupling of every node it touches. The global
matrices are the plain sum of the subsystems' contributions, assembled here by
index arithmetic (independently of ``fbs_core.direct.assemble``), so that the
direct solution of the whole is the ground truth for every coupling method.
"""

from __future__ import annotations

import numpy as np

from fbs_core import FRF

DIRS = ("x", "y")


def label(node: int, d: str) -> str:
    return f"n{node}:{d}"


def build(partition: dict[str, list[int]], gyro: float, seed: int = 0):
    """Random split structure.

    Returns
    -------
    subs : dict name -> (M, C, K, labels)
    glob : (M, C, K, labels) of the whole structure
    """
    rng = np.random.default_rng(seed)
    nodes = sorted({n for ns in partition.values() for n in ns})
    share = {n: sum(n in ns for ns in partition.values()) for n in nodes}
    glabels = [label(n, d) for n in nodes for d in DIRS]
    gidx = {lab: i for i, lab in enumerate(glabels)}
    N = len(glabels)
    Mg, Cg, Kg = (np.zeros((N, N)) for _ in range(3))
    mass = {n: rng.uniform(0.5, 2.0) for n in nodes}
    subs = {}
    for name, ns in partition.items():
        labs = [label(n, d) for n in ns for d in DIRS]
        n = len(labs)
        M, C, K = (np.zeros((n, n)) for _ in range(3))
        loc = {lab: i for i, lab in enumerate(labs)}
        for node in ns:
            for d in DIRS:
                i = loc[label(node, d)]
                M[i, i] += mass[node] / share[node]
            ix, iy = loc[label(node, "x")], loc[label(node, "y")]
            g = gyro * mass[node] / share[node]
            C[ix, iy] += g  # skew gyroscopic coupling of a spinning node
            C[iy, ix] -= g
        # springs along the chain of the subsystem's nodes, plus random extras
        pairs = list(zip(ns[:-1], ns[1:], strict=True))
        pairs += [tuple(rng.choice(ns, 2, replace=False)) for _ in range(len(ns) // 2)]
        for a, b in pairs:
            for d in DIRS:
                k = rng.uniform(2e3, 8e3)
                c = 1e-3 * k
                ia, ib = loc[label(a, d)], loc[label(b, d)]
                for i, j, sgn in ((ia, ia, 1), (ib, ib, 1), (ia, ib, -1), (ib, ia, -1)):
                    K[i, j] += sgn * k
                    C[i, j] += sgn * c
            # a cross spring x_a - y_b makes the stiffness fully coupled
            kc = rng.uniform(5e2, 1e3)
            ia, ib = loc[label(a, "x")], loc[label(b, "y")]
            for i, j, sgn in ((ia, ia, 1), (ib, ib, 1), (ia, ib, -1), (ib, ia, -1)):
                K[i, j] += sgn * kc
        # grounding springs on the first node of every subsystem
        for d in DIRS:
            i = loc[label(ns[0], d)]
            K[i, i] += rng.uniform(1e3, 3e3)
            C[i, i] += 0.5
        subs[name] = (M, C, K, labs)
        g = [gidx[lab] for lab in labs]
        Mg[np.ix_(g, g)] += M
        Cg[np.ix_(g, g)] += C
        Kg[np.ix_(g, g)] += K
    return subs, (Mg, Cg, Kg, glabels)


def frf_of(M, C, K, labels, freq, quantity="mobility") -> FRF:
    """Square FRF of a matrix model by direct solution (independent of fbs_core)."""
    w = 2 * np.pi * np.asarray(freq)
    Z = K[None] - w[:, None, None] ** 2 * M[None] + 1j * w[:, None, None] * C[None]
    H = np.linalg.inv(Z)
    p = {"receptance": 0, "mobility": 1, "accelerance": 2}[quantity]
    return FRF(freq, H * ((1j * w) ** p)[:, None, None], labels, labels, quantity)
