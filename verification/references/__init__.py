"""Independent references for checking the finite-element results.

- :mod:`verification.references.relaxed_energy`: the relaxed (tension-field) stress of one
  material point by direct minimisation of Pipkin's relaxed energy (docs/method.md section 4);
- :mod:`verification.references.shear_stretch`: the analytic edge forces of the paper's
  shear-and-stretch test (docs/method.md section 8);
- one module per gallery benchmark with its closed-form or semi-analytical solution and the
  derivation in its docstring: ``simple_shear``, ``annulus_hub``, ``lame_annulus``,
  ``membrane_beam``, ``airbag`` (extrapolation and equilibrium), ``inflated_cylinder``,
  ``sphere``;
- :mod:`verification.references.mooney_rivlin_sphere`: the Mooney-Rivlin sphere's closed-form
  pressure-stretch curve with its maximum and minimum (tested in tests/test_rubber_laws.py).

Nothing here imports the element's wrinkling routine (``wrinkle.wrinkling``).
"""

from verification.references.relaxed_energy import RelaxedState, relax, shifted_energy
from verification.references.shear_stretch import (
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
