"""The bushing's six DOFs by a second virtual point: sensors around it, response side only.

Truth: the FE model of fbs_core.vpt.validation solved directly. The sensors around the
bushing are either the bushing node's rigid-body motion (``bushing="rigid"``: the
transformation's exact case, to machine precision) or FE nodes on three short stiff arms
welded to it (``bushing="arms"``: off by the arms' own compliance, below
``(f / f_1)^2`` of the response with ``f_1`` their first flexible mode). The coupled bushing
response of the measured chassis is compared with that of the model's exact chassis at all
six bushing DOFs. Files go through the project's writers (UFF 58, CSV geometry) and
readers (``load_measured_chassis``).
"""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.chassis import BUSHING, SPINDLE
from fbs_core.errors import DOFError, GeometryError, QuantityError
from fbs_core.io import load_measured_chassis
from fbs_core.io.geometry import geometry_csv
from fbs_core.vpt import Channels, response_point, transformation
from fbs_core.vpt import validation as val

F = np.arange(2.0, 450.1, 4.0)
#: UFF node numbers of the points of the measured set
NODES = {101: "sa", 102: "sb", 103: "sc", 201: "ma", 202: "mb", 203: "mc", 301: "ta"}
NODES |= {302: "tb", 303: "tc", 2: "bushing", 401: "bushing_a", 402: "bushing_b"}
NODES |= {403: "bushing_c"}


def rel_to_peak(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """max over lines |a - b| / max over lines |b|, per entry."""
    out: np.ndarray = np.abs(a - b).max(0) / np.abs(b).max(0)
    return out


@pytest.fixture(scope="module")
def rigid() -> val.KnuckleMeasurement:
    return val.knuckle_measurement(F, "mobility", bushing="rigid")


def _files(m: val.KnuckleMeasurement) -> tuple[bytes, bytes]:
    assert m.bushing_sensors is not None
    frf = fc.save_frf(m.measured, format="uff", nodes=NODES)
    geo = geometry_csv(
        m.layout, "mm", sensors=m.bushing_sensors, points={"bushing": val.bushing_point()}
    )
    return frf, geo


def test_rigid_sensors_give_the_fe_bushing_dofs_exactly(rigid) -> None:
    assert rigid.bushing_sensors is not None and rigid.exact_bushing is not None
    rp = response_point(rigid.measured, rigid.bushing_sensors, val.bushing_point(), "bushing")
    assert rp.frf.outputs == rigid.layout.sensors.labels + BUSHING
    assert rp.frf.inputs == rigid.measured.inputs  # the inputs are not transformed
    q = rp.frf.sel(outputs=list(BUSHING))
    assert (rel_to_peak(q.data, rigid.exact_bushing.data)).max() < 1e-8
    np.testing.assert_allclose(rp.consistency.sensor_overall, 1.0, atol=1e-10)
    assert rp.consistency.impacts == () and np.isnan(rp.consistency.overall()[1])
    assert max(rp.sensor_leverage.values()) < 0.9  # every channel checked (layout rule 4)


def test_sensors_on_stiff_arms_are_within_their_compliance() -> None:
    # the arms' tips move as the bushing node's rigid body up to the arms' deformation
    # under their own inertia, about (f / f_1)^2 of the response at f
    f1 = val.bushing_arms_flexible_mode()
    assert f1 > 10 * F[-1]
    m = val.knuckle_measurement(F, "mobility", bushing="arms")
    assert m.bushing_sensors is not None and m.exact_bushing is not None
    rp = response_point(m.measured, m.bushing_sensors, val.bushing_point(), "bushing")
    err = rel_to_peak(rp.frf.sel(outputs=list(BUSHING)).data, m.exact_bushing.data)
    assert err.max() < (F[-1] / f1) ** 2 < 0.01, (err.max(), f1)
    assert rp.consistency.worst()[1] > 0.99


def test_a_real_tests_errors_stay_within_the_derived_bound(rigid) -> None:
    # 1 % noise, 2 mm and 2 degrees on the bushing sensors: every line, DOF and impact
    # within the first-order bound; the consistency falls
    assert rigid.bushing_sensors is not None and rigid.exact_bushing is not None
    E = rigid.exact_bushing.data
    # truth: the FE bushing DOFs; tolerance: the first-order bound of the three errors
    # (validation.bushing_error_bound: T_u on each channel's noise at 5 sigma, direction
    # and position error)
    bound = val.bushing_error_bound(rigid, 0.01, 0.002, 2.0)
    clean = response_point(rigid.measured, rigid.bushing_sensors, val.bushing_point(), "bushing")
    for seed in range(3):
        ch = val.perturbed_channels(rigid.bushing_sensors, 0.002, 2.0, seed=seed)
        rp = response_point(
            val.noisy(rigid.measured, 0.01, seed), ch, val.bushing_point(), "bushing"
        )
        err = np.abs(rp.frf.sel(outputs=list(BUSHING)).data - E)
        assert np.all(err <= 1.1 * bound)
        assert rp.consistency.overall()[0] < clean.consistency.overall()[0]
        assert rp.consistency.worst()[1] < 0.99


def test_uff_files_give_the_chassis_with_six_bushing_dofs_and_its_coupled_response() -> None:
    f = fc.harmonic(4).frequencies()
    m = val.knuckle_measurement(f, "accelerance", bushing="arms")
    frf, geo = _files(m)
    mc = load_measured_chassis(
        frf, geo, frf_filename="knuckle.unv", geometry_filename="geometry.csv", nodes=NODES
    )
    assert mc.bushing_vp is not None
    assert "second virtual point 'bushing'" in mc.summary
    assert "9 sensor channels around it" in mc.summary
    Y = mc.chassis.mobility(f)
    assert Y.outputs == SPINDLE + BUSHING
    E = m.exact.to("mobility")
    assert rel_to_peak(Y.data, E.data).max() < 0.01
    v = fc.bushing_response(4, chassis=mc.chassis)
    v_ex = fc.bushing_response(4, chassis=fc.FRFChassis(E))
    assert v.outputs == BUSHING
    err = rel_to_peak(v.data, v_ex.data)
    assert err.shape[0] == 6 and err.max() < 0.01, err.ravel()


def test_coupled_response_under_bushing_sensor_errors_stays_within_the_bound() -> None:
    # the bushing's rows of the chassis enter the coupled bushing response linearly,
    # v_b = Y_bs g with g the coupled interface forces at the spindle (which the bushing's
    # rows do not change): the per-impact bound, through T_f^T and |g|, bounds the error of
    # every line and DOF (knuckle channels exact; bushing sensors 1 %, 2 mm, 2 degrees)
    f = fc.harmonic(4).frequencies()
    m = val.knuckle_measurement(f, "accelerance", bushing="rigid")
    assert m.bushing_sensors is not None
    E = m.exact.to("mobility")
    v_ex = fc.bushing_response(4, chassis=fc.FRFChassis(E)).data[:, :, 0]
    unit = E.data.copy()
    unit[:, 6:12] = np.eye(6)  # bushing rows I: the "bushing response" is g itself
    g = fc.bushing_response(4, chassis=fc.FRFChassis(E.replace(data=unit))).data[:, :, 0]
    Tf = np.abs(transformation(m.layout.modes("impacts")))
    b = val.bushing_error_bound(m, 0.01, 0.002, 2.0)  # (n_f, 6, n_impacts), mobility
    B = np.einsum("fim,sm,fs->fi", b, Tf, np.abs(g))
    r0 = val.bushing_point()
    v0 = None
    for seed in range(3):
        ch = val.perturbed_channels(m.bushing_sensors, 0.002, 2.0, seed=seed)
        noisy = val.noisy(m.measured, 0.01, seed).data
        d = m.measured.data.copy()
        nk = len(m.layout.sensors)
        d[:, nk:] = noisy[:, nk:]
        rp = response_point(m.measured.replace(data=d), ch, r0, "bushing")
        vp = fc.virtual_point(rp.frf, m.layout, transfers=list(BUSHING))
        v = fc.bushing_response(4, chassis=fc.FRFChassis(vp.frf.to("mobility"))).data[:, :, 0]
        if v0 is None:
            clean = response_point(m.measured, m.bushing_sensors, r0, "bushing")
            vpc = fc.virtual_point(clean.frf, m.layout, transfers=list(BUSHING))
            v0 = fc.bushing_response(4, chassis=fc.FRFChassis(vpc.frf.to("mobility"))).data
            v0 = v0[:, :, 0]
            # noise-free: the knuckle's VPT alone, within 1 % of each DOF's peak
            assert (np.abs(v0 - v_ex).max(0) / np.abs(v_ex).max(0)).max() < 0.01
        assert np.all(np.abs(v - v_ex) <= np.abs(v0 - v_ex) + 1.1 * B)


def test_coupled_response_with_a_real_tests_errors() -> None:
    # 1 % noise on every FRF, 2 mm / 2 degrees on every knuckle and bushing channel, through
    # the files: the coupled bushing response's median level error per DOF within 3 dB for
    # the translations (docs/vpt.md) and 6 dB for the rotations (the lever arm's price)
    f = fc.harmonic(4).frequencies()
    m = val.knuckle_measurement(f, "accelerance", bushing="arms")
    assert m.bushing_sensors is not None
    v_ex = fc.bushing_response(4, chassis=fc.FRFChassis(m.exact.to("mobility")))
    clean = response_point(m.measured, m.bushing_sensors, val.bushing_point(), "bushing")
    for seed in range(3):
        lay = val.perturbed_layout(m.layout, 0.002, 2.0, seed=seed)
        ch = val.perturbed_channels(m.bushing_sensors, 0.002, 2.0, seed=100 + seed)
        geo = geometry_csv(lay, sensors=ch, points={"bushing": val.bushing_point()})
        raw = fc.save_frf(val.noisy(m.measured, 0.01, seed=seed), format="hdf5")
        mc = load_measured_chassis(raw, geo, frf_filename="k.h5", geometry_filename="g.csv")
        assert mc.bushing_vp is not None
        assert mc.bushing_vp.consistency.overall()[0] < clean.consistency.overall()[0]
        assert mc.bushing_vp.consistency.worst()[1] < clean.consistency.worst()[1]
        v = fc.bushing_response(4, chassis=mc.chassis)
        db = np.median(np.abs(20 * np.log10(np.abs(v.data) / np.abs(v_ex.data))), axis=0)[:, 0]
        assert db[:3].max() < 3.0 and db[3:].max() < 6.0, db


def test_both_direct_bushing_outputs_and_sensors_around_it_are_refused(rigid) -> None:
    both = fc.FRF(
        F,
        np.concatenate([rigid.measured.data, rigid.exact_bushing.data[:, :3]], axis=1),
        rigid.measured.outputs + BUSHING[:3],
        rigid.measured.inputs,
        "mobility",
    )
    frf = fc.save_frf(both, format="hdf5")
    _, geo = _files(rigid)
    with pytest.raises(
        DOFError,
        match=r"'bushing' itself \(bushing:x, bushing:y, bushing:z\) "
        r"and sensors around it \(bushing_a:x",
    ):
        load_measured_chassis(frf, geo, frf_filename="k.h5", geometry_filename="g.csv")
    # the explicit rule: no sensors around the bushing -> the direct outputs, as before
    mc = load_measured_chassis(
        fc.save_frf(both.sel(outputs=[o for o in both.outputs if "_" not in o]), format="hdf5"),
        geo,
        frf_filename="k.h5",
        geometry_filename="g.csv",
    )
    assert mc.bushing_vp is None and "second virtual point" not in mc.summary
    with pytest.raises(DOFError, match=r"'bushing' itself"):
        response_point(both, rigid.bushing_sensors, val.bushing_point(), "bushing")


def test_too_few_collinear_or_unplaced_bushing_sensors_are_named(rigid) -> None:
    ch = rigid.bushing_sensors
    assert ch is not None
    r0 = val.bushing_point()
    few = Channels(ch.labels[:4], ch.positions[:4], ch.directions[:4])
    with pytest.raises(
        GeometryError,
        match=r"4 sensor channels \(bushing_a:x, .*bushing_b:x\) "
        r"cannot observe the six DOFs of the virtual point 'bushing'",
    ):
        response_point(rigid.measured, few, r0, "bushing")
    # the three sensors on one line through the bushing: the rotation about it is unseen
    line = Channels(ch.labels, [r0 + (0.03 * (k // 3 + 1), 0, 0) for k in range(9)], ch.directions)
    with pytest.raises(GeometryError, match=r"'bushing': bushing:rx.*one line"):
        response_point(rigid.measured, line, r0, "bushing")
    # the same through the files: the geometry puts the three sensors on the line through
    # the bushing and sensor a (at 1, -1 and 2 times a's lever arm)
    frf, geo = _files(rigid)
    text = geo.decode().splitlines()
    r0_mm = 1000 * r0
    a_mm = np.array(
        [float(v) for v in next(r for r in text if r.startswith("bushing_a:x")).split(",")[2:5]]
    )
    at = {"bushing_a": 1.0, "bushing_b": -1.0, "bushing_c": 2.0}

    def on_line(row: str) -> str:
        cells = row.split(",")
        s = at.get(cells[0].split(":")[0])
        if s is None:
            return row
        xyz = r0_mm + s * (a_mm - r0_mm)
        return ",".join([cells[0], cells[1], *(f"{v:.9g}" for v in xyz), *cells[5:]])

    with pytest.raises(
        GeometryError,
        match=r"the 9 sensor channels \(bushing_a:x.*\) do not "
        r"observe 1 of the six DOFs of the virtual point 'bushing'.*one line",
    ):
        load_measured_chassis(
            frf,
            "\n".join(on_line(r) for r in text).encode(),
            frf_filename="k.unv",
            geometry_filename="g.csv",
            nodes=NODES,
        )
    missing = "\n".join(r for r in text if not r.startswith("bushing_b:"))
    with pytest.raises(GeometryError, match=r"bushing sensor channel 'bushing_b:x': node "):
        load_measured_chassis(
            frf, missing.encode(), frf_filename="k.unv", geometry_filename="g.csv", nodes=NODES
        )
    nopoint = "\n".join(r for r in text if not r.startswith("bushing,point"))
    with pytest.raises(GeometryError, match=r"second virtual point 'bushing' as a point"):
        load_measured_chassis(
            frf, nopoint.encode(), frf_filename="k.unv", geometry_filename="g.csv", nodes=NODES
        )
    rot = rigid.measured.replace(
        outputs=tuple("bushing_a:rx" if o == "bushing_a:x" else o for o in rigid.measured.outputs)
    )
    lab = tuple("bushing_a:rx" if o == "bushing_a:x" else o for o in ch.labels)
    with pytest.raises(QuantityError, match=r"'bushing_a:rx' is a rotation"):
        response_point(rot, Channels(lab, ch.positions, ch.directions), r0, "bushing")


def test_dashboard_upload_with_bushing_sensors_gives_six_bushing_dofs() -> None:
    # the page's upload path without a browser: geometry (with the bushing sensors and the
    # point 'bushing'), then the measured set; the session's chassis has the bushing's six
    # DOFs, rotations included, within 1 % of the exact chassis' peaks
    from app.datasource import REFERENCE, DataSource

    grid = np.arange(13.0, 422.01, 0.5)  # every harmonic's analysis grid
    m = val.knuckle_measurement(grid, "accelerance", bushing="arms")
    assert m.bushing_sensors is not None
    geo = geometry_csv(
        m.layout, "mm", sensors=m.bushing_sensors, points={"bushing": val.bushing_point()}
    )
    ds = DataSource()
    assert ds.load_geometry(geo, "knuckle.csv"), ds.error
    assert ds.load_chassis(fc.save_frf(m.measured, format="hdf5"), "knuckle.h5"), ds.error
    assert ds.models is not REFERENCE
    assert "second virtual point 'bushing'" in ds.chassis_summary
    assert ds.bushing_vp is not None and ds.bushing_vp.node == "bushing"
    from app.views.vpt_consistency import report_notes

    spindle_note, bushing_note = report_notes(ds)
    assert "virtual point 'spindle'" in spindle_note
    assert "second virtual point 'bushing' (9 sensor channels" in bushing_note
    f = fc.harmonic(4).frequencies()
    Y = ds.models.chassis.mobility(f)
    assert Y.outputs == SPINDLE + BUSHING
    E = m.exact.to("mobility").data[np.searchsorted(grid, f)]
    assert rel_to_peak(Y.data, E).max() < 0.01
    ds.reset()
    assert ds.bushing_vp is None and ds.vpt is None


def test_a_sensor_at_the_bushing_itself_joins_the_second_virtual_point() -> None:
    # the documented way to keep a tri-axial sensor at the bushing with sensors around it:
    # its node named bushing_0, its row at the bushing point; the result stays exact
    ch = val.bushing_sensors()
    r0 = val.bushing_point()
    lab = [*ch.labels, "bushing_0:x", "bushing_0:y", "bushing_0:z"]
    with0 = Channels(
        lab, np.vstack([ch.positions, np.tile(r0, (3, 1))]), np.vstack([ch.directions, np.eye(3)])
    )
    m = val.knuckle_measurement(F, "mobility", bushing="rigid", bushing_layout=with0)
    assert m.exact_bushing is not None
    frf, geo = _files(m)
    nodes = NODES | {400: "bushing_0"}
    frf = fc.save_frf(m.measured, format="uff", nodes=nodes)
    mc = load_measured_chassis(
        frf, geo, frf_filename="k.unv", geometry_filename="g.csv", nodes=nodes
    )
    assert mc.bushing_vp is not None and len(mc.bushing_vp.sensors) == 12
    q = mc.bushing_vp.frf.sel(outputs=list(BUSHING)).data
    assert rel_to_peak(q, m.exact_bushing.data).max() < 1e-8  # through the UFF 58 file
