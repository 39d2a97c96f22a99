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
from typing import Any

import numpy as np

from .. import compute

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
FIELDS: dict[str, tuple[str, str]] = {
    "harmonic": ("case", "harmonic"),
    "n_modes": ("case", "n_modes"),
    "dof": ("case", "dof"),
    "coupling": ("case", "coupling"),
    "residual": ("case", "residual"),
    "show_uncoupled": ("case", "show_uncoupled"),
    "spindle_input": ("case", "spindle_input"),
    "models": ("case", "models"),
    "review": ("case", "review"),
    "scope": ("case", "scope"),
    "wheels": ("case", "wheels"),
    "tracks": ("case", "tracks"),
    "coherence": ("case", "coherence"),
    "point": ("case", "point"),
    "noise": ("noise", "noise"),
    "target": ("noise", "target"),
    "frequency_dependent": ("noise", "frequency_dependent"),
    "rounds": ("noise", "rounds"),
    "seed": ("noise", "seed"),
    "single_round": ("noise", "single_round"),
    "percentile": ("noise", "percentile"),
    "first_order": ("noise", "first_order"),
    "threshold": ("truncation", "threshold"),
    "f_max": ("truncation", "f_max"),
    "map_mode": ("truncation", "map_mode"),
    "tab": ("analysis", "tab"),
    "frf": ("analysis", "frf"),
    "phase_mode": ("analysis", "phase_mode"),
    "log_freq": ("analysis", "log_freq"),
    "cursor1": ("analysis", "cursor1"),
    "cursor2": ("analysis", "cursor2"),
    "picked_speed": ("analysis", "picked_speed"),
    "picked_freq": ("analysis", "picked_freq"),
    "contrib_mode": ("analysis", "contrib_mode"),
    "pin_text": ("analysis", "pins"),
    "compare_to": ("analysis", "compare_to"),
    "overlay": ("plot", "overlay"),
    "level_scale": ("plot", "level_scale"),
    "mcursor1": ("plot", "cursor1"),
    "mcursor2": ("plot", "cursor2"),
    "snap": ("plot", "snap"),
    "mode_pick": ("analysis", "mode_pick"),
    "mode_speed": ("analysis", "mode_speed"),
    "mode_rank": ("analysis", "mode_rank"),
    "waves_all": ("analysis", "waves_all"),
}
#: Fields of a snapshot that are published results, not settings.
PUBLISHED = ("band", "pins")
_TYPES = {"int": int, "float": float, "bool": bool, "str": str, "tuple": tuple}
#: Fields that act only in vehicle scope (a corner's results are not made of them).
VEHICLE_FIELDS = ("wheels", "tracks", "coherence", "point")


@dataclass(frozen=True)
class Snapshot:
    """A session's state at one moment: its settings (plain values) and the published
    inputs other results are made of. Equal snapshots make equal results."""

    harmonic: int
    n_modes: int
    dof: str
    coupling: str
    residual: bool
    show_uncoupled: bool
    spindle_input: str
    models: Any  # app.datasource.Models (hashed by the digest of the uploads)
    review: Any  # app.review.Review (candidates, targets; hashed by their digest)
    scope: str
    wheels: tuple
    tracks: str
    coherence: float
    point: str
    noise: float
    target: str
    frequency_dependent: bool
    rounds: int
    seed: int
    single_round: int
    percentile: int
    first_order: bool
    threshold: float
    f_max: float
    map_mode: str
    tab: str
    frf: str
    phase_mode: str
    log_freq: bool
    cursor1: float
    cursor2: float
    picked_speed: float
    picked_freq: float
    contrib_mode: str
    pin_text: str
    compare_to: str
    overlay: tuple
    level_scale: str
    mcursor1: float
    mcursor2: float
    snap: bool
    mode_pick: int
    mode_speed: float
    mode_rank: str
    waves_all: bool
    band: Any = None  # the published Band (compared by identity)
    pins: tuple = ()  # the published pins (app.results.pins.Pin, by identity)

    @classmethod
    def of(cls, state: Any, band: Any = None, pins: tuple = ()) -> Snapshot:
        """The snapshot of a ``DashboardState`` (and the published band and pins)."""
        kw: dict[str, Any] = {}
        for name, (group, p) in FIELDS.items():
            value = getattr(getattr(state, group), p)
            kind = cls.__dataclass_fields__[name].type
            kw[name] = _TYPES[kind](value) if kind in _TYPES else value
        return cls(**kw, band=band, pins=tuple(pins))

    def replace(self, **changes: Any) -> Snapshot:
        return dataclasses.replace(self, **changes)

    def settings(self) -> Snapshot:
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
