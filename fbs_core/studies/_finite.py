"""The check that a study's result is finite at every frequency line."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..errors import SingularInterfaceError

__all__ = ["require_finite"]


def require_finite(x: ArrayLike, freq: ArrayLike, what: str, why: str) -> None:
    """Raise :class:`~fbs_core.errors.SingularInterfaceError` naming the first frequency
    line (axis 0 of ``x``) where ``x`` is not finite: "``what`` is not finite at f Hz
    (``why``)".

    Parameters
    ----------
    x : array_like
        Values, frequency first.
    freq : array_like
        The frequency lines (Hz) of axis 0.
    what, why : str
        What is checked and the likely cause, for the message.
    """
    a = np.asarray(x)
    if not np.all(np.isfinite(a)):
        line = int(np.argwhere(~np.isfinite(a))[0][0])
        f = float(np.asarray(freq, float)[line])
        raise SingularInterfaceError(f"{what} is not finite at {f:g} Hz ({why})")
