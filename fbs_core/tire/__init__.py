"""The reference rolling tire: physics (``ring``), complex modes (``modes``),
the supplier-style modal model (``model``) and its file format (``storage``).

See ``docs/tire-model.md``.
"""

from .params import DEFAULT_PARAMETERS, FAMILIES, TireParameters
from .ring import HUB_DOFS, build_tire_system, patch_load, ring_closed_form

__all__ = [
    "DEFAULT_PARAMETERS",
    "FAMILIES",
    "HUB_DOFS",
    "TireParameters",
    "build_tire_system",
    "patch_load",
    "ring_closed_form",
]
