"""The inflated neo-Hookean sphere: the closed form against the energy principle and the
material law, its limit point and inverse, the octant mesh generator, and the case file."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from verification.references.sphere import LIMIT_STRETCH, InflatedSphere, effective_radius
from wrinkle import material_response
from wrinkle.case import CaseError, read_case, read_case_data
from wrinkle.materials import NeoHookean
from wrinkle.mesh import mesh_size, sphere

CASE = Path(__file__).resolve().parents[2] / "verification" / "cases" / "sphere.toml"
MU, THICKNESS, RADIUS = 4.0e5, 1.0e-3, 0.1  # N/m^2, m, m (the case file's values)
STRETCHES = np.array([1.0005, 1.05, 1.2, 1.3, LIMIT_STRETCH, 1.6, 2.5, 4.0])


@pytest.fixture
def balloon() -> InflatedSphere:
    return InflatedSphere(MU, THICKNESS, RADIUS)


def test_pressure_is_the_derivative_of_strain_energy_by_volume(balloon):
    """p = dW/dV with W(lambda) = 4 pi R^2 w(lambda^2 I), w the strain energy per unit
    reference area of wrinkle's incompressible neo-Hookean law, and V = 4/3 pi R^3 lambda^3;
    central differences in lambda (truncation ~ step^2, relative 1e-9 here; lambda >= 1.05,
    since close to 1 the energy difference is lost in the round-off of tr C + 1/det C - 3)."""
    material = NeoHookean(MU, THICKNESS)
    stretches = STRETCHES[STRETCHES >= 1.05]

    def strain_energy(stretch):
        C = stretch[:, None, None] ** 2 * np.eye(2)
        return 4.0 * math.pi * RADIUS**2 * material.energy(C)

    def volume(stretch):
        return 4.0 / 3.0 * math.pi * RADIUS**3 * stretch**3

    step = 1e-5
    up, down = stretches + step, stretches - step
    energy_principle = (strain_energy(up) - strain_energy(down)) / (volume(up) - volume(down))
    np.testing.assert_allclose(balloon.pressure(stretches), energy_principle, rtol=1e-8)
    # the same with the strain energy written out, W = 4 pi R^2 T mu/2 (2 l^2 + l^-4 - 3)
    written = (
        2.0 * math.pi * RADIUS**2 * THICKNESS * MU * (2 * up**2 + up**-4 - 2 * down**2 - down**-4)
    )
    np.testing.assert_allclose(
        balloon.pressure(stretches), written / (volume(up) - volume(down)), rtol=1e-8
    )


def test_tension_and_thickness_match_the_material_law(balloon):
    """At the equibiaxial deformation F = lambda I the material point is taut, with both
    principal Cauchy resultants mu T (1 - lambda^-6), thickness T / lambda^2, Cauchy stress
    resultant / thickness = mu (lambda^2 - lambda^-4), and Laplace's law p r = 2 N holds."""
    material = NeoHookean(MU, THICKNESS)
    for stretch in STRETCHES:
        point = material_response(material, stretch * np.eye(2))
        assert point.state == "taut"
        np.testing.assert_allclose(point.principal_stress, balloon.tension(stretch), rtol=1e-12)
        assert point.thickness == pytest.approx(balloon.current_thickness(stretch), rel=1e-13)
        assert point.principal_stress[1] / point.thickness == pytest.approx(
            balloon.cauchy_stress(stretch), rel=1e-12
        )
        assert balloon.pressure(stretch) * stretch * RADIUS == pytest.approx(
            2.0 * balloon.tension(stretch), rel=1e-13
        )


def test_small_strain_limit_is_the_thin_walled_vessel(balloon):
    """For lambda = 1 + e, e -> 0: hoop stress p R / (2 T) and strain e = (1 - nu) sigma / E
    with the small-strain constants of the incompressible solid E = 3 mu, nu = 1/2 give
    p = 4 E T e / R = 12 mu T e / R (Timoshenko & Goodier, thin spherical vessel)."""
    strain = np.array([1e-6, 1e-5])
    np.testing.assert_allclose(
        balloon.pressure(1.0 + strain), 12.0 * MU * THICKNESS * strain / RADIUS, rtol=1e-4
    )


def test_limit_point_at_seventh_root(balloon):
    """dp/dlambda = 0 at lambda = 7^(1/6) (central differences), p is largest there over a
    fine grid, and p_max = (2 mu T / R)(6/7) 7^(-1/6)."""
    assert LIMIT_STRETCH == pytest.approx(1.3830875542684884, rel=1e-15)
    step = 1e-6
    slope = (balloon.pressure(LIMIT_STRETCH + step) - balloon.pressure(LIMIT_STRETCH - step)) / (
        2 * step
    )
    assert abs(slope) < 1e-9 * balloon.pressure_scale
    grid = np.linspace(1.0, 3.0, 200_001)
    assert grid[np.argmax(balloon.pressure(grid))] == pytest.approx(LIMIT_STRETCH, abs=2e-5)
    assert balloon.limit_pressure == pytest.approx(
        2 * MU * THICKNESS / RADIUS * 6.0 / 7.0 * 7.0 ** (-1.0 / 6.0), rel=1e-14
    )
    assert np.all(np.diff(balloon.pressure(np.linspace(1.0, LIMIT_STRETCH, 1001))) > 0)


def test_stretch_inverts_the_pressure_on_the_rising_branch(balloon):
    stretch = np.linspace(1.0, LIMIT_STRETCH, 41)[1:-1]
    found = balloon.stretch(balloon.pressure(stretch))
    np.testing.assert_allclose(found, stretch, rtol=1e-12)
    assert balloon.stretch(0.0) == 1.0
    assert float(balloon.stretch(balloon.limit_pressure)) == pytest.approx(LIMIT_STRETCH, rel=1e-7)
    # beyond the limit point the curve falls: the same pressure, the stable stretch
    assert float(balloon.stretch(balloon.pressure(1.6))) < LIMIT_STRETCH
    with pytest.raises(ValueError, match="outside 0 .. p_max"):
        balloon.stretch(1.0001 * balloon.limit_pressure)
    with pytest.raises(ValueError, match="outside"):
        balloon.stretch([100.0, -1.0])
    with pytest.raises(ValueError, match="thickness must be finite and > 0"):
        InflatedSphere(MU, 0.0, RADIUS)


# -- the octant mesh --------------------------------------------------------------------------


@pytest.mark.parametrize("n", [1, 2, 5, 16])
def test_sphere_octant_nodes_triangles_and_sets(n):
    radius = 2.5
    mesh = sphere(radius, n)
    assert mesh.n_nodes == (n + 1) * (n + 2) // 2 and mesh.n_elements == n**2
    np.testing.assert_allclose(np.linalg.norm(mesh.nodes, axis=1), radius, rtol=1e-15)
    assert np.all(mesh.nodes >= 0.0)
    assert np.array_equal(np.unique(mesh.triangles), np.arange(mesh.n_nodes))
    # outward: (X2 - X1) x (X3 - X1) points away from the centre, like the centroid
    X = mesh.nodes[mesh.triangles]
    normal = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    cosine = np.einsum("ni,ni->n", normal, X.mean(axis=1)) / (
        np.linalg.norm(normal, axis=1) * np.linalg.norm(X.mean(axis=1), axis=1)
    )
    assert np.all(cosine > 0.9)
    # the symmetry edges: exactly on their planes, n + 1 nodes each, corners shared
    for name, axis in (("yz-plane", 0), ("zx-plane", 1), ("xy-plane", 2)):
        nodes = mesh.node_sets[name]
        assert np.array_equal(nodes, np.flatnonzero(mesh.nodes[:, axis] == 0.0))
        assert nodes.size == n + 1
    # conforming: boundary edges (in one triangle) are the 3n edge segments on the planes
    edges = np.sort(mesh.triangles[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    assert set(count.tolist()) <= {1, 2}
    boundary = unique[count == 1]
    assert boundary.shape[0] == 3 * n
    on_a_plane = np.any(
        (mesh.nodes[boundary[:, 0]] == 0.0) & (mesh.nodes[boundary[:, 1]] == 0.0), axis=1
    )
    assert np.all(on_a_plane)


def test_sphere_edges_equally_spaced_and_elements_even():
    mesh = sphere(1.0, 12)
    edge = mesh.nodes[mesh.node_sets["xy-plane"]]
    angle = np.sort(np.arctan2(edge[:, 1], edge[:, 0]))
    np.testing.assert_allclose(np.diff(angle), np.pi / 24, rtol=1e-12)
    X = mesh.nodes[mesh.triangles]
    area = 0.5 * np.linalg.norm(np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]), axis=1)
    assert area.max() / area.min() < 1.8


def test_sphere_area_and_effective_radius_converge_at_order_two():
    """The faceted area tends to pi R^2 / 2 and 3V/A to R, both with error ~ h^2."""
    radius = 0.3
    sizes, area_errors, radius_errors = [], [], []
    for n in (8, 16, 32, 64):
        mesh = sphere(radius, n)
        X = mesh.nodes[mesh.triangles]
        area = 0.5 * np.linalg.norm(np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]), axis=1)
        sizes.append(mesh_size(mesh))
        area_errors.append(1.0 - area.sum() / (np.pi * radius**2 / 2))
        radius_errors.append(1.0 - effective_radius(mesh) / radius)
    for errors in (area_errors, radius_errors):
        assert np.all(np.array(errors) > 0)  # inscribed: smaller
        order = np.polyfit(np.log(sizes), np.log(errors), 1)[0]
        assert order == pytest.approx(2.0, abs=0.05)


def test_effective_radius_of_one_flat_face():
    """n = 1: the triangle R e_x, R e_y, R e_z, whose plane is R / sqrt(3) from the centre."""
    assert effective_radius(sphere(2.0, 1)) == pytest.approx(2.0 / math.sqrt(3.0), rel=1e-14)


@pytest.mark.parametrize(
    "radius, n, message",
    [
        (0.0, 4, "radius must be a finite number > 0"),
        (math.inf, 4, "radius must be a finite number > 0"),
        (1.0, 0, "n must be an integer >= 1"),
        (1.0, 2.5, "n must be an integer >= 1"),
        (1.0, True, "n must be an integer >= 1"),
    ],
)
def test_sphere_rejects_bad_input(radius, n, message):
    with pytest.raises(ValueError, match=message):
        sphere(radius, n)


# -- the case file ----------------------------------------------------------------------------


def test_case_file_reads_the_octant_and_loads_it_with_p_at_stretch_1_3(tmp_path):
    data = read_case_data(CASE)
    balloon = InflatedSphere(
        data["material"]["mu"], data["material"]["thickness"], data["mesh"]["sphere"]["radius"]
    )
    assert (MU, THICKNESS, RADIUS) == (balloon.mu, balloon.thickness, balloon.radius)
    assert data["load"][0]["value"] == pytest.approx(float(balloon.pressure(1.3)), rel=1e-15)
    model = read_case(CASE, overrides={"mesh": {"sphere": {"n": 4}}}).model
    assert model.mesh.n_elements == 16
    assert {s.label: s.nodes.size for s in model.supports} == {
        "symmetry x": 5,
        "symmetry y": 5,
        "symmetry z": 5,
    }
    bad = tmp_path / "sphere.toml"
    bad.write_text(CASE.read_text().replace("radius = 0.1", "radius = -0.1"))
    with pytest.raises(CaseError, match="'radius' must be > 0"):
        read_case(bad)


def test_octant_inflation_matches_the_faceted_energy_principle():
    """The finite-element octant (n = 8) under p(1.3): its stretch lies below the smooth
    sphere's by the faceting error, and the uniformly inflated polyhedron (p = (R / R_eff)
    p(lambda), energy principle) predicts that error to within 5 %."""
    case = read_case(CASE, overrides={"mesh": {"sphere": {"n": 8}}})
    model = case.model
    results = case.solve()
    x = model.mesh.nodes + results.final.displacement.reshape(-1, 3)
    stretch = np.linalg.norm(x, axis=1).mean() / RADIUS
    balloon = InflatedSphere(MU, THICKNESS, RADIUS)
    pressure = read_case_data(CASE)["load"][0]["value"]
    smooth = float(balloon.stretch(pressure))
    faceted = float(balloon.stretch(pressure * effective_radius(model.mesh) / RADIUS))
    assert smooth == pytest.approx(1.3, rel=1e-14)
    assert stretch < faceted < smooth
    assert abs(stretch - faceted) < 0.05 * abs(stretch - smooth)
    assert results.final.states == (model.mesh.n_elements, 0, 0)
