"""Nodal forces and stiffness of all membrane triangles at once.

Internal nodal force of node k (Roddeman et al. 1987, Part II, eq. 39, METHOD.md section 3):
f_k = A0 F N grad(psi_k), with N the (wrinkling) stress resultant. In Voigt form, with the
strain-displacement matrix B (dE_voigt = B du, (n, 3, 9)):

    f = A0 B^T s,        K = A0 (B^T D B + (grad psi_k . N grad psi_l) I_3),

the second term being the geometric (initial-stress) stiffness. Degrees of freedom of an element
are ordered node by node: (u1x, u1y, u1z, u2x, ..., u3z).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrinkle.kinematics import ReferenceGeometry, deformation_gradient, right_cauchy_green
from wrinkle.materials.base import voigt_stress
from wrinkle.wrinkling import Wrinkling, WrinklingResponse


@dataclass
class ElementResult:
    """Everything evaluated for n elements at one configuration.

    deformation_gradient: (n, 3, 2); response: the wrinkling response (state, stress, ...);
    forces: (n, 9) internal nodal forces; stiffness: (n, 9, 9) or None;
    energy: (n,) strain energy of each element (A0 times the relaxed energy density).
    """

    deformation_gradient: np.ndarray
    response: WrinklingResponse
    forces: np.ndarray
    stiffness: np.ndarray | None
    energy: np.ndarray


def strain_displacement(F: np.ndarray, shape_gradient: np.ndarray) -> np.ndarray:
    """B with dE_voigt = B du: (n, 3, 9); F (n, 3, 2), shape_gradient (n, 3, 2).

    dE_ab = (dF_a . F_b + F_a . dF_b) / 2 with dF_a = sum_k du_k dpsi_k/dP_a.
    """
    n = F.shape[0]
    grad = shape_gradient
    B = np.empty((n, 3, 3, 3))  # (element, strain row, node, component)
    B[:, 0] = grad[:, :, 0, None] * F[:, None, :, 0]
    B[:, 1] = grad[:, :, 1, None] * F[:, None, :, 1]
    B[:, 2] = grad[:, :, 1, None] * F[:, None, :, 0] + grad[:, :, 0, None] * F[:, None, :, 1]
    return B.reshape(n, 3, 9)


def element_forces(area: np.ndarray, B: np.ndarray, stress: np.ndarray) -> np.ndarray:
    """Internal nodal forces A0 B^T s, (n, 9); stress (n, 2, 2) resultant."""
    s = voigt_stress(stress)
    return area[:, None] * np.einsum("nri,nr->ni", B, s)


def element_stiffness(
    area: np.ndarray,
    B: np.ndarray,
    tangent: np.ndarray,
    shape_gradient: np.ndarray,
    stress: np.ndarray,
) -> np.ndarray:
    """Consistent tangent stiffness A0 (B^T D B + G (x) I3), (n, 9, 9)."""
    n = B.shape[0]
    material = np.matmul(B.transpose(0, 2, 1), np.matmul(tangent, B))
    geometric = np.matmul(shape_gradient, np.matmul(stress, shape_gradient.transpose(0, 2, 1)))
    K = material.reshape(n, 3, 3, 3, 3)
    for i in range(3):
        K[:, :, i, :, i] += geometric
    K *= area[:, None, None, None, None]
    return K.reshape(n, 9, 9)


class MembraneElements:
    """All triangles of one material: reference geometry plus the wrinkling material."""

    def __init__(self, geometry: ReferenceGeometry, material: Wrinkling):
        self.geometry = geometry
        self.material = material

    def evaluate(self, x_elements: np.ndarray, stiffness: bool = True) -> ElementResult:
        """Forces (and stiffness) at current node coordinates x_elements, (n, 3, 3)."""
        g = self.geometry
        F = deformation_gradient(x_elements, g.shape_gradient)
        response = self.material.response(right_cauchy_green(F), tangent=stiffness)
        B = strain_displacement(F, g.shape_gradient)
        forces = element_forces(g.area, B, response.stress)
        K = None
        if stiffness:
            K = element_stiffness(g.area, B, response.tangent, g.shape_gradient, response.stress)
        return ElementResult(F, response, forces, K, g.area * response.energy)
