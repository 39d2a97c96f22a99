"""Dashboard state: one :class:`param.Parameterized` class per concern.

The widgets are generated from these parameters (``Widget.from_param``); the views watch
only the parameters they depend on. Everything here is plain state: no numerics (those live
in :mod:`fbs_core`, reached through :mod:`app.compute`).
"""

from __future__ import annotations

import param

from fbs_core.vocabulary import COUPLINGS, DIRECTIONS

from .analysis_state import AnalysisState
from .datasource import REFERENCE, DataSource, Models

__all__ = [
    "DIRECTIONS",
    "COUPLINGS",
    "MODE_COUNTS",
    "MAP_MODES",
    "NOISE_TARGETS",
    "CaseState",
    "NoiseState",
    "TruncationState",
    "DashboardState",
    "URL_KEYS",
]

#: Where the Monte-Carlo noise is applied (thesis eqs. 5.2-5.4).
NOISE_TARGETS = ("both", "tire", "chassis")  # fbs_core.studies.scatter.TARGETS
#: Old names of targets (links made before the rename still open on the same state).
RENAMED_TARGETS = {"vehicle": "chassis"}
#: Retained-mode counts offered (thesis 5.1: 10 to 400 in steps of 10).
MODE_COUNTS = tuple(range(10, 401, 10))
#: Largest noise level in percent (fbs_core.scatter_band needs p < 1, two decimals here).
MAX_NOISE_PCT = 99.99
#: Largest seed offered (exact as a JavaScript number; fbs_core takes up to 2**64 - 1).
MAX_SEED = 2**32 - 1
#: What the truncation error map shows.
MAP_MODES = ("selected DOF", "max over 6 DOFs")


class _TargetSelector(param.Selector):
    """The noise target; an old name (:data:`RENAMED_TARGETS`) is set as its new one."""

    def __set__(self, obj: object, val: object) -> None:
        super().__set__(obj, RENAMED_TARGETS.get(val, val) if isinstance(val, str) else val)


class CaseState(param.Parameterized):
    """The prediction case: harmonic, retained tire modes, response DOF, hub coupling."""

    harmonic = param.Integer(
        default=1, bounds=(1, 7), doc="Harmonic excitation case (thesis fig. 4.4)."
    )
    n_modes = param.Selector(
        default=50,
        objects=list(MODE_COUNTS),
        doc="Retained complex tire modes N, 10-400 in steps of 10 (in +/- pairs: N/2 "
        "physical modes, lowest first; thesis 5.1).",
    )
    dof = param.Selector(default="z", objects=list(DIRECTIONS), doc="Response DOF at the bushing.")
    coupling = param.Selector(
        default="6dof",
        objects=list(COUPLINGS),
        doc="Couple all 6 hub DOFs (braked wheel) or 5 with the spin (ry) released.",
    )
    show_uncoupled = param.Boolean(
        default=False, doc="Also show the uncoupled tire (hub) and chassis FRFs."
    )
    spindle_input = param.Selector(
        default="z",
        objects=list(DIRECTIONS),
        doc="Spindle input DOF of the uncoupled chassis spindle-to-bushing mobility.",
    )
    residual = param.Boolean(
        default=False,
        doc="Residual compensation: the tire modes left out of N still enter with their "
        "quasi-static part (upper residual flexibility, docs/tire-model.md); acts on the "
        "coupled response, the error map and the suggested N it marks.",
    )
    models = param.ClassSelector(
        class_=Models,
        default=REFERENCE,
        instantiate=False,
        precedence=-1,
        doc="The session's tire and chassis (uploads or the reference), mirrored from "
        "DashboardState.data; not a control and not in the URL.",
    )


class NoiseState(param.Parameterized):
    """Monte-Carlo noise study settings (thesis section 5.2)."""

    noise = param.Number(
        default=10.0,
        bounds=(0.0, MAX_NOISE_PCT),
        softbounds=(0.0, 10.0),
        step=0.1,
        doc="Noise level p in percent: scaling factors uniform in [1-p, 1+p] "
        "(below 100 %: a factor must stay positive, as fbs_core.scatter_band requires).",
    )
    target = _TargetSelector(
        default="both", objects=list(NOISE_TARGETS), doc="Subsystem(s) that get noise."
    )
    frequency_dependent = param.Boolean(
        default=False,
        doc="New scaling matrix at every frequency line (else one per round).",
    )
    rounds = param.Integer(
        default=10_000,
        bounds=(1, 200_000),
        doc="Number of Monte-Carlo rounds R.",
    )
    seed = param.Integer(
        default=0,
        bounds=(0, MAX_SEED),
        doc="Random seed of the study (up to 2**32 - 1: exact in a browser's numbers).",
    )
    single_round = param.Integer(
        default=0,
        bounds=(0, 200_000 - 1),
        doc="Index of the single polluted round drawn inside the band (0-based).",
    )
    percentile = param.Selector(
        default=90,
        objects=[50, 80, 90, 95, 99],
        doc="Width of the central percentile band in percent (90 -> 5-95 %).",
    )

    @param.depends("rounds", watch=True, on_init=True)
    def _clip_single_round(self):
        # the single round must exist in the batch
        self.param.single_round.bounds = (0, max(self.rounds - 1, 0))
        if self.single_round > self.rounds - 1:
            self.single_round = self.rounds - 1


class TruncationState(param.Parameterized):
    """Truncation study settings (thesis section 5.1)."""

    threshold = param.Number(
        default=20.0,
        bounds=(0.1, 1000.0),
        softbounds=(1.0, 50.0),
        step=1.0,
        doc="Error threshold in percent: colour cap of the map and criterion of the table.",
    )
    f_max = param.Number(
        default=160.0,
        bounds=(1.0, 1000.0),
        softbounds=(50.0, 450.0),
        step=10.0,
        doc="Upper frequency in Hz for the suggested number of modes (table 5.1).",
    )
    map_mode = param.Selector(
        default=MAP_MODES[0],
        objects=list(MAP_MODES),
        doc="Error map of the selected DOF (fig. 5.3/5.7) or the maximum over 6 DOFs (fig. 5.6).",
    )


class DashboardState(param.Parameterized):
    """All state of one browser session."""

    case = param.ClassSelector(class_=CaseState, instantiate=False)
    noise = param.ClassSelector(class_=NoiseState, instantiate=False)
    truncation = param.ClassSelector(class_=TruncationState, instantiate=False)
    analysis = param.ClassSelector(
        class_=AnalysisState, instantiate=False, doc="The Analysis card (issue 18)."
    )
    data = param.ClassSelector(
        class_=DataSource,
        instantiate=False,
        doc="This session's uploads (never shared between sessions).",
    )

    def __init__(self, **params):
        params.setdefault("case", CaseState())
        params.setdefault("noise", NoiseState())
        params.setdefault("truncation", TruncationState())
        params.setdefault("data", DataSource())
        params.setdefault("analysis", AnalysisState())
        super().__init__(**params)
        self.case.models = self.data.models
        self.data.param.watch(self._use_models, "models")

    def _use_models(self, event):
        self.case.models = event.new


#: URL query keys of each state parameter (short, stable: links are shared in reviews).
URL_KEYS: dict[str, dict[str, str]] = {
    "case": {
        "harmonic": "h",
        "n_modes": "N",
        "dof": "dof",
        "coupling": "coupling",
        "show_uncoupled": "uncoupled",
        "spindle_input": "input",
        "residual": "res",
    },
    "noise": {
        "noise": "noise",
        "target": "target",
        "frequency_dependent": "fdep",
        "rounds": "rounds",
        "seed": "seed",
        "single_round": "round",
        "percentile": "pct",
    },
    "truncation": {"threshold": "thr", "f_max": "fmax", "map_mode": "map"},
    "analysis": {
        "tab": "atab",
        "frf": "afrf",
        "phase_mode": "aphase",
        "log_freq": "alog",
        "cursor1": "c1",
        "cursor2": "c2",
        "picked_speed": "pv",
        "picked_freq": "pf",
        "contrib_mode": "acontrib",
        "pins": "pins",
        "compare_to": "cmp",
    },
}
