"""Sensitivity studies of the coupled prediction (thesis chapter 5).

- :mod:`.metric`: the floating-band error of eq. 5.1;
- :mod:`.truncation`: modal truncation error maps, suggested modes (section 5.1);
- :mod:`.chassis`: the same truncation study on the chassis side (section 7);
- :mod:`.scatter`: Monte-Carlo noise scatter band (section 5.2, eqs. 5.2-5.4);
- :mod:`.firstorder`: its first-order (linearised) counterpart, a cheap cross-check.
"""

from .chassis import chassis_truncation_map, default_chassis_counts
from .firstorder import FirstOrderBand, compare_with_band, first_order_band
from .metric import band_centres, floating_band_error
from .scatter import Convergence, ScatterBand, scatter_band, scatter_band_arrays
from .truncation import (
    ModeFrequencies,
    SuggestedModes,
    TruncationMap,
    mode_frequencies,
    suggest_modes,
    suggest_n_modes,
    truncation_map,
    truncation_map_arrays,
)

__all__ = [
    "Convergence",
    "FirstOrderBand",
    "ModeFrequencies",
    "ScatterBand",
    "SuggestedModes",
    "TruncationMap",
    "band_centres",
    "chassis_truncation_map",
    "default_chassis_counts",
    "compare_with_band",
    "first_order_band",
    "floating_band_error",
    "mode_frequencies",
    "scatter_band",
    "scatter_band_arrays",
    "suggest_modes",
    "suggest_n_modes",
    "truncation_map",
    "truncation_map_arrays",
]
