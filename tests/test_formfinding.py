"""Form finding (issue 21, item 3; ``wrinkle.formfinding``), against closed forms: the
catenoid's neck radius, the edge cable's arc of radius T / n, the flat sheet that is its own
form; the shape does not depend on the elastic stiffness; the outer iterations do not grow
with the mesh; a model without a form is refused in one line."""

import math

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import brentq

from wrinkle import Model, StVenantKirchhoff, rectangle
from wrinkle.formfinding import FormFindingError, find_form, form_residual
from wrinkle.materials import Prestressed
from wrinkle.mesh import Mesh

N = 100.0  # prestress, N/m


def sheet(E: float = 1e6) -> Prestressed:
    return Prestressed(StVenantKirchhoff.isotropic(E=E, nu=0.3, thickness=1e-3), N)


def tube(radius: float, height: float, n_around: int, n_along: int) -> Mesh:
    """An open tube about z, -height/2 <= z <= height/2: (n_along + 1) rings of n_around
    nodes, each quadrilateral split into two triangles."""
    i, j = np.meshgrid(np.arange(n_along + 1), np.arange(n_around), indexing="ij")
    angle = 2 * np.pi * j / n_around
    nodes = np.stack(
        [radius * np.cos(angle), radius * np.sin(angle), height * (i / n_along - 0.5)], axis=-1
    ).reshape(-1, 3)
    a, b = (k.ravel() for k in np.meshgrid(np.arange(n_along), np.arange(n_around), indexing="ij"))

    def node(ring, k):
        return ring * n_around + k % n_around

    first = np.stack([node(a, b), node(a, b + 1), node(a + 1, b + 1)], axis=1)
    second = np.stack([node(a, b), node(a + 1, b + 1), node(a + 1, b)], axis=1)
    return Mesh(nodes, np.concatenate([first, second]))


def catenoid_neck(radius: float, height: float) -> float:
    """The neck radius r0 of the catenoid r = r0 cosh(z / r0) through two coaxial rings of
    radius R at z = +-h/2: the stable (larger) root of h/2 = r0 arccosh(R / r0). A soap film,
    the surface of zero mean curvature, is the form of an isotropic prestress; among the
    surfaces of revolution r(z) they are the catenaries (Euler-Lagrange of int r sqrt(1 + r'^2))."""

    def slope(r: float) -> float:  # d/dr of r arccosh(R / r); zero at the fold of the roots
        ratio = radius / r
        return math.acosh(ratio) - ratio / math.sqrt(ratio**2 - 1.0)

    turn = brentq(slope, 1e-6 * radius, radius * (1 - 1e-12))
    return brentq(lambda r: r * math.acosh(radius / r) - height / 2, turn, radius * (1 - 1e-15))


def test_catenoid_neck_converges_to_the_closed_form():
    """R = 1, h = 1 (r0 = 0.84834): the neck's error falls with the mesh at about second
    order and is within 0.1 % on the finest mesh."""
    r0 = catenoid_neck(1.0, 1.0)
    errors = []
    for n_around in (32, 64):
        mesh = tube(1.0, 1.0, n_around, n_around // 6 * 2)
        model = Model(mesh, sheet())
        model.fix("z == -0.5 or z == 0.5")
        form = find_form(model)
        neck = np.isclose(mesh.nodes[:, 2], 0.0)
        radius = np.hypot(form.nodes[neck, 0], form.nodes[neck, 1])
        errors.append(abs(radius.mean() / r0 - 1.0))
        assert form.converged and form.iterations < 40
    assert errors[-1] < 1e-3, errors
    assert errors[0] / errors[1] > 3.0, errors


def cable_arc_model(E: float = 1e6, n: int = 16) -> Model:
    """A 1 m square with isotropic prestress 20 N/m, held along x = 0 and x = 1, its edges
    y = 0 and y = 1 free but for a cable of force T = 20 N each."""
    model = Model(rectangle(1.0, 1.0, n, n), Prestressed(sheet(E).material, 20.0))
    model.fix("x == 0 or x == 1")
    model.add_cables("y == 0", EA=1e4, prestress=20.0, label="south")
    model.add_cables("y == 1", EA=1e4, prestress=20.0, label="north")
    return model


def test_edge_cable_is_an_arc_of_radius_T_over_n():
    """A cable of constant force T bounding a membrane of isotropic prestress n: its balance
    across the cable, T / rho = n, makes a circular arc of radius rho = T / n. With
    T = 20 N and n = 20 N/m, rho = 1 m through the held corners (0, 0) and (1, 0), bulging
    inwards with the sag rho - sqrt(rho^2 - 1/4) = 1 - sqrt(3)/2 at mid-span."""
    model = cable_arc_model(n=24)
    form = find_form(model)
    south = np.flatnonzero(np.isclose(model.mesh.nodes[:, 1], 0.0))
    x, y = form.nodes[south, 0], form.nodes[south, 1]
    assert np.allclose(form.nodes[:, 2], 0.0)
    # the circle through the points: x^2 + y^2 + D x + E y + F = 0 by least squares
    A = np.stack([x, y, np.ones_like(x)], axis=1)
    D, E_, F = np.linalg.lstsq(A, -(x**2 + y**2), rcond=None)[0]
    rho = math.sqrt(D**2 / 4 + E_**2 / 4 - F)
    assert rho == pytest.approx(1.0, rel=1e-2)
    assert y.max() == pytest.approx(1.0 - math.sqrt(3.0) / 2.0, rel=1e-2)


def test_the_shape_does_not_depend_on_the_elastic_stiffness():
    """The strategy uses the prestress alone: two sheets 1000 times apart in E have the
    same form to round-off."""
    soft = find_form(cable_arc_model(E=1e6)).nodes
    stiff = find_form(cable_arc_model(E=1e9)).nodes
    assert np.abs(soft - stiff).max() < 1e-12


def test_a_flat_prestressed_sheet_is_its_own_form():
    """A constant stress balances in any flat triangulation: held all round, the square is
    its form in one iteration, residual at round-off."""
    model = Model(rectangle(1.0, 0.6, 7, 5), sheet())
    model.fix("x == 0 or x == 1 or y == 0 or y == 0.6")
    form = find_form(model)
    assert form.iterations == 1
    assert np.abs(form.nodes - model.mesh.nodes).max() < 1e-13
    assert form_residual(model, form.nodes)[0] < 1e-12


def sail(n: int) -> Model:
    """A four-point sail: a 10 m square, corners (10, 0) and (0, 10) raised 3 m, edge
    cables of 20 kN, prestress 2 kN/m."""
    model = Model(
        rectangle(10.0, 10.0, n, n),
        Prestressed(StVenantKirchhoff.isotropic(E=6e8, nu=0.3, thickness=1e-3), 2000.0),
    )
    for selector in ("y == 0", "y == 10", "x == 0", "x == 10"):
        model.add_cables(selector, EA=1e7, prestress=2e4, label=selector)
    model.fix("x == 0 and y == 0 or x == 10 and y == 10")
    model.prescribe("x == 10 and y == 0 or x == 0 and y == 10", [0.0, 0.0, 3.0])
    return model


def test_sail_iterations_do_not_grow_with_the_mesh():
    """The outer iterations are the same on 512 and 8,192 elements, and the centre's height,
    1.5 m by the sail's symmetry (a saddle through the corners' mid-height), converges."""
    counts, centres = [], []
    for n in (16, 64):
        form = find_form(sail(n))
        counts.append(form.iterations)
        centre = np.argmin(np.linalg.norm(form.mesh.nodes[:, :2] - [5.0, 5.0], axis=1))
        centres.append(form.nodes[centre, 2])
    assert counts[0] == counts[1] and counts[0] < 30
    assert abs(centres[1] - 1.5) < abs(centres[0] - 1.5) < 1e-2


def test_node_matrix_sums_element_and_pair_entries():
    """``SparsityPattern.node_matrix`` against a COO sum of the same entries."""
    model = Model(rectangle(1.0, 1.0, 3, 2), sheet())
    pattern = model.pattern()
    rng = np.random.default_rng(1)
    triangles = model.mesh.triangles
    element = rng.standard_normal((len(triangles), 3, 3))
    pairs = np.array([[0, 1], [1, 0], [4, 4]])
    values = rng.standard_normal(3)
    got = pattern.node_matrix(element, pairs, values).toarray()
    rows = np.repeat(triangles, 3, axis=1).ravel()
    cols = np.tile(triangles, (1, 3)).ravel()
    n = model.mesh.n_nodes
    want = sp.coo_matrix((element.ravel(), (rows, cols)), shape=(n, n)).toarray()
    want += sp.coo_matrix((values, (pairs[:, 0], pairs[:, 1])), shape=(n, n)).toarray()
    np.testing.assert_allclose(got, want, rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda m: None, "neither held nor on a cable"),
        (
            lambda m: m.add_cables("y == 0", EA=1.0) or m.add_cables("y == 1", EA=1.0),
            "needs a prestress force on every cable",
        ),
    ],
)
def test_a_model_without_a_form_is_refused(change, message):
    model = Model(rectangle(1.0, 1.0, 4, 4), sheet())
    model.fix("x == 0 or x == 1")
    change(model)
    with pytest.raises(ValueError, match=message):
        find_form(model)


def test_a_cable_too_weak_for_its_span_is_said_in_one_line():
    """T / n = 0.2 m is less than half the 1 m chord: no arc spans it, the shape
    collapses, and the error says so (with the last shape)."""
    model = Model(rectangle(1.0, 1.0, 8, 8), sheet())
    model.fix("x == 0 or x == 1")
    model.add_cables("y == 0", EA=1e4, prestress=20.0)
    model.add_cables("y == 1", EA=1e4, prestress=20.0)
    with pytest.raises(FormFindingError, match="no form exists") as failure:
        find_form(model)
    assert failure.value.form.iterations >= 1


def test_form_finding_needs_a_prestress_and_supports():
    plain = Model(rectangle(1.0, 1.0, 4, 4), sheet().material)
    plain.fix("x == 0 or x == 1 or y == 0 or y == 1")
    with pytest.raises(ValueError, match="positive definite prestress on every element"):
        find_form(plain)
    loose = Model(rectangle(1.0, 1.0, 4, 4), sheet())
    with pytest.raises(ValueError, match="form finding needs supports"):
        find_form(loose)
