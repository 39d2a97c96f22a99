"""Array type aliases for annotations (typing only, no runtime behaviour)."""

from __future__ import annotations

from typing import Any, TypeAlias

import numpy as np
from numpy.typing import NDArray

__all__ = ["AnyArray", "BoolArray", "ComplexArray", "FloatArray", "IntArray"]

#: Real array (frequencies in Hz, magnitudes, parameters).
FloatArray: TypeAlias = NDArray[np.float64]
#: Complex array (FRF data, mode shapes).
ComplexArray: TypeAlias = NDArray[np.complex128]
#: Integer array (indices, counts).
IntArray: TypeAlias = NDArray[np.intp]
#: Boolean mask.
BoolArray: TypeAlias = NDArray[np.bool_]
#: Array of unspecified dtype (object arrays, inputs before validation).
AnyArray: TypeAlias = NDArray[Any]
