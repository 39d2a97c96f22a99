"""The report's first page holds the summary (issue 29): the suggested N and the chosen N's
largest eq. 5.1 error, the band's width at the peaks, the largest contributions and the
peak table; then the plots; the long tables last.

Truth: the eq. 5.1 error summed by hand over the bands of the FRFs, the band's width
read from its minimum and maximum, the shares of the contributions from their terms
(``Re(t conj(total)) / |total|^2`` by hand), the suggestion by its definition.
"""

from __future__ import annotations

import dataclasses
import io
import re

import numpy as np
import pytest
from pypdf import PdfReader

from app.report import build_html, build_pdf
from app.report.summary import report_summary
from fbs_core.analysis import bushing_contributions, peak_labels
from tests import report_snapshot
from tests.report_snapshot import N
from tests.test_report_files import _eq51_max


@pytest.fixture(scope="module")
def snap():
    res = report_snapshot.results()
    tr = res["truncated"].sel(outputs="bushing:z", inputs="patch")
    peaks = peak_labels(tr, harmonic=1, max_peaks=8)
    con = bushing_contributions(1, n_modes=N)
    return dataclasses.replace(report_snapshot.snapshot(res), peaks=peaks, contributions=con)


def _rows(snap) -> dict[str, str]:
    return dict(report_summary(snap).rows)


def _suggested_by_definition(m, thr, fmax, dof) -> int:
    """The smallest N of the map from which the error stays below ``thr`` up to fmax."""
    err = 100 * m.dof_error(dof)[:, m.centres <= fmax].max(axis=1)
    ok = err < thr
    for i in range(len(ok)):
        if ok[i:].all():
            return int(m.n_modes[i])
    return int(m.n_modes_total)


def test_the_summary_holds_the_suggested_n_and_the_chosen_ns_largest_error(snap):
    rows = _rows(snap)
    n_s = _suggested_by_definition(snap.truncation, 20.0, 40.0, "bushing:z")
    assert rows["suggested N"].startswith(f"{n_s}: ")
    err, at = _eq51_max(snap.reference, snap.truncated, 40.0, width=snap.truncation.width)
    text = rows[f"largest eq. 5.1 error of the chosen N = {N}"]
    assert text.startswith(f"{err:.1f} % at the {at:.1f} Hz band")
    assert ("below" if err < 20 else "at or above") in text


def _line(freq, f):
    return int(np.argmin(np.abs(freq - f)))


def test_the_peak_table_holds_band_width_and_contributions_at_each_peak(snap):
    sm = report_summary(snap)
    tr = snap.truncated.sel(outputs="bushing:z", inputs="patch").data[:, 0, 0]
    b, c = snap.band, snap.contributions
    j = b.dofs.index("bushing:z")
    terms = c.at("bushing:z").data[:, 0, :]
    assert len(sm.peak_rows) == len(snap.peaks) >= 1
    for p, row in zip(sorted(snap.peaks, key=lambda p: p.freq), sm.peak_rows, strict=True):
        i = _line(snap.truncated.freq, p.freq)
        assert abs(20 * np.log10(abs(tr[i])) - p.level_db) < 1.0  # a peak of this curve
        assert row[0] == f"{p.freq:.1f} Hz" and row[2] == f"{p.level_db:.2f} dB"
        width = 20 * np.log10(b.maximum[i, j] / b.minimum[i, j])
        assert row[4] == f"{width:.2f} dB"
        tot = terms[i].sum()
        shares = (terms[i] * np.conj(tot)).real / abs(tot) ** 2
        k = int(np.argmax(np.abs(shares)))
        assert row[5].startswith(f"{c.interface[k]} {100 * shares[k]:.0f} %")
    i = int(np.argmax(np.abs(tr)))  # the highest level of the plotted curve
    i = _line(b.freq, snap.truncated.freq[i])
    width = 20 * np.log10(b.maximum[i, j] / b.minimum[i, j])
    assert _rows(snap)["scatter band width at the highest level"].startswith(f"{width:.2f} dB")


def _edge_snap(snap, edge: int):
    """``snap`` whose N-mode response rises at one edge line above all its peaks (the
    review's case: a peak at 62.3 Hz, the plotted maximum at the band's edge)."""
    tr = snap.truncated
    data = np.array(tr.data, copy=True)
    j = list(tr.outputs).index("bushing:z")
    data[edge, j, 0] = 4 * np.abs(data[:, j, 0]).max()
    return dataclasses.replace(snap, truncated=type(tr)(tr.freq, data, tr.outputs, tr.inputs))


@pytest.mark.parametrize("edge", [0, -1])
def test_one_rule_for_the_highest_level_corner_and_car_the_band_edge_counts(snap, edge):
    """The summary's highest level is the plotted maximum over the whole band, the edge
    lines included, whether the data hold peak labels (the corner) or not (the car)."""
    s = _edge_snap(snap, edge)
    tr = s.truncated.sel(outputs="bushing:z").data[:, 0, 0]
    lv = 20 * np.log10(np.abs(tr))
    i = int(np.argmax(lv))
    assert i == (edge % lv.size)
    f = s.truncated.freq[i]
    side = "lower" if edge == 0 else "upper"
    for variant in (s, dataclasses.replace(s, peaks=())):  # with and without peak labels
        text = _rows(variant)["highest level of bushing:z"]
        assert text.startswith(f"{lv[i]:.2f} dB at {f:.1f} Hz (the band's {side} edge)"), text
    # the highest labelled peak, inside the band, is said beside it
    pk = max(s.peaks, key=lambda p: p.level_db)
    assert _rows(s)["highest labelled peak"].startswith(f"{pk.level_db:.2f} dB at {pk.freq:.1f}")


def test_without_band_or_contributions_the_summary_says_which_view_computes_them(snap):
    bare = dataclasses.replace(snap, band=None, contributions=None)
    rows = _rows(bare)
    assert "not computed for these settings" in rows["scatter band width at the highest level"]
    key = "largest contributions at the highest level (share of the total)"
    assert "Contributions tab" in rows[key]
    assert "band max - min" not in report_summary(bare).peak_header


def test_the_first_pdf_page_is_the_summary_then_the_plots_then_the_long_tables(snap):
    _, pdf = build_pdf(snap)
    pages = [p.extract_text() for p in PdfReader(io.BytesIO(pdf)).pages]
    first = pages[0]
    n_s = _suggested_by_definition(snap.truncation, 20.0, 40.0, "bushing:z")
    err, at = _eq51_max(snap.reference, snap.truncated, 40.0, width=snap.truncation.width)
    assert "Summary" in first and re.search(rf"suggested N\s+{n_s}:", first)
    assert f"{err:.1f} % at the {at:.1f} Hz band" in first
    top = min(snap.peaks, key=lambda p: p.freq)
    row = rf"{top.freq:.1f} Hz\s+{top.speed_kmh:.1f} km/h\s+{top.level_db:.2f} dB"
    assert re.search(row, first)
    assert "Settings of the page" not in first and "Largest error up to" not in first
    assert "Coupled response" in pages[1]  # the first plot on page 2
    plot_pages = [k for k, t in enumerate(pages) if "Eigenfrequency vs number of modes" in t]
    long = [k for k, t in enumerate(pages) if "Largest error up to 40 Hz for each N" in t]
    settings = [k for k, t in enumerate(pages) if "Settings of the page" in t]
    assert long and settings and min(long) > max(plot_pages) and min(settings) >= min(long)


def test_the_html_report_opens_with_the_summary_and_ends_with_the_long_tables(snap):
    _, html = build_html(snap)
    pos = {
        k: html.index(v)
        for k, v in {
            "summary": 'id="summary"',
            "figure": "<figure",
            "tables": 'id="tables"',
            "per-N": "Largest error up to 40 Hz for each N",
            "settings": 'id="settings"',
        }.items()
    }
    assert pos["summary"] < pos["figure"] < pos["tables"] < pos["per-N"] < pos["settings"]
    assert html.rindex("<figure") < pos["tables"]
    assert "The case in numbers" in html[: pos["figure"]]
