"""The campaign card's results as rows of the session's store, its file and case in the link.

Truth: the campaign file opened directly (``fbs_core.campaign.open_campaign``) and the
case makers of ``app.results.campaign`` called on it (a second path beside the store's
rows); for the link, the page's own link writer and reader (``state_query``,
``read_link``, ``sync_url``).
"""

from __future__ import annotations

import shutil
import time
import urllib.parse

import h5py
import numpy as np
import pytest

from app.export import export_columns, read_csv, to_csv
from app.page.titles import read_link, state_query
from app.results import Snapshot
from app.results.campaign import scatter_case_result, truncation_case_result
from app.state import URL_KEYS, DashboardState
from app.store import TABLE, Results
from fbs_core.campaign import open_campaign, parse_campaign, run_campaign

TOML = """
[campaign]
name = "linked"
seed = 11
output = "{out}"
[scatter]
harmonics = [1]
noise = [0.1]
targets = ["tire", "both"]
frequency_dependent = [false]
rounds = 100
percentiles = [5.0, 95.0]
[truncation]
harmonics = [1]
n_modes = {{ from = 10, to = 30, step = 10 }}
thresholds = [0.2]
f_max = [130.0]
couplings = ["6dof"]
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("linked")
    camp = parse_campaign(TOML.format(out=(d / "linked.h5").as_posix()), d)
    assert run_campaign(camp).status == "complete"
    shutil.copy(d / "linked.h5", d / "broken.h5")
    with h5py.File(d / "broken.h5", "r+") as h:  # still says it is a campaign result
        del h["cases"]
        h["cases"] = np.zeros(3)
    return d


def _names(folder):
    res = open_campaign(folder / "linked.h5")
    band = next(c.name for c in res.cases if c.kind == "scatter")
    trunc = next(c.name for c in res.cases if c.kind == "truncation")
    return res, band, trunc


class _Location:
    """The part of Panel's location the page's link reader uses: the query of a link."""

    def __init__(self, query):
        from panel.util import parse_query

        self.search = "?" + urllib.parse.urlencode(query)
        self.query_params = parse_query(self.search)


def _state(folder, **campaign) -> DashboardState:
    state = DashboardState()
    state.campaign.param.update(directory=folder.resolve(), **campaign)
    return state


def test_the_campaign_file_and_case_go_into_the_link_and_come_back(folder):
    _, band, _ = _names(folder)
    chosen = {"file": "linked.h5", "case": band, "dof": "y", "max_over_dofs": True, "harmonic": 1}
    state = _state(folder, **chosen)
    q = state_query(state)
    assert {q[k] for k in ("cfile", "ccase", "cdof")} == {"linked.h5", band, "y"}
    assert "cmax" in q and "ch" in q
    fresh = _state(folder)
    read_link(_Location(q), fresh.campaign, URL_KEYS["campaign"])
    assert {k: getattr(fresh.campaign, k) for k in chosen} == chosen
    assert Snapshot.of(fresh) == Snapshot.of(state)
    # the defaults write nothing, and the folder is never in the link (the server's own)
    assert not {"cfile", "ccase", "cdof", "cmax", "ch"} & set(state_query(_state(folder)))
    assert str(folder.resolve()) not in urllib.parse.urlencode(q)


def test_a_link_naming_a_case_opens_the_page_on_it(folder, monkeypatch):
    """The page's link reader (``sync_url``) sets the file and the case; the page's card is
    shown opened on that case, the store's numbers the file's."""
    from app.main import create_app, sync_url

    res, _, trunc = _names(folder)
    monkeypatch.setenv("FBS_CAMPAIGN_DIR", str(folder))
    q = {"cfile": "linked.h5", "ccase": trunc, "cdof": "x"}
    state = DashboardState()
    state.noise.rounds = 20
    sync_url(state, location=_Location(q))
    assert (state.campaign.file, state.campaign.case, state.campaign.dof) == (
        "linked.h5",
        trunc,
        "x",
    )
    page = create_app(state)
    (card,) = [c for c in page.main[0].objects if "campaign-card" in c.css_classes]
    assert not card.collapsed and card.browser.case == trunc
    shown = card.browser.shown
    want = truncation_case_result(res, trunc, "x")
    np.testing.assert_array_equal(shown.columns["error_pct"], want.columns["error_pct"])


def _same_result(got, want) -> None:
    assert got is not None and got.columns.keys() == want.columns.keys()
    for k in want.columns:
        np.testing.assert_array_equal(got.columns[k], want.columns[k])
    assert dict(got.meta) == dict(want.meta)
    assert (got.filename, got.caption) == (want.filename, want.caption)


def _wait(cond, timeout=120.0) -> None:
    t0 = time.monotonic()
    while not cond():
        assert time.monotonic() - t0 < timeout, "timed out"
        time.sleep(0.02)


@pytest.mark.parametrize("background", [False, True], ids=["in place", "background worker"])
def test_the_store_publishes_the_case_the_maker_makes_of_the_file(folder, background):
    """The store's row ``campaign`` against ``app.results.campaign``'s makers called on the
    file opened directly; the CSV keeps the case's provenance."""
    res, band, trunc = _names(folder)
    store = Results(_state(folder), background=background)
    assert store.campaign_cases is None and store.campaign is None  # nothing chosen
    store.state.campaign.param.update(file="linked.h5", case=band, dof="y")
    _wait(lambda: store.campaign is not None and store.campaign.columns)
    _same_result(store.campaign, scatter_case_result(res, band, "y"))
    table = store.campaign_cases
    assert list(table.draw["rows"]["case"]) == [c.name for c in res.cases]
    assert table.caption.startswith("campaign 'linked'") and str(folder) not in table.caption
    cols, meta = export_columns(store.campaign)
    head, _ = read_csv(to_csv(cols, meta, "campaign"))
    assert head["campaign file"] == "linked.h5" and head["case"] == band
    assert head["case digest"] == res.case_attrs(band)["digest"]
    store.state.campaign.param.update(case=trunc, max_over_dofs=True)
    _wait(lambda: store.campaign.filename != scatter_case_result(res, band, "y").filename)
    _same_result(store.campaign, truncation_case_result(res, trunc, None))
    store.close()


def test_the_file_the_user_chose_is_read_at_the_servers_priority(folder, tmp_path, monkeypatch):
    """Reading a chosen file is work the user waits for: it runs on the worker at the
    server's priority, never queued behind the low-priority work nobody waits for."""
    from app.runtime import background

    asked: dict[str, list] = {"ahead": [], "background": []}
    for name, worker in (("ahead", background.AHEAD), ("background", background.BACKGROUND)):
        submit = worker.submit
        monkeypatch.setattr(
            worker,
            "submit",
            lambda key, work, _n=name, _s=submit: (asked[_n].append(key[1]), _s(key, work)),
        )
    _res, band, _trunc = _names(folder)
    shutil.copy(folder / "linked.h5", tmp_path / "fresh.h5")  # not read by this process yet
    store = Results(_state(tmp_path), background=True)
    store.state.campaign.param.update(file="fresh.h5", case=band)
    _wait(lambda: store.campaign is not None and store.campaign.columns)
    assert "campaign" in asked["ahead"] or "campaign_cases" in asked["ahead"]
    assert not {"campaign", "campaign_cases"} & set(asked["background"])
    store.close()


def _published(store: Results) -> dict:
    return {row.name: getattr(store, row.name) for row in TABLE}


@pytest.mark.parametrize(
    "name, words",
    [
        ("broken.h5", ("broken.h5", "cases")),
        ("gone.h5", ("gone.h5", "no campaign result file")),
        ("../linked.h5", ("../linked.h5", "not a campaign result file name")),
    ],
)
def test_a_bad_file_is_the_cards_message_and_nothing_else_changes(folder, name, words):
    from app.views.campaign import CampaignBrowser

    _, band, _ = _names(folder)
    store = Results(_state(folder, file="linked.h5", case=band), background=False)
    before = _published(store)
    b = CampaignBrowser(store=store)
    assert b.shown is before["campaign"] is not None
    store.state.campaign.file = name
    problem = store.campaign_cases.draw["problem"]
    assert all(w in problem for w in words), problem
    assert str(folder.resolve()) not in problem  # the server's folder is not said
    assert b.message == problem and b.shown is None and store.message == ""
    assert not store.campaign.columns
    after = _published(store)
    changed = {k for k in before if after[k] is not before[k]}
    assert changed == {"campaign_cases", "campaign"}, changed
    # the good file again: its case as before
    store.state.campaign.param.update(file="linked.h5", case=band)
    _same_result(store.campaign, before["campaign"])
