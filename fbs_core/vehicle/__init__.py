"""The whole car: four rolling tires on one body, the road seen by each wheel.

See docs/vehicle-model.md.
"""

from .landmarks import Landmark, landmark_table
from .layout import MIRROR, WHEELS, hub_labels, road_label, spindle_labels
from .model import (
    RESPONSES,
    SPINDLES,
    FRFVehicle,
    VehicleModel,
    VehicleParameters,
    reference_vehicle,
)
from .response import (
    VehicleResponse,
    WheelTransfer,
    couple_wheels,
    random_road_response,
    road_transfer,
    vehicle_response,
    vehicle_transfer,
)
from .road import ISO_8608, Road, RoadProfile, iso8608_psd, isotropic_coherence
from .structure import RESPONSE_NODES, BodyParameters, FrontParameters
from .studies import vehicle_scatter_band, vehicle_suggest_modes, vehicle_truncation_map
from .tires import mirror_arrays, mirror_tire

__all__ = [
    "BodyParameters",
    "FRFVehicle",
    "FrontParameters",
    "ISO_8608",
    "Landmark",
    "MIRROR",
    "RESPONSES",
    "RESPONSE_NODES",
    "Road",
    "RoadProfile",
    "SPINDLES",
    "VehicleModel",
    "VehicleParameters",
    "VehicleResponse",
    "WHEELS",
    "WheelTransfer",
    "couple_wheels",
    "hub_labels",
    "iso8608_psd",
    "isotropic_coherence",
    "landmark_table",
    "mirror_arrays",
    "mirror_tire",
    "random_road_response",
    "reference_vehicle",
    "road_label",
    "road_transfer",
    "spindle_labels",
    "vehicle_response",
    "vehicle_scatter_band",
    "vehicle_suggest_modes",
    "vehicle_transfer",
    "vehicle_truncation_map",
]
