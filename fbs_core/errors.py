"""Domain exceptions of :mod:`fbs_core`.

Every exception subclasses the built-in it refines, so ``except ValueError`` (or
``KeyError``, ``numpy.linalg.LinAlgError``) in user code keeps working, in the
manner of python-control's ``control/exception.py``.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "FBSError",
    "DOFError",
    "FrequencyGridError",
    "QuantityError",
    "SingularInterfaceError",
    "DataFormatError",
]


class FBSError(ValueError):
    """Base class of all errors raised by ``fbs_core`` for bad input."""


class DOFError(FBSError, KeyError):
    """An unknown, duplicated or malformed DOF label."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class FrequencyGridError(FBSError):
    """Frequency grids that are invalid or do not match."""


class QuantityError(FBSError):
    """An unknown FRF quantity or an impossible conversion between quantities."""


class SingularInterfaceError(FBSError, np.linalg.LinAlgError):
    """The interface matrix to be inverted is singular or too ill-conditioned."""


class DataFormatError(FBSError):
    """A file or array that is not what it claims to be."""
