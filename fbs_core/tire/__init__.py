"""The reference rolling tire: physics (``ring``), complex modes (``modes``),
the supplier-style modal model (``model``, ``build``) and its file format
(``storage``). See ``docs/tire-model.md``.
"""

from .build import OPERATING_POINTS, build_modal_model
from .landmarks import landmark_table
from .model import ModeCountError, OperatingPointError, TireModel
from .modes import ComplexModes, ModalError, complex_modes, track_modes
from .params import DEFAULT_PARAMETERS, FAMILIES, TireParameters
from .ring import HUB_DOFS, build_tire_system, patch_load, ring_closed_form, system_matrices
from .storage import DATA_FILE, load_tire_model, read_tire_h5, reference_tire, save_tire_model

__all__ = [
    "DATA_FILE",
    "DEFAULT_PARAMETERS",
    "FAMILIES",
    "HUB_DOFS",
    "OPERATING_POINTS",
    "ComplexModes",
    "ModalError",
    "ModeCountError",
    "OperatingPointError",
    "TireModel",
    "TireParameters",
    "build_modal_model",
    "build_tire_system",
    "complex_modes",
    "landmark_table",
    "load_tire_model",
    "patch_load",
    "read_tire_h5",
    "reference_tire",
    "ring_closed_form",
    "save_tire_model",
    "system_matrices",
    "track_modes",
]
