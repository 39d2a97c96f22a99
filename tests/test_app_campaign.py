"""The dashboard's campaign browser: the files of FBS_CAMPAIGN_DIR, their cases with
filters, and the chosen case's numbers and provenance.

Truth: the campaign file read independently with h5py (the stored blocks and maps), and the
campaign's own TOML (the case matrix).
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from app.export import read_csv, to_csv
from app.views.campaign import CampaignBrowser, case_rows, list_campaigns
from fbs_core.campaign import open_campaign, parse_campaign, run_campaign

TOML = """
[campaign]
name = "browse"
seed = 99
output = "{out}"
[scatter]
harmonics = [1]
noise = [0.05, 0.1]
targets = ["tire", "both"]
frequency_dependent = [false]
rounds = 200
percentiles = [5.0, 95.0]
[truncation]
harmonics = [1]
n_modes = {{ from = 10, to = 50, step = 10 }}
thresholds = [0.2]
f_max = [130.0]
couplings = ["6dof"]
[execution]
task_round_lines = 4000
"""


@pytest.fixture(scope="module")
def campaign_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("campaigns")
    camp = parse_campaign(TOML.format(out=(d / "browse.h5").as_posix()), d)
    assert run_campaign(camp).status == "complete"
    (d / "notes.h5").write_bytes(b"not an HDF5 file")  # listed only if a campaign
    with h5py.File(d / "other.h5", "w") as h:
        h.attrs["content"] = "frf"
    return d


def _labels(attr) -> list[str]:
    """DOF labels as the store writes them (a JSON list)."""
    return [str(x) for x in json.loads(attr)] if isinstance(attr, str) else list(attr)


def _stored_band(path, name):
    """Edges and percentiles of a case, joined from its stored blocks with h5py alone."""
    with h5py.File(path, "r") as h:
        g = h["cases"][name]["blocks"]
        keys = sorted(g, key=lambda k: int(k.split("_")[0]))
        lo = np.concatenate([g[k]["lower"][()] for k in keys])
        hi = np.concatenate([g[k]["upper"][()] for k in keys])
        pct = np.concatenate([g[k]["percentiles"][()] for k in keys], axis=1)
        inputs = h["cases"][name].attrs["inputs"]
        freq = h["inputs"][inputs]["freq"][()]
        ref = h["inputs"][inputs]["reference"][()]
        dofs = _labels(h["inputs"][inputs].attrs["dofs"])
    return freq, ref, lo, hi, pct, dofs, len(keys)


def test_lists_only_campaign_files_of_the_directory(campaign_dir):
    assert list_campaigns(campaign_dir) == ["browse.h5"]
    assert list_campaigns(None) == []


def test_case_table_holds_every_case_of_the_matrix_with_its_settings(campaign_dir):
    res = open_campaign(campaign_dir / "browse.h5")
    rows = case_rows(res)
    camp = parse_campaign(TOML.format(out="x.h5"), campaign_dir)
    assert sorted(rows["case"]) == sorted(c.name for c in camp.cases)  # 4 bands + 1 map
    for c in camp.band_cases:
        i = rows["case"].index(c.name)
        assert rows["harmonic"][i] == 1 and rows["noise_pct"][i] == pytest.approx(100 * c.noise)
        assert rows["target"][i] == c.target and rows["seed"][i] == str(c.seed)
        assert rows["rounds"][i] == 200 and rows["status"][i] == "complete"
    (t,) = [i for i, k in enumerate(rows["kind"]) if k == "truncation"]
    assert rows["truncation"][t] == "N = 10..50 (5)"


def test_filters_and_the_chosen_band_are_the_files_numbers(campaign_dir):
    b = CampaignBrowser(directory=campaign_dir)
    b.__panel__()
    assert b.file == "browse.h5"
    assert len(b.param.case.objects) == 5
    b.param.update(kind="scatter", noise=10.0, target="tire")
    (name,) = b.param.case.objects
    assert b.case == name and list(b._table.value["case"]) == [name]
    b.dof = "y"
    path = campaign_dir / "browse.h5"
    freq, ref, lo, hi, pct, dofs, n_blocks = _stored_band(path, name)
    assert n_blocks > 1  # joined from several stored blocks
    j = dofs.index("bushing:y")
    cols = b.shown.columns
    np.testing.assert_array_equal(cols["freq_Hz"], freq)
    np.testing.assert_array_equal(cols["minimum"], lo[:, j])
    np.testing.assert_array_equal(cols["maximum"], hi[:, j])
    np.testing.assert_array_equal(cols["p95"], pct[1, :, j])
    np.testing.assert_array_equal(cols["reference"], np.abs(ref[:, j]))
    np.testing.assert_allclose(b._band_src.data["hi"], 20 * np.log10(hi[:, j]), rtol=1e-12)
    # the provenance and the export carry the case's seed and the campaign's
    with h5py.File(path, "r") as h:
        seed = str(h["cases"][name].attrs["settings"])
        digest = str(h["cases"][name].attrs["digest"])
    meta, back = read_csv(to_csv(cols, b.shown.meta, "campaign"))
    assert meta["case digest"] == digest and meta["campaign seed"] == "99"
    assert f'"seed": {meta["case seed"]}' in seed
    np.testing.assert_allclose(back["maximum"], hi[:, j], rtol=1e-12)


def test_the_chosen_truncation_case_shows_the_stored_map_and_suggestion(campaign_dir):
    b = CampaignBrowser(directory=campaign_dir)
    b.__panel__()
    b.kind = "truncation"
    (name,) = b.param.case.objects
    with h5py.File(campaign_dir / "browse.h5", "r") as h:
        g = h["cases"][name]["result"]
        err, n, centres, sugg = (g[k][()] for k in ("error", "n_modes", "centres", "suggested"))
        dofs = _labels(g.attrs["dofs"])
    b.dof = "x"
    e = b.shown.columns["error_pct"].reshape(n.size, centres.size)
    np.testing.assert_array_equal(e, 100 * err[:, :, dofs.index("bushing:x")])
    b.max_over_dofs = True
    e = b.shown.columns["error_pct"].reshape(n.size, centres.size)
    np.testing.assert_array_equal(e, 100 * err.max(axis=2))
    np.testing.assert_array_equal(b._map_src.data["image"][0], 100 * err.max(axis=2))
    assert b.shown.draw["suggested"] == {"20 % up to 130 Hz": int(sugg[0, 0])}
    assert f"**{int(sugg[0, 0])}**" in b._suggested.object


def test_without_a_directory_the_browser_says_how_to_configure_it(monkeypatch):
    monkeypatch.delenv("FBS_CAMPAIGN_DIR", raising=False)
    b = CampaignBrowser()
    assert b.file is None and "FBS_CAMPAIGN_DIR" in b.message


#: a variants study (issue 32) of a cheap base tire (few orders, six speeds): a rebuild takes
#: a fraction of a second
VARIANTS_TOML = """
[campaign]
name = "corridor"
seed = 7
output = "{out}"
[variants]
name = "cheap"
parameters = ["inflation_pressure", "knuckle_mass"]
design = "saltelli"
n = 2
harmonics = [1, 4]
percentiles = [10.0, 50.0, 90.0]
speeds = [20.0, 40.0, 60.0, 80.0, 100.0, 120.0]
[variants.tire]
orders = [6, 3, 4, 3, -1, -1, -1, -1]
slip_zones = 1
"""


@pytest.fixture(scope="module")
def variants_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("variants")
    camp = parse_campaign(VARIANTS_TOML.format(out=(d / "corridor.h5").as_posix()), d)
    assert run_campaign(camp).status == "complete"
    return d


def test_a_variants_case_is_listed_with_readable_columns(variants_dir):
    rows = case_rows(open_campaign(variants_dir / "corridor.h5"))
    assert rows["case"] == ["variants_cheap"] and rows["kind"] == ["variants"]
    assert rows["harmonic"] == ["1, 4"]
    assert rows["tire"] == ["inflation_pressure; base changed"]  # [variants.tire] given
    assert rows["chassis"] == ["knuckle_mass"]
    assert rows["design"] == ["saltelli n=2 (8 variants)"]  # N (k + 2) = 2 x 4
    assert rows["status"] == ["complete"]
    b = CampaignBrowser(directory=variants_dir)
    assert "variants" in b.param.kind.objects
    b.kind = "variants"
    assert b.param.case.objects == ["variants_cheap"]
    b.harmonic = 4
    assert b.param.case.objects == ["variants_cheap"]
    b.harmonic = 7
    assert b.case is None and "variants_cheap" not in b.param.case.objects


def test_the_chosen_variants_case_draws_the_studys_corridor_and_ranking(variants_dir):
    """Truth: the study read independently (open_campaign(...).variants), its corridor
    recomputed from the stored responses with numpy (min, max, percentiles over the rows)."""
    path = variants_dir / "corridor.h5"
    b = CampaignBrowser(directory=variants_dir)
    b.__panel__()
    b.case = "variants_cheap"
    b.dof = "x"
    b.harmonic = 4
    st = open_campaign(path).variants("variants_cheap")
    mag = np.abs(st.responses[4][:, :, st.corridor(4).dof_index("bushing:x")])
    cols = b.shown.columns
    np.testing.assert_array_equal(cols["freq_Hz"], st.freq(4))
    np.testing.assert_allclose(cols["minimum"], mag.min(axis=0), rtol=1e-12)
    np.testing.assert_allclose(cols["maximum"], mag.max(axis=0), rtol=1e-12)
    np.testing.assert_allclose(cols["p90"], np.percentile(mag, 90, axis=0), rtol=1e-12)
    np.testing.assert_allclose(cols["p10"], np.percentile(mag, 10, axis=0), rtol=1e-12)
    j = st.corridor(4).dof_index("bushing:x")
    np.testing.assert_array_equal(cols["nominal"], np.abs(st.nominal[4][:, j]))
    # what is drawn: the corridor's edges and outer percentiles in dB over the nominal
    d = b._corridor_src.data
    np.testing.assert_allclose(d["hi"], 20 * np.log10(mag.max(axis=0)), rtol=1e-12)
    np.testing.assert_allclose(d["qlo"], 20 * np.log10(np.percentile(mag, 10, axis=0)))
    np.testing.assert_allclose(d["nominal"], 20 * np.log10(np.abs(st.nominal[4][:, j])))
    assert b._corridor_fig.visible and not b._band_fig.visible and not b._map_fig.visible
    # the ranking beside it: the leaders of the study's own Sobol' indices
    lead = st.sensitivity(4).leaders("bushing:x")
    table = b._leaders.value
    assert list(table["leading parameter"]) == [x["parameter"] for x in lead]
    assert len(table) == len(lead) > 0 and b._leaders.visible
    # title block and export: campaign file, case, parameters, percentiles
    for word in ("corridor.h5", "variants_cheap", "harmonic 4", "inflation_pressure", "10, 50, 90"):
        assert word in b.shown.caption
    meta, back = read_csv(to_csv(cols, b.shown.meta, "campaign"))
    assert meta["campaign file"] == "corridor.h5" and meta["case"] == "variants_cheap"
    assert meta["parameters"] == "inflation_pressure, knuckle_mass"
    assert meta["percentiles"] == "10, 50, 90" and meta["harmonic"] == "4"
    assert lead[0]["parameter"] in meta["sensitivity leaders (total Sobol' index per band)"]
    np.testing.assert_allclose(back["maximum"], mag.max(axis=0), rtol=1e-12)
    assert b.shown.filename == "corridor_variants_cheap_h4_x.csv"
    # the other harmonic of the case through the harmonic filter
    b.harmonic = 1
    np.testing.assert_array_equal(b.shown.columns["freq_Hz"], st.freq(1))


def test_the_shown_variants_case_is_a_section_of_the_sessions_report(variants_dir, monkeypatch):
    """The card's browser publishes its case to the session's store; the report shows it
    (the corridor's curves and the ranking) as the page shows it."""
    from types import SimpleNamespace

    import panel as pn

    from app.report.session import report_data
    from app.store import Results
    from app.views.campaign import campaign_card

    monkeypatch.setenv("FBS_CAMPAIGN_DIR", str(variants_dir))
    store = Results(background=False)
    parts = SimpleNamespace(
        results=store, card=lambda title, view, height, **kw: pn.Card(view, title=title, **kw)
    )
    card = campaign_card(parts)
    assert "campaign" not in store.outside
    card.collapsed = False  # the user opens the card: the file is read, its case shown
    card.browser.param.update(case="variants_cheap", dof="y")
    st = open_campaign(variants_dir / "corridor.h5").variants("variants_cheap")
    c = st.corridor(1, percentiles=(10.0, 50.0, 90.0))
    j = c.dof_index("bushing:y")
    (sec,) = [x for x in report_data(store).extra if x.key == "campaign"]
    np.testing.assert_allclose(sec.curves["maximum"], 20 * np.log10(c.maximum[:, j]))
    np.testing.assert_allclose(sec.curves["p90"], 20 * np.log10(c.percentiles[2, :, j]))
    rows = dict(sec.rows)
    assert rows["campaign file"] == "corridor.h5" and rows["parameters"].startswith("inflation")
    lead = st.sensitivity(1).leaders("bushing:y")[0]["parameter"]
    assert lead in rows["sensitivity leaders (total Sobol' index per band)"]
    card.browser.case = None  # nothing shown: no section
    assert all(x.key != "campaign" for x in report_data(store).extra)


def test_without_a_directory_the_page_says_how_to_get_corridors_and_campaigns(monkeypatch):
    """The card is on the page even when the operator set no campaign folder: it names the
    setting, what a campaign file is and the commands, and the commands it gives work on the
    example files it names."""
    import subprocess
    import sys
    from types import SimpleNamespace

    import panel as pn

    from app.views.campaign import campaign_card

    monkeypatch.delenv("FBS_CAMPAIGN_DIR", raising=False)
    parts = SimpleNamespace(card=lambda title, view, height, **kw: pn.Card(view, title=title, **kw))
    card = campaign_card(parts)
    assert card is not None and "campaign-card" in card.css_classes
    assert "not set up" in card.title
    text = card.objects[0].object
    for words in (
        "FBS_CAMPAIGN_DIR",
        "campaign file",
        "TOML",
        "python -m fbs_core.campaign run campaigns/corridor.toml",
        "corridor",
    ):
        assert words in text, words
    root = Path(__file__).resolve().parents[1]
    for example in ("campaigns/example.toml", "campaigns/corridor.toml"):
        assert example in text and (root / example).is_file()
    plan = subprocess.run(
        [sys.executable, "-m", "fbs_core.campaign", "plan", "campaigns/corridor.toml"],
        cwd=root,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert plan.returncode == 0 and "variants" in plan.stdout, plan.stderr
