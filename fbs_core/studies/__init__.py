"""Sensitivity studies of the coupled prediction (thesis chapter 5).

- :mod:`.metric`: the floating-band error of eq. 5.1;
- :mod:`.truncation`: modal truncation error maps, suggested modes (section 5.1);
- :mod:`.scatter`: Monte-Carlo noise scatter band (section 5.2, eqs. 5.2-5.4).
"""

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
    "ModeFrequencies",
    "ScatterBand",
    "SuggestedModes",
    "TruncationMap",
    "band_centres",
    "floating_band_error",
    "mode_frequencies",
    "scatter_band",
    "scatter_band_arrays",
    "suggest_modes",
    "suggest_n_modes",
    "truncation_map",
    "truncation_map_arrays",
]
