"""The FRF data object: complex frequency response data labelled by DOF.

Data are stored frequency first, ``(n_freq, n_out, n_in)``, so that batched
``@``, :func:`numpy.linalg.solve` and :func:`numpy.einsum` run over all lines at
once (the layout of scikit-rf's ``Network.s``). Objects are immutable: every
method returns a new :class:`FRF`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._typing import AnyArray, ComplexArray, FloatArray, IntArray
from .dofs import index_of, validate_labels
from .errors import DataFormatError, FrequencyGridError, QuantityError
from .vocabulary import magnitude_db
from .vocabulary import readonly as _frozen

__all__ = ["FRF", "QUANTITIES", "UNITS", "check_grid"]

#: A position selector of :meth:`FRF.isel`: int, slice, index list or boolean mask.
type _Index = "slice | ArrayLike | None"

#: FRF quantities (thesis table 2.1) and the power of ``j omega`` that turns a
#: receptance into each of them.
QUANTITIES: dict[str, int] = {"receptance": 0, "mobility": 1, "accelerance": 2}

#: SI units of a translational response per force, by quantity.
UNITS: dict[str, str] = {"receptance": "m/N", "mobility": "m/(N s)", "accelerance": "m/(N s^2)"}


def _check_kinds(
    kinds: Mapping[str, str] | None, outs: Sequence[str], ins: Sequence[str]
) -> dict[str, str] | None:
    if not kinds:
        return None
    from .units import INPUT_KINDS, OUTPUT_KINDS

    if not isinstance(kinds, Mapping):
        raise DataFormatError(f"kinds must map DOF labels to kinds, got {type(kinds).__name__}")
    allowed = dict.fromkeys([*OUTPUT_KINDS, *INPUT_KINDS])
    out = {}
    for lab, k in kinds.items():
        if k not in allowed:
            raise DataFormatError(f"unknown kind {k!r} for {lab!r}; allowed: {', '.join(allowed)}")
        if lab in outs or lab in ins:
            out[str(lab)] = str(k)
    return out or None


def check_grid(freq: ArrayLike) -> FloatArray:
    """Validate a frequency grid in Hz: 1-D, finite, non-negative, strictly increasing.

    Raises
    ------
    FrequencyGridError
    """
    f = np.asarray(freq)
    if f.ndim != 1 or f.size == 0:
        raise FrequencyGridError(f"frequencies must be a non-empty 1-D array, got shape {f.shape}")
    if not np.issubdtype(f.dtype, np.number) or np.iscomplexobj(f):
        raise FrequencyGridError(f"frequencies must be real numbers in Hz, got dtype {f.dtype}")
    f = f.astype(float)
    if not np.all(np.isfinite(f)):
        raise FrequencyGridError("frequencies must be finite (found NaN or inf)")
    if f[0] < 0:
        raise FrequencyGridError(f"frequencies must be >= 0 Hz, got {f[0]:g} Hz")
    d = np.diff(f)
    if np.any(d <= 0):
        k = int(np.argmax(d <= 0))
        raise FrequencyGridError(
            "frequencies must be strictly increasing; "
            f"line {k + 1} ({f[k + 1]:g} Hz) does not exceed line {k} ({f[k]:g} Hz)"
        )
    return f


class FRF:
    """Frequency response functions between labelled DOFs.

    Parameters
    ----------
    freq : array_like, shape (n_freq,)
        Frequencies in Hz, strictly increasing.
    data : array_like, shape (n_freq, n_out, n_in)
        Complex response per unit input at each frequency.
    outputs, inputs : sequence of str
        DOF labels ``"node:dir"`` (e.g. ``"hub:z"``) or generalised names
        (e.g. ``"patch"``); see :mod:`fbs_core.dofs`.
    quantity : {"receptance", "mobility", "accelerance"}
        What the response is per unit input (thesis table 2.1).
    kinds : mapping, optional
        Kind of DOFs whose direction does not tell it, e.g. ``{"patch": "road"}``
        (:mod:`fbs_core.units`); by default ``x y z`` are translations / forces,
        ``rx ry rz`` rotations / moments, ``patch`` a road input. The unit of every
        entry follows (:attr:`units`, :meth:`unit`).

    Raises
    ------
    FrequencyGridError, DataFormatError, DOFError, QuantityError

    Examples
    --------
    >>> import numpy as np
    >>> f = np.array([10.0, 20.0])
    >>> Y = FRF(f, np.ones((2, 1, 1)), ["hub:z"], ["hub:z"])
    >>> Y.sel(outputs="hub:z").shape
    (2, 1, 1)
    """

    __slots__ = ("_freq", "_data", "_outputs", "_inputs", "_quantity", "_kinds")
    _freq: FloatArray
    _data: ComplexArray
    _outputs: tuple[str, ...]
    _inputs: tuple[str, ...]
    _quantity: str
    _kinds: dict[str, str] | None

    def __init__(
        self,
        freq: ArrayLike,
        data: ArrayLike,
        outputs: Iterable[str],
        inputs: Iterable[str],
        quantity: str = "mobility",
        kinds: Mapping[str, str] | None = None,
    ) -> None:
        f = check_grid(freq)
        d = np.asarray(data)
        if not np.issubdtype(d.dtype, np.number):
            raise DataFormatError(f"FRF data must be numeric, got dtype {d.dtype}")
        outs = validate_labels(outputs, "output")
        ins = validate_labels(inputs, "input")
        expected = (f.size, len(outs), len(ins))
        if d.shape != expected:
            raise DataFormatError(
                f"FRF data has shape {d.shape}, expected (n_freq, n_out, n_in) = {expected} "
                f"from {f.size} frequencies, {len(outs)} outputs and {len(ins)} inputs"
            )
        if not np.all(np.isfinite(d)):
            bad = np.argwhere(~np.isfinite(d))[0]
            raise DataFormatError(
                f"FRF data contain non-finite values (first at {f[bad[0]]:g} Hz, "
                f"output {outs[bad[1]]!r}, input {ins[bad[2]]!r})"
            )
        if quantity not in QUANTITIES:
            raise QuantityError(f"unknown quantity {quantity!r}; allowed: {', '.join(QUANTITIES)}")
        object.__setattr__(self, "_freq", _frozen(f))
        object.__setattr__(self, "_data", _frozen(d, complex))  # one copy
        object.__setattr__(self, "_outputs", outs)
        object.__setattr__(self, "_inputs", ins)
        object.__setattr__(self, "_quantity", quantity)
        object.__setattr__(self, "_kinds", _check_kinds(kinds, outs, ins))

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError("FRF objects are immutable; methods return new objects")

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        """Pickled as a call of the constructor (immutable: no state is set afterwards)."""
        args = (self._freq, self._data, self._outputs, self._inputs, self._quantity, self._kinds)
        return (type(self), args)

    # -- properties ----------------------------------------------------------------
    @property
    def freq(self) -> FloatArray:
        """Frequencies in Hz, shape ``(n_freq,)`` (read-only)."""
        return self._freq

    @property
    def omega(self) -> FloatArray:
        """Angular frequencies ``2 pi f`` in rad/s, shape ``(n_freq,)``."""
        return 2 * np.pi * self._freq

    @property
    def data(self) -> ComplexArray:
        """Complex data, shape ``(n_freq, n_out, n_in)`` (read-only)."""
        return self._data

    @property
    def outputs(self) -> tuple[str, ...]:
        return self._outputs

    @property
    def inputs(self) -> tuple[str, ...]:
        return self._inputs

    @property
    def quantity(self) -> str:
        return self._quantity

    @property
    def shape(self) -> tuple[int, int, int]:
        return self._data.shape

    # -- units -----------------------------------------------------------------------
    @property
    def kinds(self) -> dict[str, str]:
        """The kind overrides given at construction (label -> kind)."""
        return dict(self._kinds or {})

    @property
    def output_kinds(self) -> tuple[str, ...]:
        """``translation`` / ``rotation`` / ``generalised`` per output."""
        from .units import output_kind

        return tuple(output_kind(o, self._kinds) for o in self._outputs)

    @property
    def input_kinds(self) -> tuple[str, ...]:
        """``force`` / ``moment`` / ``road`` / ``generalised`` per input."""
        from .units import input_kind

        return tuple(input_kind(i, self._kinds) for i in self._inputs)

    @property
    def units(self) -> AnyArray:
        """SI unit of every entry, shape ``(n_out, n_in)`` of str (e.g. ``m/(N s)``)."""
        from .units import frf_unit

        ok, ik = self.output_kinds, self.input_kinds
        u = np.empty((len(ok), len(ik)), dtype=object)
        for a, o in enumerate(ok):
            for b, i in enumerate(ik):
                u[a, b] = frf_unit(o, i, self._quantity)
        return u

    def unit(self, output: str | None = None, input: str | None = None) -> str:
        """SI unit of one entry (for plot labels); without labels, the common unit of
        all entries, or the units joined by ``" | "`` when they differ.

        Examples
        --------
        >>> import numpy as np
        >>> Y = FRF([1.0], np.ones((1, 2, 1)), ["hub:z", "hub:ry"], ["patch"])
        >>> Y.unit("hub:ry", "patch"), Y.unit()
        ('(rad/s)/m', '(m/s)/m | (rad/s)/m')
        """
        from .units import frf_unit, input_kind, output_kind

        if output is not None or input is not None:
            o = output if output is not None else self._outputs[0]
            i = input if input is not None else self._inputs[0]
            index_of(self._outputs, o, "output DOF")
            index_of(self._inputs, i, "input DOF")
            return frf_unit(output_kind(o, self._kinds), input_kind(i, self._kinds), self._quantity)
        return " | ".join(dict.fromkeys(self.units.ravel().tolist()))

    def __repr__(self) -> str:
        f = self._freq
        return (
            f"<FRF {self._quantity} {self.shape[1]}x{self.shape[2]} at {f.size} lines "
            f"{f[0]:g}-{f[-1]:g} Hz; outputs {list(self._outputs)}; inputs {list(self._inputs)}>"
        )

    # -- construction helpers ------------------------------------------------------
    def replace(self, **changes: Any) -> FRF:
        """A new FRF with some of ``freq, data, outputs, inputs, quantity`` replaced."""
        kw: dict[str, Any] = dict(
            freq=self._freq,
            data=self._data,
            outputs=self._outputs,
            inputs=self._inputs,
            quantity=self._quantity,
            kinds=self._kinds,
        )
        unknown = set(changes) - set(kw)
        if unknown:
            raise TypeError(f"unknown field(s) {sorted(unknown)}; allowed: {sorted(kw)}")
        kw.update(changes)
        return FRF(**kw)

    # -- selection -----------------------------------------------------------------
    def sel(
        self, outputs: str | Iterable[str] | None = None, inputs: str | Iterable[str] | None = None
    ) -> FRF:
        """Select by DOF label (like xarray's ``sel``); ``None`` keeps all.

        Raises
        ------
        DOFError
            For an unknown label, naming the available ones.
        """
        oi = None if outputs is None else index_of(self._outputs, outputs, "output DOF")
        ii = None if inputs is None else index_of(self._inputs, inputs, "input DOF")
        return self.isel(outputs=oi, inputs=ii)

    def isel(self, freq: _Index = None, outputs: _Index = None, inputs: _Index = None) -> FRF:
        """Select by 0-based position (ints, slices or index lists); ``None`` keeps all."""

        def norm(k: _Index, n: int) -> IntArray:
            if k is None:
                return np.arange(n)
            if isinstance(k, slice):
                return np.arange(n)[k]
            a = np.atleast_1d(np.asarray(k))
            if a.dtype == bool:
                return np.flatnonzero(a)
            if not np.issubdtype(a.dtype, np.integer):
                raise IndexError(f"positions must be integers, got {a.dtype}")
            if np.any((a >= n) | (a < -n)):
                raise IndexError(f"position out of range for axis of length {n}: {a.tolist()}")
            return a % n

        fi = norm(freq, self._freq.size)
        oi = norm(outputs, len(self._outputs))
        ii = norm(inputs, len(self._inputs))
        return FRF(
            self._freq[fi],
            self._data[np.ix_(fi, oi, ii)],
            [self._outputs[i] for i in oi],
            [self._inputs[i] for i in ii],
            self._quantity,
            self._kinds,
        )

    def crop(self, fmin: float | None = None, fmax: float | None = None) -> FRF:
        """Keep the lines with ``fmin <= f <= fmax``."""
        lo = -np.inf if fmin is None else fmin
        hi = np.inf if fmax is None else fmax
        keep = (self._freq >= lo) & (self._freq <= hi)
        if not keep.any():
            raise FrequencyGridError(
                f"no lines in [{lo:g}, {hi:g}] Hz; the FRF spans "
                f"{self._freq[0]:g}-{self._freq[-1]:g} Hz"
            )
        return self.isel(freq=keep)

    # -- quantities ----------------------------------------------------------------
    def to(self, quantity: str) -> FRF:
        """Convert between receptance, mobility and accelerance.

        Each step multiplies by ``j omega`` (receptance -> mobility ->
        accelerance) or divides by it (thesis table 2.1).

        Raises
        ------
        QuantityError
            For an unknown quantity, or when dividing by ``j omega`` at 0 Hz.
        """
        if quantity not in QUANTITIES:
            raise QuantityError(f"unknown quantity {quantity!r}; allowed: {', '.join(QUANTITIES)}")
        p = QUANTITIES[quantity] - QUANTITIES[self._quantity]
        if p == 0:
            return self
        jw = 1j * self.omega
        if p < 0 and np.any(jw == 0):
            raise QuantityError(
                f"cannot convert {self._quantity} to {quantity}: the grid contains 0 Hz, "
                "where dividing by j*omega is undefined; crop it first"
            )
        return self.replace(data=self._data * (jw**p)[:, None, None], quantity=quantity)

    # -- grids ---------------------------------------------------------------------
    def same_grid(self, other: FRF, rtol: float = 1e-12) -> bool:
        """True when both FRFs share the frequency lines."""
        return self._freq.shape == other._freq.shape and np.allclose(
            self._freq, other._freq, rtol=rtol, atol=0.0
        )

    def require_grid(self, other: FRF, what: str = "FRFs") -> None:
        """Raise :class:`FrequencyGridError` unless ``other`` has the same lines."""
        if not self.same_grid(other):
            raise FrequencyGridError(
                f"{what} are on different frequency grids ({self._freq.size} lines "
                f"{self._freq[0]:g}-{self._freq[-1]:g} Hz vs {other._freq.size} lines "
                f"{other._freq[0]:g}-{other._freq[-1]:g} Hz); they are never interpolated "
                "silently: call .interpolate(freq) explicitly"
            )

    def interpolate(self, freq: ArrayLike) -> FRF:
        """Linear interpolation of real and imaginary parts onto ``freq``.

        This is the explicit way to put FRFs on a common grid; nothing in
        ``fbs_core`` interpolates silently.

        Raises
        ------
        FrequencyGridError
            If ``freq`` reaches outside the FRF's range (no extrapolation).
        """
        f = check_grid(freq)
        if f[0] < self._freq[0] - 1e-9 or f[-1] > self._freq[-1] + 1e-9:
            raise FrequencyGridError(
                f"cannot interpolate onto {f[0]:g}-{f[-1]:g} Hz: the FRF spans "
                f"{self._freq[0]:g}-{self._freq[-1]:g} Hz and is never extrapolated"
            )
        flat = self._data.reshape(self._freq.size, -1)
        re = np.stack([np.interp(f, self._freq, c.real) for c in flat.T], axis=-1)
        im = np.stack([np.interp(f, self._freq, c.imag) for c in flat.T], axis=-1)
        return self.replace(freq=f, data=(re + 1j * im).reshape((f.size,) + self.shape[1:]))

    # -- comparisons and arithmetic --------------------------------------------------
    def allclose(self, other: FRF, rtol: float = 1e-10, atol: float = 0.0) -> bool:
        """Same labels, quantity and grid, and data equal within tolerance."""
        return (
            self._outputs == other._outputs
            and self._inputs == other._inputs
            and self._quantity == other._quantity
            and self.same_grid(other)
            and np.allclose(self._data, other._data, rtol=rtol, atol=atol)
        )

    def transpose(self) -> FRF:
        """Swap outputs and inputs (``Y^T`` at every line)."""
        return self.replace(
            data=np.swapaxes(self._data, 1, 2), outputs=self._inputs, inputs=self._outputs
        )

    def magnitude_db(self, ref: float = 1.0) -> FloatArray:
        """``20 log10(|data| / ref)``, shape ``(n_freq, n_out, n_in)``; ``-inf`` where 0
        (:func:`fbs_core.vocabulary.magnitude_db` without a floor)."""
        return magnitude_db(self._data, ref, floor=None)
