"""What a report, a title block or a file name shows, as plain data (:class:`ReportData`).

It holds no Panel or param objects: the settings as a plain dict, where the data came from
(the shipped reference models or uploaded files with their digests), the results as the
core library's immutable objects (:class:`fbs_core.FRF`, :class:`fbs_core.TruncationMap`,
:class:`fbs_core.SuggestedModes`, :class:`fbs_core.ScatterBand`,
:class:`fbs_core.ModeFrequencies`: those the session's store published, see
:mod:`app.report.session`), the page URL that reproduces the state and the time it was
taken. Everything in :mod:`app.report` is a pure function of it.
"""

from __future__ import annotations

import datetime as _dt
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from numpy.typing import ArrayLike

import fbs_core
from fbs_core.analysis import Contributions, Peak
from fbs_core.errors import FBSError
from fbs_core.vocabulary import COUPLINGS, DIRECTIONS, percent

from ..state import SCHEMA

__all__ = [
    "present",
    "ExtraSection",
    "ReportError",
    "DataFile",
    "Provenance",
    "ReportData",
    "SETTING_KEYS",
    "DIRECTIONS",
    "COUPLINGS",
    "NOISE_TARGETS",
    "MAP_MODES",
    "N_AXES",
]

#: Noise targets, map modes and N-axis scales accepted in the settings (the dashboard's
#: choices; the DOF directions and couplings are the core's vocabulary).
NOISE_TARGETS = SCHEMA.choices["target"]
MAP_MODES = SCHEMA.choices["map_mode"]
N_AXES = SCHEMA.choices["n_axis"]

#: Settings a report may hold: name -> (type, meaning), from the settings schema (each
#: setting's declaration gives its label). The first four are required.
SETTING_KEYS: dict[str, tuple[type, str]] = SCHEMA.report_keys
_REQUIRED = ("harmonic", "n_modes", "dof", "coupling")
_CHOICES = SCHEMA.choices
#: Settings each result needs to be described.
_NEEDS = {
    "truncation": ("threshold", "f_max", "map_mode"),
    "suggested": ("threshold", "f_max", "map_mode"),
    "band": (
        "noise",
        "target",
        "frequency_dependent",
        "rounds",
        "seed",
        "single_round",
        "percentile",
    ),
}


class ReportError(FBSError):
    """Report data that cannot be reported: missing or invalid settings, mismatched results."""


def present[T](value: T | None, what: str) -> T:
    """``value``, which a report part needs: a :class:`ReportError` naming ``what`` if None."""
    if value is None:
        raise ReportError(f"the report data hold no {what}")
    return value


@dataclass(frozen=True)
class DataFile:
    """One model of the report: the shipped reference (``name=None``) or an uploaded file.

    Attributes
    ----------
    role : {"tire", "chassis"}
    name : str or None
        File name as uploaded; None for the shipped reference model.
    digest : str or None
        Digest of the uploaded bytes and import settings (identifies the data).
    """

    role: str
    name: str | None = None
    digest: str | None = None

    def __post_init__(self) -> None:
        if self.role not in ("tire", "chassis"):
            raise ReportError(f"unknown data role {self.role!r}; allowed: tire, chassis")
        if self.name is not None and not str(self.name).strip():
            raise ReportError(f"the uploaded {self.role} file needs a name")

    @property
    def is_reference(self) -> bool:
        return self.name is None

    def describe(self) -> str:
        """``"reference tire (shipped model)"`` or ``"uploaded chassis 'x.uff' (digest ...)"``."""
        if self.is_reference:
            return f"reference {self.role} (shipped model)"
        dig = f", digest {self.digest}" if self.digest else ""
        return f"uploaded {self.role} '{self.name}'{dig}"


@dataclass(frozen=True)
class Provenance:
    """Where the models of a report came from.

    Attributes
    ----------
    tire, chassis : DataFile
    notes : tuple of str
        What the import did (unit conversions, interpolation), one note per entry.
    """

    tire: DataFile = field(default_factory=lambda: DataFile("tire"))
    chassis: DataFile = field(default_factory=lambda: DataFile("chassis"))
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.tire.role != "tire" or self.chassis.role != "chassis":
            raise ReportError("Provenance takes DataFile('tire', ...) and DataFile('chassis', ...)")
        object.__setattr__(self, "notes", tuple(str(n) for n in self.notes))

    @property
    def is_reference(self) -> bool:
        """True when both models are the shipped reference."""
        return self.tire.is_reference and self.chassis.is_reference

    @property
    def uploads(self) -> tuple[DataFile, ...]:
        return tuple(d for d in (self.tire, self.chassis) if not d.is_reference)

    def describe(self) -> str:
        """One line naming the data in use."""
        if self.is_reference:
            return "reference tire and chassis (shipped models)"
        return "; ".join(d.describe() for d in (self.tire, self.chassis))


def _check_setting(name: str, value: Any) -> Any:
    typ, meaning = SETTING_KEYS[name]
    if typ is bool:
        if not isinstance(value, bool):
            raise ReportError(f"setting {name!r} ({meaning}) must be True or False, got {value!r}")
        return value
    if typ is int:
        if isinstance(value, bool) or not float(value).is_integer():
            raise ReportError(f"setting {name!r} ({meaning}) must be an integer, got {value!r}")
        value = int(value)
    elif typ is float:
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise ReportError(
                f"setting {name!r} ({meaning}) must be a number, got {value!r}"
            ) from None
    else:
        value = str(value)
    if name in _CHOICES and value not in _CHOICES[name]:
        raise ReportError(
            f"setting {name!r} ({meaning}) is {value!r}; allowed: {', '.join(_CHOICES[name])}"
        )
    if name == "harmonic" and not 1 <= value <= 7:
        raise ReportError(f"setting 'harmonic' is {value}; allowed: 1, 2, 3, 4, 5, 6, 7")
    if name in ("n_modes", "rounds", "percentile") and value < 1:
        raise ReportError(f"setting {name!r} ({meaning}) must be >= 1, got {value}")
    if name in ("threshold", "f_max") and not value > 0:
        raise ReportError(f"setting {name!r} ({meaning}) must be > 0, got {value}")
    if name in ("noise", "seed", "single_round") and not value >= 0:
        raise ReportError(f"setting {name!r} ({meaning}) must be >= 0, got {value}")
    return value


def normalise_settings(settings: Mapping[str, Any]) -> Mapping[str, Any]:
    """Checked, typed, read-only copy of ``settings`` (keys of :data:`SETTING_KEYS`).

    Raises
    ------
    ReportError
        For an unknown key (naming the allowed ones), a missing required key or a value
        of the wrong type or outside its choices.
    """
    unknown = sorted(set(settings) - set(SETTING_KEYS))
    if unknown:
        raise ReportError(
            f"unknown setting(s) {', '.join(map(repr, unknown))}; allowed: "
            + ", ".join(SETTING_KEYS)
        )
    missing = [k for k in _REQUIRED if k not in settings]
    if missing:
        raise ReportError(f"missing setting(s): {', '.join(missing)}")
    out = {k: _check_setting(k, settings[k]) for k in SETTING_KEYS if k in settings}
    out.setdefault("n_axis", "linear")
    return MappingProxyType(out)


def _check_plot(key: str, plot: Mapping[str, Any]) -> None:
    """A section's plot description (:attr:`ExtraSection.plot`) of consistent shapes."""
    import numpy as np

    kind = plot.get("kind")
    if kind not in ("lines", "image"):
        raise ReportError(f"section {key!r}: plot kind {kind!r}; allowed: lines, image")
    x = np.asarray(plot.get("x", ()), float)
    if kind == "lines":
        for label, ys in dict(plot.get("groups", {})).items():
            for y in ys:
                if np.shape(y) != x.shape:
                    raise ReportError(
                        f"section {key!r}: a line of {label!r} has shape {np.shape(y)}, "
                        f"its x {x.shape}"
                    )
    else:
        y = np.asarray(plot.get("y", ()), float)
        z_shape = np.asarray(plot.get("z", ()), float).shape
        if z_shape != (x.size, y.size):
            raise ReportError(
                f"section {key!r}: the image has shape {z_shape}, its axes ({x.size}, {y.size})"
            )


@dataclass(frozen=True, eq=False)
class ExtraSection:
    """A section another view contributes to the report (an analysis, a pinned curve).

    Built from a published ``app.store.Result`` with :meth:`of_result` (its description,
    its CSV header as a table and, when it has a ``freq_Hz`` column, its ``*_dB`` columns
    as curves), so a new view appears in the report without code in :mod:`app.report`.

    Attributes
    ----------
    key : str
        Short name (anchor and file name).
    heading : str
    paragraphs : tuple of str
    rows : tuple of (str, str)
        Described values (the CSV header of the result).
    freq : ndarray or None
        Frequencies (Hz) of the curves.
    curves : mapping of str to ndarray
        Levels in dB on ``freq``, by label.
    y_label : str
    plot : mapping, optional
        A plot that is no set of curves over frequency, as the view describes it in its
        result's ``draw["report_plot"]``: ``{"kind": "lines", "x", "groups": {label:
        [y, ...]}, "x_label", "y_label"}`` (e.g. the Campbell diagram: branches and order
        lines over speed) or ``{"kind": "image", "x", "y", "z" (n_x, n_y), "x_label",
        "y_label", "z_label", "line": (x, y) optional}`` (e.g. the speed map).
    strip : mapping or None
        A mode shape's frames drawn side by side (``figures.draw_strip``): the result's
        ``draw["strip"]``.
    """

    key: str
    heading: str
    paragraphs: tuple[str, ...] = ()
    rows: tuple[tuple[str, str], ...] = ()
    freq: ArrayLike | None = None
    curves: Mapping[str, Any] = field(default_factory=dict)
    y_label: str = "Level (dB)"
    plot: Mapping[str, Any] | None = None
    strip: Mapping[str, Any] | None = None

    def __post_init__(self) -> None:
        import numpy as np

        if not str(self.key).strip() or not str(self.heading).strip():
            raise ReportError("an extra report section needs a key and a heading")
        if self.curves:
            if self.freq is None:
                raise ReportError(f"section {self.key!r}: curves need their frequencies")
            f = np.asarray(self.freq, float)
            for label, c in self.curves.items():
                if np.shape(c) != f.shape:
                    raise ReportError(
                        f"section {self.key!r}: curve {label!r} has shape {np.shape(c)}, "
                        f"the frequencies {f.shape}"
                    )
        if self.plot is not None:
            _check_plot(self.key, self.plot)

    @classmethod
    def of_result(cls, key: str, result: Any) -> ExtraSection:
        """The section of a published result (``columns``, ``meta``, ``caption``)."""
        import re

        import numpy as np

        meta = dict(result.meta)
        heading = str(meta.pop("view", key))
        caption = re.sub(r"\*\*(.+?)\*\*", r"\1", str(result.caption or ""))
        caption = caption.replace("&middot;", "-")
        cols = result.columns
        freq = cols.get("freq_Hz")
        curves = {}
        # curves over a frequency axis (a long layout, one row per (curve, line), is a table)
        if freq is not None and np.all(np.diff(np.asarray(freq, float)) > 0):
            curves = {
                k[: -len("_dB")].replace("_", " "): np.asarray(v, float)
                for k, v in cols.items()
                if k.endswith("_dB") and np.shape(v) == np.shape(freq)
            }
        unit = meta.get("unit")
        plot = result.draw.get("report_plot") if not curves else None
        return cls(
            key=key,
            heading=heading[:1].upper() + heading[1:],
            paragraphs=(caption,) if caption else (),
            rows=tuple((str(k), str(v)) for k, v in meta.items()),
            freq=None if not curves else np.asarray(freq, float),
            curves=curves,
            y_label=f"Level ({unit})" if unit else "Level (dB)",
            plot=plot,
            strip=result.draw.get("strip"),
        )


@dataclass(frozen=True, eq=False)
class ReportData:
    """Everything one report shows, as plain data.

    Attributes
    ----------
    settings : Mapping
        The dashboard settings (keys of :data:`SETTING_KEYS`; harmonic, n_modes, dof and
        coupling required; the others required by the results given).
    provenance : Provenance
        Reference models or uploaded files (names and digests).
    url : str
        The page URL that reproduces the state (``""`` if unknown).
    created : datetime.datetime
        When the data were taken (timezone-aware; naive is taken as UTC).
    reference, truncated : fbs_core.FRF, optional
        Coupled bushing response (eq. 4.1) with all tire modes and with ``n_modes`` modes
        (with residual compensation when the settings say so): outputs ``bushing:<dof>``
        (and possibly the other bushing DOFs), input ``patch``.
    truncation : fbs_core.TruncationMap, optional
        Error map of the harmonic (eq. 5.1).
    suggested : fbs_core.SuggestedModes, optional
        Suggested number of modes (thesis table 5.1).
    band : fbs_core.ScatterBand, optional
        Monte-Carlo scatter band (eqs. 5.2-5.4).
    eigen : fbs_core.ModeFrequencies, optional
        Highest retained eigenfrequency versus N (thesis fig. 5.8).
    n_modes_total : int, optional
        Modes of the tire (default from the truncation map).
    suggested_n : int, optional
        The N the error map suggests (marked on the page's map; default read from the map).
    peaks : tuple of fbs_core.analysis.Peak
        The peaks of the N-mode response the page labels (the summary's peak table).
    contributions : fbs_core.analysis.Contributions, optional
        The contributions of the interface forces, when the page computed them for these
        settings (the summary's largest contributions).
    extra : tuple of ExtraSection
        Sections contributed by other views (after the built-in ones).
    verdict : fbs_core.verdict.Verdict, optional
        The review's verdict (candidates against targets): the report's first section.
    """

    settings: Mapping[str, Any]
    provenance: Provenance = field(default_factory=Provenance)
    url: str = ""
    created: _dt.datetime = field(default_factory=lambda: _dt.datetime.now(_dt.UTC))
    reference: fbs_core.FRF | None = None
    truncated: fbs_core.FRF | None = None
    truncation: fbs_core.TruncationMap | None = None
    suggested: fbs_core.SuggestedModes | None = None
    band: fbs_core.ScatterBand | None = None
    eigen: fbs_core.ModeFrequencies | None = None
    n_modes_total: int | None = None
    suggested_n: int | None = None
    peaks: tuple[Any, ...] = ()
    contributions: Any = None
    extra: tuple[ExtraSection, ...] = ()
    verdict: Any = None

    def __post_init__(self) -> None:
        s = normalise_settings(self.settings)
        object.__setattr__(self, "settings", s)
        if not isinstance(self.provenance, Provenance):
            raise ReportError(f"provenance must be a Provenance, got {type(self.provenance)}")
        if not isinstance(self.created, _dt.datetime):
            raise ReportError(f"created must be a datetime, got {self.created!r}")
        if self.created.tzinfo is None:
            object.__setattr__(self, "created", self.created.replace(tzinfo=_dt.UTC))
        url = str(self.url or "")
        if url and not url.startswith(("http://", "https://")):
            raise ReportError(f"url must be an http(s) address of the page, got {url!r}")
        if any(c in url for c in "\"'<> \n"):
            raise ReportError("url must not contain quotes, angle brackets or spaces")
        object.__setattr__(self, "url", url)
        for name, cls in (
            ("reference", fbs_core.FRF),
            ("truncated", fbs_core.FRF),
            ("truncation", fbs_core.TruncationMap),
            ("suggested", fbs_core.SuggestedModes),
            ("band", fbs_core.ScatterBand),
            ("eigen", fbs_core.ModeFrequencies),
        ):
            v = getattr(self, name)
            if v is not None and not isinstance(v, cls):
                raise ReportError(f"{name} must be a {cls.__name__}, got {type(v).__name__}")
        for name, keys in _NEEDS.items():
            if getattr(self, name) is not None:
                missing = [k for k in keys if k not in s]
                if missing:
                    raise ReportError(
                        f"the {name} result needs the setting(s) {', '.join(missing)}"
                    )
        object.__setattr__(self, "peaks", tuple(self.peaks))
        for p in self.peaks:
            if not isinstance(p, Peak):
                raise ReportError(f"peaks must be fbs_core.analysis.Peak, got {type(p).__name__}")
        c = self.contributions
        if c is not None:
            if not isinstance(c, Contributions):
                raise ReportError(f"contributions must be a Contributions, got {type(c).__name__}")
            if self.response_dof not in c.outputs:
                raise ReportError(
                    f"the contributions have no output {self.response_dof!r}; "
                    f"outputs: {', '.join(c.outputs)}"
                )
        object.__setattr__(self, "extra", tuple(self.extra))
        for ex in self.extra:
            if not isinstance(ex, ExtraSection):
                raise ReportError(f"extra sections must be ExtraSection, got {type(ex).__name__}")
        self._check_results(s)
        if self.n_modes_total is None and self.truncation is not None:
            object.__setattr__(self, "n_modes_total", self.truncation.n_modes_total)

    def _check_results(self, s: Mapping[str, Any]) -> None:
        if s.get("scope") == "vehicle" and "point" not in s:
            raise ReportError("a report in vehicle scope needs the setting 'point'")
        dof = self.response_dof
        for name in ("reference", "truncated"):
            frf = getattr(self, name)
            if frf is not None and dof not in frf.outputs:
                raise ReportError(
                    f"the {name} response has no output {dof!r}; outputs: {', '.join(frf.outputs)}"
                )
        k = s["harmonic"]
        for name in ("truncation", "band"):
            res = getattr(self, name)
            if res is not None and res.harmonic not in (None, k):
                raise ReportError(f"the {name} result is of harmonic {res.harmonic}, not {k}")
            if res is not None and dof not in res.dofs:
                raise ReportError(
                    f"the {name} result has no response DOF {dof!r}; DOFs: {', '.join(res.dofs)}"
                )
        if self.band is not None:
            w = s["percentile"]
            q = {float(x) for x in self.band.q}
            if (100 - w) / 2 not in q or (100 + w) / 2 not in q:
                raise ReportError(
                    f"the band holds the percentiles {sorted(q)}, not the "
                    f"{(100 - w) / 2:g} and {(100 + w) / 2:g} % of a {w} % central band"
                )
            b = self.band
            given = (percent(b.noise), b.target, b.frequency_dependent, b.rounds, b.seed)
            said = (s["noise"], s["target"], s["frequency_dependent"], s["rounds"], s["seed"])
            if not (abs(given[0] - said[0]) <= 1e-9 * max(1.0, said[0]) and given[1:] == said[1:]):
                raise ReportError(
                    "the band was computed with noise, target, frequency dependence, rounds, "
                    f"seed = {given}, the settings say {said}"
                )
            if not 0 <= s["single_round"] < self.band.rounds:
                raise ReportError(
                    f"single_round {s['single_round']} is not a round of the band "
                    f"(0..{self.band.rounds - 1})"
                )

        if self.suggested is not None:
            sm = self.suggested
            if not (
                abs(percent(sm.threshold) - s["threshold"]) <= 1e-9 * s["threshold"]
                and sm.f_max == s["f_max"]
                and sm.dof == self.map_dof
            ):
                raise ReportError(
                    f"the suggested modes were read at threshold {percent(sm.threshold):g} %, "
                    f"f_max {sm.f_max:g} Hz, DOF {sm.dof}; the settings say "
                    f"{s['threshold']:g} %, {s['f_max']:g} Hz, DOF {self.map_dof}"
                )

    @property
    def harmonic(self) -> fbs_core.Harmonic:
        return fbs_core.harmonic(self.settings["harmonic"])

    @property
    def vehicle(self) -> bool:
        """Whether the report is of the whole car (vehicle scope)."""
        return self.settings.get("scope") == "vehicle"

    @property
    def response_dof(self) -> str:
        """``"bushing:z"`` etc.; in vehicle scope the car's point, ``"seat_fl:z"``."""
        if self.vehicle:
            return f"{self.settings['point']}:{self.settings['dof']}"
        return f"bushing:{self.settings['dof']}"

    @property
    def map_dof(self) -> str | None:
        """DOF of the error map and the suggested modes (None: maximum over the 6 DOFs)."""
        if self.settings.get("map_mode", MAP_MODES[0]) == MAP_MODES[0]:
            return self.response_dof
        return None
