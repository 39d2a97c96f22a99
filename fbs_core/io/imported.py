"""What an import returns: the FRF or tire model, its summary, notes and provenance.

:func:`frf_import` and :func:`tire_import` are the last step of
:func:`fbs_core.io.load_frf` and :func:`fbs_core.io.import_tire_model`, after the
format's reader (:mod:`fbs_core.io.formats`).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..frf import FRF
from .checks import describe, quantity_notes, require_dofs

if TYPE_CHECKING:
    from ..tire.model import TireModel

__all__ = ["ImportResult", "frf_import", "tire_import", "describe_tire"]


@dataclass(frozen=True)
class ImportResult:
    """What an importer read.

    Attributes
    ----------
    frf : FRF or None
        The FRF (None for a tire model).
    model : TireModel or None
        The tire model (None for an FRF).
    summary : str
        Short human-readable description: quantity, DOFs, frequency range,
        operating points; with the notes appended.
    notes : tuple of str
        Conversions applied, records skipped, plausibility warnings.
    metadata : dict
        Provenance stored in the file.
    source : str
        File name; ``format`` the format it was read as.
    """

    frf: FRF | None
    summary: str
    notes: tuple[str, ...] = ()
    metadata: dict[str, Any] = field(default_factory=dict)
    source: str = ""
    format: str = ""
    model: object | None = None

    def __iter__(self) -> Iterator[Any]:
        """Unpack as ``frf, summary = load_frf(...)``."""
        return iter((self.frf if self.model is None else self.model, self.summary))


def frf_import(
    frf: FRF,
    notes: list[str],
    meta: dict[str, Any],
    name: str,
    fmt: str,
    require_outputs: Iterable[str] = (),
    require_inputs: Iterable[str] = (),
) -> ImportResult:
    """The result of an FRF import: the DOFs required checked, the plausibility notes of
    the quantity added (:func:`~.checks.quantity_notes`), the summary written.

    Raises
    ------
    DOFError
        Listing the required outputs and inputs the FRF lacks.
    """
    require_dofs(frf, require_outputs, require_inputs, what=f"{name!r}")
    notes = list(notes) + quantity_notes(frf)
    text = f"{name} ({fmt}): " + describe(frf)
    if notes:
        text += "\nnotes: " + "; ".join(notes)
    return ImportResult(frf, text, tuple(notes), dict(meta), name, fmt)


def tire_import(model: TireModel, name: str, label: str) -> ImportResult:
    """The result of a tire-model import, with the summary of :func:`describe_tire`."""
    text = f"{name} ({label}): " + describe_tire(model)
    return ImportResult(None, text, (), dict(model.meta), name, label, model)


def describe_tire(model: TireModel) -> str:
    """Short summary of a tire model: operating points, modes, frequencies, wavelengths."""
    f = np.abs(np.asarray(model.poles).imag) / (2 * np.pi)
    return "\n".join(
        [
            f"modal tire model, {model.n_modes} complex modes ({model.n_modes // 2} pairs), "
            f"eigenfrequencies {f.min():.1f}-{f.max():.1f} Hz",
            "operating points: " + ", ".join(f"{v:g}" for v in model.speeds) + " km/h",
            "hub DOFs: " + ", ".join(model.hub_dofs),
            "patch participation for wavelengths: "
            + ", ".join(f"{w:g}" for w in model.wavelengths)
            + " m",
        ]
    )
