"""Nodal forces and stiffness of all membrane triangles at once.

Internal nodal force of node k (Roddeman et al. 1987, Part II, eq. 39; docs/method.md
section 3): f_k = A0 F N grad(psi_k), with N the (wrinkling) stress resultant. In Voigt form,
with the strain-displacement matrix B (dE_voigt = B du, (n, 3, 9)):

    f = A0 B^T s,        K = A0 (B^T D B + (grad psi_k . N grad psi_l) I_3),

the second term of K being the geometric (initial-stress) stiffness. The forces are computed
as f_k = A0 F N grad psi_k, the same as A0 B^T s without forming B. Degrees of freedom of an
element are ordered node by node: (u1x, u1y, u1z, u2x, ..., u3z).
"""

from __future__ import annotations

from dataclasses import dataclass
from dataclasses import fields as dataclass_fields

import numpy as np

from wrinkle import compiled as kernels
from wrinkle.kinematics import ReferenceGeometry, deformation_gradient, right_cauchy_green
from wrinkle.wrinkling import Wrinkling, WrinklingError, WrinklingResponse

__all__ = [
    "KERNEL_BLOCK",
    "ElementResult",
    "MembraneElements",
    "add_geometric_stiffness",
    "element_stiffness",
    "nodal_forces",
    "strain_displacement",
    "unit_tension_stiffness",
]


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


# Elements per block: the wrinkling response runs on blocks of _BLOCK elements and the element
# kernels on sub-blocks of KERNEL_BLOCK, so that their temporaries stay in the processor caches
# (and memory stays bounded) on large meshes, while numpy's per-call overhead stays small.
_BLOCK = 1 << 15
KERNEL_BLOCK = 1 << 13


def strain_displacement(F: np.ndarray, shape_gradient: np.ndarray) -> np.ndarray:
    """B with dE_voigt = B du: (n, 3, 9); F (n, 3, 2), shape_gradient (n, 3, 2).

    dE_ab = (dF_a . F_b + F_a . dF_b) / 2 with dF_a = sum_k du_k dpsi_k/dP_a.
    """
    n = F.shape[0]
    B = np.empty((n, 3, 3, 3))  # (element, strain row, node, component)
    for k in range(3):
        g0, g1 = shape_gradient[:, k, 0], shape_gradient[:, k, 1]
        for i in range(3):
            F0, F1 = F[:, i, 0], F[:, i, 1]
            np.multiply(g0, F0, out=B[:, 0, k, i])
            np.multiply(g1, F1, out=B[:, 1, k, i])
            B[:, 2, k, i] = g1 * F0 + g0 * F1
    return B.reshape(n, 3, 9)


def nodal_forces(
    area: np.ndarray, F: np.ndarray, shape_gradient: np.ndarray, stress: np.ndarray, out: np.ndarray
) -> np.ndarray:
    """Internal nodal forces A0 B^T s without forming B: f_k = A0 F N grad psi_k written into
    out (n, 9).

    area (n,), F (n, 3, 2), shape_gradient (n, 3, 2), stress (n, 2, 2) resultant N.
    """
    N00, N11, N01 = area * stress[:, 0, 0], area * stress[:, 1, 1], area * stress[:, 0, 1]
    for i in range(3):
        F0, F1 = F[:, i, 0], F[:, i, 1]
        P0 = F0 * N00 + F1 * N01  # row i of A0 F N
        P1 = F0 * N01 + F1 * N11
        for k in range(3):
            out[:, 3 * k + i] = P0 * shape_gradient[:, k, 0] + P1 * shape_gradient[:, k, 1]
    return out


def element_stiffness(
    area: np.ndarray,
    B: np.ndarray,
    tangent: np.ndarray,
    shape_gradient: np.ndarray,
    stress: np.ndarray,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Consistent tangent stiffness A0 (B^T D B + G (x) I3), (n, 9, 9).

    G_kl = grad psi_k . N grad psi_l is the geometric (initial-stress) part;
    ``out``: optional (n, 9, 9) array to write into.
    """
    K = np.matmul(B.transpose(0, 2, 1), np.matmul(tangent * area[:, None, None], B), out=out)
    return add_geometric_stiffness(K, area, shape_gradient, stress)


def add_geometric_stiffness(
    K: np.ndarray, area: np.ndarray, shape_gradient: np.ndarray, stress: np.ndarray
) -> np.ndarray:
    """K += A0 G (x) I3 in place, G_kl = grad psi_k . N grad psi_l: the geometric
    (initial-stress) stiffness of the stress resultant N, (m, 2, 2); K (m, 9, 9), returned."""
    N00, N11, N01 = area * stress[:, 0, 0], area * stress[:, 1, 1], area * stress[:, 0, 1]
    for k in range(3):
        gk0, gk1 = shape_gradient[:, k, 0], shape_gradient[:, k, 1]
        v0 = N00 * gk0 + N01 * gk1  # A0 N grad psi_k
        v1 = N01 * gk0 + N11 * gk1
        for l in range(k, 3):
            G = shape_gradient[:, l, 0] * v0 + shape_gradient[:, l, 1] * v1
            for i in range(3):
                K[:, 3 * k + i, 3 * l + i] += G
                if l != k:
                    K[:, 3 * l + i, 3 * k + i] += G
    return K


def unit_tension_stiffness(area: np.ndarray, shape_gradient: np.ndarray) -> np.ndarray:
    """Geometric stiffness of a unit isotropic tension N = I in the reference configuration,
    A0 (grad psi_k . grad psi_l) I_3, (m, 9, 9); area (m,), shape_gradient (m, 3, 2).

    Assembled, a discrete Laplacian acting on each displacement component (the H1 seminorm of
    a displacement field): the metric in which the Newton solver measures its steps.
    """
    m = area.shape[0]
    return add_geometric_stiffness(
        np.zeros((m, 9, 9)), area, shape_gradient, np.broadcast_to(np.eye(2), (m, 2, 2))
    )


class MembraneElements:
    """All triangles of one material: reference geometry plus the wrinkling material.

    compiled: whether the element loops run as the Numba kernels of ``wrinkle.compiled``
    (the same formulas; NumPy if False). The discrete system chooses it once for the mesh.
    """

    def __init__(self, geometry: ReferenceGeometry, material: Wrinkling, compiled: bool = False):
        self.geometry = geometry
        self.material = material
        self.compiled = compiled

    def evaluate(
        self,
        x_elements: np.ndarray,
        stiffness: bool = True,
        stiffness_sink=None,
        matrices: bool = True,
    ) -> ElementResult:
        """Forces (and stiffness) at current node coordinates x_elements, (n, 3, 3).

        Elements are evaluated block by block (results do not depend on the blocks). With
        ``stiffness_sink(elements, K)`` the stiffness of each block (elements: a slice of this
        group's rows, K: (m, 9, 9), overwritten afterwards) goes to the sink, to be assembled
        at once, and the result holds none: no (n, 9, 9) array on a large mesh. With
        ``matrices`` False the element matrices are not formed at all: the result holds the
        material tangent (``response.tangent``) and F, from which the caller forms and adds
        them itself (``wrinkle.compiled.assemble_stiffness``). Raises WrinklingError listing
        every element whose wrinkling conditions could not be solved.
        """
        g = self.geometry
        n = g.n_elements
        with_matrices = stiffness and matrices
        # in one block where that costs no temporaries: a compiled response
        if n <= _BLOCK or (self.compiled and self.material.has_compiled_response):
            F, C = self._strain(x_elements, g.shape_gradient)
            response = self.material.response(C, tangent=stiffness, compiled=self.compiled)
            forces, K = self._forces_and_stiffness(
                F, slice(0, n), response, with_matrices, sink=stiffness_sink
            )
            return ElementResult(F, response, forces, K, g.area * response.energy)

        F = np.empty((n, 3, 2))
        forces = np.empty((n, 9))
        K = np.empty((n, 9, 9)) if with_matrices and stiffness_sink is None else None
        response = WrinklingResponse(
            state=np.empty(n, dtype=np.int8),
            stress=np.empty((n, 2, 2)),
            tangent=np.empty((n, 3, 3)) if stiffness else None,
            thickness=np.empty(n),
            wrinkle_angle=np.empty(n),
            wrinkle_parameter=np.empty(n),
            energy=np.empty(n),
        )
        fields = {f.name: getattr(response, f.name) for f in dataclass_fields(response)}
        failed = []
        for start in range(0, n, _BLOCK):
            block = slice(start, min(start + _BLOCK, n))
            F_block, C_block = self._strain(x_elements[block], g.shape_gradient[block])
            try:
                r = self.material.response(C_block, tangent=stiffness, compiled=self.compiled)
            except WrinklingError as error:
                failed.append(error.elements + start)
                continue
            except ValueError as error:
                raise ValueError(f"elements {start} to {block.stop - 1}: {error}") from error
            F[block] = F_block
            for name, array in fields.items():
                if array is not None:
                    array[block] = getattr(r, name)
            self._forces_and_stiffness(
                F_block,
                block,
                r,
                with_matrices,
                forces[block],
                None if K is None else K[block],
                stiffness_sink,
            )
        if failed:
            raise WrinklingError(np.concatenate(failed))
        return ElementResult(F, response, forces, K, g.area * response.energy)

    def _strain(
        self, x_elements: np.ndarray, shape_gradient: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """F (m, 3, 2) and C = F^T F (m, 2, 2) at the coordinates x_elements (m, 3, 3)."""
        if self.compiled:
            return kernels.deformation_gradient(x_elements, shape_gradient)
        F = deformation_gradient(x_elements, shape_gradient)
        return F, right_cauchy_green(F)

    def _forces_and_stiffness(
        self, F, elements, response, stiffness, forces=None, K=None, sink=None
    ):
        """Forces (m, 9) and stiffness (m, 9, 9) or None of the block ``elements`` (a slice),
        written into ``forces`` and ``K`` if given, or the stiffness of each sub-block handed
        to ``sink(rows, K_sub)`` (then None is returned for it); computed in sub-blocks."""
        g = self.geometry
        m = F.shape[0]
        if forces is None:
            forces = np.empty((m, 9))
        if stiffness and K is None:
            K = np.empty((min(m, KERNEL_BLOCK) if sink else m, 9, 9))
        # without matrices, the compiled forces in one call (no temporaries)
        step = max(m, 1) if self.compiled and not stiffness else KERNEL_BLOCK
        for start in range(0, m, step):
            sub = slice(start, min(start + step, m))
            mesh_sub = slice(elements.start + sub.start, elements.start + sub.stop)
            area, grad = g.area[mesh_sub], g.shape_gradient[mesh_sub]
            F_sub, stress = F[sub], response.stress[sub]
            if self.compiled:
                kernels.nodal_forces(area, F_sub, grad, stress, forces[sub])
            else:
                nodal_forces(area, F_sub, grad, stress, forces[sub])
            if stiffness:
                out = K[: sub.stop - sub.start] if sink else K[sub]
                if self.compiled:
                    kernels.element_stiffness(area, F_sub, grad, response.tangent[sub], stress, out)
                else:
                    B = strain_displacement(F_sub, grad)
                    element_stiffness(area, B, response.tangent[sub], grad, stress, out=out)
                if sink:
                    sink(mesh_sub, out)
        return forces, K if stiffness and not sink else None
