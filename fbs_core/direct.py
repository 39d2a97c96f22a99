"""Direct solution of second-order systems: the ground truth of the coupling tests.

A :class:`SecondOrderSystem` holds ``M x'' + C x' + K x = f`` with labelled DOFs
(thesis eq. 2.1). ``C`` may hold viscous damping plus a gyroscopic (skew) part,
``K`` may be complex (hysteretic damping ``K (1 + j eta)``). Its FRFs come from
solving the dynamic stiffness ``(K - omega^2 M + j omega C) x = f`` (eq. 2.2)
at every line, without any modal approximation. Systems are joined at shared
DOFs by primal assembly (:func:`assemble`), which is how a finite-element code
would couple them, so that FBS results can be checked against it.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike

from ._typing import ComplexArray
from .dofs import index_of, validate_labels
from .errors import DataFormatError
from .frf import FRF, QUANTITIES, check_grid

__all__ = ["SecondOrderSystem", "assemble"]

#: A dense ndarray or a scipy.sparse matrix (scipy ships no type stubs, so this is Any).
type Matrix = Any


def _as_matrix(a: Matrix, n: int, name: str) -> Matrix:
    if sp.issparse(a):
        a = sp.csc_matrix(a)
    else:
        a = np.asarray(a)
    if a.shape != (n, n):
        raise DataFormatError(f"{name} has shape {a.shape}, expected ({n}, {n}) for {n} DOFs")
    return a


@dataclass(frozen=True)
class SecondOrderSystem:
    """A linear structure ``M x'' + C x' + K x = f`` with labelled DOFs.

    Parameters
    ----------
    M, C, K : array_like or scipy.sparse matrix, shape (n, n)
        Mass, damping (viscous plus gyroscopic) and stiffness (complex for
        hysteretic damping). ``C`` may be ``None`` (no viscous damping).
    dofs : sequence of str, length n
        DOF labels.
    """

    M: Matrix
    C: Matrix
    K: Matrix
    dofs: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        dofs = validate_labels(self.dofs)
        n = len(dofs)
        object.__setattr__(self, "dofs", dofs)
        object.__setattr__(self, "M", _as_matrix(self.M, n, "M"))
        object.__setattr__(self, "K", _as_matrix(self.K, n, "K"))
        if self.C is None:
            C = sp.csc_matrix((n, n)) if sp.issparse(self.M) else np.zeros((n, n))
        else:
            C = self.C
        object.__setattr__(self, "C", _as_matrix(C, n, "C"))

    @property
    def n(self) -> int:
        return len(self.dofs)

    def _dense(self, a: Matrix) -> ComplexArray:
        return a.toarray() if sp.issparse(a) else np.asarray(a)

    def dynamic_stiffness(self, omega: float) -> Matrix:
        """``K - omega^2 M + j omega C`` at one angular frequency (eq. 2.2)."""
        if any(sp.issparse(a) for a in (self.M, self.C, self.K)):
            return (
                sp.csc_matrix(self.K)
                - omega**2 * sp.csc_matrix(self.M)
                + 1j * omega * sp.csc_matrix(self.C)
            ).tocsc()
        return self.K - omega**2 * self.M + 1j * omega * self.C

    def frf(
        self,
        freq: ArrayLike,
        outputs: Iterable[str] | None = None,
        inputs: Iterable[str] | None = None,
        quantity: str = "mobility",
        loads: Mapping[str, ArrayLike] | None = None,
    ) -> FRF:
        """FRFs by direct solution at every line.

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz (must be > 0 for mobility and accelerance only if
            the system has rigid-body modes).
        outputs, inputs : sequence of str, optional
            DOF labels; default all DOFs.
        quantity : str
            receptance, mobility or accelerance.
        loads : dict of str -> ndarray (n,), optional
            Generalised inputs: named load vectors (e.g. ``{"patch": f_patch}``)
            appended to ``inputs``.

        Returns
        -------
        FRF, shape (n_freq, n_out, n_in)
        """
        f = check_grid(freq)
        outputs = self.dofs if outputs is None else tuple(outputs)
        inputs = self.dofs if inputs is None and not loads else tuple(inputs or ())
        oi = index_of(self.dofs, outputs, "output DOF")
        ii = index_of(self.dofs, inputs, "input DOF")
        rhs = np.zeros((self.n, len(ii) + len(loads or {})), complex)
        rhs[ii, np.arange(len(ii))] = 1.0
        names = list(inputs)
        for k, (name, vec) in enumerate((loads or {}).items()):
            vec = np.asarray(vec)
            if vec.shape != (self.n,):
                raise DataFormatError(f"load {name!r} has shape {vec.shape}, expected ({self.n},)")
            rhs[:, len(ii) + k] = vec
            names.append(name)
        out = np.empty((f.size, len(oi), rhs.shape[1]), complex)
        sparse = any(sp.issparse(a) for a in (self.M, self.C, self.K))
        for i, w in enumerate(2 * np.pi * f):
            Z = self.dynamic_stiffness(w)
            x = spla.splu(Z).solve(rhs) if sparse else sla.solve(Z, rhs)
            out[i] = x[oi]
        jw = 1j * 2 * np.pi * f
        out *= (jw ** QUANTITIES[quantity])[:, None, None]
        return FRF(f, out, outputs, names, quantity)

    def to_dense(self) -> SecondOrderSystem:
        return SecondOrderSystem(
            self._dense(self.M), self._dense(self.C), self._dense(self.K), self.dofs
        )


def assemble(
    systems: dict[str, SecondOrderSystem], connections: Sequence[tuple[str, str]]
) -> SecondOrderSystem:
    """Primal assembly of several systems, merging connected DOFs.

    Parameters
    ----------
    systems : dict of name -> SecondOrderSystem
    connections : sequence of (str, str)
        Pairs of qualified labels ``"name/dof"``; the two DOFs become one. The
        merged DOF keeps the label of the first of the pair.

    Returns
    -------
    SecondOrderSystem
        DOFs labelled ``"name/dof"`` in the order of the systems, with the second
        DOF of each connection removed.
    """
    labels: list[str] = []
    for name, s in systems.items():
        labels += [f"{name}/{d}" for d in s.dofs]
    # map every global DOF onto a reduced DOF (union-find on connections)
    parent = list(range(len(labels)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in connections:
        ia, ib = index_of(labels, [a, b], "connection DOF")
        ra, rb = find(ia), find(ib)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    roots = sorted({find(i) for i in range(len(labels))})
    col = {r: k for k, r in enumerate(roots)}
    rows = np.arange(len(labels))
    cols = [col[find(int(i))] for i in rows]
    L = sp.csr_matrix(
        (np.ones(len(labels)), (rows, cols)),
        shape=(len(labels), len(roots)),
    )
    blocks: dict[str, list[Matrix]] = {k: [] for k in "MCK"}
    for s in systems.values():
        for k in "MCK":
            a = getattr(s, k)
            blocks[k].append(sp.csc_matrix(a))
    mats = {k: (L.T @ sp.block_diag(blocks[k], format="csr") @ L).tocsc() for k in "MCK"}
    dense = not any(sp.issparse(getattr(s, k)) for s in systems.values() for k in "MCK")
    if dense:
        mats = {k: v.toarray() for k, v in mats.items()}
    return SecondOrderSystem(mats["M"], mats["C"], mats["K"], tuple(labels[r] for r in roots))
