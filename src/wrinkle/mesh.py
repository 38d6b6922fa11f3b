"""Triangle meshes of membranes: nodes, triangles, checks and generators."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Mesh:
    """A triangle mesh in 3-D.

    nodes: (n_nodes, 3) reference coordinates (a (n_nodes, 2) array is taken as z = 0).
    triangles: (n_elements, 3) node indices, counter-clockwise seen from the membrane normal.
    node_sets: named (k,) arrays of node indices (e.g. physical groups).
    Raises ValueError naming the element or node at fault.
    """

    nodes: np.ndarray
    triangles: np.ndarray
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self):
        nodes = np.asarray(self.nodes, dtype=float)
        if nodes.ndim != 2 or nodes.shape[1] not in (2, 3):
            raise ValueError(f"mesh nodes must be shaped (n, 2) or (n, 3), got {nodes.shape}")
        if nodes.shape[1] == 2:
            nodes = np.column_stack([nodes, np.zeros(nodes.shape[0])])
        bad = np.flatnonzero(~np.all(np.isfinite(nodes), axis=1))
        if bad.size:
            raise ValueError(f"node {bad[0]} has a non-finite coordinate {nodes[bad[0]].tolist()}")
        triangles = np.asarray(self.triangles)
        if triangles.ndim != 2 or triangles.shape[1] != 3:
            raise ValueError(f"mesh triangles must be shaped (n, 3), got {triangles.shape}")
        if not np.issubdtype(triangles.dtype, np.integer):
            raise ValueError("mesh triangles must hold integer node indices")
        out = np.flatnonzero(np.any((triangles < 0) | (triangles >= nodes.shape[0]), axis=1))
        if out.size:
            raise ValueError(
                f"element {out[0]} refers to node(s) {triangles[out[0]].tolist()} "
                f"outside 0..{nodes.shape[0] - 1}"
            )
        repeated = np.flatnonzero(
            (triangles[:, 0] == triangles[:, 1])
            | (triangles[:, 1] == triangles[:, 2])
            | (triangles[:, 0] == triangles[:, 2])
        )
        if repeated.size:
            raise ValueError(f"element {repeated[0]} repeats a node: {triangles[repeated[0]]}")
        key = np.sort(triangles, axis=1)
        _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
        if np.any(counts > 1):
            dup = np.flatnonzero(np.all(key == key[first[counts > 1][0]], axis=1))
            raise ValueError(f"elements {dup.tolist()} are duplicates (same three nodes)")
        self.nodes = nodes
        self.triangles = triangles.astype(np.int64)
        self.node_sets = {name: np.asarray(v, dtype=np.int64) for name, v in self.node_sets.items()}

    @property
    def n_nodes(self) -> int:
        return self.nodes.shape[0]

    @property
    def n_elements(self) -> int:
        return self.triangles.shape[0]


def rectangle(width: float, height: float, nx: int, ny: int, diagonal: str = "right") -> Mesh:
    """Structured mesh of [0, width] x [0, height] in the plane z = 0.

    nx, ny: numbers of squares along x and y, each split into two triangles along the diagonal
    from its lower-left to upper-right corner (``diagonal="right"``) or the other one ("left").
    Node sets "left", "right", "bottom", "top" name the edges (corners included).
    Node numbering: row by row from the lower-left corner, node (i, j) = j (nx + 1) + i.
    """
    if width <= 0 or height <= 0:
        raise ValueError(f"rectangle: width and height must be > 0, got {width}, {height}")
    if int(nx) < 1 or int(ny) < 1:
        raise ValueError(f"rectangle: nx and ny must be >= 1, got {nx}, {ny}")
    x = np.linspace(0.0, width, nx + 1)
    y = np.linspace(0.0, height, ny + 1)
    X, Y = np.meshgrid(x, y)
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    n00 = (j * (nx + 1) + i).ravel()
    n10, n01, n11 = n00 + 1, n00 + nx + 1, n00 + nx + 2
    if diagonal == "right":
        triangles = np.concatenate([np.column_stack([n00, n10, n11]), np.column_stack([n00, n11, n01])])
    elif diagonal == "left":
        triangles = np.concatenate([np.column_stack([n00, n10, n01]), np.column_stack([n10, n11, n01])])
    else:
        raise ValueError(f"rectangle: diagonal must be 'right' or 'left', got {diagonal!r}")
    grid = np.arange(nodes.shape[0]).reshape(ny + 1, nx + 1)
    sets = {"bottom": grid[0], "top": grid[-1], "left": grid[:, 0], "right": grid[:, -1]}
    return Mesh(nodes, triangles, sets)
