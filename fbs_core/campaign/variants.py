"""The "variants" study of a campaign: a corridor of systematic errors on Dask.

A campaign file's ``[variants]`` table describes a corridor study (:mod:`fbs_core.variants`):
the named physical parameters and their ranges, the design and its size, the harmonics and
the base models::

    [variants]
    name = "corridor"                 # the case is "variants_corridor"
    parameters = ["inflation_pressure", "tread_mass", "body_bushing_stiffness"]
    ranges = { tread_mass = [6.0, 7.5] }   # optional: replaces a documented default range
    design = "sobol"                  # "sobol" (n a power of 2), "lhs", "saltelli" (N (k + 2))
    n = 64
    harmonics = [4]
    n_modes = "all"
    coupling = "6dof"
    percentiles = [5.0, 50.0, 95.0]
    speeds = [20.0, 40.0, 60.0, 80.0, 100.0, 120.0]   # optional: rebuilt tires' operating points
    [variants.tire]                   # optional: the base tire's parameters (TireParameters)
    orders = [6, 3, 4, 3, -1, -1, -1, -1]
    [variants.chassis]                # optional: the base chassis' (ChassisParameters)

Every task is one *tire*: the rows of the design that share a rebuilt tire (one per row for
a tire parameter of a Sobol' design; a Saltelli design's ``AB_i`` of a chassis parameter
shares its tire with ``A``; all of them for chassis parameters only, then split into tasks
of :data:`ROWS_PER_TASK` rows), computed by :func:`fbs_core.variants.evaluate_rows`
(seconds to minutes). One task more computes the
nominal models. The design (unit points, values, parameter ranges, seed) is stored when
the run starts; every task's rows, parameter values and responses as a unit of the result
file (``cases/<case>/tires/<key>``), so a stopped run resumes with the tires not done.
:func:`study_from_file` reads them back as a :class:`~fbs_core.variants.VariantStudy`,
the same numbers as :func:`fbs_core.variants.run_variants` of the same seed in one process.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import time
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..errors import CampaignError, FBSError
from ..vocabulary import COUPLINGS
from ..vocabulary import readonly as _ro

if TYPE_CHECKING:
    from pathlib import Path

    from ..variants import Design, VariantSettings, VariantStudy
    from .run import Task
    from .spec import Campaign
    from .store import CampaignStore

__all__ = [
    "VARIANT_WORK",
    "VariantsCase",
    "parse_variants",
    "study_from_file",
    "variant_task",
]

#: Most rows of one task: rows sharing a tire beyond this are split into several tasks.
ROWS_PER_TASK = 16

#: Work of one variant in the units of the progress bar's time-left estimate (rounds x
#: lines of a scatter band): a tire rebuild of about 15 s at 0.81 us per round-line.
VARIANT_WORK = 2e7

_KEYS = (
    "name",
    "parameters",
    "ranges",
    "design",
    "n",
    "harmonics",
    "n_modes",
    "coupling",
    "percentiles",
    "speeds",
    "tire",
    "chassis",
)


@dataclass(frozen=True)
class VariantsCase:
    """One corridor study of a campaign (the ``[variants]`` table).

    Attributes
    ----------
    study : str
        Its name (the case is ``variants_<study>``).
    parameters : tuple of str
    ranges : tuple of (str, float, float)
        Every parameter's sampled range, defaults resolved (a changed default changes the
        case's digest).
    design : {"sobol", "lhs", "saltelli"}
    n : int
    seed : int
        The design's seed (derived from the campaign seed like a scatter case's).
    harmonics : tuple of int
    n_modes : int or None
    coupling : {"6dof", "5dof"}
    percentiles : tuple of float
    speeds : tuple of float or None
    tire, chassis : tuple of (str, value)
        Base parameters replacing the reference models' (TOML lists as tuples).
    df : float
    """

    study: str
    parameters: tuple[str, ...]
    ranges: tuple[tuple[str, float, float], ...]
    design: str
    n: int
    seed: int
    harmonics: tuple[int, ...]
    n_modes: int | None
    coupling: str
    percentiles: tuple[float, ...]
    speeds: tuple[float, ...] | None
    tire: tuple[tuple[str, Any], ...]
    chassis: tuple[tuple[str, Any], ...]
    df: float

    kind: ClassVar[str] = "variants"

    @property
    def name(self) -> str:
        return f"variants_{self.study}"

    def settings(self) -> dict[str, Any]:
        return {"kind": self.kind, **asdict(self)}

    def digest(self) -> str:
        from .fields import _digest

        return _digest(self.settings())

    def variant_settings(self) -> VariantSettings:
        """The :class:`~fbs_core.variants.VariantSettings` of the study."""
        from ..chassis import ChassisParameters
        from ..tire.params import DEFAULT_PARAMETERS, TireParameters
        from ..variants import VariantSettings

        tire = (
            TireParameters.from_dict({**DEFAULT_PARAMETERS.to_dict(), **dict(self.tire)})
            if self.tire
            else DEFAULT_PARAMETERS
        )
        return VariantSettings(
            harmonics=self.harmonics,
            df=self.df,
            n_modes=self.n_modes,
            coupling=self.coupling,
            speeds=self.speeds,
            tire=tire,
            chassis=ChassisParameters(**dict(self.chassis)),
        )

    def sample(self) -> Design:
        """The design (the same for the same seed, wherever it is drawn)."""
        from ..variants import ParameterSpace, sample_design

        space = ParameterSpace.from_names(
            self.parameters, {n: (lo, hi) for n, lo, hi in self.ranges}
        )
        return sample_design(space, self.n, self.design, self.seed)


def _tuples(v: Any) -> Any:
    return tuple(_tuples(x) for x in v) if isinstance(v, list | tuple) else v


def _base(d: Any, kind: str) -> tuple[tuple[str, Any], ...]:
    from ..chassis import ChassisParameters
    from ..tire.params import DEFAULT_PARAMETERS, TireParameters

    where = f"[variants.{kind}]"
    if not isinstance(d, dict):
        raise CampaignError(f"campaign file, {where}: must be a table, got {type(d).__name__}")
    items = tuple(sorted((str(k), _tuples(v)) for k, v in d.items()))
    cls: Any = TireParameters if kind == "tire" else ChassisParameters
    known = [f.name for f in dataclasses.fields(cls)]
    bad = sorted(set(dict(items)) - set(known))
    if bad:
        raise CampaignError(f"campaign file, {where}: unknown key(s) {bad}; allowed: {known}")
    try:
        if kind == "tire":
            TireParameters.from_dict({**DEFAULT_PARAMETERS.to_dict(), **dict(items)})
        else:
            ChassisParameters(**dict(items))
    except (TypeError, ValueError) as e:
        raise CampaignError(f"campaign file, {where}: {e}") from None
    return items


def parse_variants(d: dict[str, Any], campaign_seed: int, seeds: str, df: float) -> VariantsCase:
    """The :class:`VariantsCase` of a ``[variants]`` table (checked, nothing evaluated).

    Raises
    ------
    CampaignError
        For unknown keys, parameters or designs, bad ranges, sizes or base parameters,
        naming the key and what is allowed.
    """
    from ..variants import DESIGNS, ParameterSpace, sample_design
    from .fields import _choice, _float, _int, _known, _list, _name, case_seed

    w = "[variants]"
    _known(d, _KEYS, w)
    study = _name(str(d.get("name", "corridor")), f"{w} name")
    names = [str(x) for x in _list(d.get("parameters", []), w)]
    if not names:
        raise CampaignError(f"campaign file, {w} parameters: list at least one parameter")
    ranges = d.get("ranges", {})
    if not isinstance(ranges, dict):
        raise CampaignError(f"campaign file, {w} ranges: must be a table of [low, high]")
    try:
        space = ParameterSpace.from_names(names, ranges)
    except FBSError as e:
        raise CampaignError(f"campaign file, {w}: {e}") from None
    design = _choice(d.get("design", "sobol"), DESIGNS, f"{w} design")
    n = _int(d.get("n", 64), f"{w} n", 2, 1 << 20)
    try:  # a bad n for the design is refused here, not on the cluster
        sample_design(space, n, design, 0)
    except FBSError as e:
        raise CampaignError(f"campaign file, {w} n: {e}") from None
    hs = tuple(_int(h, f"{w} harmonics", 1, 7) for h in _list(d.get("harmonics", [4]), w))
    if len(set(hs)) != len(hs):
        raise CampaignError(f"campaign file, {w} harmonics: duplicates in {list(hs)}")
    nm = d.get("n_modes", "all")
    n_modes = None if nm == "all" else _int(nm, f"{w} n_modes", 1)
    coupling = _choice(d.get("coupling", "6dof"), COUPLINGS, f"{w} coupling")
    qs = tuple(
        _float(q, f"{w} percentiles", 0.0, 100.0)
        for q in _list(d.get("percentiles", [5.0, 50.0, 95.0]), w)
    )
    sp = d.get("speeds")
    speeds = None
    if sp is not None:
        speeds = tuple(_float(v, f"{w} speeds", 0.0, 400.0) for v in _list(sp, w))
        if len(speeds) < 2 or any(b <= a for a, b in zip(speeds, speeds[1:], strict=False)):
            raise CampaignError(
                f"campaign file, {w} speeds: need >= 2 increasing km/h, got {list(speeds)}"
            )
    tire = _base(d.get("tire", {}), "tire")
    chassis = _base(d.get("chassis", {}), "chassis")
    proto = VariantsCase(
        study,
        space.names,
        tuple((p.name, p.low, p.high) for p in space.parameters),
        design,
        n,
        campaign_seed,
        hs,
        n_modes,
        coupling,
        qs,
        speeds,
        tire,
        chassis,
        df,
    )
    seed = campaign_seed if seeds == "common" else case_seed(campaign_seed, proto.name)
    case = dataclasses.replace(proto, seed=seed)
    try:
        case.variant_settings()
    except FBSError as e:
        raise CampaignError(f"campaign file, {w}: {e}") from None
    return case


# ---- tasks ---------------------------------------------------------------------------------


@functools.lru_cache(maxsize=8)
def _design(case: VariantsCase) -> Design:
    return case.sample()


@functools.lru_cache(maxsize=8)
def _settings(case: VariantsCase) -> VariantSettings:
    return case.variant_settings()


def groups(case: VariantsCase) -> list[tuple[str, list[int]]]:
    """The tasks of a study: ``(unit name, rows)``, the nominal models first (no rows).

    The rows sharing a tire, in chunks of at most :data:`ROWS_PER_TASK` (a study of chassis
    parameters alone shares one tire over all its rows: its chunks run in parallel, each
    worker loading or building that tire once and keeping it in its cache).
    """
    from ..variants import tire_groups

    out: list[tuple[str, list[int]]] = [(f"cases/{case.name}/nominal", [])]
    for key, rows in tire_groups(_design(case), _settings(case)):
        for j in range(0, len(rows), ROWS_PER_TASK):
            out.append((f"cases/{case.name}/tires/{key[:24]}-{j}", rows[j : j + ROWS_PER_TASK]))
    return out


def write_designs(campaign: Campaign, store: CampaignStore, done: set[str]) -> None:
    """Store the design of every variants study not stored yet (when a run starts)."""
    for c in campaign.variants_cases:
        if f"cases/{c.name}/design" not in done:
            write_design(store, c, _design(c))


def submit(client: Any, task: Task, numba_threads: int | None, token: str) -> Any:
    """Submit a variants task to the cluster (its rows' parameter values, the settings)."""
    case = task.case
    assert isinstance(case, VariantsCase)
    d = _design(case)
    return client.submit(
        variant_task,
        _settings(case),
        [d.row(i) for i in task.rows],
        numba_threads,
        key=f"variants-{task.unit.rsplit('/', 1)[-1]}-{token}",
        pure=False,
    )


def variant_task(
    settings: VariantSettings, rows: list[dict[str, float]], numba_threads: int | None = None
) -> dict[str, Any]:
    """A campaign task: the responses of the variants ``rows`` (or the nominal models when
    ``rows`` is empty), with the provenance of the run.

    Returns
    -------
    dict
        ``responses``: harmonic -> ``(n_rows, n_f, 6)`` complex (``(1, n_f, 6)`` for the
        nominal models); ``seconds`` (wall), ``cpu_seconds`` (of the worker process),
        ``worker``, ``host``, ``pid``.
    """
    from ..variants import evaluate_rows
    from .work import _where

    if numba_threads:
        import numba

        n_max = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]  # no stubs
        numba.set_num_threads(max(1, min(int(numba_threads), n_max)))
    t0, c0 = time.perf_counter(), time.process_time()
    res = evaluate_rows(rows or [{}], settings)
    return {
        "responses": res["responses"],
        "seconds": time.perf_counter() - t0,
        "cpu_seconds": time.process_time() - c0,  # of the worker process: < seconds when
        **_where(),  # the machine's cores are shared with other work
    }


def case_attrs(case: VariantsCase, design: Design) -> dict[str, Any]:
    """Attributes of the case group (the study's settings and size)."""
    return {
        "kind": case.kind,
        "name": case.name,
        "digest": case.digest(),
        "settings": case.settings(),
        "seed": str(case.seed),
        "n_variants": design.n,
        "parameters": list(case.parameters),
        "design": case.design,
    }


def write_design(store: CampaignStore, case: VariantsCase, design: Design) -> None:
    """Store the design: unit points, values, names and ranges, seed (a unit of its own)."""
    s = case.variant_settings()
    data: dict[str, Any] = {
        "unit": design.unit,
        "values": design.values,
        "names": np.array(design.names, dtype=object),
    }
    for k in s.harmonics:
        data[f"freq_h{k}"] = s.freq(k)
    attrs = {
        "method": design.method,
        "seed": str(design.seed),
        "n_base": design.n_base,
        "space": design.space.to_dict(),
        "variant_settings": s.to_dict(),
    }
    store.write_unit(
        f"cases/{case.name}/design", data, attrs, {f"cases/{case.name}": case_attrs(case, design)}
    )


def write_result(
    store: CampaignStore, case: VariantsCase, unit: str, rows: list[int], res: dict[str, Any]
) -> Path:
    """Store a finished task: its rows, their parameter values and responses (returns the part
    file)."""
    design = _design(case)
    keys = ("worker", "host", "pid", "seconds", "cpu_seconds")
    prov: dict[str, Any] = {k: res[k] for k in keys if k in res}
    data: dict[str, Any] = {"rows": np.asarray(rows, np.int64)}
    if rows:
        data["values"] = design.values[rows]
    for k, v in res["responses"].items():
        data[f"h{k}"] = np.asarray(v)
    return store.write_unit(
        unit,
        data,
        {"n_rows": len(rows), **prov},
        {f"cases/{case.name}": case_attrs(case, design)},
    )


# ---- reading back --------------------------------------------------------------------------


def study_from_file(path: Any, name: str) -> VariantStudy:
    """The :class:`~fbs_core.variants.VariantStudy` of a complete variants case of a result
    file (and the parts of an unfinished run).

    Raises
    ------
    CampaignError
        For an unknown case, another kind of case, or one not complete.
    """

    from ..variants import VariantStudy, tire_key
    from ..variants.parameters import apply_values
    from .store import CampaignStore, read_file

    store = CampaignStore(path)
    attrs: dict[str, Any] | None = None
    units: dict[str, dict[str, Any]] = {}
    design_unit: dict[str, Any] | None = None
    for p in store.files():
        with read_file(p) as h:
            g = h.get(f"cases/{name}")
            if g is None:
                continue
            if attrs is None:
                attrs = {k: v for k, v in g.attrs.items()}
            if "design" in g and design_unit is None:
                design_unit = {k: g["design"][k][()] for k in g["design"]}
            for key, u in g.get("tires", {}).items():
                units.setdefault(key, {k: u[k][()] for k in u})
            if "nominal" in g:
                units.setdefault("", {k: g["nominal"][k][()] for k in g["nominal"]})
    if attrs is None:
        raise CampaignError(f"no case {name!r} in {path}")
    if str(attrs.get("kind")) != "variants":
        raise CampaignError(
            f"{path}: case {name} is a {attrs.get('kind')} case, not a variants study"
        )
    st = json.loads(attrs["settings"])
    case = VariantsCase(
        **{k: _tuples(v) if isinstance(v, list) else v for k, v in st.items() if k != "kind"}
    )
    design = _design(case)
    if design_unit is None or not np.array_equal(design_unit["unit"], design.unit):
        raise CampaignError(
            f"{path}: case {name}: the stored design is missing or is not the one of its seed "
            "(another scipy's Sobol' / Latin hypercube?)"
        )
    done = np.zeros(design.n, bool)
    s = case.variant_settings()
    resp = {k: np.empty((design.n, s.freq(k).size, 6), complex) for k in s.harmonics}
    nominal = None
    for key, u in units.items():
        if key == "":
            nominal = {k: u[f"h{k}"][0] for k in s.harmonics}
            continue
        rows = np.asarray(u["rows"])
        if rows.ndim != 1 or rows.dtype.kind not in "iu" or np.any((rows < 0) | (rows >= design.n)):
            raise CampaignError(f"{path}: case {name}: task {key!r} names rows outside the design")
        for k in s.harmonics:
            v = np.asarray(u[f"h{k}"])
            if v.shape != (rows.size, s.freq(k).size, 6):
                raise CampaignError(
                    f"{path}: case {name}: task {key!r} holds responses of shape {v.shape}, "
                    f"not {(rows.size, s.freq(k).size, 6)}"
                )
            resp[k][rows] = v
        done[rows] = True
    if nominal is None or not done.all():
        raise CampaignError(
            f"{path}: case {name} is not complete: {int(done.sum())} of {design.n} variants"
            f"{'' if nominal is not None else ' and the nominal models'}; rerun the campaign"
        )
    speeds = s.tire_speeds()
    keys = tuple(
        tire_key(apply_values(design.row(i), s.tire, s.chassis)[0], speeds) for i in range(design.n)
    )
    return VariantStudy(
        design=design,
        settings=s,
        responses={k: _ro(v) for k, v in resp.items()},
        nominal={k: _ro(v) for k, v in nominal.items()},
        tire_keys=keys,
    )
