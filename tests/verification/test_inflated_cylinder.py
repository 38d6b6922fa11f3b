"""The closed-tube mesh generator and Comer & Levy's moment-curvature relation of an inflated
membrane tube (verification.references.inflated_cylinder), each against an independent
reference: the divergence theorem and edge counts for the mesh, numerical integration of the
tension-field stress over the section for the relation."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from verification.references.inflated_cylinder import InflatedTube, moment_ratio, taut_half_angle
from wrinkle.case import read_case
from wrinkle.loads import pressure_volume
from wrinkle.mesh import boundary_nodes, cylinder

CASE = Path(__file__).resolve().parents[2] / "verification" / "cases" / "inflated_cylinder.toml"

# a tube R = 0.1 m, E t = 1e5 N/m, inflated to 100 Pa (p R / (E t) = 1e-4)
R, P_INFLATION, ET, NU = 0.1, 100.0, 1.0e5, 0.3


# -- the closed tube ----------------------------------------------------------------------------


def triangle_vectors(mesh) -> tuple[np.ndarray, np.ndarray]:
    """(X2 - X1) x (X3 - X1) (twice the area along the normal) and centroids, (n, 3) each."""
    X = mesh.nodes[mesh.triangles]
    return np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]), X.mean(axis=1)


@pytest.mark.parametrize("n, n_axial, n_cap", [(3, 1, 1), (8, 5, 2), (17, 9, 4)])
def test_cylinder_is_a_closed_surface_facing_outwards(n, n_axial, n_cap):
    radius, length = 0.3, 1.7
    mesh = cylinder(radius, length, n, n_axial, n_cap)
    caps = n + 2 * n * (n_cap - 1)  # fan + rings, triangles per cap
    assert mesh.n_elements == 2 * n * n_axial + 2 * caps
    assert mesh.n_nodes == (n_axial + 1) * n + 2 * (1 + (n_cap - 1) * n)
    # closed and consistently oriented: each undirected edge in exactly two triangles, each
    # directed edge in exactly one (neighbours run along a shared edge in opposite directions)
    directed = mesh.triangles[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2)
    _, counts = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    assert np.all(counts == 2)
    assert np.unique(directed, axis=0).shape[0] == directed.shape[0]
    # outward normals: away from the axis on the wall, -x at the root, +x at the tip
    normal, centre = triangle_vectors(mesh)
    wall = mesh.element_sets["wall"]
    assert np.all(np.einsum("ij,ij->i", normal[wall, 1:], centre[wall, 1:]) > 0.0)
    assert np.all(normal[mesh.element_sets["root_cap"], 0] < 0.0)
    assert np.all(normal[mesh.element_sets["tip_cap"], 0] > 0.0)
    assert np.allclose(normal[mesh.element_sets["root_cap"], 1:], 0.0)
    sets = np.concatenate([mesh.element_sets[k] for k in ("wall", "root_cap", "tip_cap")])
    assert np.array_equal(np.sort(sets), np.arange(mesh.n_elements))
    # the enclosed volume by the divergence theorem, V = sum X1.(X2 x X3) / 6: exactly the
    # prism on the inscribed n-gon
    polygon = 0.5 * n * math.sin(2.0 * math.pi / n) * radius**2
    assert pressure_volume(mesh.nodes[mesh.triangles]).sum() == pytest.approx(
        polygon * length, rel=1e-12
    )


def test_cylinder_volume_tends_to_the_tube_at_second_order():
    radius, length = 0.1, 0.5
    errors = []
    for n in (16, 32, 64):
        mesh = cylinder(radius, length, n, 4, 3)
        volume = pressure_volume(mesh.nodes[mesh.triangles]).sum()
        errors.append(abs(volume / (math.pi * radius**2 * length) - 1.0))
    # (1 - sin(2 pi/n) n / (2 pi)) ~ (2 pi / n)^2 / 6: halving h quarters the error
    assert errors[0] == pytest.approx((2 * math.pi / 16) ** 2 / 6, rel=0.02)
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.02)
    assert errors[1] / errors[2] == pytest.approx(4.0, rel=0.01)


def test_cylinder_numbering_and_node_sets():
    radius, length, n, n_axial, n_cap = 0.2, 1.0, 6, 4, 3
    mesh = cylinder(radius, length, n, n_axial, n_cap)
    i, j = np.divmod(np.arange((n_axial + 1) * n), n)
    angle = 2.0 * np.pi * j / n
    expected = np.column_stack(
        [length * i / n_axial, radius * np.cos(angle), radius * np.sin(angle)]
    )
    assert np.allclose(mesh.nodes[: (n_axial + 1) * n], expected, atol=1e-15)
    assert np.allclose(mesh.nodes[mesh.node_sets["root"], 0], 0.0)
    assert np.allclose(mesh.nodes[mesh.node_sets["tip"], 0], length)
    for name, x in (("root_cap", 0.0), ("tip_cap", length)):
        nodes = mesh.nodes[mesh.node_sets[name]]
        assert mesh.node_sets[name].size == 1 + n_cap * n
        assert np.allclose(nodes[:, 0], x)
        radii = np.sort(np.unique(np.round(np.hypot(nodes[:, 1], nodes[:, 2]) / radius, 12)))
        assert np.allclose(radii, np.arange(n_cap + 1) / n_cap)
    # the wall's panel (i, j) is split into triangles i n + j and (n_axial + i) n + j
    panel = np.sort(
        np.concatenate([mesh.triangles[1 * n + 2], mesh.triangles[(n_axial + 1) * n + 2]])
    )
    assert set(panel) == {1 * n + 2, 1 * n + 3, 2 * n + 2, 2 * n + 3}


@pytest.mark.parametrize(
    "args, message",
    [
        ((0.0, 1.0, 8, 2, 2), "radius must be a finite number > 0"),
        ((1.0, -1.0, 8, 2, 2), "length must be a finite number > 0"),
        ((1.0, 1.0, 2, 2, 2), "n_circumferential must be an integer >= 3"),
        ((1.0, 1.0, 8, 0, 2), "n_axial must be an integer >= 1"),
        ((1.0, 1.0, 8, 2, 1.5), "n_cap must be an integer >= 0"),
        ((1.0, 1.0, 8, 2, -1), "n_cap must be an integer >= 0"),
    ],
)
def test_cylinder_rejects_bad_input(args, message):
    with pytest.raises(ValueError, match=message):
        cylinder(*args)


def test_open_cylinder_is_the_wall_alone_with_two_free_end_circles():
    """n_cap = 0: the tube without its caps; every edge but those of the two end circles is
    shared by two triangles, and the boundary is the root and tip circles."""
    tube = cylinder(1.0, 2.0, 12, 4, 0)
    assert tube.n_nodes == 12 * 5 and tube.n_elements == 2 * 12 * 4
    assert set(tube.node_sets) == {"root", "tip"} and set(tube.element_sets) == {"wall"}
    np.testing.assert_array_equal(
        np.flatnonzero(boundary_nodes(tube)),
        np.concatenate([tube.node_sets["root"], tube.node_sets["tip"]]),
    )
    np.testing.assert_allclose(np.hypot(tube.nodes[:, 1], tube.nodes[:, 2]), 1.0)


def test_case_file_reads_the_cylinder_generator():
    divisions = {"n_circumferential": 8, "n_axial": 6, "n_cap": 2}
    model = read_case(CASE, overrides={"mesh": {"cylinder": divisions}}).model
    assert model.mesh.n_elements == 2 * 8 * 6 + 2 * (8 + 2 * 8)
    assert {"root plate", "tip plate"} <= {s.label for s in model.supports}


# -- Comer & Levy's relation --------------------------------------------------------------------


@pytest.fixture(scope="module")
def tube() -> InflatedTube:
    return InflatedTube(R, P_INFLATION, ET, NU)


def section_by_quadrature(tube: InflatedTube, curvature: float) -> tuple[float, float]:
    """Moment M and axis strain eps_0 of a section bent to ``curvature`` whose wall carries
    the tension-field axial stress N(theta) = max(0, E t (eps_0 + kappa R cos theta)),
    eps_0 such that the integral of N R d(theta) is the axial force P: 40-point
    Gauss-Legendre quadrature on the arc where the bracket is positive (its end found from
    eps_0, where the integrand has its kink), eps_0 by root finding. Independent of the
    closed forms."""
    nodes, weights = np.polynomial.legendre.leggauss(40)

    def integrals(eps0: float) -> tuple[float, float]:
        ratio = -eps0 / (curvature * R)
        end = math.pi if ratio <= -1.0 else math.acos(min(ratio, 1.0))  # N > 0 on |theta| < end
        theta = 0.5 * end * (nodes + 1.0)
        stress = np.maximum(0.0, ET * (eps0 + curvature * R * np.cos(theta)))
        force = 2.0 * 0.5 * end * np.sum(weights * stress * R)
        moment = 2.0 * 0.5 * end * np.sum(weights * stress * R**2 * np.cos(theta))
        return force, moment

    eps0 = brentq(
        lambda e: integrals(e)[0] - tube.axial_force,
        -curvature * R,
        tube.axial_force / (2 * math.pi * R * ET),
        xtol=1e-20,
        rtol=1e-15,
    )
    return integrals(eps0)[1], eps0


@pytest.mark.parametrize("ratio", [0.51, 0.6, 0.75, 0.9, 0.97])
def test_moment_curvature_against_quadrature_of_the_section(tube, ratio):
    moment = ratio * tube.collapse_moment
    curvature = float(tube.curvature(moment))
    integrated, eps0 = section_by_quadrature(tube, curvature)
    assert integrated == pytest.approx(moment, rel=1e-10)
    assert float(tube.moment_of_curvature(curvature)) == pytest.approx(moment, rel=1e-12)
    # the wall is taut where eps_0 + kappa R cos(theta) > 0: |theta| < alpha
    alpha = float(tube.taut_half_angle(moment))
    assert math.cos(alpha) == pytest.approx(-eps0 / (curvature * R), rel=1e-9)
    # the closed-form stress vanishes beyond alpha and integrates to the axial force and the
    # moment (Gauss-Legendre on the taut arc, where it is smooth)
    theta = np.linspace(0.0, math.pi, 2001)
    stress = tube.axial_stress(theta, moment)
    assert np.all(stress[theta > alpha] == 0.0) and np.all(stress[theta < alpha] > 0.0)
    nodes, weights = np.polynomial.legendre.leggauss(40)
    arc = 0.5 * alpha * (nodes + 1.0)
    on_arc = tube.axial_stress(arc, moment)
    force = 2 * 0.5 * alpha * np.sum(weights * on_arc * R)
    bending = 2 * 0.5 * alpha * np.sum(weights * on_arc * R**2 * np.cos(arc))
    assert force == pytest.approx(tube.axial_force, rel=1e-11)
    assert bending == pytest.approx(moment, rel=1e-11)


def test_taut_tube_is_a_linear_beam(tube):
    moments = np.array([0.0, 0.1, 0.3, 0.5]) * tube.collapse_moment
    assert np.array_equal(tube.taut_half_angle(moments), np.full(4, np.pi))
    assert np.allclose(
        tube.curvature(moments), moments / (ET * math.pi * R**3), rtol=1e-15, atol=0.0
    )
    assert tube.wrinkling_moment == pytest.approx(math.pi * P_INFLATION * R**3 / 2, rel=1e-15)
    # N_x = p R / 2 + M cos(theta) / (pi R^2), zero at theta = pi when M = M_w
    stress = tube.axial_stress([0.0, math.pi], tube.wrinkling_moment)
    assert stress == pytest.approx([P_INFLATION * R, 0.0], abs=1e-12)
    # integrating over the section gives back P and M
    moment = 0.3 * tube.collapse_moment
    force = quad(lambda t: tube.axial_stress(t, moment) * R, -math.pi, math.pi)[0]
    bending = quad(lambda t: tube.axial_stress(t, moment) * R**2 * math.cos(t), -math.pi, math.pi)[
        0
    ]
    assert force == pytest.approx(P_INFLATION * math.pi * R**2, rel=1e-12)
    assert bending == pytest.approx(moment, rel=1e-12)


def test_relation_is_continuous_at_the_wrinkling_moment(tube):
    below, above = tube.wrinkling_moment * (1 - 1e-9), tube.wrinkling_moment * (1 + 1e-9)
    linear = tube.wrinkling_moment / (ET * math.pi * R**3)  # = p / (2 E t)
    assert linear == pytest.approx(P_INFLATION / (2 * ET), rel=1e-15)
    assert float(tube.curvature(below)) == pytest.approx(linear, rel=2e-9)
    assert float(tube.curvature(above)) == pytest.approx(linear, rel=1e-7)
    assert float(tube.taut_half_angle(above)) == pytest.approx(math.pi, abs=1e-3)
    assert moment_ratio(math.pi) == pytest.approx(0.5, rel=1e-15)
    # beyond M_w the tube is softer than the taut beam, and ever more so
    moments = np.linspace(0.5, 0.99, 50) * tube.collapse_moment
    secant = moments / tube.curvature(moments)
    assert np.all(np.diff(secant) < 0.0)
    assert np.all(np.diff(tube.curvature(moments)) > 0.0)


def test_collapse_limit(tube):
    # g / (2 f) = (1 - alpha^2/5 + ...) / (1 - alpha^2/10 + ...) = 1 - alpha^2/10 + O(alpha^4)
    for alpha in (1e-1, 1e-2, 1e-3):
        assert 1.0 - moment_ratio(alpha) == pytest.approx(alpha**2 / 10, rel=2 * alpha**2)
    # kappa E t R^2 / P -> 3 / (2 alpha^3) as the taut arc closes
    for ratio in (0.99, 0.999, 0.99999):
        alpha = float(taut_half_angle(ratio))
        moment = ratio * tube.collapse_moment
        asymptote = 3.0 * tube.axial_force / (2.0 * ET * R**2 * alpha**3)
        assert float(tube.curvature(moment)) == pytest.approx(asymptote, rel=0.2 * alpha**2)
    assert tube.collapse_moment == pytest.approx(math.pi * P_INFLATION * R**3, rel=1e-15)
    with pytest.raises(ValueError, match="collapse moment"):
        tube.curvature(tube.collapse_moment)


def test_taut_angle_solves_equation_3_to_round_off():
    ratios = np.linspace(0.5, 0.999, 200)
    alpha = taut_half_angle(ratios)
    assert np.max(np.abs(moment_ratio(alpha) - ratios)) < 1e-13
    assert np.all(np.diff(alpha) < 0.0)
    # series and closed form agree where they hand over (alpha = 0.1)
    edge = np.array([0.1 - 1e-12, 0.1 + 1e-12])
    assert moment_ratio(edge)[0] == pytest.approx(moment_ratio(edge)[1], rel=1e-12)
    with pytest.raises(ValueError, match=r"\[1/2, 1\)"):
        taut_half_angle(1.0)


def test_axis_strain_follows_the_taut_law(tube):
    """On the taut arc, N_x = E t (eps_axis + kappa R cos(theta)) + nu p R (hoop stress p R)."""
    theta = np.linspace(-0.5, 0.5, 7)
    for ratio in (0.3, 0.7, 0.9):
        moment = ratio * tube.collapse_moment
        strain = float(tube.axis_strain(moment)) + float(tube.curvature(moment)) * R * np.cos(theta)
        assert ET * strain + NU * P_INFLATION * R == pytest.approx(
            tube.axial_stress(theta, moment), rel=1e-12
        )


def test_end_force_scales_the_relation():
    """A tube whose wall carries the axial force 2 P behaves like one inflated to 2 p, apart
    from the hoop stress, which only enters the axis strain."""
    pulled = InflatedTube(R, P_INFLATION, ET, NU, end_force=math.pi * P_INFLATION * R**2)
    doubled = InflatedTube(R, 2 * P_INFLATION, ET, NU)
    assert pulled.collapse_moment == pytest.approx(doubled.collapse_moment, rel=1e-15)
    moments = np.array([0.2, 0.6, 0.9]) * pulled.collapse_moment
    assert np.allclose(pulled.curvature(moments), doubled.curvature(moments), rtol=1e-14)
