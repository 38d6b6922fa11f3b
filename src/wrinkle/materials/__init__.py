"""Membrane materials evaluated on batches of in-plane right Cauchy-Green tensors.

See :mod:`wrinkle.materials.base` for the interface every material follows.
"""

from wrinkle.materials.base import (
    Material,
    MembraneResponse,
    as_cauchy_green_batch,
    green_lagrange_voigt,
    tangent_is_isotropic,
    tangent_to_voigt,
    tensor_from_voigt_stress,
    voigt_stress,
)
from wrinkle.materials.mooney_rivlin import MooneyRivlin
from wrinkle.materials.neo_hookean import NeoHookean
from wrinkle.materials.ogden import Ogden
from wrinkle.materials.prestress import Prestressed
from wrinkle.materials.svk import StVenantKirchhoff

__all__ = [
    "Material",
    "MembraneResponse",
    "MooneyRivlin",
    "NeoHookean",
    "Ogden",
    "Prestressed",
    "StVenantKirchhoff",
    "as_cauchy_green_batch",
    "green_lagrange_voigt",
    "tangent_is_isotropic",
    "tangent_to_voigt",
    "tensor_from_voigt_stress",
    "voigt_stress",
]
