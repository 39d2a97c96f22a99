"""Campaign part files: a cluster task's units in one part file, merged while the run goes on.

Truth: the units a run (or a killed run) wrote are in the result file after the next run,
none computed twice, and the bands are those of :func:`fbs_core.scatter_band` computing each
case in one call in this process.
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

import fbs_core
from fbs_core.campaign import (
    CampaignStore,
    group_blocks,
    open_campaign,
    parse_campaign,
    plan,
    run_campaign,
    work,
)
from fbs_core.campaign import store as store_mod
from fbs_core.campaign.run import _write_group, n_lines

ROUNDS = 100
Q = (5.0, 50.0, 95.0)


def _campaign(tmp_path: Path):
    """6 cases of harmonic 1 (one block each), two cases a cluster task: 3 tasks."""
    per_case = ROUNDS * n_lines(1, 0.5)
    text = (
        f'[campaign]\nname = "p"\nseed = 5\noutput = "{(tmp_path / "p.h5").as_posix()}"\n'
        '[scatter]\nharmonics = [1]\nnoise = [0.02, 0.05, 0.1]\ntargets = ["tire", "both"]\n'
        f"rounds = {ROUNDS}\npercentiles = {list(Q)}\n"
        f"[execution]\ntask_round_lines = {int(2.5 * per_case)}\n"
    )
    camp = parse_campaign(text, tmp_path)
    groups = group_blocks(plan(camp)[0], camp.task_round_lines)
    assert [len(g) for g in groups] == [2, 2, 2]
    return camp, groups


def _results(group):
    """The results of a band group, computed here as a worker would."""
    c = group[0].case
    inp = work.prepare_inputs("reference", "reference", c.harmonic, None, "6dof", 0.5)
    blocks = [
        (t.case.noise, t.case.target, t.case.rounds, t.case.frequency_dependent, t.case.seed,
         t.case.percentiles, t.l0, t.l1)
        for t in group
    ]  # fmt: skip
    return work.band_blocks(inp, blocks)


def _units_in(path: Path) -> set[str]:
    with h5py.File(path, "r") as h:
        return store_mod._units(h)


def _all_bands_are_scatter_band(camp):
    res = open_campaign(camp.output)
    assert all(x.complete for x in res.cases)
    for x in camp.band_cases:
        direct = fbs_core.scatter_band(
            x.harmonic, x.noise, x.target, ROUNDS, False, seed=x.seed, percentiles=Q
        )
        got = res.band(x.name)
        np.testing.assert_array_equal(got.minimum, direct.minimum)
        np.testing.assert_array_equal(got.maximum, direct.maximum)
        np.testing.assert_array_equal(got.percentiles, direct.percentiles)
        np.testing.assert_array_equal(got.argmax_round, direct.argmax_round)


def test_a_task_of_several_units_is_one_part_file_kept_by_a_killed_run_and_resumed(tmp_path):
    camp, groups = _campaign(tmp_path)
    store = CampaignStore(camp.output)
    store.commit({"campaign_name": camp.name})
    # a killed run: one task's two units written as one part file, merged into the open copy
    # of the result file, then the process dies (the copy neither closed nor renamed)
    part = _write_group(store, camp, groups[0], _results(groups[0]))
    assert part.parent == store.parts and _units_in(part) == {t.unit for t in groups[0]}
    merging = store.merging({"campaign_name": camp.name})
    assert merging.add(part) and merging.tmp.is_file()
    merging._h.close()  # the process dies here
    assert _units_in(camp.output) == set()  # the result file as it was
    assert store.done() == {t.unit for t in groups[0]}  # both units, from the part
    seen = open_campaign(camp.output)
    assert sum(c.complete for c in seen.cases) == 2
    rep = run_campaign(camp)
    assert rep.status == "complete" and rep.tasks_skipped == 2 and rep.tasks_done == 4
    assert not store.parts.exists()  # the parts and the stale copy gone, all in the file
    assert _units_in(camp.output) >= {t.unit for g in groups for t in g}
    _all_bands_are_scatter_band(camp)


def test_a_run_stopped_after_a_task_keeps_all_its_units_and_resumes(tmp_path):
    camp, groups = _campaign(tmp_path)
    seen = []

    def progress(done, total, rounds):
        seen.append(done)
        raise KeyboardInterrupt  # Ctrl-C as the first unit of the first task is counted

    rep = run_campaign(camp, progress=progress)
    assert rep.status == "stopped" and seen == [1]
    assert rep.tasks_done == 2  # the task's two units were written together, before
    mid = open_campaign(camp.output)
    assert sum(c.complete for c in mid.cases) == 2 and mid.runs[-1]["status"] == "stopped"
    assert not CampaignStore(camp.output).parts.exists()
    rep = run_campaign(camp)
    assert rep.status == "complete" and rep.tasks_skipped == 2 and rep.tasks_done == 4
    _all_bands_are_scatter_band(camp)


def test_parts_are_merged_as_they_arrive_and_a_failed_merge_falls_back_to_a_commit(
    tmp_path, monkeypatch
):
    camp, _ = _campaign(tmp_path)
    events: list[tuple[str, str]] = []
    write_units = store_mod.CampaignStore.write_units
    add = store_mod.Merging.add

    def spy_write(self, units):
        part = write_units(self, units)
        events.append(("write", part.name))
        return part

    def spy_add(self, part):
        ok = add(self, part)
        events.append(("add", part.name))
        return ok

    monkeypatch.setattr(store_mod.CampaignStore, "write_units", spy_write)
    monkeypatch.setattr(store_mod.Merging, "add", spy_add)
    assert run_campaign(camp).status == "complete"
    bands = [(w, n) for w, n in events if "blocks" in n]
    # every task's part merged right after it was written, while the others computed
    assert bands == [(w, n) for _, n in bands[::2] for w in ("write", "add")]
    assert len(bands) == 6

    # a merge into the copy fails once: the run goes on, the end merges all parts afresh
    out2 = tmp_path / "q.h5"
    merge = store_mod._merge
    calls = []

    def failing_merge(src, dst):
        calls.append(1)
        if len(calls) == 2:
            raise OSError("disk full")
        merge(src, dst)

    monkeypatch.setattr(store_mod, "_merge", failing_merge)
    rep = run_campaign(camp, output=out2)
    assert rep.status == "complete" and rep.tasks_done == 6
    assert not CampaignStore(out2).parts.exists()
    assert len(calls) > 2  # the fallback commit merged the parts again
    camp2 = parse_campaign(camp.text.replace("p.h5", "q.h5"), tmp_path)
    _all_bands_are_scatter_band(camp2)


def test_write_units_writes_all_units_or_none(tmp_path):
    store = CampaignStore(tmp_path / "w.h5")
    good = ("cases/a/blocks/0_2", {"lower": np.zeros((2, 6))}, {"l0": 0, "l1": 2}, None)
    bad = ("cases/b/blocks/0_2", {"lower": {"not": "an array"}}, {"l0": 0, "l1": 2}, None)
    with pytest.raises(TypeError):
        store.write_units([good, bad])
    assert store.done() == set()
    p = store.write_units([good, (bad[0], good[1], bad[2], {"cases/b": {"kind": "band"}})])
    assert _units_in(p) == {good[0], bad[0]}
    assert store.commit({"campaign_name": "w"}) == 2
    assert store.done() == {good[0], bad[0]} and not store.parts.exists()
    with h5py.File(store.output, "r") as h:
        assert h["cases/b"].attrs["kind"] == "band"
