"""The problem benchmarks/vs_kratos.py hands to Kratos (no Kratos needed): the airbag of
examples/airbag.toml as wrinkle builds it, checked against the case file and the geometry of
its quarter model. The script had stopped working unnoticed when ``read_case`` began to
return a ``Case``; this runs its wrinkle side."""

import sys
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def test_the_airbag_written_for_kratos_is_the_case_on_its_mesh(tmp_path):
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from vs_kratos import write_problem

    n = 4
    problem = np.load(write_problem(n, tmp_path))
    case = tomllib.loads((ROOT / "examples" / "airbag.toml").read_text())
    nodes, triangles, held = problem["nodes"], problem["triangles"], problem["held"]
    assert nodes.shape == ((n + 1) ** 2, 3) and triangles.shape == (2 * n * n, 3)
    side = case["mesh"]["rectangle"]["width"]
    assert np.isclose(nodes[:, 0].max() - nodes[:, 0].min(), side)
    # the quarter model: x held on x = 0, y on y = 0, z on the seams x = side or y = side
    x, y = nodes[:, 0] - nodes[:, 0].min(), nodes[:, 1] - nodes[:, 1].min()
    np.testing.assert_array_equal(held[:, 0], np.isclose(x, 0.0))
    np.testing.assert_array_equal(held[:, 1], np.isclose(y, 0.0))
    np.testing.assert_array_equal(held[:, 2], np.isclose(x, side) | np.isclose(y, side))
    centre = int(np.ravel(problem["centre"])[0])
    assert np.isclose(x[centre], 0.0) and np.isclose(y[centre], 0.0)
    material, (load,) = case["material"], case["load"]
    assert problem["young_modulus"] == material["E"]
    assert problem["poisson_ratio"] == material["nu"]
    assert problem["thickness"] == material["thickness"]
    assert problem["pressure"] == load["value"]
    assert problem["tolerance"] == case["solver"]["tolerance"]
