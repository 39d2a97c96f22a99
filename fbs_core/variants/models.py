"""Variants of the reference models: rebuilt from their parameters, cached by content.

A variant is a set of parameter values (:mod:`.parameters`) applied to the base tire and
chassis. Its tire is *rebuilt*: the complex modes of the physical tire at every operating
point, tracked across the speeds (:func:`fbs_core.tire.build_modal_model`, seconds to
minutes); its chassis is a :class:`~fbs_core.ChassisModel` of the changed parameters (its
complex modes, well under a second). The coupled response of a variant is the bushing
response of eq. 4.1 (:func:`fbs_core.bushing_response`) for each harmonic of the study.

Tires are cached by their *content*: the key is the SHA-256 of the tire's parameters, its
operating points and wavelengths (:func:`tire_key`), so the same parameters give the same
model whichever variant, study or process asks (a Saltelli design varies the chassis of a
row without changing its tire: one build serves them all). The cache holds a few models in
memory (each ~25 MB) and, with a directory, every model as an HDF5 file named by its key
(:func:`fbs_core.tire.save_tire_model`; written to a temporary name and renamed, atomic).
The build is deterministic: the same key gives the same numbers (on the same BLAS and
thread count; LAPACK's last bits depend on them).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import threading
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._typing import ComplexArray
from ..chassis import ChassisModel, ChassisParameters
from ..errors import FBSError
from ..harmonics import WAVELENGTHS
from ..tire.model import TireModel
from ..tire.params import DEFAULT_PARAMETERS, TireParameters
from .parameters import ParameterError, apply_values

__all__ = [
    "TIRE_CACHE",
    "TireCache",
    "VariantSettings",
    "needed_speeds",
    "tire_key",
    "variant_models",
    "variant_responses",
]

#: Bumped when the tire build changes its numbers for the same parameters (part of the key).
BUILD_VERSION = 2


def _reference_speeds() -> tuple[float, ...]:
    from ..tire.storage import reference_tire

    return tuple(float(v) for v in reference_tire().speeds)


@dataclass(frozen=True)
class VariantSettings:
    """What a variant's response is: harmonics, grid, truncation, coupling, base models.

    Parameters
    ----------
    harmonics : tuple of int
        Excitation cases 1..7 whose bushing response is computed.
    df : float
        Line spacing in Hz of each harmonic's grid (``harmonic.frequencies(df)``).
    n_modes : int, optional
        Retained tire modes (default all).
    coupling : {"6dof", "5dof"}
    speeds : tuple of float, optional
        Operating points (km/h) of the rebuilt tires; default (None) those of the shipped
        reference tire (20-120 km/h, 43 points), whose nominal variant is then the shipped
        model itself. A tire is rebuilt at those of them the harmonics' lines read
        (:meth:`tire_speeds`).
    tire : TireParameters
        The base tire (default the reference); a smaller configuration (fewer orders,
        speeds) makes a rebuild cheap, e.g. in tests.
    chassis : ChassisParameters
        The base chassis (default the reference).
    """

    harmonics: tuple[int, ...] = (4,)
    df: float = 0.5
    n_modes: int | None = None
    coupling: str = "6dof"
    speeds: tuple[float, ...] | None = None
    tire: TireParameters = DEFAULT_PARAMETERS
    chassis: ChassisParameters = field(default_factory=ChassisParameters)

    def __post_init__(self) -> None:
        from ..harmonics import harmonic
        from ..prediction import coupled_dofs

        hs = tuple(int(harmonic(h).k) for h in self.harmonics)
        if not hs or len(set(hs)) != len(hs):
            raise FBSError(f"harmonics must be distinct cases 1..7, got {list(self.harmonics)}")
        object.__setattr__(self, "harmonics", hs)
        coupled_dofs(self.coupling)
        if not (np.isfinite(self.df) and 0.0 < self.df <= 10.0):
            raise FBSError(f"df must be in (0, 10] Hz, got {self.df!r}")
        if self.speeds is not None:
            sp = tuple(float(v) for v in self.speeds)
            if len(sp) < 2 or np.any(np.diff(sp) <= 0) or sp[0] < 0:
                raise FBSError(f"speeds must be >= 2 increasing values in km/h, got {list(sp)}")
            object.__setattr__(self, "speeds", sp)

    def tire_speeds(self) -> tuple[float, ...]:
        """The operating points of the rebuilt tires (km/h): those the harmonics' lines use.

        Of ``speeds`` (default the shipped tire's), the points that the lines of the
        study's harmonics interpolate between (:func:`needed_speeds`), so that a rebuilt
        tire is solved only where its response is read, with the same numbers as a tire
        built at all the points.
        """
        from ..harmonics import harmonic

        sp = _reference_speeds() if self.speeds is None else self.speeds
        v = np.concatenate(
            [np.atleast_1d(harmonic(k).speed_at(self.freq(k))) for k in self.harmonics]
        )
        return needed_speeds(sp, float(v.min()), float(v.max()))

    def freq(self, k: int) -> np.ndarray:
        """The grid of harmonic ``k`` in Hz."""
        from ..harmonics import harmonic

        return harmonic(k).frequencies(self.df)

    def to_dict(self) -> dict[str, Any]:
        """Plain values (for storage and for the content key of a study)."""
        return {
            "harmonics": list(self.harmonics),
            "df": self.df,
            "n_modes": self.n_modes,
            "coupling": self.coupling,
            "speeds": list(self.tire_speeds()),
            "tire": self.tire.to_dict(),
            "chassis": dataclasses.asdict(self.chassis),
        }


def needed_speeds(speeds: Sequence[float], v_min: float, v_max: float) -> tuple[float, ...]:
    """The operating points a modal tire model reads between ``v_min`` and ``v_max`` km/h.

    Between the operating points the model interpolates every mode in speed, cubic on the
    four nearest points (linear in the first and last interval;
    :class:`~fbs_core.tire.TireModel`). The points kept are the stencils of the intervals
    holding ``v_min`` and ``v_max`` and all points between; cut there, the model's
    intervals of those speeds keep the stencil (cubic or linear) they had in the whole
    model, so its responses at speeds in ``[v_min, v_max]`` are the whole model's (to
    the order in which its modes are summed).

    Parameters
    ----------
    speeds : sequence of float
        Operating points in km/h, increasing (at least two).
    v_min, v_max : float
        The slowest and fastest speed read, within the points.

    Returns
    -------
    tuple of float

    Examples
    --------
    >>> needed_speeds([20, 22.5, 25, 27.5, 30, 32.5, 35], 30.0, 32.0)
    (27.5, 30.0, 32.5, 35.0)
    """
    sp = tuple(float(v) for v in speeds)
    n = len(sp)
    if n < 4:
        return sp
    k0, k1 = (
        min(max(int(np.searchsorted(sp, v, side="right")) - 1, 0), n - 2) for v in (v_min, v_max)
    )
    a = 0 if k0 == 0 else k0 - 1
    b = min(n - 1, k1 + 2)
    return sp[a : b + 1]


def tire_key(
    params: TireParameters,
    speeds: Sequence[float],
    wavelengths: Sequence[float] = WAVELENGTHS,
) -> str:
    """Content key of a rebuilt tire: SHA-256 of its parameters, speeds and wavelengths.

    Floats enter by their shortest exact representation (``repr``), so equal numbers give
    equal keys and any change gives another key.

    Parameters
    ----------
    params : TireParameters
    speeds : sequence of float
        Operating points in km/h.
    wavelengths : sequence of float
        Road wavelengths of the patch participation in m.

    Examples
    --------
    >>> from fbs_core.tire import DEFAULT_PARAMETERS
    >>> tire_key(DEFAULT_PARAMETERS, [20.0, 40.0]) == tire_key(DEFAULT_PARAMETERS, [20, 40])
    True
    """
    text = json.dumps(
        {
            "params": params.to_dict(),
            "speeds": [float(v) for v in speeds],
            "wavelengths": [float(w) for w in wavelengths],
            "build": BUILD_VERSION,
        },
        sort_keys=True,
    )
    return hashlib.sha256(text.encode()).hexdigest()


class TireCache:
    """Rebuilt tires by content key (:func:`tire_key`): a few in memory, all on disk.

    Parameters
    ----------
    maxsize : int
        Models kept in memory (least recently used dropped; each about 25 MB).
    directory : path, optional
        Folder of HDF5 files ``<key>.h5`` (this package's tire format); a model found there
        is read, not rebuilt, when its stored parameters and speeds are the requested ones.

    Attributes
    ----------
    builds : int
        Models built by this cache (a test and a campaign's record of the work done).
    """

    def __init__(self, maxsize: int = 2, directory: str | os.PathLike[str] | None = None) -> None:
        if int(maxsize) < 0:
            raise FBSError(f"maxsize must be >= 0, got {maxsize}")
        self.maxsize = int(maxsize)
        self.directory = None if directory is None else Path(directory)
        self.builds = 0
        self._mem: OrderedDict[str, TireModel] = OrderedDict()
        self._lock = threading.Lock()

    def __repr__(self) -> str:
        return f"TireCache({len(self._mem)} in memory, directory={self.directory})"

    def _keep(self, key: str, model: TireModel) -> None:
        with self._lock:
            self._mem[key] = model
            self._mem.move_to_end(key)
            while len(self._mem) > self.maxsize:
                self._mem.popitem(last=False)

    def _read(
        self, key: str, params: TireParameters, speeds: tuple[float, ...]
    ) -> TireModel | None:
        if self.directory is None:
            return None
        path = self.directory / f"{key}.h5"
        if not path.is_file():
            return None
        from ..tire.storage import read_tire_h5

        try:
            m = read_tire_h5(path)
        except FBSError:
            return None
        same = m.params == params and tuple(float(v) for v in m.speeds) == speeds
        return m if same else None  # a file of other content under this name: rebuilt

    def get(
        self,
        params: TireParameters,
        speeds: Sequence[float],
        wavelengths: Sequence[float] = WAVELENGTHS,
    ) -> TireModel:
        """The tire of ``params`` at ``speeds`` (km/h): from memory, disk, or built.

        Parameters
        ----------
        params : TireParameters
        speeds : sequence of float
            Operating points, increasing.
        wavelengths : sequence of float
            Road wavelengths of the patch participation (default: all seven harmonics).

        Returns
        -------
        TireModel
            ``meta["variant_key"]`` is its content key.
        """
        sp = tuple(float(v) for v in speeds)
        key = tire_key(params, sp, wavelengths)
        with self._lock:
            hit = self._mem.get(key)
            if hit is not None:
                self._mem.move_to_end(key)
                return hit
        model: TireModel | None = self._read(key, params, sp)
        if model is None:
            from ..tire.build import build_modal_model

            model = build_modal_model(params, speeds=sp, wavelengths=wavelengths)
            model.meta["variant_key"] = key
            with self._lock:
                self.builds += 1
            if self.directory is not None:
                from ..tire.storage import save_tire_model

                self.directory.mkdir(parents=True, exist_ok=True)
                tmp = self.directory / f"{key}.h5.{os.getpid()}.{threading.get_ident()}.tmp"
                save_tire_model(model, tmp, "tire variant (fbs_core.variants)")
                os.replace(tmp, self.directory / f"{key}.h5")
        self._keep(key, model)
        return model

    def clear(self) -> None:
        """Forget the models in memory (the files stay)."""
        with self._lock:
            self._mem.clear()


#: The process-wide cache of :func:`variant_models` (two models in memory, no files).
TIRE_CACHE = TireCache()


def variant_models(
    values: Mapping[str, float],
    settings: VariantSettings | None = None,
    cache: TireCache | None = None,
) -> tuple[TireModel, ChassisModel]:
    """The rebuilt tire and chassis of one variant.

    Parameters
    ----------
    values : mapping of str to float
        Parameter name -> value (:data:`~fbs_core.variants.PARAMETERS`); parameters not
        given keep the base's value.
    settings : VariantSettings, optional
        Base models and operating points (default: the reference models).
    cache : TireCache, optional
        Default :data:`TIRE_CACHE`.

    Returns
    -------
    (TireModel, ChassisModel)
        The shipped reference tire itself when the tire parameters are the reference's and
        ``settings.speeds`` is None.

    Raises
    ------
    ParameterError
        For unknown names or unphysical values.
    """
    s = VariantSettings() if settings is None else settings
    tp, cp = apply_values(values, s.tire, s.chassis)
    if s.speeds is None and tp == DEFAULT_PARAMETERS:
        from ..tire.storage import reference_tire

        tire = reference_tire()
    else:
        tire = (TIRE_CACHE if cache is None else cache).get(tp, s.tire_speeds())
    return tire, ChassisModel(cp)


def variant_responses(
    values: Mapping[str, float],
    settings: VariantSettings | None = None,
    cache: TireCache | None = None,
) -> dict[int, ComplexArray]:
    """The coupled bushing response of one variant for every harmonic (thesis eq. 4.1).

    Parameters
    ----------
    values, settings, cache
        As :func:`variant_models`.

    Returns
    -------
    dict of int to ndarray, shape (n_f, 6)
        Harmonic -> complex velocity at ``bushing:x`` ... ``bushing:rz`` per metre of road
        on the harmonic's grid (``settings.freq(k)``), as :func:`fbs_core.bushing_response`.
    """
    from ..prediction import bushing_response

    s = VariantSettings() if settings is None else settings
    tire, chassis = variant_models(values, s, cache)
    out: dict[int, ComplexArray] = {}
    for k in s.harmonics:
        v = bushing_response(k, s.n_modes, s.freq(k), s.coupling, tire=tire, chassis=chassis).data[
            :, :, 0
        ]
        if not np.all(np.isfinite(v)):
            raise ParameterError(
                f"the response of variant {dict(values)} is not finite for harmonic {k}"
            )
        out[k] = np.ascontiguousarray(v)
    return out
