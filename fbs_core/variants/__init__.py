"""Systematic errors: corridors from physical parameters and their sensitivities.

The thesis' section 7 asks for "a noise corridor for systematic errors" from a
"simultaneous change of physical properties such as mass and stiffness". Here:

- :mod:`.parameters`: named physical parameters of the reference tire and chassis with
  documented ranges (:data:`PARAMETERS`, docs/corridor.md);
- :mod:`.models`: a variant is a rebuilt pair of models (the tire's complex modes at its
  operating points), tires cached by content (:class:`TireCache`);
- :mod:`.design`: seeded Sobol', Latin-hypercube and Saltelli designs (``scipy.stats.qmc``);
- :mod:`.corridor`: min, max and percentiles of ``|v_e|`` over the variants per line and
  DOF, beside the noise scatter band of eqs. 5.2-5.4;
- :mod:`.sensitivity`: first-order and total Sobol' indices of the band levels (Saltelli
  2010, Jansen 1999) with their convergence;
- :mod:`.study`: a whole study in this process (a campaign runs it on Dask);
- :mod:`.report`: its tables as text.

Example
-------
>>> import fbs_core.variants as fv
>>> st = fv.corridor_study(["inflation_pressure", "knuckle_mass"], n=16)   # doctest: +SKIP
>>> c = st.corridor(4)                  # doctest: +SKIP
>>> c.width_db.max(axis=0)              # doctest: +SKIP
"""

from .corridor import Corridor, corridor
from .design import DESIGNS, Design, sample_design
from .models import (
    TIRE_CACHE,
    TireCache,
    VariantSettings,
    needed_speeds,
    tire_key,
    variant_models,
)
from .models import variant_responses as variant_responses
from .parameters import (
    PARAMETERS,
    Parameter,
    ParameterError,
    ParameterSpace,
    apply_values,
    parameter,
)
from .sensitivity import Sensitivity, band_levels, sensitivity, sobol_indices, third_octave_bands
from .study import VariantStudy, corridor_study, evaluate_rows, run_variants, tire_groups

__all__ = [
    "DESIGNS",
    "PARAMETERS",
    "TIRE_CACHE",
    "Corridor",
    "Design",
    "Parameter",
    "ParameterError",
    "ParameterSpace",
    "Sensitivity",
    "TireCache",
    "VariantSettings",
    "VariantStudy",
    "apply_values",
    "band_levels",
    "corridor",
    "corridor_study",
    "evaluate_rows",
    "needed_speeds",
    "parameter",
    "run_variants",
    "sample_design",
    "sensitivity",
    "sobol_indices",
    "third_octave_bands",
    "tire_key",
    "tire_groups",
    "variant_models",
    "variant_responses",
]
