"""Node selectors and position-dependent expressions against brute-force NumPy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wrinkle.mesh import Mesh, annulus, mesh_size, rectangle
from wrinkle.selectors import evaluate_expression, select_nodes

# a tilted sheet: z = 0.1 x, so that z conditions select something
SHEET = rectangle(2.0, 1.0, 8, 4)
SHEET.nodes[:, 2] = 0.1 * SHEET.nodes[:, 0]
RING = annulus(0.5, 1.5, 4, 24)
TOL = 1e-9


def coordinates(mesh):
    x, y, z = mesh.nodes.T
    return x, y, z, np.hypot(x, y), np.arctan2(y, x)


def close(a, b):
    return np.abs(a - b) <= TOL


# selector, mesh, brute-force mask from (x, y, z, r, theta)
CASES = [
    ("x == 0", SHEET, lambda x, y, z, r, t: close(x, 0)),
    ("x==2", SHEET, lambda x, y, z, r, t: close(x, 2)),
    ("y >= 0.5 and z == 0", SHEET, lambda x, y, z, r, t: (y >= 0.5 - TOL) & close(z, 0)),
    ("x < 1 or y > 0.5", SHEET, lambda x, y, z, r, t: (x < 1 - TOL) | (y > 0.5 + TOL)),
    ("not x <= 1.5", SHEET, lambda x, y, z, r, t: ~(x <= 1.5 + TOL)),
    ("x != 1", SHEET, lambda x, y, z, r, t: ~close(x, 1)),
    ("0.5 <= x <= 1", SHEET, lambda x, y, z, r, t: (x >= 0.5 - TOL) & (x <= 1 + TOL)),
    ("x + 2 * y == 2", SHEET, lambda x, y, z, r, t: close(x + 2 * y, 2)),
    ("x - y - 1 == 0", SHEET, lambda x, y, z, r, t: close(x - y - 1, 0)),
    ("-x >= -0.5", SHEET, lambda x, y, z, r, t: -x >= -0.5 - TOL),
    ("x ** 2 + y ** 2 <= 1", SHEET, lambda x, y, z, r, t: x**2 + y**2 <= 1 + TOL),
    ("x / 2 == y", SHEET, lambda x, y, z, r, t: close(x / 2, y)),
    ("2 ** -1 == x", SHEET, lambda x, y, z, r, t: close(x, 0.5)),
    ("-2 ** 2 == -4 and x == 0", SHEET, lambda x, y, z, r, t: close(x, 0)),  # as in Python
    (
        "(x == 0 or x == 2) and not (y == 0)",
        SHEET,
        lambda x, y, z, r, t: (close(x, 0) | close(x, 2)) & ~close(y, 0),
    ),
    ("z == 0.1 * x and x > 1", SHEET, lambda x, y, z, r, t: x > 1 + TOL),
    ("abs(x - 1) <= 0.25", SHEET, lambda x, y, z, r, t: np.abs(x - 1) <= 0.25 + TOL),
    ("sqrt(x) >= 1", SHEET, lambda x, y, z, r, t: np.sqrt(x) >= 1 - TOL),
    ("hypot(x, y) <= 1", SHEET, lambda x, y, z, r, t: np.hypot(x, y) <= 1 + TOL),
    ("1.0e0 == y or .25 == y", SHEET, lambda x, y, z, r, t: close(y, 1) | close(y, 0.25)),
    ("(y == 1) * 3 + x == 3", SHEET, lambda x, y, z, r, t: close(close(y, 1) * 3 + x, 3)),
    ("r == 0.5", RING, lambda x, y, z, r, t: close(r, 0.5)),
    ("r >= 1.25", RING, lambda x, y, z, r, t: r >= 1.25 - TOL),
    ("theta == pi / 2", RING, lambda x, y, z, r, t: close(t, np.pi / 2)),
    (
        "0 <= theta <= pi/4 and r == 1.5",
        RING,
        lambda x, y, z, r, t: (t >= -TOL) & (t <= np.pi / 4 + TOL) & close(r, 1.5),
    ),
    ("atan2(y, x) == theta", RING, lambda x, y, z, r, t: np.ones_like(x, dtype=bool)),
    (
        "sin(theta) * r == y and cos(theta) * r == x",
        RING,
        lambda x, y, z, r, t: np.ones_like(x, dtype=bool),
    ),
    ("tan(theta) >= 1 and x > 0", RING, lambda x, y, z, r, t: (np.tan(t) >= 1 - TOL) & (x > TOL)),
]


@pytest.mark.parametrize("selector, mesh, mask", CASES, ids=[c[0] for c in CASES])
def test_selector_matches_brute_force(selector, mesh, mask):
    expected = np.flatnonzero(mask(*coordinates(mesh)))
    assert expected.size > 0
    selected = select_nodes(mesh, selector, tolerance=TOL)
    assert selected.dtype == np.int64
    assert np.array_equal(selected, expected)


def test_node_set_names():
    assert np.array_equal(select_nodes(SHEET, "top"), SHEET.node_sets["top"])
    assert np.array_equal(select_nodes(RING, " outer "), RING.node_sets["outer"])
    # an exact node-set name wins over the coordinate of the same name; sets come out sorted
    mesh = Mesh(SHEET.nodes, SHEET.triangles, {"x": [7, 3, 3], "a b-c": [1]})
    assert select_nodes(mesh, "x").tolist() == [3, 7]
    assert select_nodes(mesh, "a b-c").tolist() == [1]


def test_tolerance_relative_to_mesh_size():
    """Default tolerance 1e-3 mesh_size: nodes nudged by half of it are caught, by twice not."""
    mesh = rectangle(1.0, 1.0, 4, 4)
    tol = 1e-3 * mesh_size(mesh)
    mesh.nodes[[1, 2, 3], 0] += [0.5 * tol, -0.5 * tol, 2 * tol]  # x = .25, .5, .75 nominally
    assert select_nodes(mesh, "x == 0.25 and y == 0").tolist() == [1]
    assert select_nodes(mesh, "x == 0.5 and y == 0").tolist() == [2]
    with pytest.raises(ValueError, match="matches no node"):
        select_nodes(mesh, "x == 0.75 and y == 0")
    assert select_nodes(mesh, "x == 0.75 and y == 0", tolerance=3 * tol).tolist() == [3]
    # inequalities: non-strict ones include the band, strict ones exclude it
    bottom = mesh.node_sets["bottom"]
    ge = np.intersect1d(select_nodes(mesh, "x >= 0.5"), bottom)
    gt = np.intersect1d(select_nodes(mesh, "x > 0.5"), bottom)
    le = np.intersect1d(select_nodes(mesh, "x <= 0.25"), bottom)
    lt = np.intersect1d(select_nodes(mesh, "x < 0.25"), bottom)
    assert ge.tolist() == [2, 3, 4] and gt.tolist() == [3, 4]
    assert le.tolist() == [0, 1] and lt.tolist() == [0]
    # with zero tolerance the comparisons are exact
    assert np.intersect1d(select_nodes(mesh, "x >= 0.5", tolerance=0.0), bottom).tolist() == [3, 4]


@pytest.mark.parametrize(
    "selector, message",
    [
        ("x === 0", r'selector "x === 0": unexpected \'=\' at column 5$'),
        ("x = 0", r"unexpected '=' at column 3 \(compare with '=='\)"),
        ("x == 0 & y == 0", r"unexpected '&' at column 8"),
        ("x ==", r"unexpected end at column 5 \(expected a number, a name or '\('\)"),
        ("(x == 0", r"unexpected end at column 8 \(expected '\)' to close '\(' at column 1\)"),
        ("x == 0)", r"unexpected '\)' at column 7 \(expected an operator\)"),
        ("2x == 1", r"unexpected 'x' at column 2"),
        ("x == 0 and", r"unexpected end at column 11"),
        ("and x == 0", r"unexpected 'and' at column 1"),
        ("", r'selector "": empty'),
        ("   ", r'selector "   ": empty'),
        (
            "foo == 1",
            (
                r"unknown name 'foo' at column 1 \(allowed names: x, y, z, r, theta, pi, "
                r"sqrt, abs, sin, cos, tan, atan2, hypot; node sets: bottom, top, left, "
                r"right\)"
            ),
        ),
        ("topp", r"unknown name 'topp' at column 1 .*node sets: bottom, top"),
        ("__import__(x) == 0", r"unknown name '__import__' at column 1"),
        ("__import__('os')", r"unexpected \"'\" at column 12"),
        ("x.real == 0", r"unexpected '\.' at column 2"),
        ("sqrt == 1", r"sqrt is a function: write sqrt\(\.\.\.\) at column 1"),
        ("sqrt(x, y) == 1", r"sqrt takes 1 argument, got 2, at column 1"),
        ("2 * atan2(y) == 0", r"atan2 takes 2 arguments, got 1, at column 5"),
        ("hypot(x y) == 0", r"unexpected 'y' at column 9 \(expected ',' or '\)'"),
        ("x and y == 0", r"a number where 'and' needs a condition \(such as x == 0\) at column 1"),
        ("x == 0 or 1", r"a number where 'or' needs a condition .* at column 11"),
        ("not x", r"a number where 'not' needs a condition .* at column 5"),
        ("x + 1", r'selector "x \+ 1" is a number, not a condition'),
        ("x == 5", r'^selector "x == 5" matches no node \(x spans 0 \.\. 2\)$'),
        ("y > 1 and x < 0", r"matches no node \(y spans 0 \.\. 1, x spans 0 \.\. 2\)$"),
        ("1 == 2", r'^selector "1 == 2" matches no node$'),
        (
            "sqrt(x - 1) >= 0",
            (
                r"a comparison meets NaN \(not a number\) at node 0 "
                r"\(x = 0, y = 0, z = 0\)"
            ),
        ),
    ],
)
def test_selector_errors(selector, message):
    with pytest.raises(ValueError, match=message) as error:
        select_nodes(SHEET, selector)
    assert "\n" not in str(error.value)


def test_empty_node_set_and_bad_arguments():
    mesh = Mesh(SHEET.nodes, SHEET.triangles, {"nothing": []})
    with pytest.raises(
        ValueError,
        match=r'selector "nothing" matches no node '
        r'\(node set "nothing" is empty\)',
    ):
        select_nodes(mesh, "nothing")
    with pytest.raises(ValueError, match="node sets: none"):
        select_nodes(Mesh(SHEET.nodes, SHEET.triangles), "left")
    with pytest.raises(ValueError, match="tolerance must be a finite number >= 0"):
        select_nodes(SHEET, "x == 0", tolerance=-1.0)
    with pytest.raises(TypeError, match="selector must be"):
        select_nodes(SHEET, 3)


def test_evaluate_expression_values():
    nodes = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 0.5], [-3.0, 4.0, 1.0]])
    x, y, z = nodes.T
    r, theta = np.hypot(x, y), np.arctan2(y, x)
    cases = {
        "0.1 * y": 0.1 * y,
        "x + y * z - 1": x + y * z - 1,
        "-x ** 2": -(x**2),
        "2 ** 3 ** 2": np.full(3, 512.0),  # right-associative
        "(1 + x) / 2": (1 + x) / 2,
        "r": r,
        "0.01 * sin(theta) + cos(pi)": 0.01 * np.sin(theta) - 1,
        "hypot(x, z) - abs(x)": np.hypot(x, z) - np.abs(x),
        "atan2(y, 1) + tan(z)": np.arctan2(y, 1) + np.tan(z),
        "sqrt(r)": np.sqrt(r),
        "0.5 * (y >= 2)": 0.5 * (y >= 2),  # a condition counts as 1 or 0
        "x > 0": (x > 0).astype(float),
        "1e-3": np.full(3, 1e-3),
    }
    for text, expected in cases.items():
        values = evaluate_expression(text, nodes)
        assert values.shape == (3,) and values.dtype == float, text
        np.testing.assert_allclose(values, expected, rtol=1e-15, atol=1e-15, err_msg=text)
    # numbers instead of text, and planar nodes
    assert evaluate_expression(0.25, nodes).tolist() == [0.25] * 3
    assert evaluate_expression(2, nodes[:, :2]).tolist() == [2.0] * 3
    assert evaluate_expression("z + 1", nodes[:, :2]).tolist() == [1.0] * 3
    assert evaluate_expression("x", np.zeros((0, 3))).shape == (0,)


@pytest.mark.parametrize(
    "text, message",
    [
        ("0.1 * ", r'expression "0.1 \* ": unexpected end at column 7'),
        (
            "y + q",
            (
                r"unknown name 'q' at column 5 \(allowed names: x, y, z, r, theta, pi, sqrt, "
                r"abs, sin, cos, tan, atan2, hypot\)$"
            ),
        ),
        ("1 / x", r'expression "1 / x" is inf at \(x = 0, y = 0, z = 0\)'),
        ("sqrt(x - 2)", r"is nan at \(x = 0, y = 0, z = 0\)"),
        (float("nan"), r"expression nan is not finite"),
    ],
)
def test_evaluate_expression_errors(text, message):
    nodes = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 0.5]])
    with pytest.raises(ValueError, match=message):
        evaluate_expression(text, nodes)


def test_evaluate_expression_rejects_bad_input():
    with pytest.raises(TypeError, match="expression must be a number or a text"):
        evaluate_expression(True, np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"nodes must be shaped \(k, 2\) or \(k, 3\)"):
        evaluate_expression("x", np.zeros(3))


def test_many_nodes():
    """Vectorised over the nodes: 9 x 10^4 nodes at once."""
    mesh = rectangle(1.0, 1.0, 299, 299)
    selected = select_nodes(mesh, "x == 0 or (y >= 0.5 and hypot(x, y) <= 1)")
    x, y = mesh.nodes[:, 0], mesh.nodes[:, 1]
    tol = 1e-3 * mesh_size(mesh)
    expected = (np.abs(x) <= tol) | ((y >= 0.5 - tol) & (np.hypot(x, y) <= 1 + tol))
    assert np.array_equal(selected, np.flatnonzero(expected))
    assert math.isclose(evaluate_expression("2 * x", mesh.nodes).sum(), 2 * x.sum())
