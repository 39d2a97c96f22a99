"""Target curves of the response: the level a bushing DOF (or any response point) may reach.

A :class:`Target` is a level over frequency for one output DOF, in a quantity of thesis
table 2.1 (receptance, mobility, accelerance) per unit of the response's input (a metre
of road amplitude for the bushing response of eq. 4.1, ``(m/s)/m``). It is defined at
points ``(f_i, L_i)`` with the level ``L_i`` in dB re :attr:`Target.ref` (SI) and is
**piecewise linear in dB** between them, over frequency (``axis="linear"``) or over
``log10 f`` (``axis="log"``). Between its first and last point it is evaluated on any
grid (:meth:`Target.level_db_at`); it is never extrapolated: lines outside its range get
NaN ("not judged"). Evaluated in another quantity it is converted exactly at every line,
``L + 20 p log10(2 pi f)`` with ``p`` the difference of the powers of ``j omega``
(thesis table 2.1; accelerance -> mobility is ``p = -1``).

Targets come from

* straight segments in dB (:meth:`Target.segments`, closed form at every line);
* a file (:func:`read_targets`): the target CSV layout below, or UFF dataset 58 records
  read by :func:`fbs_core.io.load_frf` (units converted to SI as for FRFs, the level is
  ``|H|``);
* the incumbent candidate's response plus a margin (:class:`IncumbentTarget`, resolved
  per harmonic by :func:`fbs_core.verdict.verdict`; :meth:`Target.from_response`).

Target CSV layout (docs/verdict.md)::

    # tire-fbs target
    # quantity: mobility
    # units: (mm/s)/mm
    # scale: dB
    # axis: log
    freq [Hz],bushing:z,bushing:x
    20,-20.0,-26.0
    200,-30.0,-32.0

``quantity`` (or a ``units`` label that implies it) is required; ``units`` defaults to
SI; ``scale`` is ``linear`` (levels in ``units``, default) or ``dB`` (dB re ``ref``
``units``; ``ref`` default 1); ``axis`` ``linear`` (default) or ``log``; ``harmonic``
(1..7) restricts the targets to one excitation case. Bad input raises an
:class:`~fbs_core.errors.FBSError` naming the file, line, column, unit or DOF; nothing
is kept of a refused file.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._typing import FloatArray
from .dofs import parse_label
from .errors import DataFormatError, DOFError, FBSError, FrequencyGridError, QuantityError
from .frf import FRF, check_grid
from .units import INPUT_KINDS, QUANTITY_POWER, frf_unit, output_kind, parse_units
from .vocabulary import magnitude_db, readonly

__all__ = [
    "AXES",
    "IncumbentTarget",
    "Target",
    "read_targets",
    "response_level",
]

#: Abscissae over which a target is linear in dB: frequency, or its base-10 logarithm.
AXES: tuple[str, ...] = ("linear", "log")
#: How the levels of a target CSV are written.
SCALES: tuple[str, ...] = ("linear", "dB")
#: File endings read by :func:`read_targets`.
CSV_SUFFIXES = (".csv", ".txt")
UFF_SUFFIXES = (".uff", ".unv", ".uf", ".58")

_REL = 1e-9


def response_level(frf: FRF) -> FloatArray:
    """The level of every output of a response: ``sqrt(sum_i |Y[f, o, i]|^2)``.

    One input (the bushing response of eq. 4.1 to the patch load): ``|Y|``. Several
    inputs are uncorrelated components (``VehicleResponse.response``: the tracks' in-
    and anti-phase parts), whose levels add in power.

    Returns
    -------
    ndarray, shape (n_freq, n_out)
    """
    d = np.asarray(frf.data)
    out: FloatArray = np.sqrt(np.sum(np.abs(d) ** 2, axis=2))
    return out


def _input_kind_of(frf: FRF, where: str) -> str:
    kinds = set(frf.input_kinds)
    if len(kinds) != 1:
        raise QuantityError(
            f"{where}: the inputs {', '.join(frf.inputs)} are of kinds {sorted(kinds)}; a level "
            "sums inputs of one kind only"
        )
    return kinds.pop()


@dataclass(frozen=True)
class Target:
    """The largest level one output DOF may reach, piecewise linear in dB.

    Parameters
    ----------
    dof : str
        Output DOF label ``"node:dir"`` (e.g. ``"bushing:z"``).
    freq : array_like, shape (n_p,)
        Frequencies of the defining points in Hz, strictly increasing, at least two.
    level_db : array_like, shape (n_p,)
        Levels at those points in dB re ``ref``, finite.
    quantity : {"receptance", "mobility", "accelerance"}
        What the level is (thesis table 2.1); default that of the bushing response.
    input_kind : {"road", "force", "moment", "generalised"}
        Per unit of what input (``road``: per metre of road amplitude, as eq. 4.1).
    ref : float
        The level of 0 dB in SI units of :attr:`unit` (default 1).
    axis : {"linear", "log"}
        Linear in dB over frequency, or over ``log10`` of frequency (needs ``freq > 0``).
    harmonic : int, optional
        Excitation case 1..7 the target applies to (None: every case).
    source : str
        Where it came from (a file name, "segments", "incumbent ... + 3 dB").

    Raises
    ------
    DOFError, FrequencyGridError, QuantityError, FBSError
        Naming the DOF, the point or the value.

    Examples
    --------
    >>> t = Target.segments("bushing:z", [(10.0, -20.0), (100.0, -40.0)], axis="log")
    >>> float(t.level_db_at([31.622776601683793])[0])
    -30.0
    """

    dof: str
    freq: FloatArray
    level_db: FloatArray
    quantity: str = "mobility"
    input_kind: str = "road"
    ref: float = 1.0
    axis: str = "linear"
    harmonic: int | None = None
    source: str = ""

    def __post_init__(self) -> None:
        from .harmonics import harmonic as _harmonic

        if not isinstance(self.dof, str):
            raise DOFError(f"a target's DOF must be a label 'node:dir', got {self.dof!r}")
        parse_label(self.dof)
        where = f"target of {self.dof}"
        try:
            f = check_grid(self.freq)
        except FrequencyGridError as e:
            raise FrequencyGridError(f"{where}: {e}") from None
        if f.size < 2:
            raise FrequencyGridError(
                f"{where}: needs at least two points to span a frequency range, got {f.size}"
            )
        lv = np.asarray(self.level_db, dtype=float)
        if lv.shape != f.shape:
            raise FBSError(f"{where}: {lv.size} levels for {f.size} frequencies")
        if not np.all(np.isfinite(lv)):
            k = int(np.flatnonzero(~np.isfinite(lv))[0])
            raise FBSError(f"{where}: the level at {f[k]:g} Hz is {lv[k]} (not a finite dB value)")
        if self.quantity not in QUANTITY_POWER:
            raise QuantityError(
                f"{where}: unknown quantity {self.quantity!r}; allowed: {', '.join(QUANTITY_POWER)}"
            )
        if self.input_kind not in INPUT_KINDS:
            raise QuantityError(
                f"{where}: unknown input kind {self.input_kind!r}; allowed: "
                f"{', '.join(INPUT_KINDS)}"
            )
        if not (isinstance(self.ref, int | float) and np.isfinite(self.ref) and self.ref > 0):
            raise FBSError(f"{where}: the dB reference must be a positive number, got {self.ref!r}")
        if self.axis not in AXES:
            raise FBSError(f"{where}: unknown axis {self.axis!r}; allowed: {', '.join(AXES)}")
        if self.axis == "log" and f[0] <= 0:
            raise FrequencyGridError(
                f"{where}: a target linear over log frequency needs points above 0 Hz"
            )
        h = None if self.harmonic is None else _harmonic(self.harmonic).k
        object.__setattr__(self, "freq", readonly(f))
        object.__setattr__(self, "level_db", readonly(lv))
        object.__setattr__(self, "ref", float(self.ref))
        object.__setattr__(self, "harmonic", h)
        object.__setattr__(self, "source", str(self.source))

    # -- what it is --------------------------------------------------------------------
    @property
    def unit(self) -> str:
        """SI unit of the level (``(m/s)/m`` for a bushing translation's mobility)."""
        return frf_unit(output_kind(self.dof), self.input_kind, self.quantity)

    @property
    def freq_range(self) -> tuple[float, float]:
        """The range judged, Hz: the first and last defining points."""
        return float(self.freq[0]), float(self.freq[-1])

    def describe(self) -> str:
        """One line: DOF, range, unit and source."""
        h = "" if self.harmonic is None else f", harmonic {self.harmonic}"
        return (
            f"target of {self.dof}{h}: {self.freq_range[0]:g}-{self.freq_range[1]:g} Hz, dB re "
            f"{self.ref:g} {self.unit} ({self.quantity}, {self.axis} frequency axis)"
            + (f" from {self.source}" if self.source else "")
        )

    # -- evaluation --------------------------------------------------------------------
    def level_db_at(
        self, freq: ArrayLike, quantity: str | None = None, ref: float | None = None
    ) -> FloatArray:
        """The target in dB on any grid; NaN outside its range (never extrapolated).

        Between two defining points ``(f_a, L_a)``, ``(f_b, L_b)`` the level is
        ``L_a + (L_b - L_a) (x - x_a) / (x_b - x_a)`` with ``x = f`` (``axis="linear"``)
        or ``x = log10 f`` (``axis="log"``). In another quantity it is converted line by
        line by ``20 p log10(2 pi f)`` (thesis table 2.1).

        Parameters
        ----------
        freq : array_like, shape (n_f,)
            Lines in Hz (a grid: increasing).
        quantity : str, optional
            Quantity of the result (default the target's).
        ref : float, optional
            dB reference of the result in SI (default :attr:`ref`).

        Returns
        -------
        ndarray, shape (n_f,)

        Raises
        ------
        FrequencyGridError, QuantityError
        """
        f = check_grid(freq)
        q = self.quantity if quantity is None else quantity
        if q not in QUANTITY_POWER:
            raise QuantityError(f"unknown quantity {q!r}; allowed: {', '.join(QUANTITY_POWER)}")
        lo, hi = self.freq_range
        inside = (f >= lo * (1 - _REL)) & (f <= hi * (1 + _REL))
        out = np.full(f.size, np.nan)
        if inside.any():
            fi = np.clip(f[inside], lo, hi)
            if self.axis == "log":
                out[inside] = np.interp(np.log10(fi), np.log10(self.freq), self.level_db)
            else:
                out[inside] = np.interp(fi, self.freq, self.level_db)
        p = QUANTITY_POWER[q] - QUANTITY_POWER[self.quantity]
        if p:
            w = 2 * np.pi * f
            if p < 0 and np.any(inside & (w == 0)):
                raise QuantityError(
                    f"cannot convert the target of {self.dof} from {self.quantity} to {q} at "
                    "0 Hz (division by j omega)"
                )
            out = out + p * magnitude_db(w, floor=None)  # 20 p log10(omega)
        if ref is not None:
            if not (np.isfinite(ref) and ref > 0):
                raise FBSError(f"the dB reference must be a positive number, got {ref!r}")
            out = out + magnitude_db(self.ref / float(ref))
        return out

    def level_at(self, freq: ArrayLike, quantity: str | None = None) -> FloatArray:
        """The target as a linear level in SI units on any grid; NaN outside its range."""
        out: FloatArray = 10.0 ** (self.level_db_at(freq, quantity, ref=1.0) / 20.0)
        return out

    # -- construction ------------------------------------------------------------------
    @classmethod
    def segments(
        cls,
        dof: str,
        points: Iterable[tuple[float, float]],
        *,
        axis: str = "log",
        quantity: str = "mobility",
        input_kind: str = "road",
        ref: float = 1.0,
        harmonic: int | None = None,
    ) -> Target:
        """A target drawn as straight segments in dB through ``(frequency Hz, level dB)``
        points (dB re ``ref``; linear over ``log10 f`` by default, as on a log axis)."""
        pts = [tuple(p) for p in points]
        if any(len(p) != 2 for p in pts):
            raise FBSError(f"target of {dof}: points must be (frequency, dB) pairs, got {pts}")
        f = np.array([float(p[0]) for p in pts])
        db = np.array([float(p[1]) for p in pts])
        return cls(dof, f, db, quantity, input_kind, ref, axis, harmonic, "segments")

    @classmethod
    def from_levels(
        cls,
        dof: str,
        freq: ArrayLike,
        level: ArrayLike,
        *,
        quantity: str = "mobility",
        input_kind: str = "road",
        axis: str = "linear",
        harmonic: int | None = None,
        source: str = "",
    ) -> Target:
        """A target from linear levels in SI units (positive), dB re 1."""
        lv = np.asarray(level, dtype=float)
        if lv.ndim != 1:
            raise FBSError(f"target of {dof}: levels must be 1-D, got shape {lv.shape}")
        bad = ~(np.isfinite(lv) & (lv > 0))
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise FBSError(
                f"target of {dof}: level {lv[k]!r} at point {k + 1} is not a positive number"
            )
        f = np.asarray(freq, dtype=float)
        return cls(dof, f, magnitude_db(lv), quantity, input_kind, 1.0, axis, harmonic, source)

    @classmethod
    def from_response(
        cls,
        response: FRF,
        dof: str,
        margin_db: float = 0.0,
        harmonic: int | None = None,
        source: str = "",
    ) -> Target:
        """A target ``margin_db`` above the level of a response (e.g. the incumbent
        tire's), defined at its lines (:func:`response_level`)."""
        if dof not in response.outputs:
            raise DOFError(
                f"no output {dof!r} in the response; available: {', '.join(response.outputs)}"
            )
        if not np.isfinite(margin_db):
            raise FBSError(f"the margin must be a finite number of dB, got {margin_db!r}")
        lv = response_level(response)[:, response.outputs.index(dof)]
        return cls(
            dof,
            response.freq,
            magnitude_db(lv) + float(margin_db),
            response.quantity,
            _input_kind_of(response, f"target of {dof}"),
            1.0,
            "linear",
            harmonic,
            source or f"response + {margin_db:g} dB",
        )


@dataclass(frozen=True)
class IncumbentTarget:
    """The target "the incumbent candidate + margin": for every harmonic, the level of
    that candidate's response plus ``margin_db`` (resolved by :func:`fbs_core.verdict.verdict`
    from the responses it is given).

    Parameters
    ----------
    candidate : str
        Name or digest of the incumbent candidate.
    margin_db : float
        dB above the incumbent's level that a candidate may reach (negative: must be
        quieter than the incumbent).
    dofs : tuple of str, optional
        Output DOFs judged this way (default every output of the responses).
    """

    candidate: str
    margin_db: float = 0.0
    dofs: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.candidate, str) or not self.candidate:
            raise FBSError(f"the incumbent must be named by a candidate, got {self.candidate!r}")
        if not (isinstance(self.margin_db, int | float) and np.isfinite(self.margin_db)):
            raise FBSError(f"the margin must be a finite number of dB, got {self.margin_db!r}")
        object.__setattr__(self, "margin_db", float(self.margin_db))
        if self.dofs is not None:
            ds = (self.dofs,) if isinstance(self.dofs, str) else tuple(self.dofs)
            for d in ds:
                parse_label(d)
            object.__setattr__(self, "dofs", ds)

    def resolve(self, response: FRF, harmonic: int) -> tuple[Target, ...]:
        """The targets of one harmonic from the incumbent's response to it."""
        dofs = response.outputs if self.dofs is None else self.dofs
        src = f"incumbent {self.candidate} {self.margin_db:+g} dB"
        return tuple(Target.from_response(response, d, self.margin_db, harmonic, src) for d in dofs)


# -- files --------------------------------------------------------------------------------
def read_targets(
    source: Any,
    *,
    filename: str | None = None,
    dofs: Sequence[str] | None = None,
    nodes: Mapping[Any, Any] | None = None,
    quantity: str | None = None,
    input_kind: str = "road",
    timeout: float | None = None,
) -> tuple[Target, ...]:
    """Read target curves from a target CSV or a UFF 58 file.

    Parameters
    ----------
    source : path or bytes
        A file path, or an upload's bytes (then pass ``filename``).
    filename : str, optional
        The upload's name; its ending selects the format (``.csv .txt``: the target CSV
        layout of this module; ``.uff .unv .uf .58``: UFF dataset 58 records, one per
        output DOF, read by :func:`fbs_core.io.load_frf`).
    dofs : sequence of str, optional
        The output DOFs that exist (default the bushing's six, ``bushing:x`` ...
        ``bushing:rz``); a target for any other is refused, naming it.
    nodes : mapping, optional
        Node names by number or old name, as :func:`fbs_core.io.load_frf`.
    quantity : str, optional
        For a file that does not say its quantity; checked against it otherwise.
    input_kind : str
        The response's input (default ``road``: per metre of road amplitude).
    timeout : float, optional
        Seconds the parser may take (default that of :mod:`fbs_core.io`).

    Returns
    -------
    tuple of Target
        One per DOF column (CSV) or output (UFF), in the file's order.

    Raises
    ------
    DataFormatError
        Unknown ending, unreadable file, NaN or non-positive levels (naming line and
        column), a UFF file with several inputs.
    DOFError
        A DOF that does not exist (naming it and those that do) or given twice.
    QuantityError
        Units that are not understood or are of another kind (naming the unit), no
        quantity.
    FrequencyGridError
        Frequencies that do not increase (naming the line).
    """
    from .chassis import BUSHING
    from .io._sandbox import DEFAULT_TIMEOUT
    from .io.checks import read_source

    src = read_source(source, filename)
    known = tuple(BUSHING if dofs is None else dofs)
    t = DEFAULT_TIMEOUT if timeout is None else float(timeout)
    suffix = src.suffix
    if suffix in CSV_SUFFIXES:
        out = _read_csv(src.raw, src.name, nodes, quantity, input_kind, t)
    elif suffix in UFF_SUFFIXES:
        out = _read_uff(src.raw, src.name, nodes, quantity, input_kind, t)
    else:
        raise DataFormatError(
            f"{src.name!r}: target files are read from {', '.join(CSV_SUFFIXES + UFF_SUFFIXES)}"
            f", not {suffix or 'a file without an ending'}"
        )
    seen: set[tuple[str, int | None]] = set()
    for tg in out:
        if tg.dof not in known:
            raise DOFError(
                f"{src.name!r}: a target for {tg.dof!r}, which is not a response DOF here; "
                f"available: {', '.join(known)}"
            )
        key = (tg.dof, tg.harmonic)
        if key in seen:
            raise DOFError(f"{src.name!r}: two targets for {tg.dof}")
        seen.add(key)
    return out


def _read_csv(
    raw: bytes,
    name: str,
    nodes: Mapping[Any, Any] | None,
    quantity: str | None,
    input_kind: str,
    timeout: float,
) -> tuple[Target, ...]:
    from .io._sandbox import parse_isolated
    from .io.assembly import dof_labels
    from .io.csv import _FREQ, _key_values
    from .io.units import frequency_from_units, reconcile_quantity

    parsed, (a,) = parse_isolated("csv", raw, f"target file {name!r}", timeout=timeout)
    meta = _key_values(parsed["comments"])
    line = int(parsed["header_line"])
    header = [str(h).strip() for h in parsed["header"]]
    m = _FREQ.match(header[0]) if header else None
    if not m:
        raise DataFormatError(
            f"{name!r} line {line}: the first column must be the frequency ('freq' or "
            f"'freq [Hz]'), got {header[0] if header else ''!r}"
        )
    if len(header) < 2:
        raise DataFormatError(f"{name!r} line {line}: no target columns after the frequency")
    if a.shape[0] < 2:
        raise DataFormatError(f"{name!r}: a target needs at least two rows, got {a.shape[0]}")
    bad = ~np.isfinite(a)
    if bad.any():
        r, c = (int(x) for x in np.argwhere(bad)[0])
        raise DataFormatError(
            f"{name!r} line {line + 1 + r}, column {c + 1} ({header[c]!r}): {a[r, c]} is not a "
            "level (NaN or inf); a target needs a value at every point of its range"
        )
    scale = meta.get("scale", "linear")
    scale = {"db": "dB", "linear": "linear"}.get(scale.lower(), scale)
    if scale not in SCALES:
        raise DataFormatError(f"{name!r}: scale {scale!r}; allowed: {', '.join(SCALES)}")
    axis = meta.get("axis", "linear").lower()
    if axis not in AXES:
        raise DataFormatError(f"{name!r}: axis {axis!r}; allowed: {', '.join(AXES)}")
    harmonic = _harmonic_meta(meta.get("harmonic"), name)
    label = meta.get("units") or None
    units = parse_units(label)  # raises QuantityError for force per motion
    if label is not None and (units is None or units.quantity is None):
        raise QuantityError(
            f"{name!r}: the units {label!r} are not understood as a level of a receptance, "
            "mobility or accelerance per unit input (known: m mm cm um in ft / N kN mN lbf / "
            "s ms / rad deg / g, e.g. '(m/s)/m', '(mm/s)/mm', '(m/s^2)/m')"
        )
    q = reconcile_quantity(meta.get("quantity") or None, units, quantity, repr(name), label)
    ref_text = meta.get("ref", "1")
    try:
        ref_file = float(ref_text)
    except ValueError:
        raise DataFormatError(f"{name!r}: ref {ref_text!r} is not a number") from None
    if not (np.isfinite(ref_file) and ref_file > 0):
        raise DataFormatError(f"{name!r}: ref must be a positive number, got {ref_text!r}")
    freq = frequency_from_units(a[:, 0], m.group(2) or meta.get("freq_unit"), repr(name))
    try:
        check_grid(freq)
    except FrequencyGridError as e:
        raise FrequencyGridError(f"{name!r}: {e}") from None
    try:
        labels, _ = dof_labels(header[1:], "output", nodes)
    except DOFError as e:
        raise DOFError(f"{name!r} line {line}: {e}") from None
    out = []
    for c, dof in enumerate(labels, start=1):
        factor = _si_factor(units, dof, input_kind, q, name)
        v = a[:, c]
        if scale == "dB":
            db, ref = v, ref_file * factor
        else:
            nonpos = np.flatnonzero(v <= 0)
            if nonpos.size:
                r = int(nonpos[0])
                raise DataFormatError(
                    f"{name!r} line {line + 1 + r}, column {c + 1} ({header[c]!r}): level "
                    f"{v[r]:g} is not positive (a linear level; write '# scale: dB' for dB)"
                )
            db, ref = magnitude_db(v * factor), 1.0
        out.append(Target(dof, freq, db, q, input_kind, ref, axis, harmonic, name))
    return tuple(out)


def _harmonic_meta(text: str | None, name: str) -> int | None:
    from .harmonics import harmonic as _harmonic

    if text is None or not text.strip():
        return None
    try:
        return _harmonic(int(text)).k
    except (ValueError, FBSError):
        raise DataFormatError(
            f"{name!r}: harmonic {text!r}; allowed: 1, 2, 3, 4, 5, 6, 7 (or no harmonic line: "
            "every case)"
        ) from None


def _si_factor(units: Any, dof: str, input_kind: str, quantity: str, name: str) -> float:
    """SI value of one file unit of the level of ``dof`` (1 without a units label)."""
    if units is None:
        return 1.0
    ok = output_kind(dof)
    if units.kinds is not None:
        if units.kinds[1] != input_kind:
            per = {"generalised": "no input (a response alone)"}.get(
                units.kinds[1], f"a {units.kinds[1]}"
            )
            raise QuantityError(
                f"{name!r}: the units {units.label!r} are a level per {per}; the response is "
                f"per {input_kind} ({frf_unit(ok, input_kind, quantity)} for {dof})"
            )
        if units.kinds[0] != ok and ok != "generalised":
            raise QuantityError(
                f"{name!r}: the units {units.label!r} are those of a {units.kinds[0]}, but "
                f"{dof} is a {ok} ({frf_unit(ok, input_kind, quantity)})"
            )
    return float(units.factor(ok, input_kind, quantity))


def _read_uff(
    raw: bytes,
    name: str,
    nodes: Mapping[Any, Any] | None,
    quantity: str | None,
    input_kind: str,
    timeout: float,
) -> tuple[Target, ...]:
    from .io import load_frf

    frf = load_frf(raw, filename=name, nodes=nodes, quantity=quantity, timeout=timeout).frf
    assert frf is not None  # load_frf returns an FRF
    if len(frf.inputs) != 1:
        raise DataFormatError(
            f"{name!r}: a target file holds records of one input (the response's load), "
            f"this one has {len(frf.inputs)}: {', '.join(frf.inputs)}"
        )
    kind = frf.input_kinds[0]
    if kind != input_kind:
        raise QuantityError(
            f"{name!r}: the records are per {kind} (input {frf.inputs[0]!r}, "
            f"{frf.unit()}); the response is per {input_kind} (name the road input's node "
            "'patch' with nodes=... for a road)"
        )
    lv = response_level(frf)
    out = []
    for o, dof in enumerate(frf.outputs):
        zero = np.flatnonzero(lv[:, o] <= 0)
        if zero.size:
            raise DataFormatError(
                f"{name!r}: the target of {dof} is 0 at {frf.freq[zero[0]]:g} Hz; a target "
                "level must be positive"
            )
        out.append(Target(dof, frf.freq, magnitude_db(lv[:, o]), frf.quantity, kind, source=name))
    return tuple(out)
