"""The content of a report, independent of its format (HTML and PDF render the same blocks).

:func:`report_content` turns a :class:`~app.report.data.ReportData` into sections of
title blocks, figures and tables whose numbers are formatted once here, so the HTML file and
the PDF hold the same text.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, SupportsFloat

import numpy as np
from numpy.typing import ArrayLike

import fbs_core
from fbs_core.harmonics import Harmonic
from fbs_core.vocabulary import magnitude_db, percent

from . import figures
from .data import SETTING_KEYS, ExtraSection, ReportData, ReportError, present
from .figures import FigureBlock
from .method import EQUATIONS, METHOD_PARAGRAPHS, THESIS, Equation
from .summary import Summary, report_summary, suggested_n
from .titles import (
    PLAIN_TEXT,
    TitleBlock,
    coupling_description,
    file_stem,
    harmonic_description,
    title_block,
)

__all__ = [
    "Table",
    "FigureBlock",
    "Section",
    "Report",
    "report_content",
    "plot_file",
]


@dataclass(frozen=True)
class Table:
    """A table of formatted cells."""

    caption: str
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]


@dataclass(frozen=True)
class Section:
    key: str
    heading: str
    paragraphs: tuple[str, ...]
    figure: FigureBlock | None
    tables: tuple[Table, ...]
    title: TitleBlock | None = None
    #: Tables printed last, after every plot (a row per N, per speed, a view's settings).
    long_tables: tuple[Table, ...] = ()


@dataclass(frozen=True)
class Report:
    """Everything a report shows, formatted."""

    title: str
    stem: str
    title_block: TitleBlock
    url: str
    reproduce_note: str
    summary: Summary
    provenance: Table
    settings: Table
    sections: tuple[Section, ...]
    method: tuple[str, ...]
    equations: tuple[Equation, ...]
    thesis: str
    #: The review's verdict (candidates against targets), first after the title; None
    #: without targets.
    verdict: Section | None = None


def _fixed(x: SupportsFloat, digits: int) -> str:
    """``x`` with ``digits`` decimals, never ``-0.00``."""
    v = round(float(x), digits)
    return f"{v + 0.0:.{digits}f}"


def _db_text(x: SupportsFloat) -> str:
    return f"{_fixed(x, 2)} dB"


def _hz(x: SupportsFloat) -> str:
    return f"{_fixed(x, 1)} Hz"


def _pct(x: SupportsFloat) -> str:
    return f"{_fixed(x, 1)} %"


def _setting_text(name: str, value: object) -> str:
    if isinstance(value, bool):
        return "yes" if value else "no"
    if name == "rounds":
        return f"{value:,}"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def _settings_table(snap: ReportData) -> Table:
    rows = tuple(
        (name, SETTING_KEYS[name][1], _setting_text(name, v)) for name, v in snap.settings.items()
    )
    return Table("Settings of the page", ("setting", "meaning", "value"), rows)


def _provenance_table(snap: ReportData) -> Table:
    p = snap.provenance
    rows = []
    for d in (p.tire, p.chassis):
        rows.append(
            (
                d.role,
                "reference (shipped model)" if d.is_reference else f"uploaded file '{d.name}'",
                d.digest or "-",
            )
        )
    for note in p.notes:
        rows.append(("note", note, ""))
    rows.append(("fbs_core", f"version {fbs_core.__version__}", ""))
    return Table("Data in use", ("model", "source", "digest"), tuple(rows))


def _peak_row(label: str, freq: np.ndarray, v: ArrayLike, h: Harmonic) -> tuple[str, ...]:
    lv = magnitude_db(v)
    i = int(np.argmax(lv))
    return (label, _db_text(lv[i]), _hz(freq[i]), f"{h.speed_at(freq[i]):.1f} km/h")


def _coupled_section(snap: ReportData) -> Section:
    dof = snap.response_dof
    s, h = snap.settings, snap.harmonic
    rows = []
    ref = snap.reference.sel(outputs=dof) if snap.reference else None
    tr = snap.truncated.sel(outputs=dof) if snap.truncated else None
    if ref is not None:
        rows.append(_peak_row("all tire modes", ref.freq, ref.data[:, 0, 0], h))
    res = " + residual" if s.get("residual") else ""
    if tr is not None:
        rows.append(_peak_row(f"N = {s['n_modes']} modes{res}", tr.freq, tr.data[:, 0, 0], h))
    tables = [
        Table(
            f"Peak level at {dof} ({figures.level_unit(dof)})",
            ("response", "peak level", "at frequency", "vehicle speed"),
            tuple(rows),
        )
    ]
    if ref is not None and tr is not None and np.array_equal(ref.freq, tr.freq):
        lr, lt = magnitude_db(ref.data[:, 0, 0]), magnitude_db(tr.data[:, 0, 0])
        i = int(np.argmax(lr))
        d = lt - lr
        j = int(np.argmax(np.abs(d)))
        tables.append(
            Table(
                f"N = {s['n_modes']}{res} against all modes",
                ("quantity", "value", "at frequency"),
                (
                    ("level difference at the reference peak", _db_text(d[i]), _hz(ref.freq[i])),
                    ("largest level difference", _db_text(d[j]), _hz(ref.freq[j])),
                ),
            )
        )
    fig = FigureBlock(
        "coupled-response",
        title_block(snap, "coupled-response"),
        figures.draw_coupled(snap),
        stem=file_stem(snap, "coupled-response"),
    )
    comp = (
        " and the quasi-static part of the modes left out (residual compensation)"
        if s.get("residual")
        else ""
    )
    para = (
        f"Velocity v_e* at {dof} per metre of road amplitude along the harmonic's speed line "
        f"(eq. 4.1, {coupling_description(s['coupling'])}), with all tire modes and with the "
        f"first {s['n_modes']} modes{comp}.",
    )
    return Section("coupled-response", "Coupled response", para, fig, tuple(tables))


def _truncation_section(snap: ReportData) -> Section:
    m, s = present(snap.truncation, "truncation map"), snap.settings
    dof = snap.map_dof
    err = percent(m.max_error if dof is None else m.dof_error(dof))
    thr, fmax = s["threshold"], s["f_max"]
    n_sugg = present(suggested_n(snap), "suggested N")
    sel = m.centres <= fmax + 1e-9
    rows = []
    for i, n in enumerate(m.n_modes):
        if sel.any():
            k = int(np.argmax(np.where(sel, err[i], -np.inf)))
            worst, at = err[i, k], m.centres[k]
            mark = "below" if worst < thr else "at or above"
        else:
            worst, at, mark = np.nan, np.nan, "-"
        notes = [t for t, ok in (("chosen", n == s["n_modes"]), ("suggested", n == n_sugg)) if ok]
        rows.append(
            (str(int(n)), _pct(worst), _hz(at), mark, ", ".join(notes)),
        )
    what = f"{dof}" if dof else "the maximum over the 6 bushing DOFs"
    comp = " (with residual compensation)" if s.get("residual") else ""
    para = (
        f"Floating-band error of eq. 5.1 ({m.width:g} Hz band, {m.step:g} Hz steps) of "
        f"{what} for N retained modes{comp} against all {m.n_modes_total} modes. Blue: below the "
        f"{thr:g} % threshold (darker is larger); red, hatched: at or above it; black line: "
        f"the {thr:g} % contour. Suggested N = {n_sugg}: the smallest N from which the error "
        f"stays below {thr:g} % at all centres up to {fmax:g} Hz (thesis table 5.1).",
    )
    table = Table(
        f"Largest error up to {fmax:g} Hz for each N ({what})",
        ("N", "largest error", "at centre", f"vs {thr:g} %", ""),
        tuple(rows),
    )
    fig = FigureBlock(
        "truncation-map",
        title_block(snap, "truncation-map"),
        figures.draw_truncation(snap, n_sugg),
        aspect=0.62,
        stem=file_stem(snap, "truncation-map"),
    )
    return Section("truncation-map", "Truncation error map", para, fig, (), long_tables=(table,))


def _suggested_section(snap: ReportData) -> Section:
    sm = present(snap.suggested, "suggested modes")
    rows = []
    for k, n, ef, (lo, hi) in zip(
        sm.harmonics, sm.n_modes, sm.eigenfrequency, sm.freq_range, strict=True
    ):
        rows.append(
            (
                str(k),
                f"{lo:.1f}-{hi:.1f} Hz",
                str(int(n)),
                "-" if not np.isfinite(ef) else f"{ef:.1f} Hz",
            )
        )
    what = sm.dof or "maximum over the 6 bushing DOFs"
    comp = ", N modes with residual compensation" if snap.settings.get("residual") else ""
    para = (
        f"Smallest N from which the eq. 5.1 error stays below {percent(sm.threshold):g} % at all "
        f"centres up to {sm.f_max:g} Hz ({what}{comp}), and the highest eigenfrequency among "
        f"those modes at {sm.speed:g} km/h (thesis table 5.1).",
    )
    table = Table(
        "Suggested number of modes",
        ("harmonic", "band", "suggested N", f"highest eigenfreq. at {sm.speed:g} km/h"),
        tuple(rows),
    )
    tb = title_block(snap, "suggested-modes")
    return Section("suggested-modes", "Suggested number of modes", para, None, (table,), tb)


def _band_section(snap: ReportData) -> Section:
    b, s = present(snap.band, "scatter band"), snap.settings
    dof = snap.response_dof
    j = b.dofs.index(dof)
    w = s["percentile"]
    q = [float(x) for x in b.q]
    lo, hi = (100 - w) / 2, (100 + w) / 2
    ref = magnitude_db(b.reference[:, j])
    i = int(np.argmax(ref))
    rnd = magnitude_db(b.round(s["single_round"])[:, j])
    width = magnitude_db(b.maximum[:, j]) - magnitude_db(b.minimum[:, j])
    k = int(np.argmax(width))
    conv = np.asarray(b.convergence.step_change_db, float)
    f_i = _hz(b.freq[i])
    rows = (
        ("unpolluted reference", _db_text(ref[i])),
        ("minimum over the rounds", _db_text(magnitude_db(b.minimum[i, j]))),
        ("maximum over the rounds", _db_text(magnitude_db(b.maximum[i, j]))),
        (f"{lo:g} % percentile", _db_text(magnitude_db(b.percentiles[q.index(lo), i, j]))),
        (f"{hi:g} % percentile", _db_text(magnitude_db(b.percentiles[q.index(hi), i, j]))),
        (f"round #{s['single_round']}", _db_text(rnd[i])),
    )
    extra = (
        ("widest corridor (max - min)", _db_text(width[k]), _hz(b.freq[k])),
        (
            "last change of a band edge",
            _db_text(conv[-1]) if conv.size else "-",
            f"rounds {int(b.convergence.rounds[-2]):,} to {int(b.convergence.rounds[-1]):,}"
            if conv.size
            else "",
        ),
    )
    para = (
        f"Each element of the subsystem FRFs scaled by a factor uniform in "
        f"[1 - p, 1 + p], p = {s['noise']:g} %, the response recomputed R = {s['rounds']:,} "
        f"times (eqs. 5.2-5.4). Shaded: minimum to maximum over the rounds and the {w} % "
        f"central band ({lo:g}-{hi:g} % percentiles); dark line: the unpolluted reference; "
        f"orange: round #{s['single_round']}. A large last change of a band edge means R is "
        "too small."
        + (
            f" The band is the N = {s['n_modes']} model's, a {PLAIN_TEXT} (the page's "
            "residual compensation acts on the coupled response, the error map and the "
            "suggested N)."
            if s.get("residual")
            else ""
        ),
    )
    tables = (
        Table(f"Levels at the reference peak, {f_i}", ("curve", "level"), rows),
        Table("Corridor", ("quantity", "value", "where"), extra),
    )
    fig = FigureBlock(
        "scatter-band",
        title_block(snap, "scatter-band"),
        figures.draw_band(snap),
        stem=file_stem(snap, "scatter-band"),
    )
    return Section("scatter-band", "Noise scatter band", para, fig, tables)


def _eigen_section(snap: ReportData) -> Section:
    e, n = present(snap.eigen, "eigenfrequencies"), snap.settings["n_modes"]
    hit = np.flatnonzero(e.n_modes == n)
    rows = []
    if hit.size:
        for v, row in zip(e.speeds, e.frequency, strict=True):
            rows.append((f"{v:g} km/h", _hz(row[hit[0]])))
    para = (
        f"Highest eigenfrequency among the first N modes (N/2 +/- pairs, lowest first); "
        f"chosen N = {n}.",
    )
    fig = FigureBlock(
        "eigenfrequency",
        title_block(snap, "eigenfrequency"),
        figures.draw_eigen(snap),
        aspect=0.5,
        stem=file_stem(snap, "eigenfrequency"),
    )
    table = Table(
        f"Highest retained eigenfrequency at N = {n}", ("speed", "frequency"), tuple(rows)
    )
    return Section(
        "eigenfrequency", "Eigenfrequency vs number of modes", para, fig, (), long_tables=(table,)
    )


def _extra_section(snap: ReportData, ex: ExtraSection) -> Section:
    """A section contributed by another view (:class:`~app.report.data.ExtraSection`)."""
    table = Table(f"{ex.heading}: settings and description", ("item", "value"), ex.rows)
    fig = None
    draw = None
    if ex.curves and ex.freq is not None:  # curves always come with their frequencies
        draw = figures.draw_curves(ex.freq, ex.curves, ex.y_label)
    elif ex.plot is not None:
        kind = ex.plot["kind"]
        draw = figures.draw_lines(ex.plot) if kind == "lines" else figures.draw_image(ex.plot)
    if draw is not None:
        base = title_block(snap, "report")
        tb = TitleBlock(ex.heading, base.lines)
        fig = FigureBlock(
            ex.key,
            tb,
            draw,
            stem=f"{file_stem(snap, 'report')}_{re.sub(r'[^A-Za-z0-9._-]', '-', ex.key)}",
        )
    if draw is None and ex.strip is not None:  # a mode shape: its frames side by side
        base = title_block(snap, "report")
        fig = FigureBlock(
            ex.key,
            TitleBlock(ex.heading, base.lines),
            figures.draw_strip(ex.strip),
            aspect=0.22,
            stem=f"{file_stem(snap, 'report')}_{re.sub(r'[^A-Za-z0-9._-]', '-', ex.key)}",
        )
    return Section(
        ex.key, ex.heading, ex.paragraphs, fig, (), long_tables=(table,) if ex.rows else ()
    )


def _cell(x: float, fmt: str = "+.2f") -> str:
    return "-" if not math.isfinite(x) else format(x, fmt)


def verdict_section(v: Any) -> Section:
    """The review's verdict (:class:`fbs_core.verdict.Verdict`): the ranking, each
    candidate's delivery, then every candidate x harmonic x DOF row."""
    ranking = Table(
        "Ranking: worst level - target in dB (> 0 fails), where it is worst",
        ("rank", "candidate", "status", "worst dB", "harmonic", "DOF", "Hz", "km/h",
         "fail / noise / pass"),
        tuple(
            (str(s.rank), s.candidate, s.status, _cell(s.worst_db),
             str(s.harmonic) if s.harmonic else "-", s.dof or "-", _cell(s.freq, ".1f"),
             _cell(s.speed, ".0f"), f"{s.fails} / {s.noise_fails} / {s.passes}")
            for s in v.ranking
        ),
    )  # fmt: skip
    delivery = Table(
        "Delivery: the candidate's modes against table 5.1's suggested N (harmonics 1-7)",
        ("candidate", "adequate", "modes", "suggested N", "km/h", "warnings"),
        tuple(
            (d.candidate, "yes" if d.adequate else "no", str(d.n_modes),
             " ".join(str(int(x)) for x in d.suggested), f"{d.speeds[0]:g}-{d.speeds[1]:g}",
             "; ".join(d.warnings) or "-")
            for d in v.deliveries
        ),
    )  # fmt: skip
    rows = Table(
        "Every candidate x harmonic x DOF against its target",
        ("candidate", "harmonic", "DOF", "status", "worst dB", "margin dB", "Hz", "km/h",
         "target"),
        tuple(
            (r.candidate, str(r.harmonic), r.dof, r.status, _cell(r.worst_db),
             _cell(r.margin_db), _cell(r.freq, ".1f"), _cell(r.speed, ".0f"), r.target)
            for r in v.rows
        ),
    )  # fmt: skip
    best = v.ranking[0] if v.ranking else None
    points = list(dict.fromkeys(r.point for r in v.rows))
    if points and points != ["bushing"]:  # vehicle scope: the car's response points
        what = (
            f"the targets at the car's {', '.join(points)}: each candidate's response of the "
            "whole car with its tire on the four wheels (eq. 4.1, the four hubs as one "
            "interface, every mode it delivered)"
        )
    else:
        what = (
            "the bushing targets: each candidate's coupled bushing response (eq. 4.1, every "
            "mode it delivered)"
        )
    text = (
        f"Which candidate tire meets {what} against the targets on every harmonic "
        "(docs/verdict.md)."
        + (f" Best: {best.candidate} ({best.status})." if best is not None else "")
    )
    return Section("verdict", "Verdict", (text,), None, (ranking, delivery), long_tables=(rows,))


def report_content(snap: ReportData) -> Report:
    """The formatted content of the report of a snapshot (all results it holds)."""
    sections = []
    if snap.reference is not None or snap.truncated is not None:
        sections.append(_coupled_section(snap))
    if snap.truncation is not None:
        sections.append(_truncation_section(snap))
    if snap.suggested is not None:
        sections.append(_suggested_section(snap))
    if snap.band is not None:
        sections.append(_band_section(snap))
    if snap.eigen is not None:
        sections.append(_eigen_section(snap))
    sections.extend(_extra_section(snap, ex) for ex in snap.extra)
    s = snap.settings
    if snap.provenance.is_reference:
        note = "The link reproduces this page with the shipped reference models."
    else:
        files = ", ".join(f"'{d.name}'" for d in snap.provenance.uploads)
        note = (
            f"The link reproduces this page only after uploading the same file(s) {files} "
            "(check the digests above): without them it shows the reference models."
        )
    title = (
        f"tire-fbs report: {harmonic_description(s['harmonic']).split(':')[0]}, "
        f"{snap.response_dof}, N = {s['n_modes']}{' + residual' if s.get('residual') else ''}, "
        f"{s['coupling']}"
    )
    return Report(
        title=title,
        stem=file_stem(snap, "report"),
        title_block=title_block(snap, "report"),
        url=snap.url,
        reproduce_note=note,
        summary=report_summary(snap),
        provenance=_provenance_table(snap),
        settings=_settings_table(snap),
        sections=tuple(sections),
        method=METHOD_PARAGRAPHS,
        equations=EQUATIONS,
        thesis=THESIS,
        verdict=None if snap.verdict is None else verdict_section(snap.verdict),
    )


def plot_file(snap: ReportData, view: str, fmt: str = "png") -> tuple[str, bytes]:
    """``(file name, bytes)`` of one plot of the report with its title block on top.

    ``view`` is one of the report's plots (``coupled-response``, ``truncation-map``,
    ``scatter-band``, ``eigenfrequency``) whose result the snapshot holds; ``fmt`` is
    ``png``, ``svg`` or ``pdf``.

    Raises
    ------
    ReportError
        For a view the snapshot has no plot of, naming those it has.
    """
    blocks = {sec.figure.key: sec.figure for sec in report_content(snap).sections if sec.figure}
    if view not in blocks:
        raise ReportError(
            f"no {view!r} plot in this snapshot; plots: {', '.join(blocks) or 'none'}"
        )
    fig = figures.standalone(blocks[view])
    return f"{blocks[view].stem}.{fmt}", figures.render(fig, fmt)
