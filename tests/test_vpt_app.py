"""A measured chassis in a session: geometry upload, then the measured set, through the
session's DataSource (the page's upload path, without a browser)."""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core as fc
from app.datasource import REFERENCE, DataSource
from app.report.data import Provenance
from app.report.session import provenance_of
from app.views.vpt_consistency import consistency_plot, report_notes, table_html
from fbs_core.io.geometry import geometry_csv
from fbs_core.vpt import validation as val

#: Every harmonic's analysis grid (multiples of 0.5 Hz in 13-422 Hz).
GRID = np.arange(13.0, 422.01, 0.5)


@pytest.fixture(scope="module")
def files():
    m = val.knuckle_measurement(GRID, quantity="accelerance")
    return m, fc.save_frf(m.measured, format="hdf5"), geometry_csv(m.layout, "mm")


def test_geometry_then_measured_set_becomes_the_sessions_chassis(files) -> None:
    m, frf, geo = files
    ds = DataSource()
    assert ds.load_geometry(geo, "knuckle.csv"), ds.error
    assert ds.models is REFERENCE  # a geometry alone changes no model
    assert ds.load_chassis(frf, "knuckle.h5"), ds.error
    assert ds.vpt is not None and "virtual point 'spindle'" in ds.chassis_summary
    f = fc.harmonic(4).frequencies()
    Y = ds.models.chassis.mobility(f)
    E = m.exact.to("mobility")
    idx = np.searchsorted(GRID, f)
    err = np.abs(Y.data - E.data[idx]).max(0) / np.abs(E.data[idx]).max(0)
    assert err.max() < 0.01
    html = table_html(ds.vpt)
    assert "sa:x" in html and "tc:z" in html and "leverage" in html
    assert consistency_plot(ds.vpt).visible
    (note,) = report_notes(ds)
    assert "virtual point 'spindle'" in note and "lowest channel" in note
    prov = provenance_of(ds.models, report_notes(ds))
    assert isinstance(prov, Provenance) and prov.notes == (note,)
    # a geometry that misses a channel is refused, and the chassis stays as it was
    key = ds.models.key
    bad = "\n".join(r for r in geo.decode().splitlines() if not r.startswith("sb:"))
    assert not ds.load_geometry(bad.encode(), "bad.csv")
    assert "sensor channel 'sb:x'" in ds.error
    assert ds.models.key == key
    ds.reset()
    assert ds.models is REFERENCE and ds.vpt is None and not consistency_plot(None).visible
    assert report_notes(ds) == ()


def test_a_refused_geometry_file_changes_nothing() -> None:
    ds = DataSource()
    assert not ds.load_geometry(b"channel,role,x\n", "g.csv")
    assert "needs the columns" in ds.error
    assert ds.models is REFERENCE and ds.geometry_summary == ""


def test_the_report_draws_the_consistency_of_the_measured_chassis(files) -> None:
    """A session whose chassis was measured: its report has a section per role (sensors,
    impacts) drawing each channel's specific consistency over frequency, the core's values;
    back to the reference, the sections go."""
    from app.report.session import report_data
    from app.state import DashboardState
    from app.store import Results

    _m, frf, geo = files
    store = Results(DashboardState())
    ds = store.state.data
    assert ds.load_geometry(geo, "knuckle.csv") and ds.load_chassis(frf, "knuckle.h5"), ds.error
    c = ds.vpt.consistency
    extra = {x.key: x for x in report_data(store).extra}
    for role, labels, values in (
        ("sensors", c.sensors, c.sensor_specific),
        ("impacts", c.impacts, c.impact_specific),
    ):
        sec = extra[f"vpt_{role}"]
        assert sec.plot["kind"] == "lines" and list(sec.plot["groups"]) == list(labels)
        for k, lab in enumerate(labels):
            np.testing.assert_array_equal(sec.plot["groups"][lab][0], values[:, k])
        assert 0.0 <= float(dict(sec.rows)[f"overall {role[:-1]} consistency"]) <= 1.0
    from app.report.html import build_html

    _name, page = build_html(report_data(store))
    assert "Virtual point consistency of the sensors" in page and page.count("<svg") >= 2
    ds.reset()
    assert not {"vpt_sensors", "vpt_impacts"} & {x.key for x in report_data(store).extra}
