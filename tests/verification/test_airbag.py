"""Helpers of the airbag benchmark: Richardson extrapolation against manufactured sequences,
the prolongation of a rectangle-mesh field against an independent linear interpolator, and the
projected area of eq. (3) against plane geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest

from verification.benchmarks.airbag import refine_rectangle_field
from verification.references.airbag import projected_area, richardson
from wrinkle.mesh import rectangle


@pytest.mark.parametrize("order", [0.7, 1.0, 2.0, 3.5])
@pytest.mark.parametrize("sizes", [(0.4, 0.2, 0.1), (1 / 8, 1 / 12, 1 / 16), (0.3, 0.2, 0.05)])
def test_richardson_recovers_a_manufactured_sequence(order, sizes):
    """q(h) = 3.25 - 1.7 h^p is extrapolated to 3.25 with order p, for any mesh ratios."""
    values = [3.25 - 1.7 * h**order for h in sizes]
    result = richardson(sizes, values)
    assert result.order == pytest.approx(order, rel=1e-9)
    assert result.limit == pytest.approx(3.25, rel=1e-12)


def test_richardson_uses_the_last_three_meshes():
    sizes = [0.8, 0.4, 0.2, 0.1]
    values = [99.0] + [2.0 + 0.5 * h**2 for h in sizes[1:]]  # a wild first value is ignored
    result = richardson(sizes, values)
    assert result.limit == pytest.approx(2.0, rel=1e-12)
    assert result.order == pytest.approx(2.0, rel=1e-9)


def test_richardson_with_halving_meshes_is_the_textbook_formula():
    """h, h/2, h/4: p = log2((q1 - q2)/(q2 - q3)), q_inf = q3 - (q2 - q3)/(2^p - 1)."""
    values = [1.0, 1.3, 1.39]
    result = richardson([1.0, 0.5, 0.25], values)
    p = math.log2((values[0] - values[1]) / (values[1] - values[2]))
    assert result.order == pytest.approx(p, rel=1e-10)
    assert result.limit == pytest.approx(
        values[2] + (values[2] - values[1]) / (2**p - 1), rel=1e-12
    )


@pytest.mark.parametrize("values", [(1.0, 2.0, 1.5), (1.0, 1.1, 1.3)])
def test_richardson_refuses_a_sequence_that_is_not_converging(values):
    """Oscillating, or differences growing: no order in (0.05, 20), so NaN, not a number."""
    result = richardson([0.4, 0.2, 0.1], values)
    assert math.isnan(result.limit) and math.isnan(result.order)


def test_richardson_rejects_bad_sizes():
    with pytest.raises(ValueError, match="decreasing"):
        richardson([0.1, 0.2, 0.4], [1.0, 2.0, 3.0])


def test_refined_field_reproduces_a_linear_field_exactly():
    nx, ny = 3, 2
    coarse = rectangle(1.5, 1.0, nx, ny).nodes
    fine = rectangle(1.5, 1.0, 2 * nx, 2 * ny).nodes

    def field(X):
        return np.column_stack([1.0 + 2.0 * X[:, 0] - X[:, 1], 0.5 * X[:, 1], -X[:, 0]])

    refined = refine_rectangle_field(field(coarse), nx, ny)
    np.testing.assert_allclose(refined, field(fine), rtol=0, atol=1e-14)
    flat = refine_rectangle_field(field(coarse).ravel(), nx, ny)
    np.testing.assert_allclose(flat, field(fine).ravel(), rtol=0, atol=1e-14)


def test_refined_field_is_the_interpolant_on_the_coarse_triangles():
    """A random nodal field: the refined values equal an independent piecewise-linear
    interpolation (matplotlib's) on the coarse mesh's own triangles."""
    tri = pytest.importorskip("matplotlib.tri")
    nx, ny = 4, 3
    mesh = rectangle(2.0, 1.0, nx, ny)
    fine = rectangle(2.0, 1.0, 2 * nx, 2 * ny).nodes
    values = np.random.default_rng(7).normal(size=mesh.n_nodes)
    triangulation = tri.Triangulation(mesh.nodes[:, 0], mesh.nodes[:, 1], mesh.triangles)
    expected = tri.LinearTriInterpolator(triangulation, values)(fine[:, 0], fine[:, 1])
    refined = refine_rectangle_field(values[:, None], nx, ny)[:, 0]
    np.testing.assert_allclose(refined, np.asarray(expected), rtol=0, atol=1e-12)


def test_refined_field_rejects_a_wrong_size():
    with pytest.raises(ValueError, match="do not fit"):
        refine_rectangle_field(np.zeros(7), 2, 2)


def test_projected_area_of_a_lifted_and_turned_sheet():
    """A 0.6 x 0.4 sheet lifted onto the plane z = 0.3 x - 0.2 y and turned about z keeps its
    projected area 0.24; mirrored (triangles reversed) it counts negative."""
    mesh = rectangle(0.6, 0.4, 5, 3)
    X = mesh.nodes.copy()
    X[:, 2] = 0.3 * X[:, 0] - 0.2 * X[:, 1]
    angle = 0.7
    turn = np.array(
        [
            [math.cos(angle), -math.sin(angle), 0.0],
            [math.sin(angle), math.cos(angle), 0.0],
            [0.0, 0.0, 1.0],
        ]
    )
    x = X @ turn.T
    assert projected_area(x, mesh.triangles) == pytest.approx(0.24, rel=1e-13)
    assert projected_area(x, mesh.triangles[:, ::-1]) == pytest.approx(-0.24, rel=1e-13)
    # a vertical wall projects to nothing
    wall = np.column_stack([X[:, 0], np.zeros(mesh.n_nodes), X[:, 1]])
    assert projected_area(wall, mesh.triangles) == pytest.approx(0.0, abs=1e-15)
