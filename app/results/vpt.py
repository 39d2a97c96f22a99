"""The consistency of a measured chassis as results (virtual point transformation,
docs/vpt.md): the specific consistency of every sensor and impact channel over frequency,
for the report (its plots) and the CSV. Numbers from :mod:`fbs_core.vpt`; nothing is
computed here.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .base import Result

__all__ = ["ROLES", "consistency_results"]

#: The report's sections of a measured chassis: sensors, then impacts.
ROLES = ("sensors", "impacts")


def consistency_results(vpt: Any) -> dict[str, Result]:
    """``{"vpt_sensors": Result, "vpt_impacts": Result}`` of a
    :class:`fbs_core.vpt.VirtualPoint` (empty for None): per role, one column per channel
    (1 = the channel agrees with a rigid knuckle), its overall and lowest channel in the
    header, and the lines the report draws (``draw["report_plot"]``)."""
    if vpt is None:
        return {}
    c = vpt.consistency
    freq = np.asarray(c.freq, float)
    overall = dict(zip(ROLES, c.overall(), strict=True))
    out = {}
    for role, labels, values in (
        ("sensors", c.sensors, np.asarray(c.sensor_specific, float)),
        ("impacts", c.impacts, np.asarray(c.impact_specific, float)),
    ):
        means = {lab: float(np.mean(values[:, k])) for k, lab in enumerate(labels)}
        low = min(means, key=means.__getitem__)
        out[f"vpt_{role}"] = Result(
            columns={"freq_Hz": freq, **{lab: values[:, k] for k, lab in enumerate(labels)}},
            meta={
                "view": f"virtual point consistency of the {role} (docs/vpt.md)",
                "virtual point": vpt.layout.node,
                "channels": len(labels),
                f"overall {role[:-1]} consistency": f"{overall[role]:.4f}",
                "lowest channel (mean over the lines)": f"{low} {means[low]:.3f}",
            },
            filename=f"vpt_consistency_{role}.csv",
            caption=(
                f"Specific consistency of each {role[:-1]} channel: the share of it the "
                "virtual point's rigid motion explains (1: consistent; a loose sensor or a "
                "wrong direction drops)"
            ),
            draw={
                "report_plot": {
                    "kind": "lines",
                    "x": freq,
                    "groups": {lab: [values[:, k]] for k, lab in enumerate(labels)},
                    "x_label": "Frequency (Hz)",
                    "y_label": "specific consistency",
                    "y_max": 1.05,
                }
            },
        )
    return out
