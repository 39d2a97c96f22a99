"""The floating-band error metric of thesis eq. 5.1.

For a true (reference) response ``v_T`` and a modified one ``v_M`` the error over a
band of lines is the mismatch of power related to the power of the reference::

    eps = sum_band | |v_T|^2 - |v_M|^2 |  /  sum_band |v_T|^2          (eq. 5.1)

and the band floats: the error is mapped to the band's centre frequency, and the
band is moved in steps (thesis fig. 5.2; defaults 12 Hz wide and 1 Hz steps, as
chosen in the thesis' section 5.1.1).

Band edges. A band holds the lines with ``|f - f_c| <= width / 2`` (both ends
included). Near the ends of the frequency range the thesis does not say what
happens; here ``edges="clip"`` (default) evaluates every centre in the range and
clips its band to the available lines, so that the first and last centres use a
one-sided band of at least half the width; ``edges="valid"`` only keeps centres
whose full band lies inside the range. Default centres are the multiples of
``step`` inside ``[f_0, f_end]`` (``"clip"``) or ``[f_0 + w/2, f_end - w/2]``
(``"valid"``). The sums are plain sums over lines as in eq. 5.1 (on a uniform grid
they are proportional to the band integrals).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray, IntArray
from ..errors import DataFormatError, FBSError
from ..frf import check_grid

__all__ = ["EDGES", "band_centres", "band_power_sums", "floating_band_error"]

#: Allowed band-edge treatments.
EDGES = ("clip", "valid")

_TOL = 1e-9


def _check_band(width: float, step: float, edges: str) -> None:
    if not (np.isfinite(width) and width > 0):
        raise FBSError(f"band width must be a positive number of Hz, got {width!r}")
    if not (np.isfinite(step) and step > 0):
        raise FBSError(f"band step must be a positive number of Hz, got {step!r}")
    if edges not in EDGES:
        raise FBSError(f"unknown band-edge treatment {edges!r}; allowed: {', '.join(EDGES)}")


def band_centres(
    freq: ArrayLike, width: float = 12.0, step: float = 1.0, edges: str = "clip"
) -> FloatArray:
    """Default centre frequencies of the floating band: multiples of ``step`` in range.

    Parameters
    ----------
    freq : array_like, shape (n_f,)
        Frequency lines in Hz.
    width, step : float
        Band width and step in Hz.
    edges : {"clip", "valid"}
        ``"clip"``: centres in ``[f_0, f_end]``; ``"valid"``: only where the whole
        band fits, ``[f_0 + width/2, f_end - width/2]``.

    Returns
    -------
    ndarray, shape (n_c,)
        Possibly empty (for ``"valid"`` on a range narrower than the band).
    """
    f = check_grid(freq)
    _check_band(width, step, edges)
    half = width / 2 if edges == "valid" else 0.0
    lo, hi = f[0] + half, f[-1] - half
    k0 = np.ceil(lo / step - _TOL)
    k1 = np.floor(hi / step + _TOL)
    return np.arange(k0, k1 + 1) * step + 0.0 if k1 >= k0 else np.empty(0)


def _band_bounds(
    f: FloatArray, centres: FloatArray, width: float, edges: str
) -> tuple[IntArray, IntArray]:
    half = width / 2
    i0 = np.searchsorted(f, centres - half - _TOL, side="left")
    i1 = np.searchsorted(f, centres + half + _TOL, side="right")
    if edges == "valid":
        bad = (centres - half < f[0] - _TOL) | (centres + half > f[-1] + _TOL)
        if np.any(bad):
            c = centres[np.argmax(bad)]
            raise FBSError(
                f"centre {c:g} Hz: its {width:g} Hz band leaves the range "
                f"{f[0]:g}-{f[-1]:g} Hz, which edges='valid' does not allow; use edges='clip'"
            )
    return i0, i1


def band_power_sums(
    freq: ArrayLike,
    v_ref: ArrayLike,
    v_mod: ArrayLike,
    centres: ArrayLike,
    width: float = 12.0,
    edges: str = "clip",
) -> tuple[FloatArray, FloatArray]:
    """Numerator and denominator of eq. 5.1 for every centre (the array kernel).

    Parameters
    ----------
    freq : ndarray, shape (n_f,)
    v_ref : ndarray, shape (n_f, ...)
        Reference (true) response, frequency first.
    v_mod : ndarray, shape (..., n_f, ...)
        Modified responses; broadcast against ``v_ref`` from the right, so leading
        batch axes (e.g. retained-mode counts) are allowed.
    centres : ndarray, shape (n_c,)

    Returns
    -------
    num, den : ndarray, shape (..., n_c, ...)
        ``sum | |v_T|^2 - |v_M|^2 |`` and ``sum |v_T|^2`` over each band.
    """
    f = np.asarray(freq, float)
    pr = np.abs(np.asarray(v_ref)) ** 2
    pm = np.abs(np.asarray(v_mod)) ** 2
    if pr.shape[:1] != f.shape:
        raise DataFormatError(
            f"reference response has {pr.shape[0] if pr.ndim else 0} lines along its first axis, "
            f"expected {f.size} (frequency first)"
        )
    try:
        diff = np.abs(pr - pm)
    except ValueError:
        raise DataFormatError(
            f"modified response of shape {pm.shape} does not broadcast against the reference "
            f"of shape {pr.shape} (frequency axis {pr.ndim} from the right)"
        ) from None
    ax = diff.ndim - pr.ndim  # frequency axis of the broadcast result
    i0, i1 = _band_bounds(f, np.asarray(centres, float), width, edges)
    zero_d = np.zeros_like(np.take(diff, [0], axis=ax))
    cd = np.concatenate([zero_d, np.cumsum(diff, axis=ax)], axis=ax)
    cr = np.concatenate([np.zeros_like(pr[:1]), np.cumsum(pr, axis=0)], axis=0)
    num = np.take(cd, i1, axis=ax) - np.take(cd, i0, axis=ax)
    den = np.take(cr, i1, axis=0) - np.take(cr, i0, axis=0)
    return num, den


def floating_band_error(
    freq: ArrayLike,
    v_ref: ArrayLike,
    v_mod: ArrayLike,
    width: float = 12.0,
    step: float = 1.0,
    edges: str = "clip",
    centres: ArrayLike | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Thesis eq. 5.1 over a floating band: error versus centre frequency.

    Parameters
    ----------
    freq : array_like, shape (n_f,)
        Frequency lines in Hz (strictly increasing).
    v_ref : array_like, shape (n_f, ...)
        True (reference) response ``v_T``, complex or real, frequency first.
    v_mod : array_like, shape (..., n_f, ...)
        Modified response ``v_M``; broadcasts against ``v_ref`` from the right, so
        e.g. ``(n_N, n_f, n_dof)`` against ``(n_f, n_dof)``.
    width, step : float
        Band width and step in Hz (thesis: 12 Hz and 1 Hz).
    edges : {"clip", "valid"}
        Band-edge treatment at the ends of the range (module docstring).
    centres : array_like, optional
        Centre frequencies in Hz; default :func:`band_centres`.

    Returns
    -------
    centres : ndarray, shape (n_c,)
    error : ndarray, shape (..., n_c, ...)
        Relative error (0.2 = 20 %); the frequency axis of the inputs becomes the
        centre axis. Where the reference has no power in a band the error is 0 if
        the modified curve has none either, else ``inf``.

    Raises
    ------
    FBSError
        For a non-positive width or step, an unknown ``edges``, or (``"valid"``)
        explicit centres whose band leaves the range.
    FrequencyGridError, DataFormatError
        For a bad grid or shapes that do not match it.

    Examples
    --------
    >>> import numpy as np
    >>> f = np.arange(0.0, 50.0, 0.5)
    >>> v = 1 / (1 + 1j * (f - 20))
    >>> c, e = floating_band_error(f, v, 1.1 * v)
    >>> bool(np.allclose(e, 0.21))
    True
    """
    f = check_grid(freq)
    _check_band(width, step, edges)
    c = band_centres(f, width, step, edges) if centres is None else np.asarray(centres, float)
    if c.ndim != 1:
        raise FBSError(f"centres must be a 1-D array of Hz, got shape {c.shape}")
    num, den = band_power_sums(f, v_ref, v_mod, c, width, edges)
    with np.errstate(divide="ignore", invalid="ignore"):
        err = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.where(num > 0, np.inf, 0.0))
    return c, err
