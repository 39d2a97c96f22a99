"""The pins of the link: a pinned baseline's name and the settings it was pinned in.

A pin travels in the URL as its *settings* (``AnalysisState.pins``, written by
:func:`encode_pins`); a new session recomputes its data from them (pins of uploaded data only
where the same upload is loaded). What a link may say is checked against the controls' own
definitions (:mod:`app.state`), and every refusal names the value it refused.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from fbs_core.errors import FBSError

from . import CaseState, NoiseState

__all__ = ["PIN_NAME", "PinSettings", "check_pin_name", "decode_pins", "encode_pins", "shown"]

#: A pin's name: letters, digits, space, ``_.-+``, 1-24 characters (it travels in the URL).
PIN_NAME = re.compile(r"^[A-Za-z0-9 _.+-]{1,24}$")


@dataclass(frozen=True)
class PinSettings:
    """What a pin in the URL says: its name and the state it was pinned in."""

    name: str
    harmonic: int
    n_modes: int
    dof: str
    coupling: str
    residual: bool
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
                f"r{int(self.residual)}",
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
    "r": ("residual", lambda s: {"0": False, "1": True}[s]),
    "p": ("noise", float),
    "t": ("target", str),
    "f": ("frequency_dependent", lambda s: {"0": False, "1": True}[s]),
    "R": ("rounds", int),
    "s": ("seed", int),
    "q": ("percentile", int),
    "m": ("models", str),
}
#: A models key in a pin: the reference, or the digests of the uploads (app.datasource).
MODELS_KEY = re.compile(
    r"^(reference|tire=(reference|[0-9a-f]{8,64});chassis=(reference|[0-9a-f]{8,64}))$"
)
#: Characters a message repeats of a link's value as they are (others as \xNN escapes).
_SHOWN = re.compile(r"[^A-Za-z0-9 _.,:;=+~|-]")
#: Most characters of a link's value a message repeats.
_SHOWN_CHARS = 80


def shown(text: str) -> str:
    """A value of the link, quoted for a message: at most 80 characters, and every character
    that could be markup in a page (``<``, ``&``, quotes, brackets, ...) written as an escape
    (``\\x3c``), so the message is plain text wherever it is shown."""
    text = str(text)
    cut = text[:_SHOWN_CHARS]
    out = _SHOWN.sub(lambda m: f"\\x{ord(m.group()):02x}" if ord(m.group()) < 256 else "?", cut)
    return "'" + out + ("..." if len(text) > _SHOWN_CHARS else "") + "'"


def _allowed() -> dict[str, tuple[Callable[[Any], bool], str]]:
    """field -> (check, what is allowed), from the controls' own definitions (app.state)."""
    import math

    case, noise = CaseState.param, NoiseState.param

    def within(p) -> Callable[[Any], bool]:
        lo, hi = p.bounds
        return lambda v: lo <= v <= hi and math.isfinite(v)

    def one_of(p) -> tuple[Callable[[Any], bool], str]:
        objects = list(p.objects)
        listed = objects if len(objects) <= 8 else [*objects[:2], "...", objects[-1]]
        return (lambda v: v in objects), ", ".join(map(str, listed))

    def bounds(p) -> str:
        return f"{p.bounds[0]:g} to {p.bounds[1]:g}"

    return {
        "harmonic": (within(case.harmonic), bounds(case.harmonic)),
        "n_modes": one_of(case.n_modes),
        "dof": one_of(case.dof),
        "coupling": one_of(case.coupling),
        "noise": (within(noise.noise), f"{bounds(noise.noise)} (percent)"),
        "target": one_of(noise.target),
        "residual": ((lambda v: isinstance(v, bool)), "0 or 1"),
        "frequency_dependent": ((lambda v: isinstance(v, bool)), "0 or 1"),
        "rounds": (within(noise.rounds), bounds(noise.rounds)),
        "seed": (within(noise.seed), bounds(noise.seed)),
        "percentile": one_of(noise.percentile),
        "models": ((lambda v: bool(MODELS_KEY.match(v))), "reference or an upload's key"),
    }


def check_pin_name(name: str) -> str:
    """The name stripped, or :class:`FBSError` naming the allowed characters."""
    name = str(name).strip()
    if not PIN_NAME.match(name):
        raise FBSError(f"a pin name has 1-24 letters, digits, spaces or _.+- ; got {shown(name)}")
    return name


def encode_pins(pins) -> str:
    """The URL value of pins' settings (``|`` between pins, ``~`` between fields)."""
    return "|".join(p.encode() for p in pins)


#: Most pins a link may hold (the Analysis card keeps 4; a longer value is not a link of it).
MAX_PINS_IN_LINK = 8


def decode_pins(text: str) -> tuple[PinSettings, ...]:
    """Pins' settings from :func:`encode_pins` text, every field checked.

    Each field must be given once and hold a value the page's controls accept (harmonic
    1-7, N one of 10..400 in steps of 10, a bushing DOF, a coupling, noise 0-99.99 %, a
    noise target, 0/1, rounds 1-200,000, a seed, a percentile band, the models'
    key), so a pin of a crafted link is refused here with a message, never later while the
    page is built.

    Raises
    ------
    FBSError
        For a malformed entry or value, naming the pin, the field and what is allowed;
        the link's text is repeated only as escaped plain text (:func:`shown`). Nothing is
        evaluated.
    """
    entries = [e for e in str(text).split("|") if e]
    if len(entries) > MAX_PINS_IN_LINK:
        raise FBSError(f"malformed pins in the link: {len(entries)}, at most {MAX_PINS_IN_LINK}")
    allowed = _allowed()
    out = []
    for entry in entries:
        parts = entry.split("~")
        try:
            name = check_pin_name(parts[0])
        except FBSError as e:
            raise FBSError(f"malformed pin in the link: {e}") from None
        kw: dict[str, Any] = {}
        for part in parts[1:]:
            if not part or part[0] not in _FIELDS:
                raise FBSError(
                    f"malformed pin {name!r} in the link: unknown field {shown(part[:1])}; fields: "
                    + ", ".join(_FIELDS)
                )
            field, conv = _FIELDS[part[0]]
            if field in kw:
                raise FBSError(f"malformed pin {name!r} in the link: {field} given twice")
            check, what = allowed[field]
            try:
                value = conv(part[1:])
                ok = check(value)
            except (KeyError, ValueError, TypeError, OverflowError):
                ok = False
            if not ok:
                raise FBSError(
                    f"malformed pin {name!r} in the link: {field} {shown(part[1:])} is not "
                    f"allowed; allowed: {what}"
                )
            kw[field] = value
        kw.setdefault("residual", False)  # links made before it was pinned
        missing = [f for f, _ in _FIELDS.values() if f not in kw]
        if missing:
            raise FBSError(f"malformed pin {name!r} in the link: it lacks {', '.join(missing)}")
        out.append(PinSettings(name=name, **kw))
    return tuple(out)
