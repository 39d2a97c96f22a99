"""What the corner's and the car's structure models share: modal FRFs, FRF-given shells, files.

The reference corner (:class:`fbs_core.chassis.ChassisModel`) and the reference car
(:class:`fbs_core.vehicle.VehicleModel`) are FE models whose FRFs are exact sums over
their complex modes; :class:`fbs_core.chassis.FRFChassis` and
:class:`fbs_core.vehicle.FRFVehicle` are the same structures given by an FRF (measured or
computed elsewhere). All of them answer ``mobility(freq, outputs, inputs, quantity)`` with
a labelled :class:`~fbs_core.frf.FRF`, frequency first ``(n_freq, n_out, n_in)``. This
module holds what they have in common, written once:

- :func:`modal_factors`, :func:`modal_sum`: the modal synthesis of the receptance;
- :func:`receptance_frf`: the requested quantity from a receptance (thesis table 2.1);
- :func:`match_grid`, :class:`FRFGiven`: an FRF used on its own lines (interpolated only
  when the user chose it) and cut to the requested DOFs;
- :func:`read_model_frf`: the ``/frf`` group of a shipped model file (its writer,
  :func:`fbs_core.io.hdf5.write_model_hdf5`, needs :mod:`fbs_core.io`, which imports the
  chassis).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._typing import BoolArray, ComplexArray, FloatArray, IntArray
from .errors import DataFormatError, FrequencyGridError, QuantityError
from .frf import FRF, QUANTITIES

__all__ = [
    "modal_factors",
    "modal_sum",
    "receptance_frf",
    "match_grid",
    "FRFGiven",
    "read_model_frf",
]


def modal_factors(lam: ComplexArray, freq: ArrayLike) -> ComplexArray:
    """Modal factors ``1 / (lam_r - omega^2)`` of every line and mode.

    For hysteretic damping the complex modes ``K V = M V diag(lam)``,
    ``lam_r = omega_r^2 (1 + j eta_r)``, diagonalise the dynamic stiffness
    ``K (1 + j eta) - omega^2 M`` at every frequency, so these factors are all that
    depends on ``omega`` in the receptance (:func:`modal_sum`).

    Parameters
    ----------
    lam : ndarray, shape (n_modes,)
        Complex eigenvalues, (rad/s)^2.
    freq : array_like, shape (n_freq,)
        Frequencies in Hz.

    Returns
    -------
    ndarray, shape (n_freq, n_modes)
    """
    w2 = (2 * np.pi * np.asarray(freq, float)) ** 2
    g: ComplexArray = 1.0 / (lam[None, :] - w2[:, None])
    return g


def modal_sum(g: ComplexArray, V_out: ComplexArray, W_in: ComplexArray) -> ComplexArray:
    """Modal synthesis of a receptance, ``H(omega) = V_o diag(g(omega)) W_i`` on every line.

    The modal sum of thesis eq. 2.5 in its second-order form: with the right mode shapes
    ``V`` and the left factors ``W`` (``V^-1 M^-1`` for the plain complex modes,
    :func:`modal_factors`; the car's shifted-inverse form has its own ``W`` and factors),
    ``H_oi(omega) = sum_r V_or g_r(omega) W_ri``, all modes (no truncation) unless the
    caller passes fewer. The mobility is ``j omega H`` (thesis table 2.1,
    :func:`receptance_frf`).

    Parameters
    ----------
    g : ndarray, shape (n_freq, n_modes)
        Modal factors per line.
    V_out : ndarray, shape (n_out, n_modes)
        Mode shapes at the outputs.
    W_in : ndarray, shape (n_modes, n_in)
        Left factors at the inputs.

    Returns
    -------
    ndarray, shape (n_freq, n_out, n_in)
    """
    # (n_freq, n_out, n_modes) @ (n_modes, n_in) -> (n_freq, n_out, n_in)
    H: ComplexArray = (g[:, None, :] * V_out[None]) @ W_in
    return H


def receptance_frf(
    f: FloatArray,
    outputs: tuple[str, ...],
    inputs: tuple[str, ...],
    quantity: str,
    receptance: Callable[[], ComplexArray],
) -> FRF:
    """The FRF of ``quantity`` from a model's receptance on the checked grid ``f``.

    ``quantity`` is checked before the (costly) ``receptance()`` runs; the receptance is
    multiplied by ``(j omega)^p``, ``p`` = 0, 1, 2 for receptance, mobility and
    accelerance (thesis table 2.1).

    Parameters
    ----------
    f : ndarray, shape (n_freq,)
        Frequencies in Hz, as returned by :func:`fbs_core.frf.check_grid`.
    outputs, inputs : tuple of str
        The DOF labels of the receptance's rows and columns.
    quantity : {"receptance", "mobility", "accelerance"}
    receptance : callable
        Returns the receptance, shape (n_freq, n_out, n_in).

    Raises
    ------
    QuantityError
        For an unknown quantity, naming the allowed ones.
    """
    if quantity not in QUANTITIES:
        raise QuantityError(f"unknown quantity {quantity!r}; allowed: {', '.join(QUANTITIES)}")
    H = receptance()
    jw = 1j * 2 * np.pi * f
    return FRF(f, H * (jw ** QUANTITIES[quantity])[:, None, None], outputs, inputs, quantity)


def _nearest(F: FloatArray, f: FloatArray, rtol: float) -> tuple[IntArray, BoolArray]:
    """Per frequency, the first line of ``F`` at or above ``f - tol`` and whether it matches.

    ``F`` is non-empty and increasing; ``tol = rtol * max(1, |f|)`` Hz.
    """
    tol = rtol * np.maximum(1.0, np.abs(f))
    idx = np.clip(np.searchsorted(F, f - tol), 0, F.size - 1)
    return idx, np.abs(F[idx] - f) <= tol


def match_grid(available: ArrayLike, wanted: ArrayLike, rtol: float = 1e-9) -> IntArray | None:
    """Positions of the ``wanted`` frequencies in the sorted grid ``available``.

    A line matches when it lies within ``rtol * max(1, |f|)`` Hz of a wanted frequency
    (grids read from files carry rounding in their last digits).

    Parameters
    ----------
    available : array_like, shape (n,)
        Increasing frequencies in Hz.
    wanted : array_like, shape (m,)
        Frequencies in Hz.

    Returns
    -------
    ndarray of int, shape (m,), or None
        ``None`` when some wanted frequency has no line.

    Examples
    --------
    >>> match_grid([1.0, 2.0, 3.0], [3.0, 1.0 + 1e-12]).tolist()
    [2, 0]
    >>> match_grid([1.0, 2.0], [1.5]) is None
    True
    """
    F = np.asarray(available, float)
    f = np.asarray(wanted, float)
    if F.size == 0:
        return None if f.size else np.zeros(0, int)
    idx, hit = _nearest(F, f, rtol)
    return idx if bool(np.all(hit)) else None


class FRFGiven:
    """A structure given by an FRF, used like the model it stands for.

    The FRF is used on its own lines; frequencies it does not hold are refused unless the
    user chose ``interpolate=True`` (then :meth:`FRF.interpolate`: linear in real and
    imaginary part, never extrapolated). No silent interpolation (docs/file-formats.md).
    A subclass says how the refusal reads (:meth:`_refusal`) and which DOFs
    :meth:`mobility` returns by default (:meth:`_default_dofs`).

    Parameters
    ----------
    frf : FRF
        The structure's FRF, shape (n_freq, n_out, n_in).
    interpolate : bool
        Interpolate onto frequencies the FRF has no line at (an explicit choice).
    """

    def __init__(self, frf: FRF, interpolate: bool = False) -> None:
        self.frf = frf
        self.interpolate = bool(interpolate)

    def needs_interpolation(self, freq: ArrayLike) -> bool:
        """True when some of ``freq`` (Hz) is not a line of the FRF."""
        return match_grid(self.frf.freq, freq) is None

    def on_grid(self, freq: ArrayLike) -> FRF:
        """The whole FRF on ``freq`` (Hz): its own lines, else interpolated if allowed.

        Raises
        ------
        FrequencyGridError
            When some frequency is not a line of the FRF and ``interpolate`` is False.
        """
        f = np.asarray(freq, float)
        idx = match_grid(self.frf.freq, f)
        if idx is not None:
            return self.frf.isel(freq=idx)
        if self.interpolate:
            return self.frf.interpolate(f)
        _, hit = _nearest(self.frf.freq, f, 1e-9)
        raise FrequencyGridError(self._refusal(f, f[~hit]))

    def mobility(
        self,
        freq: ArrayLike,
        outputs: Iterable[str] | None = None,
        inputs: Iterable[str] | None = None,
        quantity: str = "mobility",
    ) -> FRF:
        """The FRF on ``freq`` (Hz) between the requested DOFs, in ``quantity``.

        Parameters
        ----------
        freq : array_like, shape (n_freq,)
            Frequencies in Hz.
        outputs, inputs : sequence of str, optional
            Default: the structure's (:meth:`_default_dofs`).
        quantity : {"receptance", "mobility", "accelerance"}

        Returns
        -------
        FRF, shape (n_freq, n_out, n_in)

        Raises
        ------
        FrequencyGridError
            As :meth:`on_grid`.
        DOFError, QuantityError
            For a label the FRF lacks, or an unknown quantity.
        """
        Y = self.on_grid(freq)
        default_outputs, default_inputs = self._default_dofs()
        Y = Y.sel(
            outputs=default_outputs if outputs is None else list(outputs),
            inputs=default_inputs if inputs is None else list(inputs),
        )
        return Y if quantity == Y.quantity else Y.to(quantity)

    def _refusal(self, f: FloatArray, missing: FloatArray) -> str:
        """The message of the refusal of the grid ``f``, whose lines ``missing`` the FRF lacks."""
        raise NotImplementedError

    def _default_dofs(self) -> tuple[Sequence[str], Sequence[str]]:
        """The outputs and inputs :meth:`mobility` returns when none are named."""
        raise NotImplementedError


def _labels(values: Any) -> list[str]:
    """DOF labels of an HDF5 string attribute (bytes or str)."""
    return [v.decode() if isinstance(v, bytes) else str(v) for v in values]


def read_model_frf(path: str | os.PathLike[str], model: str) -> FRF:
    """The FRF of a shipped model file, checked to be a ``model`` file of this project.

    The file follows the project's HDF5 layout (``fbs_core.io.hdf5``): the root
    attributes ``format = "tire-fbs"`` and ``model``, the FRF in ``/frf``. It is opened
    through :func:`fbs_core.hdf5_guard.open_h5` (no links or data leaving the file).

    Parameters
    ----------
    path : str or pathlib.Path
        An HDF5 file.
    model : str
        The root attribute ``model`` the file must carry, e.g. ``"reference chassis"``.

    Returns
    -------
    FRF, shape (n_freq, n_out, n_in)

    Raises
    ------
    DataFormatError
        If the file is not a ``model`` file, or links to other files.
    """
    from .hdf5_guard import open_h5

    with open_h5(path) as h:  # refuses links and data leaving the file
        if h.attrs.get("format") != "tire-fbs" or h.attrs.get("model") != model:
            raise DataFormatError(
                f"{path}: not a 'tire-fbs' {model} file "
                f"(format={h.attrs.get('format')!r}, model={h.attrs.get('model')!r})"
            )
        g = h["frf"]
        return FRF(
            g["freq"][()],
            g["data"][()],
            _labels(g.attrs["outputs"]),
            _labels(g.attrs["inputs"]),
            str(g.attrs["quantity"]),
        )
