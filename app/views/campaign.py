"""The campaign card: browse a campaign's result file, its cases and one case's view.

The view lists the cases of a campaign file of ``FBS_CAMPAIGN_DIR`` (harmonic, noise,
target, frequency dependence, truncation range, tire and chassis variants, coupling,
rounds, seed, status) with filters, and shows the chosen case: a scatter case's band at
one bushing DOF, a truncation case's error map with its suggested mode counts, or a
variants case's corridor with its sensitivity leaders, each with its provenance and a CSV
export whose header carries the same provenance.

This module holds the page's side only: :class:`CampaignBrowser` (widgets, filters, the
figures it draws) and :func:`campaign_card` (the card, or :data:`HOW_TO` when the server
has no campaign directory). What it shows is made elsewhere, so each part can be read and
tested without the others:

- :mod:`app.state.campaign`: the file, the case and its view as settings of the session
  (in the link: a link opens the same file on the same case);
- :mod:`app.results.campaign_rows`: the case table and the chosen case as rows of the
  session's store (:data:`app.store.TABLE`), the file read on the store's background
  worker while the card says so;
- :mod:`app.runtime.campaign_files`: the campaign files on the server's disk, listed and
  opened, kept per process and read again only when a file changes;
- :mod:`app.results.campaign`: the case table and each case's :class:`~app.results.Result`
  (pure functions of the opened file; nothing is recomputed).

A page costs no file access until the card is expanded (:meth:`CampaignBrowser.activate`
lists the files and opens the first) or its link names a campaign file. A malformed file
is a message in the card naming the file and the problem
(:class:`~fbs_core.campaign.CampaignError`), never an error of the page.
"""

from __future__ import annotations

import html
import logging
from pathlib import Path

import numpy as np
import panel as pn
import param
from bokeh.models import ColorBar, ColumnDataSource, LinearColorMapper
from bokeh.plotting import figure

from fbs_core.vocabulary import DIRECTIONS

from ..results import Result
from ..results.campaign import case_rows, variants_case_result
from ..runtime.campaign_files import CAMPAIGN_DIR_ENV, campaign_dir, list_campaigns
from ..runtime.draw import on_document, served_document
from ..state import DashboardState
from ..store import Results
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

ALL = "all"
STATUSES = (ALL, "complete", "partial")
KINDS = (ALL, "scatter", "truncation", "variants")


class CampaignBrowser(pn.viewable.Viewer):
    """The campaign files of ``directory``, their cases (filtered) and the chosen case.

    The file, the case, the DOF, the maximum over the DOFs and the harmonic are the
    session's settings (``store.state.campaign``, in the link); the browser's parameters
    of the same names mirror them for its widgets. The case table and the case are the
    store's published results (``campaign_cases``, ``campaign``), which the browser only
    draws; the filters other than the harmonic are the browser's own (they choose the
    rows listed, nothing a result is made of). Without a ``store`` the browser makes one of
    its own (no server: tests, notebooks).
    """

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

    #: Settings of ``state.campaign`` mirrored by the browser's parameter of the same name.
    MIRRORED = ("file", "case", "dof", "max_over_dofs", "harmonic")

    def __init__(
        self,
        directory: Path | None = None,
        lazy: bool = False,
        store: Results | None = None,
        **params,
    ):
        if store is None:
            state = DashboardState()
            if directory is not None:
                state.campaign.directory = Path(directory).resolve()
            store = Results(state, background=False)
        elif directory is not None:
            store.state.campaign.directory = Path(directory).resolve()
        params["directory"] = store.state.campaign.directory
        super().__init__(**params)
        self._store = store
        self._settings = store.state.campaign
        self._rows: dict[str, tuple] = {}
        self._tabled_file: str | None = None
        self._table_shown: Result | None = None
        self._lazy = lazy
        self._active = False
        self._listed: str = ""  # why no file is listed ('' when some are)
        self._doc = served_document()  # the session's page (None: no server)
        self._build()
        self._from_state()
        self._settings.param.watch(lambda *_: self._from_state(), list(self.MIRRORED))
        self.param.watch(self._to_state, list(self.MIRRORED))
        store.param.watch(lambda *_: self._refresh(), ["campaign_cases", "campaign"])
        self._refresh()
        if not lazy:
            self.activate()

    @property
    def store(self) -> Results:
        """The session's results the browser draws."""
        return self._store

    def activate(self) -> None:
        """List the campaign files and open the first one unless one is chosen (once; a
        ``lazy`` browser waits for this until its card is expanded, so a page build reads
        no file)."""
        if self._active:
            return
        self._active = True
        files = list_campaigns(self.directory)
        chosen = self._settings.file
        self.param.file.objects = files + ([chosen] if chosen and chosen not in files else [])
        if not files:
            self._listed = (
                f"No campaign result files in {self.directory}."
                if self.directory
                else f"No campaign directory configured (set {CAMPAIGN_DIR_ENV})."
            )
        if chosen:
            self.file = chosen
        elif files:
            self.file = files[0]
        self._say()

    # -- the settings and the browser's widgets ---------------------------------------------
    def _from_state(self) -> None:
        """The browser's parameters from the session's settings."""
        st = self._settings
        for name, objs in (("file", st.file), ("case", st.case)):
            known = self.param[name].objects
            if objs and known and objs not in known:
                self.param[name].objects = [*known, objs]
        self.param.update(
            file=st.file or None,
            case=st.case or None,
            dof=st.dof,
            max_over_dofs=st.max_over_dofs,
            harmonic=st.harmonic or ALL,
        )

    def _to_state(self, *events) -> None:
        """The session's settings from the browser's parameters (a file the user chooses
        opens on its first case, the harmonic filter reset)."""
        values = {e.name: e.new for e in events}
        st = self._settings
        out: dict = {}
        if "file" in values and (values["file"] or "") != st.file:
            out.update(file=values["file"] or "", case="", harmonic=0)
        if "case" in values and "file" not in out:
            out["case"] = values["case"] or ""
        for name in ("dof", "max_over_dofs"):
            if name in values:
                out[name] = values[name]
        if "harmonic" in values and "file" not in out:
            out["harmonic"] = 0 if values["harmonic"] == ALL else int(values["harmonic"])
        out = {k: v for k, v in out.items() if getattr(st, k) != v}
        if out:
            st.param.update(**out)

    # -- the published results ------------------------------------------------------------------
    def _refresh(self) -> None:
        """Show the published case table and case (on the session's event loop when served)."""
        on_document(self._doc, self._apply)

    def _apply(self) -> None:
        if self._store.closed:
            return
        table = self._store.campaign_cases
        rows = dict(table.draw["rows"]) if table is not None and "rows" in table.draw else {}
        file = table.draw.get("file") if table is not None else None
        new = table is not self._table_shown  # a new table: listed, a case chosen in it
        if new:
            self._table_shown, self._rows = table, rows
        if rows and file != self._tabled_file:  # another file: its filters' choices
            self._tabled_file = file
            noises = sorted({v for v in rows["noise_pct"] if v is not None})
            targets = sorted({v for v in rows["target"] if v})
            with param.parameterized.batch_call_watchers(self):
                self.param.noise.objects = [ALL, *noises]
                self.param.target.objects = [ALL, *targets]
                self.param.update(noise=ALL, target=ALL, kind=ALL, status=ALL)
        if new and (table is None or rows):
            self._filter()
        r = self._store.campaign
        self.shown = r if r is not None and r.columns else None
        self._say()

    def _say(self) -> None:
        """The card's message: why nothing is listed, the file being read or its problem,
        the case's problem, else the file's headline."""
        table, case = self._store.campaign_cases, self._store.campaign
        text = self._listed if table is None else table.caption
        if table is not None and table.draw.get("state") == "done" and case is not None:
            text = case.draw.get("problem", text)
        self.message = text

    def filtered(self) -> list[int]:
        """Indices of the rows that pass the filters."""
        r = self._rows
        out = []
        for i in range(len(r.get("case", ()))):
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
        """List the rows that pass the filters; the chosen case stays when listed, else the
        first listed is chosen (only once the file's table is published: a link's case
        waits for its file)."""
        idx = self.filtered()
        names = [self._rows["case"][i] for i in idx]
        self._table.value = _frame({k: [v[i] for i in idx] for k, v in self._rows.items()})
        self.param.case.objects = names
        if not self._rows:
            return
        if self._settings.case not in names:  # (the setting: the browser's may lag behind)
            self._settings.case = names[0] if names else ""

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
        self.param.watch(lambda _e: self._draw(), "shown")

    def _clicked(self, event) -> None:
        names = self._table.value["case"].tolist()
        if 0 <= event.row < len(names):
            self.case = names[event.row]

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
        self._doc = served_document() or self._doc
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
    the first, :meth:`CampaignBrowser.activate`) or the link names a file (then the card is
    shown expanded on it). The shown case is in the session's report: it is a row of the
    store (``campaign``)."""
    if campaign_dir() is None:
        return parts.card(
            "Corridors and campaigns (not set up on this server)",
            pn.pane.Markdown(HOW_TO, sizing_mode="stretch_width", css_classes=["campaign-howto"]),
            None,
            collapsed=True,
            css_classes=["campaign-card"],
        )
    browser = CampaignBrowser(lazy=True, store=parts.results)
    linked = bool(parts.results.state.campaign.file)  # a link names a file: shown opened
    card = parts.card(
        "Campaign results (FBS_CAMPAIGN_DIR)",
        browser,
        None,
        collapsed=not linked,
        css_classes=["campaign-card"],
    )
    if linked:
        browser.activate()

    def expanded(event):
        if not event.new:
            browser.activate()

    card.param.watch(expanded, "collapsed")
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


def _frame(cols: dict[str, list]):
    import pandas as pd

    return pd.DataFrame(cols if cols else {"case": []})
