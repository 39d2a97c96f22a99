"""Geometry files for the virtual point transformation: UFF 15/2411, CSV and HDF5 tables.

Truth: files written by independent writers (pyuff for UFF, h5py for HDF5, plain text for
CSV) with known coordinates; the whole path file -> load_frf / load_geometry ->
virtual_point gives the same FRF as the layout in memory. Bad input is refused by name.
"""

from __future__ import annotations

import io

import h5py
import numpy as np
import pytest
import pyuff

import fbs_core as fc
from fbs_core.errors import DataFormatError, DOFError, GeometryError
from fbs_core.io.geometry import geometry_csv, load_geometry
from fbs_core.vpt import validation as val
from fbs_core.vpt import virtual_point

F = np.arange(5.0, 200.0, 15.0)


def _uff(tmp_path, sets) -> str:
    p = tmp_path / "geometry.unv"
    u = pyuff.UFF(str(p))
    for s in sets:
        u.write_sets(s, "add")
    return str(p)


def test_uff_15_and_2411_in_mm_with_dataset_164(tmp_path) -> None:
    path = _uff(
        tmp_path,
        [
            pyuff.prepare_164(
                units_code=5,
                units_description="mm",
                temp_mode=1,
                length=1000.0,
                force=1.0,
                temp=1.0,
                temp_offset=273.15,
            ),
            pyuff.prepare_15(
                node_nums=[1, 2],
                def_cs=[0, 0],
                disp_cs=[0, 0],
                color=[1, 1],
                x=[90.0, -90.0],
                y=[720.0, 720.0],
                z=[120.0, 130.0],
            ),
            pyuff.prepare_2411(
                node_nums=[3, 4],
                def_cs=[1, 1],
                disp_cs=[1, 1],
                color=[1, 1],
                x=[15.0, 0.0],
                y=[710.0, 750.0],
                z=[-25.0, 80.0],
            ),
        ],
    )
    g = load_geometry(path, nodes={4: "spindle"})
    np.testing.assert_allclose(g.points["1"], [0.09, 0.72, 0.12])
    np.testing.assert_allclose(g.points["3"], [0.015, 0.71, -0.025])
    np.testing.assert_allclose(g.points["spindle"], [0.0, 0.75, 0.08])
    pos, d = g.channel("2:y")
    np.testing.assert_allclose(pos, [-0.09, 0.72, 0.13])
    assert d.tolist() == [0.0, 1.0, 0.0]


def test_uff_node_in_a_local_system_is_refused_by_name(tmp_path) -> None:
    path = _uff(
        tmp_path,
        [
            pyuff.prepare_15(
                node_nums=[7], def_cs=[0], disp_cs=[3], color=[1], x=[0.0], y=[0.0], z=[0.0]
            )
        ],
    )
    with pytest.raises(
        GeometryError, match="node 7 gives its displacements in coordinate system 3"
    ):
        load_geometry(path)


def test_csv_and_hdf5_tables_give_the_same_virtual_point_as_memory(tmp_path) -> None:
    m = val.knuckle_measurement(F, quantity="accelerance")
    lay = m.layout
    direct = virtual_point(m.measured, lay).frf
    # the measured set through a file, as today
    frf, _ = fc.load_frf(fc.save_frf(m.measured, format="csv"), filename="meas.csv")
    sensors = [o for o in frf.outputs if not o.startswith("bushing")]
    # CSV in mm
    g = load_geometry(geometry_csv(lay, "mm"), filename="geometry.csv")
    r = virtual_point(frf, g.layout(sensors, frf.inputs))
    assert r.frf.outputs == direct.outputs
    np.testing.assert_allclose(
        r.frf.data, direct.data, rtol=0, atol=1e-9 * np.abs(direct.data).max()
    )
    # HDF5 written by h5py in metres
    buf = io.BytesIO()
    labels = list(lay.sensors.labels) + list(lay.impacts.labels) + ["spindle"]
    roles = ["sensor"] * len(lay.sensors) + ["impact"] * len(lay.impacts) + ["point"]
    pos = np.vstack([lay.sensors.positions, lay.impacts.positions, lay.origin])
    dirs = np.vstack([lay.sensors.directions, lay.impacts.directions, np.full(3, np.nan)])
    with h5py.File(buf, "w") as h:
        grp = h.create_group("geometry")
        grp.attrs["length_unit"] = "m"
        grp.create_dataset(
            "channel", data=np.array(labels, dtype=object), dtype=h5py.string_dtype()
        )
        grp.create_dataset("role", data=np.array(roles, dtype=object), dtype=h5py.string_dtype())
        grp.create_dataset("position", data=pos)
        grp.create_dataset("direction", data=dirs)
    g5 = load_geometry(buf.getvalue(), filename="geometry.h5")
    l5 = g5.layout(lay.sensors.labels, lay.impacts.labels)
    np.testing.assert_allclose(l5.sensors.positions, lay.sensors.positions, atol=1e-12)
    np.testing.assert_allclose(l5.impacts.directions, lay.impacts.directions, atol=1e-12)
    np.testing.assert_allclose(l5.origin, lay.origin)


HEAD = "channel,role,x,y,z,dx,dy,dz,unit\n"


@pytest.mark.parametrize(
    ("rows", "error", "match"),
    [
        ("sa:x,sensor,0.1,0,0,,,,m\n", GeometryError, r"channel 'sa:x' has no direction"),
        (
            "sa:x,sensor,0.1,0,0,1,0,0,m\nsa:y,sensor,100,0,0,0,1,0,mm\n",
            GeometryError,
            r"channel 'sa:y' is in 'mm', the rows before it in 'm'",
        ),
        ("sa:x,sensor,0.1,0,0,1,0,0,inch\n", GeometryError, r"'sa:x': unknown length unit 'inch'"),
        ("sa:x,sensor,,0,0,1,0,0,m\n", GeometryError, r"channel 'sa:x', column x is empty"),
        (
            "sa:x,sensor,0.1,0,0,2,0,0,m\n",
            GeometryError,
            r"'sa:x': direction cosines .* not a unit",
        ),
        ("sa:x,hammer,0.1,0,0,1,0,0,m\n", DataFormatError, r"'sa:x': role 'hammer'"),
        ("sa:x,sensor,0.1,0,0,1,0,0,m\nsa:x,sensor,0.1,0,0,1,0,0,m\n", DOFError, "listed twice"),
    ],
)
def test_bad_tables_are_refused_naming_the_channel(rows, error, match) -> None:
    with pytest.raises(error, match=match):
        load_geometry((HEAD + rows).encode(), filename="g.csv")


def test_missing_coordinates_rotations_and_a_flat_layout_are_refused() -> None:
    text = HEAD + "spindle,point,0,0.75,0.08,,,,m\nk1,point,0.1,0.7,0.1,,,,m\n"
    g = load_geometry(text.encode(), filename="g.csv")
    with pytest.raises(GeometryError, match=r"sensor channel 'k2:x': node 'k2' has no coordinates"):
        g.layout(["k1:x", "k2:x"], ["k1:y"])
    with pytest.raises(GeometryError, match=r"sensor channel 'k1:rx' has no direction: a rotation"):
        g.layout(["k1:rx"], ["k1:y"])
    with pytest.raises(GeometryError, match=r"virtual point 'hub' is not a point"):
        g.layout(["k1:x"], ["k1:y"], origin="hub")
    # one tri-axial point and the spindle's own axes: all on one line -> six DOFs unseen
    lay = g.layout(
        ["k1:x", "k1:y", "k1:z", "spindle:x", "spindle:y", "spindle:z"],
        ["k1:x", "k1:y", "k1:z", "spindle:x", "spindle:y", "spindle:z"],
    )
    Y = fc.FRF([1.0], np.ones((1, 6, 6)), lay.sensors.labels, lay.impacts.labels, "mobility")
    with pytest.raises(GeometryError, match=r"do not observe .* one line"):
        virtual_point(Y, lay)


def test_files_without_geometry_are_refused(tmp_path) -> None:
    Y = fc.FRF([1.0, 2.0], np.ones((2, 1, 1)), ["1:z"], ["1:z"], "mobility")
    with pytest.raises(DataFormatError, match="holds no node coordinates"):
        load_geometry(fc.save_frf(Y, format="uff"), filename="frf.unv")
    with pytest.raises(DataFormatError, match="needs the columns"):
        load_geometry(b"a,b\n1,2\n", filename="g.csv")
    with pytest.raises(DataFormatError, match="/geometry/channel"):
        load_geometry(fc.save_frf(Y, format="hdf5"), filename="frf.h5")


def test_measured_chassis_from_two_files_couples_like_the_exact_one() -> None:
    from fbs_core.io import load_measured_chassis

    f = fc.harmonic(4).frequencies()
    m = val.knuckle_measurement(f, quantity="accelerance")
    raw = fc.save_frf(m.measured, format="hdf5")
    geo = geometry_csv(m.layout, "mm")
    mc = load_measured_chassis(
        raw, geo, frf_filename="knuckle.h5", geometry_filename="geometry.csv"
    )
    assert "lowest channel" in mc.summary and "geometry.csv" in mc.summary
    v = fc.bushing_response(4, chassis=mc.chassis)
    v_ex = fc.bushing_response(4, chassis=fc.FRFChassis(m.exact.to("mobility")))
    assert (np.abs(v.data - v_ex.data).max(0) / np.abs(v_ex.data).max(0)).max() < 0.01
    # a geometry that misses one impact: refused by name
    rows = [r for r in geo.decode().splitlines() if not r.startswith("tb:z")]
    with pytest.raises(GeometryError, match="impact channel 'tb:z': node 'tb' has no coord"):
        load_measured_chassis(
            raw,
            "\n".join(rows).encode(),
            frf_filename="knuckle.h5",
            geometry_filename="geometry.csv",
        )
    with pytest.raises(DOFError, match="no outputs at the bushing node 'hub'"):
        load_measured_chassis(
            raw, geo, frf_filename="knuckle.h5", geometry_filename="geometry.csv", bushing="hub"
        )


def test_one_universal_file_with_geometry_and_frfs(tmp_path) -> None:
    # the test lab's usual file: nodes (dataset 15, mm, dataset 164) and FRFs (58) together;
    # channels along the vehicle's axes (the UFF 58 direction codes)
    lay0 = val.knuckle_layout()
    S = lay0.origin
    pts = {n: S + np.asarray(o) for n, o in val.ARMS.items()}
    s_lab = [f"s{n}:{d}" for n in "abc" for d in "xyz"]
    i_lab = [f"m{n}:{d}" for n in "abc" for d in "xyz"] + ["ta:x", "tb:y", "tc:z"]

    def where(lab: str) -> np.ndarray:
        node, d = lab.split(":")
        p = pts[node[1]] if node[0] in "st" else S + 0.5 * np.asarray(val.ARMS[node[1]])
        return p

    def axis(lab: str) -> np.ndarray:
        return np.eye(3)["xyz".index(lab.split(":")[1])]

    lay = fc.vpt.Layout(
        fc.vpt.Channels(s_lab, [where(s) for s in s_lab], [axis(s) for s in s_lab]),
        fc.vpt.Channels(i_lab, [where(s) for s in i_lab], [axis(s) for s in i_lab], "impact"),
        S,
    )
    m = val.knuckle_measurement(F, quantity="accelerance", layout=lay)
    names = ["sa", "sb", "sc", "ma", "mb", "mc", "ta", "tb", "tc", "spindle", "bushing"]
    number = {n: 101 + k for k, n in enumerate(names)}
    xyz = {n: where(f"{n}:x") for n in names[:9]} | {"spindle": S}
    nodes15 = pyuff.prepare_15(
        node_nums=[number[n] for n in xyz],
        def_cs=[0] * len(xyz),
        disp_cs=[0] * len(xyz),
        color=[1] * len(xyz),
        x=[1000 * xyz[n][0] for n in xyz],
        y=[1000 * xyz[n][1] for n in xyz],
        z=[1000 * xyz[n][2] for n in xyz],
    )
    u164 = pyuff.prepare_164(
        units_code=5,
        units_description="mm",
        temp_mode=1,
        length=1000.0,
        force=1.0,
        temp=1.0,
        temp_offset=273.15,
    )
    head = tmp_path / "head.unv"
    u = pyuff.UFF(str(head))
    u.write_sets(u164, "add")
    u.write_sets(nodes15, "add")
    by_number = {v: k for k, v in number.items()}
    frf_raw = fc.save_frf(m.measured, format="uff", nodes=by_number)
    path = tmp_path / "knuckle.unv"
    path.write_bytes(head.read_bytes() + frf_raw)

    frf, _ = fc.load_frf(path, nodes=by_number)
    geo = load_geometry(path, nodes=by_number)
    sensors = [o for o in frf.outputs if not o.startswith("bushing")]
    r = virtual_point(frf, geo.layout(sensors, frf.inputs))
    direct = virtual_point(m.measured, lay).frf
    err = np.abs(r.frf.data - direct.data).max(0) / np.abs(direct.data).max(0)
    assert err.max() < 1e-4  # the file's single-precision numbers
