"""Counter-based random numbers for the Monte-Carlo noise study (thesis 5.2).

The noise factor of round ``r``, frequency line ``l`` and matrix element ``e`` is a
pure function of ``(seed, r, l, e)``: no generator state is carried from one round
to the next. Any round can therefore be regenerated alone, in any order, on any
number of threads, and the rounds of a batch never have to be stored.

The hash is the SplitMix64 output function (Steele, Lea & Flood, "Fast splittable
pseudorandom number generators", OOPSLA 2014; finaliser constants of D. Stafford's
"Mix13"), applied in three levels::

    key        = mix(seed + G)
    base(r, l) = mix(mix(key + (r + 1) G) + (l + 1) G)
    word(k)    = mix(base(r, l) + (k + 1) G)           # k = e // 2

with ``G = 0x9E3779B97F4A7C15`` and all arithmetic modulo 2**64. Each 64-bit word
gives two uniforms in ``[0, 1)`` with 32-bit resolution: element ``2k`` from the high
half, element ``2k + 1`` from the low half.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ..errors import FBSError

__all__ = ["GOLDEN", "mix64", "mix64_np", "seed_key", "stream_base", "as_seed"]

GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S27 = np.uint64(27)
_S30 = np.uint64(30)
_S31 = np.uint64(31)
_S32 = np.uint64(32)
_LO32 = np.uint64(0xFFFFFFFF)
_ONE = np.uint64(1)
_INV32 = 2.0**-32


def mix64_np(z: NDArray[np.uint64]) -> NDArray[np.uint64]:
    """:func:`mix64` on numpy ``uint64`` arrays (call under ``np.errstate(over="ignore")``)."""
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@njit(cache=True)
def mix64(z: np.uint64) -> np.uint64:
    """SplitMix64 output function (a bijection of the 64-bit integers)."""
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


def seed_key(seed: int) -> np.uint64:
    """The 64-bit key ``mix(seed + G)`` of an integer seed (computed in Python)."""
    mask = (1 << 64) - 1
    z = (int(seed) + int(GOLDEN)) & mask
    z = ((z ^ (z >> 30)) * int(_M1)) & mask
    z = ((z ^ (z >> 27)) * int(_M2)) & mask
    return np.uint64(z ^ (z >> 31))


@njit(cache=True)
def stream_base(key: np.uint64, r: int, line: int) -> np.uint64:
    """The base counter of round ``r`` at frequency line ``line``."""
    a = mix64(key + (np.uint64(r) + _ONE) * GOLDEN)
    return mix64(a + (np.uint64(line) + _ONE) * GOLDEN)


def as_seed(seed: int | np.integer[Any] | np.random.Generator) -> int:
    """An integer seed in ``[0, 2**64)`` from an int or a :class:`numpy.random.Generator`.

    A generator contributes one draw, so that ``scatter_band(..., seed=rng)`` is
    reproducible from the generator's own seed.

    Raises
    ------
    FBSError
        For negative, too large or non-integer seeds.
    """
    if isinstance(seed, np.random.Generator):
        return int(seed.integers(0, 2**63))
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise FBSError(f"seed must be a non-negative integer or a numpy Generator, got {seed!r}")
    s = int(seed)
    if not 0 <= s < 2**64:
        raise FBSError(f"seed must be in [0, 2**64), got {s}")
    return s
