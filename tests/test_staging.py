"""Analysis steps (issue 22, item 7): ``[[step]]`` tables and ``Model.solve(start=...)``.

The references are path independence and the one-path results: a hyperelastic membrane under
a pressure on a surface held at its boundary (or closed by the end plates) has a potential,
and where its equilibrium is unique the end state of two analysis steps equals that of one
proportional path to the convergence tolerance. The gallery's tube (inflated, then bent by
its end plate into a wrinkled state) and a roof (prestressed by jacking its edges, then
loaded) are both checked to 1e-8 of the largest displacement.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import sheet_case

import wrinkle
from wrinkle.case import CaseError, read_case
from wrinkle.cli import main
from wrinkle.materials import StVenantKirchhoff
from wrinkle.plot import _load_column
from wrinkle.selectors import select_nodes
from wrinkle.solvers import ConvergenceError, SolverSettings
from wrinkle.staging import AnalysisStep, restart_point, solve_steps

ROOT = Path(__file__).resolve().parents[1]
TUBE = ROOT / "verification" / "cases" / "inflated_cylinder.toml"
# the gallery's tube on a coarse mesh; tight tolerance so that both paths converge far
# below the 1e-8 they are compared at
COARSE_TUBE = {
    "mesh": {"cylinder": {"n_circumferential": 16, "n_axial": 30, "n_cap": 3}},
    "solver": {"tolerance": 1e-11},
}
TUBE_STEPS = """
[[step]]
name = "inflate"
loads = ["load 1"]
steps = 2

[[step]]
name = "bend"
supports = ["tip plate"]
steps = 3
"""


def relative_difference(u: np.ndarray, reference: np.ndarray) -> float:
    return float(np.abs(u - reference).max() / np.abs(reference).max())


@pytest.fixture(scope="module")
def tube_one_path():
    """The gallery tube's one proportional path (pressure and plate together)."""
    return read_case(TUBE, COARSE_TUBE).solve()


def test_the_tube_inflated_then_bent_ends_where_the_one_path_run_ends(tube_one_path):
    """Python: inflate (the pressure alone, the tip plate held at zero), then bend (the
    plate turned, the pressure kept): the wrinkled end state equals the one-path result of
    the verification gallery's case to 1e-8, and so do the plate's reactions."""
    one = tube_one_path
    assert one.final.states[1] > 0  # the bent tube is partly wrinkled
    model = read_case(TUBE, COARSE_TUBE).model
    settings = read_case(TUBE, COARSE_TUBE).settings
    inflated = model.solve(settings, loads=["load 1"], supports=[], steps=2)
    assert [s.analysis_step for s in inflated.steps] == [1, 1]
    assert inflated.final.pressure == pytest.approx(100.0)
    assert inflated.final.states[1] == 0  # inflated alone: taut
    bent = model.solve(settings, start=inflated, supports=["tip plate"], steps=3)
    assert [s.analysis_step for s in bent.steps] == [2, 2, 2]
    assert [s.pressure for s in bent.steps] == pytest.approx([100.0] * 3)
    assert relative_difference(bent.final.displacement, one.final.displacement) < 1e-8
    tip = model.support_reactions(bent.final.reactions)["tip plate"]
    reference = model.support_reactions(one.final.reactions)["tip plate"]
    np.testing.assert_allclose(tip, reference, rtol=0, atol=1e-8 * np.abs(reference).max())


def test_a_staged_case_file_writes_the_steps_in_turn(tube_one_path, tmp_path):
    """The case file with [[step]] tables: the same end state; the summary and history
    carry each step's analysis step and total time, which the collection's timesteps
    follow; the pressure is held in the bending step."""
    case_file = tmp_path / "tube.toml"
    text = TUBE.read_text().split("\n[verification]\n")[0]
    case_file.write_text(text + TUBE_STEPS)
    case = read_case(case_file, COARSE_TUBE)
    results = case.run(tmp_path / "out")
    assert [s.analysis_step for s in results.steps] == [1, 1, 2, 2, 2]
    one = tube_one_path.final.displacement
    assert relative_difference(results.final.displacement, one) < 1e-8
    folder = wrinkle.open_results(tmp_path / "out")
    assert folder.summary["analysis_steps"] == ["inflate", "bend"]
    assert folder.summary["converged"]
    assert "analysis step 2 ('bend')" in folder.summary["message"]
    times = [s["time"] for s in folder.steps]
    assert times == pytest.approx([0.5, 1.0, 4 / 3, 5 / 3, 2.0])
    assert [s["analysis_step"] for s in folder.steps] == [1, 1, 2, 2, 2]
    assert [s["pressure"] for s in folder.steps] == pytest.approx([50.0] + [100.0] * 4)
    history = folder.history
    np.testing.assert_allclose(history["time"], times)
    header = list(history)
    table = np.column_stack([history[name] for name in header])
    assert _load_column(header, table, None) == ("time", "load_factor")  # the curve's axis
    pvd = (tmp_path / "out" / "results.pvd").read_text()
    assert [float(t) for t in pvd.split('timestep="')[1:] for t in [t.split('"')[0]]] == (
        pytest.approx(times)
    )


def roof(mesh):
    """A 10 m square PVC roof (E t = 500 kN/m) whose frame is jacked outwards by 2.5 mm per
    metre (a biaxial prestress of E t 0.0025 / (1 - nu) = 1.8 kN/m), then loaded by 300 Pa
    of wind suction; the frame's four edges are four supports."""
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=5e8, nu=0.3, thickness=1e-3))
    for label, edge in (
        ("west", "x == 0"),
        ("east", "x == 10"),
        ("south", "y == 0"),
        ("north", "y == 10"),
    ):
        nodes = select_nodes(mesh, edge)
        model.prescribe(nodes, 0.0025 * (mesh.nodes[nodes] - [5.0, 5.0, 0.0]), label=label)
    model.add_pressure(300.0, label="wind")
    return model


def test_a_roof_prestressed_then_loaded_equals_the_one_path_roof():
    """Path independence where the problem has a potential and one equilibrium: jacking
    the edges, then the wind, ends where both together end, to 1e-8."""
    mesh = wrinkle.rectangle(10.0, 10.0, 12, 12)
    together = roof(mesh).solve(steps=3, tolerance=1e-12)
    model = roof(mesh)
    prestressed = model.solve(supports=["west", "east", "south", "north"], tolerance=1e-12)
    assert np.abs(prestressed.final.displacement.reshape(-1, 3)[:, 2]).max() == 0.0
    loaded = model.solve(start=prestressed, loads=["wind"], steps=3, tolerance=1e-12)
    difference = relative_difference(loaded.final.displacement, together.final.displacement)
    assert difference < 1e-8
    assert loaded.final.pressure == pytest.approx(300.0)
    assert prestressed.final.pressure == 0.0


def test_a_load_changed_between_steps_grows_from_its_old_value_to_its_new():
    """Python: a pressure raised between two solves grows in the second from the value it
    had at the end of the first (50 -> 100 Pa); the result equals the roof under 100 Pa."""
    mesh = wrinkle.rectangle(10.0, 10.0, 8, 8)
    reference = roof(mesh)
    reference.add_pressure(-200.0, label="wind")  # 100 Pa in all
    one = reference.solve(steps=2, tolerance=1e-12)
    model = roof(mesh)
    model.add_pressure(-250.0, label="wind")  # 50 Pa
    first = model.solve(steps=2, tolerance=1e-12)
    assert first.final.pressure == pytest.approx(50.0)
    model.add_pressure(50.0, label="wind")  # 100 Pa
    second = model.solve(start=first, loads=["wind"], steps=2, tolerance=1e-12)
    assert [s.pressure for s in second.steps] == pytest.approx([75.0, 100.0])
    assert relative_difference(second.final.displacement, one.final.displacement) < 1e-8


def test_a_support_added_between_steps_holds_the_node_where_it_is():
    """A component held in the second step but free at its start starts from its
    displacement there (no jump), and moves to its own value over the step."""
    mesh = wrinkle.rectangle(10.0, 10.0, 6, 6)
    model = roof(mesh)
    first = model.solve(steps=2, tolerance=1e-12)
    centre = int(np.argmin(np.linalg.norm(mesh.nodes - [5.0, 5.0, 0.0], axis=1)))
    rise = first.final.displacement[3 * centre + 2]
    assert rise > 0.05
    model.prescribe([centre], (np.nan, np.nan, 2.0 * rise), label="mast")
    second = model.solve(start=first, supports=["mast"], steps=2, tolerance=1e-12)
    z = [s.displacement[3 * centre + 2] for s in second.steps]
    assert z == pytest.approx([1.5 * rise, 2.0 * rise], rel=1e-12)


def test_wrong_analysis_steps_in_python_are_refused():
    """An unknown label, a start that did not reach its end, a start and a u0."""
    mesh = wrinkle.rectangle(10.0, 10.0, 4, 4)
    model = roof(mesh)
    with pytest.raises(ValueError, match="no load is labelled 'snow'.*'wind'"):
        model.solve(loads=["snow"])
    with pytest.raises(ValueError, match="no support is labelled 'mast'"):
        model.solve(supports=["mast"])
    first = model.solve(supports=["west", "east", "south", "north"])
    first.steps[-1].load_factor = 0.5  # as if the path had stopped halfway
    with pytest.raises(ValueError, match="ended at load factor 0.5, not 1"):
        model.solve(start=first, loads=["wind"])
    first.steps[-1].load_factor = 1.0
    with pytest.raises(ValueError, match="either u0 or start"):
        model.solve(start=first, loads=["wind"], u0=np.zeros(model.n_dofs))
    with pytest.raises(ValueError, match="nested = true is for one proportional path"):
        model.solve(start=first, loads=["wind"], nested=True)


def test_modes_of_a_staged_state_are_those_of_the_one_path_state():
    """The natural modes about the end of the second step use that step's loads: the same
    frequencies as about the one-path state (the pressure's load stiffness is in both)."""
    mesh = wrinkle.rectangle(10.0, 10.0, 6, 6)
    together = roof(mesh)
    together.assign_material(together.materials[0], density=1300.0)
    one = together.solve(steps=2, tolerance=1e-12)
    model = roof(mesh)
    model.assign_material(model.materials[0], density=1300.0)
    first = model.solve(supports=["west", "east", "south", "north"], tolerance=1e-12)
    second = model.solve(start=first, loads=["wind"], steps=2, tolerance=1e-12)
    np.testing.assert_allclose(second.modes(4).frequencies, one.modes(4).frequencies, rtol=1e-7)


STAGED_SHEET = sheet_case(nx=4, top="[0.1, 0.05, 0.0]", steps=1)


def staged_sheet(steps: str) -> str:
    """The sheared sheet of ``sheet_case`` with a nodal load and the tables ``steps``."""
    load = '\n[[load]]\nlabel = "pull"\nkind = "nodal"\nnodes = "y == 1"\nforce = [0, 0.01, 0]\n'
    return STAGED_SHEET + load + steps


@pytest.mark.parametrize(
    ("steps", "message"),
    [
        ('[[step]]\nloads = ["push"]\nsupports = ["top"]\n', "no load is labelled 'push'"),
        ('[[step]]\nsupports = ["top"]\n', "load 'pull' grows in no step"),
        ('[[step]]\nloads = ["pull"]\n', "support 'top' prescribes a displacement but moves"),
        (
            '[[step]]\nloads = ["pull"]\nsupports = ["top"]\n[[step]]\nloads = ["pull"]\n',
            r"\[\[step\]\] 2: 'loads': 'pull' grew in \[\[step\]\] 1 already",
        ),
        (
            '[[step]]\nloads = ["pull"]\nsupports = ["top"]\n[[step]]\nname = "idle"\n',
            r"\[\[step\]\] 2: names no load and no support",
        ),
        ('[[step]]\nloads = "pull"\nsupports = ["top"]\n', "'loads' must be a list of labels"),
        (
            '[[step]]\nloads = ["pull"]\nsupports = ["top"]\nnested = true\n',
            r"\[\[step\]\] 1: unknown key 'nested'",
        ),
        (
            '[[step]]\nloads = ["pull"]\nsupports = ["top"]\ncontrol = "volume"\n',
            "control = 'volume' is solved in one path",
        ),
        (
            '[[step]]\nloads = ["pull"]\nsupports = ["top"]\ncontrol = "arc-length"\n',
            r"\[\[step\]\] 1: control = 'arc-length'.*moves support 'top'",
        ),
    ],
)
def test_bad_step_tables_are_one_line_naming_the_table(tmp_path, steps, message):
    path = tmp_path / "case.toml"
    path.write_text(staged_sheet(steps))
    with pytest.raises(CaseError, match=message) as error:
        read_case(path)
    assert str(path) in str(error.value) and "\n" not in str(error.value)


def test_a_staged_case_stopped_in_its_second_step_restarts_to_the_same_end(tmp_path):
    """Stopped (Ctrl-C) in the middle of the second analysis step, and at the boundary
    between the two, then restarted: the same steps and the same final state to 1e-10 as
    the run that was not stopped."""
    path = tmp_path / "case.toml"
    path.write_text(
        staged_sheet(
            '[[step]]\nname = "shear"\nsupports = ["top"]\nsteps = 4\n'
            '[[step]]\nname = "pull"\nloads = ["pull"]\nsteps = 5\n'
        )
    )
    assert main(["run", str(path), "--out", str(tmp_path / "full"), "-q"]) == 0
    full = wrinkle.open_results(tmp_path / "full")
    assert [s["analysis_step"] for s in full.steps] == [1] * 4 + [2] * 5
    for after in (6, 4):
        out = tmp_path / f"stopped_{after}"
        count = [0]

        def stop(step, count=count, after=after):
            count[0] += 1
            if count[0] == after:
                raise KeyboardInterrupt

        with pytest.raises(KeyboardInterrupt):
            read_case(path).run(out, on_step=stop)
        assert len(wrinkle.open_results(out)) == after
        assert main(["run", str(path), "--out", str(out), "--restart", "-q"]) == 0
        again = wrinkle.open_results(out)
        np.testing.assert_allclose(again.load_factors, full.load_factors, rtol=1e-14)
        assert [s["analysis_step"] for s in again.steps] == [1] * 4 + [2] * 5
        scale = np.abs(full.displacement()).max()
        np.testing.assert_allclose(
            again.displacement(), full.displacement(), rtol=0, atol=1e-10 * scale
        )
    # a finished staged run has nothing to continue
    code = main(["run", str(path), "--out", str(tmp_path / "full"), "--restart", "-q"])
    assert code == 2
    assert json.loads((tmp_path / "full" / "summary.json").read_text())["converged"]


def test_a_failing_second_step_keeps_the_first_steps_states():
    """A ConvergenceError in the second analysis step carries every converged state of
    both steps in its results (``solve_steps``)."""
    mesh = wrinkle.rectangle(10.0, 10.0, 4, 4)
    steps = [
        AnalysisStep("prestress", supports=("west", "east", "south", "north")),
        AnalysisStep(
            "wind", loads=("wind",), settings=SolverSettings(max_iterations=1, min_step=0.5)
        ),
    ]
    with pytest.raises(ConvergenceError) as error:
        solve_steps(roof(mesh), steps)
    assert [s.analysis_step for s in error.value.results.steps] == [1]


def test_the_roof_example_is_prestressed_by_its_frame_then_lifted(tmp_path):
    """examples/roof.toml: after the first step the roof carries the homogeneous biaxial
    prestress of its jacked frame, E t (e + e^2 / 2) / (1 - nu) with e = 0.0025, to the
    tolerance; the wind then grows with the frame held, and the centre rises."""
    assert main(["run", str(ROOT / "examples" / "roof.toml"), "--out", str(tmp_path), "-q"]) == 0
    folder = wrinkle.open_results(tmp_path)
    first = folder.steps[0]
    assert (first["analysis_step"], first["load_factor"], first["pressure"]) == (1, 1.0, 0.0)
    e = 0.0025
    prestress = 5e8 * 1e-3 * (e + e * e / 2) / (1 - 0.3)
    assert first["max_principal_stress"]["value"] == pytest.approx(prestress, rel=1e-6)
    wind = [s for s in folder.steps if s["analysis_step"] == 2]
    assert [s["pressure"] for s in wind] == pytest.approx([75.0, 150.0, 225.0, 300.0])
    rise = folder.history["centre_uz"]
    assert rise[0] == pytest.approx(0.0, abs=1e-12) and np.all(np.diff(rise) > 0)
    assert folder.summary["analysis_steps"] == ["prestress", "wind"]


def test_a_staged_xdmf_series_is_timed_by_the_total_time(tmp_path):
    """examples/roof.toml written as an XDMF time series: meshio's reader sees every step at
    its total time (analysis step - 1 + load factor), increasing across the steps."""
    meshio = pytest.importorskip("meshio")
    pytest.importorskip("h5py")
    path = tmp_path / "roof.toml"
    text = (ROOT / "examples" / "roof.toml").read_text()
    path.write_text(text.replace("[solver]", '[output]\nformat = "xdmf"\n\n[solver]'))
    read_case(path, {"mesh": {"rectangle": {"nx": 8, "ny": 8}}}).run(tmp_path / "out")
    with meshio.xdmf.TimeSeriesReader(tmp_path / "out" / "results.xdmf") as reader:
        reader.read_points_cells()
        times = [reader.read_data(k)[0] for k in range(reader.num_steps)]
    assert times == pytest.approx([1.0, 1.25, 1.5, 1.75, 2.0])


def test_a_restart_sets_a_component_two_supports_hold_as_the_run_did(tmp_path):
    """Two supports of one node, the one later in the file named first: the node ends the
    second step where the second step's support puts it, and a run restarted in the third
    step starts it there too (the state rebuilt step by step, not in the file's order)."""
    fan = ROOT / "benchmarks" / "hard_cases" / "pulled_node.toml"
    node = "x == 0.5 and y == 1"
    overrides = {
        "support": [
            {"label": "bottom", "nodes": "y == 0", "fix": ["x", "y", "z"]},
            {"label": "push", "nodes": node, "displacement": [0.0, 0.05, 0.0]},
            {"label": "pull", "nodes": node, "displacement": [0.0, 0.1, 0.0]},
            {"label": "plane", "nodes": "z == 0", "fix": ["z"]},
        ],
        "load": [
            {
                "label": "tug",
                "kind": "nodal",
                "nodes": "x == 0.25 and y == 1",
                "force": [0.0, 1e-3, 0.0],
            }
        ],
        "step": [
            {"supports": ["pull"]},
            {"supports": ["push"]},
            {"loads": ["tug"], "steps": 3},
        ],
    }
    full = read_case(fan, overrides).run(tmp_path / "full")
    y = 3 * int(full.model.supports[1].nodes[0]) + 1
    assert [s.displacement[y] for s in full.steps] == pytest.approx([0.1, 0.05, 0.05, 0.05, 0.05])
    count = [0]

    def stop(step):
        count[0] += 1
        if count[0] == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        read_case(fan, overrides).run(tmp_path / "again", on_step=stop)
    again = read_case(fan, overrides).run(tmp_path / "again", restart=True)
    assert [s.displacement[y] for s in again.steps] == pytest.approx([0.05, 0.05])
    reference = wrinkle.open_results(tmp_path / "full").displacement()
    restarted = wrinkle.open_results(tmp_path / "again").displacement()
    np.testing.assert_allclose(restarted, reference, rtol=0, atol=1e-10)


def test_pressures_that_cancel_are_reported_as_zero_with_their_volume():
    """A frame-held square inflated by one pressure load, then vented by another of the
    opposite sign: the pressure reported is 5 then 0 (not missing), and the enclosed volume
    of the elements under pressure is reported in both steps (back to flat after the vent)."""
    mesh = wrinkle.rectangle(1.0, 1.0, 4, 4)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1e4, nu=0.3, thickness=1e-3))
    model.fix("x == 0 or x == 1 or y == 0 or y == 1")
    model.add_pressure(5.0, label="inflate")
    model.add_pressure(-5.0, label="vent")
    inflated = model.solve(loads=["inflate"], tolerance=1e-10)
    vented = model.solve(start=inflated, loads=["vent"], tolerance=1e-10)
    assert inflated.final.pressure == pytest.approx(5.0)
    assert vented.final.pressure == pytest.approx(0.0, abs=1e-12)
    assert inflated.final.enclosed_volume > 0
    assert abs(vented.final.enclosed_volume) < 1e-4 * inflated.final.enclosed_volume  # flat


@pytest.mark.parametrize(
    "factors, increment, in_a_row",
    [
        ([0.25, 0.375], 0.125, 1),  # one step at the cut increment: it stays
        ([0.25, 0.375, 0.5], 0.25, 0),  # two in a row: it grows back (rule 6)
        ([0.25, 0.5], 0.25, 2),  # the first increment, two in a row: nothing to undo
    ],
)
def test_a_restart_counts_the_steps_in_a_row_at_the_last_increment(factors, increment, in_a_row):
    """``restart_point`` takes the step controller's state that the summary saved with the
    last step; for a folder without it, it rebuilds it from the saved levels: the increment
    of the last, how many before it had the same one, and the growth that the uninterrupted
    run would have made (steps = 4, every step 9 iterations: not easy)."""
    model = roof(wrinkle.rectangle(10.0, 10.0, 4, 4))
    steps = [
        AnalysisStep(
            "prestress",
            supports=("west", "east", "south", "north"),
            settings=SolverSettings(steps=4),
        )
    ]
    saved = [{"analysis_step": 1, "load_factor": f, "iterations": 9} for f in factors]
    _, _, resume = restart_point(model, steps, saved, lambda i: np.zeros(model.n_dofs))
    assert resume is not None
    assert resume.factor == factors[-1] and resume.previous[0] == (factors[-2])
    assert resume.controller["increment"] == pytest.approx(increment)
    assert resume.controller["in_a_row"] == in_a_row
    # a folder that holds the controller's state: taken as it is
    state = {"increment": 0.125, "in_a_row": 1, "needed": 4, "regrown": False}
    saved[-1]["controller"] = state
    _, _, resume = restart_point(model, steps, saved, lambda i: np.zeros(model.n_dofs))
    assert resume is not None and resume.controller == state
