"""The load path (wrinkle.solvers.stepping): the step controller's rules, checked against
increment sequences worked out by hand, and the path follower on a real model."""

from pathlib import Path

import numpy as np
import pytest

import wrinkle
from wrinkle.case import read_case
from wrinkle.materials import StVenantKirchhoff
from wrinkle.solvers import ConvergenceError, SolverSettings, StepController, follow_load_path
from wrinkle.solvers.arc_length import _first_step, follow_arc_length
from wrinkle.solvers.base import Diverging, Evaluation, SolverResult
from wrinkle.solvers.stepping import _Increments


class FakeProblem:
    """A load level whose evaluations are never in balance (so the solver is always called)."""

    def __init__(self, load_factor, n_dofs):
        self.load_factor = load_factor
        self.prescribed = np.zeros(n_dofs)
        self.free = np.ones(n_dofs, dtype=bool)
        self.timer = None

    def evaluate(self, u, stiffness=True, lift=None):
        return Evaluation(np.ones(u.size), 0.0, 1.0, (1, 0, 0))


class FakeLevels:
    n_dofs = 3

    def at(self, load_factor=1.0, prescribed=None):
        return FakeProblem(load_factor, self.n_dofs)


class FakeSolver:
    """Fails a step whose increment exceeds ``largest``; otherwise converges in
    ``iterations`` iterations. Records the load factors it is asked to solve."""

    tolerance = 1e-6
    tangent_predictor = False

    def __init__(self, largest, iterations):
        self.largest, self.iterations = largest, iterations
        self.trials, self.reached = [], 0.0

    def solve(self, problem, start, at_start=None):
        factor = problem.load_factor
        self.trials.append(round(factor, 12))
        if factor - self.reached > self.largest + 1e-12:
            raise ConvergenceError("too far", [])
        self.reached = factor
        return SolverResult(start, self.iterations, [], at_start)


def test_controller_rules():
    controller = StepController(
        first_step=0.5, min_step=0.1, max_step=0.4, cutback=0.25, growth=3.0, target_iterations=4
    )
    assert controller.first() == 0.4  # never above max_step
    assert controller.after_failure(0.4) == pytest.approx(0.1)
    assert controller.after_failure(0.3) is None  # 0.075 < min_step
    assert controller.after_success(0.1, 4) == pytest.approx(0.3)  # easy: grown by 3
    assert controller.after_success(0.1, 5) == 0.1  # not easy: kept
    assert controller.after_success(0.3, 1) == pytest.approx(0.4)  # up to max_step


def test_cut_back_and_growth_sequence():
    """Worked by hand: increments of 0.25 aimed at, steps larger than 0.2 fail, 3 iterations
    (easy) each: 0.25 fails, 0.125 converges, grows back to 0.25 which fails from 0.125,
    0.125 again, and so on: the path reaches 1 in eight steps of 0.125."""
    solver = FakeSolver(largest=0.2, iterations=3)
    controller = SolverSettings(
        steps=4, cutback=0.5, growth=2.0, target_iterations=6, look_ahead=False
    )
    converged = []
    follow_load_path(
        FakeLevels(),
        solver,
        controller.controller(),
        on_step=lambda f, u, s: converged.append(round(f, 12)),
    )
    assert converged == [0.125 * k for k in range(1, 9)]
    assert solver.trials[:4] == [0.25, 0.125, 0.375, 0.25]


def test_hard_steps_do_not_grow_without_regrowth():
    """With regrow_after = 0 a step taking more than target_iterations keeps its increment:
    after the first cut (0.5 -> 0.25 under a limit of 0.3) every later step stays at 0.25."""
    solver = FakeSolver(largest=0.3, iterations=9)
    settings = SolverSettings(steps=2, look_ahead=False, regrow_after=0)
    follow_load_path(FakeLevels(), solver, settings.controller())
    assert solver.trials == [0.5, 0.25, 0.5, 0.75, 1.0]


def test_a_cut_increment_grows_back_after_two_steps_and_backs_off():
    """Worked by hand, steps = 1, increments above 0.15 fail, every step takes 9 iterations
    (not easy): 1, 0.5 and 0.25 fail; 0.125 and 0.25 converge at the cut increment 0.125, two
    in a row, so it grows to 0.25, and 0.5 fails; now four in a row are needed (0.375, 0.5,
    0.625, 0.75) before the next try at 0.25, to 1.0, fails; eight would be needed next, and
    0.875 and 1.0 end the path."""
    solver = FakeSolver(largest=0.15, iterations=9)
    settings = SolverSettings(steps=1, look_ahead=False)
    follow_load_path(FakeLevels(), solver, settings.controller())
    assert settings.regrow_after == 2
    assert solver.trials == [1.0, 0.5, 0.25, 0.125, 0.25, 0.5] + [
        0.375,
        0.5,
        0.625,
        0.75,
        1.0,
        0.875,
        1.0,
    ]


def test_look_ahead_tries_the_end_before_cutting_back():
    """With the look-ahead (the default), the first failure above is followed by a try of the
    end of the path (1.0, which fails too, being an increment of 1 > 0.3), then the same
    cut-backs as without it: 0.25 and 0.5 at the cut increment, its regrowth to 0.5 failing
    at 1.0, and 0.75 and 1.0."""
    solver = FakeSolver(largest=0.3, iterations=9)
    follow_load_path(FakeLevels(), solver, SolverSettings(steps=2).controller())
    assert solver.trials == [0.5, 1.0, 0.25, 0.5, 1.0, 0.75, 1.0]


class HarderNearZero:
    """A flat sheet under pressure: a step from the reference state (zero displacements) to a
    load factor below ``easiest`` fails; every other step converges, at the displacements
    u = load factor (so that each reported state can be matched to its level)."""

    tolerance = 1e-6
    tangent_predictor = False

    def __init__(self, easiest, below_fails_always=False):
        self.easiest, self.always = easiest, below_fails_always
        self.trials = []

    def solve(self, problem, start, at_start=None):
        factor = round(problem.load_factor, 12)
        self.trials.append(factor)
        from_rest = not np.any(start)
        if factor < self.easiest and (from_rest or self.always):
            raise ConvergenceError("small load from the flat sheet", [])
        return SolverResult(np.full(start.size, factor), 4, [], at_start)


def test_a_failed_first_step_is_reached_downwards_from_the_end():
    """Worked by hand, steps = 4, steps from rest below 0.6 fail: 0.25 fails, 1.0 converges,
    then 0.75, 0.5 and 0.25 downwards, each from the level above; the path is reported in
    increasing load factor, each level with its own displacements."""
    solver = HarderNearZero(easiest=0.6)
    reported = []
    u = follow_load_path(
        FakeLevels(),
        solver,
        SolverSettings(steps=4).controller(),
        on_step=lambda f, u, s: reported.append((round(f, 12), u[0])),
    )
    assert solver.trials == [0.25, 1.0, 0.75, 0.5, 0.25]
    assert reported == [(0.25, 0.25), (0.5, 0.5), (0.75, 0.75), (1.0, 1.0)]
    assert u[0] == 1.0


def test_a_failed_descent_falls_back_to_cutting_back():
    """Steps below 0.3 fail from any start, and min_step = 0.2: downwards 0.25 fails and its
    cut-back would be below min_step, so the first step is cut back as without the look-ahead,
    which is below min_step as well: the path fails having reached nothing."""
    solver = HarderNearZero(easiest=0.3, below_fails_always=True)
    settings = SolverSettings(steps=4, min_step=0.2)
    with pytest.raises(ConvergenceError, match="minimum 0.2") as caught:
        follow_load_path(FakeLevels(), solver, settings.controller())
    assert caught.value.reached == 0.0
    assert solver.trials == [0.25, 1.0, 0.75, 0.5, 0.25]


class NeedsIterations:
    """A flat sheet that needs ``needed`` iterations from the reference state (zero
    displacements) at any load factor, and 5 from any other start; its limit is the method's
    default (100) unless ``default`` is False. Records (load factor, limit) of each solve."""

    tolerance = 1e-6
    tangent_predictor = False
    max_iterations = 100

    def __init__(self, needed, default=True):
        self.needed, self.limit_is_default = needed, default
        self.calls = []

    def solve(self, problem, start, at_start=None, iterations=None):
        limit = self.max_iterations if iterations is None else iterations
        self.calls.append((round(problem.load_factor, 12), limit))
        needed = self.needed if not np.any(start) else 5
        if needed > limit:
            raise ConvergenceError(f"not converged in {limit} iterations", [])
        return SolverResult(np.full(start.size, problem.load_factor), needed, [], at_start)


def test_the_end_of_the_path_from_the_reference_state_gets_four_times_the_iterations():
    """Worked by hand, a solve from rest needing 250 iterations: in one step the end of the
    path is solved once with 4 x 100; in 4 steps the first step (100) fails, the look-ahead
    solves the end with 400 and the levels below it with 100 each, from the level above."""
    solver = NeedsIterations(250)
    follow_load_path(FakeLevels(), solver, SolverSettings(steps=1).controller())
    assert solver.calls == [(1.0, 400)]
    solver = NeedsIterations(250)
    follow_load_path(FakeLevels(), solver, SolverSettings(steps=4).controller())
    assert solver.calls == [(0.25, 100), (1.0, 400), (0.75, 100), (0.5, 100), (0.25, 100)]


def test_an_arc_length_path_in_one_step_gives_its_first_step_the_creep_budget():
    """Arc length with steps = 1 solves its first, load-controlled step to load factor 1
    from rest, the whole path: as under load control it gets 4 x 100 (rule 7), and a solve
    needing 250 converges at once instead of being cut back into a smaller load from the
    same flat sheet. A first step below 1 keeps the method's 100."""
    solver = Balanced(250)
    follow_arc_length(FakeLevels(), solver, SolverSettings(steps=1).controller(), on_step, 10)
    assert solver.calls == [(1.0, 400)]
    solver = Balanced(250)
    with pytest.raises(ConvergenceError, match="not converged in 100"):
        _first_step(
            FakeLevels(),
            solver,
            SolverSettings(steps=4, min_step=0.25).controller(),
            np.zeros(3),
            None,
        )
    assert solver.calls == [(0.25, 100)]


class Balanced(NeedsIterations):
    """``NeedsIterations`` whose solves end with an evaluation (as a real solver's do)."""

    def solve(self, problem, start, at_start=None, iterations=None):
        solved = super().solve(problem, start, at_start, iterations)
        state = problem.evaluate(solved.u)
        return SolverResult(solved.u, solved.iterations, [], state)


def on_step(*step):
    """Nothing to record (``follow_arc_length``'s on_step)."""


def test_the_end_of_the_path_on_a_larger_mesh_gets_iterations_by_its_size():
    """Worked by hand: with 40,000 free unknowns the end of the path from rest may take
    12 sqrt(40,000) = 2,400 iterations (more than 4 x 100), so a solve needing 1,000 (the
    40,394-element gmsh airbag needed 1,022) converges at once; one needing 2,500 fails and
    is cut back with 100 a solve. A user's limit keeps 100."""

    class Larger(FakeLevels):
        n_dofs = 40_000

    solver = NeedsIterations(1000)
    follow_load_path(Larger(), solver, SolverSettings(steps=1).controller())
    assert solver.calls == [(1.0, 2400)]
    solver = NeedsIterations(2500)
    with pytest.raises(ConvergenceError, match="not converged in 100"):
        follow_load_path(Larger(), solver, SolverSettings(steps=1, min_step=0.2).controller())
    assert solver.calls == [(1.0, 2400), (0.5, 100), (0.25, 100)]
    solver = NeedsIterations(1000, default=False)
    with pytest.raises(ConvergenceError, match="not converged in 100"):
        follow_load_path(Larger(), solver, SolverSettings(steps=1, min_step=0.5).controller())
    assert solver.calls == [(1.0, 100), (0.5, 100)]


def test_a_limit_set_by_the_user_or_a_start_away_from_rest_is_kept():
    """With max_iterations given, or from a start that is not the reference state, the end
    of the path has the solver's own limit: the solve from rest needing 250 fails and is cut
    back (to the minimum step, failing there too); the one from elsewhere takes 5."""
    solver = NeedsIterations(250, default=False)
    with pytest.raises(ConvergenceError, match="not converged in 100"):
        follow_load_path(FakeLevels(), solver, SolverSettings(steps=1, min_step=0.2).controller())
    assert solver.calls == [(1.0, 100), (0.5, 100), (0.25, 100)]
    solver = NeedsIterations(250)
    follow_load_path(FakeLevels(), solver, SolverSettings().controller(), u0=np.ones(3))
    assert solver.calls == [(1.0, 100)]


def test_failure_below_min_step_reports_where_it_stopped():
    solver = FakeSolver(largest=0.05, iterations=1)
    settings = SolverSettings(steps=1, min_step=0.1)  # the first step is the end: no look-ahead
    with pytest.raises(ConvergenceError, match="minimum 0.1") as caught:
        follow_load_path(FakeLevels(), solver, settings.controller())
    assert caught.value.reached == 0.0
    assert solver.trials == [1.0, 0.5, 0.25, 0.125]  # 0.0625 would be below min_step


@pytest.mark.parametrize(
    "field, value",
    [
        ("steps", 0),
        ("cutback", 1.0),
        ("cutback", 0.0),
        ("growth", 0.5),
        ("min_step", -1.0),
        ("max_step", 2.0),
        ("target_iterations", -1),
        ("tolerance", 0.0),
        ("method", "lbfgs"),
        ("linear_solver", "mumps"),
        ("max_iterations", 0),
        ("look_ahead", 1),
        ("nested", "yes"),
    ],
)
def test_bad_settings_name_the_field(field, value):
    with pytest.raises(ValueError, match=f"solver {field} must be"):
        SolverSettings(**{field: value})


def test_unknown_setting_is_a_type_error():
    with pytest.raises(TypeError, match="unknown solver setting 'step'"):
        SolverSettings().replace(step=3)


def test_model_solve_takes_the_controller_settings():
    """A sheet pulled in a path of 2 aimed steps; with max_step = 1/8 and no growth it takes
    8 equal steps, with the same final state as the 2-step path."""
    mesh = wrinkle.rectangle(1.0, 1.0, 4, 4)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1e3, nu=0.3, thickness=0.01))
    model.fix("bottom")
    model.prescribe("top", (0.02, 0.05, 0.0))
    two = model.solve(steps=2, tolerance=1e-10)
    eight = model.solve(steps=2, max_step=0.125, tolerance=1e-10)
    assert [s.load_factor for s in two.steps] == [0.5, 1.0]
    np.testing.assert_allclose([s.load_factor for s in eight.steps], np.arange(1, 9) / 8)
    np.testing.assert_allclose(eight.final.displacement, two.final.displacement, atol=1e-9)


_SPHERE = {
    "mesh": {"sphere": {"radius": 0.1, "n": 4}},
    "load": [{"kind": "pressure", "value": 4000.0}],
}


@pytest.mark.parametrize(
    "case_file, material, more, hint",
    [
        ("examples/airbag.toml", {"bending": False}, {}, True),
        ("examples/airbag.toml", {"bending": True}, {}, False),
        ("examples/airbag.toml", {"prestress": 100.0}, {}, False),
        ("benchmarks/hard_cases/pulled_node.toml", {}, {}, False),
        ("verification/cases/sphere.toml", {}, _SPHERE, False),
    ],
)
def test_a_path_under_pressure_that_reaches_no_level_names_the_remedy(
    case_file, material, more, hint
):
    """An airbag (8 x 8 quarter mesh) whose Newton is allowed 2 iterations converges at no
    load level: the error says that a pressure on a flat sheet is harder the smaller it is and
    names the iteration limit and the bending stiffness; not where the sheet has its bending
    stiffness already, nor where it is prestressed (it does not start unstressed), nor for
    the pulled-node fan, moved by its support alone, nor for a balloon (the 16-element octant
    of a sphere at 0.8 of its limit pressure: it does not start flat), which fail the same
    way."""
    path = Path(__file__).resolve().parents[1] / case_file
    overrides = {
        "mesh": {"rectangle": {"nx": 8, "ny": 8}},
        "solver": {"max_iterations": 2, "min_step": 0.3},
        "material": material,
        **more,
    }
    with pytest.raises(ConvergenceError, match="minimum 0.3") as caught:
        read_case(path, overrides).solve()
    assert ("bending = true" in str(caught.value)) == hint
    assert ("harder the smaller" in str(caught.value)) == hint
    assert ("raise [solver] max_iterations" in str(caught.value)) == hint
    assert caught.value.reached == 0.0


def test_only_a_regrowth_whose_step_fails_doubles_the_steps_needed():
    """steps = 4, every step 9 iterations (not easy): a cut 0.25 -> 0.125 grows back after
    two steps in a row. If the step at the regrown 0.25 converges, a later failure needs two
    in a row again; if that step fails, four."""
    controller = SolverSettings(steps=4).controller()
    for regrown_step_converges, needed in ((True, 2), (False, 4)):
        increment = _Increments(controller)
        assert increment.failed() and increment.value == 0.125
        increment.converged(9)
        assert increment.value == 0.125 and increment.in_a_row == 1
        increment.converged(9)
        assert increment.value == 0.25 and increment.in_a_row == 0
        if regrown_step_converges:
            increment.converged(9)
        assert increment.failed() and increment.value == 0.125
        assert increment.needed == needed


def test_a_path_resumed_from_any_level_goes_on_as_the_uninterrupted_one():
    """The hand-worked path of ``test_a_cut_increment_grows_back_after_two_steps_and_backs_off``
    (cut-backs, regrowths, a failed regrowth and its doubling) resumed after each of its
    levels from the controller's state saved with that level (``path_state``, the summary's
    "controller") tries the same load factors as the uninterrupted path from there on."""
    from wrinkle.solvers.stepping import Resume

    controller = SolverSettings(steps=1, look_ahead=False).controller()
    solver = FakeSolver(largest=0.15, iterations=9)
    levels = []
    follow_load_path(
        FakeLevels(),
        solver,
        controller,
        on_step=lambda f, u, s: levels.append((round(f, 12), len(solver.trials), s.path_state)),
    )
    full = solver.trials
    for k in range(1, len(levels) - 1):
        factor, tried, state = levels[k]
        resumed = FakeSolver(largest=0.15, iterations=9)
        resumed.reached = factor
        resume = Resume(factor, np.zeros(3), (levels[k - 1][0], np.zeros(3)), state)
        follow_load_path(FakeLevels(), resumed, controller, resume=resume)
        assert resumed.trials == full[tried:], factor


class CreepsDown(NeedsIterations):
    """``NeedsIterations`` whose steps down across the load factor ``fold`` need ``creep``
    iterations (the folds rearranging as the pressure falls), from the last level it
    converged at."""

    def __init__(self, needed, creep, fold, default=True):
        super().__init__(needed, default)
        self.creep, self.fold, self.last = creep, fold, None

    def solve(self, problem, start, at_start=None, iterations=None):
        factor = problem.load_factor
        if self.last is None or not self.last > self.fold >= factor:
            result = super().solve(problem, start, at_start, iterations)
        else:
            limit = self.max_iterations if iterations is None else iterations
            self.calls.append((round(factor, 12), limit))
            if self.creep > limit:
                raise ConvergenceError(f"not converged in {limit} iterations", [])
            result = SolverResult(np.full(start.size, factor), self.creep, [], at_start)
        self.last = factor
        return result


class CreepsUp(NeedsIterations):
    """``NeedsIterations`` whose steps up across the load factor ``fold`` need ``creep``
    iterations (the sheet going slack round a node pushed back through its plane), and whose
    steps beyond ``limit`` diverge."""

    def __init__(self, creep, fold, limit=2.0, default=True):
        super().__init__(5, default)
        self.creep, self.fold, self.limit, self.last = creep, fold, limit, 0.0

    def solve(self, problem, start, at_start=None, iterations=None):
        factor = problem.load_factor
        if not self.last < self.fold <= factor and factor <= self.limit:
            result = super().solve(problem, start, at_start, iterations)
        else:
            limit = self.max_iterations if iterations is None else iterations
            self.calls.append((round(factor, 12), limit))
            if factor > self.limit:
                raise Diverging("the solve diverges", [])
            if self.creep > limit:
                raise ConvergenceError(f"not converged in {limit} iterations", [])
            result = SolverResult(np.full(start.size, factor), self.creep, [], at_start)
        self.last = factor
        return result


def test_a_step_up_that_fails_is_tried_again_with_the_creep_budget():
    """Worked by hand, rule 9 under load control, 4 steps, a step across load factor 0.4
    needing 250 iterations: 0.25 converges with 100 (5 iterations); 0.5 fails with 100 and
    is tried again at the same increment with 400, where it converges; 0.75 and 1 follow
    with 100. Needing 500, 0.5's retry fails too and the step is cut back to 0.375 (100,
    an easy step: the increment grows back to 0.25), whose own next step, 0.625, gets the
    budget again (one retry a level). A step that diverges is cut back at once, and a user's
    limit holds everywhere (no retry). From a start that is not the reference state the
    first step is tried again too."""
    solver = CreepsUp(250, fold=0.4)
    follow_load_path(FakeLevels(), solver, SolverSettings(steps=4).controller())
    assert solver.calls == [(0.25, 100), (0.5, 100), (0.5, 400), (0.75, 100), (1.0, 100)]
    solver = CreepsUp(500, fold=0.4)
    with pytest.raises(ConvergenceError):
        follow_load_path(FakeLevels(), solver, SolverSettings(steps=4, min_step=0.1).controller())
    assert solver.calls[:6] == [
        (0.25, 100),
        (0.5, 100),
        (0.5, 400),
        (0.375, 100),
        (0.625, 100),
        (0.625, 400),
    ]
    solver = CreepsUp(5, fold=0.4, limit=0.6)
    with pytest.raises(ConvergenceError, match="diverges"):
        follow_load_path(FakeLevels(), solver, SolverSettings(steps=4, min_step=0.1).controller())
    assert solver.calls == [(0.25, 100), (0.5, 100), (0.75, 100), (0.625, 100)]
    solver = CreepsUp(250, fold=0.4, default=False)
    with pytest.raises(ConvergenceError):
        follow_load_path(FakeLevels(), solver, SolverSettings(steps=4, min_step=0.1).controller())
    assert solver.calls[:3] == [(0.25, 100), (0.5, 100), (0.375, 100)]
    # from a state that is not the reference one (an analysis step's start), the first
    # step too is tried again before the end of the path is solved first (rule 3)
    solver = CreepsUp(250, fold=0.2)
    follow_load_path(FakeLevels(), solver, SolverSettings(steps=4).controller(), u0=np.ones(3))
    assert solver.calls == [(0.25, 100), (0.25, 400), (0.5, 100), (0.75, 100), (1.0, 100)]


def test_a_step_down_that_fails_is_tried_again_with_the_creep_budget():
    """Worked by hand, rule 8, 4 steps, a step down across load factor 0.6 needing 250
    iterations: the first step (100) fails from rest, the end is solved with 400 (rule 7),
    0.75 with 100 (5 iterations); 0.5 fails with 100 and is tried again at the cut
    increment, 0.625, with 400 (5 iterations: the increment grows back to 0.25); 0.375
    then crosses 0.6, fails with 100, and its retry 0.5 converges with 400 (250); 0.375
    and 0.125 follow with 100. Needing 500 to cross, 0.5's retry with 400 fails too, and
    0.5625 gets 100 again: one retry with the budget a level. A user's limit holds
    everywhere (the end from rest then fails, and the first step is cut back)."""
    solver = CreepsDown(250, creep=250, fold=0.6)
    follow_load_path(FakeLevels(), solver, SolverSettings(steps=4).controller())
    assert solver.calls == [
        (0.25, 100),
        (1.0, 400),
        (0.75, 100),
        (0.5, 100),
        (0.625, 400),
        (0.375, 100),
        (0.5, 400),
        (0.375, 100),
        (0.125, 100),
    ]
    settings = SolverSettings(steps=4, min_step=0.05)
    solver = CreepsDown(250, creep=500, fold=0.6)
    with pytest.raises(ConvergenceError, match="not converged in 100"):
        follow_load_path(FakeLevels(), solver, settings.controller())
    assert solver.calls[3:8] == [(0.5, 100), (0.625, 400), (0.375, 100), (0.5, 400), (0.5625, 100)]
    solver = CreepsDown(250, creep=250, fold=0.6, default=False)
    with pytest.raises(ConvergenceError, match="not converged in 100"):
        follow_load_path(FakeLevels(), solver, settings.controller())
    assert solver.calls == [(0.25, 100), (1.0, 100), (0.125, 100), (0.0625, 100)]
