"""Uniform refinement of a triangle mesh: each triangle into four, the named sets carried along.

``refine(mesh)`` puts a node at the midpoint of every edge and splits each triangle (a, b, c)
with edge midpoints m_ab, m_bc, m_ca into (a, m_ab, m_ca), (m_ab, b, m_bc), (m_ca, m_bc, c) and
(m_ab, m_bc, m_ca), all in the parent's orientation. The coarse nodes keep their numbers, the
midpoints follow them, and the children of element e are 4e .. 4e + 3, so that

- element sets and per-element data (``Mesh.cell_data``, e.g. a fibre field) pass to the
  children of each element;
- a node set gains the midpoint of an edge whose two ends are in it; where every node of the
  set lies on the mesh boundary (an edge or a seam, such as a gmsh physical line), only
  boundary edges count, so a set made of two boundary lines that meet at a corner does not
  gain the midpoint of the diagonal that cuts the corner.

The refined mesh is the same piecewise flat surface: a midpoint lies on the straight edge, not
on a curved surface the coarse mesh approximates (refine a sphere or a cylinder by its
generator's own counts instead). Linear (P1) fields are interpolated exactly by
``Refinement.prolong``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrinkle.mesh import Mesh, mesh_edges

__all__ = ["MAX_REFINED_ELEMENTS", "Refinement", "refine", "refined"]

# the largest mesh ``refined`` makes (the performance docs measure up to 10^6 elements)
MAX_REFINED_ELEMENTS = 20_000_000


@dataclass(frozen=True)
class Refinement:
    """A mesh refined once: the fine mesh and, for each of its midpoint nodes (numbered from
    the coarse mesh's n_nodes on), the two coarse nodes of its edge, (n_midpoints, 2)."""

    mesh: Mesh
    edges: np.ndarray

    def prolong(self, values: np.ndarray) -> np.ndarray:
        """Nodal values of the coarse mesh, (n_coarse_nodes, ...), interpolated linearly onto
        the fine mesh, (n_fine_nodes, ...): kept at the coarse nodes, the mean of the edge's
        ends at each midpoint."""
        values = np.asarray(values)
        midpoints = 0.5 * (values[self.edges[:, 0]] + values[self.edges[:, 1]])
        return np.concatenate([values, midpoints])


def refine(mesh: Mesh) -> Refinement:
    """The mesh with each triangle split into four (module docstring)."""
    n_nodes, triangles = mesh.n_nodes, mesh.triangles
    edges, edge_of, sharing = mesh_edges(mesh)
    nodes = np.vstack([mesh.nodes, 0.5 * (mesh.nodes[edges[:, 0]] + mesh.nodes[edges[:, 1]])])
    a, b, c = triangles.T
    ab, bc, ca = (n_nodes + edge_of).T
    children = np.stack(
        [
            np.column_stack([a, ab, ca]),
            np.column_stack([ab, b, bc]),
            np.column_stack([ca, bc, c]),
            np.column_stack([ab, bc, ca]),
        ],
        axis=1,
    ).reshape(-1, 3)

    on_boundary = np.zeros(n_nodes, dtype=bool)
    boundary_edges = sharing == 1
    on_boundary[edges[boundary_edges].ravel()] = True
    node_sets = {}
    for name, members in mesh.node_sets.items():
        inside = np.zeros(n_nodes, dtype=bool)
        inside[members] = True
        gains = inside[edges[:, 0]] & inside[edges[:, 1]]
        if members.size and np.all(on_boundary[members]):
            gains &= boundary_edges
        node_sets[name] = np.concatenate([members, n_nodes + np.flatnonzero(gains)])
    element_sets = {
        name: (4 * members[:, None] + np.arange(4)).ravel()
        for name, members in mesh.element_sets.items()
    }
    cell_data = {name: np.repeat(values, 4, axis=0) for name, values in mesh.cell_data.items()}
    fine = Mesh(nodes, children, node_sets, element_sets, cell_data)
    return Refinement(fine, edges)


def refined(mesh: Mesh, times: int) -> Mesh:
    """The mesh refined ``times`` times (4^times as many elements). Raises ValueError for a
    negative count or a mesh that would exceed ``MAX_REFINED_ELEMENTS`` elements."""
    if times < 0:
        raise ValueError(f"refine must be an integer >= 0, got {times}")
    if mesh.n_elements * 4**times > MAX_REFINED_ELEMENTS:
        raise ValueError(
            f"refining {mesh.n_elements:,} elements {times} times would make "
            f"{float(mesh.n_elements) * 4.0 ** min(times, 400):.3g} elements "
            f"(at most {MAX_REFINED_ELEMENTS:,})"
        )
    for _ in range(times):
        mesh = refine(mesh).mesh
    return mesh
