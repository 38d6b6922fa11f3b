"""External loads: follower pressure and edge loads against closed forms and finite
differences of their forces; gravity and dead edge tractions against totals; the inflated
square airbag against the literature."""

import numpy as np
import pytest

import wrinkle
import wrinkle.compiled
import wrinkle.element
import wrinkle.system
from wrinkle.loads import (
    boundary_edges,
    edge_follower_forces,
    pressure_forces,
    pressure_volume,
    subtract_pressure_stiffness,
)
from wrinkle.materials import StVenantKirchhoff

RNG = np.random.default_rng(11)


def random_triangles(n=6):
    x = RNG.normal(size=(n, 3, 3))
    return x


def finite_difference(function, x, h=1e-6):
    """d function(x) / dx for function (n, 3, 3) -> (n, 9): (n, 9, 9)."""
    n = x.shape[0]
    out = np.empty((n, 9, 9))
    for j in range(9):
        dx = np.zeros((n, 9))
        dx[:, j] = h
        plus = function(x + dx.reshape(n, 3, 3))
        minus = function(x - dx.reshape(n, 3, 3))
        out[:, :, j] = (plus - minus) / (2 * h)
    return out


def test_pressure_forces_total_p_times_area_vector():
    x = random_triangles()
    p = RNG.uniform(1, 2, size=x.shape[0])
    forces, _ = pressure_forces(x, p)
    area_vector = 0.5 * np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    np.testing.assert_allclose(forces.reshape(-1, 3, 3).sum(axis=1), p[:, None] * area_vector)


def test_pressure_load_stiffness_is_derivative_of_forces():
    x = random_triangles()
    p = RNG.uniform(1, 2, size=x.shape[0])
    _, K = pressure_forces(x, p)
    fd = finite_difference(lambda y: pressure_forces(y, p, stiffness=False)[0], x)
    np.testing.assert_allclose(K, fd, atol=1e-8)


def test_pressure_stiffness_subtracted_in_place_equals_the_full_matrices():
    rng = np.random.default_rng(7)
    x = rng.normal(size=(6, 3, 3))
    p = rng.uniform(0.5, 2.0, 6)
    K = rng.normal(size=(6, 9, 9))
    expected = K - pressure_forces(x, p)[1]
    subtract_pressure_stiffness(K, x, p)
    np.testing.assert_allclose(K, expected, rtol=0, atol=1e-14)


def test_pressure_volume_gradient_is_pressure_force_on_closed_surface():
    """For a closed surface (a tetrahedron) the cone volume is the enclosed volume and its
    gradient equals the follower pressure forces at every node."""
    nodes = RNG.normal(size=(4, 3))
    faces = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    if np.linalg.det(nodes[1:] - nodes[0]) < 0:
        faces = faces[:, [0, 2, 1]]
    volume = pressure_volume(nodes[faces]).sum()
    assert volume == pytest.approx(abs(np.linalg.det(nodes[1:] - nodes[0])) / 6)
    forces = np.zeros((4, 3))
    f, _ = pressure_forces(nodes[faces], np.ones(4), stiffness=False)
    np.add.at(forces, faces.ravel(), f.reshape(-1, 3))
    h = 1e-6
    for node in range(4):
        for i in range(3):
            plus, minus = nodes.copy(), nodes.copy()
            plus[node, i] += h
            minus[node, i] -= h
            slope = (pressure_volume(plus[faces]).sum() - pressure_volume(minus[faces]).sum()) / (
                2 * h
            )
            assert forces[node, i] == pytest.approx(slope, rel=1e-7, abs=1e-9)


def test_follower_edge_load_stiffness_is_derivative_of_forces():
    x = random_triangles()
    q = RNG.uniform(1, 2, size=x.shape[0])
    forces, K = edge_follower_forces(x, q)
    # total force q e x n, in the plane of the triangle, perpendicular to the edge
    e = x[:, 1] - x[:, 0]
    total = forces[:, :3] + forces[:, 3:6]
    normal = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    np.testing.assert_allclose(np.einsum("ni,ni->n", total, e), 0, atol=1e-12)
    np.testing.assert_allclose(np.einsum("ni,ni->n", total, normal), 0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(total, axis=1), q * np.linalg.norm(e, axis=1))
    # outward: away from the third node
    assert np.all(np.einsum("ni,ni->n", total, x[:, 2] - x[:, 0]) < 0)
    fd = finite_difference(lambda y: edge_follower_forces(y, q, stiffness=False)[0], x)
    np.testing.assert_allclose(K, fd, atol=1e-7)


def test_boundary_edges_of_a_rectangle():
    mesh = wrinkle.rectangle(2.0, 1.0, 4, 3)
    triples, owner = boundary_edges(mesh.triangles)
    assert triples.shape[0] == 2 * (4 + 3)
    length = np.linalg.norm(mesh.nodes[triples[:, 1]] - mesh.nodes[triples[:, 0]], axis=1)
    assert length.sum() == pytest.approx(6.0)
    assert np.all(np.isin(triples, mesh.triangles[owner]).all(axis=1))


def _model(nx=4):
    mesh = wrinkle.rectangle(2.0, 1.0, nx, nx)
    return mesh, wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=100.0, nu=0.3, thickness=0.1))


def test_dead_edge_loads_and_gravity_totals():
    mesh, model = _model()
    model.add_edge_load(mesh.node_sets["right"], traction=(3.0, 1.0, 0.0))
    np.testing.assert_allclose(model.forces.reshape(-1, 3).sum(axis=0), [3.0, 1.0, 0.0])
    model.add_edge_load(mesh.node_sets["top"], normal=2.0)  # outward = +y, length 2
    np.testing.assert_allclose(model.forces.reshape(-1, 3).sum(axis=0), [3.0, 5.0, 0.0])
    model.add_gravity((0.0, 0.0, -9.81), density=1000.0)
    weight = 1000.0 * 0.1 * 2.0 * -9.81
    np.testing.assert_allclose(model.forces.reshape(-1, 3).sum(axis=0), [3.0, 5.0, weight])
    with pytest.raises(ValueError, match="no boundary edge"):
        model.add_edge_load([0], normal=1.0)


@pytest.mark.parametrize("block", [None, 5])
def test_model_stiffness_with_follower_loads_matches_finite_difference(monkeypatch, block):
    """Pressure and following edge tension on a bulged, taut membrane: the assembled tangent
    (material, geometric and load stiffness) is the derivative of the residual; also when it
    is assembled in blocks of 5 elements from two material groups."""
    if block is not None:
        monkeypatch.setattr(wrinkle.element, "KERNEL_BLOCK", block)
        monkeypatch.setattr(wrinkle.system, "KERNEL_BLOCK", block)
    mesh, model = _model(3)
    if block is not None:
        softer = StVenantKirchhoff.isotropic(E=30.0, nu=0.2, thickness=0.1)
        model.assign_material(softer, elements=np.arange(mesh.n_elements) % 3 == 0)
    model.fix(mesh.node_sets["left"])
    model.add_pressure(0.5)
    model.add_edge_load(mesh.node_sets["right"], normal=2.0, follow=True)
    X = mesh.nodes
    u = np.column_stack([0.05 * X[:, 0], 0.03 * X[:, 1], 0.2 * np.sin(X[:, 0]) * X[:, 1]]).ravel()
    u[model.constrained] = 0.0
    problem = model.discretise().at(1.0)
    K = problem.evaluate(u).stiffness.toarray()
    free = np.flatnonzero(problem.free)
    h = 1e-6
    fd = np.empty((free.size, free.size))
    for j, dof in enumerate(free):
        du = np.zeros_like(u)
        du[dof] = h
        fd[:, j] = -(
            problem.evaluate(u + du, False).residual - problem.evaluate(u - du, False).residual
        )[free] / (2 * h)
    assert not problem.symmetric
    np.testing.assert_allclose(K[np.ix_(free, free)], fd, atol=1e-6 * np.abs(fd).max())


@pytest.mark.parametrize("numba", ["0", "1"])
def test_pressure_on_some_elements_equals_element_by_element_sums(monkeypatch, numba):
    """Pressure on every other element: the follower forces, their load stiffness taken from
    the element matrices and the pressure work, with the element coordinates gathered or given
    and with or without the compiled kernels, equal sums over the loaded elements."""
    if numba == "1" and not wrinkle.compiled.installed():
        pytest.skip("numba not installed")
    monkeypatch.setenv("WRINKLE_NUMBA", numba)
    mesh, model = _model(3)
    loaded = np.arange(mesh.n_elements)[::2]
    model.add_pressure(0.5, elements=loaded)
    X = mesh.nodes
    u = np.column_stack([0.05 * X[:, 0], 0.03 * X[:, 1], 0.2 * np.sin(X[:, 0]) * X[:, 1]]).ravel()
    x = model.discretise().element_coordinates(u)
    f, K = pressure_forces(x[loaded], np.full(loaded.size, 0.5))
    expected = np.zeros(model.n_dofs)
    np.add.at(expected, model.discretise().pattern.element_dofs[loaded], f)
    for given in (None, x):
        forces, _ = model.discretise().follower_forces(u, 1.0, stiffness=False, x_elements=given)
        np.testing.assert_allclose(forces, expected, rtol=1e-14, atol=1e-15)
        assert model.discretise().pressure_work(u, x_elements=given) == pytest.approx(
            0.5 * pressure_volume(x[loaded]).sum(), rel=1e-14
        )
    matrices = RNG.normal(size=(mesh.n_elements, 9, 9))
    subtracted = matrices.copy()
    system = model.discretise()
    system.subtract_pressure_stiffness(
        subtracted, x, slice(0, mesh.n_elements), system.pressure_at(1.0)
    )
    expected_matrices = matrices.copy()
    expected_matrices[loaded] -= K
    np.testing.assert_allclose(subtracted, expected_matrices, rtol=0, atol=1e-14)


def test_materials_per_region():
    """Two materials in series (nu = 0, uniaxial): the same force per unit reference width
    P = stretch E t E11 in both halves, E11 = (stretch^2 - 1)/2, stretches adding up to the
    prescribed length."""
    mesh = wrinkle.rectangle(2.0, 1.0, 4, 2)
    stiff = StVenantKirchhoff.isotropic(E=100.0, nu=0.0, thickness=0.1)
    soft = StVenantKirchhoff.isotropic(E=10.0, nu=0.0, thickness=0.1)
    centroid_x = mesh.nodes[mesh.triangles].mean(axis=1)[:, 0]
    model = wrinkle.Model(mesh, stiff)
    model.assign_material(soft, elements=centroid_x > 1.0)
    model.fix(mesh.node_sets["left"], "x")
    model.fix([0], "y")
    model.fix(np.arange(mesh.n_nodes), "z")
    model.prescribe(mesh.node_sets["right"], (0.1, np.nan, np.nan))
    results = model.solve(tolerance=1e-12)
    ux = results.final.displacement.reshape(-1, 3)[:, 0]
    middle = np.flatnonzero(np.isclose(mesh.nodes[:, 0], 1.0))
    # 100 l1 (l1^2 - 1) = 10 l2 (l2^2 - 1), l1 + l2 = 2.1
    from scipy.optimize import brentq

    l1 = brentq(lambda a: 100 * a * (a**2 - 1) - 10 * (2.1 - a) * ((2.1 - a) ** 2 - 1), 1.0, 1.1)
    np.testing.assert_allclose(ux[middle], l1 - 1.0, rtol=1e-9)
    assert len(model.discretise().groups) == 2


def test_inflated_square_airbag_centre_deflection():
    """Contri & Schrefler (1988) square airbag, quarter model: diagonal 1.2 m, E = 588 MPa,
    nu = 0.4, t = 0.6 mm, p = 5 kPa; centre deflection 217 mm in the literature (e.g. Ziegler,
    Wagner & Bletzinger 2003). Solved from the flat sheet at full pressure, 2,048 elements."""
    half = 1.2 / np.sqrt(2) / 2  # quarter: the square between the centre and the seams
    mesh = wrinkle.rectangle(half, half, 32, 32)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=588e6, nu=0.4, thickness=0.6e-3))
    X = mesh.nodes
    model.fix(np.flatnonzero(np.isclose(X[:, 0], 0)), "x", label="symmetry x = 0")
    model.fix(np.flatnonzero(np.isclose(X[:, 1], 0)), "y", label="symmetry y = 0")
    seam = np.isclose(X[:, 0], half) | np.isclose(X[:, 1], half)
    model.fix(np.flatnonzero(seam), "z", label="seam")
    model.add_pressure(5000.0)
    results = model.solve(steps=1)
    centre = results.final.displacement[2]
    assert centre == pytest.approx(0.217, rel=0.03)
    _, wrinkled, _ = results.final.states
    assert wrinkled > 0.3 * mesh.n_elements  # wrinkled band along the seams
    # vertical equilibrium: the seam carries the pressure times the deformed projected area
    x = mesh.nodes + results.final.displacement.reshape(-1, 3)
    t = x[mesh.triangles]
    a, b = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    projected = 0.5 * np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    reactions = model.support_reactions(results.final.reactions)
    assert reactions["seam"][2] == pytest.approx(-5000.0 * projected, rel=1e-7)
    # the step's reactions, taken from the solver's last evaluation, are the reactions
    # evaluated afresh at the converged displacements (internal minus follower forces)
    np.testing.assert_array_equal(
        results.final.reactions, model.discretise().reactions(results.final.displacement, 1.0)
    )


def test_supports_with_one_label_count_a_shared_component_once():
    """Two supports labelled alike that both hold the corner's x and y: the label's reaction
    balances the applied force once (global equilibrium), not with the corner counted twice."""
    mesh = wrinkle.rectangle(1.0, 1.0, 3, 3)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=1.0))
    bottom = mesh.node_sets["bottom"]
    model.fix(bottom, "xyz", label="base")
    model.fix(bottom[:1], "xy", label="base")  # the corner again
    model.fix(np.arange(mesh.n_nodes), "z", label="plane")
    top = mesh.node_sets["top"]
    model.add_nodal_force(top, (0.02, 0.05, 0.0))
    results = model.solve()
    reactions = model.support_reactions(results.final.reactions)
    np.testing.assert_allclose(
        reactions["base"][:2], [-0.02 * top.size, -0.05 * top.size], rtol=1e-7
    )
