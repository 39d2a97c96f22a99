"""HDF5 file format of a modal tire model (format ``tire-fbs/modal-tire``, version 2;
version 1 files, without the optional residual, still load).

The layout, described for suppliers in ``docs/tire-model.md``::

    /                      attrs: format, format_version, description, source
    /speeds                (n_s,)            float64  km/h
    /poles                 (n_s, n_m)        complex128 rad/s, pairs [r, conj(r), ...]
    /psi                   (n_s, n_m, 6)     complex128 right shapes at the hub
    /chi                   (n_s, n_m, 6)     complex128 left shapes at the hub
    /hub_dofs              (6,)              str  hub:x ... hub:rz (vehicle axes)
    /wavelengths           (n_h,)            float64  m
    /participation         (n_s, n_h, n_m)   complex128 chi_r^T f_patch
    /residual              (n_s, 36 + 6 n_h) complex128 optional (format 2): residual
                           flexibility of the modes not in the file
    /parameters            group, attrs: the physical parameters (optional)

Complex data use h5py's native compound type with fields ``r`` and ``i``.
Every dataset carries ``unit`` and ``description`` attributes. No pickles.
"""

from __future__ import annotations

import json
import os
import warnings
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from ..errors import DataFormatError
from ..hdf5_guard import open_h5
from .model import TireModel
from .params import TireParameters
from .ring import HUB_DOFS

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "READABLE_VERSIONS",
    "DATA_FILE",
    "save_tire_model",
    "read_tire_h5",
    "load_tire_model",
    "tire_from_content",
    "reference_tire",
]

FORMAT = "tire-fbs/modal-tire"
FORMAT_VERSION = 2
#: Versions this code reads: 1 (no residual), 2 (optional /residual).
READABLE_VERSIONS = (1, 2)

#: The shipped reference model.
DATA_FILE = Path(__file__).resolve().parents[2] / "data" / "reference_tire.h5"

_DATASETS = {
    "speeds": ("km/h", "operating points (vehicle speed)"),
    "poles": (
        "rad/s",
        "complex poles lambda_r in conjugate pairs [r, conj(r), ...], pairs "
        "ordered by eigenfrequency averaged over the speeds; mode r is the same "
        "tracked mode at every speed",
    ),
    "psi": (
        "m or rad per unit modal coordinate",
        "right mode shapes at the hub DOFs, normalised with the left ones so that "
        "a_r = chi_r^T (2 lambda_r M + C) psi_r = 1",
    ),
    "chi": (
        "m or rad per unit modal coordinate",
        "left mode shapes at the hub DOFs (a_r = 1); receptance "
        "H = sum_r psi_r chi_r^T / (j omega - lambda_r)",
    ),
    "wavelengths": ("m", "road wavelengths of the patch loads"),
    "participation": (
        "N/m (load per metre of road amplitude, per unit modal coordinate)",
        "modal participation chi_r^T f_patch of the distributed patch load "
        "exp(j 2 pi x / lambda) per speed and wavelength",
    ),
}


def save_tire_model(model: TireModel, path: str | os.PathLike[str], description: str = "") -> Path:
    """Write a :class:`TireModel` to HDF5 (format version 2).

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with h5py.File(path, "w", track_order=True) as f:
        f.attrs["format"] = FORMAT
        f.attrs["format_version"] = FORMAT_VERSION
        f.attrs["description"] = description
        f.attrs["meta"] = json.dumps(model.meta, sort_keys=True)
        for name, (unit, desc) in _DATASETS.items():
            ds = f.create_dataset(name, data=np.asarray(getattr(model, name)))
            ds.attrs["unit"] = unit
            ds.attrs["description"] = desc
        ds = f.create_dataset(
            "hub_dofs", data=np.array(model.hub_dofs, dtype=object), dtype=h5py.string_dtype()
        )
        ds.attrs["description"] = (
            "hub DOF labels, vehicle coordinates ISO 8855: x forward, "
            "y left, z up; rotations about these axes"
        )
        if model.residual is not None:
            ds = f.create_dataset("residual", data=np.asarray(model.residual))
            ds.attrs["unit"] = "m/N (receptance; rad, N m as for the hub DOFs), per m of road"
            ds.attrs["description"] = (
                "optional (format 2): upper residual flexibility of the modes not in the "
                "file, -sum R_r / lambda_r per speed; columns: hub receptance 6 x 6 row "
                "major, then the 6 hub responses to the patch load of every wavelength"
            )
        if model.params is not None:
            g = f.create_group("parameters")
            g.attrs["description"] = "physical parameters (SI units), fbs_core.tire.TireParameters"
            for k, v in model.params.to_dict().items():
                g.attrs[k] = np.asarray(v)
    return path


def read_tire_h5(path: str | os.PathLike[str]) -> TireModel:
    """Read a modal tire model written in format ``tire-fbs/modal-tire`` (this package's file).

    The file is opened in this process: for the shipped reference model and files written by
    :func:`save_tire_model`. Files from users or suppliers (MATLAB or this format) go
    through :func:`fbs_core.io.import_tire_model`, which parses them in a sandbox process.

    Raises
    ------
    DataFormatError
        If the file is missing, not this format, of an unknown version, or has
        inconsistent data.
    """
    path = Path(path)
    if not path.is_file():
        raise DataFormatError(f"no modal tire file at {path}")
    try:
        with open_h5(path) as f:  # refuses links and data leaving the file
            root = dict(f.attrs.items())
            data = {k: f[k][()] for k in f if isinstance(f[k], h5py.Dataset)}
            params = dict(f["parameters"].attrs.items()) if "parameters" in f else None
    except OSError as e:
        raise DataFormatError(f"cannot read {path} as HDF5: {e}") from e
    return tire_from_content(root, data, params, str(path))


def load_tire_model(path: str | os.PathLike[str]) -> TireModel:
    """Deprecated name of :func:`read_tire_h5` (a ``DeprecationWarning``; removed in the
    next release). Not to be confused with :func:`fbs_core.io.import_tire_model`."""
    warnings.warn(
        "fbs_core.tire.load_tire_model is deprecated; use fbs_core.tire.read_tire_h5 "
        "(this package's HDF5 file) or fbs_core.io.import_tire_model (user files)",
        DeprecationWarning,
        stacklevel=2,
    )
    return read_tire_h5(path)


def _text(v: Any) -> str:
    if isinstance(v, bytes):
        return v.decode("utf-8", "replace")
    if isinstance(v, np.ndarray) and v.shape == ():
        return _text(v.item())
    return str(v)


def tire_from_content(
    root: Mapping[str, Any],
    data: Mapping[str, Any],
    parameters: Mapping[str, Any] | None = None,
    where: str = "tire model",
) -> TireModel:
    """Build a :class:`TireModel` from already-read content of a ``tire-fbs/modal-tire`` file.

    No file is opened here: the importer (:func:`fbs_core.io.import_tire_model`) passes
    what the sandbox parsed, :func:`read_tire_h5` what h5py read.

    Parameters
    ----------
    root : mapping
        Attributes of the root group (``format``, ``format_version``, ``meta``).
    data : mapping
        Dataset name (without ``/``) -> array; ``hub_dofs`` an array or list of str.
        Datasets not needed are ignored (later versions may add optional ones).
    parameters : mapping, optional
        Attributes of the ``/parameters`` group.
    where : str
        How to name the file in messages.

    Raises
    ------
    DataFormatError
        For another format or version, missing or inconsistent data.
    """
    fmt = root.get("format")
    fmt = _text(fmt) if fmt is not None else None
    if fmt != FORMAT:
        raise DataFormatError(f"{where} is not a {FORMAT!r} file (format={fmt!r})")
    raw_ver = root.get("format_version", -1)
    try:
        ver = int(np.asarray(raw_ver).item())
        shown = str(ver)
    except (TypeError, ValueError):
        ver, shown = -1, repr(raw_ver)[:40]
    if ver not in READABLE_VERSIONS:
        raise DataFormatError(
            f"{where} has format_version {shown}; this code reads "
            f"{', '.join(map(str, READABLE_VERSIONS))}"
        )
    missing = [k for k in (*_DATASETS, "hub_dofs") if k not in data]
    if missing:
        raise DataFormatError(f"{where} lacks dataset(s) {missing}")
    arrays = {}
    for k in _DATASETS:
        a = np.asarray(data[k])
        if a.dtype.kind not in "biufc":
            raise DataFormatError(f"{where}: dataset {k!r} must be numeric, got {a.dtype}")
        arrays[k] = a
    hub_raw = data["hub_dofs"]
    if isinstance(hub_raw, np.ndarray):
        hub_raw = hub_raw.ravel().tolist()
    if not isinstance(hub_raw, list | tuple):
        raise DataFormatError(f"{where}: hub_dofs must be 6 DOF labels")
    hub = tuple(_text(x) for x in hub_raw)
    if hub != HUB_DOFS:
        raise DataFormatError(f"hub_dofs must be {list(HUB_DOFS)}, got {list(hub)[:6]}")
    params = None
    if parameters is not None:
        attrs = {k: v for k, v in parameters.items() if k != "description"}
        try:
            params = TireParameters.from_dict(
                {
                    k: (np.asarray(v).tolist() if k == "orders" else float(np.asarray(v)))
                    for k, v in attrs.items()
                }
            )
        except (TypeError, ValueError, KeyError) as e:
            raise DataFormatError(f"{where}: invalid /parameters: {e}") from None
    try:
        meta = json.loads(_text(root.get("meta", "{}")))
    except (ValueError, RecursionError):
        raise DataFormatError(f"{where}: the 'meta' attribute is not valid JSON") from None
    if not isinstance(meta, dict):
        raise DataFormatError(f"{where}: the 'meta' attribute must be a JSON object")
    residual = None
    if ver >= 2 and "residual" in data:
        residual = np.asarray(data["residual"])
        if residual.dtype.kind not in "biufc":
            raise DataFormatError(f"{where}: dataset 'residual' must be numeric")
    return TireModel(
        arrays["speeds"],
        arrays["poles"],
        arrays["psi"],
        arrays["chi"],
        arrays["wavelengths"],
        arrays["participation"],
        params=params,
        meta=meta,
        hub_dofs=hub,
        residual=residual,
    )


@lru_cache(maxsize=1)
def reference_tire() -> TireModel:
    """The shipped reference tire model (``data/reference_tire.h5``), loaded once.

    Examples
    --------
    >>> tire = reference_tire()
    >>> tire.n_modes
    400
    """
    return read_tire_h5(DATA_FILE)
