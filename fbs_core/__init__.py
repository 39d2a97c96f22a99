"""fbs_core: Frequency Based Substructuring of a rolling tire and a chassis.

Follows Rosholm & Westers, "Assembly of a tire and a vehicle model to predict
vibrations at the bushings", Chalmers MSc thesis (2018).
"""

from . import analysis as analysis
from . import io as io
from . import vocabulary as vocabulary
from .analysis import bushing_contributions, campbell, peak_labels, speed_map
from .chassis import ChassisModel, FRFChassis, reference_chassis
from .coupling import (
    couple_generalized,
    couple_impedance,
    couple_lm,
    couple_receptance,
    couple_response,
    interface_condition,
)
from .direct import SecondOrderSystem, assemble
from .dofs import DIRECTIONS, node_labels, parse_label
from .errors import (
    CampaignError,
    CouplingOptionError,
    DataFormatError,
    DOFError,
    FBSError,
    FrequencyGridError,
    HarmonicError,
    ModalError,
    ModeCountError,
    OperatingPointError,
    QuantityError,
    SingularInterfaceError,
    StudyCancelled,
)
from .frf import FRF, QUANTITIES
from .harmonics import HARMONICS, Harmonic, harmonic
from .io import load_frf, save_frf
from .prediction import bushing_response
from .studies import (
    Convergence,
    ModeFrequencies,
    ScatterBand,
    SuggestedModes,
    TruncationMap,
    floating_band_error,
    mode_frequencies,
    scatter_band,
    suggest_modes,
    truncation_map,
)
from .tire import TireModel, reference_tire
from .vocabulary import COUPLINGS, EIGEN_SPEEDS, magnitude_db, readonly

__version__ = "0.1.0"

__all__ = [
    "SecondOrderSystem",
    "assemble",
    "couple_generalized",
    "couple_impedance",
    "couple_lm",
    "couple_receptance",
    "couple_response",
    "interface_condition",
    "DIRECTIONS",
    "FRF",
    "HARMONICS",
    "Harmonic",
    "TireModel",
    "QUANTITIES",
    "DOFError",
    "DataFormatError",
    "FBSError",
    "FrequencyGridError",
    "QuantityError",
    "SingularInterfaceError",
    "CampaignError",
    "CouplingOptionError",
    "HarmonicError",
    "ModalError",
    "ModeCountError",
    "OperatingPointError",
    "StudyCancelled",
    "COUPLINGS",
    "EIGEN_SPEEDS",
    "magnitude_db",
    "readonly",
    "FRFChassis",
    "harmonic",
    "reference_tire",
    "ChassisModel",
    "reference_chassis",
    "bushing_response",
    "truncation_map",
    "suggest_modes",
    "mode_frequencies",
    "scatter_band",
    "floating_band_error",
    "TruncationMap",
    "SuggestedModes",
    "ModeFrequencies",
    "ScatterBand",
    "Convergence",
    "node_labels",
    "parse_label",
    "load_frf",
    "save_frf",
    "bushing_contributions",
    "campbell",
    "peak_labels",
    "speed_map",
]
