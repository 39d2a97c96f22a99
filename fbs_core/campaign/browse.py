"""Browsing a campaign result file: its cases, their bands and maps, its provenance.

:func:`open_campaign` reads the result file together with the parts of a run that has not
committed yet (a running or killed campaign is browsable too). Bands come back as
:class:`~fbs_core.ScatterBand` objects, equal to those of :func:`fbs_core.scatter_band`
with the case's seed, including :meth:`~fbs_core.ScatterBand.round` (the subsystem
arrays are in the file); truncation cases as :class:`~fbs_core.TruncationMap` (when the
responses were stored) or as the error map alone.

A result file is data from outside the process (a disk, a volume other runs write to): every
way it can be malformed (a case's settings that are not JSON or lack a key, a block of
another name, an array of the wrong shape, a file that is not HDF5 ...) ends in a
:class:`CampaignError` that names the file, the case or array and the problem, never in
another exception.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._typing import AnyArray, FloatArray, IntArray
from ..errors import CampaignError
from .store import CampaignStore, read_file

if TYPE_CHECKING:
    from ..studies.scatter import ScatterBand
    from ..studies.truncation import TruncationMap
    from ..variants import VariantStudy

__all__ = ["open_campaign", "CampaignResult", "CaseEntry", "TruncationEntry"]


#: What reading a malformed file raises in h5py, numpy and the standard library.
_MALFORMED = (ValueError, TypeError, KeyError, IndexError, AttributeError, OSError, RuntimeError)

#: Settings each kind of case must hold, and their types (a bool is not a number here).
_SETTINGS: dict[str, dict[str, tuple[type, ...]]] = {
    "scatter": {
        "harmonic": (int,),
        "noise": (int, float),
        "target": (str,),
        "frequency_dependent": (bool,),
        "rounds": (int,),
        "seed": (int,),
        "percentiles": (list,),
        "coupling": (str,),
        "tire": (str,),
        "chassis": (str,),
    },
    "truncation": {
        "harmonic": (int,),
        "n_modes": (list,),
        "coupling": (str,),
        "tire": (str,),
        "chassis": (str,),
    },
    "variants": {
        "study": (str,),
        "parameters": (list,),
        "design": (str,),
        "n": (int,),
        "seed": (int,),
        "harmonics": (list,),
        "coupling": (str,),
        "percentiles": (list,),
    },
}


@contextmanager
def _readable(path: Path, what: str = "") -> Iterator[None]:
    """Turn the errors of reading a malformed ``path`` into :class:`CampaignError`."""
    try:
        yield
    except CampaignError:
        raise
    except _MALFORMED as e:
        where = f"{path}: {what}" if what else str(path)
        raise CampaignError(f"{where} is malformed ({type(e).__name__}: {e})") from None


def _check_settings(path: Path, name: str, kind: Any, settings: Any) -> dict[str, Any]:
    """The case's settings, checked against :data:`_SETTINGS` (CampaignError naming what)."""
    if kind not in _SETTINGS:
        raise CampaignError(
            f"{path}: case {name!r} is of kind {kind!r}; known kinds: {', '.join(_SETTINGS)}"
        )
    if not isinstance(settings, dict):
        raise CampaignError(
            f"{path}: case {name!r} has no settings (got {type(settings).__name__})"
        )
    for key, types in _SETTINGS[kind].items():
        if key not in settings:
            raise CampaignError(f"{path}: case {name!r}: its settings lack {key!r}")
        v = settings[key]
        if isinstance(v, bool) and bool not in types or not isinstance(v, types):
            raise CampaignError(
                f"{path}: case {name!r}: setting {key!r} = {v!r} is not of type "
                f"{' or '.join(t.__name__ for t in types)}"
            )
    return settings


def _attr(v: Any) -> Any:
    if isinstance(v, bytes):
        v = v.decode()
    if isinstance(v, np.generic):
        return v.item()
    return v


def _json(v: Any) -> Any:
    v = _attr(v)
    if isinstance(v, str) and v[:1] in "[{":
        return json.loads(v)
    return v


@dataclass(frozen=True)
class CaseEntry:
    """One case of a campaign as stored.

    Attributes
    ----------
    name : str
    kind : {"scatter", "truncation", "variants"}
    settings : dict
        Everything the case was computed with (harmonic, noise, target, rounds, seed ...).
    lines_done, n_lines : int
        Frequency lines stored and in all (truncation: 1 and 1 when done; variants: the
        variants and the nominal models stored and in all).
    complete : bool
    """

    name: str
    kind: str
    settings: dict[str, Any]
    lines_done: int
    n_lines: int

    @property
    def complete(self) -> bool:
        return self.lines_done == self.n_lines

    def label(self) -> str:
        s = self.settings
        if self.kind == "variants":
            return (
                f"variants {s['design']} n={s['n']} of "
                f"{', '.join(s['parameters'])}; h{','.join(map(str, s['harmonics']))} "
                f"{s['coupling']}"
            )
        if self.kind == "scatter":
            return (
                f"h{s['harmonic']} noise {100 * s['noise']:g} % {s['target']:<7s} "
                f"{'freq.-dep.' if s['frequency_dependent'] else 'fixed':<10s} "
                f"R={s['rounds']} {s['coupling']} tire={s['tire']} chassis={s['chassis']}"
            )
        return (
            f"h{s['harmonic']} truncation N={s['n_modes'][0]}..{s['n_modes'][-1]} "
            f"{s['coupling']} tire={s['tire']} chassis={s['chassis']}"
        )


@dataclass(frozen=True, eq=False)
class TruncationEntry:
    """A stored truncation case.

    Attributes
    ----------
    n_modes : ndarray of int, shape (n_N,)
    centres : ndarray, shape (n_c,)
    dofs : tuple of str, length n_dof
    error : ndarray, shape (n_N, n_c, n_dof)
        Eq. 5.1 error (absent when not in the outputs: None).
    suggested : ndarray of int, shape (n_t, n_fmax)
        Suggested mode counts for every threshold and upper frequency.
    thresholds, f_max : tuple of float
    map : TruncationMap or None
        The full map when the responses were stored.
    """

    n_modes: IntArray
    centres: FloatArray
    dofs: tuple[str, ...]
    error: FloatArray | None
    suggested: IntArray | None
    thresholds: tuple[float, ...]
    f_max: tuple[float, ...]
    map: TruncationMap | None


def _groups(h: Any, key: str, path: Path) -> list[tuple[str, Any]]:
    """The members of group ``h[key]`` (none when absent; CampaignError when not a group)."""
    import h5py

    if key not in h:
        return []
    g = h[key]
    if not isinstance(g, h5py.Group):
        raise CampaignError(f"{path}: {g.name!r} is not a group")
    return list(g.items())


class CampaignResult:
    """A campaign result file opened for reading (see :func:`open_campaign`)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:

        self.path = Path(path)
        self._store = CampaignStore(self.path)
        files = self._store.files()
        if not files:
            raise CampaignError(f"{self.path}: no campaign result file (nor parts of a run)")
        self.attrs: dict[str, Any] = {}
        self.runs: list[dict[str, Any]] = []
        cases: dict[str, dict[str, Any]] = {}
        self._where: dict[str, Path] = {}  # unit path -> file
        for p in files:
            with read_file(p) as h, _readable(p):
                if p == self.path:
                    if h.attrs.get("content") != "campaign":
                        raise CampaignError(f"{p}: not a campaign result file")
                    self.attrs = {k: _attr(v) for k, v in h.attrs.items()}
                for name, g in _groups(h, "cases", p):
                    with _readable(p, f"case {name!r}"):
                        d = cases.setdefault(name, {"attrs": {}, "blocks": {}, "result": None})
                        for k, v in g.attrs.items():
                            d["attrs"].setdefault(k, _json(v))
                        for b, _ in _groups(g, "blocks", p):
                            a, z = (int(x) for x in b.split("_"))
                            if not 0 <= a < z:
                                raise ValueError(f"block {b!r} is not a range of lines")
                            d["blocks"].setdefault((a, z), p)
                        if "result" in g:
                            d["result"] = p
                        for t, u in _groups(g, "tires", p):  # a variants study's tasks
                            d.setdefault("tires", {}).setdefault(t, int(u.attrs.get("n_rows", 0)))
                        if "nominal" in g:
                            d["tires"] = d.get("tires", {}) | {"": 1}
                for name, _ in _groups(h, "inputs", p):
                    self._where.setdefault(f"inputs/{name}", p)
                for name, g in _groups(h, "runs", p):
                    with _readable(p, f"run {name!r}"):
                        self.runs.append({k: _json(v) for k, v in g.attrs.items()} | {"id": name})
        self._cases = cases
        entries = []
        for name, d in sorted(cases.items()):
            a = d["attrs"]
            with _readable(self.path, f"case {name!r}"):
                st = _check_settings(self.path, name, a.get("kind"), a.get("settings"))
                if a.get("kind") == "scatter":
                    n = int(a.get("n_lines", 0))
                    got = sum(z - x for x, z in d["blocks"])
                    if n < 1 or got > n:
                        raise CampaignError(
                            f"{self.path}: case {name!r} has {got} of n_lines = {n} lines stored"
                        )
                elif a.get("kind") == "variants":  # the variants and the nominal models
                    n = int(a.get("n_variants", 0)) + 1
                    got = sum(d.get("tires", {}).values())
                    if n < 2 or got > n:
                        raise CampaignError(
                            f"{self.path}: case {name!r} has {got} of {n} variants "
                            "(with the nominal models) stored"
                        )
                else:
                    n, got = 1, int(d["result"] is not None)
            entries.append(CaseEntry(name, str(a.get("kind")), dict(st), got, n))
        self.cases: tuple[CaseEntry, ...] = tuple(entries)
        self.runs.sort(key=lambda r: str(r.get("started", "")))

    def __repr__(self) -> str:
        return f"CampaignResult({str(self.path)!r}, {len(self.cases)} cases)"

    @property
    def campaign_toml(self) -> str:
        """The text of the campaign file the result was made with."""
        return str(self.attrs.get("campaign_toml", ""))

    def case(self, name: str) -> CaseEntry:
        for c in self.cases:
            if c.name == name:
                return c
        raise CampaignError(
            f"no case {name!r} in {self.path}; cases: {', '.join(c.name for c in self.cases)}"
        )

    def case_attrs(self, name: str) -> dict[str, Any]:
        """Everything stored about a case (its settings, ``digest``, ``inputs`` ...)."""
        self.case(name)  # an unknown name: CampaignError listing the cases
        return dict(self._cases[name]["attrs"])

    def find(self, **settings: Any) -> tuple[CaseEntry, ...]:
        """The cases whose settings match all given values (e.g. ``harmonic=4, noise=0.1``)."""
        return tuple(
            c for c in self.cases if all(c.settings.get(k) == v for k, v in settings.items())
        )

    def _inputs(self, name: str) -> tuple[dict[str, AnyArray], tuple[str, ...]]:

        p = self._where.get(f"inputs/{name}")
        if p is None:
            raise CampaignError(f"{self.path}: the subsystem arrays {name!r} are missing")
        with _readable(p, f"subsystem arrays {name!r}"), read_file(p) as h:
            g = h["inputs"][name]
            arr = {k: g[k][()] for k in ("freq", "YjjA", "vj", "YjjE", "YejE", "reference")}
            dofs = tuple(str(x) for x in _json(g.attrs["dofs"]))
        return arr, dofs

    def band(self, name: str) -> ScatterBand:
        """The :class:`~fbs_core.ScatterBand` of a complete scatter case.

        Raises
        ------
        CampaignError
            For an unknown, truncation or incomplete case, or one stored without its
            band edges (``[outputs] scatter``).
        """

        from .work import BLOCK_KEYS

        c = self.case(name)
        if c.kind != "scatter":
            raise CampaignError(f"case {name} is a {c.kind} case, not a scatter band")
        if not c.complete:
            raise CampaignError(
                f"case {name} is not complete: {c.lines_done} of {c.n_lines} lines; "
                "rerun the campaign to finish it"
            )
        d = self._cases[name]
        st = c.settings
        with _readable(self.path, f"case {name!r}"):
            arr, dofs = self._inputs(str(d["attrs"]["inputs"]))
        blocks = []
        for (a, z), p in sorted(d["blocks"].items()):
            with _readable(p, f"case {name!r} block {a}_{z}"), read_file(p) as h:
                g = h["cases"][name]["blocks"][f"{a}_{z}"]
                b = {k: (g[k][()] if k in g else None) for k in (*BLOCK_KEYS, "checkpoints")}
            blocks.append(b | {"l0": a, "l1": z})
        if any(b["lower"] is None for b in blocks):
            raise CampaignError(f"case {name} was stored without its band ([outputs] scatter)")
        with _readable(self.path, f"case {name!r} (its band)"):
            return self._assemble(arr, dofs, blocks, st)

    @staticmethod
    def _assemble(
        arr: dict[str, AnyArray],
        dofs: tuple[str, ...],
        blocks: list[dict[str, Any]],
        st: dict[str, Any],
    ) -> ScatterBand:
        from .work import assemble_band

        n = np.asarray(arr["freq"]).shape[0]
        for b in blocks:
            for k in ("lower", "upper"):
                shape = np.shape(b[k])
                if len(shape) != 2 or shape[0] != b["l1"] - b["l0"] or shape[1] != len(dofs):
                    raise ValueError(
                        f"block {b['l0']}_{b['l1']} {k!r} has shape {shape}, expected "
                        f"({b['l1'] - b['l0']}, {len(dofs)})"
                    )
        if blocks[-1]["l1"] != n:
            raise ValueError(f"the blocks end at line {blocks[-1]['l1']} of {n}")
        band: ScatterBand = assemble_band(
            arr["freq"],
            dofs,
            arr["reference"],
            arr["YjjA"],
            arr["vj"],
            arr["YjjE"],
            arr["YejE"],
            blocks,
            q=st["percentiles"],
            noise=st["noise"],
            target=st["target"],
            rounds=st["rounds"],
            frequency_dependent=st["frequency_dependent"],
            seed=st["seed"],
            harmonic=st["harmonic"],
        )
        return band

    def variants(self, name: str) -> VariantStudy:
        """The :class:`~fbs_core.variants.VariantStudy` of a complete variants case: the
        design and every variant's response (its corridor and sensitivities follow).

        Raises
        ------
        CampaignError
            For an unknown, other or incomplete case.
        """
        from .variants import study_from_file

        c = self.case(name)
        if c.kind != "variants":
            raise CampaignError(f"case {name} is a {c.kind} case, not a variants study")
        if not c.complete:
            raise CampaignError(
                f"case {name} is not complete: {c.lines_done} of {c.n_lines} variants "
                "(and the nominal models); rerun the campaign to finish it"
            )
        with _readable(self.path, f"case {name!r}"):
            return study_from_file(self.path, name)

    def truncation(self, name: str) -> TruncationEntry:
        """The stored truncation case (error map, suggested modes, the map when stored)."""
        c = self.case(name)
        if c.kind != "truncation":
            raise CampaignError(f"case {name} is a {c.kind} case, not a truncation case")
        if not c.complete:
            raise CampaignError(f"case {name} is not computed yet; rerun the campaign")
        p = self._cases[name]["result"]
        with _readable(p, f"case {name!r} (its map)"):
            return self._truncation(p, name, c)

    def _truncation(self, p: Path, name: str, c: CaseEntry) -> TruncationEntry:

        from ..studies.truncation import TruncationMap

        with read_file(p) as h:
            g = h["cases"][name]["result"]
            get = {k: g[k][()] for k in g}
            at = {k: _json(v) for k, v in g.attrs.items()}
        dofs = tuple(str(x) for x in at["dofs"])
        n_n, n_c = np.shape(get["n_modes"])[0], np.shape(get["centres"])[0]
        want = (n_n, n_c, len(dofs))
        if "error" in get and np.shape(get["error"]) != want:
            raise ValueError(f"'error' has shape {np.shape(get['error'])}, expected {want}")
        sugg = (len(at["thresholds"]), len(at["f_max"]))
        if "suggested" in get and np.shape(get["suggested"]) != sugg:
            raise ValueError(f"'suggested' has shape {np.shape(get['suggested'])}, expected {sugg}")
        m = None
        if "response" in get and "error" in get:
            m = TruncationMap(
                harmonic=int(c.settings["harmonic"]),
                n_modes=get["n_modes"],
                n_modes_total=int(at["n_modes_total"]),
                centres=get["centres"],
                dofs=dofs,
                error=get["error"],
                freq=get["freq"],
                response=get["response"],
                reference=get["reference"],
                width=float(at["width"]),
                step=float(at["step"]),
                edges=str(at["edges"]),
            )
        return TruncationEntry(
            get["n_modes"],
            get["centres"],
            dofs,
            get.get("error"),
            get.get("suggested"),
            tuple(at["thresholds"]),
            tuple(at["f_max"]),
            m,
        )

    def planned(self) -> tuple[str, ...] | None:
        """Names of all the cases of the campaign file stored in the result (None when it
        cannot be read back, e.g. a model file of it has moved)."""
        from .spec import parse_campaign

        try:
            return tuple(c.name for c in parse_campaign(self.campaign_toml, self.path.parent).cases)
        except CampaignError:
            return None

    def headline(self, planned: bool = True) -> str:
        """The first line of :meth:`summary`: cases complete, partial and not started
        (``planned=False``: of the cases stored, without reading the campaign's TOML)."""
        name = self.attrs.get("campaign_name", self.path.stem)
        done = sum(c.complete for c in self.cases)
        names = self.planned() if planned else None
        total = len(self.cases) if names is None else len(set(names) | {c.name for c in self.cases})
        partial = sum(0 < c.lines_done < c.n_lines for c in self.cases)
        return (
            f"campaign {name!r}: {done} of {total} cases complete, {partial} partial, "
            f"{total - len(self.cases)} not started ({self.path})"
        )

    def summary(self) -> str:
        """One line per case (status, settings, band width or suggested modes)."""
        out = [self.headline()]
        if self.runs:
            r = self.runs[-1]
            out.append(
                f"last run {r.get('started')}: {r.get('status')}, {r.get('tasks_done')} tasks in "
                f"{float(r.get('seconds', 0)):.1f} s on {r.get('workers')} worker(s) "
                f"({r.get('scheduler')})"
            )
        for c in self.cases:
            unit = "variants" if c.kind == "variants" else "lines"
            status = "done" if c.complete else f"{c.lines_done}/{c.n_lines} {unit}"
            extra = ""
            if c.kind == "truncation" and c.complete:
                t = self.truncation(c.name)
                if t.suggested is not None:
                    extra = "  suggested N: " + ", ".join(
                        f"{100 * th:g}%/{fm:g}Hz={int(t.suggested[i, j])}"
                        for i, th in enumerate(t.thresholds)
                        for j, fm in enumerate(t.f_max)
                    )
            out.append(f"  {status:>12s}  {c.label()}  seed={c.settings.get('seed', '-')}{extra}")
        return "\n".join(out)


def open_campaign(path: str | os.PathLike[str]) -> CampaignResult:
    """Open a campaign result file (and the parts of an unfinished run) for browsing.

    Raises
    ------
    CampaignError
        When neither the file nor parts exist, or it is not a campaign result file.
    """
    return CampaignResult(path)
