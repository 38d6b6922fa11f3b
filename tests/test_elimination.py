"""Nonlinear elimination (issue 18, item 3; ``wrinkle.solvers.elimination``): the patch's seed
nodes, its growth by element rings, the patch's sub-system against the whole system (an
energy identity), one relaxation (the energy principle), and whole solves against Newton's
without it.

References: the potential energy is a sum over elements, so moving only the patch's nodes
changes the whole system's energy exactly as the patch's (every element that touches them is
in the patch); the relaxed point of a minimisation is never above its start in energy; the
nodes one ring away are those sharing a triangle, from the triangles themselves."""

from pathlib import Path

import numpy as np
import pytest

from wrinkle.case import CaseError, read_case
from wrinkle.solvers import base as solver_base
from wrinkle.solvers import settings as solver_settings
from wrinkle.solvers.elimination import Elimination, seed_nodes
from wrinkle.solvers.settings import SolverSettings

ROOT = Path(__file__).resolve().parents[1]
AIRBAG = ROOT / "examples" / "airbag.toml"
RECTANGLE = ROOT / "benchmarks" / "hard_cases" / "sheared_rectangle.toml"


def airbag(n: int, **solver):
    return read_case(AIRBAG, {"mesh": {"rectangle": {"nx": n, "ny": n}}, "solver": solver})


def test_the_seeds_are_the_fewest_nodes_carrying_the_share_of_the_residual():
    """Per-node |r|^2 of 100, 1, 50, 0, 30 (total 181): 0.9 of it (162.9) needs the nodes
    of 100, 50 and 30; at most a fifth of the nodes, only the first; 0.5 (90.5) the first
    alone; a zero residual has no seeds."""
    per_node = np.array([100.0, 1.0, 50.0, 0.0, 30.0])
    residual = np.zeros((5, 3))
    residual[:, 1] = np.sqrt(per_node)
    residual = residual.ravel()
    np.testing.assert_array_equal(seed_nodes(residual, 0.9, 1.0), [1, 0, 1, 0, 1])
    np.testing.assert_array_equal(seed_nodes(residual, 0.9, 0.2), [1, 0, 0, 0, 0])
    np.testing.assert_array_equal(seed_nodes(residual, 0.5, 1.0), [1, 0, 0, 0, 0])
    assert seed_nodes(np.zeros(15), 0.9, 1.0) is None


def test_a_ring_of_elements_adds_the_nodes_that_share_a_triangle():
    """On the 8 x 8 airbag mesh, one node grown by one ring is the node and every node of a
    triangle it belongs to; two rings are one ring of one ring."""
    system = airbag(8).model.discretise()
    triangles = system.mesh.triangles
    node = 40
    nodes = np.zeros(system.mesh.n_nodes, dtype=bool)
    nodes[node] = True
    expected = np.zeros_like(nodes)
    expected[np.unique(triangles[np.any(triangles == node, axis=1)])] = True
    np.testing.assert_array_equal(system.grow(nodes, 1), expected)
    np.testing.assert_array_equal(system.grow(nodes, 2), system.grow(expected, 1))


def test_the_patch_changes_energy_and_forces_as_the_whole_system_does():
    """The 8 x 8 airbag under its pressure, at a bulged state u: the patch of the elements
    around six nodes (one ring grown) has the free components of those nodes free and
    every other one held at u; moving its free components by v changes the patch's energy
    as it changes the whole system's (to 1e-9 of the energy), and its residual is the
    system's on those components."""
    case = airbag(8)
    system = case.model.discretise()
    problem = system.at(1.0)
    X = system.mesh.nodes
    rng = np.random.default_rng(4)
    u = np.zeros(system.n_dofs)
    u[2::3] = 0.1 * np.cos(np.pi * X[:, 0] / 0.85) * np.cos(np.pi * X[:, 1] / 0.85)
    u += np.where(problem.free, 1e-3 * rng.standard_normal(u.size), 0.0)
    u = np.where(problem.free, u, problem.prescribed)
    nodes = np.zeros(system.mesh.n_nodes, dtype=bool)
    nodes[[0, 10, 30, 31, 50, 80]] = True
    nodes = system.grow(nodes, 1)
    local, start, dofs = problem.patch(nodes, u)
    np.testing.assert_array_equal(start, u[dofs])
    np.testing.assert_array_equal(local.free, problem.free[dofs] & np.repeat(nodes, 3)[dofs])
    whole, part = problem.evaluate(u, stiffness=False), local.evaluate(start, stiffness=False)
    np.testing.assert_allclose(part.residual[local.free], whole.residual[dofs][local.free])
    v = np.where(local.free, 1e-3 * rng.standard_normal(dofs.size), 0.0)
    moved = u.copy()
    moved[dofs] += v
    change = problem.evaluate(moved, stiffness=False).energy - whole.energy
    local_change = local.evaluate(start + v, stiffness=False).energy - part.energy
    assert abs(change) > 1e-6 * abs(whole.energy)
    assert abs(change - local_change) <= 1e-9 * abs(whole.energy)


def test_a_relaxed_trial_point_is_lower_in_energy_and_balanced_on_its_patch():
    """The 16 x 16 airbag at a bulged state, relaxed once as a trial point: the energy does
    not rise, the point moves only on the patch's nodes, and the largest residual force of
    the seed nodes falls tenfold."""
    case = airbag(16)
    system = case.model.discretise()
    problem = system.at(1.0)
    X = system.mesh.nodes
    u = np.zeros(system.n_dofs)
    u[2::3] = 0.15 * np.cos(np.pi * X[:, 0] / 0.85) * np.cos(np.pi * X[:, 1] / 0.85)
    u = np.where(problem.free, u, problem.prescribed)
    trial = problem.evaluate(u, stiffness=False)
    relaxed, evaluation = Elimination().relax(problem, u, trial, 1e-8)
    assert problem.timer.patches == 1 and problem.timer.local_iterations > 0
    assert evaluation.energy <= trial.energy
    moved = np.flatnonzero(np.any((relaxed - u).reshape(-1, 3) != 0, axis=1))
    seeds = seed_nodes(trial.residual, 0.9, 0.1)
    assert np.all(system.grow(seeds, Elimination.layers)[moved])
    before = np.linalg.norm(trial.residual.reshape(-1, 3)[seeds], axis=1).max()
    after = np.linalg.norm(evaluation.residual.reshape(-1, 3)[seeds], axis=1).max()
    assert after < 0.1 * before


@pytest.mark.parametrize("n", [8, 16])
def test_a_solve_with_elimination_reaches_the_same_equilibrium(n):
    """The airbag from the flat sheet, 8 x 8 and 16 x 16: with elimination, balanced to the
    case's tolerance on the whole mesh, at the centre deflection of Newton's solve without
    it (the same equilibrium: 217.4424 and 216.9518 mm), in fewer global iterations (9 and
    17 against 19 and 27, 6 December 2026), its patches counted."""
    plain = airbag(n).solve()
    case = airbag(n, elimination=True)
    results = case.solve()
    node = case.probes["centre"][0]
    centre = [r.final.displacement.reshape(-1, 3)[node, 2] for r in (plain, results)]
    assert abs(centre[1] - centre[0]) < 1e-9
    ev = results.final
    assert ev.residual <= 1e-8 * 1e3  # the case's tolerance x a force scale below 1 kN
    assert results.final.iterations < plain.final.iterations
    work = results.elimination
    assert work["patches"] > 0 and work["local_iterations"] >= work["patches"]
    assert plain.elimination["patches"] == 0


def test_elimination_on_a_sheet_moved_by_its_supports(monkeypatch):
    """The sheared rectangle 40 x 20 (every z held, the top edge moved): with elimination
    the top edge's reaction is Newton's without it, to 1e-6 of it; the patches' solves use
    the case's linear solver."""

    def reaction(elimination: bool) -> np.ndarray:
        case = read_case(
            RECTANGLE,
            {"mesh": {"rectangle": {"nx": 40, "ny": 20}}, "solver": {"elimination": elimination}},
        )
        results = case.solve()
        assert (results.elimination["patches"] > 0) == elimination
        return case.model.support_reactions(results.final.reactions)["top"]

    plain, eliminated = reaction(False), reaction(True)
    # the case's linear solver serves the patches too: every back-end made is the one named
    # ("superlu"), none "auto"
    used = []
    original = solver_base.make_linear_solver

    def recording(name, *args, **kwargs):
        used.append(name)
        return original(name, *args, **kwargs)

    monkeypatch.setattr(solver_base, "make_linear_solver", recording)
    case = read_case(
        RECTANGLE,
        {
            "mesh": {"rectangle": {"nx": 40, "ny": 20}},
            "solver": {"elimination": True, "linear_solver": "superlu"},
        },
    )
    assert case.solve().elimination["patches"] > 0
    assert used and set(used) == {"superlu"}
    np.testing.assert_allclose(eliminated, plain, rtol=1e-6, atol=1e-6 * np.abs(plain).max())


def test_elimination_is_refused_where_it_cannot_solve_patches():
    """One line naming the key: with the sheet's bending stiffness (in a case and in
    ``Model.solve``), with cables, with the restricted step method, under volume control,
    with the accuracy stop, with a gas load, and for a value that is not true or false."""
    with pytest.raises(CaseError, match=r"\[solver\]: elimination = true: .*bending stiffness"):
        read_case(AIRBAG, {"solver": {"elimination": True}, "material": {"bending": True}})
    bent = read_case(
        AIRBAG, {"mesh": {"rectangle": {"nx": 4, "ny": 4}}, "material": {"bending": True}}
    )
    with pytest.raises(ValueError, match="elimination = true: .*bending stiffness"):
        bent.model.solve(elimination=True)
    with pytest.raises(CaseError, match="elimination = true: .*cables"):
        read_case(ROOT / "examples" / "sail.toml", {"solver": {"elimination": True}})
    with pytest.raises(ValueError, match="cannot go with convergence = 'accuracy'"):
        SolverSettings(elimination=True, convergence="accuracy", nested=True)
    with pytest.raises(ValueError, match="elimination = true needs method = 'newton'"):
        SolverSettings(elimination=True, method="restricted-step")
    with pytest.raises(ValueError, match="and control = 'load'"):
        SolverSettings(elimination=True, control="volume", volume=1.0)
    gas = {"kind": "gas", "amount": 1639.6, "ambient": 1.0e5, "gamma": 1.0}
    with pytest.raises(CaseError, match="elimination = true: .*a gas load"):
        read_case(AIRBAG, {"solver": {"elimination": True}, "load": [gas]})
    with pytest.raises(CaseError, match="'elimination' must be true or false"):
        read_case(AIRBAG, {"solver": {"elimination": "yes"}})
    assert isinstance(SolverSettings(elimination=True).solver().elimination, Elimination)
    assert SolverSettings().solver().elimination is None
    assert solver_settings.Elimination is Elimination
