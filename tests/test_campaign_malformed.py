"""A malformed campaign result file is a CampaignError naming the file and the problem
(issue 28, finding 4), in ``fbs_core.campaign.open_campaign`` and in the dashboard's
campaign card, and a page build opens no campaign file.

Each case starts from a real result (a small campaign run here) and breaks one thing with
h5py the way a damaged or hand-edited file would be: settings that are not JSON, a missing
setting, a setting of the wrong type, a block renamed, a block or map of the wrong shape,
an unknown kind of case, a group replaced by a dataset, a file that is not HDF5 at all.
"""

from __future__ import annotations

import os
import shutil

import h5py
import numpy as np
import pytest

from app.runtime import campaign_files
from app.views import campaign as view
from app.views.campaign import CampaignBrowser
from fbs_core.campaign import CampaignError, open_campaign, parse_campaign, run_campaign

TOML = """
[campaign]
name = "malformed"
seed = 5
output = "{out}"
[scatter]
harmonics = [1]
noise = [0.05]
targets = ["both"]
frequency_dependent = [false]
rounds = 30
percentiles = [5.0, 95.0]
[truncation]
harmonics = [1]
n_modes = {{ from = 10, to = 30, step = 10 }}
thresholds = [0.2]
f_max = [130.0]
couplings = ["6dof"]
[execution]
task_round_lines = 600
"""


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    d = tmp_path_factory.mktemp("good")
    camp = parse_campaign(TOML.format(out=(d / "good.h5").as_posix()), d)
    assert run_campaign(camp).status == "complete"
    return d / "good.h5"


def _names(path):
    with h5py.File(path, "r") as h:
        band = next(n for n, g in h["cases"].items() if g.attrs["kind"] == "scatter")
        trunc = next(n for n, g in h["cases"].items() if g.attrs["kind"] == "truncation")
    return band, trunc


def _set_settings(h, name, edit):
    import json

    g = h["cases"][name]
    s = json.loads(g.attrs["settings"])
    edit(s)
    g.attrs["settings"] = json.dumps(s)


def _cut_json(h, band, trunc):
    h["cases"][band].attrs["settings"] = '{"kind": "scatter", "harmonic": '


def _missing_key(h, band, trunc):
    _set_settings(h, band, lambda s: s.pop("noise"))


def _wrong_type(h, band, trunc):
    _set_settings(h, band, lambda s: s.update(rounds="many"))


def _renamed_block(h, band, trunc):
    blocks = h["cases"][band]["blocks"]
    first = sorted(blocks)[0]
    blocks.move(first, "first_block")


def _block_shape(h, band, trunc):
    blocks = h["cases"][band]["blocks"]
    g = blocks[sorted(blocks)[0]]
    data = g["lower"][()]
    del g["lower"]
    g["lower"] = data[:, :2]


def _map_shape(h, band, trunc):
    g = h["cases"][trunc]["result"]
    data = g["error"][()]
    del g["error"]
    g["error"] = data[:1]


def _unknown_kind(h, band, trunc):
    h["cases"][band].attrs["kind"] = "bogus"


def _cases_not_a_group(h, band, trunc):
    del h["cases"]
    h["cases"] = np.zeros(3)


def _inputs_missing(h, band, trunc):
    del h["inputs"]


BREAKS = {
    "settings not JSON": (_cut_json, "band"),
    "a setting missing": (_missing_key, "band"),
    "a setting of the wrong type": (_wrong_type, "band"),
    "a block renamed": (_renamed_block, "band"),
    "a block of the wrong shape": (_block_shape, "band"),
    "a map of the wrong shape": (_map_shape, "trunc"),
    "an unknown kind of case": (_unknown_kind, "band"),
    "cases not a group": (_cases_not_a_group, None),
    "the subsystem arrays missing": (_inputs_missing, "band"),
}


def _broken(good, tmp_path, how) -> tuple:
    path = tmp_path / "broken.h5"
    shutil.copy(good, path)
    band, trunc = _names(good)
    with h5py.File(path, "r+") as h:
        BREAKS[how][0](h, band, trunc)
    return path, band, trunc


def _use(path, band, trunc, which) -> None:
    """What the browser does with a file: open it, show its cases, read the chosen one."""
    res = open_campaign(path)
    view.case_rows(res)
    if which == "band":
        res.band(band)
    elif which == "trunc":
        res.truncation(trunc)


@pytest.mark.parametrize("how", list(BREAKS))
def test_every_malformed_file_is_a_campaign_error_naming_file_and_problem(good, tmp_path, how):
    path, band, trunc = _broken(good, tmp_path, how)
    with pytest.raises(CampaignError) as err:
        _use(path, band, trunc, BREAKS[how][1])
    assert str(path) in str(err.value)
    # the good file stays usable (the control: the breaking is what fails)
    _use(good, band, trunc, BREAKS[how][1])


def test_a_file_that_is_not_hdf5_is_a_campaign_error(tmp_path):
    path = tmp_path / "noise.h5"
    path.write_bytes(os.urandom(4096))
    with pytest.raises(CampaignError, match="not a readable HDF5"):
        open_campaign(path)


@pytest.mark.parametrize("how", list(BREAKS))
def test_the_card_says_what_is_wrong_and_the_page_goes_on(good, tmp_path, how):
    path, band, trunc = _broken(good, tmp_path, how)
    shutil.copy(good, tmp_path / "zz_good.h5")
    b = CampaignBrowser(directory=tmp_path)  # opens broken.h5 first (sorted)
    b.__panel__()
    # choose the broken case (when the file opened at all)
    name = band if BREAKS[how][1] == "band" else trunc
    if name in b.param.case.objects:
        b.case = name
    assert "broken.h5" in b.message and b.shown is None
    # the other file of the directory is browsable in the same card
    b.file = "zz_good.h5"
    assert b.message.startswith("campaign 'malformed'") and b.shown is not None


def test_a_page_build_reads_no_campaign_file_and_a_file_is_read_once_per_change(
    good, tmp_path, monkeypatch
):
    from app.main import create_app
    from app.state import DashboardState

    d = tmp_path / "dir"
    d.mkdir()
    shutil.copy(good, d / "good.h5")
    monkeypatch.setenv(view.CAMPAIGN_DIR_ENV, str(d))
    opened = []
    real = campaign_files.open_campaign
    monkeypatch.setattr(campaign_files, "open_campaign", lambda p: opened.append(p) or real(p))
    pages = []
    for _ in range(2):
        state = DashboardState()
        state.noise.rounds = 20
        pages.append(create_app(state))
    assert opened == []  # no page build opened the file
    cards = [c for p in pages for c in p.main[0].objects if "campaign-card" in c.css_classes]
    assert len(cards) == 2
    cards[0].collapsed = False  # expanding the card opens the first file ...
    assert len(opened) == 1 and cards[0].browser.shown is not None
    cards[1].collapsed = False  # ... once for all sessions while it does not change
    assert len(opened) == 1 and cards[1].browser.shown is not None
    with h5py.File(d / "good.h5", "r+") as h:  # a run adds to the file
        h.attrs["updated"] = "later"
    b = CampaignBrowser(directory=d)
    assert len(opened) == 2 and b.shown is not None
