"""Case files read into a Case (wrinkle.case): the [solver] table becomes SolverSettings,
bad values get one line naming the file, table and key, and the Case solves and runs with
its probes and units."""

import json

import numpy as np
import pytest

import wrinkle
from wrinkle.case import CaseError, read_case
from wrinkle.solvers import SolverSettings

# inline tables and arrays of them: the same case as [material], [[support]] tables
CASE = """
title = "pulled sheet"
material = {model = "svk", E = 1000.0, nu = 0.3, thickness = 0.01}
support = [
    {nodes = "y == 0", fix = ["x", "y", "z"]},
    {label = "top", nodes = "y == 1", displacement = [0.05, 0.02, 0.0]},
]
probe = [{name = "corner", nodes = "x == 1 and y == 1"}]

[mesh]
rectangle = {width = 1.0, height = 1.0, nx = 2, ny = 2}
units = {length = "m", force = "N"}
"""


def write(tmp_path, text):
    path = tmp_path / "case.toml"
    path.write_text(text)
    return path


def test_solver_table_becomes_settings(tmp_path):
    path = write(
        tmp_path,
        CASE
        + """
[solver]
steps = 4
min_step = 0.01
max_step = 0.5
cutback = 0.25
growth = 1.5
target_iterations = 3
regrow_after = 3
tolerance = 1e-9
""",
    )
    case = read_case(path)
    assert case.settings == SolverSettings(
        steps=4,
        min_step=0.01,
        max_step=0.5,
        cutback=0.25,
        growth=1.5,
        target_iterations=3,
        regrow_after=3,
        tolerance=1e-9,
    )
    assert case.settings.controller().regrow_after == 3
    assert case.title == "pulled sheet" and case.source == path
    assert case.units == {"length": "m", "force": "N"}


@pytest.mark.parametrize(
    "line, fragment",
    [
        ("cutback = 1.5", "[solver]: solver cutback must be a number in (0, 1), got 1.5"),
        ("growth = 0.5", "[solver]: solver growth must be a number >= 1, got 0.5"),
        ("max_step = 2.0", "[solver]: solver max_step must be a number in [min_step, 1]"),
        ("target_iterations = 2.5", "[solver]: 'target_iterations' must be an integer"),
        ("regrow_after = 1.5", "[solver]: 'regrow_after' must be an integer"),
        ("cutback = -1", "[solver]: 'cutback' must be > 0"),
        ("steps = 0", "[solver]: 'steps' must be >= 1"),
        ("step = 3", "[solver]: unknown key 'step'"),
        ("look_ahead = 1", "[solver]: 'look_ahead' must be true or false, got 1"),
    ],
)
def test_bad_solver_keys(tmp_path, line, fragment):
    path = write(tmp_path, CASE + f"\n[solver]\n{line}\n")
    with pytest.raises(CaseError) as caught:
        read_case(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: ") and fragment in message, message


def test_disk_rejects_inner_radius(tmp_path):
    """A disk has no hole: the key that was silently dropped is refused, naming annulus."""
    disk = (
        CASE.replace(
            "rectangle = {width = 1.0, height = 1.0, nx = 2, ny = 2}",
            "disk = {outer_radius = 1.0, inner_radius = 0.5, n_radial = 3, n_circumferential = 12}",
        )
        .replace('"y == 0"', '"r == 1"')
        .replace('"y == 1"', '"x == 0 and y == 0"')
        .replace('"x == 1 and y == 1"', '"x == 0 and y == 0"')
    )
    with pytest.raises(CaseError, match=r"\[mesh\] disk: a disk has no 'inner_radius'.*annulus"):
        read_case(write(tmp_path, disk))
    nodes = read_case(write(tmp_path, disk.replace("inner_radius = 0.5, ", ""))).model.mesh.nodes
    assert np.min(np.hypot(nodes[:, 0], nodes[:, 1])) == 0.0  # a disk: a node at the centre


def test_overrides_merge_over_the_file(tmp_path):
    path = write(tmp_path, CASE + "\n[solver]\nsteps = 2\n")
    case = read_case(path, overrides={"mesh": {"rectangle": {"nx": 4}}, "solver": {"steps": 3}})
    assert case.model.mesh.n_elements == 2 * 4 * 2
    assert case.settings.steps == 3
    assert case.model.mesh.nodes[:, 1].max() == 1.0  # the file's other keys stay


def test_case_solve_and_run(tmp_path):
    """Case.solve gives Results carrying the probes and units; Case.run writes the same steps
    as they converge; options override the [solver] table."""
    case = read_case(write(tmp_path, CASE + "\n[solver]\nsteps = 2\n"))
    results = case.solve(tolerance=1e-12)
    assert [s.load_factor for s in results.steps] == [0.5, 1.0]
    assert list(results.probes) == ["corner"] and results.units == case.units
    run = case.run(tmp_path / "out", steps=1, tolerance=1e-12)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["converged"] and len(summary["steps"]) == 1 == len(run.steps)
    assert summary["units"] == {"length": "m", "force": "N"}
    np.testing.assert_allclose(run.final.displacement, results.final.displacement, atol=1e-8)
    results.save(tmp_path / "saved")
    header = (tmp_path / "saved" / "history.csv").read_text().splitlines()[0]
    assert header.endswith("corner_ux,corner_uy,corner_uz")


def test_failed_case_solve_keeps_the_labelled_steps(tmp_path):
    case = read_case(
        write(
            tmp_path,
            CASE.replace("[0.05, 0.02, 0.0]", "[0.3, 0.01, 0.0]")
            + "\n[solver]\nsteps = 4\nmax_iterations = 3\nmin_step = 0.2\n",
        )
    )
    with pytest.raises(wrinkle.ConvergenceError) as caught:
        case.solve()
    assert caught.value.results.probes is case.probes
    steps = caught.value.results.steps
    assert caught.value.reached == (steps[-1].load_factor if steps else 0.0)


RUBBER = {
    "mooney-rivlin": '{model = "mooney-rivlin", C10 = 150.0, C01 = 20.0, thickness = 0.01}',
    "ogden": '{model = "ogden", mu = [300, -40.0], alpha = [2.0, -2], thickness = 0.01}',
}


def test_rubber_models_read_and_solve_alike(tmp_path):
    """[material] model = "mooney-rivlin" and "ogden" give MooneyRivlin and Ogden with the
    file's parameters (integers taken as numbers); Ogden alpha = (2, -2) is Mooney-Rivlin with
    C10 = mu1/2, C01 = -mu2/2, so the two cases solve to the same displacements."""
    finals = {}
    for name, table in RUBBER.items():
        text = CASE.replace('{model = "svk", E = 1000.0, nu = 0.3, thickness = 0.01}', table)
        case = read_case(write(tmp_path, text))
        (material,) = [m.material for m in case.model.materials]
        finals[name] = case.solve(steps=2, tolerance=1e-12).final.displacement
        if name == "ogden":
            assert isinstance(material, wrinkle.Ogden)
            assert material.mu == (300.0, -40.0) and material.alpha == (2.0, -2.0)
        else:
            assert isinstance(material, wrinkle.MooneyRivlin)
            assert (material.C10, material.C01, material.thickness) == (150.0, 20.0, 0.01)
    np.testing.assert_allclose(finals["ogden"], finals["mooney-rivlin"], rtol=1e-9, atol=1e-12)
