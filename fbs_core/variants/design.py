"""Sampling designs of a parameter space from :mod:`scipy.stats.qmc` (seeded).

- ``"sobol"``: a scrambled Sobol' sequence (Owen scrambling), ``n`` a power of two (its
  balance properties hold for 2^m points);
- ``"lhs"``: a Latin hypercube (every parameter's range cut into ``n`` equal strata, one
  point in each), any ``n``;
- ``"saltelli"``: the pick-freeze design of the variance-based sensitivity indices
  (Saltelli et al., Comput. Phys. Commun. 181 (2010) 259-270): matrices ``A`` and ``B``
  of ``N`` rows each from one scrambled Sobol' sequence of dimension ``2 k`` (A its first
  ``k`` columns, B its last ``k``), and for every parameter ``i`` the matrix ``AB_i``: A
  with column ``i`` taken from B. ``N (k + 2)`` variants, rows ordered
  ``A, B, AB_1 .. AB_k``. Its first ``N' = 2^m`` rows of each block are the design of
  ``N'`` (the sequence's prefix), which is how :mod:`.sensitivity` shows convergence.

Values are uniform over each parameter's range: ``low + u (high - low)``.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._typing import FloatArray, IntArray
from ..vocabulary import readonly as _ro
from .parameters import ParameterError, ParameterSpace

__all__ = ["DESIGNS", "Design", "sample_design"]

#: The sampling methods.
DESIGNS = ("sobol", "lhs", "saltelli")


@dataclass(frozen=True, eq=False)
class Design:
    """Points of a parameter space, one row per variant.

    Parameters
    ----------
    space : ParameterSpace
        The parameters (columns).
    method : {"sobol", "lhs", "saltelli"}
    seed : int
        The seed of the scrambling / stratification.
    unit : ndarray, shape (n, k)
        The points in the unit cube.
    n_base : int
        ``N`` of a Saltelli design (rows per block); ``n`` otherwise.
    """

    space: ParameterSpace
    method: str
    seed: int
    unit: FloatArray
    n_base: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "unit", _ro(np.asarray(self.unit, float)))

    @property
    def values(self) -> FloatArray:
        """Parameter values, shape (n, k)."""
        v: FloatArray = _ro(self.space.scale(self.unit))
        return v

    @property
    def n(self) -> int:
        """Number of variants (rows)."""
        return int(self.unit.shape[0])

    @property
    def names(self) -> tuple[str, ...]:
        return self.space.names

    def row(self, i: int) -> dict[str, float]:
        """Parameter name -> value of variant ``i``."""
        return {n: float(x) for n, x in zip(self.names, self.values[int(i)], strict=True)}

    def blocks(self) -> dict[str, IntArray]:
        """Row indices of ``A``, ``B`` and ``AB_<name>`` of a Saltelli design.

        Raises
        ------
        ParameterError
            For another design.
        """
        if self.method != "saltelli":
            raise ParameterError(f"a {self.method!r} design has no Saltelli blocks")
        N = self.n_base
        out = {"A": np.arange(N), "B": np.arange(N, 2 * N)}
        for i, name in enumerate(self.names):
            out[f"AB_{name}"] = np.arange((2 + i) * N, (3 + i) * N)
        return out


def _rng_kw(cls: Any, seed: int) -> dict[str, Any]:
    """The seed keyword of a qmc engine (``rng`` from scipy 1.15, ``seed`` before)."""
    g = np.random.default_rng(seed)
    return {"rng": g} if "rng" in inspect.signature(cls).parameters else {"seed": g}


def _power_of_two(n: int, method: str) -> int:
    m = int(n).bit_length() - 1
    if n < 2 or 2**m != n:
        raise ParameterError(
            f"a {method!r} design needs n a power of two >= 2 (its balance properties hold "
            f"for 2^m points), got {n}; use 'lhs' for any n"
        )
    return m


def sample_design(space: ParameterSpace, n: int, method: str = "sobol", seed: int = 0) -> Design:
    """A seeded design of ``n`` points (``n`` base rows for ``"saltelli"``).

    Parameters
    ----------
    space : ParameterSpace
    n : int
        Variants (``"sobol"``: a power of two; ``"lhs"``: any >= 2); for ``"saltelli"`` the
        base rows ``N`` (a power of two), giving ``N (k + 2)`` variants.
    method : {"sobol", "lhs", "saltelli"}
    seed : int
        Non-negative; the same seed gives the same design.

    Returns
    -------
    Design

    Raises
    ------
    ParameterError
        For an unknown method, a bad ``n`` or seed.

    Examples
    --------
    >>> from fbs_core.variants import ParameterSpace
    >>> sp = ParameterSpace.from_names(["tread_mass", "knuckle_mass"])
    >>> d = sample_design(sp, 8, "lhs", seed=1)
    >>> d.values.shape
    (8, 2)
    """
    from scipy.stats import qmc

    if method not in DESIGNS:
        raise ParameterError(f"unknown design {method!r}; allowed: {', '.join(DESIGNS)}")
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 2:
        raise ParameterError(f"n must be an integer >= 2, got {n!r}")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ParameterError(f"seed must be a non-negative integer, got {seed!r}")
    n, seed, k = int(n), int(seed), len(space)
    if method == "lhs":
        u = qmc.LatinHypercube(d=k, **_rng_kw(qmc.LatinHypercube, seed)).random(n)
        return Design(space, method, seed, u, n)
    m = _power_of_two(n, method)
    if method == "sobol":
        u = qmc.Sobol(d=k, scramble=True, **_rng_kw(qmc.Sobol, seed)).random_base2(m)
        return Design(space, method, seed, u, n)
    ab = qmc.Sobol(d=2 * k, scramble=True, **_rng_kw(qmc.Sobol, seed)).random_base2(m)
    A, B = ab[:, :k], ab[:, k:]
    blocks = [A, B]
    for i in range(k):
        ABi = A.copy()
        ABi[:, i] = B[:, i]
        blocks.append(ABi)
    return Design(space, method, seed, np.concatenate(blocks), n)
