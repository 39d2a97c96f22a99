"""Title blocks, file names and the help page of app.report (no results needed)."""

from __future__ import annotations

import datetime as dt
import re
from pathlib import Path

import pytest

import fbs_core
from app.report import DataFile, Provenance, ReportData, ReportError, file_stem, title_block
from app.report.data import normalise_settings
from app.report.titles import VIEWS, harmonic_description

DATE = dt.datetime(2026, 12, 1, 20, 15, tzinfo=dt.UTC)
SETTINGS = dict(
    harmonic=4,
    n_modes=60,
    dof="z",
    coupling="6dof",
    threshold=20.0,
    f_max=160.0,
    map_mode="selected DOF",
    noise=10.0,
    target="both",
    frequency_dependent=False,
    rounds=10_000,
    seed=0,
    single_round=0,
    percentile=90,
)


def snap(**kw) -> ReportData:
    kw.setdefault("settings", SETTINGS)
    kw.setdefault("created", DATE)
    return ReportData(**kw)


# wavelengths of thesis table 5.1 / fig. 4.4 and the band f = v / lambda at 30 and 120 km/h
@pytest.mark.parametrize(
    "k, lam",
    [(1, 0.646), (2, 0.499), (3, 0.339), (4, 0.2395), (5, 0.166), (6, 0.1156), (7, 0.0789)],
)
def test_harmonic_description_has_wavelength_speeds_and_band(k, lam):
    text = harmonic_description(k)
    lo, hi = 30 / 3.6 / lam, 120 / 3.6 / lam
    assert text == (
        f"Harmonic {k}: road wavelength {lam:g} m, 30-120 km/h, band {lo:.1f}-{hi:.1f} Hz"
    )


def test_harmonic_description_refuses_unknown_case():
    with pytest.raises(fbs_core.FBSError, match="allowed: 1, 2, 3, 4, 5, 6, 7"):
        harmonic_description(8)


def test_report_file_stem_says_what_it_shows():
    assert file_stem(snap()) == "tire-fbs_h4_bushing-z_N60_6dof_2026-12-01"
    up = snap(provenance=Provenance(chassis=DataFile("chassis", "car.uff", "ab12")))
    assert file_stem(up) == "tire-fbs_h4_bushing-z_N60_6dof_upload_2026-12-01"


def test_view_file_stems_differ_and_are_safe():
    s = snap(settings={**SETTINGS, "noise": 12.5, "frequency_dependent": True})
    stems = {v: file_stem(s, v) for v in VIEWS}
    assert len(set(stems.values())) == len(VIEWS)
    for stem in stems.values():
        assert re.fullmatch(r"[A-Za-z0-9._-]+", stem), stem
        assert stem.endswith("2026-12-01")
    assert stems["scatter-band"] == (
        "tire-fbs_scatter-band_h4_bushing-z_N60_6dof_p12.5-both_R10000_fdep_2026-12-01"
    )
    assert (
        stems["suggested-modes"]
        == "tire-fbs_suggested-modes_thr20_fmax160_bushing-z_6dof_2026-12-01"
    )
    mx = snap(settings={**SETTINGS, "map_mode": "max over 6 DOFs"})
    assert (
        file_stem(mx, "truncation-map")
        == "tire-fbs_truncation-map_h4_bushing-max6_thr20_6dof_2026-12-01"
    )


def test_title_block_lines():
    prov = Provenance(
        tire=DataFile("tire", "my tire.h5", "d1g3st"),
        chassis=DataFile("chassis", "car.uff", "ab12"),
    )
    url = "http://localhost:5006/main?h=4&N=60&dof=z"
    tb = title_block(snap(provenance=prov, url=url, n_modes_total=400), "scatter-band")
    text = tb.text
    assert tb.what.startswith("Noise scatter band")
    assert harmonic_description(4) in tb.lines
    assert "DOF bushing:z | N = 60 of 400 tire modes | 6-DOF hub coupling (braked wheel)" in text
    assert "Noise p = 10 % in tire and chassis (eq. 5.4)" in text
    assert "R = 10,000 rounds, seed 0, 90 % central band, round #0" in text
    assert "uploaded tire 'my tire.h5', digest d1g3st" in text
    assert "uploaded chassis 'car.uff', digest ab12" in text
    assert "2026-12-01 20:15 UTC" in text
    assert tb.lines[-1] == url
    # noise only where it applies
    assert "Noise" not in title_block(snap(), "coupled-response").text
    tm = title_block(snap(), "truncation-map").text
    assert "chosen N = 60 tire modes" in tm and "threshold 20 % up to f_max 160 Hz" in tm
    assert "reference tire and chassis (shipped models)" in tm
    allmodes = title_block(snap(n_modes_total=60), "coupled-response").text
    assert "N = all 60 tire modes" in allmodes


def test_title_block_errors():
    with pytest.raises(ReportError, match="unknown view 'bode'; allowed: report, "):
        title_block(snap(), "bode")
    bare = snap(settings=dict(harmonic=1, n_modes=50, dof="x", coupling="5dof"))
    with pytest.raises(ReportError, match="needs the setting"):
        title_block(bare, "scatter-band")
    # the report's title takes what there is
    assert "5-DOF hub coupling" in title_block(bare, "report").text


@pytest.mark.parametrize(
    "change, message",
    [
        ({"harmonic": 8}, "allowed: 1, 2, 3, 4, 5, 6, 7"),
        ({"dof": "q"}, "allowed: x, y, z, rx, ry, rz"),
        ({"coupling": "4dof"}, "allowed: 6dof, 5dof"),
        ({"n_modes": 12.5}, "must be an integer"),
        ({"n_modes": 0}, "must be >= 1"),
        ({"threshold": -1}, "must be > 0"),
        ({"noise": "lots"}, "must be a number"),
        ({"frequency_dependent": 1}, "True or False"),
        ({"colour": "red"}, "unknown setting"),
    ],
)
def test_settings_validation(change, message):
    with pytest.raises(ReportError, match=message):
        normalise_settings({**SETTINGS, **change})


def test_snapshot_validation():
    with pytest.raises(ReportError, match="missing setting"):
        ReportData(settings={"harmonic": 1})
    with pytest.raises(ReportError, match="http"):
        snap(url="javascript:alert(1)")
    with pytest.raises(ReportError, match="quotes"):
        snap(url='http://x/"><script>')
    with pytest.raises(ReportError, match="must be a FRF"):
        snap(reference="not an FRF")
    with pytest.raises(ReportError, match="allowed: tire, chassis"):
        DataFile("wheel")
    naive = snap(created=dt.datetime(2026, 12, 1, 8, 0))
    assert naive.created.tzinfo is not None


def test_help_page_names_the_thesis_equations_and_the_harmonics():
    text = (Path(__file__).parents[1] / "app" / "page" / "help.md").read_text()
    flat = re.sub(r"\s*\n>?\s*", " ", text)
    assert (
        'J. Rosholm and M. Westers, "Assembly of a tire and a vehicle model to predict '
        'vibrations at the bushings", MSc thesis, Chalmers University of Technology, 2018' in flat
    )
    for eq in ("2.44", "4.1", "5.1", "5.2", "5.3", "5.4"):
        assert f"eq. {eq}" in text or f"({eq})" in text, eq
    # the harmonics table matches f = v / lambda at 30 and 120 km/h
    rows = re.findall(r"^\| (\d) \| ([\d.]+) \| ([\d.]+)-([\d.]+) \|$", text, re.M)
    assert len(rows) == 7
    for k, lam, lo, hi in rows:
        h = fbs_core.harmonic(int(k))
        assert float(lam) == h.wavelength
        assert float(lo) == round(30 / 3.6 / float(lam), 1)
        assert float(hi) == round(120 / 3.6 / float(lam), 1)


def test_help_covers_the_analysis_card_residual_compensation_presentation_and_uploads():
    """Issue 29: the help said nothing of these. Each has a section, and each tab of the
    Analysis card (the state's own list) and each upload format is named in it."""
    from app.state.analysis import ANALYSIS_TABS

    text = (Path(__file__).parents[1] / "app" / "page" / "help.md").read_text()
    heads = re.findall(r"^## (.+)$", text, flags=re.M)
    for head in ("The Analysis card", "The presentation view", "Uploads"):
        assert head in heads, head
    assert "**Residual compensation**" in text
    card = text.split("## The Analysis card")[1].split("\n## ")[0]
    for tab in ANALYSIS_TABS:
        if tab:
            assert f"**{tab.capitalize()}.**" in card, tab
    uploads = text.split("## Uploads")[1].split("\n## ")[0]
    for fmt in ("UFF 58", "MATLAB", "CSV", "HDF5", "100 MiB"):
        assert fmt in uploads, fmt
    assert "?view=present" in text and "FBS_PUBLIC_URL" in text
