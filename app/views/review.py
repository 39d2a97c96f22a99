"""The review card: tire candidates side by side, targets, and the verdict.

A supplier review asks which candidate tire meets the bushing targets (docs/verdict.md).
The card holds the session's candidates (the reference and every tire uploaded, here or in
"Your data"; one is current for the detail views), its targets (a target file, straight
segments typed in dB, or "the incumbent + margin dB") and shows the published verdict
(:mod:`app.results.review`): the ranking, the delivery of each candidate and one row per
candidate x harmonic x DOF, with a CSV download of all of it.

Every change goes to the session's :class:`~app.datasource.DataSource`; a refused file or
value is its ``error`` (shown here) and changes nothing. The tables are set in place on
the session's event loop (:class:`~app.views.live.LiveText`).
"""

from __future__ import annotations

import html
import io
import math
import re

import panel as pn
import param
from panel.viewable import Viewer

from fbs_core.candidates import MAX_CANDIDATES
from fbs_core.errors import FBSError
from fbs_core.targets import AXES, Target
from fbs_core.vocabulary import HARMONIC_CASES

from ..datasource import TARGET_ACCEPT, TARGET_DOFS, TIRE_ACCEPT
from ..export import dated
from ..runtime.draw import on_document, served_document
from .bind import control
from .common import CANDIDATE_COLORS
from .live import LiveText, export_meta
from .upload import _alert, _uploaded, queue_read

__all__ = ["ReviewView", "parse_points", "review_card"]

assert len(CANDIDATE_COLORS) >= MAX_CANDIDATES

STATUS_COLORS = {
    "pass": "#2b8a3e",
    "fail": "#c92a2a",
    "fails within the noise band": "#e67700",
    "not judged": "#868e96",
}
EVERY = "every harmonic"
NO_INCUMBENT = "(none)"
_PAIR = re.compile(r"^\s*([-+0-9.eE]+)\s*[:=]\s*([-+0-9.eE]+)\s*$")


def parse_points(text: str) -> list[tuple[float, float]]:
    """``"20:-20, 200:-30"`` as ``[(20.0, -20.0), (200.0, -30.0)]`` (frequency Hz: level dB
    pairs, separated by commas or semicolons).

    Raises
    ------
    FBSError
        Naming the part that is not a pair of numbers.
    """
    pairs = []
    for part in re.split(r"[,;]", text):
        if not part.strip():
            continue
        m = _PAIR.match(part)
        if m is None:
            raise FBSError(f"{part.strip()!r} is not 'frequency:dB' (e.g. 20:-20, 200:-30)")
        try:
            f, db = float(m.group(1)), float(m.group(2))
        except ValueError:
            raise FBSError(f"{part.strip()!r} is not 'frequency:dB' of two numbers") from None
        if not (math.isfinite(f) and math.isfinite(db)):
            raise FBSError(f"{part.strip()!r}: frequency and level must be finite")
        pairs.append((f, db))
    if len(pairs) < 2:
        raise FBSError("a target needs at least two points 'frequency:dB' (e.g. 20:-20, 200:-30)")
    return pairs


def _t(value: object) -> str:
    return html.escape(str(value), quote=True)


def _num(x: float, fmt: str = "+.1f") -> str:
    return "&ndash;" if not math.isfinite(x) else format(x, fmt)


def _swatch(color: str) -> str:
    return (
        f'<span style="display:inline-block;width:0.9em;height:0.9em;background:{color};'
        'border-radius:2px;vertical-align:middle;margin-right:4px"></span>'
    )


def _table(head: list[str], rows: list[list[str]], css: str) -> str:
    th = "".join(f"<th style='text-align:left;padding:1px 8px'>{h}</th>" for h in head)
    body = "".join(
        "<tr>" + "".join(f"<td style='padding:1px 8px'>{c}</td>" for c in r) + "</tr>" for r in rows
    )
    return f"<table class='{css}' style='border-collapse:collapse'><tr>{th}</tr>{body}</table>"


def _status(s: str) -> str:
    color = STATUS_COLORS.get(s, "#495057")
    return f"<b style='color:{color}' class='verdict-status'>{_t(s)}</b>"


class ReviewView(Viewer):
    """Candidates, targets and the verdict of one session."""

    store = param.Parameter(doc="The session's results store (app.store.Results).")

    def __init__(self, **params):
        super().__init__(**params)
        ds = self.store.state.data
        self._data = ds
        W = pn.widgets
        self.tire_file = W.FileInput(
            accept=TIRE_ACCEPT, multiple=False, css_classes=["review-tire"], width=230
        )
        self.current = W.Select(
            name="Current tire (detail views)", css_classes=["review-current"], width=220
        )
        self.remove = W.Button(
            name="Remove", button_type="light", css_classes=["review-remove"], width=90
        )
        self.cand_name = W.TextInput(name="Name", css_classes=["review-name"], width=150)
        self.cand_supplier = W.TextInput(
            name="Supplier", css_classes=["review-supplier"], width=130
        )
        self.cand_size = W.TextInput(
            name="Size / description", css_classes=["review-size"], width=150
        )
        self.cand_version = W.TextInput(name="Version", css_classes=["review-version"], width=90)
        self.describe = W.Button(
            name="Save description", button_type="light", css_classes=["review-describe"], width=140
        )
        self.target_file = W.FileInput(
            accept=TARGET_ACCEPT, multiple=False, css_classes=["review-target-file"], width=230
        )
        self.seg_dof = W.Select(
            name="DOF",
            options=list(TARGET_DOFS),  # the corner's bushing, then the car's points
            value="bushing:z",
            css_classes=["review-seg-dof"],
            width=130,
        )
        self.seg_points = W.TextInput(
            name="Points (Hz:dB re 1 (m/s)/m)",
            placeholder="20:-20, 200:-30",
            css_classes=["review-seg-points"],
            width=220,
        )
        self.seg_axis = W.Select(
            name="Straight over", options={"log f": "log", "f": "linear"}, value="log", width=90
        )
        self.seg_harmonic = W.Select(
            name="Harmonic",
            options=[EVERY, *map(str, HARMONIC_CASES)],
            value=EVERY,
            css_classes=["review-seg-harmonic"],
            width=130,
        )
        self.seg_add = W.Button(
            name="Add target", button_type="light", css_classes=["review-seg-add"], width=110
        )
        self.incumbent = W.Select(
            name="Incumbent", css_classes=["review-incumbent"], width=160, value=None
        )
        self.margin = W.FloatInput(
            name="+ margin (dB)", value=0.0, step=0.5, css_classes=["review-margin"], width=100
        )
        self.use_incumbent = W.Button(
            name="Judge against it", button_type="light", css_classes=["review-use-incumbent"]
        )
        self.clear = W.Button(
            name="Clear targets", button_type="light", css_classes=["review-clear"], width=120
        )
        self.download = W.FileDownload(
            callback=self._csv,
            filename="verdict.csv",
            label="Verdict CSV",
            button_type="light",
            css_classes=["review-csv"],
            width=130,
        )
        self.band_switch = control(
            W.Checkbox,
            self.store.state.noise.param.verdict_band,
            name="Judge with the noise band",
            css_classes=["review-band"],
        )
        self.candidates_text = LiveText(css_classes=["review-candidates"])
        self.targets_text = LiveText(css_classes=["review-targets"])
        self.verdict_text = LiveText(css_classes=["review-verdict"])
        self.pending_text = LiveText(css_classes=["review-pending-text"])
        self._error = _alert("", "danger", "review-error", visible=False)
        self._doc = served_document()
        # widgets: each a call into the data source
        self.tire_file.param.watch(self._on_tire, ["value", "filename"])
        self.target_file.param.watch(self._on_target, ["value", "filename"])
        self.current.param.watch(self._on_current, "value")
        self.remove.on_click(lambda _: ds.remove_candidate(self.current.value))
        self.describe.on_click(lambda _: self._describe())
        self.seg_add.on_click(lambda _: self._add_segments())
        self.use_incumbent.on_click(lambda _: self._set_incumbent())
        self.clear.on_click(lambda _: ds.clear_targets())
        ds.param.watch(lambda _e: self._sync_widgets(), ["review", "pending"])
        ds.param.watch(lambda _e: self._show_error(), ["error"])
        self.store.param.watch(lambda _e: self.redraw(), ["verdict"])
        self._sync_widgets()
        self._show_error()
        self._apply()

    # -- actions -------------------------------------------------------------------------
    def _read(self, slot: str, fn, got) -> None:
        """Read a file on the upload queue (a slow file holds no thread of the sessions)."""
        queue_read(self._data, slot, lambda: fn(*got), self._refused)

    def _refused(self, message: str) -> None:
        self._data.error = message

    def _on_tire(self, *events) -> None:
        got = _uploaded(self.tire_file, events)
        if got is not None:
            self._read("tire", self._data.load_tire, got)

    def _on_target(self, *events) -> None:
        got = _uploaded(self.target_file, events)
        if got is not None:
            self._read("targets", self._data.load_targets, got)

    def _on_current(self, event) -> None:
        cands = self._data.review.candidates
        if event.new and cands is not None and cands.current is not None:
            if event.new != cands.current.name:
                self._data.select_candidate(event.new)

    def _describe(self) -> None:
        cands = self._data.review.candidates
        cur = "reference" if cands is None or cands.current is None else cands.current.name
        self._data.describe_candidate(
            cur,
            name=self.cand_name.value.strip(),
            supplier=self.cand_supplier.value.strip(),
            size=self.cand_size.value.strip(),
            version=self.cand_version.value.strip(),
        )

    def _add_segments(self) -> None:
        h = None if self.seg_harmonic.value == EVERY else int(self.seg_harmonic.value)
        try:
            axis = self.seg_axis.value if self.seg_axis.value in AXES else "log"
            t = Target.segments(
                self.seg_dof.value, parse_points(self.seg_points.value), axis=axis, harmonic=h
            )
        except FBSError as e:
            self._data.error = f"typed target: {e}"
            return
        self._data.add_target(t)

    def _set_incumbent(self) -> None:
        name = self.incumbent.value
        margin = self.margin.value
        if margin is None or not math.isfinite(float(margin)):
            self._data.error = "incumbent: the margin must be a number of dB"
            return
        self._data.set_incumbent(None if name in (None, NO_INCUMBENT) else name, float(margin))

    def _csv(self):
        r = self.store.verdict
        v = None if r is None else r.core.get("verdict")
        if v is None:
            return io.BytesIO(b"")
        self.download.filename = dated(r.filename)
        return io.BytesIO(v.to_csv(export_meta(r.meta)))

    # -- display ---------------------------------------------------------------------------
    def _sync_widgets(self) -> None:
        """The selectors follow the review (names, current candidate)."""
        review = self._data.review
        names = list(review.names())
        cands = review.candidates
        cur = "reference" if cands is None or cands.current is None else cands.current.name
        self.current.param.update(options=names, value=cur)  # (select() skips its own)
        c = None if cands is None else cands.current
        self.cand_name.value = cur
        self.cand_supplier.value = "" if c is None else c.supplier
        self.cand_size.value = "" if c is None else c.size
        self.cand_version.value = "" if c is None else c.version
        self.remove.disabled = len(names) <= 1
        inc = review.incumbent
        self.incumbent.param.update(
            options=[NO_INCUMBENT, *names], value=NO_INCUMBENT if inc is None else inc.candidate
        )
        self.redraw()

    def _show_error(self) -> None:
        err = self._data.error
        body = f"<b>Refused, nothing changed.</b> {_t(err)}" if err else ""
        self._error.param.update(
            object=f'<div class="alert alert-danger" role="alert">{body}</div>', visible=bool(err)
        )

    def redraw(self) -> None:
        on_document(self._doc, self._apply)

    def _apply(self) -> None:
        review = self._data.review
        cands = review.candidates
        rows = []
        if cands is None:
            rows.append([_swatch(CANDIDATE_COLORS[0]) + "reference", "tire-fbs", "", "", "yes"])
        else:
            for c in cands:
                rows.append(
                    [
                        _swatch(CANDIDATE_COLORS[cands.slot(c.digest)]) + _t(c.name),
                        _t(c.supplier),
                        _t(c.size),
                        _t(c.version),
                        "yes" if c.digest == cands.current_digest else "",
                        f"{c.model.n_modes}",
                        _t(c.digest[:12]),
                        _t("; ".join(c.notes)),
                    ]
                )
        self.candidates_text.text = _table(
            ["candidate", "supplier", "size", "version", "current", "modes", "digest", "notes"],
            rows,
            "review-candidates-table",
        )
        trows = [
            [
                _t(t.dof),
                "every" if t.harmonic is None else str(t.harmonic),
                f"{float(t.freq[0]):g}&ndash;{float(t.freq[-1]):g}",
                f"{t.level_db.min():.1f} &ndash; {t.level_db.max():.1f}",
                _t(t.quantity),
                _t(t.source),
            ]
            for t in review.targets
        ]
        if review.incumbent is not None:
            inc = review.incumbent
            trows.append(
                ["every DOF without a target", "every", "", f"{inc.margin_db:+g}", "", "incumbent "
                 + _t(inc.candidate)]
            )  # fmt: skip
        self.targets_text.text = (
            _table(
                ["DOF", "harmonic", "Hz", "dB re 1 SI", "quantity", "source"],
                trows,
                "review-targets-table",
            )
            if trows
            else "<p><i>No targets yet.</i></p>"
        )
        self.verdict_text.text = self._verdict_html()
        want = self._data.pending
        self.pending_text.text = (
            ""
            if want is None or not want.candidates
            else "<p class='review-pending'>This page's link names candidates not loaded in "
            f"this session (digests {_t(', '.join(want.candidates))}): add their tire files "
            "to restore them.</p>"
        )

    def _verdict_html(self) -> str:
        r = self.store.verdict
        if r is None:
            return ""
        cap = html.escape(r.caption).replace("**", "")
        v = r.core.get("verdict")
        if v is None:
            return f"<p class='verdict-state'>{cap}</p>"
        cands = r.draw["candidates"]
        ranking = [
            [
                str(s.rank),
                _swatch(CANDIDATE_COLORS[cands.slot(s.digest)]) + _t(s.candidate),
                _status(s.status),
                _num(s.worst_db),
                "" if not s.harmonic else f"{s.harmonic}",
                _t(s.dof),
                _num(s.freq, ".1f"),
                _num(s.speed, ".0f"),
                f"{s.fails} / {s.noise_fails} / {s.passes}",
            ]
            for s in v.ranking
        ]
        deliveries = [
            [
                _t(d.candidate),
                "yes" if d.adequate else "<b style='color:#c92a2a'>no</b>",
                str(d.n_modes),
                " ".join(str(int(x)) for x in d.suggested),
                f"{d.speeds[0]:g}&ndash;{d.speeds[1]:g}",
                _t("; ".join(d.warnings)) or "&ndash;",
            ]
            for d in v.deliveries
        ]
        rows = [
            [
                _t(x.candidate),
                str(x.harmonic),
                _t(x.dof),
                _status(x.status),
                _num(x.worst_db),
                _num(x.margin_db),
                _num(x.freq, ".1f"),
                _num(x.speed, ".0f"),
                _t(x.target),
            ]
            for x in v.rows
        ]
        return (
            f"<p class='verdict-state'>{cap}</p>"
            + "<p><b>Ranking</b> (worst level &minus; target in dB; &gt; 0 fails)</p>"
            + _table(
                [
                    "rank",
                    "candidate",
                    "status",
                    "worst dB",
                    "harmonic",
                    "DOF",
                    "Hz",
                    "km/h",
                    "fail / noise / pass",
                ],
                ranking,
                "verdict-ranking",
            )  # fmt: skip
            + "<p><b>Delivery</b> (its modes against table 5.1's N, harmonics 1-7)</p>"
            + _table(
                ["candidate", "adequate", "modes", "suggested N", "km/h", "warnings"],
                deliveries,
                "verdict-delivery",
            )
            + "<details><summary><b>Every candidate x harmonic x DOF</b></summary>"
            + _table(
                [
                    "candidate",
                    "harmonic",
                    "DOF",
                    "status",
                    "worst dB",
                    "margin dB",
                    "Hz",
                    "km/h",
                    "target",
                ],
                rows,
                "verdict-rows",
            )  # fmt: skip
            + "</details>"
        )

    def __panel__(self):
        label = pn.pane.Markdown
        return pn.Column(
            self._error,
            label(
                "**Candidates** (the reference and each tire added; colours as in every "
                f"plot; at most {MAX_CANDIDATES})",
                margin=(0, 5),
            ),  # fmt: skip
            pn.FlexBox(
                pn.Column(label("Add a tire (.h5/.mat)", margin=(0, 5)), self.tire_file),
                self.current,
                self.remove,
                flex_wrap="wrap",
                align_items="flex-end",
                sizing_mode="stretch_width",
            ),
            pn.FlexBox(
                self.cand_name,
                self.cand_supplier,
                self.cand_size,
                self.cand_version,
                self.describe,
                flex_wrap="wrap",
                align_items="flex-end",
                sizing_mode="stretch_width",
            ),  # fmt: skip
            self.pending_text,
            self.candidates_text,
            label(
                "**Targets** (bushing velocity per metre of road; docs/verdict.md)", margin=(0, 5)
            ),  # fmt: skip
            pn.FlexBox(
                pn.Column(label("Target file (CSV, UFF 58)", margin=(0, 5)), self.target_file),
                self.seg_dof,
                self.seg_points,
                self.seg_axis,
                self.seg_harmonic,
                self.seg_add,
                flex_wrap="wrap",
                align_items="flex-end",
                sizing_mode="stretch_width",
            ),
            pn.FlexBox(
                self.incumbent,
                self.margin,
                self.use_incumbent,
                self.clear,
                flex_wrap="wrap",
                align_items="flex-end",
                sizing_mode="stretch_width",
            ),  # fmt: skip
            self.targets_text,
            pn.Row(label("**Verdict**", margin=(0, 5)), self.download),
            pn.FlexBox(
                self.band_switch,
                label(
                    "a band of the noise settings per candidate and harmonic (all modes): a "
                    "target crossed only by its upper percentile edge *fails within the noise "
                    "band*",
                    margin=(0, 5),
                    styles={"font-size": "0.85em"},
                ),
                flex_wrap="wrap",
                align_items="center",
                sizing_mode="stretch_width",
            ),
            self.verdict_text,
            sizing_mode="stretch_width",
        )


def review_card(parts) -> pn.Card:
    """The review card, collapsed; its content is built when it is first opened (it is the
    meeting's, not every session's: a page that never opens it pays nothing for it), or at
    once when the session already has a review (candidates or targets)."""
    holder = pn.Column(sizing_mode="stretch_width", margin=0)
    card = parts.card(
        "Review: tire candidates against targets, the verdict",
        holder,
        height=None,
        collapsed=True,
        css_classes=["review-card"],
    )

    def build(*_):
        if not holder.objects:
            holder.objects = [ReviewView(store=parts.results)]

    review = parts.state.data.review
    if review.candidates is not None or review.judged:
        build()
    card.param.watch(lambda e: None if e.new else build(), "collapsed")
    return card
