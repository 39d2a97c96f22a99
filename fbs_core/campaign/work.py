"""The tasks of a campaign: pure functions of small, explicit arguments (run on Dask workers).

- :func:`prepare_inputs`: the subsystem arrays of one (harmonic, tire, chassis, coupling,
  retained modes) combination, shared by all the scatter cases that use them (computed
  once by the client and scattered, see below);
- :func:`band_block`: the band statistics of one scatter case over a block of frequency
  lines, with all of the case's rounds;
- :func:`truncation_case`: the truncation error map and suggested mode counts of one case.

Why a block is a range of lines and not a range of rounds. The noise factors are
counter based (:mod:`fbs_core.studies._rng`): those of round ``r`` at line ``l`` are a pure
function of ``(seed, r, l)``, so every (round, line) is already an independent,
reproducible stream whatever the split, and no per-block stream (``SeedSequence.spawn``)
is needed: a block computes exactly the numbers the whole band would. The band's
statistics, however, are not all mergeable over rounds: minimum, maximum, the first round
attaining them and the convergence checkpoints are, the percentiles are not (an exact
percentile needs every magnitude of its column, ``8 R`` bytes per line and DOF, shipped
to one place). Over lines everything is independent, so a block of lines holding all
rounds gives the exact band with only its statistics sent back; within the task the lines
are processed in chunks bounded by ``max_chunk_bytes``, as in
:func:`fbs_core.scatter_band`, so the task size (``rounds x lines``) and the memory bound
are set independently.

Why the subsystem arrays are computed once, by the client. The chassis synthesis goes
through LAPACK, whose results depend in the last bits on its thread count: Dask's worker
processes run with one BLAS thread (``OPENBLAS_NUM_THREADS=1``), a plain Python process
with all cores, and the chassis mobility then differs by about 1e-10 (relative), which
the near-singular interface sums amplify to 1e-7 in the band edges at resonances
(measured on the reference models). Computed once and shipped, the arrays are the same
for every block, stored in the result file, and equal to those of
:func:`fbs_core.scatter_band` in the client's process: the band is then the same to the
last bit. The truncation tasks get the chassis FRF on their grid from the client for the
same reason (the tire's modal sums do not depend on the BLAS threads).
"""

from __future__ import annotations

import os
import socket
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import ComplexArray, FloatArray
from ..errors import FBSError
from ..vocabulary import readonly

if TYPE_CHECKING:
    from ..frf import FRF
    from ..studies.scatter import ScatterBand
    from .spec import TruncationCase

__all__ = [
    "BandInputs",
    "resolve_model",
    "prepare_inputs",
    "band_block",
    "assemble_band",
    "truncation_case",
]


class BandInputs:
    """Subsystem arrays of a scatter case on its frequency grid (read-only).

    Attributes
    ----------
    freq : ndarray, shape (n_f,)
    dofs : tuple of str, length n_e
    YjjA, vj, YjjE, YejE : ndarray
        As in :func:`fbs_core.studies.scatter_band_arrays`.
    reference : ndarray, shape (n_f, n_e)
        The noise-free response (all factors 1).
    n_modes_total : int
    """

    def __init__(
        self,
        freq: ArrayLike,
        dofs: Sequence[str],
        YjjA: ArrayLike,
        vj: ArrayLike,
        YjjE: ArrayLike,
        YejE: ArrayLike,
        n_modes_total: int,
    ) -> None:
        from ..studies.band_kernel import kernel_arrays, reference_response

        self.freq = readonly(freq)
        self.dofs = tuple(dofs)
        self.YjjA, self.vj, self.YjjE, self.YejE = (readonly(x) for x in (YjjA, vj, YjjE, YejE))
        self.n_modes_total = int(n_modes_total)
        self.arrays = kernel_arrays(self.YjjA, self.vj, self.YjjE, self.YejE)
        self.reference = readonly(reference_response(self.arrays))

    def __setstate__(self, state: dict[str, Any]) -> None:
        # arrays arrive writeable from pickling: read-only again, so that the compiled
        # kernels see the one signature they were compiled (and cached) for
        for v in state.values():
            if isinstance(v, np.ndarray):
                v.setflags(write=False)
        for v in state["arrays"]:
            v.setflags(write=False)
        self.__dict__.update(state)

    @property
    def n_lines(self) -> int:
        return int(self.freq.size)


def resolve_model(kind: str, spec: Any) -> Any:
    """A model from its campaign spec: ``"reference"`` or an already loaded object."""
    if isinstance(spec, str):
        if spec != "reference":
            raise FBSError(f"{kind} model {spec!r}: only 'reference' is resolved by name")
        import fbs_core

        return fbs_core.reference_tire() if kind == "tire" else fbs_core.reference_chassis()
    return spec


def load_model(kind: str, source: str) -> Any:
    """Load a model variant from a file (on the client; the object is then scattered).

    Tire: a modal tire model (:func:`fbs_core.io.import_tire_model`). Chassis: an FRF file
    (:func:`fbs_core.io.load_frf`) with inputs ``spindle:*``; it is interpolated onto each
    harmonic's grid (never extrapolated).
    """
    if source == "reference":
        return "reference"
    from .. import io

    if kind == "tire":
        return io.import_tire_model(source).model
    return io.load_frf(source).frf


def chassis_on(chassis: Any, f: FloatArray) -> FRF:
    """The chassis FRF on the grid ``f``: a model's exact synthesis, or an FRF (from a file)
    interpolated onto ``f`` (never extrapolated; an FRF already on ``f`` as it is)."""
    from ..frf import FRF

    chassis = frf_from(resolve_model("chassis", chassis))
    if isinstance(chassis, FRF):
        if chassis.freq.shape == f.shape and np.array_equal(chassis.freq, f):
            return chassis
        return chassis.interpolate(f)
    Y: FRF = chassis.mobility(f)
    return Y


def frf_payload(
    frf: FRF,
) -> tuple[FloatArray, ComplexArray, tuple[str, ...], tuple[str, ...], str]:
    """An FRF as plain arrays and labels, to send to a worker (FRF objects do not pickle)."""
    return (np.asarray(frf.freq), np.asarray(frf.data), frf.outputs, frf.inputs, frf.quantity)


def frf_from(payload: Any) -> Any:
    """The FRF of :func:`frf_payload` (or the object itself when it is not a payload)."""
    from ..frf import FRF

    if isinstance(payload, tuple) and len(payload) == 5:
        return FRF(*payload)
    return payload


def prepare_inputs(
    tire: Any, chassis: Any, harmonic: int, n_modes: int | None, coupling: str, df: float
) -> BandInputs:
    """The arrays of :func:`fbs_core.scatter_band` for one harmonic, model pair and coupling."""
    from ..studies import _models

    tire = resolve_model("tire", tire)
    h = _models.resolve_harmonic(harmonic)
    dirs = _models.coupled_directions(coupling)
    f = h.frequencies(df)
    n_total = _models.total_modes(tire)
    n = n_total if n_modes is None else int(n_modes)
    if not 1 <= n <= n_total:
        raise FBSError(f"n_modes must be in 1..{n_total} (the tire's modes), got {n_modes!r}")
    YjjE, YejE, resp = _models.chassis_arrays(chassis_on(chassis, f), f, dirs)
    YjjA, vj = _models.tire_arrays(tire, f, h, [n], dirs)
    return BandInputs(f, resp, YjjA[0], vj[0], YjjE, YejE, n_total)


def _where() -> dict[str, Any]:
    try:
        from distributed import get_worker

        addr = get_worker().address
    except (ImportError, ValueError):
        addr = "client"
    return {"worker": addr, "host": socket.gethostname(), "pid": os.getpid()}


def band_block(
    inputs: BandInputs,
    noise: float,
    target: str,
    rounds: int,
    frequency_dependent: bool,
    seed: int,
    percentiles: ArrayLike,
    l0: int,
    l1: int,
    max_chunk_bytes: float = 64e6,
    numba_threads: int | None = None,
) -> dict[str, Any]:
    """Band statistics of lines ``l0 .. l1 - 1`` over all ``rounds`` (exactly the numbers of
    :func:`fbs_core.studies.scatter_band_arrays` for those lines).

    Returns
    -------
    dict
        ``lower``, ``upper``, ``argmin_round``, ``argmax_round`` ``(n_l, n_e)``,
        ``percentiles`` ``(n_q, n_l, n_e)``, ``conv_lower``, ``conv_upper``
        ``(n_k, n_l, n_e)``, ``checkpoints``, ``l0``, ``l1`` and the provenance of the run
        (``worker``, ``host``, ``pid``, ``seconds``).
    """
    from ..studies.band_kernel import BandStats, band_lines, noise_flags, seed_key
    from ..studies.scatter import default_checkpoints

    t0 = time.perf_counter()
    if numba_threads:
        import numba

        n_max = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]  # not in numba's stubs
        numba.set_num_threads(max(1, min(int(numba_threads), n_max)))
    nf, ne = inputs.n_lines, len(inputs.dofs)
    if not 0 <= l0 < l1 <= nf:
        raise FBSError(f"line block {l0}..{l1} outside 0..{nf}")
    if not 0.0 <= noise < 1.0:
        raise FBSError(f"noise must be in [0, 1), got {noise!r}")
    tire, chassis = noise_flags(target)
    rounds = int(rounds)
    qs = np.asarray(percentiles, float)
    ck = default_checkpoints(rounds)
    key = seed_key(seed)
    nl = l1 - l0
    st = BandStats.empty(nl, ne, qs.size, ck.size)
    chunk = int(max(1, min(nl, max_chunk_bytes // (8 * ne * rounds))))
    mag = np.empty((chunk, ne, rounds))
    rids = np.arange(rounds, dtype=np.int64)
    for a in range(l0, l1, chunk):
        b = min(l1, a + chunk)
        band_lines(
            inputs.arrays, a, b, key, rids, noise, tire, chassis, bool(frequency_dependent), qs,
            ck, st, row=a - l0, work=mag,
        )  # fmt: skip
    return {
        "l0": int(l0),
        "l1": int(l1),
        "lower": st.minimum,
        "upper": st.maximum,
        "argmin_round": st.argmin_round,
        "argmax_round": st.argmax_round,
        "percentiles": st.percentiles,
        "checkpoints": ck,
        "conv_lower": st.conv_minimum,
        "conv_upper": st.conv_maximum,
        "seconds": time.perf_counter() - t0,
        **_where(),
    }


def band_blocks(
    inputs: BandInputs,
    blocks: list[tuple[Any, ...]],
    max_chunk_bytes: float = 64e6,
    numba_threads: int | None = None,
) -> list[dict[str, Any]]:
    """:func:`band_block` of every ``(noise, target, rounds, frequency_dependent, seed,
    percentiles, l0, l1)`` of ``blocks`` (cases sharing ``inputs``), one after the other:
    one task for blocks too small to be a task each (each result exactly that of its own
    :func:`band_block`)."""
    out = []
    for noise, target, rounds, frequency_dependent, seed, percentiles, l0, l1 in blocks:
        out.append(
            band_block(
                inputs,
                noise,
                target,
                rounds,
                frequency_dependent,
                seed,
                percentiles,
                l0,
                l1,
                max_chunk_bytes,
                numba_threads,
            )  # fmt: skip
        )
    return out


BLOCK_KEYS: tuple[str, ...] = ("lower", "upper", "argmin_round", "argmax_round", "percentiles")
BLOCK_KEYS += ("conv_lower", "conv_upper")


def assemble_band(
    freq: Any,
    dofs: Sequence[str],
    reference: Any,
    YjjA: Any,
    vj: Any,
    YjjE: Any,
    YejE: Any,
    blocks: Sequence[dict[str, Any]],
    *,
    q: Any,
    noise: float,
    target: str,
    rounds: int,
    frequency_dependent: bool,
    seed: int,
    harmonic: Any,
) -> ScatterBand:
    """The :class:`~fbs_core.ScatterBand` of line blocks of :func:`band_block` (the one place
    blocks become a band: the campaign file's browser and the dashboard's cluster bands).

    ``blocks`` are dicts with the keys of :func:`band_block` (a statistic may be None when
    it was not stored), covering the lines ``0 .. n_f - 1`` in ascending order. Without
    percentiles they are NaN; without the convergence checkpoints the band edges are the one
    checkpoint (all rounds).

    Raises
    ------
    CampaignError
        When the blocks do not cover the lines or hold no band edges.
    SingularInterfaceError
        When an edge is not finite (as :func:`fbs_core.scatter_band`).
    """
    from ..errors import CampaignError, SingularInterfaceError
    from ..studies.band_kernel import kernel_arrays, target_name
    from ..studies.scatter import Convergence, ScatterBand

    blocks = sorted(blocks, key=lambda b: int(b["l0"]))
    nf = int(np.asarray(freq).size)
    ends = [0] + [int(b["l1"]) for b in blocks]
    if [int(b["l0"]) for b in blocks] != ends[:-1] or ends[-1] != nf:
        got = ", ".join(f"{b['l0']}..{b['l1']}" for b in blocks)
        raise CampaignError(f"line blocks [{got}] do not cover the {nf} lines once")
    if any(b.get("lower") is None for b in blocks):
        raise CampaignError("blocks hold no band edges ([outputs] scatter without 'band')")

    def cat(k: str, axis: int) -> Any:
        v = [b[k] for b in blocks if b.get(k) is not None]
        return None if len(v) < len(blocks) else np.concatenate(v, axis=axis)

    ne = len(dofs)
    qs = np.asarray(q, float)
    pct = cat("percentiles", 1)
    if pct is None:
        pct = np.full((qs.size, nf, ne), np.nan)
    clo, chi = cat("conv_lower", 1), cat("conv_upper", 1)
    ck = next((b["checkpoints"] for b in blocks if b.get("checkpoints") is not None), None)
    lo, hi = cat("lower", 0), cat("upper", 0)
    if clo is None or chi is None or ck is None:
        ck = np.array([rounds], np.int64)
        clo, chi = lo[None], hi[None]
    for what, x in (("upper edge", hi), ("lower edge", lo)):
        if not np.all(np.isfinite(x)):
            line = int(np.argwhere(~np.isfinite(x))[0][0])
            raise SingularInterfaceError(
                f"{what} of the scatter band is not finite at {freq[line]:g} Hz: the (noisy) "
                "interface matrix Y_jj^A + Y_jj^E is singular there"
            )
    return ScatterBand.of_kernel(
        kernel_arrays(YjjA, vj, YjjE, YejE),
        int(seed),
        freq=readonly(np.asarray(freq)),
        dofs=tuple(dofs),
        reference=readonly(np.asarray(reference)),
        minimum=readonly(lo),
        maximum=readonly(hi),
        argmin_round=readonly(cat("argmin_round", 0)),
        argmax_round=readonly(cat("argmax_round", 0)),
        q=readonly(qs),
        percentiles=readonly(pct),
        convergence=Convergence(readonly(np.asarray(ck)), readonly(clo), readonly(chi)),
        noise=float(noise),
        target=target_name(str(target), warn=False),  # "vehicle" in older files
        rounds=int(rounds),
        frequency_dependent=bool(frequency_dependent),
        harmonic=None if harmonic is None else int(harmonic),
    )


def truncation_case(tire: Any, chassis: Any, case: TruncationCase) -> dict[str, Any]:
    """Error map (eq. 5.1) and suggested mode counts (table 5.1) of a
    :class:`~fbs_core.campaign.spec.TruncationCase`.

    Returns
    -------
    dict
        ``n_modes``, ``n_modes_total``, ``centres``, ``dofs``, ``error`` ``(n_N, n_c, n_e)``,
        ``suggested`` ``(n_threshold, n_fmax)`` (max over DOFs), ``freq``, ``response``
        ``(n_N, n_f, n_e)``, ``reference`` ``(n_f, n_e)`` and the provenance of the run.
    """
    from ..studies import _models
    from ..studies.truncation import truncation_map

    t0 = time.perf_counter()
    tire = resolve_model("tire", tire)
    f = _models.resolve_harmonic(case.harmonic).frequencies(case.df)
    m = truncation_map(
        case.harmonic,
        np.asarray(case.n_modes, int),
        freq=f,
        width=case.width,
        step=case.step,
        tire=tire,
        chassis=chassis_on(chassis, f),
        coupling=case.coupling,
    )
    sugg = np.array([[m.suggest(t, fm) for fm in case.f_max] for t in case.thresholds], np.int64)
    assert m.n_modes_total is not None  # truncation_map always sets it
    return {
        "n_modes": np.asarray(m.n_modes),
        "n_modes_total": int(m.n_modes_total),
        "centres": np.asarray(m.centres),
        "dofs": tuple(m.dofs),
        "error": np.asarray(m.error),
        "suggested": sugg,
        "freq": np.asarray(m.freq),
        "response": np.asarray(m.response),
        "reference": np.asarray(m.reference),
        "width": m.width,
        "step": m.step,
        "edges": m.edges,
        "seconds": time.perf_counter() - t0,
        **_where(),
    }
