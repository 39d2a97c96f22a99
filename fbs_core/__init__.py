"""fbs_core: Frequency Based Substructuring of a rolling tire and a chassis.

Follows Rosholm & Westers, "Assembly of a tire and a vehicle model to predict
vibrations at the bushings", Chalmers MSc thesis (2018).
"""

from . import analysis as analysis
from . import io as io
from . import variants as variants
from . import vehicle as vehicle
from . import vocabulary as vocabulary
from . import vpt as vpt
from .analysis import (
    bushing_contributions,
    campbell,
    mode_participation,
    peak_labels,
    select_modes,
    speed_map,
    wave_campbell,
)
from .candidates import MAX_CANDIDATES, Candidate, CandidateSet
from .chassis import ChassisModel, FRFChassis, reference_chassis
from .chassis_modal import ModalChassis
from .coupling import (
    couple_generalized,
    couple_impedance,
    couple_lm,
    couple_receptance,
    couple_response,
    interface_condition,
)
from .delivery import Delivery, assess_delivery
from .direct import SecondOrderSystem, assemble
from .dofs import DIRECTIONS, node_labels, parse_label
from .errors import (
    CampaignError,
    ClusterUnavailable,
    CouplingOptionError,
    DataFormatError,
    DOFError,
    FBSError,
    ForeignDataError,
    FrequencyGridError,
    GeometryError,
    HarmonicError,
    InsecureScheduler,
    ModalError,
    ModeCountError,
    OperatingPointError,
    ParameterError,
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
    FirstOrderBand,
    ModeFrequencies,
    ScatterBand,
    SuggestedModes,
    TruncationMap,
    chassis_truncation_map,
    first_order_band,
    floating_band_error,
    mode_frequencies,
    scatter_band,
    suggest_modes,
    truncation_map,
)
from .targets import IncumbentTarget, Target, read_targets
from .tire import TireModel, reference_tire
from .vehicle import random_road_response, reference_vehicle, vehicle_response
from .verdict import NoiseEdge, Verdict
from .vocabulary import COUPLINGS, EIGEN_SPEEDS, magnitude_db, readonly
from .vpt import Layout, VirtualPoint, virtual_point

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
    "ClusterUnavailable",
    "ForeignDataError",
    "InsecureScheduler",
    "CouplingOptionError",
    "HarmonicError",
    "ModalError",
    "ModeCountError",
    "OperatingPointError",
    "ParameterError",
    "GeometryError",
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
    "first_order_band",
    "floating_band_error",
    "TruncationMap",
    "SuggestedModes",
    "ModeFrequencies",
    "ScatterBand",
    "FirstOrderBand",
    "Convergence",
    "node_labels",
    "parse_label",
    "load_frf",
    "save_frf",
    "bushing_contributions",
    "campbell",
    "peak_labels",
    "speed_map",
    "mode_participation",
    "select_modes",
    "wave_campbell",
    "ModalChassis",
    "chassis_truncation_map",
    "reference_vehicle",
    "vehicle_response",
    "random_road_response",
    "MAX_CANDIDATES",
    "Candidate",
    "CandidateSet",
    "Target",
    "IncumbentTarget",
    "read_targets",
    "NoiseEdge",
    "Verdict",
    "Delivery",
    "assess_delivery",
    "Layout",
    "VirtualPoint",
    "virtual_point",
]
