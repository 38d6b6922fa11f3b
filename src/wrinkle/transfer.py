"""Nodal fields moved between two meshes of the same reference surface, by point location.

``PointTransfer(coarse, fine)`` finds, for each node p of the fine mesh, the closest point q
of the coarse mesh's triangulated surface (reference coordinates, in 3-D, so the meshes may
be curved, a cylinder or a sphere) and the coarse triangle T holding it, and interpolates a
coarse nodal field linearly there:

    v(p) = λ_a v_a + λ_b v_b + λ_c v_c,    q = λ_a X_a + λ_b X_b + λ_c X_c,

λ ≥ 0, λ_a + λ_b + λ_c = 1, the barycentric coordinates of q in T (a point of T, inside
or on its edges). The meshes need not be nested: independent gmsh meshes of one geometry
will do. Where p lies on the coarse surface (flat meshes of one domain) a field linear in
the reference coordinates is reproduced exactly; on a curved surface the error of a smooth
field is of order h² (h the coarse element size), as is the distance from p to the facets.

The search (``closest_points``) is vectorised. Candidates for each fine node are the k
coarse triangles with the nearest centroids (``scipy.spatial.cKDTree``), and the closest
point on each candidate is computed in one pass (``closest_on_triangles``). The result is
proved to be the closest point of the whole surface where the k-th centroid distance r_k
satisfies r_k ≥ d + R, with d the best candidate's distance and R the largest distance from
a coarse triangle's centroid to its corners: a triangle T outside the candidates is at least
|p − c_T| − R ≥ r_k − R ≥ d from p. Nodes for which this does not hold search again with 4k
candidates, until it holds for all (at most all the triangles).

A fine node farther from the coarse surface than ``MAX_GAP`` times the longest edge of the
closest coarse triangle is refused: the meshes do not cover the same surface (ValueError).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from wrinkle.mesh import Mesh

__all__ = ["MAX_GAP", "PointTransfer", "closest_on_triangles", "closest_points"]

# a fine node may be this many times the longest edge of its coarse triangle off the coarse
# surface: the gap a facet of a curved surface leaves is (its edge)² / (6 radius) or so, a
# quarter of the edge for an edge of 1.5 radii; a fine mesh sticking out of the coarse one by
# more than a quarter of an element is refused
MAX_GAP = 0.25
FIRST_CANDIDATES = 8  # coarse triangles tried first per fine node (k above)
PAIRS_PER_BLOCK = 1 << 20  # (node, candidate) pairs evaluated at once, for the memory


def closest_on_triangles(points: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """The barycentric coordinates, (n, 3), of the point of each triangle closest to each
    point: points (n, 3), corners (n, 3, 3) (triangle i's corners a, b, c in rows). The
    Voronoi regions of the corners, edges and face of each triangle (Ericson, Real-Time
    Collision Detection, 5.1.5), tested for all points at once."""
    a, b, c = corners.transpose(1, 2, 0)  # (3 components, n) each
    ab, ac, ap = b - a, c - a, points.T - a

    def dot(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]

    d1, d2 = dot(ab, ap), dot(ac, ap)
    ab_ab, ab_ac, ac_ac = dot(ab, ab), dot(ab, ac), dot(ac, ac)
    d3, d4 = d1 - ab_ab, d2 - ab_ac  # ab.bp, ac.bp with bp = ap - ab
    d5, d6 = d1 - ab_ac, d2 - ac_ac  # ab.cp, ac.cp with cp = ap - ac
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        total = va + vb + vc
        v, w = vb / total, vc / total  # inside the face: q = a + v ab + w ac
        on_ab = d1 / (d1 - d3)
        on_ac = d2 / (d2 - d6)
        on_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    # the regions in reverse order of Ericson's tests, so that the first test that holds wins
    regions = [
        ((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), 1.0 - on_bc, on_bc),  # edge bc
        ((vb <= 0) & (d2 >= 0) & (d6 <= 0), 0.0, on_ac),  # edge ac
        ((d6 >= 0) & (d5 <= d6), 0.0, 1.0),  # corner c
        ((vc <= 0) & (d1 >= 0) & (d3 <= 0), on_ab, 0.0),  # edge ab
        ((d3 >= 0) & (d4 <= d3), 1.0, 0.0),  # corner b
        ((d1 <= 0) & (d2 <= 0), 0.0, 0.0),  # corner a
    ]
    for mask, v_there, w_there in regions:
        v = np.where(mask, v_there, v)
        w = np.where(mask, w_there, w)
    # -1e-16 for a point on an edge, from the face's formula: clipped, the sum kept at 1
    v, w = np.clip(v, 0.0, 1.0), np.clip(w, 0.0, 1.0)
    u = np.clip(1.0 - v - w, 0.0, 1.0)
    bary = np.column_stack([u, v, w])
    return bary / bary.sum(axis=1, keepdims=True)


def _best_candidates(
    mesh: Mesh, points: np.ndarray, candidates: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Of the candidate triangles of each point, (m, k), the closest: its index (m,), the
    barycentric coordinates of the closest point (m, 3) and the distance (m,)."""
    m, k = candidates.shape
    triangle = np.empty(m, dtype=np.int64)
    bary = np.empty((m, 3))
    distance = np.empty(m)
    rows = max(1, PAIRS_PER_BLOCK // k)
    for start in range(0, m, rows):  # blocks of points, for the memory (not a loop per node)
        block = slice(start, min(m, start + rows))
        tried = candidates[block].ravel()
        repeated = np.repeat(points[block], k, axis=0)
        corners = mesh.nodes[mesh.triangles[tried]]
        weights = closest_on_triangles(repeated, corners)
        closest = np.einsum("ij,ijk->ik", weights, corners)
        gap = np.linalg.norm(repeated - closest, axis=1).reshape(-1, k)
        best = np.argmin(gap, axis=1)
        pick = np.arange(best.size) * k + best
        triangle[block] = tried[pick]
        bary[block] = weights[pick]
        distance[block] = gap[np.arange(best.size), best]
    return triangle, bary, distance


def closest_points(mesh: Mesh, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The closest point of the triangulated surface ``mesh`` to each of ``points`` (n, 3)
    (module docstring): the triangle holding it (n,), its barycentric coordinates in that
    triangle (n, 3) and its distance (n,), in the length unit of the nodes."""
    points = np.asarray(points, dtype=float)
    corners = mesh.nodes[mesh.triangles]
    centroids = corners.mean(axis=1)
    reach = float(np.linalg.norm(corners - centroids[:, None, :], axis=2).max())  # R
    tree = cKDTree(centroids)
    n = points.shape[0]
    triangle = np.empty(n, dtype=np.int64)
    bary = np.empty((n, 3))
    distance = np.empty(n)
    todo = np.arange(n)
    k = FIRST_CANDIDATES
    while todo.size:
        k = min(k, mesh.n_elements)
        found_radii, found_candidates = tree.query(points[todo], k=k, workers=-1)
        radii = np.reshape(found_radii, (todo.size, k))
        candidates = np.reshape(found_candidates, (todo.size, k))
        found = _best_candidates(mesh, points[todo], candidates)
        triangle[todo], bary[todo], distance[todo] = found
        proved = (k == mesh.n_elements) | (radii[:, -1] >= found[2] + reach)
        todo = todo[~proved]
        k *= 4
    return triangle, bary, distance


class PointTransfer:
    """Linear interpolation of the nodal fields of ``coarse`` onto the nodes of ``fine`` at
    their closest points on the coarse surface (module docstring).

    matrix: the interpolation, a sparse (n_fine_nodes, n_coarse_nodes) matrix, three
    barycentric weights per row, each row summing to 1; distance: each fine node's distance
    to the coarse surface, (n_fine_nodes,). names: how the two meshes are called in the
    error (coarse first). Raises ValueError if a fine node is more than ``MAX_GAP`` times the
    longest edge of its closest coarse triangle off the coarse surface.
    """

    def __init__(
        self, coarse: Mesh, fine: Mesh, names: Sequence[str] = ("the coarse mesh", "the fine mesh")
    ):
        triangle, bary, distance = closest_points(coarse, fine.nodes)
        corners = coarse.nodes[coarse.triangles[triangle]]
        edges = corners - np.roll(corners, 1, axis=1)
        size = np.linalg.norm(edges, axis=2).max(axis=1)
        off = np.flatnonzero(distance > MAX_GAP * size)
        if off.size:
            worst = off[np.argmax(distance[off] / size[off])]
            raise ValueError(
                f"the meshes do not cover the same surface: node {worst} of {names[1]} is "
                f"{distance[worst]:.3g} from {names[0]}'s surface (more than {MAX_GAP} times "
                f"its element size there, {size[worst]:.3g})"
            )
        rows = np.repeat(np.arange(fine.n_nodes), 3)
        columns = coarse.triangles[triangle].ravel()
        self.matrix = sp.csr_array(
            (bary.ravel(), (rows, columns)), shape=(fine.n_nodes, coarse.n_nodes)
        )
        self.distance = distance

    def prolong(self, values: np.ndarray) -> np.ndarray:
        """Nodal values of the coarse mesh, (n_coarse_nodes, ...), interpolated onto the fine
        mesh, (n_fine_nodes, ...)."""
        values = np.asarray(values)
        flat = values.reshape(values.shape[0], -1)
        return (self.matrix @ flat).reshape(self.matrix.shape[0], *values.shape[1:])
