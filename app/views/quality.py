"""How far the session's tire can be trusted between its operating points.

A badge and a one-row table next to the data source: the leave-one-out interpolation
error per harmonic band (every interior operating point predicted from its neighbours,
:func:`fbs_core.tire.quality.interpolation_quality`) and a warning for every harmonic band
that needs speeds outside the stored operating points
(:func:`fbs_core.tire.quality.speed_coverage`). Computed once per tire (``app.compute``).
"""

from __future__ import annotations

import html

import numpy as np
import panel as pn
import param
from panel.viewable import Viewer

from ..store import Results
from .layout import font
from .live import download_button, inline_html

#: Badge colours (background, text) by the worst leave-one-out error: < 1 dB, < 3 dB, more.
BADGE = (("#d1e7dd", "#0f5132"), ("#fff3cd", "#664d03"), ("#f8d7da", "#842029"))


def badge_level(worst_db: float) -> int:
    """0 (< 1 dB, the goal near the peaks), 1 (< 3 dB) or 2 (3 dB or more / unknown)."""
    if not np.isfinite(worst_db):
        return 2
    return 0 if worst_db < 1.0 else 1 if worst_db < 3.0 else 2


def quality_html(r) -> str:
    """The badge, the per-harmonic table and the speed-range warnings as HTML."""
    q = r.draw["quality"]
    loo = np.asarray(q["loo_db"], float)
    worst = float(np.nanmax(loo)) if np.isfinite(loo).any() else float("nan")
    bg, fg = BADGE[badge_level(worst)]
    worst_txt = "n/a" if not np.isfinite(worst) else f"{worst:.2f} dB"
    head = "".join(f"<th>h{k}</th>" for k in q["harmonic"])
    cells = "".join(f"<td>{'n/a' if not np.isfinite(v) else f'{v:.2f}'}</td>" for v in loo)
    warn = [w for w in r.draw["warnings"] if w]
    warn_html = "".join(
        f'<div class="tire-speed-warning" style="color:#842029">&#9888; {html.escape(w)}</div>'
        for w in warn
    )
    cover = (
        ""
        if warn
        else f'<span class="tire-speed-covered">every harmonic band inside '
        f"{q['speeds'][0]:g}-{q['speeds'][1]:g} km/h</span>"
    )
    return (
        f'<div class="tire-quality">'
        f'<span class="tire-quality-badge" style="background:{bg};color:{fg};'
        f'padding:1px 8px;border-radius:10px;font-weight:600">'
        f"interpolation {worst_txt}</span> "
        f"<span>{inline_html(r.caption)} (dB); {cover}</span>"
        f'<table class="tire-quality-table" style="font-size:{font("0.85em")};margin-top:2px">'
        f"<tr><th></th>{head}</tr><tr><th>dB</th>{cells}</tr></table>"
        f"{warn_html}</div>"
    )


class TireQualityView(Viewer):
    """Badge and table of the tire's leave-one-out interpolation error, speed warnings."""

    store = param.ClassSelector(class_=Results, doc="The session's results.")

    def __init__(self, **params):
        super().__init__(**params)
        self._layout = None
        self.store.param.watch(lambda _e: self._changed(), ["tire_quality"])

    def _changed(self):
        if self._layout is None or self.store.closed:
            return
        # a pane's object may be set from any thread (Panel schedules the model change)
        self._pane.object = quality_html(self.store.tire_quality)

    def __panel__(self):
        if self._layout is None:
            self._pane = pn.pane.HTML(
                quality_html(self.store.tire_quality),
                sizing_mode="stretch_width",
                css_classes=["tire-quality-pane"],
                margin=(0, 5),
            )
            dl = download_button("quality", lambda: self.store.tire_quality)
            self._layout = pn.Row(self._pane, dl, sizing_mode="stretch_width")
        return self._layout
