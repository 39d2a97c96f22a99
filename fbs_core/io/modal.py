"""Modal tire models from files: the project's own format and MATLAB.

MATLAB variable layout (``docs/file-formats.md``; the arrays of
:class:`fbs_core.tire.model.TireModel`, MATLAB index order):

``speeds``
    Operating points in km/h, ``n_s`` increasing values.
``poles``
    ``n_s x n_m`` complex poles ``lambda_r`` in rad/s, conjugate pairs
    ``[r, conj(r), ...]`` lowest first, the same mode in every row (tracked).
``psi``, ``chi``
    ``n_s x n_m x 6`` right and left mode shapes at the hub DOFs (``a_r = 1``).
``wavelengths``
    Road wavelengths in m of the stored patch participations, ``n_h`` values.
``participation``
    ``n_s x n_h x n_m`` complex ``chi_r^T f_patch``.
``hub_dofs`` (optional)
    Six labels of the hub DOFs in vehicle axes, default ``hub:x`` ... ``hub:rz``.
``metadata`` (optional)
    JSON text with provenance.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

import numpy as np

from ..dofs import node_labels
from ..errors import DataFormatError, FBSError
from ._sandbox import DEFAULT_TIMEOUT, parse_isolated
from .checks import Source, check_finite, normalize_label
from .matlab import MatVars, read_mat_vars, write_mat_vars

if TYPE_CHECKING:
    from ..tire.model import TireModel

__all__ = ["tire_from_vars", "read_tire_mat", "write_tire_mat", "TIRE_VARIABLES"]

TIRE_VARIABLES = ("speeds", "poles", "psi", "chi", "wavelengths", "participation")


def _num(v: MatVars, key: str, name: str) -> np.ndarray:
    if key not in v:
        raise DataFormatError(
            f"tire model {name!r} lacks the variable {key!r}; needed: "
            f"{', '.join(TIRE_VARIABLES)} (found: {', '.join(v) or 'none'})"
        )
    a = v[key]
    if isinstance(a, list):
        raise DataFormatError(f"tire model {name!r}: {key!r} must be numeric, got text")
    return check_finite(np.asarray(a), f"tire model {name!r} variable {key!r}")


def _shaped(a: np.ndarray, shape: tuple[int, ...], key: str, name: str, meaning: str) -> np.ndarray:
    def strip(shp: tuple[int, ...]) -> tuple[int, ...]:
        s = list(shp)
        while len(s) > 1 and s[-1] == 1:
            s.pop()
        return tuple(s)

    if strip(a.shape) != strip(shape):
        raise DataFormatError(
            f"tire model {name!r}: {key!r} has size {'x'.join(map(str, a.shape))}, "
            f"expected {meaning} = {'x'.join(map(str, shape))}"
        )
    return a.reshape(shape)


def tire_from_vars(v: MatVars, name: str) -> TireModel:
    """Build a :class:`~fbs_core.tire.model.TireModel` from MAT-file variables."""
    from ..tire.model import TireModel

    speeds = _num(v, "speeds", name).ravel().astype(float)
    poles = _num(v, "poles", name)
    n_s = speeds.size
    if poles.ndim != 2 or poles.shape[0] != n_s:
        raise DataFormatError(
            f"tire model {name!r}: 'poles' has size {'x'.join(map(str, poles.shape))}, "
            f"expected n_speeds x n_modes with n_speeds = {n_s} (from 'speeds')"
        )
    n_m = poles.shape[1]
    lam = _num(v, "wavelengths", name).ravel().astype(float)
    psi = _shaped(_num(v, "psi", name), (n_s, n_m, 6), "psi", name, "n_speeds x n_modes x 6")
    chi = _shaped(_num(v, "chi", name), (n_s, n_m, 6), "chi", name, "n_speeds x n_modes x 6")
    part = _shaped(
        _num(v, "participation", name),
        (n_s, lam.size, n_m),
        "participation",
        name,
        "n_speeds x n_wavelengths x n_modes",
    )
    hub = node_labels("hub")
    if "hub_dofs" in v:
        labels = v["hub_dofs"]
        if not isinstance(labels, list) or len(labels) != 6:
            raise DataFormatError(f"tire model {name!r}: 'hub_dofs' must be 6 DOF labels")
        hub = tuple(normalize_label(s, "hub")[0] for s in labels)
    meta = {"source": name}
    if isinstance(v.get("metadata"), list):
        try:
            meta.update(json.loads(" ".join(v["metadata"])))
        except ValueError:
            meta["metadata"] = " ".join(v["metadata"])
    try:
        return TireModel(speeds, poles, psi, chi, lam, part, meta=meta, hub_dofs=hub)
    except FBSError as e:
        raise type(e)(f"tire model {name!r}: {e}") from None
    except (ValueError, TypeError) as e:
        raise DataFormatError(f"tire model {name!r}: {e}") from None


def read_tire_mat(
    src: Source, kind: str | None = None, *, timeout: float = DEFAULT_TIMEOUT
) -> TireModel:
    """Read a tire model from a MAT-file (v5 or v7.3, ``kind`` as in
    :func:`~.matlab.read_mat_vars`) in the documented layout."""
    return tire_from_vars(read_mat_vars(src, kind, timeout=timeout), src.name)


def write_tire_mat(model: TireModel, *, version: str = "5") -> bytes:
    """A tire model as MAT-file content in the documented layout."""
    return write_mat_vars(
        {
            "speeds": np.asarray(model.speeds, float),
            "poles": np.asarray(model.poles),
            "psi": np.asarray(model.psi),
            "chi": np.asarray(model.chi),
            "wavelengths": np.asarray(model.wavelengths, float),
            "participation": np.asarray(model.participation),
            "hub_dofs": list(model.hub_dofs),
            "metadata": json.dumps(dict(model.meta), default=str),
        },
        version=version,
    )


def read_tire_native(src: Source, *, timeout: float = DEFAULT_TIMEOUT) -> TireModel:
    """Read a tire model in the project's format (``fbs_core.tire.storage``, HDF5).

    The file is parsed completely in the sandbox (every dataset and attribute, refusing
    links and external storage); the model is then built from that parsed content by
    :func:`fbs_core.tire.storage.tire_from_content`. The uploaded file is never opened
    in this process.

    Raises
    ------
    DataFormatError
        For damaged files, another format or version, non-finite values, and any
        inconsistency of the content (never a bare TypeError or the like).
    """
    from ..tire import storage

    what = f"tire model {src.name!r}"
    meta, arrays = parse_isolated("hdf5", src.raw, what, timeout=timeout)
    try:
        groups, datasets = meta["groups"], meta["datasets"]
        root = groups.get("/", {})
        fmt = root.get("format")
        if fmt != storage.FORMAT:
            raise DataFormatError(
                f"{what} is not a {storage.FORMAT!r} file (its format attribute is {fmt!r}); "
                "tire models are read from that format or from MATLAB (.mat)"
            )
        data: dict[str, Any] = {}
        for path, e in datasets.items():
            name = path.lstrip("/")
            if "/" in name:
                continue  # datasets inside groups are not part of version 1
            if "array" in e:
                data[name] = check_finite(arrays[e["array"]], f"{what} dataset {path}")
            elif "strings" in e:
                data[name] = list(e["strings"])
        params = groups.get("/parameters")
        return storage.tire_from_content(root, data, params, what)
    except FBSError as e:
        if what in str(e):
            raise
        raise type(e)(f"{what}: {e}") from None
    except (KeyError, ValueError, TypeError, AttributeError, IndexError, RecursionError) as e:
        raise DataFormatError(f"{what}: inconsistent content ({type(e).__name__}: {e})") from None
