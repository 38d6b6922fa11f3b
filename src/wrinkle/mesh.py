"""Triangle meshes of membranes: nodes, triangles, named sets, checks, generators and
reading mesh files through meshio."""

from __future__ import annotations

import contextlib
import io
import math
import os
import re
import tempfile
from dataclasses import dataclass, field
from numbers import Integral, Real
from pathlib import Path
from types import ModuleType

import numpy as np

__all__ = [
    "require_meshio",
    "write_mesh",
    "Mesh",
    "annulus",
    "boundary_nodes",
    "edge_numbers",
    "mesh_edges",
    "cylinder",
    "disk",
    "mesh_size",
    "read_mesh",
    "rectangle",
    "sphere",
]


@dataclass
class Mesh:
    """A triangle mesh in 3-D.

    nodes: (n_nodes, 3) reference coordinates (a (n_nodes, 2) array is taken as z = 0).
    triangles: (n_elements, 3) node indices, counter-clockwise seen from the membrane normal.
    node_sets: named (k,) arrays of node indices (e.g. physical groups, edges).
    element_sets: named (k,) arrays of element indices (e.g. physical groups of surfaces).
    cell_data: named per-element arrays (n_elements, ...) read with the mesh, e.g. a fibre
        direction (n_elements, 3).
    Raises ValueError naming the element, node or set at fault.
    """

    nodes: np.ndarray
    triangles: np.ndarray
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)
    element_sets: dict[str, np.ndarray] = field(default_factory=dict)
    cell_data: dict[str, np.ndarray] = field(default_factory=dict)

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
        _, first, counts = np.unique(
            _triangle_codes(key, nodes.shape[0]), return_index=True, return_counts=True
        )
        if np.any(counts > 1):
            dup = np.flatnonzero(np.all(key == key[first[counts > 1][0]], axis=1))
            raise ValueError(f"elements {dup.tolist()} are duplicates (same three nodes)")
        # every triangle goes round the same way: then each directed edge (a -> b) belongs
        # to one triangle at most, its neighbour across the edge running b -> a
        directed = triangles[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2).astype(np.int64)
        keys = directed[:, 0] * nodes.shape[0] + directed[:, 1]
        unique_keys, key_counts = np.unique(keys, return_counts=True)
        if np.any(key_counts > 1):
            shared = unique_keys[np.argmax(key_counts > 1)]
            first_pair = np.flatnonzero(keys == shared) // 3
            a, b = divmod(int(shared), nodes.shape[0])
            raise ValueError(
                f"elements {first_pair.tolist()} are oriented oppositely: both run their shared "
                f"edge from node {a} to node {b} (an inverted element: the nodes of every "
                "triangle must go round the same way); reverse the node order of one of them"
            )
        self.nodes = nodes
        self.triangles = triangles.astype(np.int64)
        self.node_sets = _checked_sets(self.node_sets, "node", nodes.shape[0])
        self.element_sets = _checked_sets(self.element_sets, "element", triangles.shape[0])

    @property
    def n_nodes(self) -> int:
        return self.nodes.shape[0]

    @property
    def n_elements(self) -> int:
        return self.triangles.shape[0]


def _checked_sets(sets: dict, kind: str, count: int) -> dict[str, np.ndarray]:
    """Named index sets as (k,) int64 arrays, each index checked to lie in 0 .. count - 1.

    kind: "node" or "element", for the messages."""
    checked = {}
    for name, values in dict(sets).items():
        if not isinstance(name, str):
            raise TypeError(f"{kind} set names must be strings, got {name!r}")
        indices = np.atleast_1d(np.asarray(values))
        if indices.ndim != 1:
            raise ValueError(
                f"{kind} set {name!r} must be a flat list of {kind} indices, "
                f"got shape {indices.shape}"
            )
        if indices.size == 0:
            indices = indices.astype(np.int64)
        if not np.issubdtype(indices.dtype, np.integer):
            raise ValueError(f"{kind} set {name!r} must hold integer {kind} indices")
        outside = (indices < 0) | (indices >= count)
        if np.any(outside):
            raise ValueError(
                f"{kind} set {name!r} refers to {kind} {int(indices[outside][0])} "
                f"outside 0..{count - 1}"
            )
        checked[name] = indices.astype(np.int64)
    return checked


def _triangle_codes(key: np.ndarray, n_nodes: int) -> np.ndarray:
    """One number for each row of key (m, 3) node indices below n_nodes, equal only for equal
    rows: (a n + b) n + c where n^3 fits in int64 (NumPy's unique of rows sorts a
    structured view instead, 0.4 s at 10^6 triangles), else the rows as a structured view."""
    if n_nodes < 2_000_000:
        key = key.astype(np.int64)
        return (key[:, 0] * n_nodes + key[:, 1]) * n_nodes + key[:, 2]
    rows = np.ascontiguousarray(key)
    return rows.view([("", rows.dtype)] * 3).ravel()


def _sorted_unique(values: np.ndarray) -> np.ndarray:
    """np.unique of a 1-D integer array by one sort (np.unique is far slower on 10^6 values
    with some NumPy versions)."""
    values = np.sort(np.asarray(values).ravel())
    return values[np.concatenate([[True], values[1:] != values[:-1]])] if values.size else values


def edge_numbers(triangles: np.ndarray, n_nodes: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The edges of triangles (m, 3) over nodes below n_nodes, each as one integer, lower
    node x n_nodes + higher node (sorting integers, not rows of pairs: 20 against 110 ms at
    10^5 triangles): the sorted keys (n_edges,), each triangle's edge numbers for its edges
    (a, b), (b, c), (c, a), (m, 3), and how many triangles share each edge, (n_edges,)."""
    pairs = triangles[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2).astype(np.int64)
    keys = np.minimum(pairs[:, 0], pairs[:, 1]) * n_nodes + np.maximum(pairs[:, 0], pairs[:, 1])
    unique, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
    return unique, inverse.reshape(-1, 3), counts


def mesh_edges(mesh: Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mesh's edges: (n_edges, 2) node pairs, lower node first, sorted; each triangle's
    edge numbers for its edges (a, b), (b, c), (c, a), (n_elements, 3); and how many
    triangles share each edge, (n_edges,) (1 on the boundary)."""
    keys, edge_of, counts = edge_numbers(mesh.triangles, mesh.n_nodes)
    return np.column_stack(np.divmod(keys, mesh.n_nodes)), edge_of, counts


def boundary_nodes(mesh: Mesh) -> np.ndarray:
    """(n_nodes,) bool: the nodes on an edge that only one triangle has."""
    edges, _, counts = mesh_edges(mesh)
    boundary = np.zeros(mesh.n_nodes, dtype=bool)
    boundary[edges[counts == 1].ravel()] = True
    return boundary


def mesh_size(mesh: Mesh) -> float:
    """Mean length of the mesh edges (each edge shared by two triangles counted once), in
    the length unit of the nodes: the scale for geometric tolerances."""
    if mesh.n_elements == 0:
        raise ValueError("mesh_size: the mesh has no elements")
    edges = np.sort(mesh.triangles[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    keys = _sorted_unique(edges[:, 0] * mesh.n_nodes + edges[:, 1])
    first, second = np.divmod(keys, mesh.n_nodes)
    return float(np.mean(np.linalg.norm(mesh.nodes[second] - mesh.nodes[first], axis=1)))


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
    check_fits(2 * int(nx) * int(ny), f"rectangle: nx = {nx} by ny = {ny}")
    x = np.linspace(0.0, width, nx + 1)
    y = np.linspace(0.0, height, ny + 1)
    X, Y = np.meshgrid(x, y)
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    n00 = (j * (nx + 1) + i).ravel()
    n10, n01, n11 = n00 + 1, n00 + nx + 1, n00 + nx + 2
    if diagonal == "right":
        triangles = np.concatenate(
            [np.column_stack([n00, n10, n11]), np.column_stack([n00, n11, n01])]
        )
    elif diagonal == "left":
        triangles = np.concatenate(
            [np.column_stack([n00, n10, n01]), np.column_stack([n10, n11, n01])]
        )
    else:
        raise ValueError(f"rectangle: diagonal must be 'right' or 'left', got {diagonal!r}")
    grid = np.arange(nodes.shape[0]).reshape(ny + 1, nx + 1)
    sets = {"bottom": grid[0], "top": grid[-1], "left": grid[:, 0], "right": grid[:, -1]}
    return Mesh(nodes, triangles, sets)


# the peak memory of a solve per element: 6.3 GB for the 10^6-element airbag (PARDISO's LDL^T
# factor; docs/performance.md), a lower bound (its bending version needs 12.5 GB)
BYTES_PER_ELEMENT = 6_300


def machine_memory() -> int | None:
    """Physical memory of this machine in bytes, None where the system does not say."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, OSError, ValueError):
        return None


def check_fits(n_elements: int, what: str) -> None:
    """Raise ValueError, before anything is allocated, if a mesh of ``n_elements`` triangles
    cannot be solved in this machine's memory (BYTES_PER_ELEMENT each, a lower bound); the
    message starts with ``what`` and gives the estimate."""
    memory = machine_memory()
    needed = n_elements * BYTES_PER_ELEMENT
    if memory is not None and needed > memory:
        raise ValueError(
            f"{what} gives {n_elements:.3g} elements; solving them needs at least "
            f"{needed / 1e9:.3g} GB ({BYTES_PER_ELEMENT / 1e3:.1f} kB per element, measured), "
            f"more than this machine's {memory / 1e9:.3g} GB"
        )


def _check_count(generator: str, name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, Integral) or value < minimum:
        raise ValueError(f"{generator}: {name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _check_length(generator: str, name: str, value, allow_zero: bool = False) -> float:
    if (
        isinstance(value, bool)
        or not isinstance(value, Real)
        or not math.isfinite(value)
        or value < 0
        or (value == 0 and not allow_zero)
    ):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{generator}: {name} must be a finite number {bound}, got {value!r}")
    return float(value)


def _polar_rings(radii: np.ndarray, n_circumferential: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes on concentric circles and the triangles between consecutive circles.

    radii: (n_rings,) increasing, all > 0. Node (i, j) = i n_circumferential + j sits at radius
    radii[i], angle 2 pi j / n_circumferential. Each quadrilateral (i, j), (i+1, j),
    (i+1, j+1), (i, j+1) is split along its diagonal (i, j)-(i+1, j+1) into two triangles,
    counter-clockwise seen from +z. Returns nodes (n_rings n_circumferential, 3) and
    triangles (2 (n_rings - 1) n_circumferential, 3)."""
    angle = 2.0 * np.pi * np.arange(n_circumferential) / n_circumferential
    r, a = np.meshgrid(radii, angle, indexing="ij")
    nodes = np.column_stack([(r * np.cos(a)).ravel(), (r * np.sin(a)).ravel(), np.zeros(r.size)])
    i, j = np.meshgrid(np.arange(radii.size - 1), np.arange(n_circumferential), indexing="ij")
    inner = i * n_circumferential + j
    inner_next = i * n_circumferential + (j + 1) % n_circumferential
    outer, outer_next = inner + n_circumferential, inner_next + n_circumferential
    triangles = np.concatenate(
        [
            np.column_stack([inner.ravel(), outer.ravel(), outer_next.ravel()]),
            np.column_stack([inner.ravel(), outer_next.ravel(), inner_next.ravel()]),
        ]
    )
    return nodes, triangles


def annulus(
    inner_radius: float, outer_radius: float, n_radial: int, n_circumferential: int
) -> Mesh:
    """Structured polar mesh of the ring inner_radius <= r <= outer_radius in the plane z = 0.

    n_radial rings of elements of equal radial width, n_circumferential nodes on every circle
    (the first at angle 0, on the +x axis); each ring sector is split into two triangles,
    counter-clockwise seen from +z. Node (i, j), on circle i = 0 .. n_radial (from the inside)
    at angle 2 pi j / n_circumferential, is numbered i n_circumferential + j. Node sets
    "inner" and "outer" name the two circles. The mesh is the ring between two inscribed
    polygons: its area is n_circumferential / 2 sin(2 pi / n_circumferential)
    (outer_radius**2 - inner_radius**2), which tends to pi (outer_radius**2 - inner_radius**2).
    Use ``disk`` for a full disk (inner radius 0).
    """
    inner_radius = _check_length("annulus", "inner_radius", inner_radius, allow_zero=True)
    outer_radius = _check_length("annulus", "outer_radius", outer_radius)
    if inner_radius == 0.0:
        raise ValueError("annulus: inner_radius must be > 0 (use disk for a full disk)")
    if inner_radius >= outer_radius:
        raise ValueError(
            f"annulus: inner_radius must be < outer_radius, got {inner_radius!r} >= "
            f"{outer_radius!r}"
        )
    n_radial = _check_count("annulus", "n_radial", n_radial, 1)
    n_circumferential = _check_count("annulus", "n_circumferential", n_circumferential, 3)
    check_fits(2 * n_radial * n_circumferential, "annulus: n_radial by n_circumferential")
    radii = np.linspace(inner_radius, outer_radius, n_radial + 1)
    nodes, triangles = _polar_rings(radii, n_circumferential)
    sets = {
        "inner": np.arange(n_circumferential),
        "outer": n_radial * n_circumferential + np.arange(n_circumferential),
    }
    return Mesh(nodes, triangles, sets)


def disk(radius: float, n_radial: int, n_circumferential: int) -> Mesh:
    """Structured polar mesh of the disk r <= radius in the plane z = 0.

    Node 0 is the centre; circles i = 1 .. n_radial at radius i radius / n_radial carry
    n_circumferential nodes each, node (i, j) at angle 2 pi j / n_circumferential numbered
    1 + (i - 1) n_circumferential + j. The first ring is a fan of n_circumferential triangles
    around the centre, the other rings are split as in ``annulus``; all triangles are
    counter-clockwise seen from +z. Node set "outer" names the boundary circle. Area:
    n_circumferential / 2 sin(2 pi / n_circumferential) radius**2 (the inscribed polygon).
    """
    radius = _check_length("disk", "radius", radius)
    n_radial = _check_count("disk", "n_radial", n_radial, 1)
    n_circumferential = _check_count("disk", "n_circumferential", n_circumferential, 3)
    check_fits(2 * n_radial * n_circumferential, "disk: n_radial by n_circumferential")
    radii = radius * np.arange(1, n_radial + 1) / n_radial
    ring_nodes, ring_triangles = _polar_rings(radii, n_circumferential)
    first = 1 + np.arange(n_circumferential)
    fan = np.column_stack([np.zeros(n_circumferential, dtype=np.int64), first, np.roll(first, -1)])
    nodes = np.vstack([np.zeros((1, 3)), ring_nodes])
    triangles = np.vstack([fan, 1 + ring_triangles])
    sets = {"outer": 1 + (n_radial - 1) * n_circumferential + np.arange(n_circumferential)}
    return Mesh(nodes, triangles, sets)


def sphere(radius: float, n: int) -> Mesh:
    """One octant x, y, z >= 0 of the sphere |X| = radius: a subdivided octahedron face.

    The face with corners radius e_x, radius e_y, radius e_z is cut into n**2 triangles by
    n - 1 lines parallel to each side; its node with the integer barycentric coordinates
    (i, j, k), i + j + k = n, goes onto the sphere at

        X = radius d / |d|,    d = (sin(pi i / 2n), sin(pi j / 2n), sin(pi k / 2n)),

    so that every node lies on the sphere, the nodes of the three edges (i = 0: x = 0;
    j = 0: y = 0; k = 0: z = 0, exactly) are equally spaced in angle, and the element areas
    differ by less than a factor 1.8 (plain central projection of the flat face, d = (i, j,
    k), gives a factor 5). Nodes are numbered row by row, k = 0 .. n, and along each row
    j = 0 .. n - k: node (j, k) is k (2n + 3 - k) / 2 + j. Triangles are counter-clockwise
    seen from outside (normal (X2 - X1) x (X3 - X1) pointing away from the centre), so a
    positive follower pressure inflates the octant. Node sets "yz-plane", "zx-plane" and
    "xy-plane" name the three edges x = 0, y = 0, z = 0. (n + 1)(n + 2)/2 nodes, n**2
    triangles; the faceted area tends to pi radius**2 / 2 with an error of order (1/n)**2.
    """
    radius = _check_length("sphere", "radius", radius)
    n = _check_count("sphere", "n", n, 1)
    check_fits(n * n, f"sphere: n = {n}")
    k = np.repeat(np.arange(n + 1), np.arange(n + 1, 0, -1))
    row_start = k * (2 * n + 3 - k) // 2
    j = np.arange(k.size) - row_start
    i = n - j - k
    direction = np.sin(0.5 * np.pi * np.column_stack([i, j, k]) / n)
    nodes = radius * direction / np.linalg.norm(direction, axis=1)[:, None]

    def node(j, k):
        return k * (2 * n + 3 - k) // 2 + j

    up = i > 0  # the triangle (j, k), (j + 1, k), (j, k + 1) above each node off side i = 0
    down = i > 1  # the triangle (j + 1, k), (j + 1, k + 1), (j, k + 1)
    triangles = np.concatenate(
        [
            np.column_stack([node(j[up], k[up]), node(j[up] + 1, k[up]), node(j[up], k[up] + 1)]),
            np.column_stack(
                [
                    node(j[down] + 1, k[down]),
                    node(j[down] + 1, k[down] + 1),
                    node(j[down], k[down] + 1),
                ]
            ),
        ]
    )
    sets = {
        "yz-plane": np.flatnonzero(i == 0),
        "zx-plane": np.flatnonzero(j == 0),
        "xy-plane": np.flatnonzero(k == 0),
    }
    return Mesh(nodes, triangles, sets)


def cylinder(
    radius: float, length: float, n_circumferential: int, n_axial: int, n_cap: int
) -> Mesh:
    """Closed circular tube along x: the wall 0 <= x <= length at distance ``radius`` from the
    x axis, closed by two flat circular end caps, x = 0 ("root") and x = length ("tip").

    The wall has n_axial + 1 circles of n_circumferential nodes; wall node (i, j), at
    x = i length / n_axial and angle theta_j = 2 pi j / n_circumferential from +y towards +z,
    (x, radius cos theta_j, radius sin theta_j), is numbered i n_circumferential + j; each
    quadrilateral (i, j) between two circles is split into two triangles as in ``annulus``,
    elements i n_circumferential + j and (n_axial + i) n_circumferential + j. Each cap
    is a ``disk`` of n_cap rings of elements whose outer circle is the wall's end circle: its
    centre and then its inner circles k = 1 .. n_cap - 1 (radius k radius / n_cap, nodes at
    the angles theta_j) follow the wall nodes, the root cap's before the tip cap's. All
    triangles are counter-clockwise seen from outside (normal (X2 - X1) x (X3 - X1) pointing
    out of the tube), so a positive follower pressure inflates it.

    Node sets: "root" and "tip" (the wall's end circles), "root_cap" and "tip_cap" (all nodes
    of a cap, its circle included). Element sets: "wall", "root_cap", "tip_cap". With
    n_cap = 0 the tube is open (the wall alone, no caps or their sets: a tube between two
    rings, such as a catenoid's start). With caps the surface is closed (every edge is
    shared by exactly two triangles) and encloses the prism on the inscribed polygon, volume
    n_circumferential / 2 sin(2 pi / n_circumferential) radius**2 length, which tends to
    pi radius**2 length with an error of order (1 / n_circumferential)**2.
    """
    radius = _check_length("cylinder", "radius", radius)
    length = _check_length("cylinder", "length", length)
    n_circumferential = _check_count("cylinder", "n_circumferential", n_circumferential, 3)
    n_axial = _check_count("cylinder", "n_axial", n_axial, 1)
    n_cap = _check_count("cylinder", "n_cap", n_cap, 0)
    check_fits(2 * n_circumferential * (n_axial + 2 * n_cap), "cylinder: the wall and the end caps")
    n = n_circumferential
    # the wall: an annulus's connectivity with its circles placed along x (the annulus's
    # counter-clockwise order, mapped onto the tube, faces inwards: two nodes swapped)
    _, wall = _polar_rings(np.arange(1.0, n_axial + 2.0), n)
    wall = wall[:, [0, 2, 1]]
    angle = 2.0 * np.pi * np.arange(n) / n
    x = np.repeat(length * np.arange(n_axial + 1) / n_axial, n)
    wall_nodes = np.column_stack(
        [
            x,
            radius * np.tile(np.cos(angle), n_axial + 1),
            radius * np.tile(np.sin(angle), n_axial + 1),
        ]
    )
    n_wall = wall_nodes.shape[0]
    if n_cap == 0:  # an open tube
        ends = {"root": np.arange(n), "tip": n_axial * n + np.arange(n)}
        return Mesh(wall_nodes, wall, ends, {"wall": np.arange(wall.shape[0])})
    # a cap: a disk in the (y, z) plane, local node 0 its centre, 1 + (k - 1) n + j on circle k;
    # counter-clockwise seen from +x (y x z = x), i.e. from outside at the tip
    ring_nodes, ring_triangles = _polar_rings(radius * np.arange(1, n_cap + 1) / n_cap, n)
    first = 1 + np.arange(n)
    fan = np.column_stack([np.zeros(n, dtype=np.int64), first, np.roll(first, -1)])
    cap_triangles = np.vstack([fan, 1 + ring_triangles])
    cap_yz = np.vstack([np.zeros((1, 2)), ring_nodes[: (n_cap - 1) * n, :2]])  # inner nodes
    n_inner = cap_yz.shape[0]
    nodes, triangles = [wall_nodes], [wall]
    node_sets = {"root": np.arange(n), "tip": n_axial * n + np.arange(n)}
    element_sets = {"wall": np.arange(wall.shape[0])}
    n_elements = wall.shape[0]
    for name, x_cap, ring, offset in (
        ("root_cap", 0.0, node_sets["root"], n_wall),
        ("tip_cap", length, node_sets["tip"], n_wall + n_inner),
    ):
        local_to_global = np.concatenate([offset + np.arange(n_inner), ring])
        cap = local_to_global[cap_triangles]
        triangles.append(cap[:, [0, 2, 1]] if name == "root_cap" else cap)  # root faces -x
        nodes.append(np.column_stack([np.full(n_inner, x_cap), cap_yz]))
        node_sets[name] = local_to_global
        element_sets[name] = n_elements + np.arange(cap.shape[0])
        n_elements += cap.shape[0]
    return Mesh(np.vstack(nodes), np.vstack(triangles), node_sets, element_sets)


# -- reading mesh files through meshio ------------------------------------------------------

_SURFACE_CELLS = {"triangle": 1, "quad": 2}  # triangles per cell
_NODE_GROUP_CELLS = ("vertex", "line")
_CELL_DIMENSION = {"vertex": 0, "line": 1, "triangle": 2, "quad": 2}


def _zero_area_element(nodes: np.ndarray, triangles: np.ndarray) -> int | None:
    """Index of the first triangle whose area is zero to round-off (|(X2 - X1) x (X3 - X1)|
    <= 1e-12 times its longest edge squared, as in ``kinematics.reference_geometry``)."""
    X = nodes[triangles]
    twice_area = np.linalg.norm(np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]), axis=1)
    edges = np.stack([X[:, 1] - X[:, 0], X[:, 2] - X[:, 1], X[:, 0] - X[:, 2]], axis=1)
    size = np.max(np.linalg.norm(edges, axis=2), axis=1)
    degenerate = np.flatnonzero(~(twice_area > 1e-12 * size**2))
    return int(degenerate[0]) if degenerate.size else None


# -- gmsh element data, read by element tag ------------------------------------------------
# meshio reads a gmsh $ElementData section as a list of values for every saved cell in order
# (lines and points included) and fails when it holds values for the triangles only; gmsh
# writes it as (element tag, values) pairs. So wrinkle reads these sections itself, and the
# $Elements section for the tags of the triangles, and gives meshio the file without them.

_SECTION = re.compile(rb"^\$(\w+)[ \t]*\r?$", re.MULTILINE)
_GMSH_SURFACE_TYPES = {2: "triangle", 3: "quad"}  # gmsh element type -> meshio cell type
_GMSH_MISMATCH = (
    "cannot match the gmsh element data to the elements: the cells meshio "
    "reads are not those of the file's $Elements section"
)


@dataclass
class _GmshElementData:
    """What wrinkle reads of an ASCII gmsh file itself.

    surface_tags: (k,) element tags of the triangle and quad elements, in file order;
    surface_types: (k,) their gmsh types (2 triangle, 3 quad); surface_nodes: (k, 4) their
    node tags (-1 after a triangle's three); fields: name -> ((m,) element tags, (m, c)
    values) of each $ElementData view.
    """

    surface_tags: np.ndarray
    surface_types: np.ndarray
    surface_nodes: np.ndarray
    fields: dict[str, tuple[np.ndarray, np.ndarray]]


def _gmsh_sections(content: bytes) -> list[tuple[str, int, int, int]]:
    """(name, start of the header line, start of the body, end of the $End line) of each
    section of a gmsh file, up to the first section without its $End line (meshio then says
    what is wrong with the file)."""
    sections = []
    position = 0
    while (match := _SECTION.search(content, position)) is not None:
        name = match.group(1).decode()
        end = re.compile(rb"^\$End" + re.escape(match.group(1)) + rb"[ \t]*\r?$", re.MULTILINE)
        closing = end.search(content, match.end())
        if closing is None:
            break
        sections.append((name, match.start(), match.end(), closing.end()))
        position = closing.end()
    return sections


def _section_lines(content: bytes, body: int, end: int) -> list[str]:
    """The lines of a section between its header and its $End line (see _gmsh_sections)."""
    return content[body:end].decode().splitlines()[1:-1]


def _gmsh_surface_elements(lines: list[str], version: str) -> tuple[np.ndarray, ...]:
    """Element tags (k,), gmsh types (k,) and node tags (k, 4) of the triangles and quads of
    an ASCII $Elements section (its lines without the header), in file order."""
    tags, types, nodes = [], [], []

    def keep(block_type: int, rows: np.ndarray) -> None:
        if block_type in _GMSH_SURFACE_TYPES and rows.size:
            tags.append(rows[:, 0])
            types.append(np.full(rows.shape[0], block_type))
            corners = np.full((rows.shape[0], 4), -1, dtype=np.int64)
            corners[:, : rows.shape[1] - 1] = rows[:, 1:]
            nodes.append(corners)

    if version.startswith("2"):  # tag type n_tags <tags> nodes..., one element a line
        for line in lines[1:]:
            parts = line.split()
            if len(parts) < 3:
                continue
            element_type, n_tags = int(parts[1]), int(parts[2])
            if element_type in _GMSH_SURFACE_TYPES:
                keep(
                    element_type,
                    np.array([[int(parts[0])] + [int(p) for p in parts[3 + n_tags :]]]),
                )
    else:  # 4.x: blocks "dim entity type count" (4.0: "entity dim type count"), then lines
        n_blocks = int(lines[0].split()[0])
        row = 1
        for _ in range(n_blocks):
            header = lines[row].split()
            block_type, count = int(header[2]), int(header[3])
            block = lines[row + 1 : row + 1 + count]
            row += 1 + count
            if block_type in _GMSH_SURFACE_TYPES and count:
                keep(
                    block_type, np.array(" ".join(block).split(), dtype=np.int64).reshape(count, -1)
                )
    if not tags:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, np.zeros((0, 4), dtype=np.int64)
    return np.concatenate(tags), np.concatenate(types), np.concatenate(nodes)


def _gmsh_element_data(lines: list[str], index: int) -> tuple[str, int, np.ndarray, np.ndarray]:
    """Name, time step, element tags (m,) and values (m, c) of an ASCII $ElementData section
    (its lines without the header): string tags (the first is the name), real tags (the
    time), integer tags (time step, number of components, number of entries, ...), then one
    line "element-tag value..." per entry. ``index`` names an unnamed view."""
    row = 0
    n_strings = int(lines[row])
    strings = [line.strip().strip('"') for line in lines[row + 1 : row + 1 + n_strings]]
    row += 1 + n_strings
    n_reals = int(lines[row])
    row += 1 + n_reals
    n_integers = int(lines[row])
    integers = [int(line) for line in lines[row + 1 : row + 1 + n_integers]]
    row += 1 + n_integers
    name = strings[0] if strings and strings[0] else f"ElementData {index}"
    if len(integers) < 3:
        raise ValueError(
            f"gmsh element data {name!r}: expected 3 integer tags (time step, "
            f"components, entries), got {len(integers)}"
        )
    step, n_components, n_entries = integers[:3]
    entries = np.array(" ".join(lines[row : row + n_entries]).split())
    if entries.size != n_entries * (1 + n_components):
        raise ValueError(
            f"gmsh element data {name!r}: expected {n_entries} lines of an "
            f"element tag and {n_components} values"
        )
    entries = entries.reshape(n_entries, 1 + n_components)
    return name, step, entries[:, 0].astype(np.int64), entries[:, 1:].astype(float)


def _read_gmsh_element_data(content: bytes) -> tuple[_GmshElementData | None, bytes]:
    """The element data of a gmsh file and the file without its $ElementData sections (for
    meshio); (None, content) if it has none. ValueError for a binary file with element data."""
    sections = _gmsh_sections(content)
    if not any(name == "ElementData" for name, *_ in sections):
        return None, content
    where = {name: (body, end) for name, _, body, end in sections}
    if "MeshFormat" not in where:
        raise ValueError("gmsh file without a $MeshFormat section")
    header = (
        content[slice(*where["MeshFormat"])].decode(errors="replace").splitlines() + ["", ""]
    )[1].split()
    if len(header) < 2 or header[1] != "0":  # file-type 0 ASCII, 1 binary
        raise ValueError(
            "gmsh element data ($ElementData) is read from ASCII .msh files "
            "only: save the mesh as ASCII (gmsh option Mesh.Binary = 0)"
        )
    if "Elements" not in where:
        raise ValueError("gmsh file without an $Elements section")
    tags, types, nodes = _gmsh_surface_elements(
        _section_lines(content, *where["Elements"]), header[0]
    )
    fields: dict[str, tuple[int, list[np.ndarray], list[np.ndarray]]] = {}
    kept, position = [], 0
    for index, (name, start, body, end) in enumerate(sections):
        if name != "ElementData":
            continue
        kept.append(content[position:start])
        position = end
        lines = _section_lines(content, body, end)
        field, step, field_tags, values = _gmsh_element_data(lines, index)
        if field in fields and fields[field][0] == step:  # one section per partition
            fields[field][1].append(field_tags)
            fields[field][2].append(values)
        else:  # of several time steps the last in the file is kept
            fields[field] = (step, [field_tags], [values])
    kept.append(content[position:])
    data = {name: (np.concatenate(t), np.concatenate(v)) for name, (_, t, v) in fields.items()}
    return _GmshElementData(tags, types, nodes, data), b"".join(kept)


def _gmsh_cell_data(
    gmsh: _GmshElementData, surface_blocks: list[tuple[str, np.ndarray]]
) -> dict[str, np.ndarray]:
    """The element data of ``gmsh`` per wrinkle element, (n_elements, c) ((n_elements,) for
    one component), a split quad giving both triangles its value. surface_blocks: meshio's
    triangle and quad blocks (cell type, (k, 3 or 4) point indices) in wrinkle's order.

    meshio keeps gmsh's element order (it drops the tags): the k-th surface cell of meshio is
    the k-th of the file. That is checked, so that a reader that reorders gives an error, not
    a wrong field: the cell types must agree and the node tags and meshio's point indices
    must correspond one to one."""
    types = np.concatenate(
        [np.full(len(cells), 2 if kind == "triangle" else 3) for kind, cells in surface_blocks]
    )
    points = np.full((types.size, 4), -1, dtype=np.int64)  # meshio's, padded as surface_nodes
    points[:, :3] = np.concatenate([np.asarray(cells)[:, :3] for _, cells in surface_blocks])
    points[types == 3, 3] = np.concatenate(
        [np.asarray(cells)[:, 3] for kind, cells in surface_blocks if kind == "quad"] + [[]]
    )
    if (
        types.shape != gmsh.surface_types.shape
        or np.any(types != gmsh.surface_types)
        or np.any((points < 0) != (gmsh.surface_nodes < 0))
    ):
        raise ValueError(_GMSH_MISMATCH)
    corner = points >= 0
    pairs = np.unique(np.column_stack([gmsh.surface_nodes[corner], points[corner]]), axis=0)
    if (
        np.unique(pairs[:, 0]).size != pairs.shape[0]
        or np.unique(pairs[:, 1]).size != pairs.shape[0]
    ):
        raise ValueError(_GMSH_MISMATCH)
    per_cell = np.where(types == 2, 1, 2)
    element_tags = np.repeat(gmsh.surface_tags, per_cell)
    cell_data = {}
    for name, (tags, values) in gmsh.fields.items():
        order = np.argsort(tags, kind="stable")
        sorted_tags = tags[order]
        repeated = np.flatnonzero(sorted_tags[1:] == sorted_tags[:-1])
        if repeated.size:
            raise ValueError(
                f"gmsh element data {name!r} gives element tag "
                f"{sorted_tags[repeated[0]]} more than one value"
            )
        position = np.searchsorted(sorted_tags, element_tags)
        found = position < tags.size
        found[found] = sorted_tags[position[found]] == element_tags[found]
        if not np.all(found):
            first = int(np.flatnonzero(~found)[0])
            kind = _GMSH_SURFACE_TYPES[int(np.repeat(types, per_cell)[first])]
            raise ValueError(
                f"gmsh element data {name!r} has no value for the {kind} with element tag "
                f"{element_tags[first]}: give every triangle of the mesh a value"
            )
        field_values = values[order[position]]
        cell_data[name] = field_values[:, 0] if field_values.shape[1] == 1 else field_values
    return cell_data


def require_meshio() -> ModuleType:
    """The meshio module (imported when first needed: it takes a tenth of a second), or
    ImportError saying how to install it."""
    try:
        import meshio
    except ImportError:
        raise ImportError(
            "wrinkle: meshio, which reads meshes and writes results, is missing: pip install meshio"
        ) from None
    return meshio


def read_mesh(path: str | Path) -> Mesh:
    """Read a triangle mesh from any file meshio reads (gmsh .msh, .vtu, .inp, ...).

    Surface cells become elements: "triangle"
    cells as they are, and every "quad" (nodes a, b, c, d) is split into the two triangles
    (a, b, c) and (a, c, d) along its diagonal a-c; quad k of a block becomes the two
    consecutive elements 2k, 2k + 1. Higher-order cells (triangle6, quad8, ...) and volume
    cells are refused: mesh with linear elements (in gmsh, element order 1). "line" and
    "vertex" cells only define named node groups. 2-D points get z = 0.

    Per-element data: meshio's cell data of the surface cells becomes ``Mesh.cell_data``
    (a split quad gives both triangles its value). gmsh ``$ElementData`` views (for example a
    fibre direction per triangle, written by ``gmsh.view.addModelData(..., "ElementData",
    ...)``) are read by wrinkle itself, by element tag, from ASCII .msh files (gmsh option
    ``Mesh.Binary = 0``): ``cell_data[view name]`` is (n_elements, n_components), or
    (n_elements,) for one component, in wrinkle's element order; every triangle and quad
    needs a value, values of other elements (lines, points) are ignored; of several time
    steps of a view the last in the file is kept.

    Named sets: a gmsh physical group (``field_data`` with ``cell_data["gmsh:physical"]``)
    becomes a node set holding all nodes of its cells (points, lines or surfaces) and, for a
    surface group, an element set; meshio ``cell_sets`` (e.g. Abaqus ELSET) likewise, and
    ``point_sets`` (Abaqus NSET) become node sets. Nodes that no element uses are dropped
    and the others renumbered in file order (a free node would make the stiffness singular);
    node sets keep only the nodes that remain.

    Raises ValueError naming the file: missing or unreadable file, no triangles,
    unsupported cell type, zero-area or duplicate element, bad node. Element numbers in
    messages are the indices of the (split) triangles in file order, node numbers are the
    file's points counted from 0, both before unused nodes are dropped.
    """
    require_meshio()  # before anything else: say what to install
    path = Path(path)
    if not path.exists():
        raise ValueError(f"mesh file {path}: no such file")
    if not path.is_file():
        raise ValueError(f"mesh file {path}: not a file")
    gmsh = None
    if path.suffix.lower() == ".msh":
        try:
            gmsh, content = _read_gmsh_element_data(path.read_bytes())
        except (ValueError, IndexError, UnicodeDecodeError) as error:
            detail = str(error) if isinstance(error, ValueError) else "bad $ElementData"
            raise ValueError(f"mesh file {path}: {detail}") from None
    if gmsh is None:
        data = meshio_read(path, f"mesh file {path}")
    else:  # the file without its $ElementData sections
        with tempfile.TemporaryDirectory() as folder:
            stripped = Path(folder) / path.name
            stripped.write_bytes(content)
            data = meshio_read(stripped, f"mesh file {path}", file_format="gmsh")
    try:
        return _mesh_from_meshio(data, gmsh)
    except ValueError as error:
        raise ValueError(f"mesh file {path}: {error}") from None


def write_mesh(mesh: Mesh, path: str | Path) -> Path:
    """Write ``mesh`` as an ASCII gmsh 2.2 file that ``read_mesh`` reads back to the same
    mesh: its nodes in order, its triangles in order as one block, each element set as a
    surface physical group (the triangles' physical tags; so the element sets must not
    overlap: ValueError otherwise), each other node set as a point physical group (vertex
    cells), and ``cell_data`` as $ElementData (gmsh views). Returns the path."""
    meshio = require_meshio()
    path = Path(path)
    n = mesh.n_elements
    physical = np.zeros(n, dtype=np.int64)
    field_data: dict[str, np.ndarray] = {}
    tag = 0
    for name, elements in mesh.element_sets.items():
        tag += 1
        if np.any(physical[elements]):
            raise ValueError(
                f"element set {name!r} overlaps another: a gmsh file gives each element one "
                "physical group"
            )
        physical[elements] = tag
        field_data[name] = np.array([tag, 2])
    vertex_nodes, vertex_tags = [], []
    for name, nodes in mesh.node_sets.items():
        if name in mesh.element_sets or nodes.size == 0:
            continue  # read back as the nodes of the surface group
        tag += 1
        vertex_nodes.append(nodes)
        vertex_tags.append(np.full(nodes.size, tag))
        field_data[name] = np.array([tag, 0])
    cells = [("triangle", mesh.triangles)]
    tags = [physical]
    if vertex_nodes:
        cells.append(("vertex", np.concatenate(vertex_nodes)[:, None]))
        tags.append(np.concatenate(vertex_tags))
    cell_data: dict[str, list[np.ndarray]] = {
        "gmsh:physical": tags,
        "gmsh:geometrical": [np.ones_like(t) for t in tags],
    }
    data = meshio.Mesh(mesh.nodes, cells, cell_data=cell_data, field_data=field_data)
    meshio.write(path, data, file_format="gmsh22", binary=False)
    # the views by hand: the triangles are elements 1 .. n of the file
    with path.open("a") as file:
        for name, values in mesh.cell_data.items():
            values = np.asarray(values, dtype=float).reshape(n, -1)
            header = f'$ElementData\n1\n"{name}"\n1\n0.0\n3\n0\n{values.shape[1]}\n{n}\n'
            file.write(header)
            rows = np.column_stack([np.arange(1, n + 1), values])
            np.savetxt(file, rows, fmt=["%d"] + ["%.17g"] * values.shape[1])
            file.write("$EndElementData\n")
    return path


def meshio_read(path: Path, label: str, file_format: str | None = None):
    """``meshio.read(path)`` without its prints: ValueError "<label>: cannot read it
    (<reason>)" for a file it cannot read (meshio prints its readers' errors and, when every
    reader fails, calls sys.exit(1))."""
    meshio = require_meshio()
    printed = io.StringIO()
    try:
        with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(printed):
            return meshio.read(path, file_format=file_format)
    except (Exception, SystemExit) as error:  # noqa: BLE001 -- readers raise many types
        if isinstance(error, Exception):
            lines = str(error).strip().splitlines()
            reason = lines[0] if lines else type(error).__name__
        else:  # the readers' messages come before meshio's (line-wrapped) "Error: ..."
            lines = printed.getvalue().split("Error:")[0].splitlines()
            formats = meshio.extension_to_filetypes.get(Path(path).suffix.lower(), ["meshio"])
            reason = "; ".join(
                [f"not a valid {' or '.join(formats)} file"]
                + [line.strip() for line in lines if line.strip()]
            )
        raise ValueError(f"{label}: cannot read it ({reason})") from None


def _mesh_from_meshio(data, gmsh: _GmshElementData | None = None) -> Mesh:
    """The wrinkle Mesh of a meshio.Mesh (see ``read_mesh``), with the element data of a gmsh
    file read by ``_read_gmsh_element_data``; ValueError without file name."""
    points = np.asarray(data.points, dtype=float)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise ValueError(f"points must have 2 or 3 coordinates, got shape {points.shape}")
    n_points = points.shape[0]
    blocks = [(block.type, np.asarray(block.data)) for block in data.cells]

    # element numbers of each surface cell block: first element, triangles per cell
    triangle_parts, first_element, n_elements = [], {}, 0
    for b, (cell_type, cells) in enumerate(blocks):
        if cell_type in _SURFACE_CELLS:
            per_cell = _SURFACE_CELLS[cell_type]
            triangles = cells if per_cell == 1 else cells[:, [0, 1, 2, 0, 2, 3]].reshape(-1, 3)
            triangle_parts.append(triangles)
            first_element[b] = n_elements
            n_elements += triangles.shape[0]
        elif cell_type not in _NODE_GROUP_CELLS:
            higher_order = cell_type.rstrip("0123456789") in ("triangle", "quad", "line")
            raise ValueError(
                f"cell type {cell_type!r} is not supported"
                + ("; mesh with linear elements (element order 1)" if higher_order else "")
                + " (wrinkle reads triangle and quad cells, and line and vertex cells"
                " for node groups)"
            )
        if cells.size and (cells.min() < 0 or cells.max() >= n_points):
            raise ValueError(f"a {cell_type} cell refers to a point outside 0..{n_points - 1}")
    if n_elements == 0:
        found = sorted({cell_type for cell_type, _ in blocks})
        raise ValueError(
            "no triangles in the mesh (cell types: " + (", ".join(found) if found else "none") + ")"
        )
    triangles = np.concatenate(triangle_parts).astype(np.int64)

    def elements_of(b: int, cells: np.ndarray) -> np.ndarray:
        """Element indices of cells (indices into block b); empty for line/vertex blocks."""
        if b not in first_element:
            return np.zeros(0, dtype=np.int64)
        per_cell = _SURFACE_CELLS[blocks[b][0]]
        return (first_element[b] + per_cell * cells[:, None] + np.arange(per_cell)).ravel()

    node_parts: dict[str, list[np.ndarray]] = {}
    element_parts: dict[str, list[np.ndarray]] = {}

    def add(name: str, b: int, cells: np.ndarray) -> None:
        cells = np.asarray(cells, dtype=np.int64).ravel()
        if cells.size and (cells.min() < 0 or cells.max() >= blocks[b][1].shape[0]):
            raise ValueError(f"cell set {name!r} refers to a cell that does not exist")
        node_parts.setdefault(name, []).append(blocks[b][1][cells].ravel())
        if b in first_element and cells.size:
            element_parts.setdefault(name, []).append(elements_of(b, cells))

    physical = data.cell_data.get("gmsh:physical")
    if physical is not None and len(physical) == len(blocks):
        for name, value in data.field_data.items():
            tag_dimension = np.asarray(value).ravel()
            if tag_dimension.size != 2:
                continue
            tag, dimension = int(tag_dimension[0]), int(tag_dimension[1])
            node_parts.setdefault(name, [])
            for b, (cell_type, _) in enumerate(blocks):
                if _CELL_DIMENSION.get(cell_type) == dimension:
                    add(name, b, np.flatnonzero(np.asarray(physical[b]) == tag))
    for name, per_block in data.cell_sets.items():
        if name.startswith("gmsh:"):
            continue
        if len(per_block) != len(blocks):
            raise ValueError(
                f"cell set {name!r} has {len(per_block)} parts for {len(blocks)} cell blocks"
            )
        node_parts.setdefault(name, [])
        for b, cells in enumerate(per_block):
            if cells is not None:
                add(name, b, cells)
    for name, points_in_set in data.point_sets.items():
        points_in_set = np.asarray(points_in_set, dtype=np.int64).ravel()
        if points_in_set.size and (points_in_set.min() < 0 or points_in_set.max() >= n_points):
            raise ValueError(f"point set {name!r} refers to a point outside 0..{n_points - 1}")
        node_parts.setdefault(name, []).append(points_in_set)

    # per-element data of the surface blocks (a split quad gives both triangles its value)
    cell_data = {}
    for name, per_block in data.cell_data.items():
        if name.startswith("gmsh:") or len(per_block) != len(blocks):
            continue
        parts = []
        for b in sorted(first_element):
            values = np.asarray(per_block[b], dtype=float)
            parts.append(np.repeat(values, _SURFACE_CELLS[blocks[b][0]], axis=0))
        if parts and all(p.shape[1:] == parts[0].shape[1:] for p in parts):
            cell_data[name] = np.concatenate(parts)
    if gmsh is not None:
        cell_data.update(_gmsh_cell_data(gmsh, [blocks[b] for b in sorted(first_element)]))

    # checks in the file's numbering, so that the messages point into the file
    checked = Mesh(points, triangles)
    bad = _zero_area_element(checked.nodes, triangles)
    if bad is not None:
        raise ValueError(f"element {bad} (nodes {triangles[bad].tolist()}) has zero area")

    used = np.zeros(n_points, dtype=bool)
    used[triangles.ravel()] = True
    used = np.flatnonzero(used)
    new_number = np.full(n_points, -1, dtype=np.int64)
    new_number[used] = np.arange(used.size)

    def renumbered(parts: list[np.ndarray]) -> np.ndarray:
        nodes = new_number[np.concatenate(parts)] if parts else np.zeros(0, dtype=np.int64)
        return _sorted_unique(nodes[nodes >= 0])

    node_sets = {name: renumbered(parts) for name, parts in node_parts.items()}
    element_sets = {
        name: _sorted_unique(np.concatenate(parts)) for name, parts in element_parts.items()
    }
    return Mesh(checked.nodes[used], new_number[triangles], node_sets, element_sets, cell_data)
