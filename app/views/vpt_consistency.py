"""The consistency of a measured chassis (virtual point transformation, docs/vpt.md).

Shown under the upload when the session's chassis came from a measured set and its
geometry: the specific consistency of every sensor and impact channel over frequency (1 =
the channel agrees with a rigid knuckle; a loose sensor or a mislabelled direction drops),
and a table per channel of its mean consistency and its leverage (near 1: that channel
cannot be checked). Numbers from :mod:`fbs_core.vpt`; nothing is computed here.
"""

from __future__ import annotations

import html

import numpy as np
import panel as pn
from bokeh.models import ColumnDataSource
from bokeh.palettes import Category10_10
from bokeh.plotting import figure

#: Mean specific consistency below which a channel is flagged in the table.
FLAG_BELOW = 0.9


def _figure(title: str, freq, values, labels, name: str):
    fig = figure(
        title=title,
        height=220,
        sizing_mode="stretch_width",
        x_axis_label="Frequency (Hz)",
        y_axis_label="specific consistency",
        y_range=(0.0, 1.05),
        tools="pan,box_zoom,reset,save",
    )
    for k, lab in enumerate(labels):
        src = ColumnDataSource(
            {"f": np.asarray(freq), "c": np.asarray(values[:, k])}, name=f"{name}.{lab}"
        )
        fig.line("f", "c", source=src, color=Category10_10[k % 10], legend_label=lab)
    fig.legend.click_policy = "hide"
    fig.legend.label_text_font_size = "8pt"
    fig.legend.location = "bottom_left"
    return fig


def table_html(vpt) -> str:
    """Per channel: role, mean specific consistency, leverage; low ones flagged."""
    c = vpt.consistency
    rows = []
    lev = {**vpt.sensor_leverage, **vpt.impact_leverage}
    for role, table in (("sensor", c.sensor_table()), ("impact", c.impact_table())):
        for lab, v in table.items():
            flag = v < FLAG_BELOW or lev[lab] > 0.9
            style = ' style="color:#842029;font-weight:600"' if flag else ""
            rows.append(
                f"<tr{style}><td>{html.escape(lab)}</td><td>{role}</td><td>{v:.3f}</td>"
                f"<td>{lev[lab]:.2f}</td></tr>"
            )
    so, io = c.overall()
    worst, wv = c.worst()
    return (
        f'<div class="vpt-consistency"><b>Virtual point consistency</b>: overall sensors '
        f"{so:.4f}, impacts {io:.4f}; lowest channel {html.escape(worst)} {wv:.3f}"
        '<table class="vpt-consistency-table" style="font-size:0.85em">'
        "<tr><th>channel</th><th>role</th><th>mean consistency</th><th>leverage</th></tr>"
        + "".join(rows)
        + "</table></div>"
    )


def consistency_plot(vpt):
    """The plots and the table of a :class:`fbs_core.vpt.VirtualPoint` (empty for None)."""
    if vpt is None:
        return pn.Column(visible=False)
    c = vpt.consistency
    return pn.Column(
        pn.pane.HTML(table_html(vpt), sizing_mode="stretch_width"),
        pn.pane.Bokeh(
            _figure("Sensors", c.freq, c.sensor_specific, c.sensors, "vpt.sensors"),
            sizing_mode="stretch_width",
        ),
        pn.pane.Bokeh(
            _figure("Impacts", c.freq, c.impact_specific, c.impacts, "vpt.impacts"),
            sizing_mode="stretch_width",
        ),
        sizing_mode="stretch_width",
        css_classes=["vpt-consistency-card"],
    )


def report_notes(data) -> tuple[str, ...]:
    """The report's notes on a measured chassis in use (its "Data in use" table), else ():
    the spindle's virtual point, and the bushing's second one when its sensors were around it.
    """
    vpt = getattr(data, "vpt", None)
    if vpt is None:
        return ()
    c = vpt.consistency
    so, io = c.overall()
    worst, wv = c.worst()
    lev = max({**vpt.sensor_leverage, **vpt.impact_leverage}.items(), key=lambda kv: kv[1])
    notes = (
        f"chassis measured at the knuckle, transformed to the virtual point "
        f"'{vpt.layout.node}' ({len(c.sensors)} sensor channels, {len(c.impacts)} impacts): "
        f"consistency sensors {so:.4f}, impacts {io:.4f}; lowest channel {worst} {wv:.3f}; "
        f"highest leverage {lev[0]} {lev[1]:.2f}",
    )
    bvp = getattr(data, "bushing_vp", None)
    if bvp is None:
        return notes
    bc = bvp.consistency
    bw, bwv = bc.worst()
    blev = max(bvp.sensor_leverage.items(), key=lambda kv: kv[1])
    return (
        *notes,
        f"bushing DOFs from a second virtual point '{bvp.node}' ({len(bc.sensors)} sensor "
        f"channels around it): consistency sensors {bc.overall()[0]:.4f}; lowest channel "
        f"{bw} {bwv:.3f}; highest leverage {blev[0]} {blev[1]:.2f}",
    )
