"""The report as one self-contained HTML file: inline CSS, plots as inline SVG, no scripts.

Nothing in the file is fetched from anywhere: the plots and equations are SVG written into
the page (glyphs as paths, no web fonts), and the only external address is the link to the
dashboard page that reproduces the state.
"""

from __future__ import annotations

import html
import re
from functools import lru_cache

from matplotlib.figure import Figure

from . import figures
from .content import Report, Table, report_content
from .data import ReportData
from .method import UNITS, Equation
from .titles import TitleBlock

__all__ = ["build_html", "render_html", "CSS"]

CSS = """
body { font-family: "DejaVu Sans", "Segoe UI", Helvetica, Arial, sans-serif; color: #1f2937;
       max-width: 1100px; margin: 24px auto; padding: 0 16px; line-height: 1.4; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { font-size: 1.25em; border-bottom: 1px solid #ced4da; padding-bottom: 4px;
     margin-top: 2em; }
.title-block { font-size: 0.9em; background: #f1f3f5; border-left: 4px solid #1c7ed6;
               padding: 6px 10px; margin: 8px 0; white-space: pre-wrap; }
.title-block .what { font-weight: bold; font-size: 1.05em; }
.note { color: #862e9c; }
table { border-collapse: collapse; margin: 10px 0 18px 0; font-size: 0.92em; }
caption { text-align: left; font-weight: bold; padding-bottom: 4px; }
th, td { border: 1px solid #ced4da; padding: 3px 8px; text-align: left; }
th { background: #e9ecef; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
figure { margin: 10px 0; }
figure svg { max-width: 100%; height: auto; }
.equation { margin: 12px 0; }
.equation .plain { font-family: "DejaVu Sans Mono", monospace; font-size: 0.85em;
                   color: #495057; }
.thesis { font-style: italic; }
"""

_NUM = re.compile(r"^[-+]?[\d,.]+( (dB|Hz|%|km/h))?$")


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


def _svg(fig: Figure) -> str:
    """Inline SVG text of a figure: no XML prolog, doctype or metadata block."""
    text = figures.render(fig, "svg").decode("utf-8")
    text = text[text.index("<svg") :]
    return re.sub(r"<metadata>.*?</metadata>", "", text, flags=re.S)


@lru_cache(maxsize=16)
def _equation_svg(mathtext: str) -> str:
    fig = Figure(figsize=(9.5, 0.45))
    fig.text(0.005, 0.5, mathtext, fontsize=12, va="center", gid=figures.MATH_GID)
    return _svg(fig)


def _table(t: Table) -> str:
    head = "".join(f"<th>{_e(h)}</th>" for h in t.header)
    rows = []
    for row in t.rows:
        cells = "".join(
            f'<td class="num">{_e(c)}</td>' if _NUM.match(c) else f"<td>{_e(c)}</td>" for c in row
        )
        rows.append(f"<tr>{cells}</tr>")
    return (
        f"<table><caption>{_e(t.caption)}</caption><thead><tr>{head}</tr></thead>"
        f"<tbody>{''.join(rows)}</tbody></table>"
    )


def _title_block(tb: TitleBlock) -> str:
    lines = "\n".join(_e(line) for line in tb.lines)
    return f'<div class="title-block"><div class="what">{_e(tb.what)}</div>{lines}</div>'


def _equation(eq: Equation) -> str:
    return (
        f'<div class="equation" id="eq-{_e(eq.number)}"><b>Eq. {_e(eq.number)}</b> '
        f"{_e(eq.name)}"
        f'<div role="img" aria-label="{_e(eq.plain)}">{_equation_svg(eq.mathtext)}</div>'
        f'<div class="plain">{_e(eq.plain)}</div><p>{_e(eq.meaning)}</p></div>'
    )


def render_html(rep: Report) -> str:
    """The HTML text of formatted report content."""
    out = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{_e(rep.title)}</title><style>{CSS}</style></head><body>",
        f"<h1>{_e(rep.title)}</h1>",
        _title_block(rep.title_block),
    ]
    if rep.url:
        out.append(
            f'<p>Reproduce this page: <a href="{_e(rep.url)}" id="reproduce">{_e(rep.url)}</a></p>'
        )
    out.append(f'<p class="note">{_e(rep.reproduce_note)}</p>')
    if rep.verdict is not None:  # the review's question first
        v = rep.verdict
        out.append(f'<section id="{_e(v.key)}"><h2>{_e(v.heading)}</h2>')
        out += [f"<p>{_e(p)}</p>" for p in v.paragraphs]
        out += [_table(t) for t in (*v.tables, *v.long_tables)]
        out.append("</section>")
    sm = rep.summary
    out.append('<section id="summary"><h2>Summary</h2>')
    out.append(_table(Table("The case in numbers", ("quantity", "value"), sm.rows)))
    if sm.peak_rows:
        out.append(_table(Table(sm.peak_caption, sm.peak_header, sm.peak_rows)))
    out.append("</section>")
    for sec in rep.sections:
        out.append(f'<section id="{_e(sec.key)}"><h2>{_e(sec.heading)}</h2>')
        out += [f"<p>{_e(p)}</p>" for p in sec.paragraphs]
        if sec.title is not None:
            out.append(_title_block(sec.title))
        if sec.figure is not None:
            fig = figures.standalone(sec.figure, width_in=10.0, title=False)
            out.append(
                f'<figure id="figure-{_e(sec.key)}" data-file="{_e(sec.figure.stem)}">'
                f"<figcaption>{_title_block(sec.figure.title)}</figcaption>{_svg(fig)}</figure>"
            )
        out += [_table(t) for t in sec.tables]
        out.append("</section>")
    out.append('<section id="tables"><h2>Tables</h2>')
    for sec in rep.sections:
        if sec.long_tables:
            out.append(f'<div id="tables-{_e(sec.key)}">')
            out += [_table(t) for t in sec.long_tables]
            out.append("</div>")
    out.append("</section>")
    out.append(f'<section id="data"><h2>Data in use</h2>{_table(rep.provenance)}</section>')
    out.append(f'<section id="settings"><h2>Settings</h2>{_table(rep.settings)}</section>')
    out.append('<section id="method"><h2>Method</h2>')
    out += [f"<p>{_e(p)}</p>" for p in rep.method]
    out += [_equation(eq) for eq in rep.equations]
    out += [f"<p>{_e(u)}</p>" for u in UNITS]
    out.append(f'<p>Reference: <span class="thesis">{_e(rep.thesis)}</span>.</p></section>')
    out.append("</body></html>")
    return "\n".join(out)


def build_html(snap: ReportData) -> tuple[str, str]:
    """``(file name, HTML text)`` of the report of a snapshot."""
    rep = report_content(snap)
    return f"{rep.stem}.html", render_html(rep)
