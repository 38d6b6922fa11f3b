"""Reading results back (``wrinkle.open_results``) and restarting a run (``wrinkle run
--restart``, issue 22, item 5): a run stopped after some steps and restarted reaches the
uninterrupted run's steps and answer; bad folders are one line, exit status 2."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import sheet_case

import wrinkle
from wrinkle.case import read_case
from wrinkle.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

SHEAR = sheet_case(nx=8, top="[0.2, 0.05, 0.0]", steps=20)


def interrupted(case, out: Path, after: int) -> None:
    """Run ``case`` into ``out`` and stop it (Ctrl-C) after ``after`` converged steps."""
    count = [0]

    def stop(step):
        count[0] += 1
        if count[0] == after:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        case.run(out, on_step=stop)


@pytest.fixture
def shear(tmp_path) -> Path:
    path = tmp_path / "shear.toml"
    path.write_text(SHEAR)
    return path


def test_a_restarted_run_has_the_uninterrupted_runs_steps(shear, tmp_path):
    """Stopped after 7 of 20 steps and restarted from the command line (issue 22: the same
    final state to 1e-10): the same load factors, every step's displacements equal to
    round-off (the same increments and predictions), the same work, twenty rows of history
    and twenty step files in the collection."""
    assert main(["run", str(shear), "--out", str(tmp_path / "full"), "--quiet"]) == 0
    interrupted(read_case(shear), tmp_path / "again", after=7)
    stopped = wrinkle.open_results(tmp_path / "again")
    assert len(stopped) == 7 and not stopped.summary["converged"]
    saved = stopped.summary["steps"][-1]["controller"]  # what the restart goes on from
    assert saved == {"increment": pytest.approx(0.05), "in_a_row": 7, "needed": 2, "regrown": False}
    assert main(["run", str(shear), "--out", str(tmp_path / "again"), "--restart", "-q"]) == 0
    full, again = (wrinkle.open_results(tmp_path / name) for name in ("full", "again"))
    assert [s["controller"] for s in again.summary["steps"]] == [
        s["controller"] for s in full.summary["steps"]
    ]
    np.testing.assert_array_equal(again.load_factors, full.load_factors)
    scale = np.abs(full.displacement()).max()
    for step in range(20):
        np.testing.assert_allclose(
            again.displacement(step), full.displacement(step), rtol=0, atol=1e-10 * scale
        )
    assert again.summary["converged"]
    assert again.summary["external_work"] == pytest.approx(full.summary["external_work"], 1e-12)
    np.testing.assert_array_equal(again.history["step"], np.arange(1, 21))
    np.testing.assert_array_equal(again.history["load_factor"], full.history["load_factor"])
    files = sorted(p.name for p in (tmp_path / "again").glob("step_*.vtu"))
    assert files == [f"step_{k:04d}.vtu" for k in range(1, 21)]
    assert (tmp_path / "again" / "results.pvd").read_text().count("<DataSet") == 20


def test_a_pressure_run_restarted_ends_where_the_full_one_does(tmp_path):
    """The coarse airbag in 4 steps, stopped after the first: the restart ends on the
    uninterrupted run's equilibrium."""
    overrides = {"mesh": {"rectangle": {"nx": 8, "ny": 8}}, "solver": {"steps": 4}}
    read_case(EXAMPLES / "airbag.toml", overrides).run(tmp_path / "full")
    interrupted(read_case(EXAMPLES / "airbag.toml", overrides), tmp_path / "again", after=1)
    read_case(EXAMPLES / "airbag.toml", overrides).run(tmp_path / "again", restart=True)
    full, again = (wrinkle.open_results(tmp_path / name) for name in ("full", "again"))
    np.testing.assert_array_equal(again.load_factors, full.load_factors)
    scale = np.abs(full.displacement()).max()
    assert np.abs(again.displacement() - full.displacement()).max() < 1e-10 * scale
    assert again.summary["steps"][-1]["pressure"] == full.summary["steps"][-1]["pressure"]


def test_a_crash_between_a_step_file_and_the_summary_is_taken_up(shear, tmp_path):
    """A step file the summary does not list (the run died between the two) is replaced
    by the restarted step; a folder without results starts from the beginning."""
    interrupted(read_case(shear), tmp_path / "run", after=3)
    shutil.copy(tmp_path / "run" / "step_0001.vtu", tmp_path / "run" / "step_0004.vtu")
    read_case(shear).run(tmp_path / "run", restart=True)
    run = wrinkle.open_results(tmp_path / "run")
    assert len(run) == 20
    assert np.abs(run.displacement(3) - run.displacement(0)).max() > 1e-4  # rewritten
    fresh = read_case(shear).run(tmp_path / "empty", restart=True)
    assert len(fresh) == 20


def test_open_results_gives_fields_history_and_mesh(shear, tmp_path):
    case = read_case(shear)
    results = case.run(tmp_path / "out")
    saved = wrinkle.open_results(tmp_path / "out")
    mesh = saved.mesh()
    np.testing.assert_array_equal(mesh.triangles, case.model.mesh.triangles)
    fields = saved.fields(2)
    assert fields["displacement"].shape == (mesh.n_nodes, 3)
    assert fields["state"].shape == (mesh.n_elements,)
    assert fields["stress"].shape == (mesh.n_elements, 9)
    np.testing.assert_array_equal(saved.displacement(2), results.steps[2].displacement)
    np.testing.assert_array_equal(saved.history["load_factor"], saved.load_factors)
    assert saved.history["strain_energy"][-1] == saved.summary["strain_energy"]


@pytest.mark.parametrize(
    "damage, message",
    [
        (lambda out: shutil.rmtree(out), "no such results folder"),
        (lambda out: (out / "summary.json").write_text("{"), "not readable as JSON"),
        (lambda out: (out / "summary.json").write_text('{"steps": 3}'), "no list of steps"),
    ],
)
def test_open_results_refuses_a_damaged_folder_in_one_line(shear, tmp_path, damage, message):
    read_case(shear).run(tmp_path / "out")
    damage(tmp_path / "out")
    with pytest.raises(ValueError, match=message):
        wrinkle.open_results(tmp_path / "out")


def test_restart_refusals_are_one_line_exit_2(shear, tmp_path, capsys):
    """A finished run, another mesh, another control: one line each, exit status 2."""
    out = tmp_path / "out"
    assert main(["run", str(shear), "--out", str(out), "-q"]) == 0
    assert main(["run", str(shear), "--out", str(out), "--restart", "-q"]) == 2
    assert "nothing to continue" in capsys.readouterr().err
    interrupted(read_case(shear), out, after=2)
    finer = tmp_path / "finer.toml"
    finer.write_text(SHEAR.replace("nx = 8, ny = 8", "nx = 4, ny = 4"))
    assert main(["run", str(finer), "--out", str(out), "--restart", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "a mesh of 81 nodes, not the case's 25" in err and len(err.splitlines()) == 1
    arc = tmp_path / "arc.toml"
    arc.write_text(SHEAR.replace("steps = 20", 'steps = 20\ncontrol = "arc-length"'))
    assert main(["run", str(arc), "--out", str(out), "--restart", "-q"]) == 2
    assert "only a load-controlled path" in capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["steps"]) == 2  # the refused restarts left the folder as it was
    assert summary["message"] == "interrupted"


EXAMPLE_CASES = sorted(EXAMPLES.glob("*.toml")) + sorted(  # not the study and fit files
    path
    for path in EXAMPLES.glob("*/*.toml")
    if path.parent.name != "studies" and path.name != "fit.toml"
)


@pytest.mark.parametrize("path", EXAMPLE_CASES, ids=lambda path: path.stem)
def test_the_reader_gives_back_every_examples_numbers(path, tmp_path):
    """Each example run and read back: every step's load factor, displacements and
    reactions as the in-memory results have them (bit for bit), its element states as
    counted, and the history's columns as the summary's numbers."""
    results = read_case(path).run(tmp_path / "out")
    saved = wrinkle.open_results(tmp_path / "out")
    assert len(saved) == len(results.steps)
    np.testing.assert_array_equal(saved.load_factors, [s.load_factor for s in results.steps])
    for index, step in enumerate(results.steps):
        fields = saved.fields(index)
        np.testing.assert_array_equal(saved.displacement(index), step.displacement)
        np.testing.assert_array_equal(fields["reaction"].reshape(-1), step.reactions)
        counts = np.bincount(fields["state"], minlength=3)
        assert tuple(int(c) for c in counts) == tuple(step.states)
        entry = saved.steps[index]
        assert saved.history["strain_energy"][index] == entry["strain_energy"]
        assert saved.history["residual"][index] == step.residual
