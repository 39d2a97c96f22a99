"""Browse a campaign's result file: its cases, and one case's band or error map.

The files come from a server-side directory the operator trusts, ``FBS_CAMPAIGN_DIR``
(the campaigns' ``output`` files, e.g. a volume the campaign runs write to): its ``*.h5``
files are listed in a selector and opened with :func:`fbs_core.campaign.open_campaign`
(together with the parts of a run still going on). Nothing is uploaded: an HDF5 file from a
browser is never opened in the server process (see ``fbs_core.io``'s sandbox), and a
campaign file holds many cases, so it belongs on the server's disk anyway.

The view lists the cases (harmonic, noise, target, frequency dependence, truncation range,
tire and chassis variants, coupling, rounds, seed, status) with filters, and shows the
chosen case: a scatter case's band at one bushing DOF (reference, min/max, percentiles; thesis
5.2) or a truncation case's error map (eq. 5.1) with its suggested mode counts (table 5.1),
both with their provenance (campaign, seeds, case digest, where and with what it ran) and a
CSV export whose header carries the same provenance.

The numbers are the file's: the band is :meth:`CampaignResult.band` (the stored blocks
joined), the map :meth:`CampaignResult.truncation`; nothing is recomputed.

A page costs no file access: the card's browser opens nothing until the card is expanded
(:meth:`CampaignBrowser.activate`), the list of campaign files and each opened file are
kept per process and read again only when a file changes (:func:`open_cached`: size and
modification time), and a file is read on a thread of its own while the card says so. A
malformed file is a message in the card naming the file and the
problem (:class:`~fbs_core.campaign.CampaignError`), never an error of the page.
"""

from __future__ import annotations

import html
import logging
import os
import threading
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np
import panel as pn
import param
from bokeh.models import ColorBar, ColumnDataSource, LinearColorMapper
from bokeh.plotting import figure

from fbs_core.campaign import CampaignError, CampaignResult, open_campaign
from fbs_core.vocabulary import DIRECTIONS, magnitude_db, percent

from ..results import Result
from ..runtime.draw import served_document
from .common import COLORS, FREQ_LABEL, MODES_LABEL, level_label
from .live import download_button, inline_html

__all__ = [
    "CAMPAIGN_DIR_ENV",
    "HOW_TO",
    "CampaignBrowser",
    "campaign_dir",
    "campaign_card",
    "case_rows",
    "list_campaigns",
    "variants_case_result",
]

log = logging.getLogger(__name__)

CAMPAIGN_DIR_ENV = "FBS_CAMPAIGN_DIR"
#: Opened campaign files kept per process (their case tables with them).
CACHED_FILES = 4
ALL = "all"
STATUSES = (ALL, "complete", "partial")
KINDS = (ALL, "scatter", "truncation", "variants")


def campaign_dir() -> Path | None:
    """The configured campaign directory (``$FBS_CAMPAIGN_DIR``), None when unset."""
    raw = os.environ.get(CAMPAIGN_DIR_ENV, "").strip()
    return Path(raw).resolve() if raw else None


#: path -> ((mtime_ns, size), is a campaign result)
_IS_CAMPAIGN: dict[Path, tuple[tuple[int, int], bool]] = {}


def _stamp(p: Path) -> tuple[int, int]:
    st = p.stat()
    return st.st_mtime_ns, st.st_size


def _is_campaign(p: Path) -> bool:
    """Whether ``p``'s root says it is a campaign result (read again only when it changed)."""
    from fbs_core.hdf5_guard import ForeignDataError, open_h5

    stamp = _stamp(p)
    known = _IS_CAMPAIGN.get(p)
    if known is not None and known[0] == stamp:
        return known[1]
    try:
        with open_h5(p) as h:
            ok = h.attrs.get("content") == "campaign"
    except ForeignDataError:  # listed: opening it says why it is refused
        ok = True
    except (OSError, ValueError, TypeError, KeyError, RuntimeError):  # not (readable) HDF5
        ok = False
    _IS_CAMPAIGN[p] = (stamp, ok)
    return ok


def list_campaigns(directory: Path | None) -> list[str]:
    """Names of the campaign result files directly in ``directory`` (sorted).

    Only regular ``*.h5`` files inside the directory (a link pointing elsewhere is left
    out) whose root says it is a campaign result; a file is opened for that only when it is
    new or changed since it was last looked at.
    """
    if directory is None or not directory.is_dir():
        return []
    out = []
    for p in sorted(directory.glob("*.h5")):
        try:
            if p.is_file() and p.resolve().parent == directory and _is_campaign(p):
                out.append(p.name)
        except OSError:  # removed meanwhile
            continue
    return out


class Opened:
    """A campaign file as the browser shows it: the result, its case table, its first line."""

    def __init__(self, result: CampaignResult) -> None:
        self.result = result
        self.rows = case_rows(result)
        self.headline = result.headline(planned=False)


_OPENED: OrderedDict[tuple, Opened | CampaignError] = OrderedDict()
_OPENING: dict[tuple, threading.Lock] = {}
_OPEN_LOCK = threading.Lock()


def _file_key(path: Path) -> tuple:
    """The file and the parts of a run not merged yet, with their sizes and times."""
    from fbs_core.campaign.store import CampaignStore

    try:
        files = CampaignStore(path).files()
        return (str(path), *((str(p), *_stamp(p)) for p in files))
    except OSError as exc:
        return (str(path), "unreadable", str(exc))


def open_cached(path: Path) -> Opened:
    """:class:`Opened` of the campaign file ``path``, read once per change of the file.

    Sessions opening the same file at once wait for one reading; a malformed file's
    :class:`CampaignError` is kept too (not read again until the file changes).

    Raises
    ------
    CampaignError
        For a file that cannot be used, naming the file and the problem.
    """
    key = _file_key(path)
    with _OPEN_LOCK:
        lock = _OPENING.setdefault(key, threading.Lock())
    with lock:
        with _OPEN_LOCK:
            got = _OPENED.get(key)
        if got is None:
            try:
                got = Opened(open_campaign(path))
            except CampaignError as exc:
                got = exc
            except Exception as exc:  # noqa: BLE001 (the card must say it, not the page fail)
                log.exception("campaign file %s", path)
                got = CampaignError(f"{path}: cannot be read ({type(exc).__name__}: {exc})")
            with _OPEN_LOCK:
                _OPENED[key] = got
                while len(_OPENED) > CACHED_FILES:
                    _OPENED.popitem(last=False)
        with _OPEN_LOCK:
            _OPENING.pop(key, None)
            if key in _OPENED:
                _OPENED.move_to_end(key)
    if isinstance(got, CampaignError):
        raise got
    return got


def _truncation_label(s: dict) -> str:
    n = s.get("n_modes")
    return f"N = {n[0]}..{n[-1]} ({len(n)})" if isinstance(n, list) and n else ""


def case_rows(result) -> dict[str, list]:
    """The case table of a :class:`~fbs_core.campaign.CampaignResult`, one row per case.

    Raises
    ------
    CampaignError
        For a case whose settings cannot be shown (naming the file and the case).
    """
    cols: dict[str, list] = {
        k: []
        for k in (
            "case",
            "kind",
            "harmonic",
            "noise_pct",
            "target",
            "freq_dependent",
            "truncation",
            "tire",
            "chassis",
            "coupling",
            "rounds",
            "seed",
            "design",
            "status",
        )
    }
    for c in result.cases:
        try:
            row = _case_row(c)
        except (KeyError, ValueError, TypeError, IndexError) as exc:
            raise CampaignError(
                f"{result.path}: case {c.name!r} cannot be shown ({type(exc).__name__}: {exc})"
            ) from None
        for k, v in row.items():
            cols[k].append(v)
    return cols


def _parameters_of(s: dict, model: str) -> str:
    """The varied parameters of a variants case that belong to ``model`` (comma list), and
    "base changed" when the case replaces the reference's base parameters."""
    from fbs_core.variants import PARAMETERS

    names = [n for n in s.get("parameters", ()) if n in PARAMETERS and PARAMETERS[n].model == model]
    text = ", ".join(names)
    if s.get(model):
        text = f"{text}; base changed" if text else "base changed"
    return text


def _variants_row(c) -> dict[str, Any]:
    """A variants case in the table's columns: its harmonics, the varied tire and
    chassis parameters, its design and size."""
    s = c.settings
    n_variants = c.n_lines - 1 if c.n_lines else 0  # the nominal models are one unit
    return {
        "case": c.name,
        "kind": c.kind,
        "harmonic": ", ".join(str(int(h)) for h in s["harmonics"]),
        "noise_pct": None,
        "target": "",
        "freq_dependent": None,
        "truncation": "",
        "tire": _parameters_of(s, "tire"),
        "chassis": _parameters_of(s, "chassis"),
        "coupling": str(s.get("coupling", "")),
        "rounds": None,
        "seed": str(s.get("seed", "")),
        "design": f"{s['design']} n={s['n']} ({n_variants} variants)",
        "status": "complete"
        if c.complete
        else f"partial ({c.lines_done}/{c.n_lines} variants and nominal)",
    }


def _case_row(c) -> dict[str, Any]:
    s = c.settings
    if c.kind == "variants":
        return _variants_row(c)
    band = c.kind == "scatter"
    return {
        "case": c.name,
        "kind": c.kind,
        "harmonic": int(s.get("harmonic", 0)),
        "noise_pct": round(percent(float(s["noise"])), 6) if band else None,
        "target": str(s["target"]) if band else "",
        "freq_dependent": bool(s["frequency_dependent"]) if band else None,
        "truncation": "" if band else _truncation_label(s),
        "tire": str(s.get("tire", "")),
        "chassis": str(s.get("chassis", "")),
        "coupling": str(s.get("coupling", "")),
        "rounds": int(s["rounds"]) if band else None,
        "seed": str(s.get("seed", "")) if band else "",
        "design": "",
        "status": "complete" if c.complete else f"partial ({c.lines_done}/{c.n_lines} lines)",
    }


def _provenance(result, name: str) -> dict[str, Any]:
    """Where a case comes from: file, campaign, seeds, digest, the runs that made it."""
    c = result.case(name)
    a = result.attrs
    meta: dict[str, Any] = {
        "campaign file": result.path.name,
        "campaign": a.get("campaign_name", ""),
        "campaign seed": a.get("campaign_seed", ""),
        "seeds": a.get("seeds", ""),
        "case": name,
        "case digest": result.case_attrs(name).get("digest", ""),
    }
    meta.update({f"case {k}": v for k, v in c.settings.items() if k != "kind"})
    if result.runs:
        r = result.runs[-1]
        versions = r.get("versions") or {}
        meta["last run"] = (
            f"{r.get('started')} {r.get('status')}, {r.get('workers')} worker(s) at "
            f"{r.get('scheduler')}"
        )
        if isinstance(versions, dict):
            meta["versions"] = ", ".join(f"{k} {v}" for k, v in sorted(versions.items()))
    return meta


def scatter_case_result(result, name: str, dof: str) -> Result:
    """The band of a scatter case at ``bushing:dof``, as stored (magnitudes and dB)."""
    band = result.band(name)
    j = band.dofs.index(f"bushing:{dof}")
    ref = np.abs(band.reference[:, j])
    cols = {
        "freq_Hz": np.asarray(band.freq),
        "reference": ref,
        "minimum": np.asarray(band.minimum[:, j]),
        "maximum": np.asarray(band.maximum[:, j]),
    }
    for k, q in enumerate(band.q):
        cols[f"p{q:g}"] = np.asarray(band.percentiles[k, :, j])
    db = {f"{k}_dB": magnitude_db(v) for k, v in cols.items() if k != "freq_Hz"}
    meta = {
        "view": "campaign scatter band (thesis 5.2)",
        "response DOF": f"bushing:{dof}",
        "columns": "magnitudes |v_e| and their levels in dB",
        **_provenance(result, name),
    }
    s = result.case(name).settings
    return Result(
        columns={**cols, **db},
        meta=meta,
        filename=f"{Path(result.path).stem}_{name}_{dof}.csv",
        caption=(
            f"**{name}** &middot; bushing:{dof} &middot; noise {percent(s['noise']):g} % in "
            f"{s['target']} &middot; {s['rounds']:,} rounds &middot; seed {s['seed']}"
        ),
        draw={"kind": "scatter", "dof": dof, "q": tuple(float(q) for q in band.q)},
    )


def variants_case_result(result, name: str, dof: str, harmonic: int | None = None) -> Result:
    """The corridor of a variants case at ``bushing:dof`` over its nominal response, and the
    per-band leaders of its Sobol' indices (a Saltelli design only; see
    docs/corridor.md).

    The numbers are those of :meth:`CampaignResult.variants`: the study as stored, its
    corridor at the case's percentiles and its sensitivity (:meth:`VariantStudy.corridor`,
    :meth:`VariantStudy.sensitivity`); ``harmonic`` None: the case's first harmonic.
    """
    study = result.variants(name)
    s = result.case(name).settings
    harmonics = [int(h) for h in s["harmonics"]]
    h = harmonics[0] if harmonic is None else int(harmonic)
    if h not in harmonics:
        raise CampaignError(
            f"case {name} has no harmonic {h}; computed: {', '.join(map(str, harmonics))}"
        )
    pct = tuple(float(q) for q in s["percentiles"])
    c = study.corridor(h, percentiles=pct)
    label = f"bushing:{dof}"
    j = c.dof_index(label)
    cols: dict[str, np.ndarray] = {
        "freq_Hz": np.asarray(c.freq),
        "nominal": np.abs(c.nominal[:, j]),
        "minimum": np.asarray(c.minimum[:, j]),
        "maximum": np.asarray(c.maximum[:, j]),
    }
    for k, q in enumerate(c.q):
        cols[f"p{q:g}"] = np.asarray(c.percentiles[k, :, j])
    db = {f"{k}_dB": magnitude_db(v) for k, v in cols.items() if k != "freq_Hz"}
    leaders: list[dict[str, Any]] = []
    if s["design"] == "saltelli":
        leaders = study.sensitivity(h).leaders(label)
        ranking = "; ".join(
            f"{r['band_low']:.0f}-{r['band_high']:.0f} Hz: {r['parameter']} "
            f"(S_T {r['total']:.2f}, then {r['second'] or '-'}, {r['std_db']:.1f} dB)"
            for r in leaders
        )
    else:
        ranking = f"none ({s['design']} design: Sobol' indices need a Saltelli design)"
    params = ", ".join(s["parameters"])
    pct_text = ", ".join(f"{q:g}" for q in c.q)
    meta = {
        "view": "campaign corridor of systematic errors (docs/corridor.md)",
        "response DOF": label,
        "harmonic": h,
        "parameters": params,
        "design": f"{s['design']} n={s['n']} ({c.n_variants} variants), seed {s['seed']}",
        "percentiles": pct_text,
        "columns": "magnitudes |v_e| over the variants (and the nominal models) and dB",
        "sensitivity leaders (total Sobol' index per band)": ranking,
        **_provenance(result, name),
    }
    return Result(
        columns={**cols, **db},
        meta=meta,
        filename=f"{Path(result.path).stem}_{name}_h{h}_{dof}.csv",
        caption=(
            f"**{name}** &middot; {result.path.name} &middot; harmonic {h} &middot; "
            f"{label} &middot; {c.n_variants} variants of {params} &middot; "
            f"percentiles {pct_text} %"
        ),
        draw={
            "kind": "variants",
            "dof": dof,
            "q": tuple(float(q) for q in c.q),
            "leaders": leaders,
        },
        core={"corridor": c},
    )


def truncation_case_result(result, name: str, dof: str | None) -> Result:
    """The error map of a truncation case (``dof`` None: max over the DOFs) and its
    suggested mode counts, as stored."""
    t = result.truncation(name)
    if t.error is None:
        raise CampaignError(f"case {name} was stored without its error map ([outputs])")
    if dof is None:
        err = np.max(t.error, axis=2)
        what = "max over DOFs"
    else:
        err = t.error[:, :, t.dofs.index(f"bushing:{dof}")]
        what = f"bushing:{dof}"
    nn, ff = np.meshgrid(t.n_modes, t.centres, indexing="ij")
    sugg = {}
    if t.suggested is not None:
        for i, th in enumerate(t.thresholds):
            for k, fm in enumerate(t.f_max):
                sugg[f"{percent(th):g} % up to {fm:g} Hz"] = int(t.suggested[i, k])
    meta = {
        "view": "campaign truncation error map (thesis eq. 5.1)",
        "response DOF": what,
        "layout": "long: one row per (N, centre freq)",
        "suggested N (max over DOFs)": "; ".join(f"{k}: {v}" for k, v in sugg.items()),
        **_provenance(result, name),
    }
    return Result(
        columns={
            "n_modes": nn.ravel(),
            "centre_freq_Hz": ff.ravel(),
            "error_pct": percent(err.ravel()),
        },
        meta=meta,
        filename=f"{Path(result.path).stem}_{name}_{dof or 'maxdof'}.csv",
        caption=f"**{name}** &middot; {what}",
        draw={
            "kind": "truncation",
            "error_pct": percent(err),
            "n_modes": np.asarray(t.n_modes),
            "centres": np.asarray(t.centres),
            "suggested": sugg,
        },
    )


class CampaignBrowser(pn.viewable.Viewer):
    """The campaign files of ``directory``, their cases (filtered) and the chosen case."""

    directory = param.ClassSelector(class_=Path, allow_None=True, constant=True)
    file = param.Selector(default=None, objects=[], allow_None=True, doc="Campaign file")
    kind = param.Selector(default=ALL, objects=list(KINDS))
    harmonic = param.Selector(default=ALL, objects=[ALL, *range(1, 8)])
    noise = param.Selector(default=ALL, objects=[ALL], doc="Noise level (%)")
    target = param.Selector(default=ALL, objects=[ALL])
    status = param.Selector(default=ALL, objects=list(STATUSES))
    case = param.Selector(default=None, objects=[], allow_None=True)
    dof = param.Selector(default="z", objects=list(DIRECTIONS), doc="Bushing DOF")
    max_over_dofs = param.Boolean(default=False, doc="Error map: max over the 6 DOFs")
    shown = param.ClassSelector(class_=Result, allow_None=True, doc="The chosen case's view")
    message = param.String(default="")

    def __init__(self, directory: Path | None = None, lazy: bool = False, **params):
        params["directory"] = campaign_dir() if directory is None else Path(directory).resolve()
        super().__init__(**params)
        self._result: CampaignResult | None = None
        self._rows: dict[str, list] = {}
        self._lazy = lazy
        self._active = False
        self._build()
        if not lazy:
            self.activate()

    def activate(self) -> None:
        """List the campaign files and open the first one (once; a ``lazy`` browser waits
        for this until its card is expanded, so a page build reads no file)."""
        if self._active:
            return
        self._active = True
        files = list_campaigns(self.directory)
        self.param.file.objects = files
        if files:
            self.file = files[0]
        else:
            self.message = (
                f"No campaign result files in {self.directory}."
                if self.directory
                else f"No campaign directory configured (set {CAMPAIGN_DIR_ENV})."
            )

    # -- data ------------------------------------------------------------------------------
    @param.depends("file", watch=True)
    def _open(self) -> None:
        self._result = None
        if not self.file or self.directory is None:
            return
        file, path = self.file, self.directory / self.file
        doc = self._doc or served_document()
        if not self._lazy or doc is None:
            self._loaded(file, *_read(path))
            return
        # a large file takes seconds to read: on a thread of its own, not a worker of the
        # server's that other sessions need; the result is applied on the session's loop
        self.message = f"Reading {file} ..."

        def work():
            outcome = _read(path)
            doc.add_next_tick_callback(lambda: self._loaded(file, *outcome))

        threading.Thread(target=work, name="campaign-open", daemon=True).start()

    def _loaded(self, file: str, opened: Opened | None, error: str) -> None:
        if file != self.file:
            return  # another file was chosen meanwhile
        if opened is None:
            self.message = error
            self._result, self._rows = None, {}
            self._table.value = _frame({})
            self.param.case.objects = []
            self.case = None
            return
        self._result = opened.result
        self.message = opened.headline
        self._rows = opened.rows
        noises = sorted({v for v in self._rows["noise_pct"] if v is not None})
        targets = sorted({v for v in self._rows["target"] if v})
        with param.parameterized.batch_call_watchers(self):
            self.param.noise.objects = [ALL, *noises]
            self.param.target.objects = [ALL, *targets]
            self.param.update(noise=ALL, target=ALL, kind=ALL, harmonic=ALL, status=ALL)
            self.case = None  # a case of this file is shown, also one of the same name
        self._filter()

    def filtered(self) -> list[int]:
        """Indices of the rows that pass the filters."""
        r = self._rows
        out = []
        for i in range(len(r.get("case", []))):
            if self.kind != ALL and r["kind"][i] != self.kind:
                continue
            if self.harmonic != ALL and self.harmonic not in _harmonics(r["harmonic"][i]):
                continue
            if self.noise != ALL and r["noise_pct"][i] != self.noise:
                continue
            if self.target != ALL and r["target"][i] != self.target:
                continue
            if self.status != ALL and not r["status"][i].startswith(self.status):
                continue
            out.append(i)
        return out

    @param.depends("kind", "harmonic", "noise", "target", "status", watch=True)
    def _filter(self) -> None:
        idx = self.filtered()
        names = [self._rows["case"][i] for i in idx]
        self._table.value = _frame({k: [v[i] for i in idx] for k, v in self._rows.items()})
        self.param.case.objects = names
        if self.case not in names:
            self.case = names[0] if names else None

    @param.depends("case", "dof", "max_over_dofs", "harmonic", watch=True)
    def _show(self) -> None:
        if self._result is None or self.case is None:
            self.shown = None
            return
        try:
            c = self._result.case(self.case)
            if c.kind == "scatter":
                self.shown = scatter_case_result(self._result, self.case, self.dof)
            elif c.kind == "variants":
                # the harmonic filter picks one of the case's harmonics (else its first)
                hs = [int(h) for h in c.settings["harmonics"]]
                h = self.harmonic if self.harmonic in hs else None
                self.shown = variants_case_result(self._result, self.case, self.dof, h)
            else:
                dof = None if self.max_over_dofs else self.dof
                self.shown = truncation_case_result(self._result, self.case, dof)
        except CampaignError as exc:  # incomplete, stored without these outputs, malformed
            self.shown = None
            self.message = relative_names(str(exc), self.directory)
        except Exception as exc:  # noqa: BLE001 (a file's problem: said in the card)
            log.exception("campaign case %s of %s", self.case, self.file)
            self.shown = None
            self.message = relative_names(
                f"{self.file}: case {self.case!r} cannot be shown ({exc})", self.directory
            )

    # -- page ------------------------------------------------------------------------------
    def _build(self) -> None:
        self._table = pn.widgets.Tabulator(
            _frame({}),
            disabled=True,
            show_index=False,
            height=220,
            pagination=None,
            sizing_mode="stretch_width",
            css_classes=["campaign-cases"],
        )
        self._table.on_click(self._clicked)
        self._band_src = ColumnDataSource(
            {k: [] for k in ("freq", "ref", "lo", "hi", "qlo", "qhi")}, name="campaign.band"
        )
        fb = figure(
            height=300,
            sizing_mode="stretch_width",
            x_axis_label=FREQ_LABEL,
            y_axis_label=level_label("z"),
            tools="pan,wheel_zoom,box_zoom,reset,save",
        )
        fb.varea("freq", "lo", "hi", source=self._band_src, color=COLORS["band"], alpha=0.35)
        fb.line("freq", "qlo", source=self._band_src, color=COLORS["percentile"], dash="dashed")
        fb.line("freq", "qhi", source=self._band_src, color=COLORS["percentile"], dash="dashed")
        fb.line("freq", "ref", source=self._band_src, color=COLORS["reference"], line_width=2)
        self._band_fig = fb
        # a variants case: the corridor (min/max, outer percentiles) over the nominal response
        self._corridor_src = ColumnDataSource(
            {k: [] for k in ("freq", "nominal", "lo", "hi", "qlo", "qhi")},
            name="campaign.corridor",
        )
        fc = figure(
            height=300,
            sizing_mode="stretch_width",
            x_axis_label=FREQ_LABEL,
            y_axis_label=level_label("z"),
            tools="pan,wheel_zoom,box_zoom,reset,save",
        )
        src = self._corridor_src
        fc.varea(
            "freq",
            "lo",
            "hi",
            source=src,
            color=COLORS["band"],
            alpha=0.3,
            legend_label="corridor: min-max over the variants",
        )
        self._corridor_q = [
            fc.line(
                "freq",
                col,
                source=src,
                color=COLORS["percentile"],
                dash="dashed",
                legend_label="corridor: outer percentiles",
            )
            for col in ("qlo", "qhi")
        ]
        fc.line(
            "freq",
            "nominal",
            source=src,
            color=COLORS["reference"],
            line_width=2,
            legend_label="nominal models",
        )
        fc.legend.location = "bottom_left"
        fc.legend.click_policy = "hide"
        fc.visible = False
        self._corridor_fig = fc
        self._leaders = pn.widgets.Tabulator(
            _frame({}),
            disabled=True,
            show_index=False,
            pagination=None,
            visible=False,
            css_classes=["campaign-leaders"],
        )
        self._map_src = ColumnDataSource(
            {"image": [], "x": [], "y": [], "dw": [], "dh": []}, name="campaign.map"
        )
        self._mapper = LinearColorMapper(palette="Viridis256", low=0, high=100)
        fm = figure(
            height=300,
            sizing_mode="stretch_width",
            x_axis_label="Centre frequency (Hz)",
            y_axis_label=MODES_LABEL,
            tools="pan,wheel_zoom,box_zoom,reset,save",
        )
        fm.image("image", "x", "y", "dw", "dh", source=self._map_src, color_mapper=self._mapper)
        fm.add_layout(ColorBar(color_mapper=self._mapper, title="error (%)"), "right")
        self._map_fig = fm
        # the file's strings (case names, settings, provenance) stay text: HTML panes of
        # escaped text, never Markdown
        self._caption = pn.pane.HTML("", sizing_mode="stretch_width")
        self._prov = pn.pane.HTML("", styles={"font-size": "0.8em"})
        self._suggested = pn.pane.Markdown("")
        self._note = pn.pane.HTML(
            pn.bind(_text_html, self.param.message),
            styles={"font-size": "0.85em"},
            css_classes=["campaign-note"],
        )
        self._download = download_button("campaign", lambda: self.shown)
        self._doc = None
        self.param.watch(self._redraw, "shown")

    def _clicked(self, event) -> None:
        names = self._table.value["case"].tolist()
        if 0 <= event.row < len(names):
            self.case = names[event.row]

    def _redraw(self, *_) -> None:
        """Draw on the session's event loop when served (as :class:`LiveView` does)."""
        doc = self._doc
        if doc is None:
            self._draw()
        elif served_document() is doc:
            pn.state.execute(self._draw, schedule=True)
        else:
            doc.add_next_tick_callback(self._draw)

    def _draw(self) -> None:
        r = self.shown
        if r is None:
            self._caption.object = ""
            self._prov.object = ""
            return
        self._caption.object = f"<p>{inline_html(r.caption)}</p>"
        self._prov.object = "<ul>{}</ul>".format(
            "".join(
                f"<li><b>{html.escape(str(k))}</b>: {html.escape(str(v))}</li>"
                for k, v in r.meta.items()
            )
        )
        d = r.draw
        if d["kind"] == "scatter":
            c = r.columns
            qs = d["q"]
            self._band_src.data = {
                "freq": c["freq_Hz"],
                "ref": c["reference_dB"],
                "lo": c["minimum_dB"],
                "hi": c["maximum_dB"],
                "qlo": c[f"p{min(qs):g}_dB"] if qs else c["minimum_dB"],
                "qhi": c[f"p{max(qs):g}_dB"] if qs else c["maximum_dB"],
            }
            self._band_fig.yaxis.axis_label = level_label(d["dof"])
            self._band_fig.visible, self._map_fig.visible = True, False
            self._corridor_fig.visible = self._leaders.visible = False
            self._suggested.object = ""
        elif d["kind"] == "variants":
            c = r.columns
            qs = d["q"]
            self._corridor_src.data = {
                "freq": c["freq_Hz"],
                "nominal": c["nominal_dB"],
                "lo": c["minimum_dB"],
                "hi": c["maximum_dB"],
                "qlo": c[f"p{min(qs):g}_dB"] if qs else c["minimum_dB"],
                "qhi": c[f"p{max(qs):g}_dB"] if qs else c["maximum_dB"],
            }
            q_text = f"percentiles {min(qs):g} and {max(qs):g} %" if qs else "no percentiles"
            for line in self._corridor_q:
                line.visible = bool(qs)
            items = self._corridor_fig.legend[0].items
            if len(items) > 1:
                items[1].label = {"value": f"corridor: {q_text}"}
            self._corridor_fig.yaxis.axis_label = level_label(d["dof"])
            self._leaders.value = _frame(
                {
                    "band (Hz)": [
                        f"{x['band_low']:.0f}-{x['band_high']:.0f}" for x in d["leaders"]
                    ],
                    "leading parameter": [x["parameter"] for x in d["leaders"]],
                    "total index": [round(x["total"], 3) for x in d["leaders"]],
                    "runner-up": [x["second"] for x in d["leaders"]],
                    "level std (dB)": [round(x["std_db"], 2) for x in d["leaders"]],
                }
            )
            self._corridor_fig.visible = True
            self._leaders.visible = bool(d["leaders"])
            self._band_fig.visible = self._map_fig.visible = False
            self._suggested.object = (
                ""
                if d["leaders"]
                else "**Sensitivity**: none (Sobol' indices need a Saltelli design)"
            )
        else:
            e = d["error_pct"]
            n, f = d["n_modes"], d["centres"]
            dn = float(n[1] - n[0]) if n.size > 1 else 1.0
            df = float(f[1] - f[0]) if f.size > 1 else 1.0
            self._map_src.data = {
                "image": [np.asarray(e)],
                "x": [float(f[0]) - df / 2],
                "y": [float(n[0]) - dn / 2],
                "dw": [float(f[-1] - f[0]) + df],
                "dh": [float(n[-1] - n[0]) + dn],
            }
            self._mapper.high = float(max(1.0, np.nanpercentile(e, 95)))
            self._band_fig.visible, self._map_fig.visible = False, True
            self._corridor_fig.visible = self._leaders.visible = False
            self._suggested.object = "**Suggested N** (max over DOFs): " + (
                ", ".join(f"{k}: **{v}**" for k, v in d["suggested"].items()) or "not stored"
            )

    def __panel__(self):
        w = pn.widgets
        filters = pn.Row(
            w.Select.from_param(self.param.kind, name="Kind", width=110),
            w.Select.from_param(self.param.harmonic, name="Harmonic", width=90),
            w.Select.from_param(self.param.noise, name="Noise (%)", width=90),
            w.Select.from_param(self.param.target, name="Target", width=100),
            w.Select.from_param(self.param.status, name="Status", width=110),
        )
        choose = pn.Row(
            w.Select.from_param(self.param.case, name="Case", css_classes=["campaign-case"]),
            w.RadioButtonGroup.from_param(self.param.dof, name="DOF", width=260),
            w.Checkbox.from_param(self.param.max_over_dofs, name="Error map: max over DOFs"),
        )
        self._doc = served_document()
        self._draw()
        return pn.Column(
            w.Select.from_param(
                self.param.file, name="Campaign result file", css_classes=["campaign-file"]
            ),
            self._note,
            filters,
            self._table,
            choose,
            self._caption,
            self._band_fig,
            self._map_fig,
            pn.Row(self._corridor_fig, self._leaders, sizing_mode="stretch_width"),
            self._suggested,
            self._download,
            pn.Card(self._prov, title="Provenance", collapsed=True, sizing_mode="stretch_width"),
            sizing_mode="stretch_width",
        )


#: What the campaign card says when the server has no campaign directory: what corridors
#: and campaigns are, what a campaign file is, the commands that make a result file and the
#: setting that shows it here (the examples are the repository's ``campaigns/`` files).
HOW_TO = f"""**Corridors of systematic errors and sensitivity campaigns** (many cases: harmonics,
noise levels, truncations, or physical parameters of the tire and chassis varied within their
ranges) take minutes to hours, so they run outside the page and are browsed here from their
result files. **This server has no campaign folder set**, so there is nothing to show yet.

1. **A campaign file** is a TOML case matrix: the cases to compute and where to write the
   result (one HDF5 file). Examples in the repository: `campaigns/example.toml` (scatter bands
   and truncation maps), `campaigns/corridor.toml` (a corridor of systematic errors with
   Sobol' sensitivity per band).
2. **Run it** on the server's machine (or a Dask cluster, `FBS_DASK_SCHEDULER`):
   `python -m fbs_core.campaign plan campaigns/corridor.toml` lists what it will compute,
   `python -m fbs_core.campaign run campaigns/corridor.toml --workers 2` computes it with a
   progress bar (stopped with Ctrl-C, the same command resumes), and
   `python -m fbs_core.campaign corridor corridor.h5` prints the corridor's tables.
3. **Show the results here**: the operator starts the server with `{CAMPAIGN_DIR_ENV}` set to
   the folder of the result files (`{CAMPAIGN_DIR_ENV}=/path/to/results bash scripts/serve.sh`;
   with Docker, mount the folder and pass `-e {CAMPAIGN_DIR_ENV}=/campaigns`). This card then
   lists the files and draws each case's band, error map or corridor.

In Python: `fbs_core.variants.corridor_study(["inflation_pressure", "knuckle_mass"], n=4)`
(docs/corridor.md)."""


def campaign_card(parts):
    """The page's card of the campaign browser (an entry of ``app.main.EXTRA_CARDS``):
    collapsed, built with ``parts.card``. Without a campaign directory the card says how to
    get one (:data:`HOW_TO`): corridors and campaigns must be findable from the page.

    The browser reads nothing until the card is expanded (then it lists the files and opens
    the first, :meth:`CampaignBrowser.activate`)."""
    if campaign_dir() is None:
        return parts.card(
            "Corridors and campaigns (not set up on this server)",
            pn.pane.Markdown(HOW_TO, sizing_mode="stretch_width", css_classes=["campaign-howto"]),
            None,
            collapsed=True,
            css_classes=["campaign-card"],
        )
    browser = CampaignBrowser(lazy=True)
    card = parts.card(
        "Campaign results (FBS_CAMPAIGN_DIR)",
        browser,
        None,
        collapsed=True,
        css_classes=["campaign-card"],
    )

    def expanded(event):
        if not event.new:
            browser.activate()

    card.param.watch(expanded, "collapsed")
    # the shown case is in the session's report (a section of its own, from this Result)
    browser.param.watch(lambda e: parts.results.show_outside("campaign", e.new), "shown")
    card.browser = browser  # for tests
    return card


def _harmonics(cell: int | str) -> tuple[int, ...]:
    """The harmonics of a case's table cell (an int, or a variants case's "1, 4, 7")."""
    if isinstance(cell, str):
        return tuple(int(x) for x in cell.split(",") if x.strip())
    return (int(cell),)


def _text_html(text: str) -> str:
    """A message as HTML text (it may quote a file's strings)."""
    return f"<p>{html.escape(text)}</p>"


def relative_names(text: str, directory: Path | None) -> str:
    """``text`` with the campaign folder's path left out of the file names it quotes: a
    user sees ``run.h5`` or ``run.h5.parts/0001.h5``, never the server's absolute paths."""
    if directory is None:
        return text
    folder = str(directory).rstrip(os.sep)
    return text.replace(folder + os.sep, "").replace(folder, ".")


def _read(path: Path) -> tuple[Opened | None, str]:
    """(the opened file, "") or (None, the message of its CampaignError, its file names
    relative to the campaign folder)."""
    try:
        return open_cached(path), ""
    except CampaignError as exc:
        return None, relative_names(str(exc), path.parent)


def _frame(cols: dict[str, list]):
    import pandas as pd

    return pd.DataFrame(cols if cols else {"case": []})
