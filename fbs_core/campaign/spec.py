"""A sensitivity campaign described in a TOML file: the case matrix, the models, the outputs.

A campaign is the cross product of the settings listed in its ``[scatter]`` table (noise
scatter bands, thesis 5.2, eqs. 5.2-5.4) and its ``[truncation]`` table (truncation error
maps and suggested mode counts, thesis 5.1, eq. 5.1 and table 5.1), plus an optional
``[variants]`` table: a corridor study of physical parameters (:mod:`.variants`,
``campaigns/corridor.toml``). The layout, with every key and its default, is documented in
``campaigns/example.toml``::

    [campaign]
    name = "example"
    seed = 2018                 # the campaign seed; every case's seed derives from it
    seeds = "per-case"          # or "common": every case uses the campaign seed
    output = "example.h5"       # relative to the TOML file

    [models.tire]               # variants by name: "reference" or a model file
    reference = "reference"
    [models.chassis]            # "reference" or an FRF file (interpolated per harmonic)
    reference = "reference"

    [scatter]
    harmonics = [1, 4]
    noise = [0.05, 0.10]        # 0.1 = +-10 %
    targets = ["tire", "chassis", "both"]
    frequency_dependent = [false]
    rounds = 2000
    ...

Nothing in the file is evaluated: values are checked against the allowed types and ranges
and a bad one raises :class:`CampaignError` naming the key and what is allowed.
"""

from __future__ import annotations

import os
import tomllib
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

from ..errors import CampaignError
from ..vocabulary import COUPLINGS
from .fields import (
    _choice,
    _digest,
    _err,
    _float,
    _int,
    _known,
    _list,
    _name,
    _table,
    case_seed,
)

if TYPE_CHECKING:
    from .variants import VariantsCase

__all__ = [
    "CampaignError",
    "Campaign",
    "BandCase",
    "TruncationCase",
    "load_campaign",
    "parse_campaign",
    "TARGET_NAMES",
]

#: Noise targets as written in a campaign file -> the target of :func:`fbs_core.scatter_band`
#: ("vehicle", the thesis' word, is the chassis).
TARGET_NAMES = {"tire": "tire", "chassis": "chassis", "vehicle": "chassis", "both": "both"}
#: A case's name (and so its seed, :func:`case_seed`) spells the chassis target as the first
#: release did, so a campaign file gives the same cases and numbers as before.
_NAME_TOKENS = {"chassis": "vehicle"}
SEED_MODES = ("per-case", "common")
OUTPUTS = {
    "scatter": ("band", "percentiles", "convergence"),
    "truncation": ("error", "suggested", "responses"),
}
_TOP = (
    "campaign",
    "models",
    "grid",
    "scatter",
    "truncation",
    "variants",
    "outputs",
    "execution",
)


@dataclass(frozen=True)
class BandCase:
    """One scatter-band case (thesis eqs. 5.2-5.4); ``target`` uses the library's names."""

    harmonic: int
    noise: float
    target: str
    frequency_dependent: bool
    rounds: int
    n_modes: int | None
    coupling: str
    tire: str
    chassis: str
    seed: int
    percentiles: tuple[float, ...]
    df: float

    kind: ClassVar[str] = "scatter"

    @property
    def name(self) -> str:
        """Readable, unique id (the group name in the result file)."""
        nm = "all" if self.n_modes is None else str(self.n_modes)
        return (
            f"band_h{self.harmonic}_p{self.noise:g}_{_NAME_TOKENS.get(self.target, self.target)}_"
            f"{'fdep' if self.frequency_dependent else 'fixed'}_R{self.rounds}_N{nm}_"
            f"{self.coupling}_{self.tire}_{self.chassis}"
        )

    @property
    def inputs_name(self) -> str:
        """Id of the subsystem arrays this case is computed from (shared by cases)."""
        nm = "all" if self.n_modes is None else str(self.n_modes)
        return f"h{self.harmonic}_N{nm}_{self.coupling}_{self.tire}_{self.chassis}_df{self.df:g}"

    def settings(self) -> dict[str, Any]:
        return {"kind": self.kind, **asdict(self)}

    def digest(self) -> str:
        s = self.settings()
        s["target"] = _NAME_TOKENS.get(self.target, self.target)  # as the first release did
        return _digest(s)


@dataclass(frozen=True)
class TruncationCase:
    """One truncation-map case (thesis 5.1): error map and suggested modes of a harmonic."""

    harmonic: int
    n_modes: tuple[int, ...]
    coupling: str
    tire: str
    chassis: str
    width: float
    step: float
    thresholds: tuple[float, ...]
    f_max: tuple[float, ...]
    df: float

    kind: ClassVar[str] = "truncation"

    @property
    def name(self) -> str:
        return f"trunc_h{self.harmonic}_{self.coupling}_{self.tire}_{self.chassis}"

    def settings(self) -> dict[str, Any]:
        return {"kind": self.kind, **asdict(self)}

    def digest(self) -> str:
        return _digest(self.settings())


@dataclass(frozen=True)
class Campaign:
    """A parsed campaign: its cases, models, outputs and execution settings.

    Attributes
    ----------
    name : str
    seed : int
        The campaign seed.
    seeds : {"per-case", "common"}
    output : pathlib.Path
        The result file (HDF5).
    tires, chassis : dict of str to str
        Model variants: name -> ``"reference"`` or an absolute file path.
    cases : tuple of BandCase, TruncationCase and VariantsCase
    outputs : dict of str to tuple of str
        What is stored of each kind of case.
    task_round_lines : int
        Work of one scatter task in rounds x frequency lines.
    max_chunk_bytes : float
        Working memory of one chunk of lines inside a task.
    text : str
        The TOML text (stored in the result file).
    """

    name: str
    seed: int
    seeds: str
    output: Path
    tires: dict[str, str]
    chassis: dict[str, str]
    cases: tuple[BandCase | TruncationCase | VariantsCase, ...]
    outputs: dict[str, tuple[str, ...]]
    task_round_lines: int
    max_chunk_bytes: float
    text: str = field(repr=False, default="")

    @property
    def band_cases(self) -> tuple[BandCase, ...]:
        return tuple(c for c in self.cases if isinstance(c, BandCase))

    @property
    def truncation_cases(self) -> tuple[TruncationCase, ...]:
        return tuple(c for c in self.cases if isinstance(c, TruncationCase))

    @property
    def variants_cases(self) -> tuple[VariantsCase, ...]:
        """The corridor studies (``[variants]``, :mod:`.variants`)."""
        from .variants import VariantsCase

        return tuple(c for c in self.cases if isinstance(c, VariantsCase))


def _models(d: dict[str, Any], base: Path, kind: str) -> dict[str, str]:
    where = f"[models.{kind}]"
    out: dict[str, str] = {}
    for name, src in d.items():
        _name(name, where)
        if not isinstance(src, str) or not src:
            raise _err(f"{where} {name}", f"must be 'reference' or a file path, got {src!r}")
        if src == "reference":
            out[name] = "reference"
        else:
            p = (base / src).resolve()
            if not p.is_file():
                raise _err(f"{where} {name}", f"model file {str(p)!r} does not exist")
            out[name] = str(p)
    return out or {"reference": "reference"}


def _variants(d: dict[str, Any], key: str, models: dict[str, str], where: str) -> list[str]:
    names = [str(x) for x in _list(d.get(key, list(models)), where)]
    for n in names:
        if n not in models:
            raise _err(f"{where} {key}", f"unknown variant {n!r}; defined: {', '.join(models)}")
    return names


def _couplings(d: dict[str, Any], where: str) -> list[str]:
    return [
        _choice(c, COUPLINGS, f"{where} couplings")
        for c in _list(d.get("couplings", "6dof"), where)
    ]


def _harmonics(d: dict[str, Any], where: str) -> list[int]:
    hs = [_int(h, f"{where} harmonics", 1, 7) for h in _list(d.get("harmonics", [1]), where)]
    if len(set(hs)) != len(hs):
        raise _err(f"{where} harmonics", f"duplicates in {hs}")
    return hs


def _unique(xs: list[Any], where: str) -> list[Any]:
    if len(set(xs)) != len(xs):
        raise _err(where, f"duplicate values in {xs}")
    return xs


def parse_campaign(text: str, base: Path | str = ".") -> Campaign:
    """Parse the TOML text of a campaign (paths relative to ``base``).

    Raises
    ------
    CampaignError
        For TOML syntax errors, unknown keys, values of the wrong type or range, unknown
        model variants and missing model files.
    """
    base = Path(base)
    try:
        d = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise CampaignError(f"campaign file is not valid TOML: {e}") from None
    _known(d, _TOP, "top level")
    c = _table(d, "campaign", "top level")
    _known(c, ("name", "description", "seed", "seeds", "output"), "[campaign]")
    name = c.get("name", "campaign")
    if not isinstance(name, str) or not name:
        raise _err("[campaign] name", f"must be a non-empty string, got {name!r}")
    seed = _int(c.get("seed", 0), "[campaign] seed", 0, 2**63 - 1)
    seeds = _choice(c.get("seeds", "per-case"), SEED_MODES, "[campaign] seeds")
    out = c.get("output", f"{name}.h5")
    if not isinstance(out, str) or not out:
        raise _err("[campaign] output", f"must be a file path, got {out!r}")
    output = (base / out).resolve()

    m = _table(d, "models", "top level")
    _known(m, ("tire", "chassis"), "[models]")
    tires = _models(_table(m, "tire", "[models]"), base, "tire")
    chassis = _models(_table(m, "chassis", "[models]"), base, "chassis")

    g = _table(d, "grid", "top level")
    _known(g, ("df",), "[grid]")
    df = _float(g.get("df", 0.5), "[grid] df", 0.01, 10.0)

    cases: list[BandCase | TruncationCase | VariantsCase] = []
    s = _table(d, "scatter", "top level")
    if s:
        w = "[scatter]"
        _known(
            s,
            (
                "harmonics",
                "noise",
                "targets",
                "frequency_dependent",
                "rounds",
                "n_modes",
                "percentiles",
                "couplings",
                "tires",
                "chassis",
            ),
            w,
        )
        hs = _harmonics(s, w)
        ps = _unique(
            [_float(p, f"{w} noise", 0.0, 1.0, True) for p in _list(s.get("noise", 0.1), w)],
            f"{w} noise",
        )
        tg = _list(s.get("targets", "both"), w)
        tg = _unique(
            [TARGET_NAMES[_choice(t, tuple(TARGET_NAMES), f"{w} targets")] for t in tg],
            f"{w} targets",
        )
        fds = _list(s.get("frequency_dependent", False), w)
        for v in fds:
            if not isinstance(v, bool):
                raise _err(f"{w} frequency_dependent", f"must be true/false, got {v!r}")
        fds = _unique(fds, f"{w} frequency_dependent")
        from ..studies.scatter import MAX_ROUNDS

        rounds = _int(s.get("rounds", 10_000), f"{w} rounds", 1, MAX_ROUNDS)
        nm = s.get("n_modes", "all")
        n_modes = None if nm == "all" else _int(nm, f"{w} n_modes", 1)
        qs = tuple(
            _float(q, f"{w} percentiles", 0.0, 100.0)
            for q in _list(s.get("percentiles", [5.0, 95.0]), w)
        )
        for h in hs:
            for cp in _couplings(s, w):
                for t in _variants(s, "tires", tires, w):
                    for ch in _variants(s, "chassis", chassis, w):
                        for fd in fds:
                            for tgt in tg:
                                for p in ps:
                                    proto = BandCase(
                                        h, p, tgt, fd, rounds, n_modes, cp, t, ch, seed, qs, df
                                    )
                                    cs = seed if seeds == "common" else case_seed(seed, proto.name)
                                    cases.append(
                                        BandCase(
                                            h, p, tgt, fd, rounds, n_modes, cp, t, ch, cs, qs, df
                                        )
                                    )

    tr = _table(d, "truncation", "top level")
    if tr:
        w = "[truncation]"
        _known(
            tr,
            (
                "harmonics",
                "n_modes",
                "thresholds",
                "f_max",
                "width",
                "step",
                "couplings",
                "tires",
                "chassis",
            ),
            w,
        )
        nm = tr.get("n_modes", {"from": 10, "to": 400, "step": 10})
        if isinstance(nm, dict):
            _known(nm, ("from", "to", "step"), f"{w} n_modes")
            a = _int(nm.get("from", 10), f"{w} n_modes.from", 1)
            b = _int(nm.get("to", 400), f"{w} n_modes.to", a)
            st = _int(nm.get("step", 10), f"{w} n_modes.step", 1)
            counts = tuple(range(a, b + 1, st))
        else:
            counts = tuple(_int(n, f"{w} n_modes", 1) for n in _list(nm, w))
            if any(y <= x for x, y in zip(counts, counts[1:], strict=False)):
                raise _err(f"{w} n_modes", f"must be strictly ascending, got {list(counts)}")
        ths = tuple(
            _float(x, f"{w} thresholds", 0.0, 100.0) for x in _list(tr.get("thresholds", 0.2), w)
        )
        fmx = tuple(_float(x, f"{w} f_max", 0.0, 1e5) for x in _list(tr.get("f_max", 160.0), w))
        width = _float(tr.get("width", 12.0), f"{w} width", 1e-3, 1e4)
        step = _float(tr.get("step", 1.0), f"{w} step", 1e-3, 1e4)
        for h in _harmonics(tr, w):
            for cp in _couplings(tr, w):
                for t in _variants(tr, "tires", tires, w):
                    for ch in _variants(tr, "chassis", chassis, w):
                        cases.append(
                            TruncationCase(h, counts, cp, t, ch, width, step, ths, fmx, df)
                        )
    va = _table(d, "variants", "top level")
    if va:
        from .variants import parse_variants

        cases.append(parse_variants(va, seed, seeds, df))
    if not cases:
        raise CampaignError(
            "campaign file defines no cases: add a [scatter], [truncation] or [variants] table"
        )
    names = [x.name for x in cases]
    if len(set(names)) != len(names):  # pragma: no cover - the loops make names unique
        raise CampaignError("campaign file defines the same case twice")

    o = _table(d, "outputs", "top level")
    _known(o, tuple(OUTPUTS), "[outputs]")
    outputs: dict[str, tuple[str, ...]] = {}
    for kind, allowed in OUTPUTS.items():
        sel = _list(
            o.get(kind, list(allowed if kind == "scatter" else ("error", "suggested"))), "[outputs]"
        )
        outputs[kind] = tuple(_choice(x, allowed, f"[outputs] {kind}") for x in sel)

    ex = _table(d, "execution", "top level")
    _known(ex, ("task_round_lines", "max_chunk_bytes"), "[execution]")
    trl = _int(ex.get("task_round_lines", 20_000_000), "[execution] task_round_lines", 1)
    mcb = _float(ex.get("max_chunk_bytes", 64e6), "[execution] max_chunk_bytes", 1e5, 1e11)
    return Campaign(
        name, seed, seeds, output, tires, chassis, tuple(cases), outputs, trl, mcb, text
    )


def load_campaign(path: str | os.PathLike[str]) -> Campaign:
    """Read and check a campaign file (TOML); relative paths are relative to its folder.

    Raises
    ------
    CampaignError
        For a missing or unreadable file and everything :func:`parse_campaign` refuses.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise CampaignError(f"cannot read campaign file {str(p)!r}: {e}") from None
    return parse_campaign(text, p.parent)
