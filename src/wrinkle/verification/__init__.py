"""Independent references for checking the finite-element results.

- :mod:`wrinkle.verification.relaxed_energy`: the relaxed (tension-field) stress of one
  material point by direct minimisation of Pipkin's relaxed energy (METHOD.md section 4);
- :mod:`wrinkle.verification.shear_stretch`: the analytic edge forces of the paper's
  shear-and-stretch test (METHOD.md section 8).

Nothing here imports the element's wrinkling routine (``wrinkle.wrinkling``).
"""

from wrinkle.verification.relaxed_energy import RelaxedState, relax, shifted_energy
from wrinkle.verification.shear_stretch import (
    ShearStretchCurves,
    deformation_gradient,
    homogeneous_edge_forces,
    shear_stretch_curves,
)

__all__ = [
    "RelaxedState",
    "ShearStretchCurves",
    "deformation_gradient",
    "homogeneous_edge_forces",
    "relax",
    "shear_stretch_curves",
    "shifted_energy",
]
