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
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import panel as pn
import param
from bokeh.models import ColorBar, ColumnDataSource, LinearColorMapper
from bokeh.plotting import figure

from fbs_core.campaign import CampaignError, CampaignResult, open_campaign
from fbs_core.vocabulary import DIRECTIONS, magnitude_db, percent

from ..store import Result
from .common import COLORS, FREQ_LABEL, MODES_LABEL, level_label
from .live import download_button, served_document

__all__ = [
    "CAMPAIGN_DIR_ENV",
    "CampaignBrowser",
    "campaign_dir",
    "campaign_card",
    "case_rows",
    "list_campaigns",
]

CAMPAIGN_DIR_ENV = "FBS_CAMPAIGN_DIR"
ALL = "all"
STATUSES = (ALL, "complete", "partial")
KINDS = (ALL, "scatter", "truncation")


def campaign_dir() -> Path | None:
    """The configured campaign directory (``$FBS_CAMPAIGN_DIR``), None when unset."""
    raw = os.environ.get(CAMPAIGN_DIR_ENV, "").strip()
    return Path(raw).resolve() if raw else None


def list_campaigns(directory: Path | None) -> list[str]:
    """Names of the campaign result files directly in ``directory`` (sorted).

    Only regular ``*.h5`` files inside the directory (a link pointing elsewhere is left
    out) whose root says it is a campaign result.
    """
    import h5py

    if directory is None or not directory.is_dir():
        return []
    out = []
    for p in sorted(directory.glob("*.h5")):
        if not p.is_file() or p.resolve().parent != directory:
            continue
        try:
            with h5py.File(p, "r") as h:
                if h.attrs.get("content") == "campaign":
                    out.append(p.name)
        except OSError:  # not HDF5: not a campaign
            continue
    return out


def _truncation_label(s: dict) -> str:
    n = s.get("n_modes")
    return f"N = {n[0]}..{n[-1]} ({len(n)})" if isinstance(n, list) and n else ""


def case_rows(result) -> dict[str, list]:
    """The case table of a :class:`~fbs_core.campaign.CampaignResult`, one row per case."""
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
            "status",
        )
    }
    for c in result.cases:
        s = c.settings
        band = c.kind == "scatter"
        cols["case"].append(c.name)
        cols["kind"].append(c.kind)
        cols["harmonic"].append(int(s.get("harmonic", 0)))
        cols["noise_pct"].append(round(percent(float(s["noise"])), 6) if band else None)
        cols["target"].append(str(s["target"]) if band else "")
        cols["freq_dependent"].append(bool(s["frequency_dependent"]) if band else None)
        cols["truncation"].append("" if band else _truncation_label(s))
        cols["tire"].append(str(s.get("tire", "")))
        cols["chassis"].append(str(s.get("chassis", "")))
        cols["coupling"].append(str(s.get("coupling", "")))
        cols["rounds"].append(int(s["rounds"]) if band else None)
        cols["seed"].append(str(s.get("seed", "")) if band else "")
        cols["status"].append(
            "complete" if c.complete else f"partial ({c.lines_done}/{c.n_lines} lines)"
        )
    return cols


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

    def __init__(self, directory: Path | None = None, **params):
        params["directory"] = campaign_dir() if directory is None else Path(directory).resolve()
        super().__init__(**params)
        self._result: CampaignResult | None = None
        self._rows: dict[str, list] = {}
        files = list_campaigns(self.directory)
        self.param.file.objects = files
        self._build()
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
        if not self.file:
            return
        try:
            self._result = open_campaign(self.directory / self.file)
        except CampaignError as exc:
            self.message = str(exc)
            self._rows = {}
            self.param.case.objects = []
            self.case = None
            return
        self.message = self._result.summary().splitlines()[0]
        self._rows = case_rows(self._result)
        noises = sorted({v for v in self._rows["noise_pct"] if v is not None})
        targets = sorted({v for v in self._rows["target"] if v})
        with param.parameterized.batch_call_watchers(self):
            self.param.noise.objects = [ALL, *noises]
            self.param.target.objects = [ALL, *targets]
            self.param.update(noise=ALL, target=ALL, kind=ALL, harmonic=ALL, status=ALL)
        self._filter()

    def filtered(self) -> list[int]:
        """Indices of the rows that pass the filters."""
        r = self._rows
        out = []
        for i in range(len(r.get("case", []))):
            if self.kind != ALL and r["kind"][i] != self.kind:
                continue
            if self.harmonic != ALL and r["harmonic"][i] != self.harmonic:
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

    @param.depends("case", "dof", "max_over_dofs", watch=True)
    def _show(self) -> None:
        if self._result is None or self.case is None:
            self.shown = None
            return
        c = self._result.case(self.case)
        try:
            if c.kind == "scatter":
                self.shown = scatter_case_result(self._result, self.case, self.dof)
            else:
                dof = None if self.max_over_dofs else self.dof
                self.shown = truncation_case_result(self._result, self.case, dof)
        except CampaignError as exc:  # incomplete, or stored without these outputs
            self.shown = None
            self.message = str(exc)

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
        self._caption = pn.pane.Markdown("", sizing_mode="stretch_width")
        self._prov = pn.pane.Markdown("", styles={"font-size": "0.8em"})
        self._suggested = pn.pane.Markdown("")
        self._note = pn.pane.Markdown(self.param.message, styles={"font-size": "0.85em"})
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
        self._caption.object = r.caption
        self._prov.object = "\n".join(f"- **{k}**: {v}" for k, v in r.meta.items())
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
            self._suggested.object = ""
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
            self._suggested,
            self._download,
            pn.Card(self._prov, title="Provenance", collapsed=True, sizing_mode="stretch_width"),
            sizing_mode="stretch_width",
        )


def campaign_card(parts):
    """The page's card of the campaign browser (an entry of ``app.main.EXTRA_CARDS``):
    collapsed, built with ``parts.card``; None when no campaign directory is configured."""
    if campaign_dir() is None:
        return None
    return parts.card(
        "Campaign results (FBS_CAMPAIGN_DIR)",
        CampaignBrowser(),
        None,
        collapsed=True,
        css_classes=["campaign-card"],
    )


def _frame(cols: dict[str, list]):
    import pandas as pd

    return pd.DataFrame(cols if cols else {"case": []})
