"""HDF5 files that point elsewhere are refused before anything is read from them.

An external link, a virtual dataset with a source in another file, a dataset with external
raw storage, and a soft link that dangles or loops: each crafted with h5py, each refused by
:mod:`fbs_core.hdf5_guard` with a message naming the object's path, in every reader (campaign
result files, tire model files, chassis and vehicle files; uploads go through the sandboxed
parser, which refuses links of every kind). The proof that a refused link would have been
followed: the linked file holds data the reader would otherwise have shown (a case of another
campaign, a tire model's poles).
"""

from __future__ import annotations

import shutil

import h5py
import numpy as np
import pytest

from fbs_core.errors import DataFormatError
from fbs_core.hdf5_guard import ForeignDataError, check_self_contained, open_h5


def _other_file(tmp_path):
    other = tmp_path / "elsewhere" / "other.h5"
    other.parent.mkdir(exist_ok=True)
    with h5py.File(other, "w") as h:
        h["d"] = np.arange(4.0)
        h.create_group("g").attrs["kind"] = "secret"
    return other


def _external(h, other):
    h["g"].create_group("sub")["ext"] = h5py.ExternalLink(str(other), "/g")
    return "/g/sub/ext", "external link"


def _external_self(h, other):
    h["g"]["ext"] = h5py.ExternalLink(h.filename, "/x")  # the file itself, by its name
    return "/g/ext", "external link"


def _soft_to_external(h, other):
    h["g"]["a"] = h5py.SoftLink("/g/z")  # visited first, resolved only after every link
    h["g"]["z"] = h5py.ExternalLink(str(other), "/d")
    return "/g/z", "external link"


def _virtual(h, other):
    lay = h5py.VirtualLayout(shape=(4,), dtype=float)
    lay[:] = h5py.VirtualSource(str(other), "d", shape=(4,))
    h["g"].create_virtual_dataset("v", lay)
    return "/g/v", "virtual dataset"


def _raw_external(h, other):
    h["g"].create_dataset("r", shape=(2,), dtype="<f8", external=[(str(other), 0, 16)])
    return "/g/r", "external storage"


def _dangling(h, other):
    h["g"]["s"] = h5py.SoftLink("/nowhere")
    return "/g/s", "dangles or loops"


def _loop(h, other):
    h["g"]["s"] = h5py.SoftLink("/g/s")
    return "/g/s", "dangles or loops"


WAYS_OUT = {
    "external link": _external,
    "external link to itself": _external_self,
    "soft link to an external link": _soft_to_external,
    "virtual dataset from another file": _virtual,
    "external raw storage": _raw_external,
    "dangling soft link": _dangling,
    "looping soft link": _loop,
}


def _base(path):
    with h5py.File(path, "w") as h:
        h["x"] = np.arange(3.0)
        g = h.create_group("g")
        g["alias"] = h5py.SoftLink("/x")  # a soft link inside the file: kept
        g["hard"] = h["g"]  # a hard-link cycle: visited once
        lay = h5py.VirtualLayout(shape=(3,), dtype=float)
        lay[:] = h5py.VirtualSource(".", "/x", shape=(3,))
        g.create_virtual_dataset("vself", lay)  # sources in the same file: kept


@pytest.mark.parametrize("way", list(WAYS_OUT))
def test_every_way_out_of_the_file_is_refused_naming_the_object(tmp_path, way):
    other = _other_file(tmp_path)
    path = tmp_path / "f.h5"
    _base(path)
    with h5py.File(path, "r") as h:  # the control: the file without the way out passes
        check_self_contained(h)
    with open_h5(path) as h:
        assert h["g"]["alias"][()].tolist() == [0.0, 1.0, 2.0]
    with h5py.File(path, "a") as h:
        where, what = WAYS_OUT[way](h, other)
    with pytest.raises(ForeignDataError, match=what) as err:
        with open_h5(path, name="f.h5"):
            pass
    assert f"f.h5: object {where!r}" in str(err.value) or f"dataset {where!r}" in str(err.value)
    assert str(tmp_path) not in str(err.value)  # named as asked, no server path


def test_a_refusal_is_raised_as_the_callers_error(tmp_path):
    other = _other_file(tmp_path)
    path = tmp_path / "f.h5"
    _base(path)
    with h5py.File(path, "a") as h:
        _external(h, other)

    class MyError(Exception):
        pass

    with pytest.raises(MyError, match="external link"):
        with open_h5(path, error=MyError):
            pass


# -- tire model files --------------------------------------------------------------------------
def test_a_tire_model_file_with_an_external_link_is_refused(tmp_path):
    from fbs_core.tire import reference_tire
    from fbs_core.tire.storage import read_tire_h5, save_tire_model

    path = tmp_path / "tire.h5"
    save_tire_model(reference_tire(), path)
    elsewhere = tmp_path / "elsewhere.h5"
    shutil.copy(path, elsewhere)
    with h5py.File(path, "a") as h:  # the poles now come from the other file
        del h["poles"]
        h["poles"] = h5py.ExternalLink(str(elsewhere), "/poles")
    with h5py.File(path, "r") as h:  # the control: h5py follows the link
        assert h["poles"].shape[0] > 0
    with pytest.raises(DataFormatError, match="'/poles' is an external link"):
        read_tire_h5(path)


def test_chassis_and_vehicle_files_with_an_external_link_are_refused(tmp_path):
    from fbs_core.chassis import read_chassis_frf
    from fbs_core.vehicle.storage import DATA_FILE, read_vehicle_frf

    CHASSIS_FILE = DATA_FILE.with_name("reference_chassis.h5")

    for src, read in ((CHASSIS_FILE, read_chassis_frf), (DATA_FILE, read_vehicle_frf)):
        path = tmp_path / "m.h5"
        shutil.copy(src, path)
        elsewhere = tmp_path / "e.h5"
        shutil.copy(src, elsewhere)
        with h5py.File(path, "a") as h:
            del h["frf"]["data"]
            h["frf"]["data"] = h5py.ExternalLink(str(elsewhere), "/frf/data")
        with pytest.raises(DataFormatError, match="'/frf/data' is an external link"):
            read(path)


# -- campaign result files ---------------------------------------------------------------------
TOML = """
[campaign]
name = "guarded"
seed = 5
output = "{out}"
[scatter]
harmonics = [1]
noise = [0.05]
targets = ["both"]
frequency_dependent = [false]
rounds = 30
percentiles = [5.0, 95.0]
[execution]
task_round_lines = 600
"""


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    from fbs_core.campaign import parse_campaign, run_campaign

    d = tmp_path_factory.mktemp("good")
    camp = parse_campaign(TOML.format(out=(d / "good.h5").as_posix()), d)
    assert run_campaign(camp).status == "complete"
    return d / "good.h5"


def _case(path):
    with h5py.File(path, "r") as h:
        return next(iter(h["cases"]))


def test_a_campaign_file_linking_a_case_of_another_file_is_refused(good, tmp_path):
    from fbs_core.campaign import CampaignError, open_campaign

    other = tmp_path / "other_user" / "secret.h5"
    other.parent.mkdir()
    shutil.copy(good, other)
    path = tmp_path / "mine.h5"
    shutil.copy(good, path)
    name = _case(good)
    with h5py.File(path, "a") as h:
        h["cases"]["theirs"] = h5py.ExternalLink(str(other), f"/cases/{name}")
    with h5py.File(path, "r") as h:  # the control: h5py follows it to the other file's case
        assert h["cases"]["theirs"].attrs["kind"] == "scatter"
    with pytest.raises(CampaignError, match="'/cases/theirs' is an external link"):
        open_campaign(path)
    assert {c.name for c in open_campaign(good).cases} == {name}


def test_a_campaign_block_mapped_from_another_file_is_refused(good, tmp_path):
    from fbs_core.campaign import CampaignError, open_campaign

    other = tmp_path / "other.h5"
    shutil.copy(good, other)
    path = tmp_path / "mine.h5"
    shutil.copy(good, path)
    name = _case(good)
    with h5py.File(path, "a") as h:
        blocks = h["cases"][name]["blocks"]
        b = sorted(blocks)[0]
        shape, dtype = blocks[b]["lower"].shape, blocks[b]["lower"].dtype
        del blocks[b]["lower"]
        lay = h5py.VirtualLayout(shape=shape, dtype=dtype)
        lay[...] = h5py.VirtualSource(str(other), f"/cases/{name}/blocks/{b}/upper", shape=shape)
        blocks[b].create_virtual_dataset("lower", lay)
    with pytest.raises(CampaignError, match=f"'/cases/{name}/blocks/{b}/lower' is a virtual"):
        open_campaign(path).band(name)
    open_campaign(good).band(name)  # the control


def test_the_campaign_card_names_files_relative_to_the_campaign_folder(good, tmp_path):
    from app.views.campaign import CampaignBrowser

    path = tmp_path / "sub.h5"
    shutil.copy(good, path)
    with h5py.File(path, "a") as h:
        h["cases"]["x"] = h5py.ExternalLink("/etc/passwd", "/")
    parts = tmp_path / "broken.h5.parts"  # a run's part that is not HDF5
    parts.mkdir()
    (parts / "0001.h5").write_bytes(b"not hdf5" * 100)
    shutil.copy(good, tmp_path / "broken.h5")
    b = CampaignBrowser(directory=tmp_path)
    b.__panel__()
    for file, says in (
        ("sub.h5", "sub.h5: object '/cases/x' is an external link"),
        ("broken.h5", "broken.h5.parts/0001.h5"),
    ):
        b.file = file
        assert says in b.message, b.message
        assert str(tmp_path) not in b.message, b.message
