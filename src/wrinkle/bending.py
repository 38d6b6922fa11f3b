"""A small bending stiffness on the mean surface: the quadratic bending energy of a flat sheet.

A membrane has no bending stiffness; the real sheet has D = E t^3 / 12 (1 - nu^2). Without it
the relaxed (tension-field) energy has flat directions: a fold, a crease of the mean surface
one element wide, costs nothing, and a Newton solve creeps while fold tips move through the
mesh (docs/notes/2026-12-airbag-iteration-growth.md). ``Bending`` adds the bending energy of
the mean surface,

    W_b = (D / 2) integral |Laplacian x|^2 dA = (D / 2) integral (kappa_1 + kappa_2)^2 dA,

discretised with the cotangent Laplacian L of the reference mesh and the lumped (one third of
the adjacent triangles') nodal areas M_i, as the quadratic energy of Bergou, Wardetzky,
Harmon, Zorin & Grinspun (Symposium on Geometry Processing 2006) and Wardetzky, Bergou,
Harmon, Zorin & Grinspun ("Discrete quadratic curvature energies", CAGD 24, 2007):

    W_b = (1/2) sum_i (D_i / M_i) |(L x)_i|^2 = (1/2) u^T Q u,    Q = L^T diag(D_i / M_i) L,

summed over the interior nodes (a boundary node carries no bending moment: free and supported
edges are simply supported). On a flat reference sheet L maps every affine field, rigid
motions included, to zero, so W_b in the displacements u is exact for rigid motions and, for
deformations that do not stretch the sheet, the discrete counterpart of the integral; it is
quadratic in u with the constant Hessian Q, assembled once. It is offered for flat reference
meshes only. Q couples each node with its neighbours' neighbours, so the stiffness has more
entries than the membrane's (about 12 node pairs per node instead of 7 on a structured mesh).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from wrinkle.materials.base import Material
from wrinkle.mesh import Mesh, boundary_nodes

__all__ = ["Bending", "bending_stiffness", "check_flat", "plate_bending_stiffness"]

DOFS_PER_NODE = 3


def plate_bending_stiffness(E: float, nu: float, thickness: float) -> float:
    """D = E t^3 / 12 (1 - nu^2), force x length (E in force / area, t a length)."""
    return E * thickness**3 / (12.0 * (1.0 - nu**2))


def _cotangent(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Cotangent of the angle between the rows of u and v, (n,)."""
    return np.einsum("ij,ij->i", u, v) / np.linalg.norm(np.cross(u, v), axis=1)


class Bending:
    """The bending energy (1/2) u^T Q u of a flat reference mesh (module docstring).

    mesh: the reference mesh, all its nodes in one plane (ValueError otherwise); stiffness:
    D of each element (n_elements,) or one value, force x length; a node takes the
    area-weighted mean of its elements' values. Attribute ``nodal``: Q of one displacement
    component, (n_nodes, n_nodes) CSR; Q acts on each of the three alike.
    """

    def __init__(self, mesh: Mesh, stiffness: float | np.ndarray):
        nodes, triangles, n = mesh.nodes, mesh.triangles, mesh.n_nodes
        check_flat(mesh)
        stiffness = np.broadcast_to(np.asarray(stiffness, dtype=float), (mesh.n_elements,))
        if not np.all(np.isfinite(stiffness)) or np.any(stiffness < 0):
            raise ValueError("the bending stiffness must be finite and >= 0")
        rows, columns, values = [], [], []
        for k in range(3):  # the edge (i, j) opposite node o of each triangle
            i, j, o = triangles[:, k], triangles[:, (k + 1) % 3], triangles[:, (k + 2) % 3]
            weight = 0.5 * _cotangent(nodes[i] - nodes[o], nodes[j] - nodes[o])
            rows += [i, j, i, j]
            columns += [j, i, i, j]
            values += [-weight, -weight, weight, weight]
        laplacian = sp.csr_matrix(
            (np.concatenate(values), (np.concatenate(rows), np.concatenate(columns))),
            shape=(n, n),
        )
        p0, p1, p2 = (nodes[triangles[:, k]] for k in range(3))
        area = 0.5 * np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1)
        nodal_area = np.bincount(triangles.ravel(), np.repeat(area / 3, 3), minlength=n)
        nodal_stiffness = np.bincount(
            triangles.ravel(), np.repeat(stiffness * area / 3, 3), minlength=n
        )
        weight = np.where(boundary_nodes(mesh), 0.0, nodal_stiffness / nodal_area**2)
        # CSR with sorted indices, no repeats (SciPy's CSR sum; its COO one sorts all the
        # entries at once: 0.6 s at 10^6 elements)
        nodal = (laplacian.T @ sp.diags(weight) @ laplacian).tocsr()
        nodal.sum_duplicates()
        self.nodal = nodal

    def entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows, columns and values of the nonzero entries of ``nodal``, (m,) each."""
        coo = self.nodal.tocoo()
        return coo.row.astype(np.int64), coo.col.astype(np.int64), coo.data

    def coupled_pairs(self) -> np.ndarray:
        """The node pairs (i, j), i < j, that Q couples, (m, 2)."""
        rows, columns, _ = self.entries()
        upper = rows < columns
        return np.column_stack([rows[upper], columns[upper]])

    def forces(self, u: np.ndarray) -> np.ndarray:
        """Internal nodal forces Q u of displacements u, (n_dofs,)."""
        return np.asarray(self.nodal @ u.reshape(-1, DOFS_PER_NODE)).ravel()

    def energy(self, u: np.ndarray) -> float:
        """(1/2) u^T Q u, u (n_dofs,); force x length."""
        return 0.5 * float(u @ self.forces(u))


def check_flat(mesh: Mesh) -> None:
    """ValueError unless all the mesh's nodes lie in one plane (to 1e-9 of its extent)."""
    centred = mesh.nodes - mesh.nodes.mean(axis=0)
    spread = np.linalg.svd(centred, compute_uv=False)  # the last: the distance off a plane
    if spread[-1] > 1e-9 * spread[0]:
        raise ValueError(
            "bending is offered for flat reference meshes only (the mesh's nodes do not lie "
            "in one plane)"
        )


def bending_stiffness(material: Material) -> float:
    """The plate bending stiffness of a membrane material: t^2 / 12 times the mean of its
    in-plane stiffnesses A_11 and A_22 at C = I (force per length), which is
    D = E t^3 / 12 (1 - nu^2) for an isotropic St. Venant-Kirchhoff sheet and mu t^3 / 3 for
    an incompressible neo-Hookean one. Force x length."""
    tangent = material.response(np.eye(2)[None]).tangent
    if tangent is None:
        raise ValueError("the material gives no tangent")
    return float(0.5 * (tangent[0, 0, 0] + tangent[0, 1, 1]) * material.thickness**2 / 12.0)
