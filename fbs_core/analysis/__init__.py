"""Analysis of coupled results for a design review: contributions of the
interface forces, peaks and nearby modes, phase views and cursors, comparison of
states, the tire across speed (Campbell diagram, speed-frequency map), and CSV
export with provenance. See ``docs/analysis.md``.
"""

from .contributions import (
    Contributions,
    bushing_contributions,
    contribution_kernel,
    interface_contributions,
    map_contributions,
)

__all__ = [
    "Contributions",
    "bushing_contributions",
    "contribution_kernel",
    "interface_contributions",
    "map_contributions",
]
from .peaks import (  # noqa: E402
    Mode,
    Peak,
    coupled_modes_near,
    coupled_system,
    find_peaks_db,
    parabolic_vertex,
    peak_labels,
    system_modes_near,
)
from .views import Bode, Delta, bode, delta_cursor, level_db, phase_deg, real_imag  # noqa: E402

__all__ += [
    "Mode",
    "Peak",
    "coupled_modes_near",
    "coupled_system",
    "find_peaks_db",
    "parabolic_vertex",
    "peak_labels",
    "system_modes_near",
    "Bode",
    "Delta",
    "bode",
    "delta_cursor",
    "level_db",
    "phase_deg",
    "real_imag",
]
from .campbell import (  # noqa: E402
    Campbell,
    Crossing,
    campbell,
    classify_branches,
    harmonic_lines,
    travelling_index,
)

__all__ += [
    "Campbell",
    "Crossing",
    "campbell",
    "classify_branches",
    "harmonic_lines",
    "travelling_index",
]
from .speedmap import SpeedMap, speed_map  # noqa: E402

__all__ += ["SpeedMap", "speed_map"]
from .compare import (  # noqa: E402
    LevelDifference,
    MapDifference,
    db_difference,
    truncation_map_difference,
)
from .export import export_mapping, to_csv  # noqa: E402
from .pinned import MAX_PINS, PinnedState, add_pin, digest, pin_state, remove_pin  # noqa: E402

__all__ += [
    "LevelDifference",
    "MapDifference",
    "db_difference",
    "truncation_map_difference",
    "export_mapping",
    "to_csv",
    "MAX_PINS",
    "PinnedState",
    "add_pin",
    "digest",
    "pin_state",
    "remove_pin",
]
from .participation import (  # noqa: E402
    KINDS,
    Participation,
    coupled_mode_arrays,
    mode_participation,
    pair_kinds,
    participation_from_terms,
)
from .selection import ModeSelection, prefix_responses, select_modes  # noqa: E402

__all__ += [
    "KINDS",
    "Participation",
    "pair_kinds",
    "coupled_mode_arrays",
    "mode_participation",
    "participation_from_terms",
    "ModeSelection",
    "prefix_responses",
    "select_modes",
]
from .shapes import (  # noqa: E402
    BeltShape,
    ChassisShape,
    CoupledShape,
    TireModeShape,
    chassis_geometry,
    coupled_mode_shapes,
    operating_shape,
    tire_mode_shape,
)
from .waves import WaveCampbell, wave_campbell  # noqa: E402

__all__ += [
    "BeltShape",
    "ChassisShape",
    "CoupledShape",
    "TireModeShape",
    "chassis_geometry",
    "coupled_mode_shapes",
    "operating_shape",
    "tire_mode_shape",
    "WaveCampbell",
    "wave_campbell",
]
