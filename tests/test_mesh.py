"""Mesh generator and mesh validation."""

from __future__ import annotations

import numpy as np
import pytest

from wrinkle.mesh import Mesh, rectangle


def signed_areas(mesh: Mesh) -> np.ndarray:
    """z component of (x2 - x1) x (x3 - x1) / 2: positive for counter-clockwise triangles."""
    X = mesh.nodes[mesh.triangles]
    return 0.5 * np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])[:, 2]


@pytest.mark.parametrize("diagonal", ["right", "left"])
@pytest.mark.parametrize("nx, ny", [(1, 1), (3, 2), (5, 7)])
def test_rectangle(nx, ny, diagonal):
    width, height = 2.5, 1.3
    mesh = rectangle(width, height, nx, ny, diagonal=diagonal)
    assert mesh.n_nodes == (nx + 1) * (ny + 1)
    assert mesh.n_elements == 2 * nx * ny
    assert mesh.nodes.shape == (mesh.n_nodes, 3)
    assert mesh.triangles.shape == (mesh.n_elements, 3)
    assert np.all(mesh.nodes[:, 2] == 0.0)
    area = signed_areas(mesh)
    assert np.all(area > 0.0)  # counter-clockwise seen from +z
    assert np.allclose(area, width * height / (2 * nx * ny))
    assert area.sum() == pytest.approx(width * height, rel=1e-14)
    # every node is used, every node numbered j (nx + 1) + i sits at (i dx, j dy)
    assert np.array_equal(np.unique(mesh.triangles), np.arange(mesh.n_nodes))
    j, i = np.divmod(np.arange(mesh.n_nodes), nx + 1)
    assert np.allclose(mesh.nodes[:, 0], i * width / nx)
    assert np.allclose(mesh.nodes[:, 1], j * height / ny)
    # node sets: the nodes on each edge, corners included, in increasing order
    x, y = mesh.nodes[:, 0], mesh.nodes[:, 1]
    expected = {
        "left": np.flatnonzero(np.isclose(x, 0.0)),
        "right": np.flatnonzero(np.isclose(x, width)),
        "bottom": np.flatnonzero(np.isclose(y, 0.0)),
        "top": np.flatnonzero(np.isclose(y, height)),
    }
    assert set(mesh.node_sets) == set(expected)
    for name, nodes in expected.items():
        assert np.array_equal(np.sort(mesh.node_sets[name]), nodes), name


def test_rectangle_diagonals():
    """Square 0-1-3-2 (2x2 nodes): 'right' splits along 0-3, 'left' along 1-2."""

    def edges(mesh):
        return {
            tuple(sorted((int(t[a]), int(t[b]))))
            for t in mesh.triangles
            for a, b in ((0, 1), (1, 2), (2, 0))
        }

    assert (0, 3) in edges(rectangle(1.0, 1.0, 1, 1, "right"))
    assert (1, 2) in edges(rectangle(1.0, 1.0, 1, 1, "left"))


@pytest.mark.parametrize(
    "args, message",
    [
        ((0.0, 1.0, 2, 2), "width and height"),
        ((1.0, -1.0, 2, 2), "width and height"),
        ((1.0, 1.0, 0, 2), "nx and ny"),
        ((1.0, 1.0, 2, 0), "nx and ny"),
    ],
)
def test_rectangle_rejects_bad_arguments(args, message):
    with pytest.raises(ValueError, match=message):
        rectangle(*args)


def test_rectangle_rejects_unknown_diagonal():
    with pytest.raises(ValueError, match="diagonal must be 'right' or 'left'"):
        rectangle(1.0, 1.0, 2, 2, diagonal="both")


NODES = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])


def test_valid_mesh_and_planar_nodes():
    mesh = Mesh(NODES[:, :2], [[0, 1, 2], [0, 2, 3]], {"corner": [0]})
    assert mesh.nodes.shape == (4, 3)
    assert np.all(mesh.nodes[:, 2] == 0.0)
    assert mesh.triangles.dtype == np.int64
    assert mesh.node_sets["corner"].dtype == np.int64
    assert (mesh.n_nodes, mesh.n_elements) == (4, 2)


@pytest.mark.parametrize(
    "nodes, triangles, message",
    [
        (NODES, [[0, 1, 2], [0, 2, 4]], r"element 1 refers to node\(s\) \[0, 2, 4\] outside 0..3"),
        (NODES, [[0, 1, 2], [-1, 2, 3]], r"element 1 refers to node\(s\) \[-1, 2, 3\]"),
        (NODES, [[0, 1, 2], [0, 2, 3], [3, 3, 1]], r"element 2 repeats a node"),
        (NODES, [[0, 1, 2], [0, 2, 3], [2, 0, 1]], r"elements \[0, 2\] are duplicates"),
        (NODES, [[0, 1, 2, 3]], r"\(n, 3\)"),
        (NODES, [0, 1, 2], r"\(n, 3\)"),
        (NODES, [[0.0, 1.0, 2.0]], "integer"),
        (NODES[:, :1], [[0, 1, 2]], r"\(n, 2\) or \(n, 3\)"),
        (np.ones((4, 3, 1)), [[0, 1, 2]], r"\(n, 2\) or \(n, 3\)"),
        (
            np.where(np.arange(12).reshape(4, 3) == 7, np.nan, NODES),
            [[0, 1, 2]],
            r"node 2 has a non-finite coordinate",
        ),
        (
            np.where(np.arange(12).reshape(4, 3) == 9, np.inf, NODES),
            [[0, 1, 2]],
            r"node 3 has a non-finite coordinate",
        ),
    ],
    ids=[
        "node_out_of_range",
        "negative_node",
        "repeated_node",
        "duplicate_element",
        "four_nodes_per_element",
        "flat_triangles",
        "float_indices",
        "one_coordinate",
        "nodes_3d_array",
        "nan_coordinate",
        "inf_coordinate",
    ],
)
def test_mesh_validation_names_the_culprit(nodes, triangles, message):
    with pytest.raises(ValueError, match=message):
        Mesh(nodes, np.asarray(triangles))
