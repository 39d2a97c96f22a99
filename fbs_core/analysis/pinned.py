"""Pinned states: a result plus its provenance, serialised to JSON or CSV (never pickled).

A review compares the current state with up to four pinned ones. A
:class:`PinnedState` holds the result (FRFs and/or named arrays with axes), the
settings that produced it (harmonic, N, coupling, noise, seed, ...) and the
digests of its data sources (tire model, chassis, uploaded files), so that a
pinned curve can be traced and reproduced after the settings have changed.
JSON is the lossless round trip (complex values as real and imaginary parts, full
float precision); CSV goes through :func:`fbs_core.io.export_result` with the
provenance as metadata.
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import DataFormatError, FBSError
from ..frf import FRF

__all__ = ["PinnedState", "pin_state", "add_pin", "remove_pin", "digest", "MAX_PINS"]

#: Pinned states shown at once by the dashboard.
MAX_PINS = 4

FORMAT = "tire-fbs/pinned-state"
FORMAT_VERSION = 1
_MAX_JSON_CHARS = 200_000_000


def _h(*parts: Any) -> str:
    m = hashlib.sha256()
    for p in parts:
        if isinstance(p, np.ndarray):
            a = np.ascontiguousarray(p)
            m.update(f"{a.dtype.str}{a.shape}".encode())
            m.update(a.tobytes())
        elif isinstance(p, bytes):
            m.update(p)
        else:
            m.update(json.dumps(p, sort_keys=True, default=str).encode())
        m.update(b"\x00")
    return "sha256:" + m.hexdigest()


def digest(obj: Any) -> str:
    """Content digest ``"sha256:<hex>"`` of a data source.

    Parameters
    ----------
    obj : bytes, ndarray, FRF, TireModel or ChassisModel
        An uploaded file's bytes, an array, an FRF (grid, data, labels, quantity),
        a modal tire model (its modal data) or a chassis model (its parameters).

    Returns
    -------
    str

    Raises
    ------
    FBSError
        For other types.
    """
    if isinstance(obj, bytes | bytearray):
        return _h(bytes(obj))
    if isinstance(obj, np.ndarray):
        return _h(obj)
    if isinstance(obj, FRF):
        return _h("FRF", obj.freq, obj.data, list(obj.outputs), list(obj.inputs), obj.quantity)
    names = ("speeds", "poles", "psi", "chi", "wavelengths", "participation")
    if all(hasattr(obj, n) for n in names):
        return _h("TireModel", *(np.asarray(getattr(obj, n)) for n in names))
    if hasattr(obj, "to_dict") and hasattr(obj, "mobility"):
        return _h("ChassisModel", obj.to_dict())
    raise FBSError(
        f"cannot digest a {type(obj).__name__}: give bytes, an array, an FRF, a tire or a "
        "chassis model"
    )


def _jsonable(v: Any, where: str) -> Any:
    if isinstance(v, np.generic):
        v = v.item()
    if v is None or isinstance(v, bool | int | str):
        return v
    if isinstance(v, float):
        if not np.isfinite(v):
            return repr(v)
        return v
    if isinstance(v, list | tuple):
        return [_jsonable(x, where) for x in v]
    if isinstance(v, np.ndarray) and v.ndim <= 1 and v.dtype.kind in "biufU":
        return [_jsonable(x, where) for x in v.tolist()]
    if isinstance(v, Mapping):
        return {str(k): _jsonable(x, where) for k, x in v.items()}
    raise FBSError(f"{where} must be JSON-compatible (numbers, text, lists, dicts), got {v!r}")


def _floats(a: np.ndarray) -> list[Any]:
    """Floats for JSON; NaN and infinities (not JSON numbers) as the text "nan", "inf"."""
    x = a.astype(float).ravel()
    out = x.tolist()
    for i in np.flatnonzero(~np.isfinite(x)):
        out[i] = repr(float(x[i]))
    return out


def _unfloats(v: Any) -> np.ndarray:
    return np.asarray([float(x) for x in v], float)


def _array_json(a: np.ndarray) -> dict[str, Any]:
    a = np.asarray(a)
    out: dict[str, Any] = {"shape": list(a.shape)}
    if a.dtype.kind == "c":
        out["re"] = _floats(a.real)
        out["im"] = _floats(a.imag)
    elif a.dtype.kind in "biuf":
        out["values"] = _floats(a)
    elif a.dtype.kind == "U":
        out["text"] = a.ravel().tolist()
    else:
        raise FBSError(f"cannot store an array of dtype {a.dtype}")
    return out


def _array_from(d: Any, where: str) -> np.ndarray:
    try:
        shape = tuple(int(n) for n in d["shape"])
        if "re" in d:
            a = _unfloats(d["re"]) + 1j * _unfloats(d["im"])
        elif "values" in d:
            a = _unfloats(d["values"])
        else:
            a = np.asarray([str(x) for x in d["text"]], dtype=str)
        return a.reshape(shape)
    except (KeyError, TypeError, ValueError) as err:
        raise DataFormatError(f"pinned state: {where} is not a valid array ({err})") from None


@dataclass(frozen=True, eq=False)
class PinnedState:
    """A result with its provenance.

    Attributes
    ----------
    name : str
        Label shown in the legend, unique among the pins.
    frfs : dict of str to FRF
        FRF results (e.g. ``{"response": bushing FRF}``).
    arrays : dict of str to (tuple of str, ndarray)
        Other results as arrays with axis names.
    coords : dict of str to list
        Coordinates of the axes of ``arrays``.
    settings : dict
        JSON-compatible settings that produced the result.
    sources : dict of str to str
        Digest of every data source (see :func:`digest`).
    created : str
        UTC time of pinning, ISO 8601.
    """

    name: str
    frfs: dict[str, FRF] = field(default_factory=dict)
    arrays: dict[str, tuple[tuple[str, ...], np.ndarray]] = field(default_factory=dict)
    coords: dict[str, Any] = field(default_factory=dict)
    settings: dict[str, Any] = field(default_factory=dict)
    sources: dict[str, str] = field(default_factory=dict)
    created: str = ""

    def provenance(self) -> dict[str, Any]:
        """Name, settings, sources and creation time as one flat JSON-compatible dict."""
        out: dict[str, Any] = {"pin": self.name, "pinned": self.created}
        out.update({f"setting.{k}": v for k, v in self.settings.items()})
        out.update({f"source.{k}": v for k, v in self.sources.items()})
        return out

    def to_json(self) -> str:
        """Lossless JSON text (format ``tire-fbs/pinned-state`` version 1)."""
        from .. import __version__

        doc = {
            "format": FORMAT,
            "version": FORMAT_VERSION,
            "fbs_core_version": __version__,
            "name": self.name,
            "created": self.created,
            "settings": self.settings,
            "sources": self.sources,
            "frfs": {
                k: {
                    "freq": f.freq.tolist(),
                    "outputs": list(f.outputs),
                    "inputs": list(f.inputs),
                    "quantity": f.quantity,
                    "data": _array_json(f.data),
                }
                for k, f in self.frfs.items()
            },
            "arrays": {
                k: {"dims": list(dims), **_array_json(v)} for k, (dims, v) in self.arrays.items()
            },
            "coords": {k: _jsonable(v, f"coordinate {k!r}") for k, v in self.coords.items()},
        }
        return json.dumps(doc, allow_nan=False)

    @classmethod
    def from_json(cls, text: str | bytes | bytearray) -> PinnedState:
        """Read a pinned state written by :meth:`to_json` (plain JSON, nothing executed).

        Parameters
        ----------
        text : str or bytes

        Raises
        ------
        DataFormatError
            Not JSON, another format or version, or malformed content.
        """
        if isinstance(text, bytes | bytearray):
            try:
                text = bytes(text).decode("utf-8")
            except UnicodeDecodeError:
                raise DataFormatError("pinned state: not UTF-8 text") from None
        if not isinstance(text, str) or len(text) > _MAX_JSON_CHARS:
            raise DataFormatError("pinned state: expected JSON text of at most 200 MB")
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as err:
            raise DataFormatError(f"pinned state: not valid JSON ({err})") from None
        if not isinstance(doc, dict) or doc.get("format") != FORMAT:
            raise DataFormatError(f"pinned state: not a {FORMAT!r} document")
        if doc.get("version") != FORMAT_VERSION:
            raise DataFormatError(
                f"pinned state: version {doc.get('version')!r} is not supported "
                f"(this fbs_core reads version {FORMAT_VERSION})"
            )
        try:
            frfs = {
                str(k): FRF(
                    d["freq"],
                    _array_from(d["data"], f"FRF {k!r}"),
                    d["outputs"],
                    d["inputs"],
                    d["quantity"],
                )
                for k, d in doc.get("frfs", {}).items()
            }
            arrays = {
                str(k): (tuple(str(x) for x in d["dims"]), _array_from(d, f"array {k!r}"))
                for k, d in doc.get("arrays", {}).items()
            }
            name = doc["name"]
            if not isinstance(name, str):
                raise TypeError("name must be text")
            return cls(
                name,
                frfs,
                arrays,
                dict(doc.get("coords", {})),
                dict(doc.get("settings", {})),
                {str(k): str(v) for k, v in doc.get("sources", {}).items()},
                str(doc.get("created", "")),
            )
        except DataFormatError:
            raise
        except (KeyError, TypeError, AttributeError, ValueError) as err:
            raise DataFormatError(f"pinned state: malformed content ({err})") from None

    def export_mapping(self) -> dict[str, Any]:
        """The result as a mapping for :func:`fbs_core.io.export_result`."""
        out: dict[str, Any] = dict(self.frfs)
        out.update({k: (dims, v) for k, (dims, v) in self.arrays.items()})
        if self.coords:
            out["coords"] = {k: np.asarray(v) for k, v in self.coords.items()}
        return out

    def to_csv(self) -> bytes:
        """CSV text of the result with the provenance as ``# key: value`` metadata lines."""
        from ..io import export_result

        out = export_result(self.export_mapping(), format="csv", metadata=self.provenance())
        return bytes(out)


def pin_state(
    name: str,
    result: Any,
    settings: Mapping[str, Any] | None = None,
    sources: Mapping[str, str] | None = None,
) -> PinnedState:
    """Pin a result with its provenance.

    Parameters
    ----------
    name : str
        Non-empty label.
    result : FRF, mapping or object with ``export_mapping()``
        An FRF (stored as ``"result"``), a mapping of names to FRFs and
        ``(dims, array)`` pairs (with an optional ``"coords"`` entry), or an
        analysis dataset (``Campbell``, ``SpeedMap``, ``LevelDifference``, ...).
    settings : mapping, optional
        JSON-compatible settings (harmonic, N, coupling, noise, seed, ...).
    sources : mapping of str to str, optional
        Digests of the data sources (:func:`digest`).

    Returns
    -------
    PinnedState

    Raises
    ------
    FBSError
        Empty name, non-JSON settings or a result that cannot be stored.
    """
    if not isinstance(name, str) or not name.strip():
        raise FBSError(f"a pinned state needs a non-empty name, got {name!r}")
    mapping: dict[str, Any]
    if isinstance(result, FRF):
        mapping = {"result": result}
    elif hasattr(result, "export_mapping"):
        mapping = dict(result.export_mapping())
    elif isinstance(result, Mapping):
        mapping = dict(result)
    else:
        raise FBSError(
            f"cannot pin a {type(result).__name__}: give an FRF, a mapping or an analysis dataset"
        )
    coords = mapping.pop("coords", {}) or {}
    meta = mapping.pop("metadata", {}) or {}
    frfs: dict[str, FRF] = {}
    arrays: dict[str, tuple[tuple[str, ...], np.ndarray]] = {}
    for k, v in mapping.items():
        if isinstance(v, FRF):
            frfs[str(k)] = v
        elif isinstance(v, tuple) and len(v) == 2 and hasattr(v[1], "shape"):
            arrays[str(k)] = (tuple(str(d) for d in v[0]), np.array(v[1]))
        else:
            raise FBSError(f"result entry {k!r} is neither an FRF nor a (dims, array) pair")
    sett = _jsonable({**dict(meta), **dict(settings or {})}, "settings")
    return PinnedState(
        name.strip(),
        frfs,
        arrays,
        {str(k): _jsonable(v, f"coordinate {k!r}") for k, v in coords.items()},
        sett,
        {str(k): str(v) for k, v in dict(sources or {}).items()},
        time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    )


def add_pin(
    pins: Iterable[PinnedState], state: PinnedState, limit: int = MAX_PINS
) -> tuple[PinnedState, ...]:
    """A new tuple of pins with ``state`` appended.

    Parameters
    ----------
    pins : sequence of PinnedState
    state : PinnedState
    limit : int
        Most pins allowed (default 4).

    Raises
    ------
    FBSError
        When the name is taken or ``limit`` pins exist (naming them).
    """
    have = tuple(pins)
    names = [p.name for p in have]
    if state.name in names:
        raise FBSError(f"a pinned state is already named {state.name!r}; pick another name")
    if len(have) >= limit:
        raise FBSError(
            f"at most {limit} pinned states; unpin one of {', '.join(map(repr, names))} first"
        )
    return have + (state,)


def remove_pin(pins: Iterable[PinnedState], name: str) -> tuple[PinnedState, ...]:
    """A new tuple of pins without the one named ``name``.

    Parameters
    ----------
    pins : sequence of PinnedState
    name : str

    Raises
    ------
    FBSError
        If no pin has that name.
    """
    have = tuple(pins)
    if name not in [p.name for p in have]:
        raise FBSError(
            f"no pinned state named {name!r}; pinned: {', '.join(p.name for p in have) or 'none'}"
        )
    return tuple(p for p in have if p.name != name)
