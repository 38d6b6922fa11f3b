"""External loads on membranes: follower pressure, edge loads, gravity, all elements at once.

Each load returns, for a batch of load elements (triangles or boundary edges), nodal forces
(n, 3 nodes x 3) at the current configuration and, for follower loads, their derivative with
respect to the nodal displacements ("load stiffness", (n, 9, 9), d f_ext / d u), which enters the
tangent as K = d f_int/du - d f_ext/du. Follower loads have no potential in general, so a model
with them reports no energy and the solvers use the residual norm as merit.
"""

from __future__ import annotations

import numpy as np

from wrinkle.kinematics import cross
from wrinkle.mesh import edge_numbers

__all__ = [
    "boundary_edges",
    "edge_dead_forces",
    "edge_follower_forces",
    "pressure_forces",
    "pressure_volume",
    "pressure_volume_gradient",
    "skew",
    "subtract_pressure_stiffness",
    "unclosed_edges",
]


def skew(a: np.ndarray) -> np.ndarray:
    """Cross-product matrices [a]x with [a]x b = a x b, (n, 3) -> (n, 3, 3)."""
    out = np.zeros(a.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -a[..., 2], a[..., 1]
    out[..., 1, 0], out[..., 1, 2] = a[..., 2], -a[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -a[..., 1], a[..., 0]
    return out


def _area_vector_derivative(x: np.ndarray) -> np.ndarray:
    """d c / d x_l for c = (x2 - x1) x (x3 - x1) = 2 a n, (n, 3 nodes l, 3, 3).

    dc = dx1 x (x2 - x3) + dx2 x (x3 - x1) + dx3 x (x1 - x2), and dx x w = [-w]x dx.
    """
    x1, x2, x3 = x[:, 0], x[:, 1], x[:, 2]
    return np.stack([skew(x3 - x2), skew(x1 - x3), skew(x2 - x1)], axis=1)


def pressure_forces(x: np.ndarray, pressure: np.ndarray, stiffness: bool = True):
    """Nodal forces of a follower pressure on triangles, and their load stiffness.

    x: (n, 3 nodes, 3) current coordinates; pressure: (n,) force per unit current area, positive
    along the current normal (x2 - x1) x (x3 - x1) (counter-clockwise node order).
    Each node takes a third of p a n: f_k = p c / 6 with c = (x2 - x1) x (x3 - x1).
    Returns forces (n, 9) and d f / d u (n, 9, 9) (None if not asked).
    """
    c = cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    f = (pressure[:, None] / 6.0) * c
    forces = np.tile(f, (1, 3))
    if not stiffness:
        return forces, None
    dc = _area_vector_derivative(x) * (pressure[:, None, None, None] / 6.0)  # (n, l, i, j)
    K = np.broadcast_to(dc.transpose(0, 2, 1, 3)[:, None], (x.shape[0], 3, 3, 3, 3))
    return forces, K.reshape(-1, 9, 9).copy()


def subtract_pressure_stiffness(K: np.ndarray, x: np.ndarray, pressure: np.ndarray) -> None:
    """K -= d f / d u of ``pressure_forces``, in place: K (n, 9, 9) element matrices (the
    tangent of the internal minus the external forces), x (n, 3 nodes, 3), pressure (n,).

    Row block k of the load stiffness is the same for every node k (each takes a third of
    p c / 2): block (k, l) is (p / 6) [w_l]x with w_l of ``_area_vector_derivative``, whose six
    off-diagonal entries are subtracted column by column, without (n, 9, 9) or (n, 3, 3, 3)
    temporaries (``wrinkle.compiled.subtract_pressure_stiffness`` is the same loop compiled).
    """
    q = pressure / 6.0
    x1, x2, x3 = x[:, 0], x[:, 1], x[:, 2]
    for l, w in enumerate((x3 - x2, x1 - x3, x2 - x1)):
        a0, a1, a2 = q * w[:, 0], q * w[:, 1], q * w[:, 2]  # (p / 6) w_l
        c = 3 * l
        for r in range(0, 9, 3):  # K -= (p / 6) [w_l]x in block (k, l), r = 3 k
            K[:, r, c + 1] += a2
            K[:, r, c + 2] -= a1
            K[:, r + 1, c] -= a2
            K[:, r + 1, c + 2] += a0
            K[:, r + 2, c] += a1
            K[:, r + 2, c + 1] -= a0


def pressure_volume(x: np.ndarray) -> np.ndarray:
    """Signed volume of the cone from the origin to each triangle, x1.(x2 x x3)/6, (n,).

    Its sum V gives the pressure potential -p V: its gradient equals the follower pressure
    forces at every node except where boundary edges sweep volume out of planes through the
    origin (a boundary held, or moving in a symmetry plane through the origin, sweeps none).
    """
    return np.einsum("ni,ni->n", x[:, 0], cross(x[:, 1], x[:, 2])) / 6.0


def pressure_volume_gradient(x: np.ndarray) -> np.ndarray:
    """Gradient of ``pressure_volume`` with respect to each node's coordinates, (n, 3 nodes,
    3): d/dx1 [x1.(x2 x x3)]/6 = (x2 x x3)/6, and cyclically for x2 and x3."""
    x1, x2, x3 = x[:, 0], x[:, 1], x[:, 2]
    return np.stack([cross(x2, x3), cross(x3, x1), cross(x1, x2)], axis=1) / 6.0


def unclosed_edges(
    nodes: np.ndarray, triangles: np.ndarray, constrained: np.ndarray, tolerance: float
) -> np.ndarray:
    """Boundary edges of the surface ``triangles`` that leave its cone volume from the
    origin (``pressure_volume``) something other than the volume it encloses: (m, 2) node
    pairs. An edge closes the surface if both its nodes are held in all three components
    (the edge cannot sweep volume), or if both lie in one coordinate plane through the origin
    (|X_k| <= tolerance) with that component k held (a symmetry plane, in which the edge can
    only move within the plane). nodes (n_nodes, 3) reference coordinates; constrained
    (3 n_nodes,) bool."""
    edges = boundary_edges(triangles)[0][:, :2]
    held = constrained.reshape(-1, 3)[edges]  # (m, 2, 3)
    in_plane = np.abs(nodes[edges]) <= tolerance  # (m, 2, 3)
    closes = np.all(held, axis=(1, 2)) | np.any(np.all(held & in_plane, axis=1), axis=1)
    return edges[~closes]


def edge_dead_forces(length: np.ndarray, traction: np.ndarray) -> np.ndarray:
    """Dead traction on edges (force per unit reference length) shared by the two end nodes.

    length: (n,) reference edge length; traction: (n, 3). Returns (n, 6) forces.
    """
    half = 0.5 * length[:, None] * traction
    return np.concatenate([half, half], axis=1)


def edge_follower_forces(x: np.ndarray, load: np.ndarray, stiffness: bool = True):
    """Follower normal load on boundary edges, in the membrane plane, per unit current length.

    x: (n, 3 nodes, 3): the edge's two nodes a, b (in the counter-clockwise order of their
    triangle) and the triangle's third node; load: (n,) q, positive pulling outwards. The total
    force q |e| m, with e = x_b - x_a and m = e x n / |e| the outward normal in the plane of the
    current triangle (unit normal n), is q e x n, shared equally by a and b.
    Returns forces (n, 9) (zero on the third node) and d f / d u (n, 9, 9).
    """
    e = x[:, 1] - x[:, 0]
    c = cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    c_norm = np.linalg.norm(c, axis=1)
    n = c / c_norm[:, None]
    half = 0.5 * load[:, None] * cross(e, n)
    forces = np.concatenate([half, half, np.zeros_like(half)], axis=1)
    if not stiffness:
        return forces, None
    # d(e x n) = -[n]x de + [e]x dn,  dn = (I - n n) dc / |c|
    projector = (np.eye(3) - n[:, :, None] * n[:, None, :]) / c_norm[:, None, None]
    dn = np.einsum("nij,nljk->nlik", projector, _area_vector_derivative(x))  # (n, l, 3, 3)
    d = np.einsum("nij,nljk->nlik", skew(e), dn)
    minus_n = -skew(n)
    d[:, 0] -= minus_n  # de = dx_b - dx_a
    d[:, 1] += minus_n
    d *= 0.5 * load[:, None, None, None]
    K = np.zeros((x.shape[0], 3, 3, 3, 3))  # (edge, node k, i, node l, j)
    K[:, 0] = d.transpose(0, 2, 1, 3)
    K[:, 1] = d.transpose(0, 2, 1, 3)
    return forces, K.reshape(-1, 9, 9)


def boundary_edges(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Edges that belong to one triangle only: (m, 3) node triples (a, b, third) with a -> b in
    the triangle's counter-clockwise order, and (m,) the triangle index."""
    local = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1]])
    triples = triangles[:, local].reshape(-1, 3)  # (3 n, 3): a, b, c per edge
    owner = np.repeat(np.arange(triangles.shape[0]), 3)
    _, edge_of, counts = edge_numbers(triangles, int(triangles.max(initial=-1)) + 1)
    single = counts[edge_of.ravel()] == 1  # the edges in the order of triples
    return triples[single], owner[single]
