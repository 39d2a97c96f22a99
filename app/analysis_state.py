"""State of the "Analysis" card (issue 18): which tab is shown, the phase view's options,
the delta cursors, the picked speed and frequency, and the pinned baselines.

Plain state (no numerics), one :class:`AnalysisState` per session, held by the session's
:class:`~app.state.DashboardState` as ``state.analysis`` and kept in the URL
(``URL_KEYS["analysis"]``). The pins are in the URL as their *settings* (a pin's data are
recomputed from them in a new session; pins of uploaded data only where the same upload is
loaded), see :func:`encode_pins` / :func:`decode_pins`.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import param

from fbs_core.errors import FBSError

__all__ = [
    "ANALYSIS_TABS",
    "AnalysisState",
    "PinSettings",
    "decode_pins",
    "encode_pins",
]

#: The tabs of the Analysis card ("": the card is collapsed, nothing is computed).
ANALYSIS_TABS = ("", "compare", "phase", "speed", "contributions")
#: FRFs of the phase view.
PHASE_FRFS = ("coupled", "tire", "chassis")
#: Phase view: magnitude and phase, or real and imaginary parts.
PHASE_MODES = ("bode", "real/imag")
#: Contributions drawn as levels of each term, or as stacked shares of the total.
CONTRIBUTION_MODES = ("lines", "stacked")
#: A pin's name: letters, digits, space, ``_.-+``, 1-24 characters (it travels in the URL).
PIN_NAME = re.compile(r"^[A-Za-z0-9 _.+-]{1,24}$")


class AnalysisState(param.Parameterized):
    """Settings of the Analysis card (one per session)."""

    tab = param.Selector(
        default="",
        objects=list(ANALYSIS_TABS),
        doc="Tab shown ('' while the card is collapsed): only its results are computed.",
    )
    frf = param.Selector(
        default="coupled",
        objects=list(PHASE_FRFS),
        doc="FRF of the phase view: coupled bushing response (eq. 4.1), the tire's free "
        "hub velocity, or the chassis spindle-to-bushing mobility.",
    )
    phase_mode = param.Selector(
        default="bode", objects=list(PHASE_MODES), doc="Magnitude/phase or real/imaginary."
    )
    log_freq = param.Boolean(default=False, doc="Logarithmic frequency axis (phase view).")
    cursor1 = param.Number(default=0.0, bounds=(0.0, 1000.0), doc="Delta cursor 1 in Hz (0: off).")
    cursor2 = param.Number(default=0.0, bounds=(0.0, 1000.0), doc="Delta cursor 2 in Hz (0: off).")
    picked_speed = param.Number(
        default=0.0, bounds=(0.0, 300.0), doc="Speed picked in the speed views, km/h (0: none)."
    )
    picked_freq = param.Number(
        default=0.0, bounds=(0.0, 1000.0), doc="Frequency picked in a view, Hz (0: none)."
    )
    contrib_mode = param.Selector(
        default="lines", objects=list(CONTRIBUTION_MODES), doc="Contributions as lines or stacked."
    )
    pins = param.String(
        default="",
        doc="Pinned baselines as settings (encode_pins); their data live in the results.",
    )
    compare_to = param.String(
        default="", doc="Pin the difference map is taken against ('': the first pin)."
    )


@dataclass(frozen=True)
class PinSettings:
    """What a pin in the URL says: its name and the state it was pinned in."""

    name: str
    harmonic: int
    n_modes: int
    dof: str
    coupling: str
    noise: float
    target: str
    frequency_dependent: bool
    rounds: int
    seed: int
    percentile: int
    models: str  # "reference" or the session models' key (an upload's digest)

    def encode(self) -> str:
        return "~".join(
            [
                self.name,
                f"h{self.harmonic}",
                f"N{self.n_modes}",
                f"d{self.dof}",
                f"c{self.coupling}",
                f"p{self.noise:g}",
                f"t{self.target}",
                f"f{int(self.frequency_dependent)}",
                f"R{self.rounds}",
                f"s{self.seed}",
                f"q{self.percentile}",
                f"m{self.models}",
            ]
        )


_FIELDS: dict[str, tuple[str, Callable[[str], Any]]] = {
    "h": ("harmonic", int),
    "N": ("n_modes", int),
    "d": ("dof", str),
    "c": ("coupling", str),
    "p": ("noise", float),
    "t": ("target", str),
    "f": ("frequency_dependent", lambda s: bool(int(s))),
    "R": ("rounds", int),
    "s": ("seed", int),
    "q": ("percentile", int),
    "m": ("models", str),
}


def check_pin_name(name: str) -> str:
    """The name stripped, or :class:`FBSError` naming the allowed characters."""
    name = str(name).strip()
    if not PIN_NAME.match(name):
        raise FBSError(f"a pin name has 1-24 letters, digits, spaces or _.+- ; got {name!r}")
    return name


def encode_pins(pins) -> str:
    """The URL value of pins' settings (``|`` between pins, ``~`` between fields)."""
    return "|".join(p.encode() for p in pins)


def decode_pins(text: str) -> tuple[PinSettings, ...]:
    """Pins' settings from :func:`encode_pins` text.

    Raises
    ------
    FBSError
        For a malformed entry (naming it); nothing is evaluated.
    """
    out = []
    for entry in [e for e in str(text).split("|") if e]:
        parts = entry.split("~")
        try:
            name = check_pin_name(parts[0])
            kw = {}
            for part in parts[1:]:
                field, conv = _FIELDS[part[0]]
                kw[field] = conv(part[1:])
            if set(kw) != {f for f, _ in _FIELDS.values()}:
                raise KeyError("fields")
            out.append(PinSettings(name=name, **kw))
        except (KeyError, ValueError, IndexError) as e:
            raise FBSError(f"malformed pin {entry!r} in the link ({e})") from None
    return tuple(out)
