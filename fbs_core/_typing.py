"""Array type aliases for annotations (typing only, no runtime behaviour)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["AnyArray", "BoolArray", "ComplexArray", "FloatArray", "IndexLike", "IntArray"]

#: Real array (frequencies in Hz, magnitudes, parameters).
type FloatArray = NDArray[np.float64]
#: Complex array (FRF data, mode shapes; complex128 at run time). Spelled with
#: ``complexfloating`` because numpy's stubs give that type to the results of
#: ``linalg.solve``, ``inv`` and complex arithmetic.
type ComplexArray = NDArray[np.complexfloating[Any, Any]]
#: Integer array (indices, counts).
type IntArray = NDArray[np.intp]
#: Boolean mask.
type BoolArray = NDArray[np.bool_]
#: Array of unspecified dtype (object arrays, inputs before validation).
type AnyArray = NDArray[Any]
#: Positions along one axis: a list of ints or an integer array.
type IndexLike = "Sequence[int] | NDArray[np.integer[Any]]"
