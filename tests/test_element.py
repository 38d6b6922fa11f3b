"""Element forces and consistent stiffness against finite differences and closed forms.

The references are independent of the element code: central finite differences of the
assembled internal forces (for the stiffness) and of the total strain energy (for the forces),
the balance of forces and moments of each element, the transformation under a rigid rotation,
and the closed-form edge forces of homogeneous patches (uniaxial tension-field and biaxial
states). Meshes are small, non-flat and randomly deformed, in taut, wrinkled and mixed
(taut + wrinkled + slack) states, for every material.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from wrinkle import Mesh, Model, NeoHookean, StVenantKirchhoff, rectangle
from wrinkle.element import element_stiffness, strain_displacement, unit_tension_stiffness
from wrinkle.kinematics import deformation_gradient, element_coordinates, right_cauchy_green
from wrinkle.wrinkling import SLACK, TAUT, WRINKLED

STATES = ("taut", "wrinkled", "mixed")
SIZE = 1.0  # side of the square membrane
DIVISIONS = 4
ELEMENT_SIZE = SIZE / DIVISIONS
FD_STEP = 1e-6 * ELEMENT_SIZE
FD_TOLERANCE = 1e-6


def rotation(vector) -> np.ndarray:
    """Rotation matrix about ``vector`` by |vector| radians."""
    return Rotation.from_rotvec(vector).as_matrix()


ROTATION = rotation([0.3, -0.2, 0.5])
TRANSLATION = np.array([0.1, 0.2, 0.3])


def wavy_mesh(seed: int = 0) -> Mesh:
    """4x4 rectangle mesh (32 triangles) with nodes moved in-plane and out of plane."""
    base = rectangle(SIZE, SIZE, DIVISIONS, DIVISIONS)
    rng = np.random.default_rng(seed)
    nodes = base.nodes.copy()
    nodes[:, :2] += 0.03 * rng.uniform(-1.0, 1.0, (base.n_nodes, 2))
    nodes[:, 2] = 0.05 * rng.uniform(-1.0, 1.0, base.n_nodes)
    return Mesh(nodes, base.triangles, base.node_sets)


MESH = wavy_mesh()


def deformed_positions(state: str, seed: int = 1) -> np.ndarray:
    """Current node positions (n_nodes, 3) meant to put the elements in ``state``.

    taut: biaxial stretch 1.10 x 1.08; wrinkled: stretch 1.10 with lateral contraction to 0.90;
    mixed: stretches decreasing from (1.16, 1.16) on the left edge to (0.80, 0.80) on the right
    (taut, then wrinkled, then slack). A random perturbation of 0.004 and a rigid motion
    follow.
    """
    X = MESH.nodes
    s, t = X[:, 0], X[:, 1]
    if state == "taut":
        x = X * np.array([1.10, 1.08, 1.0])
    elif state == "wrinkled":
        x = X * np.array([1.10, 0.90, 1.0])
    elif state == "mixed":
        x = np.column_stack([1.16 * s - 0.18 * s**2, (1.16 - 0.36 * s) * t, X[:, 2]])
    else:
        raise ValueError(state)
    x = x + 0.004 * np.random.default_rng(seed).uniform(-1.0, 1.0, x.shape)
    return x @ ROTATION.T + TRANSLATION


def displacement(state: str) -> np.ndarray:
    return (deformed_positions(state) - MESH.nodes).ravel()


def make_model(case) -> Model:
    return Model(MESH, case.material, case.fibre_direction, case.fibre_angle)


def check_states(counts, state: str) -> None:
    """The deformation really produces the intended state(s)."""
    n = MESH.n_elements
    if state == "taut":
        assert counts == (n, 0, 0)
    elif state == "wrinkled":
        assert counts == (0, n, 0)
    else:
        assert min(counts) >= 3, f"not all three states present (taut, wrinkled, slack) = {counts}"


def fd_stiffness(model: Model, u: np.ndarray, h: float) -> np.ndarray:
    """Central difference of the assembled internal forces, column by column, (n_dofs, n_dofs).

    Asserts that no element changes state under any perturbation: across a state switch the
    forces are not differentiable and the difference quotient means nothing.
    """
    state = model.discretise().evaluate_elements(u, stiffness=False).response.state
    K = np.empty((u.size, u.size))
    for j in range(u.size):
        columns = []
        for sign in (1.0, -1.0):
            v = u.copy()
            v[j] += sign * h
            moved = model.discretise().evaluate_elements(v, stiffness=False).response.state
            switched = np.flatnonzero(moved != state)
            assert switched.size == 0, f"elements {switched} change state when dof {j} moves"
            columns.append(model.discretise().internal_forces(v))
        K[:, j] = (columns[0] - columns[1]) / (2.0 * h)
    return K


def total_energy(model: Model, u: np.ndarray) -> float:
    """sum over elements of A0 * relaxed energy density, computed from the kinematics."""
    x = MESH.nodes + u.reshape(-1, 3)
    geometry = model.discretise().elements.geometry
    F = deformation_gradient(element_coordinates(x, MESH.triangles), geometry.shape_gradient)
    return float(
        np.sum(geometry.area * model.discretise().elements.material.energy(right_cauchy_green(F)))
    )


# --------------------------------------------------------------------------- stiffness
@pytest.mark.parametrize("state", STATES)
def test_stiffness_is_derivative_of_internal_forces(material_case, state):
    model = make_model(material_case)
    u = displacement(state)
    evaluation = model.discretise().at().evaluate(u, stiffness=True)  # no supports: the full matrix
    check_states(evaluation.states, state)
    K = evaluation.stiffness.toarray()
    K_fd = fd_stiffness(model, u, FD_STEP)
    error = np.linalg.norm(K - K_fd) / np.linalg.norm(K)
    assert error < FD_TOLERANCE, f"relative Frobenius error {error:.3g}"
    # a hyperelastic (relaxed) energy has a symmetric Hessian
    assert np.linalg.norm(K - K.T) <= 1e-12 * np.linalg.norm(K)


@pytest.mark.parametrize("state", STATES)
def test_internal_forces_are_gradient_of_energy(material_case, state):
    model = make_model(material_case)
    u = displacement(state)
    check_states(model.discretise().at().evaluate(u, stiffness=False).states, state)
    f = model.discretise().internal_forces(u)
    h = 1e-6 * ELEMENT_SIZE
    gradient = np.empty_like(u)
    for j in range(u.size):
        up, um = u.copy(), u.copy()
        up[j] += h
        um[j] -= h
        gradient[j] = (total_energy(model, up) - total_energy(model, um)) / (2.0 * h)
    error = np.linalg.norm(f - gradient) / np.linalg.norm(f)
    assert error < FD_TOLERANCE, f"relative error {error:.3g}"
    # the element energies reported by the element and the problem are the same energy
    assert np.sum(model.discretise().evaluate_elements(u, stiffness=False).energy) == pytest.approx(
        total_energy(model, u), rel=1e-12
    )
    assert model.discretise().at().evaluate(u, stiffness=False).energy == pytest.approx(
        total_energy(model, u), rel=1e-12
    )


# --------------------------------------------------------------------------- invariance
@pytest.mark.parametrize("state", STATES)
def test_element_forces_balance(material_case, state):
    """Each element is in equilibrium: nodal forces sum to zero and have zero moment."""
    model = make_model(material_case)
    u = displacement(state)
    result = model.discretise().evaluate_elements(u, stiffness=False)
    check_states(
        tuple(int(np.count_nonzero(result.response.state == s)) for s in (TAUT, WRINKLED, SLACK)),
        state,
    )
    f = result.forces.reshape(-1, 3, 3)
    x = element_coordinates(MESH.nodes + u.reshape(-1, 3), MESH.triangles)
    scale = np.max(np.abs(f))
    assert np.max(np.abs(f.sum(axis=1))) <= 1e-13 * scale
    moment = np.cross(x, f).sum(axis=1)  # about the origin
    assert np.max(np.abs(moment)) <= 1e-13 * scale * np.max(np.abs(x))
    # slack elements carry nothing
    assert np.all(f[result.response.state == SLACK] == 0.0)


@pytest.mark.parametrize("state", ["taut", "mixed"])
def test_rigid_rotation_rotates_forces_and_stiffness(material_case, state):
    model = make_model(material_case)
    x = deformed_positions(state)
    Q = rotation([-0.7, 1.1, 0.4])
    u = (x - MESH.nodes).ravel()
    u_rotated = (x @ Q.T + np.array([-1.0, 0.5, 2.0]) - MESH.nodes).ravel()
    before = model.discretise().at().evaluate(u)
    after = model.discretise().at().evaluate(u_rotated)
    assert after.states == before.states
    check_states(before.states, state)
    assert after.energy == pytest.approx(before.energy, rel=1e-12)
    f = model.discretise().internal_forces(u).reshape(-1, 3)
    f_rotated = model.discretise().internal_forces(u_rotated).reshape(-1, 3)
    assert np.allclose(f_rotated, f @ Q.T, rtol=0.0, atol=1e-12 * np.max(np.abs(f)))
    Q_all = np.kron(np.eye(MESH.n_nodes), Q)
    K = before.stiffness.toarray()
    K_rotated = after.stiffness.toarray()
    assert np.allclose(K_rotated, Q_all @ K @ Q_all.T, rtol=0.0, atol=1e-12 * np.max(np.abs(K)))


# --------------------------------------------------------------------------- closed forms
def homogeneous_patch(material, stretch_x: float, stretch_y: float, shear: float = 0.0):
    """Flat 3x3 square membrane (18 elements, the paper's mesh) under x = F X, F =
    [[stretch_x, shear], [0, stretch_y]]; returns (model, internal forces (n_nodes, 3))."""
    mesh = rectangle(1.0, 1.0, 3, 3)
    F = np.eye(3)
    F[:2, :2] = [[stretch_x, shear], [0.0, stretch_y]]
    u = (mesh.nodes @ F.T - mesh.nodes).ravel()
    model = Model(mesh, material)
    return model, u, model.discretise().internal_forces(u).reshape(-1, 3)


def edge_resultant(model: Model, forces: np.ndarray, edge: str) -> np.ndarray:
    return forces[model.mesh.node_sets[edge]].sum(axis=0)


def interior_nodes(model: Model) -> np.ndarray:
    boundary = np.unique(np.concatenate(list(model.mesh.node_sets.values())))
    return np.setdiff1d(np.arange(model.mesh.n_nodes), boundary)


def test_homogeneous_biaxial_svk_edge_forces():
    """Taut SVK patch: N = D0 E/(1 - nu^2) [[1, nu], [nu, 1]] E (plane stress), right edge
    force F N e1 per unit reference length, interior nodes in equilibrium."""
    E, nu, D0 = 2.0, 0.3, 0.1
    lx, ly = 1.12, 1.05
    model, u, f = homogeneous_patch(StVenantKirchhoff.isotropic(E, nu, D0), lx, ly)
    assert model.discretise().evaluate_elements(u).response.state.tolist() == [TAUT] * 18
    E11, E22 = 0.5 * (lx**2 - 1.0), 0.5 * (ly**2 - 1.0)
    N11 = D0 * E / (1.0 - nu**2) * (E11 + nu * E22)
    N22 = D0 * E / (1.0 - nu**2) * (E22 + nu * E11)
    assert np.allclose(f[interior_nodes(model)], 0.0, atol=1e-14)
    assert np.allclose(edge_resultant(model, f, "right"), [lx * N11, 0.0, 0.0], atol=1e-14)
    assert np.allclose(edge_resultant(model, f, "top"), [0.0, ly * N22, 0.0], atol=1e-14)


@pytest.mark.parametrize(
    "material, uniaxial_stress",
    [
        # SVK: uniaxial plane stress N11 = E D0 E11 (lateral strain free)
        (StVenantKirchhoff.isotropic(2.0, 0.3, 0.1), lambda lam: 2.0 * 0.1 * 0.5 * (lam**2 - 1)),
        # incompressible neo-Hookean: N11 = mu D0 (1 - lambda^-3)
        (NeoHookean(1.5, 0.1), lambda lam: 1.5 * 0.1 * (1.0 - lam**-3)),
    ],
    ids=["svk_isotropic", "neo_hookean_incompressible"],
)
def test_homogeneous_tension_field_edge_forces(material, uniaxial_stress):
    """Wrinkled isotropic patch stretched along x and contracted along y more than the free
    lateral contraction: a uniaxial tension field, right edge force lambda N11, top edge zero."""
    lx, ly = 1.15, 0.8
    model, u, f = homogeneous_patch(material, lx, ly)
    assert model.discretise().evaluate_elements(u).response.state.tolist() == [WRINKLED] * 18
    scale = lx * uniaxial_stress(lx)
    assert np.allclose(f[interior_nodes(model)], 0.0, atol=1e-13 * scale)
    assert np.allclose(edge_resultant(model, f, "right"), [scale, 0.0, 0.0], atol=1e-13 * scale)
    assert np.allclose(edge_resultant(model, f, "top"), 0.0, atol=1e-13 * scale)


def test_homogeneous_slack_patch_has_no_forces_or_stiffness(material_case):
    model, u, f = homogeneous_patch(material_case.material, 0.9, 0.95, shear=0.02)
    evaluation = model.discretise().at().evaluate(u)
    assert evaluation.states == (0, 0, 18)
    assert np.all(f == 0.0)
    assert evaluation.stiffness.count_nonzero() == 0


def test_unit_tension_stiffness_is_the_dirichlet_energy():
    """The assembled step metric of the Newton solver: for a displacement field linear in the
    reference coordinates, u = A X, u.L u = area * |A|^2 (the integral of |grad u|^2), and a
    rigid translation is in its null space; per element it equals the geometric stiffness of
    ``element_stiffness`` with N = I and no material part."""
    mesh = rectangle(2.0, 1.5, 5, 4)
    model = Model(mesh, StVenantKirchhoff.isotropic(1.0, 0.3, thickness=1.0))
    L = model.discretise().pattern.matrix(model.discretise().step_metric())
    A = np.array([[0.3, -0.7, 0.0], [1.1, 0.4, 0.0], [-0.2, 0.5, 0.0]])
    u = (mesh.nodes @ A.T).ravel()
    assert u @ (L @ u) == pytest.approx(3.0 * np.sum(A[:, :2] ** 2), rel=1e-12)
    translation = np.tile([0.4, -1.0, 2.0], mesh.n_nodes)
    assert np.abs(L @ translation).max() < 1e-12

    g = model.discretise().geometry
    F = np.zeros((g.n_elements, 3, 2))
    F[:, :2, :] = np.eye(2)
    B = strain_displacement(F, g.shape_gradient)
    geometric = element_stiffness(
        g.area,
        B,
        np.zeros((g.n_elements, 3, 3)),
        g.shape_gradient,
        np.tile(np.eye(2), (g.n_elements, 1, 1)),
    )
    np.testing.assert_allclose(
        unit_tension_stiffness(g.area, g.shape_gradient), geometric, atol=1e-14
    )
