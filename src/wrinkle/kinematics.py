"""Batched kinematics of the three-node constant-strain membrane triangle in 3-D space.

Notation follows docs/method.md section 2 (Roddeman et al. 1987, Part II, section 2): reference
positions X_k, current positions x_k, k = 1, 2, 3; everything is constant over an element.
Each element carries an orthonormal material frame (A1, A2) of its reference plane, A1 along
the material's fibre direction, and all in-plane tensors (F, C, stress) are written in it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "FIBRE_DIRECTION_HINT",
    "ReferenceGeometry",
    "cross",
    "current_normal",
    "deformation_gradient",
    "element_coordinates",
    "in_plane_axis",
    "material_frame",
    "reference_geometry",
    "reference_normals",
    "right_cauchy_green",
]

# d(psi_k)/d(xi_alpha) for psi_1 = xi_1, psi_2 = xi_2, psi_3 = 1 - xi_1 - xi_2: shape (3, 2)
_SHAPE_DERIVATIVES = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, -1.0]])


@dataclass(frozen=True)
class ReferenceGeometry:
    """Reference geometry of all triangles, computed once.

    area: (n,) reference area A0.
    normal: (n, 3) unit reference normal N = G1 x G2 / |G1 x G2|.
    frame: (n, 2, 3) rows A1 (fibre direction) and A2 = N x A1 of the reference plane.
    shape_gradient: (n, 3, 2) gradient of the shape function of node k with respect to the
        reference in-plane coordinates along (A1, A2), 1/length.
    """

    area: np.ndarray
    normal: np.ndarray
    frame: np.ndarray
    shape_gradient: np.ndarray

    @property
    def n_elements(self) -> int:
        return self.area.shape[0]

    def subset(self, elements: np.ndarray) -> ReferenceGeometry:
        """The geometry of some elements (indices), in that order."""
        return ReferenceGeometry(
            self.area[elements],
            self.normal[elements],
            self.frame[elements],
            self.shape_gradient[elements],
        )


def element_coordinates(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Node coordinates of each element, (n_elements, 3 nodes, 3 components)."""
    return nodes[triangles]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of batches of 3-vectors, (n, 3) x (n, 3) -> (n, 3) (faster than np.cross)."""
    return np.stack(
        [
            a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
            a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
            a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0],
        ],
        axis=-1,
    )


#: What to set when a fibre direction cannot be projected onto an anisotropic element.
FIBRE_DIRECTION_HINT = (
    "set the material's fibre direction so that it has a component in every element's plane "
    "(case file: [material] direction = [dx, dy, dz] or the name of a per-element cell-data "
    "field; Python: fibre_direction=...)"
)


def in_plane_axis(normal: np.ndarray) -> np.ndarray:
    """A unit in-plane direction of each element that depends on its normal only, (n, 3): the
    coordinate axis least aligned with the normal (the first of equals), projected onto the
    plane (its projection has length >= sqrt(2/3)). Elements of one flat face share it."""
    axis = np.eye(3)[np.argmin(np.abs(normal), axis=1)]
    projected = axis - np.sum(axis * normal, axis=1)[:, None] * normal
    return projected / np.linalg.norm(projected, axis=1)[:, None]


def material_frame(
    normal: np.ndarray,
    fibre_direction: np.ndarray | tuple,
    fibre_angle: np.ndarray | float = 0.0,
    isotropic: np.ndarray | None = None,
    element_numbers: np.ndarray | None = None,
) -> np.ndarray:
    """Orthonormal in-plane frame (A1, A2) of each element, (n, 2, 3).

    A1 is ``fibre_direction`` ((3,) or (n, 3)) projected onto the element plane and then turned
    by ``fibre_angle`` (radians, scalar or (n,)) about the normal; A2 = N x A1.
    isotropic: (n,) bool, elements whose material is isotropic (``Material.is_isotropic``):
    where the direction cannot be projected there (perpendicular to the plane, or zero), A1 is
    ``in_plane_axis`` instead, as the frame changes no result of an isotropic law.
    Raises ValueError naming the first other element whose plane is perpendicular to the
    direction, numbered by ``element_numbers`` ((n,), default 0 .. n - 1).
    """
    direction = np.broadcast_to(np.asarray(fibre_direction, dtype=float), normal.shape)
    projected = direction - np.sum(direction * normal, axis=1)[:, None] * normal
    length = np.linalg.norm(projected, axis=1)
    scale = np.linalg.norm(direction, axis=1)
    bad = ~(length > 1e-8 * np.maximum(scale, 1e-300))
    if isotropic is not None and np.any(bad):
        replace = bad & np.asarray(isotropic, dtype=bool)
        if np.any(replace):
            projected = projected.copy()
            projected[replace] = in_plane_axis(normal[replace])
            length = np.where(replace, 1.0, length)
            bad = bad & ~replace
    if np.any(bad):
        first = int(np.flatnonzero(bad)[0])
        element = first if element_numbers is None else int(element_numbers[first])
        raise ValueError(
            f"fibre direction {direction[first].tolist()} is perpendicular to element "
            f"{element} (or zero): it cannot be projected onto the element plane; "
            + FIBRE_DIRECTION_HINT
        )
    a1 = projected / length[:, None]
    a2 = cross(normal, a1)
    angle = np.broadcast_to(np.asarray(fibre_angle, dtype=float), length.shape)
    if np.any(angle != 0.0):
        cos, sin = np.cos(angle)[:, None], np.sin(angle)[:, None]
        a1, a2 = cos * a1 + sin * a2, -sin * a1 + cos * a2
    return np.stack([a1, a2], axis=1)


def reference_normals(
    nodes: np.ndarray, triangles: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Edges G1 = X1 - X3, G2 = X2 - X3 (each (n, 3)), twice the area |G1 x G2| (n,) and the
    unit normal (n, 3) of each triangle; the normal is NaN where the area is zero (see
    ``reference_geometry`` for the check)."""
    X = element_coordinates(np.asarray(nodes, dtype=float), np.asarray(triangles))
    G1 = X[:, 0] - X[:, 2]
    G2 = X[:, 1] - X[:, 2]
    G1xG2 = cross(G1, G2)
    twice_area = np.linalg.norm(G1xG2, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        normal = G1xG2 / twice_area[:, None]
    return G1, G2, twice_area, normal


def reference_geometry(
    nodes: np.ndarray,
    triangles: np.ndarray,
    fibre_direction: np.ndarray | tuple = (1.0, 0.0, 0.0),
    fibre_angle: np.ndarray | float = 0.0,
    isotropic: np.ndarray | None = None,
) -> ReferenceGeometry:
    """Areas, normals, material frames and shape-function gradients of all triangles.

    nodes: (n_nodes, 3) reference coordinates; triangles: (n, 3) node indices; fibre_direction,
    fibre_angle and isotropic ((n,) bool) as in ``material_frame``.
    Raises ValueError naming the first degenerate (zero-area) element, or the first
    anisotropic element the fibre direction cannot be projected onto.
    """
    G1, G2, twice_area, normal = reference_normals(nodes, triangles)
    size = np.maximum(np.linalg.norm(G1, axis=1), np.linalg.norm(G2, axis=1))
    degenerate = ~(twice_area > 1e-12 * size**2)
    if np.any(degenerate):
        element = int(np.flatnonzero(degenerate)[0])
        raise ValueError(
            f"element {element} (nodes {np.asarray(triangles)[element].tolist()}) has zero area"
        )
    frame = material_frame(normal, fibre_direction, fibre_angle, isotropic)
    # in-plane coordinates of G1, G2: M[:, a, alpha] = G_alpha . A_a
    M = np.einsum("nai,nki->nak", frame, np.stack([G1, G2], axis=1))
    # d psi_k / d P_a = d psi_k / d xi_alpha (M^-1)_alpha a
    shape_gradient = _SHAPE_DERIVATIVES[None] @ np.linalg.inv(M)
    return ReferenceGeometry(0.5 * twice_area, normal, frame, shape_gradient)


def deformation_gradient(x_elements: np.ndarray, shape_gradient: np.ndarray) -> np.ndarray:
    """In-plane deformation gradient F = sum_k x_k (x) grad psi_k, (n, 3, 2).

    Column a of F is the current image of the material axis A_a (docs/method.md section 2,
    F_m = g_alpha (x) Gamma^alpha written in the material frame).
    x_elements: (n, 3 nodes, 3) current node coordinates; shape_gradient: (n, 3, 2).

    Written with the edges from node 1, F = (x_2 - x_1) (x) grad psi_2 + (x_3 - x_1) (x)
    grad psi_3 (the gradients sum to zero): the sum over absolute coordinates would carry a
    round-off of eps |x| / h (h the element's size), which on a fine mesh far from the origin
    exceeds the threshold below which a stress counts as zero and makes undeformed elements
    wrinkle or go slack by noise.
    """
    F = np.empty((x_elements.shape[0], 3, 2))
    grad2, grad3 = shape_gradient[:, 1], shape_gradient[:, 2]
    # component by component: several times faster than matmul on (3, 3) x (3, 2) batches
    for i in range(3):
        x1 = x_elements[:, 0, i]
        edge2, edge3 = x_elements[:, 1, i] - x1, x_elements[:, 2, i] - x1
        for a in range(2):
            F[:, i, a] = edge2 * grad2[:, a] + edge3 * grad3[:, a]
    return F


def right_cauchy_green(F: np.ndarray) -> np.ndarray:
    """In-plane right Cauchy-Green tensor C = F^T F, (n, 2, 2), material frame; F (n, 3, 2)."""
    # explicit dot products of the columns: much faster than matmul on (2, 3) x (3, 2) batches
    F1, F2 = F[:, :, 0], F[:, :, 1]
    C = np.empty((F.shape[0], 2, 2))
    C[:, 0, 0] = F1[:, 0] * F1[:, 0] + F1[:, 1] * F1[:, 1] + F1[:, 2] * F1[:, 2]
    C[:, 1, 1] = F2[:, 0] * F2[:, 0] + F2[:, 1] * F2[:, 1] + F2[:, 2] * F2[:, 2]
    C[:, 0, 1] = F1[:, 0] * F2[:, 0] + F1[:, 1] * F2[:, 1] + F1[:, 2] * F2[:, 2]
    C[:, 1, 0] = C[:, 0, 1]
    return C


def current_normal(F: np.ndarray) -> np.ndarray:
    """Unit normal n = F A1 x F A2 / |F A1 x F A2| of the deformed elements, (n, 3)."""
    n = cross(F[:, :, 0], F[:, :, 1])
    return n / np.linalg.norm(n, axis=1)[:, None]
