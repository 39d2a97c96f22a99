"""A corridor study in this process: sample, rebuild every variant, respond, summarise.

:func:`corridor_study` samples a design of the named parameters (:mod:`.design`), computes
the coupled response of every variant (:func:`.models.variant_responses`) and returns a
:class:`VariantStudy`, from which the corridor (:mod:`.corridor`) and, for a Saltelli
design, the sensitivity indices (:mod:`.sensitivity`) of each harmonic follow. The rows
are evaluated tire by tire (:func:`tire_groups`): the rows that share a tire (a Saltelli
design's ``AB_i`` of a chassis parameter shares its tire with ``A``) are computed one after
the other from one build. A campaign (``python -m fbs_core.campaign``) runs the same groups
as tasks on a Dask cluster, with the same numbers (:func:`evaluate_rows` is the task).
"""

from __future__ import annotations

import concurrent.futures
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray
from ..errors import DataFormatError, StudyCancelled
from ..vocabulary import DIRECTIONS
from ..vocabulary import readonly as _ro
from ..workers import has_workers
from .corridor import Corridor, corridor
from .design import Design, sample_design
from .models import TireCache, VariantSettings, tire_key, variant_responses
from .parameters import ParameterSpace, apply_values
from .sensitivity import Sensitivity, sensitivity

__all__ = ["VariantStudy", "corridor_study", "evaluate_rows", "run_variants", "tire_groups"]

DOFS: tuple[str, ...] = tuple(f"bushing:{d}" for d in DIRECTIONS)


@dataclass(frozen=True, eq=False)
class VariantStudy:
    """The responses of every variant of a design, and the nominal one.

    Parameters
    ----------
    design : Design
    settings : VariantSettings
    responses : dict of int to ndarray, shape (n, n_f, n_e)
        Harmonic -> complex bushing response of every row of the design.
    nominal : dict of int to ndarray, shape (n_f, n_e)
        Harmonic -> the response of the base models.
    tire_keys : tuple of str
        The content key of every row's tire (:func:`~.models.tire_key`).
    """

    design: Design
    settings: VariantSettings
    responses: dict[int, ComplexArray]
    nominal: dict[int, ComplexArray]
    tire_keys: tuple[str, ...]

    def freq(self, harmonic: int) -> FloatArray:
        """The lines of a harmonic in Hz."""
        return self.settings.freq(self._h(harmonic))

    def _h(self, harmonic: int) -> int:
        if harmonic not in self.responses:
            raise DataFormatError(
                f"the study has no harmonic {harmonic!r}; computed: "
                f"{', '.join(map(str, self.responses))}"
            )
        return int(harmonic)

    def corridor(self, harmonic: int, percentiles: ArrayLike = (5.0, 50.0, 95.0)) -> Corridor:
        """The corridor of a harmonic (min, max and percentiles of ``|v_e|`` over the rows)."""
        k = self._h(harmonic)
        return corridor(
            self.freq(k),
            self.responses[k],
            self.nominal[k],
            dofs=DOFS,
            percentiles=percentiles,
            harmonic=k,
        )

    def sensitivity(
        self,
        harmonic: int,
        bands: ArrayLike | None = None,
        n_bootstrap: int = 200,
        seed: int = 0,
    ) -> Sensitivity:
        """Sobol' indices of the band levels of a harmonic (a Saltelli design only).

        Parameters
        ----------
        harmonic : int
        bands : array_like, shape (n_b, 2), optional
            Default: one-third-octave bands.
        n_bootstrap, seed
            Of the bootstrap intervals (:func:`~.sensitivity.sensitivity`).
        """
        k = self._h(harmonic)
        return sensitivity(
            self.design,
            self.freq(k),
            self.responses[k],
            bands=bands,
            dofs=DOFS,
            n_bootstrap=n_bootstrap,
            seed=seed,
            harmonic=k,
        )


def tire_groups(design: Design, settings: VariantSettings) -> list[tuple[str, list[int]]]:
    """Rows of the design grouped by the content key of their tire, in order of first use.

    Parameters
    ----------
    design : Design
    settings : VariantSettings
        The base models and operating points the rows' values apply to.

    Returns
    -------
    list of (str, list of int)
        ``(tire key, rows)``; every row appears once.
    """
    groups: dict[str, list[int]] = {}
    speeds = settings.tire_speeds()
    for i in range(design.n):
        tp, _ = apply_values(design.row(i), settings.tire, settings.chassis)
        groups.setdefault(tire_key(tp, speeds), []).append(i)
    return list(groups.items())


def evaluate_rows(
    rows: Sequence[Mapping[str, float]],
    settings: VariantSettings,
    cache: TireCache | None = None,
) -> dict[str, Any]:
    """The responses of several variants (one task of a campaign: rows sharing a tire).

    Parameters
    ----------
    rows : sequence of mapping of str to float
        Parameter values of each variant.
    settings : VariantSettings
    cache : TireCache, optional
        Default the process-wide cache.

    Returns
    -------
    dict
        ``responses``: harmonic -> ndarray ``(n_rows, n_f, 6)`` complex; ``seconds``: the
        time it took.
    """
    t0 = time.perf_counter()
    out: dict[int, list[ComplexArray]] = {k: [] for k in settings.harmonics}
    for r in rows:
        v = variant_responses(r, settings, cache)
        for k in settings.harmonics:
            out[k].append(v[k])
    return {
        "responses": {k: np.array(x) for k, x in out.items()},
        "seconds": time.perf_counter() - t0,
    }


def _wait_any(pending: list[Any], dask: bool, timeout: float) -> None:
    """Block until one of the futures is done or ``timeout`` seconds passed."""
    if dask:
        from distributed import wait

        try:
            wait(pending, timeout=timeout, return_when="FIRST_COMPLETED")
        except TimeoutError:
            pass
    else:
        concurrent.futures.wait(pending, timeout=timeout, return_when="FIRST_COMPLETED")


def run_variants(
    design: Design,
    settings: VariantSettings | None = None,
    *,
    cache: TireCache | None = None,
    progress: Callable[[int, int], object] | None = None,
    cancel: Callable[[], bool] | None = None,
    client: Any = None,
    processes: int = 1,
    poll: float = 0.2,
) -> VariantStudy:
    """Compute every variant of a design: in this process, in worker processes or on Dask.

    Every tire group (:func:`tire_groups`) is one task, :func:`evaluate_rows`; the
    responses are those of the same rows computed in this process (each task is the same
    computation, placed by its rows).

    Parameters
    ----------
    design : Design
    settings : VariantSettings, optional
        Default: the reference models, harmonic 4.
    cache : TireCache, optional
        Default the process-wide cache (two tires in memory); used in this process only
        (a worker uses its own process-wide cache).
    progress : callable, optional
        ``progress(rows_done, rows_total)`` at the start and after every tire group.
    cancel : callable, optional
        Asked before every tire group (with workers: every ``poll`` seconds); True stops
        with :class:`~fbs_core.StudyCancelled` (the tasks not started are cancelled).
    client : distributed.Client, optional
        A Dask client: the groups run as tasks on its cluster when it has workers
        (:func:`fbs_core.workers.has_workers`), else in this process.
    processes : int
        Without a cluster: worker processes of this machine (1: this process).
    poll : float
        Seconds between asking ``cancel`` while tasks run elsewhere.

    Returns
    -------
    VariantStudy
    """
    s = VariantSettings() if settings is None else settings
    groups = tire_groups(design, s)
    keys = [""] * design.n
    resp: dict[int, Any] = {}
    done = 0
    if progress is not None:
        progress(0, design.n)

    def place(rows: list[int], key: str, res: dict[int, ComplexArray]) -> None:
        nonlocal done
        for k, v in res.items():
            if k not in resp:
                resp[k] = np.empty((design.n, *v.shape[1:]), complex)
            resp[k][rows] = v
        for i in rows:
            keys[i] = key
        done += len(rows)
        if progress is not None:
            progress(done, design.n)

    def stop() -> None:
        raise StudyCancelled(f"variant study cancelled after {done} of {design.n} variants")

    use_dask = client is not None and has_workers(client)
    if use_dask or (int(processes) > 1 and len(groups) > 1):
        pool: Any = None
        if use_dask:
            submit: Callable[..., Any] = lambda rows: client.submit(  # noqa: E731
                evaluate_rows, rows, s, pure=False
            )
        else:
            import multiprocessing

            pool = concurrent.futures.ProcessPoolExecutor(
                max_workers=min(int(processes), len(groups)),
                mp_context=multiprocessing.get_context("spawn"),
            )
            submit = lambda rows: pool.submit(evaluate_rows, rows, s)  # noqa: E731
        futures = {submit([design.row(i) for i in rows]): (key, rows) for key, rows in groups}
        pending = list(futures)
        try:
            while pending:
                if cancel is not None and cancel():
                    stop()
                _wait_any(pending, use_dask, poll)
                for fu in [f for f in pending if f.done()]:
                    pending.remove(fu)
                    key, rows = futures[fu]
                    place(rows, key, fu.result()["responses"])
        finally:
            for fu in pending:
                fu.cancel()
            if pool is not None:
                pool.shutdown(wait=True, cancel_futures=True)
    else:
        for key, rows in groups:
            if cancel is not None and cancel():
                stop()
            place(rows, key, evaluate_rows([design.row(i) for i in rows], s, cache)["responses"])
    nominal = variant_responses({}, s, cache)
    return VariantStudy(
        design=design,
        settings=s,
        responses={k: _ro(v) for k, v in resp.items()},
        nominal={k: _ro(v) for k, v in nominal.items()},
        tire_keys=tuple(keys),
    )


def corridor_study(
    parameters: Iterable[str],
    n: int = 64,
    method: str = "sobol",
    seed: int = 0,
    settings: VariantSettings | None = None,
    *,
    ranges: Mapping[str, Sequence[float]] | None = None,
    cache: TireCache | None = None,
    progress: Callable[[int, int], object] | None = None,
    cancel: Callable[[], bool] | None = None,
    client: Any = None,
    processes: int = 1,
) -> VariantStudy:
    """Sample the named parameters and compute every variant (here, in processes or on Dask).

    Parameters
    ----------
    parameters : iterable of str
        Names of :data:`~fbs_core.variants.PARAMETERS`.
    n : int
        Variants (``"saltelli"``: base rows ``N``, ``N (k + 2)`` variants).
    method : {"sobol", "lhs", "saltelli"}
    seed : int
        Seed of the design.
    settings : VariantSettings, optional
        Harmonics, grid, coupling, base models (default: reference models, harmonic 4).
    ranges : mapping of str to (low, high), optional
        Ranges replacing the documented defaults.
    cache, progress, cancel, client, processes
        As :func:`run_variants`.

    Returns
    -------
    VariantStudy

    Examples
    --------
    >>> st = corridor_study(["knuckle_mass", "body_bushing_loss"], n=8)   # doctest: +SKIP
    >>> st.corridor(4).width_db.max()                                      # doctest: +SKIP
    """
    space = ParameterSpace.from_names(parameters, ranges)
    design = sample_design(space, n, method, seed)
    return run_variants(
        design,
        settings,
        cache=cache,
        progress=progress,
        cancel=cancel,
        client=client,
        processes=processes,
    )
