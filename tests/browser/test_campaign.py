"""The campaign browser in a real browser: a server with FBS_CAMPAIGN_DIR lists the
directory's campaign file, and the chosen case's plotted data are the file's (read with
h5py alone)."""

from __future__ import annotations

import json
import time

import h5py
import numpy as np
import pytest

from fbs_core.campaign import parse_campaign, run_campaign

from .conftest import DashboardServer, open_dashboard, set_model_value, source

pytestmark = pytest.mark.browser

TOML = """
[campaign]
name = "browser"
seed = 5
output = "{out}"
[scatter]
harmonics = [1]
noise = [0.1]
targets = ["both"]
frequency_dependent = [false]
rounds = 200
[truncation]
harmonics = [1]
n_modes = {{ from = 10, to = 40, step = 10 }}
thresholds = [0.2]
f_max = [130.0]
couplings = ["6dof"]
"""


def _labels(attr) -> list[str]:
    return [str(x) for x in json.loads(attr)] if isinstance(attr, str) else list(attr)


JS_LENGTH = """([name, col]) => {
  const m = [...Bokeh.documents[0].all_models].filter(
      m => m.name === name && m.type === 'ColumnDataSource')[0];
  if (!m) return 0;
  const d = m.data instanceof Map ? Object.fromEntries(m.data) : m.data;
  return d[col] ? d[col].length : 0;
}"""


def _wait_data(page, name: str, column: str, timeout_s: float = 60.0) -> dict:
    """The data of a named source once ``column`` holds values."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        if page.evaluate(JS_LENGTH, [name, column]) > 0:
            return source(page, name)
        page.wait_for_timeout(100)
    raise AssertionError(f"{name} never got its data")


def test_the_campaign_card_shows_the_files_cases(browser, tmp_path, monkeypatch):
    camp = parse_campaign(TOML.format(out=(tmp_path / "browser.h5").as_posix()), tmp_path)
    assert run_campaign(camp).status == "complete"
    band_case = camp.band_cases[0].name
    trunc_case = next(c.name for c in camp.cases if c.kind == "truncation")
    with h5py.File(tmp_path / "browser.h5", "r") as h:
        g = h["cases"][band_case]["blocks"]
        keys = sorted(g, key=lambda k: int(k.split("_")[0]))
        upper = np.concatenate([g[k]["upper"][()] for k in keys])
        inp = h["inputs"][h["cases"][band_case].attrs["inputs"]]
        freq, dofs = inp["freq"][()], _labels(inp.attrs["dofs"])
        t = h["cases"][trunc_case]["result"]
        err, tdofs = t["error"][()], _labels(t.attrs["dofs"])

    monkeypatch.setenv("FBS_CAMPAIGN_DIR", str(tmp_path))
    server = DashboardServer()
    try:
        page = browser.new_page(viewport={"width": 1600, "height": 1400})
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        open_dashboard(page, server.url)
        page.locator(".campaign-card .card-header").first.click()  # expand the card
        page.locator(".campaign-file").first.wait_for(timeout=60_000)
        set_model_value(page, "campaign-case", band_case)
        d = _wait_data(page, "campaign.band", "freq")
        np.testing.assert_allclose(d["freq"], freq, rtol=1e-12)
        j = dofs.index("bushing:z")
        np.testing.assert_allclose(d["hi"], 20 * np.log10(upper[:, j]), rtol=1e-9)

        set_model_value(page, "campaign-case", trunc_case)
        img = np.asarray(_wait_data(page, "campaign.map", "image")["image"])
        np.testing.assert_allclose(
            img, (100 * err[:, :, tdofs.index("bushing:z")]).ravel(), rtol=1e-9
        )
        assert errors == []
        assert server.errors() == []
        page.close()
    finally:
        server.stop()


VARIANTS_TOML = """
[campaign]
name = "corridor"
seed = 7
output = "{out}"
[scatter]
harmonics = [4]
noise = [0.1]
targets = ["both"]
frequency_dependent = [false]
rounds = 100
[variants]
name = "cheap"
parameters = ["inflation_pressure", "knuckle_mass"]
design = "saltelli"
n = 2
harmonics = [4]
speeds = [20.0, 40.0, 60.0, 80.0, 100.0, 120.0]
[variants.tire]
orders = [6, 3, 4, 3, -1, -1, -1, -1]
slip_zones = 1
"""


def test_clicking_a_variants_case_draws_its_corridor_and_ranking(browser, tmp_path, monkeypatch):
    """A user clicks the variants case's row in the case table (the file opens on its scatter
    case): the corridor plot gets the study's numbers (read independently with
    open_campaign(...).variants), and the sensitivity leaders appear beside it."""
    from fbs_core.campaign import open_campaign

    camp = parse_campaign(VARIANTS_TOML.format(out=(tmp_path / "corridor.h5").as_posix()), tmp_path)
    assert run_campaign(camp).status == "complete"
    st = open_campaign(tmp_path / "corridor.h5").variants("variants_cheap")
    c = st.corridor(4)
    j = c.dof_index("bushing:z")
    leader = st.sensitivity(4).leaders("bushing:z")[0]["parameter"]

    monkeypatch.setenv("FBS_CAMPAIGN_DIR", str(tmp_path))
    server = DashboardServer()
    try:
        page = browser.new_page(viewport={"width": 1600, "height": 1400})
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        open_dashboard(page, server.url)
        page.locator(".campaign-card .card-header").first.click()  # expand the card
        _wait_data(page, "campaign.band", "freq")  # the first case (scatter) is shown
        assert page.evaluate(JS_LENGTH, ["campaign.corridor", "freq"]) == 0
        row = page.locator(".campaign-cases .tabulator-row", has_text="variants_cheap")
        # a click while the table is being drawn again can land on a row being replaced
        # (seen 1 in 4 runs on a loaded machine): click again as a user would
        for _ in range(3):
            row.first.click()
            try:
                d = _wait_data(page, "campaign.corridor", "freq", timeout_s=60.0)
                break
            except AssertionError:
                continue
        else:
            raise AssertionError("three clicks on the variants case drew no corridor")
        np.testing.assert_allclose(d["freq"], c.freq, rtol=1e-12)
        np.testing.assert_allclose(d["hi"], 20 * np.log10(c.maximum[:, j]), rtol=1e-9)
        np.testing.assert_allclose(d["lo"], 20 * np.log10(c.minimum[:, j]), rtol=1e-9)
        np.testing.assert_allclose(d["nominal"], 20 * np.log10(np.abs(c.nominal[:, j])), rtol=1e-9)
        leaders = page.locator(".campaign-leaders")
        leaders.get_by_text(leader).first.wait_for(timeout=30_000)
        assert errors == []
        assert server.errors() == []
        page.close()
    finally:
        server.stop()
