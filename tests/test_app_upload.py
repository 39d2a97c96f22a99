"""Uploads without a browser: the session's data source, the upload view, the views' data.

Truth: the uploaded chassis is the reference chassis' own mobility with changed numbers
(scaled by 2, nodes renumbered), so what the views show must be the core's prediction with
that FRF as chassis (a second path into ``fbs_core``), the uncoupled chassis curve must be
exactly 6.02 dB above the reference one, and the same FRF unscaled must give back the
reference views.
"""

from __future__ import annotations

import hashlib
import html
from pathlib import Path

import numpy as np
import pytest

import fbs_core
from app.datasource import REFERENCE, DataSource
from app.views.upload import UploadView
from fbs_core.io import save_frf
from fbs_core.tire.model import TireModel
from fbs_core.tire.storage import save_tire_model

ROOT = Path(__file__).resolve().parents[1]
#: The union of the seven harmonics' analysis grids (0.5 Hz lattice, 13-422 Hz).
GRID = np.arange(13.0, 422.01, 0.5)


def _renumber(Y, scale=1.0, spindle="3", bushing="8"):
    ren = {"spindle": spindle, "bushing": bushing}
    lab = [ren[x.split(":")[0]] + ":" + x.split(":")[1] for x in Y.outputs]
    inp = [ren[x.split(":")[0]] + ":" + x.split(":")[1] for x in Y.inputs]
    return Y.replace(data=Y.data * scale, outputs=lab, inputs=inp)


@pytest.fixture(scope="module")
def chassis_frf():
    """The reference chassis' mobility on every harmonic's lines."""
    return fbs_core.reference_chassis().mobility(GRID)


@pytest.fixture(scope="module")
def doubled_mat(chassis_frf):
    """A MATLAB file of the reference chassis mobility times 2, nodes numbered 3 and 8."""
    return save_frf(_renumber(chassis_frf, 2.0), format="mat")


def _data_hashes():
    return {
        p.name: hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted((ROOT / "data").iterdir())
        if p.is_file()
    }


def _tire_bytes(tmp_path, model, name="tire.h5"):
    return save_tire_model(model, tmp_path / name).read_bytes()


def _sub_tire(n_modes=None, speeds=slice(None)):
    T = fbs_core.reference_tire()
    m = slice(None) if n_modes is None else slice(0, n_modes)
    return TireModel(
        T.speeds[speeds],
        T.poles[speeds, m],
        T.psi[speeds, m],
        T.chi[speeds, m],
        T.wavelengths,
        T.participation[speeds][:, :, m],
        meta={"source": "test"},
    )


# -- the chassis upload ----------------------------------------------------------------------
def test_chassis_upload_with_node_numbers_replaces_the_chassis(chassis_frf, doubled_mat):
    ds = DataSource()
    assert ds.models is REFERENCE
    # nodes numbered 3 and 8 in the file: the default names are refused with the file's nodes
    assert not ds.load_chassis(doubled_mat, "chassis.mat")
    assert "3, 8" in ds.error and ds.models is REFERENCE
    assert ds.load_chassis(doubled_mat, "chassis.mat", spindle="3", bushing="8"), ds.error
    assert ds.error == "" and ds.models.chassis is not None and ds.models.tire is None
    # what was read is shown: quantity, DOFs, frequency range
    s = ds.chassis_summary
    assert "mobility" in s and "bushing:rz" in s and "spindle:x" in s
    assert "13" in s and "422" in s
    f = fbs_core.harmonic(3).frequencies()
    got = ds.models.chassis.mobility(f)
    want = fbs_core.reference_chassis().mobility(f)
    assert got.outputs == want.outputs and got.inputs == want.inputs
    np.testing.assert_allclose(got.data, 2.0 * want.data, rtol=1e-12)


def test_bad_bytes_show_an_error_and_change_nothing(doubled_mat):
    ds = DataSource()
    assert ds.load_chassis(doubled_mat, "c.mat", spindle="3", bushing="8")
    before = (ds.models, ds.chassis_summary, ds.tire_summary)
    for raw, name, words in [
        (b"\x00garbage" * 50, "chassis.uff", "chassis.uff"),
        (b"PK\x03\x04" + bytes(200), "chassis.mat", "chassis.mat"),
        (doubled_mat[: len(doubled_mat) // 2], "cut.mat", "cut.mat"),
        (b"", "empty.csv", "empty"),
    ]:
        assert not ds.load_chassis(raw, name, spindle="3", bushing="8")
        assert words in ds.error
        assert (ds.models, ds.chassis_summary, ds.tire_summary) == before
        assert not ds.load_tire(raw, name)
        assert (ds.models, ds.chassis_summary, ds.tire_summary) == before


def test_missing_bushing_dof_is_named(chassis_frf):
    Y = _renumber(chassis_frf, 1.0, "spindle", "bushing")
    Y = Y.sel(outputs=[o for o in Y.outputs if o != "bushing:rz"])
    ds = DataSource()
    assert not ds.load_chassis(save_frf(Y, format="mat"), "five.mat")
    assert "bushing:rz" in ds.error and ds.models is REFERENCE


def test_other_grid_needs_an_explicit_interpolation(chassis_frf):
    coarse = chassis_frf.isel(freq=slice(0, None, 2)).crop(None, 422.0)  # 1 Hz lines
    raw = save_frf(coarse, format="hdf5")
    ds = DataSource()
    assert not ds.load_chassis(raw, "coarse.h5")
    assert "interpolate" in ds.error and ds.models is REFERENCE
    assert ds.load_chassis(raw, "coarse.h5", interpolate=True), ds.error
    assert "interpolated" in ds.chassis_summary
    f = fbs_core.harmonic(1).frequencies()  # 13.0, 13.5, ... : every other line is new
    got = ds.models.chassis.mobility(f).data
    on = np.isin(f, coarse.freq)
    np.testing.assert_allclose(got[on], chassis_frf.data[np.isin(GRID, f[on])], rtol=1e-12)
    # linear in real and imaginary part between the neighbouring lines
    k = np.flatnonzero(~on)[0]
    lo = coarse.data[np.flatnonzero(coarse.freq == f[k] - 0.5)[0]]
    hi = coarse.data[np.flatnonzero(coarse.freq == f[k] + 0.5)[0]]
    np.testing.assert_allclose(got[k], 0.5 * (lo + hi), rtol=1e-12)


# -- the tire upload -------------------------------------------------------------------------
def test_tire_upload_shows_modes_and_operating_points(tmp_path):
    ds = DataSource()
    # the reference tire's operating points 20, 40, ..., 120 km/h
    sp = fbs_core.reference_tire().speeds
    sub = _sub_tire(n_modes=200, speeds=np.isin(sp, np.arange(20.0, 121.0, 20.0)))
    assert ds.load_tire(_tire_bytes(tmp_path, sub), "supplier.h5"), ds.error
    assert ds.models.tire.n_modes == 200 and ds.models.chassis is None
    s = ds.tire_summary
    assert "200 complex modes" in s and "20, 40, 60, 80, 100, 120 km/h" in s
    assert "0.646" in s  # wavelengths of the harmonic cases


def test_tire_without_the_harmonics_operating_points_is_refused(tmp_path):
    ds = DataSource()
    # operating points from 60 km/h: the harmonics need 30 km/h
    sub = _sub_tire(speeds=fbs_core.reference_tire().speeds >= 60.0)
    assert not ds.load_tire(_tire_bytes(tmp_path, sub), "t.h5")
    assert "outside the operating points" in ds.error and "harmonic 1" in ds.error
    assert ds.models is REFERENCE


def test_reset_goes_back_to_the_reference(tmp_path, doubled_mat):
    ds = DataSource()
    assert ds.load_chassis(doubled_mat, "c.mat", spindle="3", bushing="8")
    assert ds.load_tire(_tire_bytes(tmp_path, _sub_tire(n_modes=100)), "t.h5")
    assert ds.models.tire is not None and ds.models.chassis is not None
    ds.reset()
    assert ds.models is REFERENCE and ds.chassis_summary == ds.tire_summary == ""


# -- sessions and the shipped data -----------------------------------------------------------
def test_two_sessions_are_independent(doubled_mat):
    a, b = DataSource(), DataSource()
    assert a.load_chassis(doubled_mat, "c.mat", spindle="3", bushing="8")
    assert b.models is REFERENCE and b.chassis_summary == "" and b.spindle == "spindle"
    assert not b.load_chassis(b"junk", "x.csv")
    assert a.error == "" and a.models.chassis is not None


def test_uploads_never_touch_the_shipped_data(tmp_path, chassis_frf):
    before = _data_hashes()
    ds = DataSource()
    # files named like the shipped ones, good and bad
    raw = save_frf(_renumber(chassis_frf, 3.0, "spindle", "bushing"), format="hdf5")
    assert ds.load_chassis(raw, "reference_chassis.h5"), ds.error
    assert not ds.load_chassis(b"\x89HDF\r\n\x1a\n" + bytes(100), "reference_chassis.h5")
    assert ds.load_tire(_tire_bytes(tmp_path, _sub_tire(n_modes=60)), "reference_tire.h5")
    assert not ds.load_tire(b"not a tire", "reference_tire.h5")
    ds.reset()
    assert _data_hashes() == before


# -- the upload view -------------------------------------------------------------------------
def test_upload_view_shows_the_summary_or_the_error(doubled_mat):
    ds = DataSource()
    view = UploadView(data=ds)
    view.__panel__().get_root()  # renders
    view.spindle.value, view.bushing.value = "3", "8"
    view.chassis_file.param.update(value=doubled_mat, filename="mine.mat")
    assert ds.error == "" and ds.models.chassis_name == "mine.mat"
    summary = view._summary()
    assert "alert-success" in summary.object and "bushing:z" in summary.object
    assert "uploaded chassis &#x27;mine.mat&#x27;" in summary.object
    assert not view._error().visible
    view.tire_file.param.update(value=b"no tire here", filename="t.mat")
    err = view._error()
    assert err.visible and "t.mat" in err.object and "refused" in err.object
    assert ds.models.chassis_name == "mine.mat" and ds.models.tire is None
    view.reset.clicks += 1
    assert ds.models is REFERENCE and not view._error().visible


def test_file_names_are_text_never_links_or_images(doubled_mat):
    """A file name with Markdown or HTML in it is shown as text in the alerts: no live link,
    no external image (the page renders what the pane's model holds)."""
    ds = DataSource()
    view = UploadView(data=ds)
    view.__panel__().get_root()
    evil = "[click](http://evil.example) ![x](http://evil.example/i.png) <img src=x>.mat"
    view.tire_file.param.update(value=b"not a tire", filename=evil)
    err = view._error()
    shown = html.unescape(err.get_root().text)  # the HTML the browser renders
    assert err.visible and "evil.example" in shown
    assert "<a" not in shown and "<img" not in shown
    view.spindle.value, view.bushing.value = "3", "8"
    view.chassis_file.param.update(value=doubled_mat, filename=evil.replace(".mat", "2.mat"))
    assert ds.error == ""
    shown = html.unescape(view._summary().get_root().text)
    assert "evil.example" in shown and "<a" not in shown and "<img" not in shown


# -- the views on the session's models (app.compute keys its caches on them) -----------------
def _results():
    from app.state import DashboardState
    from app.store import Results

    state = DashboardState()
    state.noise.rounds = 20
    return Results(state)


NAMES = [
    "mobility.reference",
    "mobility.truncated",
    "truncation.map",
    "scatter.minmax",
    "scatter.percentile",
    "scatter.reference",
    "scatter.round",
    "eigen.f_80",
]


def _plot_data(root):
    from bokeh.models import ColumnDataSource

    out = {}
    for name in NAMES:
        (src,) = [m for m in root.select({"name": name}) if isinstance(m, ColumnDataSource)]
        out[name] = {k: np.array(v, copy=True) for k, v in src.data.items()}
    return out


def _moved(a, b):
    return {
        n
        for n in a
        if not all(
            np.shape(a[n][k]) == np.shape(b[n][k])
            and np.array_equal(a[n][k], b[n][k], equal_nan=True)
            for k in a[n]
        )
    }


def test_the_page_runs_every_view_on_an_upload_of_this_session_only(doubled_mat):
    from app.main import create_app
    from app.state import DashboardState

    state, other = DashboardState(), DashboardState()
    for s in (state, other):
        s.noise.rounds = 100
    root = create_app(state).main[0].get_root()
    before = _plot_data(root)
    assert state.data.load_chassis(doubled_mat, "mine.mat", spindle="3", bushing="8")
    assert state.case.models is state.data.models and other.case.models is REFERENCE
    after = _plot_data(root)
    # the tire did not change: the eigenfrequencies stay; every coupled view moves
    assert _moved(before, after) == set(NAMES) - {"eigen.f_80"}
    c = state.case
    br = fbs_core.bushing_response(
        c.harmonic, n_modes=c.n_modes, coupling=c.coupling, chassis=state.data.models.chassis
    )
    want = 20 * np.log10(np.abs(br.sel(outputs=f"bushing:{c.dof}").data[:, 0, 0]))
    np.testing.assert_allclose(after["mobility.truncated"]["level"], want, rtol=1e-9)
    state.data.reset()
    assert _moved(before, _plot_data(root)) == set()


def test_views_on_the_unchanged_chassis_equal_the_reference(chassis_frf):
    from app import compute

    res = _results()
    res.state.case.param.update(harmonic=2, n_modes=60, dof="y", show_uncoupled=True)
    ref, ref_u = res.response.columns, res.uncoupled.columns
    raw = save_frf(_renumber(chassis_frf, 1.0, "spindle", "bushing"), format="uff")
    assert res.state.data.load_chassis(raw, "same.uff"), res.state.data.error
    got, got_u = res.response.columns, res.uncoupled.columns
    for k in ("reference", "truncated"):
        np.testing.assert_allclose(got[k], ref[k], rtol=1e-5)  # UFF: single precision
    np.testing.assert_allclose(got_u["chassis"], ref_u["chassis"], rtol=1e-5)
    # the reference results are still the cached reference ones
    again = compute.mobility_data(2, 60, "y", "6dof")
    np.testing.assert_array_equal(again["truncated"], ref["truncated"])


def test_doubled_chassis_shows_6_db_more_uncoupled_mobility(doubled_mat):
    res = _results()
    res.state.case.show_uncoupled = True
    ref = res.uncoupled.columns
    assert res.state.data.load_chassis(doubled_mat, "c.mat", spindle="3", bushing="8")
    got = res.uncoupled.columns
    np.testing.assert_allclose(
        got["chassis_dB"], ref["chassis_dB"] + 20 * np.log10(2.0), rtol=0, atol=1e-9
    )
    np.testing.assert_array_equal(got["tire_truncated"], ref["tire_truncated"])


def test_truncated_tire_upload_is_the_reference_with_fewer_modes(tmp_path):
    from app import compute

    res = _results()
    state = res.state
    state.case.param.update(harmonic=1, n_modes=100, dof="z")
    assert state.data.load_tire(_tire_bytes(tmp_path, _sub_tire(n_modes=200)), "t200.h5")
    mob = res.response.columns
    ref100 = compute.mobility_data(1, 100, "z", "6dof")
    ref200 = compute.mobility_data(1, 200, "z", "6dof")
    # the first 100 modes are the reference's; "all modes" of this tire are its 200 (the
    # reference keeps the 100 lowest pairs of each operating point and interpolates its
    # clusters of close modes whole, so a cut of the stored modes differs slightly)
    np.testing.assert_allclose(mob["truncated"], ref100["truncated"], rtol=1e-3)
    np.testing.assert_allclose(mob["reference"], ref200["truncated"], rtol=1e-3)
    m = res.error_map.draw["map"]
    assert m["n_modes"].tolist() == list(range(10, 200, 10))
    e = res.eigen.draw["curves"]
    e_ref = compute.eigen_curves()
    k = e["n_modes"].size
    assert e["n_modes"][-1] == 200
    np.testing.assert_allclose(e["f_80"], e_ref["f_80"][:k], rtol=1e-12)
    state.case.n_modes = 300  # more than the tire has: all of its modes
    mob = res.response.columns
    np.testing.assert_array_equal(mob["truncated"], mob["reference"])


def test_zero_noise_band_on_an_upload_is_its_coupled_response(doubled_mat):
    res = _results()
    res.state.noise.param.update(noise=0.0, rounds=20)
    assert res.state.data.load_chassis(doubled_mat, "c.mat", spindle="3", bushing="8")
    res.request_band(wait=True)
    b = res.band_curves.draw["band"]
    mob = res.response.columns
    np.testing.assert_allclose(b["reference"], mob["truncated"], rtol=1e-9)
    np.testing.assert_allclose(b["maximum"], np.abs(mob["truncated"]), rtol=1e-9)


def test_ill_conditioned_interface_is_refused(chassis_frf):
    # a rigid-link-like spindle block: the same huge mobility in every entry (rank one)
    Y = _renumber(chassis_frf, 1.0, "spindle", "bushing")
    data = np.array(Y.data)
    data[:, :6, :6] = 1e6 * np.abs(data[:, :1, :1]).max() * np.ones((6, 6))
    ds = DataSource()
    assert not ds.load_chassis(save_frf(Y.replace(data=data), format="mat"), "rigid.mat")
    assert "ill-conditioned" in ds.error and "harmonic 1" in ds.error
    assert ds.models is REFERENCE


def test_free_rolling_coupling_runs_on_an_upload(doubled_mat):
    res = _results()
    state = res.state
    assert state.data.load_chassis(doubled_mat, "c.mat", spindle="3", bushing="8")
    state.case.param.update(coupling="5dof", harmonic=4, n_modes=80)
    mob = res.response.columns
    br = fbs_core.bushing_response(
        4, n_modes=80, coupling="5dof", chassis=state.data.models.chassis
    )
    np.testing.assert_allclose(
        mob["truncated"], br.sel(outputs="bushing:z").data[:, 0, 0], rtol=1e-9
    )
    tab = res.suggested.draw["table"]
    assert list(tab["harmonic"]) == list(range(1, 8)) and np.all(tab["n_modes"] > 0)


def test_tire_from_matlab_in_the_documented_layout():
    import io

    from scipy.io import savemat

    from app import compute

    T = _sub_tire(n_modes=120)
    buf = io.BytesIO()
    savemat(
        buf,
        {
            "speeds": T.speeds,
            "poles": T.poles,
            "psi": T.psi,
            "chi": T.chi,
            "wavelengths": T.wavelengths,
            "participation": T.participation,
        },
    )
    res = _results()
    state = res.state
    assert state.data.load_tire(buf.getvalue(), "supplier_tire.mat"), state.data.error
    assert "120 complex modes" in state.data.tire_summary
    assert "MATLAB" in state.data.tire_summary
    state.case.param.update(harmonic=5, n_modes=60)
    mob = res.response.columns
    np.testing.assert_allclose(
        mob["truncated"], compute.mobility_data(5, 60, "z", "6dof")["truncated"], rtol=1e-9
    )


def test_changed_settings_re_read_the_chassis_even_after_a_stale_click(chassis_frf):
    """Ticking 'interpolate' re-reads the uploaded file at once. A click on 'Read chassis
    again' that the server handles before the tick (Panel runs both on worker threads, in
    either order) reads the old settings and fails, but the tick still wins: the last
    reading always has the last settings."""
    coarse = chassis_frf.isel(freq=slice(0, None, 2)).crop(None, 422.0)  # 1 Hz lines
    raw = save_frf(coarse, format="hdf5")
    ds = DataSource()
    view = UploadView(data=ds)
    view.__panel__().get_root()
    view.chassis_file.param.update(value=raw, filename="coarse.h5")
    assert "interpolate" in ds.error and ds.models is REFERENCE
    view.reread.clicks += 1  # the stale click: still without interpolation
    assert "interpolate" in ds.error and ds.models is REFERENCE
    view.interpolate.value = True  # the tick arrives: read again with the new setting
    assert ds.error == "" and ds.models.chassis_name == "coarse.h5"
    assert "interpolated" in ds.chassis_summary
    before = ds.models
    view.reread.clicks += 1  # same settings: an explicit re-read gives the same models
    assert ds.models == before
    view.bushing.value = "nowhere"  # a wrong node name is reported, nothing else changes
    assert "no bushing node 'nowhere'" in ds.error and ds.models == before


@pytest.mark.parametrize("which", ["chassis", "tire"])
def test_an_empty_file_is_refused_with_a_message(which):
    """An empty upload (issue 20: it was ignored silently) says so in the page and
    changes nothing."""
    ds = DataSource()
    view = UploadView(data=ds)
    view.__panel__().get_root()
    widget = view.chassis_file if which == "chassis" else view.tire_file
    name = "empty.uff" if which == "chassis" else "empty.h5"
    widget.param.update(value=b"", filename=name)
    err = view._error()
    assert err.visible and "refused" in err.object
    assert f"{name}" in err.object and "empty" in err.object
    assert ds.models is REFERENCE


def test_an_empty_file_is_answered_and_an_earlier_error_does_not_stay():
    """Panel hands an empty upload over as its file name with the value None (the browser's
    empty base64 text): it is read as an empty file and the page names the problem, the
    earlier file's error is replaced, and the same empty file uploaded again is answered
    again."""
    from app.views.upload import UploadView

    view = UploadView(data=DataSource())
    ds = view.data
    view.chassis_file.param.update(value=b"junk", filename="first.csv")  # a refused file
    assert "first.csv" in ds.error
    seen = []
    ds.param.watch(lambda e: seen.append(e.new), "error")
    # an empty file, as Panel gives it
    view.chassis_file.param.update(value=None, filename="empty.csv")
    assert "empty.csv" in ds.error and "empty" in ds.error.split(":", 1)[1]
    assert "first.csv" not in ds.error
    assert seen[0] == ""  # the stale error cleared as soon as the new file was taken
    seen.clear()
    view.chassis_file.param.update(value=None, filename="empty.csv")  # the same again
    assert seen and seen[-1] == ds.error and "empty.csv" in ds.error
    # a tire file, empty
    view.tire_file.param.update(value=None, filename="tire.h5")
    assert "tire.h5" in ds.error and "is empty" in ds.error
