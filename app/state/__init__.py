"""Dashboard state: one :class:`param.Parameterized` class per concern.

The widgets are generated from these parameters (``Widget.from_param``); the views watch
only the parameters they depend on. Everything here is plain state: no numerics (those live
in :mod:`fbs_core`, reached through :mod:`app.compute`).
"""

from __future__ import annotations

import param

from fbs_core.vehicle import RESPONSE_NODES, WHEELS
from fbs_core.vocabulary import COUPLINGS, DIRECTIONS

from ..datasource import REFERENCE, DataSource, Models
from ..page.layout import PageState
from ..review import EMPTY_REVIEW, Review
from ..schema import Schema, setting
from .analysis import AnalysisState
from .campaign import CampaignState, campaign_dir
from .params import Integer, Number

__all__ = [
    "DIRECTIONS",
    "COUPLINGS",
    "MODE_COUNTS",
    "MAP_MODES",
    "NOISE_TARGETS",
    "SCOPES",
    "TRACK_RELATIONS",
    "VEHICLE_ROUNDS",
    "WHEELS",
    "RESPONSE_NODES",
    "CaseState",
    "NoiseState",
    "TruncationState",
    "ResponsePlotState",
    "CampaignState",
    "DashboardState",
    "URL_KEYS",
    "SCHEMA",
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
#: What is coupled: the thesis' rear corner (one tire) or the whole car (four tires).
SCOPES = ("corner", "vehicle")
#: How the right track's road relates to the left one's (docs/vehicle-model.md, "The road as
#: each wheel sees it"): in phase (coherency 1), anti-phase (-1) or a coherency in [-1, 1].
TRACK_RELATIONS = ("in phase", "anti-phase", "coherence")
#: Default rounds of the scatter band: a car's band costs ~33x a corner's per round (a dense
#: 24 x 24 interface per round, docs/vehicle-model.md "Speed"), so vehicle scope starts at
#: fewer rounds (the scope switch moves a default count to the other scope's default).
CORNER_ROUNDS = 10_000
VEHICLE_ROUNDS = 1_000


class _WheelsSelector(param.ListSelector):
    """The wheels whose road input is on: a list of distinct names of ``WHEELS``, kept in
    their order (a link's repeated or unknown name, or a value that is not a list, is
    refused like any other value out of range)."""

    def __set__(self, obj: object, val: object) -> None:
        if isinstance(val, list | tuple):
            if len(set(val)) != len(val) or not all(isinstance(w, str) for w in val):
                raise ValueError(
                    f"wheels must be distinct names among {', '.join(WHEELS)}, got {val!r}"
                )
            val = [w for w in WHEELS if w in val] + [w for w in val if w not in WHEELS]
        super().__set__(obj, val)


class _TargetSelector(param.Selector):
    """The noise target; an old name (:data:`RENAMED_TARGETS`) is set as its new one."""

    def __set__(self, obj: object, val: object) -> None:
        super().__set__(obj, RENAMED_TARGETS.get(val, val) if isinstance(val, str) else val)


class CaseState(param.Parameterized):
    """The prediction case: harmonic, retained tire modes, response DOF, hub coupling."""

    harmonic = Integer(
        metadata=setting("h", "harmonic case 1-7"),
        default=1,
        bounds=(1, 7),
        doc="Harmonic excitation case (thesis fig. 4.4).",
    )
    n_modes = param.Selector(
        metadata=setting("N", "retained tire modes N"),
        default=50,
        objects=list(MODE_COUNTS),
        doc="Retained complex tire modes N, 10-400 in steps of 10 (in +/- pairs: N/2 "
        "physical modes, lowest first; thesis 5.1).",
    )
    dof = param.Selector(
        metadata=setting("dof", "response DOF direction at the bushing"),
        default="z",
        objects=list(DIRECTIONS),
        doc="Response DOF at the bushing.",
    )
    coupling = param.Selector(
        metadata=setting("coupling", "hub coupling"),
        default="6dof",
        objects=list(COUPLINGS),
        doc="Couple all 6 hub DOFs (braked wheel) or 5 with the spin (ry) released.",
    )
    show_uncoupled = param.Boolean(
        metadata=setting("uncoupled", "uncoupled subsystems shown"),
        default=False,
        doc="Also show the uncoupled tire (hub) and chassis FRFs.",
    )
    spindle_input = param.Selector(
        metadata=setting("input", "spindle input of the uncoupled chassis mobility"),
        default="z",
        objects=list(DIRECTIONS),
        doc="Spindle input DOF of the uncoupled chassis spindle-to-bushing mobility.",
    )
    residual = param.Boolean(
        metadata=setting("res", "residual compensation of the tire modes left out of N"),
        default=False,
        doc="Residual compensation: the tire modes left out of N still enter with their "
        "quasi-static part (upper residual flexibility, docs/tire-model.md); acts on the "
        "coupled response, the error map and the suggested N it marks.",
    )
    scope = param.Selector(
        metadata=setting(
            "scope", "corner (the thesis' tire on the rear corner) or vehicle (the whole car)"
        ),
        default="corner",
        objects=list(SCOPES),
        doc="Corner: the thesis' tire on the rear corner. Vehicle: the reference car with the "
        "tire on all four wheels (docs/vehicle-model.md).",
    )
    wheels = _WheelsSelector(
        metadata=setting(
            "wheels", "vehicle scope: the wheels whose road input is on", vehicle=True
        ),
        default=list(WHEELS),
        objects=list(WHEELS),
        doc="Vehicle scope: the wheels whose road input is on (the others still carry their tire).",
    )
    tracks = param.Selector(
        metadata=setting(
            "tracks", "vehicle scope: the right track's road against the left's", vehicle=True
        ),
        default="in phase",
        objects=list(TRACK_RELATIONS),
        doc="Vehicle scope: the right track's road against the left's: in phase, in "
        "anti-phase, or partially coherent (the coherence value).",
    )
    coherence = Number(
        metadata=setting("coh", "vehicle scope: coherency of the two tracks", vehicle=True),
        default=0.5,
        bounds=(-1.0, 1.0),
        step=0.05,
        doc="Vehicle scope: coherency of the two tracks when the relation is 'coherence' "
        "(1 in phase, -1 anti-phase, 0 independent).",
    )
    point = param.Selector(
        metadata=setting("point", "vehicle scope: the car's response point", vehicle=True),
        default="bushing_rl",
        objects=list(RESPONSE_NODES),
        doc="Vehicle scope: the response point (six DOFs; the response DOF picks one). "
        "bushing_rl is the thesis' bushing on the car.",
    )
    models = param.ClassSelector(
        metadata=setting(None),
        class_=Models,
        default=REFERENCE,
        instantiate=False,
        precedence=-1,
        doc="The session's tire and chassis (uploads or the reference), mirrored from "
        "DashboardState.data; not a control and not in the URL.",
    )
    review = param.ClassSelector(
        metadata=setting(None),
        class_=Review,
        default=EMPTY_REVIEW,
        instantiate=False,
        precedence=-1,
        doc="The session's review (tire candidates, targets, incumbent rule), mirrored from "
        "DashboardState.data; not a control and not in the URL.",
    )


class NoiseState(param.Parameterized):
    """Monte-Carlo noise study settings (thesis section 5.2)."""

    noise = Number(
        metadata=setting("noise", "noise level p in %"),
        default=10.0,
        bounds=(0.0, MAX_NOISE_PCT),
        softbounds=(0.0, 10.0),
        step=0.1,
        doc="Noise level p in percent: scaling factors uniform in [1-p, 1+p] "
        "(below 100 %: a factor must stay positive, as fbs_core.scatter_band requires).",
    )
    target = _TargetSelector(
        metadata=setting("target", "subsystem(s) with noise"),
        default="both",
        objects=list(NOISE_TARGETS),
        doc="Subsystem(s) that get noise.",
    )
    frequency_dependent = param.Boolean(
        metadata=setting("fdep", "new scaling matrix at every line"),
        default=False,
        doc="New scaling matrix at every frequency line (else one per round).",
    )
    rounds = Integer(
        metadata=setting("rounds", "Monte-Carlo rounds R"),
        default=CORNER_ROUNDS,
        bounds=(1, 200_000),
        doc="Number of Monte-Carlo rounds R.",
    )
    seed = Integer(
        metadata=setting("seed", "random seed"),
        default=0,
        bounds=(0, MAX_SEED),
        doc="Random seed of the study (up to 2**32 - 1: exact in a browser's numbers).",
    )
    single_round = Integer(
        metadata=setting("round", "index of the single round drawn"),
        default=0,
        bounds=(0, 200_000 - 1),
        doc="Index of the single polluted round drawn inside the band (0-based).",
    )
    percentile = param.Selector(
        metadata=setting("pct", "width of the central percentile band in %"),
        default=90,
        objects=[50, 80, 90, 95, 99],
        doc="Width of the central percentile band in percent (90 -> 5-95 %).",
    )
    first_order = param.Boolean(
        metadata=setting("fo", "first-order band overlaid on the scatter band"),
        default=False,
        doc="Overlay the first-order (linearised) band of the same noise on the scatter "
        "band: |v| +- k std with k the Gaussian quantile of the central percentile band "
        "(docs/corridor.md section 6; computed only while shown).",
    )
    verdict_band = param.Boolean(
        metadata=setting("vband", "verdict judged with the noise band's upper edge"),
        default=False,
        doc="Judge the review's verdict with the noise band too: a scatter band of these "
        "noise settings for every candidate and harmonic (all modes), whose upper edge of "
        "the central percentile band crossing a target makes 'fails within the noise band' "
        "(docs/verdict.md).",
    )

    @param.depends("rounds", watch=True, on_init=True)
    def _clip_single_round(self):
        # the single round must exist in the batch
        self.param.single_round.bounds = (0, max(self.rounds - 1, 0))
        if self.single_round > self.rounds - 1:
            self.single_round = self.rounds - 1


class TruncationState(param.Parameterized):
    """Truncation study settings (thesis section 5.1)."""

    threshold = Number(
        metadata=setting("thr", "error threshold in %"),
        default=20.0,
        bounds=(0.1, 1000.0),
        softbounds=(1.0, 50.0),
        step=1.0,
        doc="Error threshold in percent: colour cap of the map and criterion of the table.",
    )
    f_max = Number(
        metadata=setting("fmax", "upper frequency of the suggested N in Hz"),
        default=160.0,
        bounds=(1.0, 1000.0),
        softbounds=(50.0, 450.0),
        step=10.0,
        doc="Upper frequency in Hz for the suggested number of modes (table 5.1).",
    )
    map_mode = param.Selector(
        metadata=setting("map", "error map of the selected DOF or the maximum over 6 DOFs"),
        default=MAP_MODES[0],
        objects=list(MAP_MODES),
        doc="Error map of the selected DOF (fig. 5.3/5.7) or the maximum over 6 DOFs (fig. 5.6).",
    )


#: Level axes of the coupled-response plot: dB (a logarithmic level) or the magnitude.
LEVEL_SCALES = ("dB", "linear")


class ResponsePlotState(param.Parameterized):
    """The coupled-response plot as in a test lab's FRF display: DOFs overlaid, the level
    axis, two labelled cursors with a readout."""

    overlay = param.ListSelector(
        metadata=setting("over"),
        default=[],
        objects=list(DIRECTIONS),
        doc="Further bushing DOFs overlaid on the coupled response (their curves with N "
        "modes); the selected DOF is always shown.",
    )
    level_scale = param.Selector(
        metadata=setting("lvl"),
        default="dB",
        objects=list(LEVEL_SCALES),
        doc="Level axis: dB (20 log10 |v|) or the magnitude |v| on a linear axis.",
    )
    cursor1 = Number(
        metadata=setting("mc1", field="mcursor1"),
        default=0.0,
        bounds=(0.0, 1000.0),
        doc="Cursor 1 on the coupled response in Hz (0: off).",
    )
    cursor2 = Number(
        metadata=setting("mc2", field="mcursor2"),
        default=0.0,
        bounds=(0.0, 1000.0),
        doc="Cursor 2 on the coupled response in Hz (0: off).",
    )
    snap = param.Boolean(
        metadata=setting("snap"),
        default=False,
        doc="The cursors snap to the nearest peak of the selected DOF's curve with N modes.",
    )


class DashboardState(param.Parameterized):
    """All state of one browser session."""

    case = param.ClassSelector(class_=CaseState, instantiate=False)
    noise = param.ClassSelector(class_=NoiseState, instantiate=False)
    truncation = param.ClassSelector(class_=TruncationState, instantiate=False)
    analysis = param.ClassSelector(
        class_=AnalysisState, instantiate=False, doc="The Analysis card."
    )
    plot = param.ClassSelector(
        class_=ResponsePlotState,
        instantiate=False,
        doc="The coupled-response plot's overlays, level axis and cursors.",
    )
    data = param.ClassSelector(
        class_=DataSource,
        instantiate=False,
        doc="This session's uploads (never shared between sessions).",
    )
    campaign = param.ClassSelector(
        class_=CampaignState,
        instantiate=False,
        doc="The campaign card's file and case (the folder: the server's FBS_CAMPAIGN_DIR).",
    )

    def __init__(self, **params):
        params.setdefault("case", CaseState())
        params.setdefault("noise", NoiseState())
        params.setdefault("truncation", TruncationState())
        params.setdefault("data", DataSource())
        params.setdefault("analysis", AnalysisState())
        params.setdefault("plot", ResponsePlotState())
        if "campaign" not in params:
            params["campaign"] = CampaignState(directory=campaign_dir())
        super().__init__(**params)
        self.case.param.update(models=self.data.models, review=self.data.review)
        self.data.param.watch(self._use_models, ["models", "review"])
        self.case.param.watch(self._scope_rounds, "scope")

    def _scope_rounds(self, event):
        # a scope's default round count follows the scope (a count the user chose stays)
        defaults = {"corner": CORNER_ROUNDS, "vehicle": VEHICLE_ROUNDS}
        if self.noise.rounds == defaults.get(event.old):
            self.noise.rounds = defaults[event.new]

    def _use_models(self, *events):
        # the models and the review change together (one pass of the store)
        self.case.param.update(models=self.data.models, review=self.data.review)


#: The dashboard's settings, each declared once on its parameter (``metadata=setting(...)``):
#: the link's keys, the snapshot's fields and the report's settings table are derived here.
SCHEMA = Schema(
    {
        "case": CaseState,
        "noise": NoiseState,
        "truncation": TruncationState,
        "analysis": AnalysisState,
        "plot": ResponsePlotState,
        "campaign": CampaignState,
    },
    page={"page": PageState},
)
#: URL query keys of each state parameter (short, stable: links are shared in reviews).
URL_KEYS: dict[str, dict[str, str]] = SCHEMA.url_keys
