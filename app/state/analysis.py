"""State of the "Analysis" card: which tab is shown, the phase view's options,
the delta cursors, the picked speed and frequency, and the pinned baselines.

Plain state (no numerics), one :class:`AnalysisState` per session, held by the session's
:class:`~app.state.DashboardState` as ``state.analysis`` and kept in the URL
(``URL_KEYS["analysis"]``). The pins are in the URL as their *settings* (a pin's data are
recomputed from them in a new session; pins of uploaded data only where the same upload is
loaded), see :mod:`app.state.pins`.
"""

from __future__ import annotations

import param

from ..schema import setting
from .params import Integer, Number

__all__ = ["ANALYSIS_TABS", "AnalysisState"]

#: The tabs of the Analysis card ("": the card is collapsed, nothing is computed).
ANALYSIS_TABS = ("", "compare", "phase", "speed", "contributions", "modes", "selection")
#: FRFs of the phase view.
PHASE_FRFS = ("coupled", "tire", "chassis")
#: Phase view: magnitude and phase, or real and imaginary parts.
PHASE_MODES = ("bode", "real/imag")
#: Contributions drawn as levels of each term, or as stacked shares of the total.
CONTRIBUTION_MODES = ("lines", "stacked")
#: Measures the participation ranking is sorted by (fbs_core.analysis.participation.RANKINGS).
MODE_RANKINGS = ("loo", "loo_floating", "share", "level", "loo_direct")
#: Largest stored mode pair index a link may name (the tire's own count is checked when used).
MAX_MODE_PAIR = 4999


class AnalysisState(param.Parameterized):
    """Settings of the Analysis card (one per session)."""

    tab = param.Selector(
        metadata=setting("atab"),
        default="",
        objects=list(ANALYSIS_TABS),
        doc="Tab shown ('' while the card is collapsed): only its results are computed.",
    )
    frf = param.Selector(
        metadata=setting("afrf"),
        default="coupled",
        objects=list(PHASE_FRFS),
        doc="FRF of the phase view: coupled bushing response (eq. 4.1), the tire's free "
        "hub velocity, or the chassis spindle-to-bushing mobility.",
    )
    phase_mode = param.Selector(
        metadata=setting("aphase"),
        default="bode",
        objects=list(PHASE_MODES),
        doc="Magnitude/phase or real/imaginary.",
    )
    log_freq = param.Boolean(
        metadata=setting("alog"), default=False, doc="Logarithmic frequency axis (phase view)."
    )
    cursor1 = Number(
        metadata=setting("c1"),
        default=0.0,
        bounds=(0.0, 1000.0),
        doc="Delta cursor 1 in Hz (0: off).",
    )
    cursor2 = Number(
        metadata=setting("c2"),
        default=0.0,
        bounds=(0.0, 1000.0),
        doc="Delta cursor 2 in Hz (0: off).",
    )
    picked_speed = Number(
        metadata=setting("pv"),
        default=0.0,
        bounds=(0.0, 300.0),
        doc="Speed picked in the speed views, km/h (0: none).",
    )
    picked_freq = Number(
        metadata=setting("pf"),
        default=0.0,
        bounds=(0.0, 1000.0),
        doc="Frequency picked in a view, Hz (0: none).",
    )
    contrib_mode = param.Selector(
        metadata=setting("acontrib"),
        default="lines",
        objects=list(CONTRIBUTION_MODES),
        doc="Contributions as lines or stacked.",
    )
    pins = param.String(
        metadata=setting("pins", field="pin_text"),
        default="",
        doc="Pinned baselines as settings (app.state.pins.encode_pins); their data live in "
        "the results.",
    )
    compare_to = param.String(
        metadata=setting("cmp"),
        default="",
        doc="Pin the difference map is taken against ('': the first pin).",
    )
    mode_pick = Integer(
        metadata=setting("mode"),
        default=-1,
        bounds=(-1, MAX_MODE_PAIR),
        doc="Tire mode drawn in the Modes tab: its stored pair index (-1: the mode at the top "
        "of the participation ranking).",
    )
    mode_speed = Number(
        metadata=setting("mv"),
        default=0.0,
        bounds=(0.0, 300.0),
        doc="Speed (km/h) the mode shape is drawn at (0: where the harmonic line meets the "
        "mode in the band).",
    )
    mode_rank = param.Selector(
        metadata=setting("mrank"),
        default="loo",
        objects=list(MODE_RANKINGS),
        doc="Measure of the participation ranking: leave-one-out error (both paths), the same "
        "over the floating band, band share, level, or the direct path alone.",
    )
    waves_all = param.Boolean(
        metadata=setting("wall"),
        default=False,
        doc="Campbell diagram of the waves: every branch (else the readable default: the "
        "branches in the harmonic's band of the orders that carry its response).",
    )
