"""Browsing a campaign result file: its cases, their bands and maps, its provenance.

:func:`open_campaign` reads the result file together with the parts of a run that has not
committed yet (a running or killed campaign is browsable too). Bands come back as
:class:`~fbs_core.ScatterBand` objects, equal to those of :func:`fbs_core.scatter_band`
with the case's seed, including :meth:`~fbs_core.ScatterBand.round` (the subsystem
arrays are in the file); truncation cases as :class:`~fbs_core.TruncationMap` (when the
responses were stored) or as the error map alone.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._typing import AnyArray, FloatArray, IntArray
from .spec import CampaignError
from .store import CampaignStore

if TYPE_CHECKING:
    from ..studies.scatter import ScatterBand
    from ..studies.truncation import TruncationMap

__all__ = ["open_campaign", "CampaignResult", "CaseEntry", "TruncationEntry"]


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
    kind : {"scatter", "truncation"}
    settings : dict
        Everything the case was computed with (harmonic, noise, target, rounds, seed ...).
    lines_done, n_lines : int
        Frequency lines stored and in all (truncation: 1 and 1 when done).
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


class CampaignResult:
    """A campaign result file opened for reading (see :func:`open_campaign`)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        import h5py

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
            try:
                h = h5py.File(p, "r")
            except OSError as e:
                raise CampaignError(f"{p}: not a readable HDF5 file ({e})") from None
            with h:
                if p == self.path:
                    if h.attrs.get("content") != "campaign":
                        raise CampaignError(f"{p}: not a campaign result file")
                    self.attrs = {k: _attr(v) for k, v in h.attrs.items()}
                for name, g in h.get("cases", {}).items():
                    d = cases.setdefault(name, {"attrs": {}, "blocks": {}, "result": None})
                    for k, v in g.attrs.items():
                        d["attrs"].setdefault(k, _json(v))
                    for b in g.get("blocks", {}):
                        a, z = (int(x) for x in b.split("_"))
                        d["blocks"].setdefault((a, z), p)
                    if "result" in g:
                        d["result"] = p
                for name in h.get("inputs", {}):
                    self._where.setdefault(f"inputs/{name}", p)
                for name, g in h.get("runs", {}).items():
                    self.runs.append({k: _json(v) for k, v in g.attrs.items()} | {"id": name})
        self._cases = cases
        entries = []
        for name, d in sorted(cases.items()):
            a = d["attrs"]
            st = dict(a.get("settings") or {})
            if a.get("kind") == "scatter":
                n = int(a.get("n_lines", 0))
                got = sum(z - x for x, z in d["blocks"])
            else:
                n, got = 1, int(d["result"] is not None)
            entries.append(CaseEntry(name, str(a.get("kind")), st, got, n))
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
        import h5py

        p = self._where.get(f"inputs/{name}")
        if p is None:
            raise CampaignError(f"{self.path}: the subsystem arrays {name!r} are missing")
        with h5py.File(p, "r") as h:
            g = h["inputs"][name]
            arr = {k: g[k][()] for k in ("freq", "YjjA", "vj", "YjjE", "YejE", "reference")}
            dofs = tuple(_json(g.attrs["dofs"]))
        return arr, dofs

    def band(self, name: str) -> ScatterBand:
        """The :class:`~fbs_core.ScatterBand` of a complete scatter case.

        Raises
        ------
        CampaignError
            For an unknown, truncation or incomplete case, or one stored without its
            band edges (``[outputs] scatter``).
        """
        import h5py

        from .work import BLOCK_KEYS, assemble_band

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
        arr, dofs = self._inputs(d["attrs"]["inputs"])
        blocks = []
        for (a, z), p in sorted(d["blocks"].items()):
            with h5py.File(p, "r") as h:
                g = h["cases"][name]["blocks"][f"{a}_{z}"]
                b = {k: (g[k][()] if k in g else None) for k in (*BLOCK_KEYS, "checkpoints")}
            blocks.append(b | {"l0": a, "l1": z})
        if any(b["lower"] is None for b in blocks):
            raise CampaignError(f"case {name} was stored without its band ([outputs] scatter)")
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

    def truncation(self, name: str) -> TruncationEntry:
        """The stored truncation case (error map, suggested modes, the map when stored)."""
        import h5py

        from ..studies.truncation import TruncationMap

        c = self.case(name)
        if c.kind != "truncation":
            raise CampaignError(f"case {name} is a {c.kind} case, not a truncation case")
        if not c.complete:
            raise CampaignError(f"case {name} is not computed yet; rerun the campaign")
        p = self._cases[name]["result"]
        with h5py.File(p, "r") as h:
            g = h["cases"][name]["result"]
            get = {k: g[k][()] for k in g}
            at = {k: _json(v) for k, v in g.attrs.items()}
        dofs = tuple(at["dofs"])
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

    def summary(self) -> str:
        """One line per case (status, settings, band width or suggested modes)."""
        name = self.attrs.get("campaign_name", self.path.stem)
        done = sum(c.complete for c in self.cases)
        planned = self.planned()
        total = (
            len(self.cases) if planned is None else len(set(planned) | {c.name for c in self.cases})
        )
        partial = sum(0 < c.lines_done < c.n_lines for c in self.cases)
        out = [
            f"campaign {name!r}: {done} of {total} cases complete, {partial} partial, "
            f"{total - len(self.cases)} not started ({self.path})"
        ]
        if self.runs:
            r = self.runs[-1]
            out.append(
                f"last run {r.get('started')}: {r.get('status')}, {r.get('tasks_done')} tasks in "
                f"{float(r.get('seconds', 0)):.1f} s on {r.get('workers')} worker(s) "
                f"({r.get('scheduler')})"
            )
        for c in self.cases:
            status = "done" if c.complete else f"{c.lines_done}/{c.n_lines} lines"
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
