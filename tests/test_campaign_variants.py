"""The "variants" study of a campaign (issue 32): on Dask, resumable, seeds and parameters
recorded. Truth: :func:`fbs_core.variants.run_variants` of the same design (the case's seed)
computed in this process in one call."""

from __future__ import annotations

import os
from pathlib import Path

import h5py
import numpy as np
import pytest

import fbs_core.variants as fv
from fbs_core.campaign import (
    CampaignError,
    case_seed,
    open_campaign,
    parse_campaign,
    plan,
    run_campaign,
)
from fbs_core.campaign.__main__ import main as cli

#: a cheap base tire (few orders, six speeds): a rebuild takes a fraction of a second
VARIANTS = """
[variants]
name = "cheap"
parameters = {parameters}
design = "{design}"
n = {n}
harmonics = [4]
speeds = [20.0, 40.0, 60.0, 80.0, 100.0, 120.0]
[variants.tire]
orders = [6, 3, 4, 3, -1, -1, -1, -1]
slip_zones = 1
"""


def _toml(out: Path, parameters='["inflation_pressure", "knuckle_mass"]', design="saltelli", n=2):
    return f'[campaign]\nname = "v"\nseed = 7\noutput = "{out.as_posix()}"\n' + VARIANTS.format(
        parameters=parameters, design=design, n=n
    )


def _in_process(case):
    return fv.run_variants(case.sample(), case.variant_settings(), cache=fv.TireCache())


def test_variants_campaign_resumes_and_equals_the_in_process_study(tmp_path):
    c = parse_campaign(_toml(tmp_path / "v.h5"), tmp_path)
    (case,) = c.variants_cases
    assert case.seed == case_seed(7, case.name) and case.name == "variants_cheap"
    tasks, _ = plan(c)
    design = case.sample()
    # one task per distinct tire (A, B; AB_knuckle shares A's, AB_pressure B's) + nominal
    assert [t.kind for t in tasks] == ["variants"] * 5 and tasks[0].rows == ()
    assert sorted(i for t in tasks for i in t.rows) == list(range(design.n))
    rep = run_campaign(c, max_tasks=2)
    assert rep.status == "stopped" and rep.tasks_done == 2
    res = open_campaign(c.output)
    entry = res.case(case.name)
    assert not entry.complete and "variants" in res.summary()
    with pytest.raises(CampaignError, match="not complete"):
        res.variants(case.name)
    rep = run_campaign(c)
    assert rep.status == "complete" and rep.tasks_skipped == 2 and rep.tasks_done == 3
    st = open_campaign(c.output).variants(case.name)
    ref = _in_process(case)
    np.testing.assert_array_equal(st.responses[4], ref.responses[4])
    np.testing.assert_array_equal(st.nominal[4], ref.nominal[4])
    assert st.tire_keys == ref.tire_keys
    # recorded: the seed, the design and every variant's parameter values
    with h5py.File(c.output) as h:
        g = h["cases"][case.name]
        assert g.attrs["seed"] == str(case.seed) and g.attrs["kind"] == "variants"
        np.testing.assert_array_equal(g["design"]["values"][()], design.values)
        assert g["design"].attrs["seed"] == str(case.seed)
        for u in g["tires"].values():
            np.testing.assert_array_equal(u["values"][()], design.values[u["rows"][()]])
    assert run_campaign(c).tasks_done == 0  # nothing left
    # the corridor of the stored study is the in-process one
    np.testing.assert_array_equal(st.corridor(4).maximum, ref.corridor(4).maximum)


def test_variants_on_two_worker_processes(tmp_path):
    from distributed import Client, LocalCluster

    c = parse_campaign(
        _toml(tmp_path / "w.h5", '["tread_mass", "body_bushing_loss"]', "sobol", 4), tmp_path
    )
    (case,) = c.variants_cases
    with (
        LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address="127.0.0.1:0",
        ) as cluster,
        Client(cluster) as client,
    ):
        client.wait_for_workers(2)
        workers = set(client.scheduler_info()["workers"])
        rep = run_campaign(c, client=client)
    assert rep.status == "complete" and rep.tasks_done == 5
    with h5py.File(c.output) as h:
        units = list(h["cases"][case.name]["tires"].values()) + [h["cases"][case.name]["nominal"]]
        where = [(int(u.attrs["pid"]), str(u.attrs["worker"])) for u in units]
    assert all(pid != os.getpid() and w in workers for pid, w in where)
    st = open_campaign(c.output).variants(case.name)
    ref = _in_process(case)
    scale = np.abs(ref.responses[4]).max()
    # the workers run BLAS on one thread, this process on as many as the machine has: the
    # tires' eigensolutions then round differently (5e-8 relative seen on a 2-core Xeon); a
    # variant given another variant's tire or parameters differs by O(1)
    np.testing.assert_allclose(st.responses[4], ref.responses[4], rtol=1e-6, atol=1e-9 * scale)


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ('parameters = ["tyre_pressure"]', "unknown parameter 'tyre_pressure'"),
        ('parameters = ["wheel_load"]\nranges = { wheel_load = [5000, 3000] }', "low < high"),
        ('parameters = ["wheel_load"]\ndesign = "sobol"\nn = 12', "power of two"),
        ('parameters = ["wheel_load"]\ndesign = "grid"', "'grid' is not allowed"),
        ('parameters = ["wheel_load"]\nspeeds = [40.0, 20.0]', "increasing"),
        ('parameters = ["wheel_load"]\nrounds = 10', r"unknown key\(s\) \['rounds'\]"),
        ('parameters = ["wheel_load"]\n[variants.tire]\nradius = 0.3', "unknown key.*radius"),
        ('parameters = ["wheel_load"]\n[variants.tire]\nEI = -1.0', "EI must be finite"),
        ("parameters = []", "at least one parameter"),
    ],
)
def test_bad_variants_tables_are_refused_by_key(tmp_path, extra, match):
    text = f'[campaign]\nname = "v"\noutput = "x.h5"\n[variants]\n{extra}\n'
    with pytest.raises(CampaignError, match=match):
        parse_campaign(text, tmp_path)


def test_cli_plan_summary_and_corridor(tmp_path, capsys):
    toml = tmp_path / "v.toml"
    toml.write_text(_toml(tmp_path / "v.h5"))
    assert cli(["plan", str(toml)]) == 0
    assert "variants_cheap" in capsys.readouterr().out
    assert cli(["run", str(toml), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "1 of 1 cases complete" in out and "variants saltelli n=2" in out
    assert cli(["corridor", str(tmp_path / "v.h5"), "--dofs", "bushing:z"]) == 0
    out = capsys.readouterr().out
    assert "corridor of 8 variants" in out and "Sobol' indices" in out
    assert "inflation_pressure" in out and "bushing:z" in out
    assert cli(["corridor", str(tmp_path / "v.h5"), "--case", "nope"]) == 2


def test_rows_sharing_a_tire_are_split_into_parallel_tasks(tmp_path):
    """Chassis parameters alone share the reference tire over all rows: 40 rows in tasks
    of at most ROWS_PER_TASK, every row once."""
    from fbs_core.campaign.variants import ROWS_PER_TASK

    text = (
        f'[campaign]\nname = "v"\noutput = "{(tmp_path / "c.h5").as_posix()}"\n'
        '[variants]\nparameters = ["knuckle_mass", "link_loss"]\ndesign = "lhs"\nn = 40\n'
    )
    tasks, _ = plan(parse_campaign(text, tmp_path))
    sizes = [len(t.rows) for t in tasks[1:]]
    assert sizes == [ROWS_PER_TASK, ROWS_PER_TASK, 40 - 2 * ROWS_PER_TASK]
    assert sorted(i for t in tasks for i in t.rows) == list(range(40))
    assert len({t.unit for t in tasks}) == len(tasks)


def _break_settings(h, name):
    import json

    s = json.loads(h["cases"][name].attrs["settings"])
    del s["n"]
    h["cases"][name].attrs["settings"] = json.dumps(s)


def _break_rows(h, name):
    u = next(iter(h["cases"][name]["tires"].values()))
    del u["rows"]
    u["rows"] = np.array([99], np.int64)


def _break_shape(h, name):
    u = next(iter(h["cases"][name]["tires"].values()))
    v = u["h4"][()]
    del u["h4"]
    u["h4"] = v[:, :3]


def _break_design(h, name):
    del h["cases"][name]["design"]


def _break_tires(h, name):
    del h["cases"][name]["tires"]
    h["cases"][name]["tires"] = np.zeros(2)


@pytest.mark.parametrize(
    "breaking", [_break_settings, _break_rows, _break_shape, _break_design, _break_tires]
)
def test_a_malformed_variants_study_is_a_campaign_error_naming_the_file(
    variants_result, tmp_path, breaking
):
    import shutil

    good, name = variants_result
    path = tmp_path / "broken.h5"
    shutil.copy(good, path)
    with h5py.File(path, "r+") as h:
        breaking(h, name)
    with pytest.raises(CampaignError) as err:
        open_campaign(path).variants(name)
    assert str(path) in str(err.value)
    assert open_campaign(good).variants(name).design.n == 8  # the control reads


@pytest.fixture(scope="module")
def variants_result(tmp_path_factory):
    d = tmp_path_factory.mktemp("variants")
    c = parse_campaign(_toml(d / "good.h5"), d)
    assert run_campaign(c).status == "complete"
    return c.output, c.variants_cases[0].name
