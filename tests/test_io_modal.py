"""Modal tire models from MATLAB files in the documented variable layout."""

from __future__ import annotations

import io

import numpy as np
import pytest
import scipy.io

from fbs_core.errors import DataFormatError
from fbs_core.io import import_tire_model
from fbs_core.io.modal import write_tire_mat
from fbs_core.tire.model import TireModel


def small_tire(seed=0) -> TireModel:
    """Five damped mode pairs at two speeds; shapes random but fixed."""
    rng = np.random.default_rng(seed)
    n_s, n_p = 2, 5
    wn = 2 * np.pi * np.array([17.0, 38.0, 55.0, 80.0, 120.0])
    poles = np.empty((n_s, 2 * n_p), complex)
    for s in range(n_s):
        lam = -0.04 * wn * (1 + 0.1 * s) + 1j * wn * (1 + 0.02 * s)
        poles[s, 0::2], poles[s, 1::2] = lam, lam.conj()
    psi = rng.normal(size=(n_s, 2 * n_p, 6)) + 1j * rng.normal(size=(n_s, 2 * n_p, 6))
    psi[:, 1::2] = psi[:, 0::2].conj()
    chi = psi.copy()
    part = rng.normal(size=(n_s, 1, 2 * n_p)) + 0j
    return TireModel(
        np.array([20.0, 120.0]), poles, psi, chi, np.array([0.646]), part, meta={"supplier": "test"}
    )


def mat5(**v) -> bytes:
    b = io.BytesIO()
    scipy.io.savemat(b, v)
    return b.getvalue()


@pytest.mark.parametrize("version", ["5", "7.3"])
def test_tire_model_round_trip_gives_the_same_mobility(version):
    tire = small_tire()
    r = import_tire_model(write_tire_mat(tire, version=version), filename="tire.mat")
    model, summary = r
    f = np.linspace(5.0, 150.0, 60)
    for v in (20.0, 70.0):
        a, b = tire.hub_mobility(f, v), model.hub_mobility(f, v)
        assert b.allclose(a, rtol=1e-12)
    assert "operating points: 20, 120 km/h" in summary
    assert "10 complex modes" in summary and model.meta["supplier"] == "test"
    assert r.frf is None and r.model is model


def _vars(tire=None, **changes):
    t = tire or small_tire()
    v = dict(
        speeds=t.speeds,
        poles=t.poles,
        psi=t.psi,
        chi=t.chi,
        wavelengths=t.wavelengths,
        participation=t.participation,
    )
    v.update(changes)
    return {k: val for k, val in v.items() if val is not None}


def test_tire_model_layout_errors():
    t = small_tire()
    with pytest.raises(DataFormatError, match="lacks the variable 'chi'"):
        import_tire_model(mat5(**_vars(chi=None)), filename="t.mat")
    with pytest.raises(DataFormatError, match="'psi' has size 2x10x5"):
        import_tire_model(mat5(**_vars(psi=t.psi[:, :, :5])), filename="t.mat")
    with pytest.raises(DataFormatError, match="n_speeds = 3"):
        import_tire_model(mat5(**_vars(speeds=np.array([20.0, 60.0, 120.0]))), filename="t.mat")
    bad = np.array(t.poles)
    bad[0, 0] = np.inf
    with pytest.raises(DataFormatError, match="non-finite"):
        import_tire_model(mat5(**_vars(poles=bad)), filename="t.mat")
    bad = np.array(t.poles)
    bad[0, 1] = bad[0, 0]
    with pytest.raises(DataFormatError, match="conjugate pairs"):
        import_tire_model(mat5(**_vars(poles=bad)), filename="t.mat")
    with pytest.raises(DataFormatError, match="'hub_dofs' must be 6"):
        import_tire_model(mat5(**_vars(), hub_dofs=np.array(["hub:x"])), filename="t.mat")
    with pytest.raises(DataFormatError, match="tire models are read from MATLAB"):
        import_tire_model(b"freq,Re(a:x / a:x)\n1,2,3\n", filename="t.csv")


def test_project_format_is_read_through_the_owners_reader(tmp_path):
    from fbs_core.tire import storage

    tire = small_tire()
    p = storage.save_tire_model(tire, tmp_path / "t.h5")
    model, summary = import_tire_model(p.read_bytes(), filename="upload.h5")
    f = np.linspace(5.0, 150.0, 40)
    assert model.hub_mobility(f, 50.0).allclose(tire.hub_mobility(f, 50.0), rtol=1e-12)
    assert "tire-fbs tire model" in summary


def test_shipped_reference_tire_reads_unchanged():
    from fbs_core.tire import storage

    before = storage.DATA_FILE.read_bytes()
    model = import_tire_model(storage.DATA_FILE).model
    np.testing.assert_array_equal(model.poles, storage.reference_tire().poles)
    assert storage.DATA_FILE.read_bytes() == before


def test_project_format_refusals():
    import h5py

    from fbs_core.io import save_frf
    from fbs_core.tire import storage

    with pytest.raises(DataFormatError, match="is not a 'tire-fbs/modal-tire' file"):
        import_tire_model(save_frf(_frf_for_refusal(), format="hdf5"), filename="t.h5")
    b = io.BytesIO()
    with h5py.File(b, "w") as h:
        h.attrs["format"] = storage.FORMAT
        h.attrs["format_version"] = 99
        h["speeds"] = np.array([20.0, np.nan])
    with pytest.raises(DataFormatError, match="non-finite"):
        import_tire_model(b.getvalue(), filename="t.h5")


def _frf_for_refusal():
    from fbs_core import FRF

    return FRF([1.0, 2.0], np.ones((2, 1, 1)), ["hub:z"], ["hub:z"], "mobility")


# -- crafted tire files (issue 20.8): never opened in this process, only domain errors ----
def _crafted(tmp_path, edit):
    import h5py

    from fbs_core.tire import storage

    p = storage.save_tire_model(small_tire(), tmp_path / "t.h5")
    with h5py.File(p, "r+") as h:
        edit(h)
    return p.read_bytes()


def _deep_json(depth=100_000):
    return "[" * depth + "]" * depth


@pytest.mark.parametrize(
    "edit,match",
    [
        # metadata that made h5py / json raise RecursionError, TypeError, AttributeError
        (lambda h: h.attrs.__setitem__("meta", _deep_json()), "not valid JSON"),
        (lambda h: h.attrs.__setitem__("meta", "[1, 2]"), "must be a JSON object"),
        (lambda h: h.attrs.__setitem__("format_version", np.array([1, 2])), "format_version"),
        (lambda h: h.attrs.__setitem__("format_version", "one"), "format_version"),
        (
            lambda h: (h.__delitem__("hub_dofs"), h.create_dataset("hub_dofs", data=np.arange(6))),
            "hub_dofs",
        ),
        (
            lambda h: (
                h["parameters"].attrs.__setitem__("orders", "abc")
                if "parameters" in h
                else h.create_group("parameters").attrs.__setitem__("x", "abc")
            ),
            "parameters",
        ),
        (
            lambda h: (h.__delitem__("poles"), h.create_dataset("poles", data=np.ones((2, 3)))),
            "tire model",
        ),
    ],
)
def test_crafted_tire_files_end_in_domain_errors(tmp_path, edit, match):
    raw = _crafted(tmp_path, edit)
    with pytest.raises(DataFormatError, match=match):
        import_tire_model(raw, filename="crafted.h5")


def test_the_uploaded_tire_file_is_never_opened_in_this_process(tmp_path, monkeypatch):
    import h5py

    from fbs_core.tire import storage

    raw = storage.save_tire_model(small_tire(), tmp_path / "t.h5").read_bytes()

    def refuse(*a, **k):
        raise AssertionError("h5py.File opened in the server process")

    monkeypatch.setattr(h5py, "File", refuse)
    model = import_tire_model(raw, filename="upload.h5").model
    np.testing.assert_array_equal(model.poles, small_tire().poles)
