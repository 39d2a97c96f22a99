"""The report of a real snapshot, opened: the HTML file parsed, the PDF's text extracted.

Numbers are checked against values computed here independently from the result objects
passed in (peak levels from the FRFs, the eq. 5.1 error summed by hand over 12 Hz bands).
"""

from __future__ import annotations

import io
import re
from html.parser import HTMLParser

import numpy as np
import pytest
import report_snapshot
from pypdf import PdfReader
from report_snapshot import SETTINGS, URL, K, N

from app.report import ReportData, ReportError, build_html, build_pdf
from app.report.method import THESIS
from app.report.titles import harmonic_description


@pytest.fixture(scope="module")
def results():
    return report_snapshot.results()


@pytest.fixture(scope="module")
def snap(results):
    return report_snapshot.snapshot(results)


@pytest.fixture(scope="module")
def html_report(snap):
    return build_html(snap)


@pytest.fixture(scope="module")
def pdf_report(snap):
    return build_pdf(snap)


class _Page(HTMLParser):
    """Collects tags, URL attributes, text and tables of an HTML document."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.tags, self.urls, self.text, self.tables = [], [], [], {}
        self._caption = self._row = self._cell = None
        self._table = None

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        for k, v in attrs:
            if k in ("src", "href", "xlink:href", "action", "srcset", "data", "poster"):
                self.urls.append(v)
        if tag == "table":
            self._table, self._caption = [], ""
        elif tag == "caption":
            self._cell = []
        elif tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag == "caption":
            self._caption, self._cell = "".join(self._cell), None
        elif tag in ("td", "th"):
            self._row.append("".join(self._cell).strip())
            self._cell = None
        elif tag == "tr":
            self._table.append(self._row)
        elif tag == "table":
            self.tables[self._caption] = self._table
            self._table = None

    def handle_data(self, data):
        self.text.append(data)
        if self._cell is not None:
            self._cell.append(data)


@pytest.fixture(scope="module")
def parsed(html_report):
    p = _Page()
    p.feed(html_report[1])
    return p


def _pdf_text(data: bytes) -> str:
    reader = PdfReader(io.BytesIO(data))
    return "\n".join(pg.extract_text() for pg in reader.pages)


def _peak(frf) -> tuple[float, float]:
    v = frf.sel(outputs="bushing:z", inputs="patch").data[:, 0, 0]
    lv = 20 * np.log10(np.abs(v))
    i = int(np.argmax(lv))
    return float(lv[i]), float(frf.freq[i])


def _eq51_max(ref, mod, f_max, width=12.0):
    """Largest eq. 5.1 error up to f_max over 1 Hz centres, by hand (clipped bands)."""
    f = ref.freq
    pr = np.abs(ref.sel(outputs="bushing:z").data[:, 0, 0]) ** 2
    pm = np.abs(mod.sel(outputs="bushing:z").data[:, 0, 0]) ** 2
    best, at = -1.0, None
    for c in np.arange(np.ceil(f[0]), np.floor(f[-1]) + 1):
        if c > f_max:
            break
        band = np.abs(f - c) <= width / 2 + 1e-9
        e = np.sum(np.abs(pr[band] - pm[band])) / np.sum(pr[band])
        if e > best:
            best, at = e, c
    return 100 * best, at


def test_file_names(html_report, pdf_report):
    assert html_report[0] == "tire-fbs_h1_bushing-z_N20_6dof_upload_2026-12-01.html"
    assert pdf_report[0] == "tire-fbs_h1_bushing-z_N20_6dof_upload_2026-12-01.pdf"


def test_html_makes_no_network_request(parsed, html_report):
    assert "script" not in parsed.tags and "link" not in parsed.tags and "img" not in parsed.tags
    assert parsed.urls, "the reproducing link and the SVG glyph references"
    for u in parsed.urls:
        # in-document references, inline images (the error map's cells) or the link
        assert u.startswith(("#", "data:image/png;base64,")) or u == URL, u
    text = html_report[1]
    assert not re.search(r"url\(\s*['\"]?(https?:)?//", text)
    assert "@import" not in text
    # the only http(s) addresses: the link and the SVG/XLink namespace names
    others = set(re.findall(r"https?://[^\s\"'<>]+", text)) - {URL.replace("&", "&amp;")}
    assert others <= {"http://www.w3.org/2000/svg", "http://www.w3.org/1999/xlink"}, others


def test_html_holds_the_numbers(parsed, snap):
    tabs = parsed.tables
    sugg = tabs["Suggested number of modes"]
    assert sugg[0][2] == "suggested N"
    assert [r[2] for r in sugg[1:]] == [str(int(n)) for n in snap.suggested.n_modes]
    assert sugg[1][1] == "12.9-51.6 Hz"
    peaks = tabs["Peak level at bushing:z (dB re 1 (m/s)/m)"]
    lv, f = _peak(snap.reference)
    assert peaks[1][:3] == ["all tire modes", f"{lv:.2f} dB", f"{f:.1f} Hz"]
    lv, f = _peak(snap.truncated)
    assert peaks[2][:3] == [f"N = {N} modes", f"{lv:.2f} dB", f"{f:.1f} Hz"]
    err, at = _eq51_max(snap.reference, snap.truncated, 40.0)
    rows = {r[0]: r for r in tabs["Largest error up to 40 Hz for each N (bushing:z)"][1:]}
    assert rows[str(N)][1:3] == [f"{err:.1f} %", f"{at:.1f} Hz"]
    assert rows[str(N)][3] == ("below" if err < 20 else "at or above")
    assert "chosen" in rows[str(N)][4]
    assert "suggested" in rows[str(int(snap.suggested.n_modes[0]))][4]
    band = tabs[next(c for c in tabs if c.startswith("Levels at the reference peak"))]
    j = snap.band.dofs.index("bushing:z")
    i = int(np.argmax(np.abs(snap.band.reference[:, j])))
    hi = 20 * np.log10(snap.band.maximum[i, j])
    assert ["maximum over the rounds", f"{hi:.2f} dB"] in band
    data = tabs["Data in use"]
    assert ["chassis", "uploaded file 'rear corner <v2>.uff'", "0123abcd4567"] in data
    assert ["tire", "reference (shipped model)", "-"] in data


def test_html_title_blocks_method_and_link(parsed, html_report):
    text = " ".join(parsed.text)
    assert text.count(harmonic_description(K)) >= 4  # report and every plot's block
    assert text.count("uploaded chassis 'rear corner <v2>.uff'") >= 4
    assert "&lt;v2&gt;" in html_report[1]  # the file name is text, never markup
    assert THESIS in text
    for eq in ("2.44", "4.1", "5.1", "5.2", "5.3", "5.4"):
        assert f"Eq. {eq}" in text
    assert "only after uploading the same file(s)" in text
    assert text.count("2026-12-01 20:15 UTC") >= 4
    n_fig = len(re.findall(r'<figure id="figure-', html_report[1]))
    assert n_fig == 4  # coupled response, error map, scatter band, eigenfrequency


def test_pdf_holds_the_same(pdf_report, snap):
    data = pdf_report[1]
    assert data.startswith(b"%PDF")
    text = _pdf_text(data)
    flat = re.sub(r"\s+", " ", text)
    lv, f = _peak(snap.reference)
    assert re.search(rf"all tire modes\s+{lv:.2f} dB\s+{f:.1f} Hz", text)
    err, at = _eq51_max(snap.reference, snap.truncated, 40.0)
    assert re.search(rf"\n{N}\s+{err:.1f} %\s+{at:.1f} Hz", text)
    n_s = int(snap.suggested.n_modes[0])
    assert re.search(rf"\n1\s+12\.9-51\.6 Hz\s+{n_s}\s", text)
    assert harmonic_description(K) in flat
    assert "uploaded chassis 'rear corner <v2>.uff', digest 0123abcd4567" in flat
    assert "Rosholm" in flat and "Chalmers University of Technology, 2018" in flat
    for eq in ("2.44", "4.1", "5.1", "5.2", "5.3", "5.4"):
        assert f"Eq. {eq}" in flat
    assert URL in flat.replace(" ", "")


def test_reference_data_report_says_so(results):
    s = ReportData(settings=SETTINGS, url=URL, truncation=results["truncation"])
    name, text = build_html(s)
    assert "_upload" not in name
    assert "reproduces this page with the shipped reference models" in text


def test_snapshot_refuses_results_that_do_not_match(results):
    with pytest.raises(ReportError, match="the band was computed with"):
        ReportData(settings={**SETTINGS, "rounds": 400}, band=results["band"])
    with pytest.raises(ReportError, match="not the 10 and 90 %"):
        ReportData(settings={**SETTINGS, "percentile": 80}, band=results["band"])
    with pytest.raises(ReportError, match="harmonic 1, not 2"):
        ReportData(settings={**SETTINGS, "harmonic": 2}, truncation=results["truncation"])
    with pytest.raises(ReportError, match="suggested modes were read at threshold 20 %"):
        ReportData(settings={**SETTINGS, "threshold": 10.0}, suggested=results["suggested"])
    with pytest.raises(ReportError, match="needs the setting"):
        ReportData(
            settings=dict(harmonic=1, n_modes=20, dof="z", coupling="6dof"), band=results["band"]
        )


def test_a_plot_of_a_missing_result_is_a_report_error(results):
    from app.report import figures

    s = ReportData(settings=SETTINGS, url=URL, truncation=results["truncation"])  # no band
    with pytest.raises(ReportError, match="hold no scatter band"):
        figures.draw_band(s)
    with pytest.raises(ReportError, match="hold no eigenfrequencies"):
        figures.draw_eigen(s)


def test_plot_file_png_carries_the_title_block(snap):
    from PIL import Image

    from app.report import plot_file

    name, png = plot_file(snap, "truncation-map", "png")
    assert name == "tire-fbs_truncation-map_h1_bushing-z_thr20_6dof_upload_2026-12-01.png"
    im = Image.open(io.BytesIO(png))
    assert im.format == "PNG" and im.width > 800
    name, pdf = plot_file(snap, "truncation-map", "pdf")
    flat = re.sub(r"\s+", " ", _pdf_text(pdf))
    assert harmonic_description(K) in flat and "Truncation error (eq. 5.1" in flat
    assert "uploaded chassis 'rear corner <v2>.uff'" in flat
    with pytest.raises(ReportError, match="no 'uncoupled' plot in this snapshot; plots: "):
        plot_file(snap, "uncoupled")
