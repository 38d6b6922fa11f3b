"""Nodal fields between two meshes of one surface (wrinkle.transfer): the closest point on a
triangle against a dense sampling of it, the search against every triangle, linear fields
exact between non-nested flat meshes, O(h²) on a sphere and a cylinder against the closed
form, rows that sum to 1, the uniform refinement's own interpolation reproduced, and meshes
of different surfaces refused."""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import Delaunay

from wrinkle import rectangle
from wrinkle.mesh import Mesh, cylinder, read_mesh, sphere
from wrinkle.refinement import refine
from wrinkle.transfer import PointTransfer, closest_on_triangles, closest_points

ROOT = Path(__file__).resolve().parents[1]


def delaunay_square(n: int, seed: int, side: float = 1.0) -> Mesh:
    """An unstructured mesh of the square [0, side]²: n equally spaced nodes per side and
    about n² random ones inside, Delaunay triangles, counter-clockwise."""
    rng = np.random.default_rng(seed)
    s = np.linspace(0.0, side, n + 1)[:-1]
    boundary = np.concatenate(
        [
            np.column_stack([s, 0 * s]),
            np.column_stack([side + 0 * s, s]),
            np.column_stack([side - s, side + 0 * s]),
            np.column_stack([0 * s, side - s]),
        ]
    )
    inside = side * (0.02 + 0.96 * rng.random((n * n, 2)))
    points = np.vstack([boundary, inside])
    triangles = Delaunay(points).simplices
    a, b, c = (points[triangles[:, k]] for k in range(3))
    turn = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]
    triangles[turn < 0] = triangles[turn < 0][:, [0, 2, 1]]
    keep = np.abs(turn) > 1e-12 * side**2
    return Mesh(points, triangles[keep])


def jittered(mesh: Mesh, amount: float, seed: int) -> Mesh:
    """The mesh with its interior nodes moved at random by up to ``amount`` in x and y."""
    from wrinkle.mesh import boundary_nodes

    nodes = mesh.nodes.copy()
    inner = ~boundary_nodes(mesh)
    rng = np.random.default_rng(seed)
    nodes[inner, :2] += amount * rng.uniform(-1.0, 1.0, (int(inner.sum()), 2))
    return Mesh(nodes, mesh.triangles, mesh.node_sets, mesh.element_sets)


def test_closest_point_on_a_triangle_against_a_dense_sampling():
    """Random points and triangles in 3-D (points in every Voronoi region): the distance to
    the point found is the least over 20,000 sample points of the triangle (its face and its
    edges), to the sampling's resolution, and never above it."""
    rng = np.random.default_rng(3)
    n = 300
    points = 2.0 * rng.normal(size=(n, 3))
    corners = rng.normal(size=(n, 3, 3))
    bary = closest_on_triangles(points, corners)
    assert np.all(bary >= 0.0) and np.allclose(bary.sum(axis=1), 1.0, atol=1e-14)
    found = np.linalg.norm(points - np.einsum("ij,ijk->ik", bary, corners), axis=1)
    t = np.linspace(0.0, 1.0, 2001)
    zero = 0.0 * t
    samples = np.vstack(
        [
            rng.dirichlet([1.0, 1.0, 1.0], size=14_000),
            np.column_stack([1 - t, t, zero]),
            np.column_stack([zero, 1 - t, t]),
            np.column_stack([t, zero, 1 - t]),
        ]
    )
    sampled = np.array(
        [np.linalg.norm(samples @ corners[i] - points[i], axis=1).min() for i in range(n)]
    )
    assert np.all(found <= sampled + 1e-12)
    assert np.all(found >= sampled - 0.05 * np.linalg.norm(corners, axis=2).max(axis=1))
    assert np.max(sampled - found) > 1e-6  # some points lie off a corner and an edge's ends


@pytest.mark.parametrize("which", ["graded", "sphere", "cylinder"])
def test_the_search_finds_the_closest_of_all_triangles(which):
    """The candidates' answer is that of every triangle tried for every point, on a mesh
    whose element sizes differ 30-fold (the proof's bound R is the largest element's, so
    the search widens), on a curved octant and on a closed tube (two walls near each point),
    for points on, near and off the surface."""
    rng = np.random.default_rng(11)
    if which == "graded":
        base = rectangle(1.0, 1.0, 24, 24)
        nodes = base.nodes.copy()
        nodes[:, :2] = nodes[:, :2] ** 3  # elements near the origin 30 times smaller
        mesh = Mesh(nodes, base.triangles)
    elif which == "sphere":
        mesh = sphere(1.0, 12)
    else:
        mesh = cylinder(0.3, 2.0, 12, 8, 3)
    lo, hi = mesh.nodes.min(axis=0), mesh.nodes.max(axis=0)
    points = lo - 0.1 + (hi - lo + 0.2) * rng.random((400, 3))
    triangle, bary, distance = closest_points(mesh, points)
    corners = mesh.nodes[mesh.triangles]
    every = np.repeat(points, mesh.n_elements, axis=0)
    all_corners = np.tile(corners, (points.shape[0], 1, 1))
    weights = closest_on_triangles(every, all_corners)
    gaps = np.linalg.norm(every - np.einsum("ij,ijk->ik", weights, all_corners), axis=1)
    least = gaps.reshape(points.shape[0], mesh.n_elements).min(axis=1)
    np.testing.assert_allclose(distance, least, rtol=0, atol=1e-13)
    at = np.einsum("ij,ijk->ik", bary, corners[triangle])
    np.testing.assert_allclose(np.linalg.norm(points - at, axis=1), distance, atol=1e-13)


@pytest.mark.parametrize(
    "coarse, fine",
    [
        (lambda: rectangle(1.0, 1.0, 5, 5), lambda: rectangle(1.0, 1.0, 7, 7, diagonal="left")),
        (lambda: delaunay_square(6, 1), lambda: delaunay_square(15, 2)),
        (lambda: jittered(rectangle(1.0, 1.0, 9, 9), 0.03, 4), lambda: delaunay_square(20, 5)),
    ],
    ids=["structured", "delaunay", "jittered onto delaunay"],
)
def test_linear_fields_are_exact_between_non_nested_flat_meshes(coarse, fine):
    """Two meshes of the unit square that share no node but the corners: a field linear in
    x and y (three components) is reproduced at every fine node to round-off, and every row
    of the interpolation matrix holds at most three weights in [0, 1] summing to 1."""
    coarse, fine = coarse(), fine()
    transfer = PointTransfer(coarse, fine)

    def field(x):
        return np.column_stack(
            [1.0 + 2.0 * x[:, 0] - x[:, 1], 0.5 * x[:, 1], -3.0 * x[:, 0] + 0.25]
        )

    np.testing.assert_allclose(
        transfer.prolong(field(coarse.nodes)), field(fine.nodes), rtol=0, atol=1e-13
    )
    matrix = transfer.matrix
    assert matrix.shape == (fine.n_nodes, coarse.n_nodes)
    np.testing.assert_allclose(matrix.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    assert matrix.data.min() >= 0.0 and matrix.data.max() <= 1.0
    assert np.diff(matrix.indptr).max() <= 3
    assert transfer.distance.max() < 1e-14


def test_two_gmsh_meshes_of_the_airbag_square(tmp_path):
    """Two Frontal-Delaunay meshes of the quarter airbag (benchmarks/gmsh_airbag.py): a
    linear field passes exactly, scalar and vector fields alike."""
    pytest.importorskip("gmsh")
    import sys

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from gmsh_airbag import write_airbag_mesh

    write_airbag_mesh(300, tmp_path / "coarse.msh")
    write_airbag_mesh(2000, tmp_path / "fine.msh")
    coarse, fine = read_mesh(tmp_path / "coarse.msh"), read_mesh(tmp_path / "fine.msh")
    transfer = PointTransfer(coarse, fine)
    scalar = transfer.prolong(coarse.nodes @ [2.0, -1.0, 0.0] + 0.5)
    np.testing.assert_allclose(scalar, fine.nodes @ [2.0, -1.0, 0.0] + 0.5, atol=1e-13)
    np.testing.assert_allclose(transfer.prolong(coarse.nodes), fine.nodes, atol=1e-13)


def sphere_errors(counts, fine_count=96):
    """The largest error of the field cos(x) e^y z interpolated from octants of n² triangles
    onto the nodes of a finer one (on the sphere), for each n of counts."""

    def field(x):
        return np.cos(x[:, 0]) * np.exp(x[:, 1]) * x[:, 2]

    fine = sphere(1.0, fine_count)
    return [
        np.abs(
            PointTransfer(sphere(1.0, n), fine).prolong(field(sphere(1.0, n).nodes))
            - field(fine.nodes)
        ).max()
        for n in counts
    ]


def test_second_order_on_a_sphere():
    """On the unit sphere's octant the nodes of a finer mesh lie off the coarse facets by
    O(h²) and a smooth field interpolated there errs by O(h²): the error falls by 4 (3.5 to
    4.5) each time the coarse mesh's n doubles."""
    errors = sphere_errors([6, 12, 24])
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 3.5) & (ratios < 4.5)), (errors, ratios)


def test_second_order_on_a_cylinder():
    """A closed tube onto a finer tube (walls and flat caps): the field sin(2 theta) (1 + x)
    of the wall's angle theta errs by O(h²) against its closed form at the fine nodes."""

    def field(x):
        theta = np.arctan2(x[:, 2], x[:, 1])
        return np.sin(2.0 * theta) * (1.0 + x[:, 0]) * np.hypot(x[:, 1], x[:, 2])

    fine = cylinder(1.0, 2.0, 192, 96, 24)
    errors = []
    for n in (12, 24, 48):
        coarse = cylinder(1.0, 2.0, n, n // 2, max(1, n // 8))
        errors.append(
            np.abs(
                PointTransfer(coarse, fine).prolong(field(coarse.nodes)) - field(fine.nodes)
            ).max()
        )
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 3.0) & (ratios < 5.0)), (errors, ratios)


def test_a_refined_mesh_gets_the_refinements_interpolation():
    """Onto the mesh refined once, the point location gives Refinement.prolong's values (the
    mean of the edge's ends at each midpoint), for any field, on a curved mesh too."""
    rng = np.random.default_rng(2)
    for mesh in (delaunay_square(5, 3), sphere(2.0, 5)):
        refinement = refine(mesh)
        values = rng.normal(size=(mesh.n_nodes, 3))
        np.testing.assert_allclose(
            PointTransfer(mesh, refinement.mesh).prolong(values),
            refinement.prolong(values),
            atol=1e-12,
        )


@pytest.mark.parametrize(
    "coarse, fine, node",
    [
        (lambda: rectangle(1.0, 1.0, 4, 4), lambda: rectangle(1.5, 1.0, 6, 4), "node 6 of"),
        (lambda: sphere(1.0, 8), lambda: sphere(1.3, 12), "node"),
        (lambda: sphere(1.0, 1), lambda: sphere(1.0, 8), "node"),
    ],
    ids=["wider sheet", "larger sphere", "one facet for an octant"],
)
def test_meshes_of_different_surfaces_are_refused(coarse, fine, node):
    """A fine mesh sticking out of the coarse sheet, a sphere of another radius, and an
    octant whose one coarse facet misses the sphere by 0.42 of its radius (0.3 of its edge):
    ValueError naming the node, its distance and the element size."""
    with pytest.raises(ValueError, match=rf"do not cover the same surface: {node}") as error:
        PointTransfer(coarse(), fine(), names=("level 0", "level 1"))
    message = str(error.value)
    assert "of level 1 is" in message and "from level 0's surface" in message
    assert "\n" not in message


def test_the_gap_tolerance_is_relative_to_the_element_size():
    """Fine nodes 0.2 of the coarse element off the coarse sheet pass, 0.3 do not; the same
    holds at any length scale."""
    for scale in (1e-3, 1.0, 1e4):
        coarse = rectangle(scale, scale, 4, 4)  # longest edge: the diagonal, 0.354 scale
        size = np.hypot(0.25, 0.25) * scale
        for lift, ok in ((0.2, True), (0.3, False)):
            fine = rectangle(scale, scale, 6, 6)
            fine.nodes[:, 2] = lift * size
            if ok:
                PointTransfer(coarse, fine)
            else:
                with pytest.raises(ValueError, match="do not cover the same surface"):
                    PointTransfer(coarse, fine)
