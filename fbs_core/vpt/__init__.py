"""The virtual point transformation (VPT): a measured chassis at the hub.

Nobody can excite or measure a rotation at a spindle directly. Test engineers glue
tri-axial accelerometers around the knuckle, hit a set of points near it in several
directions, and transform both to a virtual point at the wheel centre (de Klerk, Rixen &
Voormeeren 2008; van der Seijs et al., IMAC 2015). This package does that and says how
consistent the measurement was (docs/vpt.md):

- :mod:`.geometry`: channels (positions, directions), the layout, the interface
  displacement modes, the observability check;
- :mod:`.transform`: the least-squares transformations, :func:`virtual_point` and, for a
  point observed by sensors around it but not excited (the bushing), :func:`response_point`;
- :mod:`.quality`: sensor and impact consistency, overall and per channel;
- :mod:`.validation`: the reference chassis with a flexible knuckle, "measured" at a
  realistic layout (the tests' and ``scripts/print_vpt_validation.py``'s truth).

Geometry files (UFF 15/2411, CSV, HDF5) are read by :func:`fbs_core.io.load_geometry`, and
a measured chassis from its two files, ready for the coupling, by
:func:`fbs_core.io.load_measured_chassis` (files are the io package's: this one is the
arithmetic below it).
"""

from __future__ import annotations

from .geometry import Channels, Layout, check_observable, displacement_modes
from .quality import Consistency, consistency, response_consistency
from .transform import (
    ResponsePoint,
    VirtualPoint,
    response_kernel,
    response_point,
    transformation,
    virtual_point,
    vpt_kernel,
)

__all__ = [
    "Channels",
    "Consistency",
    "Layout",
    "ResponsePoint",
    "VirtualPoint",
    "check_observable",
    "consistency",
    "displacement_modes",
    "response_consistency",
    "response_kernel",
    "response_point",
    "transformation",
    "virtual_point",
    "vpt_kernel",
]
