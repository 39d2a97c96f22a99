"""Input checks shared by the importers: size, magic bytes, labels, DOFs, grids.

Which format a file is (its ending, checked against what :func:`sniff` finds): see
:mod:`fbs_core.io.formats`.

Units and quantities are checked in :mod:`fbs_core.io.units` (re-exported here).

Every check raises a subclass of :class:`~fbs_core.errors.FBSError` whose
message names the offending thing and what is allowed. Nothing is converted or
interpolated silently: unit conversions that are applied are reported in the
import notes, and frequency grids are only unified through the explicit
:func:`common_grid` (which calls :meth:`fbs_core.FRF.interpolate`).
"""

from __future__ import annotations

import os
import re
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ..dofs import DIRECTIONS, parse_label
from ..errors import (
    DataFormatError,
    DOFError,
    SingularInterfaceError,
)
from ..frf import FRF
from .units import (  # noqa: F401  (re-exported: the importers take them from here)
    Units,
    check_quantity_arg,
    frequency_from_units,
    kinds_text,
    low_frequency_slope,
    parse_kinds,
    parse_units,
    quantity_notes,
    reconcile_quantity,
    si_factors,
    units_line,
    units_note,
)

if TYPE_CHECKING:
    from ..coupling import Interface

__all__ = [
    "DEFAULT_MAX_BYTES",
    "Source",
    "read_source",
    "sniff",
    "normalize_label",
    "rename_node",
    "Units",
    "parse_units",
    "si_factors",
    "check_finite",
    "require_dofs",
    "common_grid",
    "low_frequency_slope",
    "quantity_notes",
    "interface_check",
    "prepare_chassis",
    "describe",
    # re-exported from .units for the importers
    "check_quantity_arg",
    "frequency_from_units",
    "kinds_text",
    "parse_kinds",
    "reconcile_quantity",
    "units_line",
    "units_note",
]

#: Default upper limit of a file's size in bytes (100 MiB).
DEFAULT_MAX_BYTES = 100 * 1024 * 1024


@dataclass(frozen=True)
class Source:
    """File content and the name used in messages."""

    raw: bytes
    name: str

    @property
    def suffix(self) -> str:
        return Path(self.name).suffix.lower()


def read_source(
    source: str | os.PathLike[str] | bytes | bytearray | memoryview,
    filename: str | None = None,
    max_bytes: int = DEFAULT_MAX_BYTES,
) -> Source:
    """Read a path, or take bytes (an upload) with the file name they came with.

    Parameters
    ----------
    source : str, os.PathLike, bytes, bytearray or memoryview
        A path to read, or the file content.
    filename : str, optional
        Name of the uploaded file (for bytes; used for the format and messages).
    max_bytes : int
        Largest accepted size; the file is not read when it is larger.

    Raises
    ------
    DataFormatError
        For a file that is too large, empty, missing or of an unsupported type.
    """
    if max_bytes <= 0:
        raise DataFormatError(f"max_bytes must be positive, got {max_bytes}")
    if isinstance(source, bytes | bytearray | memoryview):
        raw = bytes(source)
        name = filename or "<uploaded bytes>"
    elif isinstance(source, str | os.PathLike):
        path = Path(source)
        name = filename or path.name
        try:
            size = path.stat().st_size
            if size > max_bytes:
                raise DataFormatError(_too_large(name, size, max_bytes))
            if not path.is_file():
                raise DataFormatError(f"{name!r} is not a regular file")
            raw = path.read_bytes()
        except OSError as e:
            raise DataFormatError(f"cannot read {str(path)!r}: {e.strerror or e}") from None
    else:
        raise DataFormatError(f"expected a path or the file's bytes, got {type(source).__name__}")
    if len(raw) > max_bytes:
        raise DataFormatError(_too_large(name, len(raw), max_bytes))
    if not raw:
        raise DataFormatError(f"file {name!r} is empty")
    return Source(raw, name)


def _too_large(name: str, size: int, max_bytes: int) -> str:
    return (
        f"file {name!r} is {size / 2**20:.1f} MiB, larger than the limit of "
        f"{max_bytes / 2**20:.1f} MiB; pass a larger max_bytes to accept it"
    )


_HDF5_SIG = b"\x89HDF\r\n\x1a\n"
_MAGIC = [
    (b"PK\x03\x04", "a ZIP archive (or an Office document)"),
    (b"\x1f\x8b", "a gzip archive"),
    (b"%PDF", "a PDF document"),
    (b"\x89PNG", "a PNG image"),
    (b"\xff\xd8\xff", "a JPEG image"),
    (b"\x7fELF", "an executable"),
    (b"MZ", "a Windows executable"),
    (b"\x80\x02", "a Python pickle"),
    (b"\x80\x03", "a Python pickle"),
    (b"\x80\x04", "a Python pickle"),
    (b"\x80\x05", "a Python pickle"),
    (b"\x93NUMPY", "a NumPy .npy file"),
    (b"\xd0\xcf\x11\xe0", "an old Office document"),
]


def sniff(raw: bytes) -> str:
    """What the content is, judged from its first bytes.

    Returns one of ``"mat5"``, ``"mat73"``, ``"hdf5"``, ``"uff"``, ``"text"`` or a
    description such as ``"a ZIP archive"`` / ``"binary data"``.
    """
    head = raw[:1024]
    if head.startswith(b"MATLAB 7.3 MAT-file") and raw[512:520] == _HDF5_SIG:
        return "mat73"
    if head.startswith(b"MATLAB 5.0 MAT-file") or (
        len(raw) >= 128
        and raw[126:128] in (b"IM", b"MI")
        and raw[:116].isascii()
        and head[:6] == b"MATLAB"
    ):
        return "mat5"
    for off in (0, 512, 1024, 2048):
        if raw[off : off + 8] == _HDF5_SIG:
            return "hdf5"
    for sig, what in _MAGIC:
        if head.startswith(sig):
            return what
    if re.match(rb"^\s*-1[ \t]*\r?\n\s*\d+", head):  # UFF, also binary 58b
        return "uff"
    if b"\x00" in head:
        return "binary data"
    try:
        text = head.decode("utf-8")
    except UnicodeDecodeError as e:
        if e.start < len(head) - 4:  # not a character cut at the end of the sample
            return "binary data"
        text = head[: e.start].decode("utf-8")
    first = next((ln for ln in text.splitlines() if ln.strip()), "")
    if first.strip() == "-1":
        return "uff"
    return "text"


# -- DOF labels ------------------------------------------------------------------------
_DIR_ALIASES = {d: d for d in DIRECTIONS}
_DIR_ALIASES.update({"tx": "x", "ty": "y", "tz": "z"})


def normalize_label(text: str, what: str = "DOF") -> tuple[str, int]:
    """Normalise a DOF label from a file to ``"node:dir"`` and a sign.

    Accepts directions in any case, ``tx``/``ty``/``tz`` for translations and a
    leading ``+`` or ``-`` (``"hub:-z"`` is ``"hub:z"`` with sign -1).

    Raises
    ------
    DOFError
        For an unknown direction or a malformed node name.
    """
    if not isinstance(text, str):
        raise DOFError(f"{what} label must be text, got {text!r}")
    s = text.strip()
    node, sep, d = s.partition(":")
    sign = 1
    if sep:
        d = d.strip().lower()
        if d[:1] in "+-" and d:
            sign = -1 if d[0] == "-" else 1
            d = d[1:]
        if d not in _DIR_ALIASES:
            raise DOFError(
                f"unknown direction {d!r} in {what} label {text!r}; allowed: "
                f"{', '.join(DIRECTIONS)} (any case, optional sign +/-)"
            )
        s = f"{node.strip()}:{_DIR_ALIASES[d]}"
    parse_label(s)
    return s, sign


def rename_node(label: str, nodes: Mapping[Any, Any] | None) -> str:
    """Apply a user node map (e.g. ``{1: "spindle", "101": "bushing"}``) to a label."""
    if not nodes:
        return label
    node, sep, d = label.partition(":")
    for key in (node, int(node) if node.isdigit() else None):
        if key is not None and key in nodes:
            new = str(nodes[key]) + sep + d
            parse_label(new)
            return new
    return label


def missing_pairs(
    outputs: Collection[str], inputs: Collection[str], present: Collection[tuple[str, str]]
) -> tuple[int, list[tuple[str, str]]]:
    """How many output/input pairs of the full matrix are not in ``present`` (a set or
    dict of pairs), and the first eight of them.

    Linear in the number of pairs present: a file naming many outputs and inputs but
    few pairs is refused without enumerating the whole matrix.
    """
    n = len(outputs) * len(inputs) - len(present)
    first: list[tuple[str, str]] = []
    if n > 0:
        for o in outputs:
            for i in inputs:
                if (o, i) not in present:
                    first.append((o, i))
                    if len(first) == 8:
                        return n, first
    return n, first


# -- values ----------------------------------------------------------------------------
def check_finite(a: np.ndarray, what: str) -> np.ndarray:
    """Raise DataFormatError naming the first non-finite entry of ``a``."""
    a = np.asarray(a)
    if a.dtype.kind not in "biufc":
        raise DataFormatError(f"{what} must be numeric, got {a.dtype}")
    bad = ~np.isfinite(a)
    if bad.any():
        pos = tuple(int(i) for i in np.argwhere(bad)[0])
        raise DataFormatError(
            f"{what} contains {int(bad.sum())} non-finite value(s) (NaN or inf), "
            f"first at index {pos}"
        )
    return a


def require_dofs(
    frf: FRF, outputs: Iterable[str] = (), inputs: Iterable[str] = (), what: str = "FRF"
) -> None:
    """Raise DOFError listing every required output/input label the FRF lacks."""
    miss_o = [o for o in outputs if o not in frf.outputs]
    miss_i = [i for i in inputs if i not in frf.inputs]
    if miss_o or miss_i:
        parts = []
        if miss_o:
            parts.append(f"outputs {', '.join(miss_o)} (has {', '.join(frf.outputs)})")
        if miss_i:
            parts.append(f"inputs {', '.join(miss_i)} (has {', '.join(frf.inputs)})")
        raise DOFError(f"{what} lacks " + "; ".join(parts))


def common_grid(frfs: Sequence[FRF], freq: ArrayLike | None = None) -> list[FRF]:
    """Put FRFs on one grid, explicitly.

    With ``freq=None`` the FRFs must already share their grid (else
    FrequencyGridError naming both grids). With ``freq`` given, every FRF is
    interpolated onto it with :meth:`fbs_core.FRF.interpolate` (linear in real and
    imaginary part, no extrapolation).
    """
    frfs = list(frfs)
    if freq is None:
        for k, f in enumerate(frfs[1:], start=1):
            frfs[0].require_grid(f, what=f"FRF 0 and FRF {k}")
        return frfs
    return [f.interpolate(freq) for f in frfs]


def interface_check(
    a: FRF, b: FRF, interface: Interface | None = None, max_cond: float = 1e8
) -> np.ndarray:
    """Condition of the interface matrix ``Y_jj^A + Y_jj^B`` (eq. 2.44) at every line.

    Calls :func:`fbs_core.coupling.interface_condition`.

    Raises
    ------
    SingularInterfaceError
        When the matrix is singular or its condition number exceeds ``max_cond`` at
        some line, naming the worst line.
    """
    from ..coupling import interface_condition

    cond = np.asarray(interface_condition(a, b, interface), dtype=float)
    bad = ~np.isfinite(cond) | (cond > max_cond)
    if bad.any():
        k = int(np.argmax(np.where(np.isfinite(cond), cond, np.inf)))
        raise SingularInterfaceError(
            f"the interface matrix Y_jj^A + Y_jj^B is singular or ill-conditioned at "
            f"{int(bad.sum())} of {cond.size} lines (worst: condition {cond[k]:.3g} at "
            f"{a.freq[k]:g} Hz; limit {max_cond:.3g}); check the interface DOFs and units"
        )
    return cond


def prepare_chassis(
    frf: FRF,
    spindle: str = "spindle",
    bushing: str = "bushing",
    directions: Sequence[str] = DIRECTIONS,
) -> tuple[FRF, list[str]]:
    """Make a user's chassis FRF fit the contract of ``ChassisModel.mobility``.

    Parameters
    ----------
    frf : FRF
        Imported chassis FRF.
    spindle, bushing : str
        Node names in ``frf`` of the spindle (the coupling node) and the bushing
        (the response node); they are renamed to ``"spindle"`` and ``"bushing"``.
    directions : sequence of str
        Coupled spindle directions (default all six).

    Returns
    -------
    frf : FRF
        Mobility with outputs ``spindle:*`` then the ``bushing:*`` present, inputs
        ``spindle:*`` (thesis eq. 4.1 needs ``Y_jj^E`` and ``Y_ej^E``).
    notes : list of str
        Conversions applied.

    Raises
    ------
    DOFError
        Listing the missing spindle or bushing DOFs.
    QuantityError
        When the FRF cannot be converted to mobility (0 Hz line of an accelerance).
    """
    notes: list[str] = []
    ren = {spindle: "spindle", bushing: "bushing"}
    if spindle == bushing:
        raise DOFError(f"the spindle and the bushing must be different nodes, got {spindle!r}")
    if any(k != v for k, v in ren.items()):
        for name in ren:
            if name not in {parse_label(x)[0] for x in frf.outputs + frf.inputs}:
                nodes = sorted({parse_label(x)[0] for x in frf.outputs + frf.inputs})
                raise DOFError(f"no node {name!r} in the FRF; nodes: {', '.join(nodes)}")
        taken = {"spindle", "bushing"} - {spindle, bushing}
        clash = [x for x in frf.outputs + frf.inputs if parse_label(x)[0] in taken]
        if clash:
            raise DOFError(
                f"cannot rename: labels {', '.join(clash[:4])} already use "
                f"{'/'.join(sorted(taken))}"
            )
        frf = frf.replace(
            outputs=[rename_node(x, ren) for x in frf.outputs],
            inputs=[rename_node(x, ren) for x in frf.inputs],
        )
        notes.append(f"nodes {spindle!r} -> 'spindle', {bushing!r} -> 'bushing'")
    sp = [f"spindle:{d}" for d in directions]
    require_dofs(frf, outputs=sp, inputs=sp, what="the chassis FRF")
    bush = [f"bushing:{d}" for d in DIRECTIONS if f"bushing:{d}" in frf.outputs]
    if not bush:
        raise DOFError(
            "the chassis FRF has no bushing output (bushing:x ... bushing:rz); outputs: "
            + ", ".join(frf.outputs)
        )
    frf = frf.sel(outputs=sp + bush, inputs=sp)
    if frf.quantity != "mobility":
        notes.append(f"converted from {frf.quantity} to mobility (thesis table 2.1)")
        frf = frf.to("mobility")
    return frf, notes


def describe(frf: FRF, operating_points: Sequence[float] | None = None) -> str:
    """A short human-readable summary: quantity, DOFs, frequency range."""
    f = frf.freq
    d = np.diff(f)
    step = f", step {d[0]:g} Hz" if d.size and np.allclose(d, d[0], rtol=1e-6) else ""
    nodes: dict[str, list[str]] = {}
    for lab in dict.fromkeys(frf.outputs + frf.inputs):
        node, dr = parse_label(lab)
        nodes.setdefault(node, []).append(dr or "(generalised)")
    lines = [
        f"{frf.quantity} FRF, {frf.shape[1]} outputs x {frf.shape[2]} inputs, "
        f"{f.size} lines from {f[0]:g} to {f[-1]:g} Hz{step}",
        "outputs: " + ", ".join(frf.outputs),
        "inputs: " + ", ".join(frf.inputs),
        "units (SI): " + frf.unit(),
        "nodes: " + "; ".join(f"{n} ({', '.join(v)})" for n, v in nodes.items()),
    ]
    if operating_points is not None:
        lines.append("operating points: " + ", ".join(f"{v:g}" for v in operating_points) + " km/h")
    return "\n".join(lines)


# -- checks of a model pair for the whole study (the dashboard's upload checks) ----------------
#: Smallest number of complex tire modes accepted (a truncation map needs N = 10 < total).
MIN_TIRE_MODES = 20


def check_tire(tire: Any) -> list[str]:
    """Refuse a tire model that cannot run every study of the thesis; return notes.

    The model must have the hub DOFs ``hub:x`` ... ``hub:rz``, at least
    :data:`MIN_TIRE_MODES` complex modes, the patch participation and operating points of
    all seven harmonic cases (thesis fig. 4.4) and the speeds of the eigenfrequency curves
    (fig. 5.8, :data:`fbs_core.vocabulary.EIGEN_SPEEDS`).

    Parameters
    ----------
    tire : TireModel
        A modal tire model (e.g. from :func:`fbs_core.io.import_tire_model`).

    Returns
    -------
    list of str
        Notes for the user (fewer than 400 modes).

    Raises
    ------
    FBSError
        Naming the missing hub DOFs, modes, wavelengths or operating points and the
        harmonic or speed that needs them.
    """
    from ..errors import FBSError
    from ..harmonics import harmonic
    from ..vocabulary import EIGEN_SPEEDS, HARMONIC_CASES

    hub = tuple(f"hub:{d}" for d in DIRECTIONS)
    if tuple(tire.hub_dofs) != hub:
        raise FBSError(
            f"the tire's hub DOFs must be {', '.join(hub)}, got {', '.join(tire.hub_dofs)}"
        )
    if tire.n_modes < MIN_TIRE_MODES:
        raise FBSError(
            f"the tire model has {tire.n_modes} complex modes; the truncation study "
            f"needs at least {MIN_TIRE_MODES}"
        )
    for k in HARMONIC_CASES:
        h = harmonic(k)
        f = h.frequencies()
        try:
            tire.truncations(f[[0, -1]], h, [tire.n_modes])
        except FBSError as e:
            raise type(e)(f"harmonic {k}: {e}") from None
    for v in EIGEN_SPEEDS:
        try:
            tire.eigenfrequencies(v)
        except FBSError as e:
            raise type(e)(f"eigenfrequency view (fig. 5.8, {v:g} km/h): {e}") from None
    notes = []
    if tire.n_modes < 400:
        notes.append(f"{tire.n_modes} complex modes: a chosen N above that uses all modes")
    return notes


def check_pair(tire: Any = None, chassis: Any = None, max_cond: float = 1e8) -> None:
    """The pair couples on every harmonic's grid: the chassis has (or may interpolate)
    the lines and the interface ``Y_jj^A + Y_jj^E`` (eq. 2.44) is well conditioned.

    Parameters
    ----------
    tire : TireModel, optional
        Default :func:`fbs_core.reference_tire`.
    chassis : ChassisModel or FRFChassis, optional
        Default :func:`fbs_core.reference_chassis`.
    max_cond : float
        Largest condition number accepted (:func:`interface_check`).

    Raises
    ------
    FrequencyGridError, SingularInterfaceError
        Naming the harmonic and its frequency range.
    """
    from ..chassis import SPINDLE, reference_chassis
    from ..errors import FBSError
    from ..harmonics import harmonic
    from ..vocabulary import HARMONIC_CASES

    if tire is None:
        from ..tire import reference_tire

        tire = reference_tire()
    chassis = reference_chassis() if chassis is None else chassis
    hub = tuple(f"hub:{d}" for d in DIRECTIONS)
    pairs = list(zip(hub, SPINDLE, strict=True))
    for k in HARMONIC_CASES:
        h = harmonic(k)
        f = h.frequencies()
        try:
            Yjj = tire.truncations(f, h, [tire.n_modes])[0][0]
            YA = FRF(f, Yjj, hub, hub, "mobility")
            YE = chassis.mobility(f, outputs=SPINDLE, inputs=SPINDLE)
            interface_check(YA, YE, interface=pairs, max_cond=max_cond)
        except FBSError as e:
            raise type(e)(f"harmonic {k} ({f[0]:g}-{f[-1]:g} Hz): {e}") from None
