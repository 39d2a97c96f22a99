"""One scatter band on a ``dask.distributed`` cluster, with progress and cancel.

:func:`scatter_band_on` is :func:`fbs_core.scatter_band` computed by a cluster's workers:
the same blocks of lines as a campaign (:func:`~fbs_core.campaign.run.block_lines`,
:func:`~fbs_core.campaign.work.band_block`), the subsystem arrays computed once here and
sent to the cluster (:func:`~fbs_core.campaign.work.prepare_inputs`: the same arrays as
the in-process band, see :mod:`.work` for why this makes the band equal to the last bit),
and the blocks joined by :func:`~fbs_core.campaign.work.assemble_band`. The dashboard uses
it for its heavy bands (``app/offload.py``).

While the blocks run, ``progress(done, total)`` (frequency lines of the finished blocks, as
:func:`fbs_core.scatter_band` reports them) is called as they finish and ``cancel()`` is
asked every ``poll`` seconds: when it returns True the block futures (and the scattered
arrays) are cancelled on the cluster and :class:`~fbs_core.StudyCancelled` is raised.

A cluster that cannot compute the band raises :class:`ClusterUnavailable` (the caller
computes it in its own process instead): a scheduler without workers (checked before the
blocks are sent, and whenever no block finished for ``stall_s`` seconds), a scheduler that
went away (the client's connection closed), a block lost with its worker.
"""

from __future__ import annotations

import concurrent.futures
import threading
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ClusterUnavailable, FBSError, StudyCancelled
from ..workers import has_workers
from . import work
from .run import block_lines

if TYPE_CHECKING:
    from ..studies.scatter import ScatterBand

__all__ = ["ClusterUnavailable", "line_blocks", "scatter_band_on"]


#: Round-lines of a dashboard block: about 1.6 s on one core (0.81 us per round-line,
#: docs/deployment.md), so progress moves and a cancel frees the workers within a block.
DEFAULT_TASK_ROUND_LINES = 2_000_000


def line_blocks(rounds: int, n_lines: int, task_round_lines: int) -> list[tuple[int, int]]:
    """The ``(l0, l1)`` line blocks of a band, as a campaign splits it (:func:`block_lines`)."""
    per = block_lines(int(rounds), int(n_lines), int(task_round_lines))
    return [(a, min(n_lines, a + per)) for a in range(0, n_lines, per)]


def scatter_band_on(
    client: Any,
    harmonic: int,
    noise: float = 0.1,
    target: str = "both",
    rounds: int = 10_000,
    frequency_dependent: bool = False,
    seed: int = 0,
    *,
    n_modes: int | None = None,
    df: float = 0.5,
    tire: Any = None,
    chassis: Any = None,
    coupling: str = "6dof",
    percentiles: Sequence[float] = (5.0, 95.0),
    task_round_lines: int = DEFAULT_TASK_ROUND_LINES,
    max_chunk_bytes: float = 64e6,
    progress: Callable[[int, int], None] | None = None,
    cancel: Callable[[], bool] | None = None,
    poll: float = 0.1,
    stall_s: float = 10.0,
) -> ScatterBand:
    """:func:`fbs_core.scatter_band` computed on the workers of ``client`` (see the module).

    Parameters
    ----------
    client : distributed.Client
    harmonic, noise, target, rounds, frequency_dependent, seed, n_modes, df, tire, chassis,
    coupling, percentiles, max_chunk_bytes
        As :func:`fbs_core.scatter_band` (``tire``/``chassis`` None: the reference models).
    task_round_lines : int
        Work of one block (rounds x lines).
    progress : callable, optional
        ``progress(done, total)`` frequency lines, once with 0 and after every finished
        block.
    cancel : callable, optional
        Asked every ``poll`` seconds; True cancels the futures.
    stall_s : float
        Seconds without a finished block after which the scheduler is asked whether it
        still has workers (none, or no connection: :class:`ClusterUnavailable`).

    Returns
    -------
    ScatterBand

    Raises
    ------
    StudyCancelled
        When ``cancel()`` returned True (nothing is left running on the cluster).
    ClusterUnavailable
        When the cluster cannot compute the band (see the module); nothing is left
        running on it.
    FBSError
        For bad settings (as the in-process band) or a failed block.
    """
    from ..studies import scatter as _sc
    from ..studies.band_kernel import noise_flags

    if cancel is not None and cancel():
        raise StudyCancelled("scatter band cancelled before it started")
    noise_flags(target)  # a bad target is refused here, not on every worker
    if isinstance(rounds, bool) or not isinstance(rounds, int | np.integer) or rounds < 1:
        raise FBSError(f"rounds must be a positive integer, got {rounds!r}")
    if rounds > _sc.MAX_ROUNDS:
        raise FBSError(f"rounds must be at most {_sc.MAX_ROUNDS:,}, got {rounds:,}")
    if not 0.0 <= noise < 1.0:
        raise FBSError(f"noise must be in [0, 1) (0.1 = +-10 %), got {noise!r}")
    if not has_workers(client):
        raise ClusterUnavailable("the Dask scheduler has no workers (or no connection)")
    inp = work.prepare_inputs(
        "reference" if tire is None else tire,
        "reference" if chassis is None else chassis,
        harmonic,
        n_modes,
        coupling,
        df,
    )
    blocks = line_blocks(rounds, inp.n_lines, task_round_lines)
    total = len(blocks)
    if progress is not None:
        progress(0, inp.n_lines)
    futures: list[Any] = []
    shipped = None
    stop = threading.Event()
    try:
        shipped = client.scatter(inp, hash=False)
        futures = [
            client.submit(
                work.band_block,
                shipped,
                float(noise),
                target,
                int(rounds),
                bool(frequency_dependent),
                seed,
                tuple(percentiles),
                l0,
                l1,
                max_chunk_bytes,
                pure=False,
            )
            for l0, l1 in blocks
        ]
        n_done = 0
        moved = time.monotonic()
        while n_done < total:
            if cancel is not None and cancel():
                raise StudyCancelled(f"scatter band cancelled after {n_done} of {total} blocks")
            stop.wait(poll)
            finished = [f.done() for f in futures]
            if sum(finished) != n_done:
                n_done, moved = sum(finished), time.monotonic()
                if progress is not None:
                    lines = sum(b - a for (a, b), ok in zip(blocks, finished, strict=True) if ok)
                    progress(lines, inp.n_lines)
            elif time.monotonic() - moved > stall_s:
                if not has_workers(client):
                    raise ClusterUnavailable(
                        f"the Dask scheduler lost its workers or its connection after "
                        f"{n_done} of {total} blocks"
                    )
                moved = time.monotonic()
        try:
            results = client.gather(futures)  # raises the first failed block's error
        except (OSError, TimeoutError, concurrent.futures.CancelledError) as e:
            # the connection closed, or a block was lost with the scheduler or its worker
            raise ClusterUnavailable(f"the Dask cluster failed the band ({e!r})") from e
    except BaseException:
        try:
            client.cancel([f for f in (*futures, shipped) if f is not None], force=True)
        except Exception:  # noqa: BLE001 (a closed connection: nothing left to cancel)
            pass
        raise
    band: ScatterBand = work.assemble_band(
        inp.freq,
        inp.dofs,
        inp.reference,
        inp.YjjA,
        inp.vj,
        inp.YjjE,
        inp.YejE,
        results,
        q=percentiles,
        noise=noise,
        target=target,
        rounds=rounds,
        frequency_dependent=frequency_dependent,
        seed=seed,
        harmonic=harmonic,
    )
    return band
