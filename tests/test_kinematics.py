"""Batched triangle kinematics against exact homogeneous deformations and vector algebra.

A homogeneous deformation x = R (Fh X) + c of 3-D space maps every material vector V of a
triangle's plane to R Fh V, so the in-plane deformation gradient of the element must send the
material axes A1, A2 exactly there, whatever the triangle.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from wrinkle.kinematics import (
    current_normal,
    deformation_gradient,
    element_coordinates,
    material_frame,
    reference_geometry,
    right_cauchy_green,
)

N_TRIANGLES = 50


def rotation(vector) -> np.ndarray:
    """Rotation matrix about ``vector`` by |vector| radians."""
    return Rotation.from_rotvec(vector).as_matrix()


def random_triangles(n: int = N_TRIANGLES, seed: int = 0):
    """n separate random triangles in 3-D with corner angles not too small: (3n, 3), (n, 3)."""
    rng = np.random.default_rng(seed)
    corners = []
    while len(corners) < n:
        X = rng.uniform(-2.0, 2.0, (3, 3))
        a, b, c = X
        area2 = np.linalg.norm(np.cross(a - c, b - c))
        longest = max(np.linalg.norm(a - b), np.linalg.norm(b - c), np.linalg.norm(c - a))
        if area2 > 0.2 * longest**2:
            corners.append(X)
    nodes = np.concatenate(corners)
    return nodes, np.arange(3 * n).reshape(n, 3)


def random_deformation(seed: int = 1):
    """R (a rotation), Fh (3x3, det > 0: a stretch/shear with chosen in-plane part) and c."""
    rng = np.random.default_rng(seed)
    Fh = np.eye(3) + 0.3 * rng.uniform(-1.0, 1.0, (3, 3))
    assert np.linalg.det(Fh) > 0.0
    return rotation(rng.normal(size=3)), Fh, rng.normal(size=3)


@pytest.fixture(scope="module")
def triangles():
    return random_triangles()


def test_deformation_gradient_is_exact_for_homogeneous_deformations(triangles):
    nodes, tri = triangles
    R, Fh, c = random_deformation()
    geometry = reference_geometry(nodes, tri, fibre_direction=(0.2, 1.0, -0.4))
    x = nodes @ (R @ Fh).T + c
    F = deformation_gradient(element_coordinates(x, tri), geometry.shape_gradient)
    assert F.shape == (N_TRIANGLES, 3, 2)
    expected = np.einsum("ij,naj->nia", R @ Fh, geometry.frame)  # column a = R Fh A_a
    assert np.allclose(F, expected, rtol=0.0, atol=1e-13)
    C = right_cauchy_green(F)
    assert C.shape == (N_TRIANGLES, 2, 2)
    expected_C = np.einsum("nia,nib->nab", expected, expected)
    assert np.allclose(C, expected_C, rtol=0.0, atol=1e-13)
    # C is also A_a . (Fh^T Fh) A_b: the rotation drops out
    metric = np.einsum("nai,ij,nbj->nab", geometry.frame, Fh.T @ Fh, geometry.frame)
    assert np.allclose(C, metric, rtol=0.0, atol=1e-13)


def test_identity_gives_unit_metric(triangles):
    nodes, tri = triangles
    geometry = reference_geometry(nodes, tri)
    F = deformation_gradient(element_coordinates(nodes, tri), geometry.shape_gradient)
    assert np.allclose(right_cauchy_green(F), np.eye(2), rtol=0.0, atol=1e-13)


def test_areas_and_normals(triangles):
    nodes, tri = triangles
    geometry = reference_geometry(nodes, tri)
    X = nodes[tri]
    G1xG2 = np.cross(X[:, 0] - X[:, 2], X[:, 1] - X[:, 2])
    assert geometry.n_elements == N_TRIANGLES
    assert np.allclose(geometry.area, 0.5 * np.linalg.norm(G1xG2, axis=1), rtol=1e-14)
    assert np.allclose(
        geometry.normal, G1xG2 / np.linalg.norm(G1xG2, axis=1)[:, None], rtol=0.0, atol=1e-15
    )
    # counter-clockwise in the xy plane: normal +z, clockwise: -z, area unchanged
    flat = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]])
    g = reference_geometry(flat, np.array([[0, 1, 2], [0, 2, 1]]))
    assert np.allclose(g.normal, [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    assert np.allclose(g.area, [3.0, 3.0])


def test_shape_gradients_partition_unity_and_reproduce_linear_fields(triangles):
    nodes, tri = triangles
    geometry = reference_geometry(nodes, tri, fibre_direction=(1.0, -0.3, 0.5))
    grad = geometry.shape_gradient
    assert grad.shape == (N_TRIANGLES, 3, 2)
    assert np.allclose(grad.sum(axis=1), 0.0, atol=1e-13)
    # phi(X) = a . X + d has in-plane gradient (a . A1, a . A2)
    rng = np.random.default_rng(2)
    a, d = rng.normal(size=3), rng.normal()
    phi = nodes[tri] @ a + d  # (n, 3)
    assert np.allclose(np.einsum("nk,nka->na", phi, grad), geometry.frame @ a, rtol=0.0, atol=1e-13)
    # and the 3-D gradient of psi_k, sum_a grad_ka A_a, gives Kronecker deltas at the nodes
    grad3 = np.einsum("nka,nai->nki", grad, geometry.frame)
    X = nodes[tri]
    for k in range(3):
        for l in range(3):
            for m in range(3):
                expected = float(k == l) - float(k == m)
                assert np.allclose(np.sum(grad3[:, k] * (X[:, l] - X[:, m]), axis=1), expected)


def test_frames_are_orthonormal_along_projected_fibre(triangles):
    nodes, tri = triangles
    fibre = np.array([0.3, 0.8, -0.5])
    geometry = reference_geometry(nodes, tri, fibre_direction=fibre)
    A1, A2, N = geometry.frame[:, 0], geometry.frame[:, 1], geometry.normal
    assert geometry.frame.shape == (N_TRIANGLES, 2, 3)
    gram = np.einsum("nai,nbi->nab", geometry.frame, geometry.frame)
    assert np.allclose(gram, np.eye(2), rtol=0.0, atol=1e-14)
    assert np.allclose(np.sum(A1 * N, axis=1), 0.0, atol=1e-14)
    assert np.allclose(np.cross(A1, A2), N, rtol=0.0, atol=1e-14)
    projected = fibre - (N @ fibre)[:, None] * N
    assert np.allclose(A1, projected / np.linalg.norm(projected, axis=1)[:, None], atol=1e-14)


def test_fibre_angle_rotates_the_frame(triangles):
    nodes, tri = triangles
    fibre = np.array([1.0, 0.2, 0.1])
    angles = np.linspace(-3.0, 3.0, N_TRIANGLES)
    base = reference_geometry(nodes, tri, fibre_direction=fibre)
    turned = reference_geometry(nodes, tri, fibre_direction=fibre, fibre_angle=angles)
    A1, A2 = base.frame[:, 0], base.frame[:, 1]
    cos, sin = np.cos(angles)[:, None], np.sin(angles)[:, None]
    assert np.allclose(turned.frame[:, 0], cos * A1 + sin * A2, atol=1e-14)
    assert np.allclose(turned.frame[:, 1], -sin * A1 + cos * A2, atol=1e-14)
    assert np.allclose(np.cross(turned.frame[:, 0], turned.frame[:, 1]), base.normal, atol=1e-14)
    # the frame change leaves the invariants of C alone
    x = nodes @ np.diag([1.2, 0.9, 1.1]).T
    invariants = []
    for g in (base, turned):
        C = right_cauchy_green(deformation_gradient(element_coordinates(x, tri), g.shape_gradient))
        invariants.append([np.trace(C, axis1=1, axis2=2), np.linalg.det(C)])
    assert np.allclose(invariants[0], invariants[1], rtol=1e-13)
    scalar = reference_geometry(nodes, tri, fibre_direction=fibre, fibre_angle=0.5)
    assert np.allclose(scalar.frame[:, 0], np.cos(0.5) * A1 + np.sin(0.5) * A2, atol=1e-14)


def test_per_element_fibre_directions():
    normal = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    directions = np.array([[1.0, 0.0, 5.0], [0.0, 2.0, 0.0], [0.0, 0.0, 1.0]])
    frame = material_frame(normal, directions)
    assert np.allclose(frame[:, 0], [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    assert np.allclose(frame[:, 1], [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def test_current_normal(triangles):
    nodes, tri = triangles
    R, Fh, c = random_deformation(seed=4)
    geometry = reference_geometry(nodes, tri, fibre_direction=(0.2, 0.3, 1.0))
    x = nodes @ (R @ Fh).T + c
    F = deformation_gradient(element_coordinates(x, tri), geometry.shape_gradient)
    xe = x[tri]
    n = np.cross(xe[:, 0] - xe[:, 2], xe[:, 1] - xe[:, 2])
    n /= np.linalg.norm(n, axis=1)[:, None]
    assert np.allclose(current_normal(F), n, rtol=0.0, atol=1e-13)
    # Nanson: n is parallel to cof(R Fh) N
    cofactor = np.linalg.det(R @ Fh) * np.linalg.inv(R @ Fh).T
    nanson = geometry.normal @ cofactor.T
    nanson /= np.linalg.norm(nanson, axis=1)[:, None]
    assert np.allclose(current_normal(F), nanson, rtol=0.0, atol=1e-13)


@pytest.mark.parametrize(
    "bad_corners",
    [
        [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]],  # collinear
        [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0], [0.0, 1.0, 0.0]],  # two nodes coincide
    ],
    ids=["collinear", "coincident"],
)
def test_zero_area_element_is_named(bad_corners):
    nodes, tri = random_triangles(n=4, seed=3)
    nodes[6:9] = bad_corners
    with pytest.raises(ValueError, match=r"element 2 \(nodes \[6, 7, 8\]\) has zero area"):
        reference_geometry(nodes, tri)


def test_fibre_perpendicular_to_element_is_named():
    nodes = np.array(
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],  # element 0: xy plane
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],  # element 1: yz plane
        ]
    )
    tri = np.array([[0, 1, 2], [3, 4, 5]])
    with pytest.raises(ValueError, match="perpendicular to element 1"):
        reference_geometry(nodes, tri, fibre_direction=(1.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="perpendicular to element 0"):
        reference_geometry(nodes, tri, fibre_direction=(0.0, 0.0, 2.0))
    with pytest.raises(ValueError, match="element 0"):
        reference_geometry(nodes, tri, fibre_direction=(0.0, 0.0, 0.0))
    # any direction with an in-plane component works
    reference_geometry(nodes, tri, fibre_direction=(1.0, 1.0, 0.0))


def _flat_and_upright():
    """Element 0 in the xy plane, element 1 in the yz plane: (6, 3) nodes, (2, 3) triangles."""
    nodes = np.array(
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]
    )
    return nodes, np.array([[0, 1, 2], [3, 4, 5]])


def test_isotropic_element_needs_no_projectable_fibre():
    nodes, tri = _flat_and_upright()
    # element 1 is perpendicular to x: fine if its material is isotropic
    geometry = reference_geometry(
        nodes, tri, fibre_direction=(1.0, 0.0, 0.0), isotropic=np.array([False, True])
    )
    frame = geometry.frame
    assert np.allclose(frame[0], [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # projectable: unchanged
    assert np.allclose(np.einsum("nai,nbi->nab", frame, frame), np.eye(2), atol=1e-15)
    assert np.allclose(np.einsum("nai,ni->na", frame, geometry.normal), 0.0, atol=1e-15)
    assert np.allclose(frame[1, 0], [0.0, 1.0, 0.0])  # the axis least aligned with the normal
    # a zero direction too, for isotropic elements
    zero = reference_geometry(
        nodes, tri, fibre_direction=(0.0, 0.0, 0.0), isotropic=np.array([True, True])
    )
    assert np.allclose(np.einsum("nai,nbi->nab", zero.frame, zero.frame), np.eye(2))
    # an anisotropic element still raises, saying what to set, on one line
    with pytest.raises(ValueError, match="perpendicular to element 1") as error:
        reference_geometry(
            nodes, tri, fibre_direction=(1.0, 0.0, 0.0), isotropic=np.array([True, False])
        )
    message = str(error.value)
    assert "\n" not in message
    assert "direction = [dx, dy, dz]" in message and "fibre_direction=" in message


def test_material_frame_names_elements_by_their_numbers():
    normal = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match="perpendicular to element 17 "):
        material_frame(normal, (1.0, 0.0, 0.0), element_numbers=np.array([4, 17]))


def test_fallback_frame_of_random_planes_is_orthonormal_and_in_plane():
    rng = np.random.default_rng(5)
    normal = rng.normal(size=(200, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    normal[:3] = np.eye(3)  # normals along the axes, where the first of equals is taken
    frame = material_frame(normal, normal, isotropic=np.ones(200, dtype=bool), fibre_angle=0.3)
    assert np.allclose(np.einsum("nai,nbi->nab", frame, frame), np.eye(2), atol=1e-14)
    assert np.allclose(np.einsum("nai,ni->na", frame, normal), 0.0, atol=1e-14)
    assert np.allclose(np.cross(frame[:, 0], frame[:, 1]), normal, atol=1e-14)  # right-handed
