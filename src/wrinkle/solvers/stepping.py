"""Following a load path: the step controller, the predictors and the load-control loop.

Loads and prescribed displacements grow in proportion to a load factor from 0 to 1. The
``StepController`` chooses the increments (cut back after a failed step, grown after easy
ones); each step starts from a prediction where it is closer to balance than the last
converged state (``solve_step``): the linear extrapolation of the last two converged states
(``extrapolate``) or, for a step that moves supports and has no extrapolation, the tangent
prediction (``tangent_prediction``). ``follow_load_path`` runs the loop and calls back on
each converged step. If the first step fails, the end of the path is tried before any
cut-back, and the levels below it are reached downwards from there (``descend``): a small
pressure on a flat sheet is harder than the full one, so cutting the first step back makes
the problem harder, not easier. The other path followers, arc length
(``wrinkle.solvers.arc_length``) and volume control and gas loads
(``wrinkle.solvers.control``), work beside it on the same ``LoadLevels``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from wrinkle.solvers.base import (
    ConvergenceError,
    Diverging,
    Evaluation,
    Problem,
    RegularisedSolver,
    SolverResult,
    StopRule,
    is_converged,
    try_evaluate,
)
from wrinkle.solvers.stability import UNSTABLE, unstable_modes
from wrinkle.timing import Stopwatch

__all__ = [
    "LIMIT_SLOPE",
    "LoadLevels",
    "PathSlope",
    "Resume",
    "StepController",
    "SteppedProblem",
    "creep_iterations",
    "descend",
    "end_iterations",
    "extrapolate",
    "follow_load_path",
    "retry_iterations",
    "solve_step",
    "tangent_prediction",
]

logger = logging.getLogger("wrinkle")

_END = 1e-12  # a load factor within this of 1 is the end of the path
# A path that fails where its load-displacement slope has fallen below this fraction of the
# first step's has met a limit point of the load (``PathSlope``)
LIMIT_SLOPE = 0.05
# A converged step whose slope is below LIMIT_SLOPE and this many times below the step
# before's has jumped across a limit point to another branch (approaching a maximum of the
# load with cut-back steps, the slope falls by 2-4 times a step)
JUMP = 10.0
# A solve of the end of the path from the unstressed reference state (the first step where it
# is the whole path, and the look-ahead's) may take this many times the method's default
# iterations: cutting it back would give it a smaller load from the same state, which is no
# easier there (a flat sheet under a smaller pressure is harder; docs/solvers.md, "The step
# controller")
END_ROUNDS = 4
# ... or, where more, this many times the square root of the free unknowns: a pure
# membrane's folds creep about a third of an element per iteration, so the iterations from
# the flat sheet grow like 1/h, the square root of the mesh's size (up to 9.2 sqrt(n) measured
# from 800 to 151,000 free unknowns, 24 % apart in two runs of one case;
# docs/notes/2026-12-hard-cases.md, section 4f). Both budgets serve as well the first try
# again after a failed step down a ramp (``descend``), whose folds creep whatever its size.
END_PER_ROOT = 12.0


class SteppedProblem(Problem, Protocol):
    """A problem at one load level: ``Problem`` plus the prescribed values of the constrained
    components (n_dofs,), a stopwatch, and an evaluation with a lift of the constrained
    components (``wrinkle.system.StepProblem.evaluate``)."""

    load_factor: float
    prescribed: np.ndarray
    timer: Stopwatch

    def evaluate(
        self, u: np.ndarray, stiffness: bool = True, lift: np.ndarray | None = None
    ) -> Evaluation: ...


class LoadLevels(Protocol):
    """What a path follower needs of a discrete system (``wrinkle.system.DiscreteSystem``)."""

    n_dofs: int

    def at(
        self, load_factor: float = 1.0, prescribed: np.ndarray | None = None
    ) -> SteppedProblem: ...


FLAT = 1e-9  # a sheet whose nodes lie within this share of its extent of one plane is flat
# said where a path under pressure fails before any load level converges (docs/solvers.md,
# the step controller): the cut-backs of the first step went down to min_step in vain
SMALL_PRESSURE_HINT = (
    "no load level converged; on a membrane that starts flat and unstressed a pressure is "
    "harder the smaller it is, so cutting the step back does not help: raise [solver] "
    "max_iterations (a small pressure creeps to its answer) or give the sheet its bending "
    "stiffness ([material] bending = true; docs/solvers.md, Load stepping)"
)


@dataclass(frozen=True)
class StepController:
    """Increments of the load factor.

    first_step: the first increment; min_step: the smallest increment a cut-back may reach
    (a failure below it ends the path); max_step: the largest increment; cutback: factor on
    the increment after a failed step, in (0, 1); growth: factor on the increment after a
    step that converged in at most target_iterations iterations (an easy step), >= 1;
    regrow_after: after a cut-back, this many steps in a row converged at the cut increment
    let it grow by ``growth`` whatever their iterations (0: only easy steps do);
    look_ahead: if the first step fails, try the end of the path from the same start before
    cutting back, and reach the levels below it downwards (``follow_load_path``).
    """

    first_step: float = 1.0
    min_step: float = 1e-4
    max_step: float = 1.0
    cutback: float = 0.5
    growth: float = 2.0
    target_iterations: int = 6
    regrow_after: int = 2
    look_ahead: bool = True

    def first(self) -> float:
        """The first increment."""
        return min(self.first_step, self.max_step)

    def after_failure(self, increment: float) -> float | None:
        """The increment to retry with after a failed step, or None below ``min_step``."""
        smaller = increment * self.cutback
        return None if smaller < self.min_step else smaller

    def after_success(
        self, increment: float, iterations: int, in_a_row: int = 0, needed: int | None = None
    ) -> float:
        """The next increment after a step that converged in ``iterations``, the
        ``in_a_row``-th converged in a row at this increment (0: not counted, as volume
        control does not). A cut increment (below the first) grows after ``needed`` such
        steps (default ``regrow_after``): the cut-back
        answered the step that failed, and a creeping solve takes as many iterations at any
        increment (the load reversed within one run: 23-88 per level at 1/32,
        docs/notes/2026-12-hard-cases.md)."""
        needed = self.regrow_after if needed is None else needed
        easy = iterations <= self.target_iterations
        cut = increment < self.first() * (1.0 - 1e-9)
        regrow = 0 < needed <= in_a_row and cut
        if (easy or regrow) and increment < self.max_step:
            return min(self.max_step, self.growth * increment)
        return increment


class _Increments:
    """A path's increment and what the controller's rules need to change it: the steps
    converged in a row at it, and how many a cut increment needs before it grows again
    (``regrow_after``, doubled each time a step at an increment so regrown fails, so that a
    path that does need the cut increment loses at most a few failed steps to trying)."""

    def __init__(self, controller: StepController, state: Mapping[str, Any] | None = None):
        """The increments of a path from its start, or from a state that ``state`` gave."""
        self.controller = controller
        self.value = controller.first()
        self.in_a_row = 0
        self.needed = controller.regrow_after
        self._regrown = False
        if state is not None:
            self.value = float(state["increment"])
            self.in_a_row = int(state.get("in_a_row", 0))
            self.needed = int(state.get("needed", controller.regrow_after))
            self._regrown = bool(state.get("regrown", False))

    def state(self) -> dict[str, Any]:
        """What a restart needs to go on as this path would: {"increment", "in_a_row",
        "needed", "regrown"} (the summary's "controller" of each step)."""
        return {
            "increment": self.value,
            "in_a_row": self.in_a_row,
            "needed": self.needed,
            "regrown": self._regrown,
        }

    def failed(self) -> bool:
        """Cut the increment back after a failed step; False if it would fall below
        ``min_step`` (the increment is then unchanged)."""
        smaller = self.controller.after_failure(self.value)
        if smaller is None:
            return False
        if self._regrown:
            self.needed *= 2
        self.value, self.in_a_row, self._regrown = smaller, 0, False
        return True

    def converged(self, iterations: int) -> None:
        """The increment after a step at it converged in ``iterations``."""
        self._regrown = False  # a step at a regrown increment converged: it stands
        self.in_a_row += 1
        grown = self.controller.after_success(self.value, iterations, self.in_a_row, self.needed)
        if grown != self.value:
            self._regrown = iterations > self.controller.target_iterations
            self.value, self.in_a_row = grown, 0


def extrapolate(
    previous: tuple[float, np.ndarray] | None, factor: float, u: np.ndarray, trial_factor: float
) -> np.ndarray | None:
    """Linear extrapolation to ``trial_factor`` of the converged states ``previous`` (load
    factor, displacements) and (factor, u), (n_dofs,); None without a previous state."""
    if previous is None:
        return None
    previous_factor, previous_u = previous
    ratio = (trial_factor - factor) / (factor - previous_factor)
    return u + ratio * (u - previous_u)


def tangent_prediction(
    problem: SteppedProblem, u: np.ndarray, solver: RegularisedSolver
) -> np.ndarray | None:
    """The step's first Newton iteration taken from the last converged state u: the
    increment of the prescribed components spread over the free ones through the tangent
    at u, K_ff du_f = f - f*(u) - K_fc du_c (the load increment included), with the
    solver's initial regularisation. Moving the supported nodes alone would strain only the
    elements beside them, which may wrinkle or go slack and lose the stiffness that spreads
    the motion; at u they still have it. None where the prescribed values do not change or
    the tangent cannot be factorised. Returns (n_dofs,) displacements."""
    lift = np.where(problem.free, 0.0, problem.prescribed - u)
    if not np.any(lift):
        return None  # the first iteration from u is this prediction already
    at_u = try_evaluate(problem, u, lift=lift)
    if at_u is None:
        return None
    step = solver.tangent_step(problem, at_u)
    return None if step is None else u + lift + step


def creep_iterations(solver: RegularisedSolver, free: np.ndarray) -> int | None:
    """The iteration limit of a solve that creeps (rules 7, 8 and 9 of the step controller):
    the larger of END_ROUNDS times the solver's and END_PER_ROOT sqrt(n), n the free
    components (free: (n_dofs,) bool), where the limit is the method's default; None (the
    solver's own) otherwise, a limit the user set included."""
    if not getattr(solver, "limit_is_default", False):
        return None
    by_size = math.ceil(END_PER_ROOT * math.sqrt(np.count_nonzero(free)))
    return max(END_ROUNDS * solver.max_iterations, by_size)


def retry_iterations(solver: RegularisedSolver, free: np.ndarray, target: float) -> int | None:
    """The iteration limit of a failed step tried again at the same increment (rule 9 of the
    step controller): ``creep_iterations``, logged with the step's target (load factor or
    path parameter); free (n_dofs,) bool."""
    limit = creep_iterations(solver, free)
    logger.info("step to %.6g failed; tried again with up to %s iterations", target, limit)
    return limit


def end_iterations(solver: RegularisedSolver, u: np.ndarray, free: np.ndarray) -> int | None:
    """The iteration limit of a solve of the end of the path from u (n_dofs,), free (n_dofs,)
    bool its free components: ``creep_iterations`` where u is the reference state (rule 7);
    None (the solver's own) otherwise."""
    limit = None if np.any(u) else creep_iterations(solver, free)
    if limit is not None:
        logger.info("the end of the path from the reference state: up to %d iterations", limit)
    return limit


def solve_step(
    problem: SteppedProblem,
    u: np.ndarray,
    solver: RegularisedSolver,
    predicted: np.ndarray | None = None,
    trusted: bool = False,
    stop: StopRule | None = None,
    iterations: int | None = None,
) -> SolverResult:
    """Solve one load level from the displacements u (n_dofs,).

    predicted: a guess of the solution, (n_dofs,), such as the extrapolation from the
    previous steps. Without one, where the step moves the constrained components, the guess
    is the tangent prediction (``tangent_prediction``; solvers with ``tangent_predictor``
    only). The solve starts from the guess, with the new prescribed values, instead of from
    u if the guess is in balance already (one evaluation of the forces) or its out-of-balance
    force is smaller (two), or, if ``trusted`` (a solution of a coarser mesh), always.
    stop: a rule that may end the solve before the residual test, used from a trusted guess
    only (``wrinkle.solvers.stopping``). iterations: the most iterations of the solve (None:
    the solver's ``max_iterations``). Raises ConvergenceError if the solver fails.
    """
    options: dict[str, Any] = {} if iterations is None else {"iterations": iterations}
    constrained = ~problem.free
    start = np.where(constrained, problem.prescribed, u)
    source = "extrapolated displacements"
    if predicted is None and solver.tangent_predictor:
        predicted = tangent_prediction(problem, u, solver)
        source = "tangent prediction"
    at_start = None
    if predicted is not None:
        guess = np.where(constrained, problem.prescribed, predicted)
        at_guess = try_evaluate(problem, guess, stiffness=False)
        if at_guess is not None and trusted:
            logger.info("load factor %.6g starts from the coarser mesh", problem.load_factor)
            return solver.solve(problem, guess, at_guess, stop=stop, **options)
        if at_guess is not None:
            if not is_converged(at_guess, solver.tolerance):
                at_start = try_evaluate(problem, start, stiffness=False)
            if at_start is None or at_guess.residual_norm < at_start.residual_norm:
                logger.info("load factor %.6g starts from the %s", problem.load_factor, source)
                start, at_start = guess, at_guess
    return solver.solve(problem, start, at_start, **options)


OnStep = Callable[[float, np.ndarray, SolverResult], None]
FirstGuess = Callable[[float], np.ndarray | None]
FirstStop = Callable[[float], StopRule | None]
Level = tuple[float, np.ndarray, SolverResult]  # load factor, displacements, the solve


def _problem_at(system: LoadLevels, load_factor: float, timer: Stopwatch | None) -> SteppedProblem:
    problem = system.at(load_factor)
    if timer is not None:
        problem.timer = timer
    return problem


def descend(
    system: LoadLevels,
    solver: RegularisedSolver,
    controller: StepController,
    top: Level,
    timer: Stopwatch | None = None,
) -> list[Level] | None:
    """The levels below a converged state ``top`` (its load factor, displacements and
    solve), reached downwards towards load factor 0 with the increments of ``controller``
    (cut back after a failure, grown after easy steps), each step started from the
    extrapolation of the two levels above it, as ``follow_load_path`` does upwards. The
    levels are those an upward path would aim at: the top's load factor minus multiples of
    the increment, down to the smallest above 0. Returns them in increasing load factor,
    ``top`` last, or None if a step fails at the smallest increment. The first try again
    after a failure below a level may take ``creep_iterations`` (rule 8 of the step
    controller). Valid for elastic (path-independent) problems, which every material of
    wrinkle is."""
    factor, u, _ = top
    levels = [top]
    above: tuple[float, np.ndarray] | None = None
    increment = _Increments(controller)
    iterations: int | None = None  # the solver's own limit until a step down fails
    budgeted = False  # whether a try at this level had ``creep_iterations``
    while factor - increment.value > _END:
        trial_factor = factor - increment.value
        problem = _problem_at(system, trial_factor, timer)
        predicted = extrapolate(above, factor, u, trial_factor)
        try:
            solved = solve_step(problem, u, solver, predicted=predicted, iterations=iterations)
        except ConvergenceError:
            if not increment.failed():
                return None
            # rule 8: tried again, at the cut increment, with the creep budget; once a level
            iterations = None if budgeted else creep_iterations(solver, problem.free)
            budgeted = True
            logger.info(
                "step down to %.6g failed; increment cut to %.4g%s",
                trial_factor,
                increment.value,
                "" if iterations is None else f", up to {iterations} iterations",
            )
            continue
        iterations, budgeted = None, False
        above = (factor, u)
        factor, u = trial_factor, solved.u
        logger.info(
            "load factor %.6g converged in %d iterations (downwards)", factor, solved.iterations
        )
        levels.append((factor, u, solved))
        increment.converged(solved.iterations)
    return levels[::-1]


def _from_the_end(
    system: LoadLevels,
    solver: RegularisedSolver,
    controller: StepController,
    u: np.ndarray,
    timer: Stopwatch | None,
    first_guess: FirstGuess | None,
    first_stop: FirstStop | None,
    stability: bool,
) -> list[Level] | None:
    """The look-ahead after a failed first step: the end of the path (load factor 1) solved
    from the start u, then the levels below it (``descend``); None if either fails or the
    levels are not a path load control may report (``_checked_levels``: past a limit
    point)."""
    logger.info("the first step failed: solving the end of the path first, then downwards")
    problem = _problem_at(system, 1.0, timer)
    predicted = None if first_guess is None else first_guess(1.0)
    stop = None if predicted is None or first_stop is None else first_stop(1.0)
    iterations = None if predicted is not None else end_iterations(solver, u, problem.free)
    try:
        solved = solve_step(
            problem,
            u,
            solver,
            predicted=predicted,
            trusted=predicted is not None,
            stop=stop,
            iterations=iterations,
        )
    except ConvergenceError:
        logger.info("the end of the path failed as well; cutting the first step back")
        return None
    logger.info("load factor 1 converged in %d iterations", solved.iterations)
    levels = descend(system, solver, controller, (1.0, solved.u, solved), timer)
    if levels is None:
        logger.info("a step down from the end of the path failed; cutting the first step back")
        return None
    beyond = _checked_levels(system, levels, u, solver if stability else None, timer)
    if beyond is not None:
        logger.info("the levels from the end of the path are past a limit point: %s", beyond)
        return None
    return levels


class PathSlope:
    """The load-displacement slope of a path, dlambda / |du| over each converged step,
    relative to the first step's (Bergan's current stiffness parameter, with the
    displacement norm for the work). It falls towards zero as the path nears a limit point
    of the load, where load control cannot go on: a path that fails with the slope below
    LIMIT_SLOPE and falling has met one (``limit_point``), and a step whose slope drops
    below LIMIT_SLOPE and JUMP times below the step before's has jumped across one to
    another branch (``jump``)."""

    def __init__(self, u0: np.ndarray, factor: float = 0.0):
        self._factor, self._u = factor, u0
        self.relative: list[float] = []  # each converged step's slope over the first's
        self._first: float | None = None

    def _slope(self, factor: float, u: np.ndarray) -> float | None:
        """dlambda / |du| of a step from the last recorded state to (factor, u), or None
        where it moved nothing or the load did not grow."""
        moved = float(np.linalg.norm(u - self._u))
        if not (moved > 0.0 and factor > self._factor):
            return None
        return (factor - self._factor) / moved

    def jump(self, factor: float, u: np.ndarray) -> str | None:
        """How a step to ``factor`` with displacements u (n_dofs,) jumped across a limit
        point, or None if it did not."""
        slope = self._slope(factor, u)
        if slope is None or self._first is None or not self.relative:
            return None
        relative = slope / self._first
        if relative < LIMIT_SLOPE and relative * JUMP < self.relative[-1]:
            return (
                f"the step from load factor {self._factor:.6g} to {factor:.6g} jumped to "
                f"another branch (its displacements changed by {np.linalg.norm(u - self._u):.3g}"
                f"; the load-displacement slope fell to {relative:.2g} of the first step's)"
            )
        return None

    def record(self, factor: float, u: np.ndarray) -> None:
        """A converged step to ``factor`` with displacements u (n_dofs,), accepted."""
        slope = self._slope(factor, u)
        if slope is not None:
            if self._first is None:
                self._first = slope
            self.relative.append(slope / self._first)
        self._factor, self._u = factor, u

    def limit_point(self) -> float | None:
        """The relative slope of the last step if the path has met a limit point there
        (below LIMIT_SLOPE and below the step before's), else None."""
        if len(self.relative) < 2:
            return None
        last, before = self.relative[-1], self.relative[-2]
        return last if last < LIMIT_SLOPE and last < before else None


class PastALimit(ConvergenceError):
    """A step that balanced in a state beyond a limit point of the load: unstable, or
    reached by a jump to another branch; treated as a failed step (cut back)."""


def _check_state(
    solved: SolverResult,
    factor: float,
    slope: PathSlope,
    stability: tuple[RegularisedSolver, SteppedProblem] | None,
) -> None:
    """Raise PastALimit if the state a step reached at load factor ``factor`` jumped across
    a limit point (``PathSlope.jump``) or, with ``stability`` (the solver and the step's
    problem), is unstable (``wrinkle.solvers.stability``)."""
    if stability is not None:
        solver, problem = stability
        ev = solved.evaluation
        if ev.stiffness is None:  # a start already in balance: evaluated without it
            ev = try_evaluate(problem, solved.u) or ev
        count = None if ev.stiffness is None else unstable_modes(solver, ev, problem.free)
        if count:
            raise PastALimit(
                f"the state reached at load factor {factor:.6g} is unstable: its tangent has "
                f"{count} eigenvalue(s) below -{UNSTABLE:g} of its mean diagonal stiffness",
                solved.residual_norms,
            )
    jumped = slope.jump(factor, solved.u)
    if jumped is not None:
        raise PastALimit(jumped, solved.residual_norms)


def _checked_levels(
    system: LoadLevels,
    levels: list[Level],
    u0: np.ndarray,
    stability: RegularisedSolver | None,
    timer: Stopwatch | None,
) -> str | None:
    """Why the levels (increasing load factor, from the start u0 at load factor 0) are not
    a path that load control may report (``_check_state``; stability: the solver, to check
    each state's stability), or None if they are."""
    slope = PathSlope(u0)
    for factor, u, solved in levels:
        checks = None
        if stability is not None:
            checks = (stability, _problem_at(system, factor, timer))
        try:
            _check_state(solved, factor, slope, checks)
        except PastALimit as error:
            return str(error)
        slope.record(factor, u)
    return None


def _limit_point_error(
    factor: float,
    what: str,
    describe_load: Callable[[float], str] | None,
    history: list[float],
) -> ConvergenceError:
    """The ConvergenceError of a path that met a limit point of the load after load factor
    ``factor`` (its last step on the branch followed); what: how it showed."""
    load = "" if describe_load is None else f" ({describe_load(factor)})"
    failure = ConvergenceError(
        f"limit point passed near load factor {factor:.6g}{load}: {what}; load control "
        'cannot pass a maximum of the load: use [solver] control = "arc-length" or '
        '"volume"',
        history,
    )
    failure.reached = failure.limit_point = factor
    return failure


@dataclass(frozen=True)
class Resume:
    """Where a load path continues (``wrinkle run --restart``): the last converged state
    (load factor ``factor``, displacements ``u`` (n_dofs,)), the converged state before it
    (``previous``: load factor and displacements; (0, u at load factor 0) after the first
    step), and the step controller's state (``_Increments.state``: the increment the path
    takes next, the steps converged in a row at it, ...)."""

    factor: float
    u: np.ndarray
    previous: tuple[float, np.ndarray]
    controller: Mapping[str, Any]


def _under_pressure(system: LoadLevels, u: np.ndarray) -> bool:
    """Whether ``SMALL_PRESSURE_HINT`` applies to a path that starts at u (n_dofs,): the
    system's loads include a pressure (a ``DiscreteSystem``'s ``loading``), the sheet has no
    bending stiffness (the hint names it as the remedy), and at u it is flat and unstressed
    (``_flat_and_unstressed``), the state the hint is about."""
    loading = getattr(system, "loading", None)
    if loading is None or getattr(system, "bending", None) is not None:
        return False
    return bool(np.any(loading.pressure)) and _flat_and_unstressed(system, u)


def _flat_and_unstressed(system: LoadLevels, u: np.ndarray) -> bool:
    """Whether the sheet at u (n_dofs,) lies in one plane, to FLAT times its extent (the
    smallest principal extent of the nodes' current positions), and carries no stress (its
    internal forces within the round-off of the convergence test; a prestress is a stress).
    A balloon, a sheet already inflated, stretched or prestressed is not: for those a small
    pressure is no harder than a large one."""
    mesh, forces = getattr(system, "mesh", None), getattr(system, "internal_forces", None)
    if mesh is None or forces is None:
        return False
    x = mesh.nodes + u.reshape(-1, 3)
    centred = x - x.mean(axis=0)
    spread = np.sqrt(np.maximum(np.linalg.eigvalsh(centred.T @ centred), 0.0))
    if spread[0] > FLAT * spread[-1]:
        return False
    return float(np.linalg.norm(forces(u))) <= float(getattr(system, "force_round_off", 0.0))


def follow_load_path(
    system: LoadLevels,
    solver: RegularisedSolver,
    controller: StepController,
    u0: np.ndarray | None = None,
    on_step: OnStep | None = None,
    timer: Stopwatch | None = None,
    first_guess: FirstGuess | None = None,
    first_stop: FirstStop | None = None,
    describe_load: Callable[[float], str] | None = None,
    stability: bool = False,
    resume: Resume | None = None,
) -> np.ndarray:
    """Load control from load factor 0 to 1: increments from ``controller``, each step
    solved by ``solve_step`` from the extrapolation of the last two converged states (u0, or
    zero, being the state at load factor 0) or, for the first, the tangent prediction.

    If the first step fails and ``controller.look_ahead``, load factor 1 is solved from the
    start, and the levels below it downwards (``descend``); if both succeed they are the
    path, reported in increasing load factor; otherwise the first step is cut back as any
    failed step is. A solve of the end of the path from the reference state (this one, or
    the first step where it is the whole path) may take END_ROUNDS times the method's default
    iterations, or END_PER_ROOT times the square root of the free unknowns where more
    (``end_iterations``); so may the first try again after a failed step downwards
    (``descend``), and a step that failed, tried again once at the same increment before
    anything else (rule 9, once a level; not the first step from the reference state, nor a
    step that jumped past a limit point or diverged).
    on_step(load_factor, u, solved) is called after each converged step (u (n_dofs,), solved
    the ``SolverResult``); timer: a stopwatch the problems share (the time of their parts);
    first_guess(load_factor): a start for the first step, (n_dofs,), or None, such as the
    solution of coarser meshes interpolated (``wrinkle.sequencing``), used without the
    comparison of ``solve_step``; first_stop(load_factor): a rule that may end the solve from
    that start (``wrinkle.solvers.stopping``), or None; describe_load(load_factor): the loads
    at a load factor in words (such as "pressure 4958"), for the message of a limit point;
    stability: check that each converged state is stable (``wrinkle.solvers.stability``, one
    factorisation a step), and end the path at the first that is not. resume: continue a
    path from its last converged state (``Resume``) as it would have gone on: the same
    increments and extrapolations, so the same steps (u0 and first_guess are then unused).
    Returns the displacements at load factor 1. Raises ConvergenceError, with ``reached``
    (the last converged load factor) set, when a step fails at the smallest increment; where
    the load-displacement slope had fallen to a limit point of the load there
    (``PathSlope``), its message says so first and its ``limit_point`` is that load factor.
    A step that jumps across a limit point (``PathSlope.jump``) or, with ``stability``,
    reaches an unstable state is a failed step (``PastALimit``), cut back like any other.
    """
    u = np.zeros(system.n_dofs) if u0 is None else np.array(u0, dtype=float)
    slope = PathSlope(u)
    increment = _Increments(controller)
    factor = 0.0
    previous: tuple[float, np.ndarray] | None = None  # the converged state before the last
    looked_ahead = not controller.look_ahead
    retry = False  # the next try is the step that failed, with the creep budget (rule 9)
    budgeted = False  # whether a try from this level had the creep budget
    if resume is not None:
        factor, u = resume.factor, np.array(resume.u, dtype=float)
        previous = resume.previous
        increment = _Increments(controller, resume.controller)
        slope = PathSlope(previous[1], previous[0])
        slope.record(factor, u)
        looked_ahead = True
    while factor < 1.0 - _END:
        trial_factor = min(1.0, factor + increment.value)
        problem = _problem_at(system, trial_factor, timer)
        predicted = extrapolate(previous, factor, u, trial_factor)
        trusted, stop = False, None
        if previous is None and first_guess is not None:
            predicted = first_guess(trial_factor)
            trusted = predicted is not None
            if trusted and first_stop is not None:
                stop = first_stop(trial_factor)
        checks = (solver, problem) if stability else None
        iterations = None
        if previous is None and not trusted and trial_factor >= 1.0 - _END:
            iterations = end_iterations(solver, u, problem.free)  # the whole path in one step
        elif retry:  # rule 9: the step that failed, again with the creep budget
            iterations = retry_iterations(solver, problem.free, trial_factor)
        budgeted, retry = budgeted or iterations is not None, False
        try:
            solved = solve_step(
                problem,
                u,
                solver,
                predicted=predicted,
                trusted=trusted,
                stop=stop,
                iterations=iterations,
            )
            _check_state(solved, trial_factor, slope, checks)
        except ConvergenceError as error:
            # rule 9: tried again at the same increment with the creep budget, once a level;
            # not the first step from the reference state (rules 3 and 7), nor a jump past a
            # limit point or a divergence
            if (
                (previous is not None or np.any(u))
                and not budgeted
                and getattr(solver, "limit_is_default", False)
                and not isinstance(error, Diverging | PastALimit)
            ):
                retry = True
                continue
            if previous is None and trial_factor >= 1.0 - _END:
                looked_ahead = True  # the end of the path failed from this start already
            elif previous is None and not looked_ahead:
                looked_ahead = True
                levels = _from_the_end(
                    system, solver, controller, u, timer, first_guess, first_stop, stability
                )
                if levels is not None:
                    for level in levels:
                        if on_step is not None:
                            on_step(*level)
                    return levels[-1][1]
            if not increment.failed():
                message = (
                    f"load step to factor {trial_factor:.6g} failed with increment "
                    f"{increment.value:.3g} (minimum {controller.min_step:.3g}): {error}"
                )
                # (not where it diverged: that is no small pressure creeping)
                if (
                    previous is None
                    and _under_pressure(system, u)
                    and not isinstance(error, Diverging)
                ):
                    message += f"; {SMALL_PRESSURE_HINT}"
                relative = slope.limit_point()
                if relative is not None or isinstance(error, PastALimit):
                    fell = (
                        ""
                        if relative is None
                        else (
                            f"the load-displacement slope fell to {relative:.2g} of the first "
                            "step's and "
                        )
                    )
                    raise _limit_point_error(
                        factor,
                        f"{fell}no step beyond it converged to a stable state on its branch "
                        f"({message})",
                        describe_load,
                        error.history,
                    ) from error
                failure = ConvergenceError(message, error.history)
                failure.reached = factor
                raise failure from error
            logger.info("step to %.6g failed; increment cut to %.4g", trial_factor, increment.value)
            continue
        slope.record(trial_factor, solved.u)
        previous = (factor, u)
        factor, u = trial_factor, solved.u
        budgeted = False
        logger.info("load factor %.6g converged in %d iterations", factor, solved.iterations)
        increment.converged(solved.iterations)
        solved.path_state = increment.state()
        if on_step is not None:
            on_step(factor, u, solved)
    return u
