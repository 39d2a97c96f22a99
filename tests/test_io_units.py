"""Units from import to export (issue 12): every unit path against an independent conversion.

The truth of every factor is written here from the definition of the unit (1 lbf =
4.4482216152605 N, 1 in = 0.0254 m, 1 g = 9.80665 m/s^2, 1 deg = pi/180 rad), never
taken from the tables of :mod:`fbs_core.units`.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.errors import QuantityError
from fbs_core.io import load_frf, save_frf
from fbs_core.units import frf_unit, parse_units

LBF = 4.4482216152605  # N, by definition (avoirdupois pound x standard gravity)
INCH = 0.0254  # m, by definition
G0 = 9.80665  # m/s^2, by definition
DEG = math.pi / 180

F = np.array([10.0, 20.0, 30.0])


def _one(quantity="mobility", out="a:z", inp="b:z"):
    return fc.FRF(F, np.ones((3, 1, 1)), [out], [inp], quantity)


def _csv_with_units(frf, label):
    text = save_frf(frf, format="csv").decode()
    line = next(ln for ln in text.splitlines() if ln.startswith("# units:"))
    return text.replace(line, f"# units: {label}").encode()


def test_the_issue_example_gives_one_thousandth():
    Y = fc.FRF([10.0, 20.0, 30.0], np.ones((3, 1, 1)), ["a:z"], ["b:z"], "mobility")
    text = save_frf(Y, format="csv").decode().replace("# units: m/(N s)", "# units: m/s/kN")
    assert load_frf(text.encode(), filename="x.csv").frf.data[0, 0, 0] == pytest.approx(0.001)


# label, quantity, SI value of 1 file unit of a translation-per-force entry
TRANSLATION_PER_FORCE = [
    ("m/(N s)", "mobility", 1.0),
    ("(mm/s)/kN", "mobility", 1e-3 / 1e3),
    ("in/lbf", "receptance", INCH / LBF),
    ("in/s/lbf", "mobility", INCH / LBF),
    ("mm/mN", "receptance", 1e-3 / 1e-3),
    ("um/N", "receptance", 1e-6),
    ("m/s^2/kN", "accelerance", 1e-3),
    ("g/N", "accelerance", G0),
    ("g/lbf", "accelerance", G0 / LBF),
    ("g/kN", "accelerance", G0 / 1e3),
    ("m/(N ms)", "mobility", 1 / 1e-3),
    ("ft/s/lbf", "mobility", 0.3048 / LBF),
    ("m/s²/N", "accelerance", 1.0),
    ("(1/N)*(m/s²)", "accelerance", 1.0),
    ("(1/kN)·(mm/s²)", "accelerance", 1e-3 / 1e3),
    ("m s^-2 N^-1", "accelerance", 1.0),
    ("[mm/s]/[N]", "mobility", 1e-3),
    ("s^2/kg", "receptance", 1.0),  # m/N = s^2/kg
]


@pytest.mark.parametrize("label,quantity,si", TRANSLATION_PER_FORCE)
def test_translation_per_force_labels_in_csv(label, quantity, si):
    r = load_frf(_csv_with_units(_one(quantity), label), filename="u.csv")
    assert r.frf.quantity == quantity
    np.testing.assert_allclose(r.frf.data, si * np.ones((3, 1, 1)), rtol=1e-13)
    if si != 1.0:
        assert any(n.startswith("converted from") for n in r.notes)


@pytest.mark.parametrize(
    "label,out,inp,si",
    [
        # rotation over moment, the label of that very entry
        ("rad/(N m)", "a:rx", "b:ry", 1.0),
        ("deg/(N m)", "a:rx", "b:ry", DEG),
        ("deg/(s lbf in)", "a:rz", "b:rz", DEG / (LBF * INCH)),
        ("mrad/(kN mm)", "a:rz", "b:rz", 1e-3 / (1e3 * 1e-3)),
        # rotation over force, translation over moment
        ("deg/N", "a:rx", "b:z", DEG),
        ("mm/(N mm)", "a:x", "b:ry", 1.0),
        # road input (patch): metres of road amplitude
        ("(mm/s)/m", "a:z", "patch", 1e-3),
        ("(m/s)/mm", "a:z", "patch", 1e3),
        ("(deg/s)/mm", "a:ry", "patch", DEG / 1e-3),
    ],
)
def test_labels_of_rotations_moments_and_road_inputs(label, out, inp, si):
    q = parse_units(label).quantity
    r = load_frf(_csv_with_units(_one(q, out, inp), label), filename="u.csv")
    np.testing.assert_allclose(r.frf.data[0, 0, 0], si, rtol=1e-13)


def test_a_translation_label_converts_every_entry_by_its_kind():
    """The file's one label 'in/(s lbf)' sets the unit system: a rotation per moment is
    then rad/(s lbf in), a translation per moment in/(s lbf in), a rotation per force
    rad/(s lbf)."""
    outs, ins = ["a:x", "a:rx"], ["b:x", "b:rx"]
    Y = fc.FRF(F, np.ones((3, 2, 2)), outs, ins, "mobility")
    r = load_frf(_csv_with_units(Y, "in/(s lbf)"), filename="u.csv")
    truth = np.array([[INCH / LBF, INCH / (LBF * INCH)], [1 / LBF, 1 / (LBF * INCH)]])
    np.testing.assert_allclose(r.frf.data[0], truth, rtol=1e-13)
    # g: a translation in g, a rotation stays rad/s^2
    Y = fc.FRF(F, np.ones((3, 2, 1)), ["a:z", "a:ry"], ["b:z"], "accelerance")
    r = load_frf(_csv_with_units(Y, "g/kN"), filename="u.csv")
    np.testing.assert_allclose(r.frf.data[0, :, 0], [G0 / 1e3, 1 / 1e3], rtol=1e-13)


def test_units_in_mat_and_hdf5_attributes_are_converted():
    Y = _one("mobility")
    for fmt in ("mat", "hdf5"):
        raw = save_frf(Y, format=fmt)
        # rewrite the units attribute / variable the way another program would store it
        if fmt == "hdf5":
            import io

            import h5py

            b = io.BytesIO(raw)
            with h5py.File(b, "r+") as f:
                f["frf"].attrs["units"] = "in/s/lbf"
            raw = b.getvalue()
        else:
            import io

            import scipy.io

            v = scipy.io.loadmat(io.BytesIO(raw))
            v = {k: x for k, x in v.items() if not k.startswith("__")}
            v["units"] = "in/s/lbf"
            out = io.BytesIO()
            scipy.io.savemat(out, v)
            raw = out.getvalue()
        r = load_frf(raw, filename=f"u.{'h5' if fmt == 'hdf5' else 'mat'}")
        np.testing.assert_allclose(r.frf.data, INCH / LBF, rtol=1e-13)


def test_a_label_that_is_present_but_not_understood_is_quoted():
    raw = _csv_with_units(_one(), "furlong/fortnight").decode()
    raw = raw.replace("# quantity: mobility\n", "")
    with pytest.raises(QuantityError, match="'furlong/fortnight' is not understood"):
        load_frf(raw.encode(), filename="u.csv")
    # with the quantity given the data load, unconverted, with a note quoting it
    r = load_frf(raw.encode(), filename="u.csv", quantity="mobility")
    assert any("'furlong/fortnight' not understood" in n for n in r.notes)


def test_inverse_units_are_refused():
    for label in ("N/m", "N s/m", "kg", "N/(m/s^2)"):
        with pytest.raises(QuantityError, match="force per motion"):
            parse_units(label)


# -- the FRF knows what every entry is -----------------------------------------------------
def test_frf_units_follow_output_and_input_kinds():
    Y = fc.FRF(F, np.ones((3, 2, 3)), ["a:z", "a:ry"], ["b:x", "b:rz", "patch"], "mobility")
    assert Y.output_kinds == ("translation", "rotation")
    assert Y.input_kinds == ("force", "moment", "road")
    assert Y.units.tolist() == [
        ["m/(N s)", "m/(N m s)", "(m/s)/m"],
        ["rad/(N s)", "rad/(N m s)", "(rad/s)/m"],
    ]
    assert Y.to("receptance").unit("a:ry", "b:rz") == "rad/(N m)"
    assert Y.to("accelerance").unit("a:z", "patch") == "(m/s^2)/m"
    # a generalised DOF of the user's is declared with kinds=
    Z = fc.FRF(F, np.ones((3, 1, 1)), ["a:z"], ["road_left"], "mobility")
    assert Z.unit() == "m/s"
    Z = Z.replace(kinds={"road_left": "road"})
    assert Z.unit() == "(m/s)/m" and Z.isel(freq=[0]).unit() == "(m/s)/m"


def test_every_unit_string_reads_back_as_its_own_kind_and_quantity():
    for o in ("translation", "rotation"):
        for i in ("force", "moment", "road"):
            for q in ("receptance", "mobility", "accelerance"):
                u = parse_units(frf_unit(o, i, q))
                assert (u.kinds, u.quantity, u.is_si) == ((o, i), q, True)


def test_bushing_response_exports_carry_road_units():
    """The bushing response per metre of road: every exporter writes (m/s)/m, and the
    file reads back as a mobility without any conversion."""
    from fbs_core.io import export_result

    Y = fc.FRF(F, np.ones((3, 2, 1)) * 1e-3, ["bushing:z", "bushing:ry"], ["patch"])
    assert "# units: (m/s)/m" in save_frf(Y, format="csv").decode()
    assert "# units: (m/s)/m" in export_result(Y, format="csv").decode()
    for fmt in ("csv", "mat", "hdf5"):
        r = load_frf(save_frf(Y, format=fmt), filename=f"b.{'h5' if fmt == 'hdf5' else fmt}")
        assert r.frf.allclose(Y) and not any("converted" in n for n in r.notes)


# -- UFF: records 8-10 and dataset 164 ------------------------------------------------------
def _pyuff_read(raw: bytes, tmp_path):
    import pyuff

    p = tmp_path / "r.uff"
    p.write_bytes(raw)
    return [s for s in pyuff.UFF(str(p)).read_sets() if s["type"] == 58]


def test_uff_records_8_to_10_carry_each_entry_s_units(tmp_path):
    """Exported bushing responses read back by pyuff: velocity (or angular velocity)
    over a road displacement in m; hub mobilities over N or N m."""
    Y = fc.FRF(F, np.ones((3, 2, 1)) * 1e-3, ["bushing:z", "bushing:ry"], ["patch"])
    sets = _pyuff_read(save_frf(Y, format="uff"), tmp_path)
    got = [
        (
            s["ordinate_spec_data_type"],
            s["ordinate_axis_units_lab"].strip(),
            s["orddenom_spec_data_type"],
            s["orddenom_axis_units_lab"].strip(),
        )
        for s in sets
    ]
    assert got == [(11, "m/s", 8, "m"), (11, "rad/s", 8, "m")]
    H = fc.FRF(F, np.ones((3, 2, 2)), ["hub:x", "hub:rx"], ["hub:x", "hub:rx"], "accelerance")
    sets = _pyuff_read(save_frf(H, format="uff"), tmp_path)
    got = [
        (s["ordinate_axis_units_lab"].strip(), s["orddenom_axis_units_lab"].strip()) for s in sets
    ]
    assert got == [("m/s^2", "N"), ("m/s^2", "N m"), ("rad/s^2", "N"), ("rad/s^2", "N m")]
    # and they come back as the same FRF, unconverted
    for Z in (Y, H):
        r = load_frf(save_frf(Z, format="uff"), filename="z.uff")
        assert r.frf.allclose(Z, rtol=1e-12) and not any("converted" in n for n in r.notes)


def _uff_with_164(tmp_path, length_factor, force_factor, num_label="NONE", den_label="NONE"):
    import pyuff

    p = tmp_path / "u164.uff"
    u = pyuff.UFF(str(p))
    u.write_sets(
        pyuff.prepare_164(
            units_code=9,
            units_description="test",
            temp_mode=2,
            length=length_factor,
            force=force_factor,
            temp=1.0,
            temp_offset=273.15,
        ),
        mode="add",
    )
    for k, (rd, fd) in enumerate([(3, 3), (3, 6), (6, 3), (6, 6)]):
        u.write_sets(
            pyuff.prepare_58(
                func_type=4,
                rsp_node=1,
                rsp_dir=rd,
                ref_node=2,
                ref_dir=fd,
                data=np.ones(3, complex),
                x=F,
                abscissa_spacing=1,
                abscissa_spec_data_type=18,
                ordinate_spec_data_type=12,
                ordinate_axis_units_lab=num_label,
                orddenom_spec_data_type=13,
                orddenom_axis_units_lab=den_label,
                id1=f"rec {k}",
            ),
            mode="add",
        )
    return p


@pytest.mark.parametrize(
    "lf,ff,trans,rot",
    [
        # dataset 164 factors turn SI into file units: 1000 for mm, 1000 for mN
        (1000.0, 1000.0, 1e-3 / 1e-3, 1 / (1e-3 * 1e-3)),  # mm, mN: z/z x1, rz/rz per N mm
        (1000.0, 1.0, 1e-3, 1 / 1e-3),  # mm, N
        (1 / INCH, 1 / LBF, INCH / LBF, 1 / (LBF * INCH)),  # in, lbf
    ],
)
def test_uff_dataset_164_unit_systems(tmp_path, lf, ff, trans, rot):
    r = load_frf(_uff_with_164(tmp_path, lf, ff), quantity="accelerance")
    np.testing.assert_allclose(r.frf.data[0].diagonal(), [trans, rot], rtol=1e-6)


def test_uff_labels_with_superscripts_and_latin1(tmp_path):
    # record 9 holds the whole FRF unit written with a superscript two, Latin-1 encoded
    p = _uff_with_164(tmp_path, 1.0, 1.0, num_label="(1/kN)*(mm/s2)")
    raw = p.read_bytes().replace(b"(1/kN)*(mm/s2)", "(1/kN)*(mm/s²)".encode("latin-1") + b" ")
    r = load_frf(raw, filename="latin1.uff")
    assert r.frf.quantity == "accelerance"
    # z/z: mm/(s² kN); rz/rz in the same unit system: rad/(s² kN mm) = 1 rad/(s² N m)
    np.testing.assert_allclose(r.frf.data[0].diagonal(), [1e-3 / 1e3, 1 / (1e3 * 1e-3)], rtol=1e-12)


def test_the_dashboard_upload_summary_shows_the_units_it_understood():
    """A chassis FRF in mm/(s kN): the summary says how the label was read and the SI
    units of the entries, and the chassis in use is the SI one (x 1e-6)."""
    from app.datasource import DataSource

    grid = np.arange(13.0, 422.01, 0.5)
    Y = fc.reference_chassis().mobility(grid)
    # a CSV as another program would write it: every entry in mm and kN
    fac = np.array(
        [
            [
                (1e3 if o.split(":")[1] in "xyz" else 1.0)
                * 1e3
                * (1e-3 if i.split(":")[1] in ("rx", "ry", "rz") else 1.0)
                for i in Y.inputs
            ]
            for o in Y.outputs
        ]
    )
    # value in mm/(s kN) = SI value x (mm per m) x (N per kN); moments: kN mm = N m
    mm_kn = Y.replace(data=Y.data * fac[None])
    raw = _csv_with_units(mm_kn, "mm/(s kN)")
    ds = DataSource()
    assert ds.load_chassis(raw, "chassis_mm_kN.csv"), ds.error
    s = ds.chassis_summary
    assert "units 'mm/(s kN)' read as mobility, mm, kN, s, rad" in s
    assert "units (SI): m/(N s) | m/(N m s) | rad/(N s) | rad/(N m s)" in s
    f = fc.harmonic(3).frequencies()
    np.testing.assert_allclose(
        ds.models.chassis.mobility(f).data, fc.reference_chassis().mobility(f).data, rtol=1e-12
    )


# -- CSV: every column carries its entry's own unit --------------------------------------
def _mixed():
    """Bushing translation and rotation per metre of road: two different units."""
    return fc.FRF(F, np.ones((3, 2, 1)), ["bushing:z", "bushing:rx"], ["patch"])


def test_csv_columns_name_each_entry_s_unit():
    """One unit line cannot describe (m/s)/m and (rad/s)/m at once: each column says its own."""
    header = next(
        ln for ln in save_frf(_mixed(), format="csv").decode().splitlines() if ln.startswith("freq")
    )
    assert "Re(bushing:z / patch) [(m/s)/m]" in header
    assert "Im(bushing:rx / patch) [(rad/s)/m]" in header


def test_csv_column_units_convert_when_there_is_no_unit_line():
    """mm/s and mrad/s per metre of road: both entries x1e-3 (independent: 1 mm = 1e-3 m,
    1 mrad = 1e-3 rad)."""
    text = save_frf(_mixed(), format="csv").decode()
    text = text.replace("# units: (m/s)/m\n", "")
    text = text.replace("[(m/s)/m]", "[(mm/s)/m]").replace("[(rad/s)/m]", "[(mrad/s)/m]")
    r = load_frf(text.encode(), filename="m.csv")
    np.testing.assert_allclose(r.frf.data, 1e-3 * np.ones((3, 2, 1)), rtol=1e-15)
    assert r.frf.quantity == "mobility"


def test_csv_column_unit_of_the_wrong_kind_is_refused():
    """A rotation column labelled in metres contradicts itself: an error names the pair."""
    text = save_frf(_mixed(), format="csv").decode().replace("[(rad/s)/m]", "[(m/s)/m]")
    with pytest.raises(fc.DataFormatError, match=r"bushing:rx / patch.*rotation"):
        load_frf(text.encode(), filename="k.csv")


def test_csv_column_unit_not_understood_is_quoted():
    text = save_frf(_mixed(), format="csv").decode().replace("[(rad/s)/m]", "[furlong]")
    with pytest.raises(fc.DataFormatError, match="'furlong'"):
        load_frf(text.encode(), filename="q.csv")


def test_csv_unit_line_governs_and_a_differing_column_scale_is_noted():
    """The issue's edit (unit line changed by hand to kN): the line governs, x1e-3, and the
    notes say the columns stated another scale."""
    text = save_frf(_one(), format="csv").decode().replace("# units: m/(N s)", "# units: m/s/kN")
    r = load_frf(text.encode(), filename="e.csv")
    assert r.frf.data[0, 0, 0] == pytest.approx(1e-3, rel=1e-15)
    assert any("governs" in n for n in r.notes)
