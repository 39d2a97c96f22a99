"""Campaigns on Dask: the same band whatever the split, resumable result files, the CLI.

Truth: :func:`fbs_core.scatter_band` and :func:`fbs_core.truncation_map` computing the whole
case in one call in this process (the campaign computes it in blocks on workers and
reassembles it from the file).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

import fbs_core
from fbs_core.campaign import (
    CampaignError,
    CampaignStore,
    case_seed,
    load_campaign,
    open_campaign,
    parse_campaign,
    plan,
    run_campaign,
)
from fbs_core.campaign.__main__ import main as cli

ROOT = Path(__file__).resolve().parents[1]


def _toml(out: Path, *, rounds=300, task_round_lines=10**9, extra="", scatter=None) -> str:
    sc = scatter or (
        'harmonics = [1]\nnoise = [0.1]\ntargets = ["both"]\nfrequency_dependent = [true]\n'
    )
    return (
        f'[campaign]\nname = "t"\nseed = 7\noutput = "{out.as_posix()}"\n'
        f"[scatter]\n{sc}rounds = {rounds}\npercentiles = [5.0, 50.0, 95.0]\n"
        f"[execution]\ntask_round_lines = {task_round_lines}\n{extra}"
    )


def _same_band(a, b, tol=1e-12):
    np.testing.assert_allclose(a.minimum, b.minimum, rtol=tol, atol=0)
    np.testing.assert_allclose(a.maximum, b.maximum, rtol=tol, atol=0)
    np.testing.assert_allclose(a.percentiles, b.percentiles, rtol=tol, atol=0)
    np.testing.assert_allclose(a.reference, b.reference, rtol=tol, atol=0)
    np.testing.assert_array_equal(a.argmax_round, b.argmax_round)
    np.testing.assert_array_equal(a.argmin_round, b.argmin_round)
    np.testing.assert_array_equal(a.convergence.rounds, b.convergence.rounds)
    np.testing.assert_allclose(a.convergence.maximum, b.convergence.maximum, rtol=tol, atol=0)
    np.testing.assert_allclose(a.convergence.minimum, b.convergence.minimum, rtol=tol, atol=0)


def _blocks(path, case):
    with h5py.File(path, "r") as h:
        g = h["cases"][case]["blocks"]
        return {k: (int(g[k].attrs["pid"]), str(g[k].attrs["worker"])) for k in g}


def test_band_same_in_one_block_in_8_blocks_on_2_worker_processes_and_scatter_band(tmp_path):
    from distributed import Client, LocalCluster

    one = parse_campaign(_toml(tmp_path / "one.h5"), tmp_path)
    eight = parse_campaign(_toml(tmp_path / "eight.h5", task_round_lines=300 * 10), tmp_path)
    (case,) = one.band_cases
    assert [t.kind for t in plan(one)[0]] == ["band"]
    assert sum(t.kind == "band" for t in plan(eight)[0]) == 8  # 78 lines in blocks of 10
    assert run_campaign(one).status == "complete"  # in-process LocalCluster, one block
    with (
        LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        Client(cluster) as client,
    ):
        client.wait_for_workers(2)
        workers = set(client.scheduler_info()["workers"])
        rep = run_campaign(eight, client=client)
    assert rep.status == "complete" and rep.tasks_done == 8
    blocks = _blocks(eight.output, case.name)
    assert len(blocks) == 8
    # computed in the worker processes, not here
    assert all(pid != os.getpid() and w in workers for pid, w in blocks.values())

    b1 = open_campaign(one.output).band(case.name)
    b8 = open_campaign(eight.output).band(case.name)
    direct = fbs_core.scatter_band(
        1,
        noise=0.1,
        target="both",
        rounds=300,
        frequency_dependent=True,
        seed=case.seed,
        percentiles=(5.0, 50.0, 95.0),
    )
    _same_band(b1, b8)
    _same_band(b8, direct)
    # the stored subsystem arrays regenerate any round as the direct band does
    r = int(direct.argmax_round[40, 2])
    np.testing.assert_allclose(b8.round(r), direct.round(r), rtol=1e-12, atol=0)
    assert np.abs(b8.round(r)[40, 2]) == pytest.approx(direct.maximum[40, 2], rel=1e-12)


def test_case_seeds_are_recorded_independent_of_the_matrix_and_common_on_request(tmp_path):
    a = parse_campaign(_toml(tmp_path / "a.h5"), tmp_path)
    b = parse_campaign(
        _toml(
            tmp_path / "b.h5",
            scatter='harmonics = [4, 1]\nnoise = [0.05, 0.1]\ntargets = ["tire", "both"]\n'
            "frequency_dependent = [false, true]\n",
        ),
        tmp_path,
    )
    (ca,) = a.band_cases
    same = [c for c in b.band_cases if c.name == ca.name]
    assert len(b.band_cases) == 16 and same[0].seed == ca.seed  # more cases, same seed
    seeds = [c.seed for c in b.band_cases]
    assert len(set(seeds)) == len(seeds)
    assert ca.seed == case_seed(7, ca.name) != 7
    c = parse_campaign(_toml(tmp_path / "c.h5").replace("seed = 7", 'seed = 7\nseeds = "common"'))
    assert c.band_cases[0].seed == 7


@pytest.mark.parametrize(
    "old, new, words",
    [
        ("[scatter]\n", "[scatter]\ntypo = 1\n", ["unknown key", "typo"]),
        ("noise = [0.1]", "noise = [1.5]", ["noise", "[0, 1)"]),
        ('targets = ["both"]', 'targets = ["road"]', ["targets", "tire, chassis"]),
        ("harmonics = [1]", "harmonics = [9]", ["harmonics", "1..7"]),
        ("rounds = 300", 'rounds = "many"', ["rounds", "integer"]),
        ("rounds = 300", "rounds = 2_000_000", ["rounds", "1..1000000"]),
        ("seed = 7", "seed = -1", ["seed"]),
    ],
)
def test_bad_campaign_files_are_refused_with_the_key_and_the_allowed_values(
    tmp_path, old, new, words
):
    text = _toml(tmp_path / "x.h5")
    with pytest.raises(CampaignError) as e:
        parse_campaign(text.replace(old, new, 1), tmp_path)
    assert all(w in str(e.value) for w in words), str(e.value)
    with pytest.raises(CampaignError, match="not valid TOML"):
        parse_campaign("[campaign\n", tmp_path)
    with pytest.raises(CampaignError, match="does not exist"):
        parse_campaign(text + '[models.tire]\nsoft = "missing.h5"\n', tmp_path)


def test_stopped_and_killed_runs_leave_a_consistent_file_and_resume(tmp_path):
    text = _toml(
        tmp_path / "r.h5",
        task_round_lines=300 * 20,
        scatter='harmonics = [1]\nnoise = [0.05, 0.1]\ntargets = ["tire"]\n',
    )
    camp = parse_campaign(text, tmp_path)
    tasks, _ = plan(camp)
    assert len(tasks) == 8  # 2 cases x 4 blocks
    rep = run_campaign(camp, max_tasks=3)
    assert rep.status == "stopped" and rep.tasks_done == 3
    part = open_campaign(camp.output)
    assert sum(c.lines_done for c in part.cases) < sum(c.n_lines for c in part.cases)
    assert "0 of 2 cases complete" in part.summary()  # planned from the stored campaign file
    with pytest.raises(CampaignError, match="not complete"):
        part.band(part.cases[0].name)
    # a killed run: a finished task's part file, and a write cut short before its rename
    store = CampaignStore(camp.output)
    done = store.done()
    todo = [t for t in plan(camp, done)[0] if t.unit not in done and t.kind == "band"]
    from fbs_core.campaign import work
    from fbs_core.campaign.run import _write

    inp = work.prepare_inputs("reference", "reference", 1, None, "6dof", 0.5)
    t = todo[0]
    c = t.case
    res = work.band_block(
        inp, c.noise, c.target, c.rounds, c.frequency_dependent, c.seed, c.percentiles, t.l0, t.l1
    )
    _write(store, camp, t, res)
    (store.parts / "junk.h5.123.tmp").write_bytes(b"half a file")
    seen = open_campaign(camp.output)  # the uncommitted part is browsable
    assert sum(x.lines_done for x in seen.cases) == sum(x.lines_done for x in part.cases) + (
        t.l1 - t.l0
    )
    rep2 = run_campaign(camp)
    assert rep2.status == "complete" and rep2.tasks_skipped == 3 + 1
    assert rep2.tasks_done == len(tasks) - 4
    assert not store.parts.exists()  # everything merged into the one file
    res = open_campaign(camp.output)
    assert all(x.complete for x in res.cases) and len(res.runs) == 2
    for x in camp.band_cases:
        direct = fbs_core.scatter_band(
            1, x.noise, "tire", 300, False, seed=x.seed, percentiles=(5.0, 50.0, 95.0)
        )
        _same_band(res.band(x.name), direct)
    assert run_campaign(camp).tasks_done == 0  # nothing left
    other = parse_campaign(text.replace("seed = 7", "seed = 8"), tmp_path)
    with pytest.raises(CampaignError, match="other settings"):
        run_campaign(other)


def test_truncation_cases_5dof_and_a_chassis_variant_from_a_file(tmp_path):
    f_wide = np.arange(10.0, 60.0, 0.25)
    chassis_frf = fbs_core.reference_chassis().mobility(f_wide)
    fbs_core.save_frf(chassis_frf, tmp_path / "chassis.h5")
    text = (
        '[campaign]\nname = "tr"\nseed = 3\noutput = "tr.h5"\n'
        '[models.chassis]\nmeasured = "chassis.h5"\n'
        '[scatter]\nharmonics = [1]\nnoise = [0.2]\ntargets = ["chassis"]\nrounds = 200\n'
        'couplings = ["5dof"]\n'
        "[truncation]\nharmonics = [1]\nn_modes = [20, 60, 400]\nthresholds = [0.1, 0.2]\n"
        'f_max = [40.0]\ncouplings = ["6dof", "5dof"]\n'
        '[outputs]\ntruncation = ["error", "suggested", "responses"]\n'
    )
    (tmp_path / "tr.toml").write_text(text)
    camp = load_campaign(tmp_path / "tr.toml")
    assert camp.chassis == {"measured": str(tmp_path / "chassis.h5")}
    assert run_campaign(camp).status == "complete"
    res = open_campaign(tmp_path / "tr.h5")
    f = fbs_core.harmonic(1).frequencies(0.5)
    on_grid = chassis_frf.interpolate(f)
    (bc,) = camp.band_cases
    direct = fbs_core.scatter_band(
        1, 0.2, "chassis", 200, seed=bc.seed, chassis=on_grid, coupling="5dof"
    )
    _same_band(res.band(bc.name), direct)
    for tc in camp.truncation_cases:
        m = fbs_core.truncation_map(1, [20, 60, 400], chassis=on_grid, coupling=tc.coupling)
        got = res.truncation(tc.name)
        np.testing.assert_allclose(got.error, m.error, rtol=1e-12, atol=1e-15)
        assert got.suggested.tolist() == [[m.suggest(0.1, 40.0)], [m.suggest(0.2, 40.0)]]
        np.testing.assert_allclose(got.map.response, m.response, rtol=1e-12, atol=0)
    # the model file changed under the same variant name: refused, the file is kept
    fbs_core.save_frf(chassis_frf.replace(data=chassis_frf.data * 1.01), tmp_path / "chassis.h5")
    with pytest.raises(CampaignError, match="changed model"):
        run_campaign(load_campaign(tmp_path / "tr.toml"))
    assert (
        open_campaign(tmp_path / "tr.h5").band(bc.name).maximum.tolist() == direct.maximum.tolist()
    )


def test_cli_summary_and_errors(tmp_path, capsys):
    camp = tmp_path / "c.toml"
    camp.write_text(_toml(tmp_path / "c.h5", rounds=50))
    assert cli(["run", str(camp), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "complete: 1 tasks done" in out and "1 of 1 cases complete, 0 partial" in out
    assert cli(["summary", str(tmp_path / "c.h5")]) == 0
    assert "h1 noise 10 % both" in capsys.readouterr().out
    assert cli(["summary", str(tmp_path / "none.h5")]) == 2
    assert "no campaign result file" in capsys.readouterr().err
    assert cli(["run", str(tmp_path / "missing.toml")]) == 2


def test_ctrl_c_stops_cleanly_and_the_same_command_resumes(tmp_path):
    camp = tmp_path / "k.toml"
    # 5 cases of one block each (harmonic 5: 301 lines), a task each (a case's work is the
    # task size: no two go together)
    camp.write_text(
        _toml(
            tmp_path / "k.h5",
            rounds=1000,
            task_round_lines=301_000,
            scatter='harmonics = [5]\nnoise = [0.01, 0.02, 0.05, 0.1, 0.2]\ntargets = ["both"]\n',
        )
    )
    cmd = [sys.executable, "-m", "fbs_core.campaign", "run", str(camp)]
    parts = tmp_path / "k.h5.parts"
    p = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        # wait until the first band block is saved, then Ctrl-C
        while not (
            parts.is_dir()
            and any("blocks" in q.name and q.suffix == ".h5" for q in parts.iterdir())
        ):
            assert p.poll() is None, p.communicate()
            assert time.monotonic() < deadline
            time.sleep(0.05)
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130, (out, err)
    assert "run the same command again to resume" in out
    assert "Traceback" not in err
    mid = open_campaign(tmp_path / "k.h5")
    n_mid = sum(c.complete for c in mid.cases)
    assert 1 <= n_mid < 5 and mid.runs[-1]["status"] == "stopped"
    r = subprocess.run(cmd + ["--quiet"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert f"{n_mid} done before" in r.stdout
    assert all(c.complete for c in open_campaign(tmp_path / "k.h5").cases)


def test_progress_bar_shows_done_total_rate_and_time_left_from_the_work():
    import io

    from fbs_core.campaign.run import Progress

    out = io.StringIO()
    bar = Progress(4, 100.0, stream=out, every=0.0)
    bar.t0 -= 10.0  # 10 s ago
    # a cheap task: half the rounds but a quarter of the work (few lines)
    bar.update(1, rounds=50.0, work=25.0)
    line = out.getvalue()
    assert "1/4 tasks" in line and "5 rounds/s" in line
    left = line.split("left ")[1].strip()
    h, m, s = (int(x) for x in left.split(":"))
    assert 29 <= 3600 * h + 60 * m + s <= 31  # 75 work units left at 2.5 per second


def test_run_in_process_gives_the_signal_handlers_back(tmp_path):
    """``run`` called in-process (a notebook, a test runner) restores the caller's SIGINT
    and SIGTERM handlers when it returns (else a later SIGTERM of the caller raised the
    campaign's KeyboardInterrupt)."""

    def mine(signum, frame):  # pragma: no cover - never called
        pass

    before = {s: signal.signal(s, mine) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        camp = tmp_path / "c.toml"
        camp.write_text(_toml(tmp_path / "c.h5", rounds=50))
        assert cli(["run", str(camp), "--quiet"]) == 0
        assert signal.getsignal(signal.SIGINT) is mine
        assert signal.getsignal(signal.SIGTERM) is mine
    finally:
        for s, h in before.items():
            signal.signal(s, h)


def test_small_cases_sharing_their_arrays_go_as_one_task_each_with_its_own_unit(tmp_path):
    """Issue 33: blocks far smaller than a task (few rounds) go to the cluster together while
    they share their subsystem arrays and fit the task size; each keeps its own unit and its
    numbers are those of the case alone (scatter_band)."""
    from fbs_core.campaign import group_blocks
    from fbs_core.campaign.run import n_lines

    rounds = 100
    per_case = rounds * n_lines(2, 0.5)  # harmonic 2 has the more lines of the two
    text = _toml(
        tmp_path / "g.h5",
        rounds=rounds,
        task_round_lines=int(2.5 * per_case),  # two cases of harmonic 2 a task, not three
        scatter='harmonics = [1, 2]\nnoise = [0.02, 0.05, 0.1]\ntargets = ["tire", "both"]\n',
    )
    camp = parse_campaign(text, tmp_path)
    tasks, _ = plan(camp)
    assert len(tasks) == 12  # one block a case
    groups = group_blocks(tasks, camp.task_round_lines)
    assert sorted(t.unit for g in groups for t in g) == sorted(t.unit for t in tasks)
    assert all(len({t.inputs for t in g}) == 1 for g in groups)  # one harmonic's arrays
    assert all(sum(t.work for t in g) <= camp.task_round_lines for g in groups)
    h2 = [g for g in groups if g[0].case.harmonic == 2]
    assert [len(g) for g in h2] == [2, 2, 2]
    assert len(groups) < len(tasks)
    rep = run_campaign(camp)
    assert rep.status == "complete" and rep.tasks_done == 12
    res = open_campaign(camp.output)
    for x in camp.band_cases:
        direct = fbs_core.scatter_band(
            x.harmonic, x.noise, x.target, rounds, False, seed=x.seed,
            percentiles=(5.0, 50.0, 95.0),
        )  # fmt: skip
        _same_band(res.band(x.name), direct)
