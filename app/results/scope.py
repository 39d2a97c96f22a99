"""How a result names the scope it is of: the corner, or the whole car's wheels, tracks and
response point (vehicle scope), in CSV headers, captions and file names."""

from __future__ import annotations

from .base import Snapshot

__all__ = [
    "CAR",
    "file_parts",
    "tracks_text",
    "vehicle_caption",
    "vehicle_meta",
    "wheels_text",
]

#: The car of vehicle scope.
CAR = "reference vehicle (docs/vehicle-model.md), the session's tire on all four wheels"


def wheels_text(wheels: tuple[str, ...]) -> str:
    """``"FL FR RL RR"`` (``"none"`` when every wheel's road input is off)."""
    return " ".join(w.upper() for w in wheels) if wheels else "none"


def tracks_text(s: Snapshot) -> str:
    """``"in phase"``, ``"anti-phase"``, ``"coherence 0.5"``."""
    return f"coherence {s.coherence:g}" if s.tracks == "coherence" else s.tracks


def file_parts(s: Snapshot) -> tuple[str, str]:
    """The wheels and the track relation in a file name (``wflfr``, ``inphase``)."""
    return _wheels_part(s), _tracks_part(s)


def _tracks_part(s: Snapshot) -> str:
    return {"in phase": "inphase", "anti-phase": "antiphase"}.get(s.tracks, f"coh{s.coherence:g}")


def _wheels_part(s: Snapshot) -> str:
    return "w" + ("".join(s.wheels) if s.wheels else "none")


def vehicle_meta(s: Snapshot) -> dict:
    """The CSV header's lines of vehicle scope."""
    return {
        "scope": "vehicle: " + CAR,
        "wheels (road input on)": wheels_text(s.wheels),
        "tracks (right against left)": tracks_text(s),
        "response point": s.point,
    }


def vehicle_caption(s: Snapshot) -> str:
    return (
        f"vehicle &middot; wheels {wheels_text(s.wheels)} &middot; tracks {tracks_text(s)} "
        f"&middot; point {s.point}"
    )
