"""The page's exports (issue 29): CSV with a speed column, the unit of its Re/Im columns and
a date in its name; UFF dataset 58 of the views over frequency, read back with fbs_core.io
and pyuff: the case from the result's snapshot (coupling, residual compensation), whole
``key=value`` pairs in ID lines 3-4 (none spilling into line 5), the node map in line 5.

Truth: the speed by v = 3.6 f lambda of the harmonic; the values read back against the
published result and the core's own response (``fbs_core.bushing_response``).
"""

from __future__ import annotations

import datetime as dt
import re

import numpy as np
import pytest

import fbs_core
from app.export import dated, export_columns, read_csv, to_csv, to_uff
from app.store import Results
from app.views.live import download_button, downloads, export_meta, uff_button
from fbs_core.io import load_frf
from fbs_core.io.uff import pack_items


def _days_around(call):
    """Run ``call`` and return its result with the UTC days before and after it.

    A run that crosses midnight names either day; both are true.
    """
    before = dt.datetime.now(dt.UTC).strftime("%Y-%m-%d")
    out = call()
    after = dt.datetime.now(dt.UTC).strftime("%Y-%m-%d")
    return out, {before, after}


@pytest.fixture(scope="module")
def store():
    res = Results()
    res.state.case.param.update(harmonic=3, n_modes=40, dof="rx", coupling="5dof")
    res.state.noise.rounds = 30
    yield res
    res.close()


def test_the_csv_has_a_speed_column_and_states_the_unit_of_its_re_im_columns(store):
    r = store.response
    cols, meta = export_columns(r)
    text = to_csv(cols, export_meta(meta), "mobility")
    got, back = read_csv(text)
    names = list(back)
    assert names[:2] == ["freq_Hz", "speed_kmh"]
    lam = fbs_core.harmonic(3).wavelength
    np.testing.assert_allclose(back["speed_kmh"], 3.6 * back["freq_Hz"] * lam, rtol=1e-12)
    # rotation rx per metre of road: rad/s per m
    assert got["Re/Im columns"].endswith("real and imaginary parts, in (rad/s)/m")
    assert "reference_re, reference_im" in got["Re/Im columns"]
    h = back["truncated_re"] + 1j * back["truncated_im"]
    want = fbs_core.bushing_response(3, n_modes=40, coupling="5dof").sel(outputs="bushing:rx")
    np.testing.assert_allclose(h, want.data[:, 0, 0], rtol=1e-9)


def test_export_file_names_carry_the_date(store):
    assert dated("a_b_upload.csv", dt.datetime(2026, 12, 3, tzinfo=dt.UTC)) == (
        "a_b_upload_2026-12-03.csv"
    )
    btn = download_button("mobility", lambda: store.response)
    _, days = _days_around(btn.callback)
    stem = store.response.filename[: -len(".csv")]
    assert btn.filename in {f"{stem}_{day}.csv" for day in days}
    ub = uff_button("mobility", lambda: store.response)
    out, days = _days_around(ub.callback)
    assert any(ub.filename.endswith(f"_{day}.uff") for day in days)
    assert out.getvalue().startswith(b"    -1")


def test_the_views_over_frequency_have_a_uff_download_beside_the_csv(store):
    assert len(downloads("mobility", lambda: store.response)) == 2
    assert len(downloads("scatter", lambda: store.band_curves)) == 2
    assert len(downloads("truncation", lambda: store.error_map)) == 1  # a map: CSV only


def _whole_pairs(line: str) -> bool:
    return all(re.fullmatch(r"[^=;]+=[^;]*|\+\d+ more", p) for p in line.split("; "))


def test_the_uff_export_reads_back_with_the_case_of_its_snapshot_and_a_node_map(store, tmp_path):
    import pyuff

    r = store.response
    path = tmp_path / "r.uff"
    path.write_bytes(to_uff(r, {"exported": "2026-12-03 14:00 UTC"}))
    sets = pyuff.UFF(str(path)).read_sets()
    sets = sets if isinstance(sets, list) else [sets]
    assert len(sets) == 2
    for st in sets:
        assert st["id3"].startswith(
            "h=3; N=40; residual=no; coupling=5dof; dof=bushing:rx; models=reference"
        )
        assert _whole_pairs(st["id3"]) and _whole_pairs(st["id4"])
        assert st["id5"] == "nodes: 1=bushing 2=patch"
    # both are whole FRF records of the same pair (bushing:rx per road patch: node 1
    # direction 4 = rx, node 2 the patch), told apart by record 6's function id
    assert [s["func_type"] for s in sets] == [4, 4]
    assert [s["func_id"] for s in sets] == [1, 2]
    for st in sets:
        assert (st["rsp_node"], st["rsp_dir"], st["ref_node"]) == (1, 4, 2), st["id1"]
        assert st["ordinate_axis_units_lab"] == sets[0]["ordinate_axis_units_lab"] != "NONE"
        assert st["orddenom_axis_units_lab"] == sets[0]["orddenom_axis_units_lab"] != "NONE"
        assert st["abscissa_axis_units_lab"] == "Hz"
    frf_rec, ref_rec = sets
    assert frf_rec["id1"].startswith("truncated: ") and ref_rec["id1"].startswith("reference: ")
    # with the node map of line 5, fbs_core reads the FRF back under its labels
    nodes = dict(p.split("=")[::-1] for p in frf_rec["id5"][len("nodes: ") :].split())
    loaded = load_frf(path, nodes={int(v): k for k, v in nodes.items()})
    got = loaded.frf
    assert got is not None  # the file's first function: the N-mode response
    assert any("function ids 2 (reference)" in n for n in loaded.notes), loaded.notes
    assert got.outputs == ("bushing:rx",) and got.inputs == ("patch",)
    want = r.core["truncated"]
    np.testing.assert_allclose(got.freq, want.freq, rtol=1e-5)
    np.testing.assert_allclose(got.data[:, 0, 0], want.data[:, 0, 0], rtol=2e-5)
    np.testing.assert_allclose(ref_rec["data"], r.core["reference"].data[:, 0, 0], rtol=2e-5)


def test_the_uff_export_records_residual_compensation_from_the_snapshot(store, tmp_path):
    import pyuff

    store.state.case.residual = True
    try:
        r = store.response
        path = tmp_path / "res.uff"
        path.write_bytes(to_uff(r))  # nothing passed by the caller
        sets = pyuff.UFF(str(path)).read_sets()
        assert all("residual=yes" in s["id3"] for s in sets)
        want = fbs_core.bushing_response(3, n_modes=40, coupling="5dof", residual=True)
        rec = next(s for s in sets if s["func_type"] == 4)
        np.testing.assert_allclose(
            rec["data"], want.sel(outputs="bushing:rx").data[:, 0, 0], rtol=2e-5
        )
    finally:
        store.state.case.residual = False


def test_the_band_exports_its_levels_as_uff_functions(store, tmp_path):
    import pyuff

    r = store.band_curves
    path = tmp_path / "b.uff"
    path.write_bytes(to_uff(r))
    sets = pyuff.UFF(str(path)).read_sets()
    by_name = {s["id1"].split(" [")[0]: s for s in sets}
    for name in ("reference_dB", "minimum_dB", "maximum_dB"):
        np.testing.assert_allclose(by_name[name]["data"], r.columns[name], rtol=2e-5, atol=1e-4)
    assert all(s["id3"].startswith("h=3; N=40;") for s in sets)


def test_id_lines_never_split_a_pair_nor_spill_into_line_five():
    items = [f"key{k}={'v' * 15}" for k in range(9)]
    lines, left = pack_items(items, lines=2)
    assert len(lines) == 2 and all(len(ln) <= 80 for ln in lines)
    assert all(_whole_pairs(ln) for ln in lines)
    kept = [p for ln in lines for p in ln.split("; ") if "=" in p]
    assert kept == items[: len(kept)] and left == len(items) - len(kept) > 0
    assert lines[-1].endswith(f"+{left} more")
    assert pack_items(["x" * 81, "a=1"], lines=1) == (["a=1; +1 more"], 1)  # never cut


def test_a_uff_export_without_its_snapshot_or_a_curve_is_refused(store):
    import dataclasses

    with pytest.raises(ValueError, match="needs the snapshot"):
        to_uff(dataclasses.replace(store.response, snapshot=None))
    with pytest.raises(ValueError, match="no function of frequency"):
        to_uff(store.error_map)
