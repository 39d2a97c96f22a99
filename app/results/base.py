"""The snapshot of a session's state and what a published result holds.

:class:`Snapshot` is the one object every result is made of: the session's settings as
plain values, read at one moment under the session's lock, and the published inputs other
results are made of (the scatter band, the pins). :class:`Result` is what a view shows, an
export writes and the report reads: the data and their description from one snapshot.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Self

import numpy as np

from .. import compute
from ..state import SCHEMA

__all__ = [
    "FIELDS",
    "Band",
    "BandStatus",
    "Result",
    "Snapshot",
    "csv_name",
    "duration_text",
    "made_of_same",
    "progress_status",
]

#: Field of a snapshot -> (group of the session's state, parameter of that group).
FIELDS: dict[str, tuple[str, str]] = SCHEMA.fields
#: Fields of a snapshot that are published results, not settings.
PUBLISHED = ("band", "pins")
#: Fields that act only in vehicle scope (a corner's results are not made of them).
VEHICLE_FIELDS = SCHEMA.vehicle_fields


@dataclass(frozen=True)
class _SnapshotBase:
    """A session's state at one moment: its settings (plain values) and the published
    inputs other results are made of. Equal snapshots make equal results.

    Its settings are one keyword field per setting of the session's state
    (:data:`app.state.SCHEMA`, e.g. ``harmonic``, ``n_modes``, ``dof``), each held as a
    plain value of its declared type; ``models`` and ``review`` are the session's uploads
    and review (hashed by their digests)."""

    band: Any = None  # the published Band (compared by identity)
    pins: tuple = ()  # the published pins (app.results.pins.Pin, by identity)
    #: The settings schema the fields were made from (set on the made class).
    schema: ClassVar[Any] = None

    if TYPE_CHECKING:  # the settings' fields are made from the schema

        def __init__(self, **fields: Any) -> None: ...

        def __getattr__(self, name: str) -> Any: ...

    @classmethod
    def of(cls, state: Any, band: Any = None, pins: tuple = ()) -> Self:
        """The snapshot of a ``DashboardState`` (and the published band and pins)."""
        kw = {
            s.field: s.convert(getattr(getattr(state, s.group), s.name))
            for s in cls.schema.settings
            if s.field
        }
        return cls(**kw, band=band, pins=tuple(pins))

    def replace(self, **changes: Any) -> Self:
        return dataclasses.replace(self, **changes)

    def settings(self) -> Self:
        """This snapshot without the published inputs (what a band or a pin keeps)."""
        return dataclasses.replace(self, band=None, pins=())

    @property
    def vehicle(self) -> bool:
        """Whether the snapshot is of the whole car (vehicle scope)."""
        return self.scope == "vehicle"

    @property
    def output(self) -> str:
        """The response DOF's label: ``bushing:z`` (corner), ``<point>:z`` (vehicle)."""
        return f"{self.point}:{self.dof}" if self.vehicle else f"bushing:{self.dof}"

    @property
    def road(self) -> str | float:
        """The track relation as the core takes it (a string, or the coherency)."""
        return self.coherence if self.tracks == "coherence" else self.tracks

    def vehicle_key(self) -> tuple | None:
        """The vehicle fields (None in corner scope: a corner's results ignore them)."""
        if not self.vehicle:
            return None
        coherence = self.coherence if self.tracks == "coherence" else None
        return (self.wheels, self.tracks, coherence, self.point)

    @property
    def map_dof(self) -> str | None:
        """The DOF the error map and the suggestion judge (None: max over the 6 DOFs)."""
        return self.dof if self.map_mode == "selected DOF" else None

    def band_key(self) -> tuple:
        """The settings that define this snapshot's scatter band (its cache key)."""
        return compute.band_key(
            self.harmonic,
            self.n_modes,
            self.coupling,
            self.noise,
            self.target,
            self.frequency_dependent,
            self.rounds,
            self.seed,
            self.models,
            self.vehicle_band_key(),
        )

    def vehicle_band_key(self) -> tuple | None:
        """What a vehicle band adds to a corner's key (None in corner scope): its road and
        its response point (the band holds the point's six DOFs)."""
        v = self.vehicle_key()
        return None if v is None else (v[0], self.road, self.point)

    def current_band(self) -> Band | None:
        """The published band if it was computed for this snapshot's settings."""
        b = self.band
        return b if b is not None and b.settings.band_key() == self.band_key() else None


if TYPE_CHECKING:
    Snapshot = _SnapshotBase
else:
    Snapshot = SCHEMA.snapshot_class(_SnapshotBase)


@dataclass(frozen=True, eq=False)
class Result:
    """What one view shows: data and their description, from one snapshot.

    Attributes
    ----------
    columns : mapping of str to 1-D ndarray
        The data as exported (CSV columns, equal length).
    meta : mapping of str to object
        The CSV header: the settings these data were computed for.
    filename : str
        The CSV file name.
    caption : str
        One line for the page (``**bold**`` and ``&middot;`` allowed; escaped as text).
    draw : mapping
        Anything else the view needs to draw these data (curves in dB, axis labels,
        marker positions).
    core : mapping
        The core library's result objects the columns come from (what the report reads).
    snapshot : Snapshot or None
        The snapshot the result describes (its title block and file names).
    key : tuple
        The values of the snapshot's fields the result was made of (set by the store).
    """

    columns: Mapping[str, np.ndarray] = field(default_factory=dict)
    meta: Mapping[str, Any] = field(default_factory=dict)
    filename: str = "data.csv"
    caption: str = ""
    draw: Mapping[str, Any] = field(default_factory=dict)
    core: Mapping[str, Any] = field(default_factory=dict)
    snapshot: Snapshot | None = None
    key: tuple = ()


def made_of_same(a: Result | None, b: Result | None, fields: tuple[str, ...]) -> bool:
    """Whether results ``a`` and ``b`` describe snapshots with the same values of
    ``fields`` (a view that draws one result over another checks that they belong
    together: their keys have the fields of their own rows, in their own order)."""
    if a is None or b is None or a.snapshot is None or b.snapshot is None:
        return False
    return all(getattr(a.snapshot, f) == getattr(b.snapshot, f) for f in fields)


def csv_name(s: Snapshot, *parts: object) -> str:
    """``part_part_..._upload.csv``: ``_upload`` when uploaded models are in use (two files of
    other data never share a name)."""
    name = "_".join(str(p) for p in parts if p != "")
    return f"{name}{'' if s.models.is_reference else '_upload'}.csv"


@dataclass(frozen=True, eq=False)
class Band:
    """A finished scatter band and the settings it was computed for."""

    result: Any  # fbs_core.ScatterBand
    settings: Snapshot
    seconds: float


@dataclass(frozen=True)
class BandStatus:
    """Whether a band is being computed, and the line the page shows about it.

    During a computation ``done`` of ``total`` frequency lines are done (0 of 0 before the
    kernel's first report) and ``seconds_left`` estimates the rest (None: not yet known).
    """

    busy: bool = False
    text: str = ""
    done: int = 0
    total: int = 0
    seconds_left: float | None = None

    @property
    def percent(self) -> int:
        return int(100 * self.done / self.total) if self.total else 0


def duration_text(seconds: float) -> str:
    """``"about 1 min 10 s"``, ``"about 8 s"``, ``"under a second"``."""
    if seconds < 1:
        return "under a second"
    s = int(round(seconds))
    return f"about {s // 60} min {s % 60} s" if s >= 60 else f"about {s} s"


def progress_status(rounds: int, done: int, total: int, seconds_left) -> BandStatus:
    """The status of a running band: done/total lines and the time left."""
    text = f"Computing {rounds:,} rounds ..."
    if total:
        text = (
            f"Computing {rounds:,} rounds: {int(100 * done / total)} % "
            f"({done} of {total} frequency lines)"
        )
        if seconds_left is not None:
            text += f", {duration_text(seconds_left)} left"
    return BandStatus(True, text, done, total, seconds_left)
