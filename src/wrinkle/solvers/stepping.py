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
the problem harder, not easier. Other path followers (arc length, volume control) and several
analysis steps belong beside it, on the same ``LoadLevels``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from wrinkle.solvers.base import (
    ConvergenceError,
    Evaluation,
    Problem,
    RegularisedSolver,
    SolverResult,
    StopRule,
    is_converged,
    try_evaluate,
)
from wrinkle.timing import Stopwatch

__all__ = [
    "LoadLevels",
    "StepController",
    "SteppedProblem",
    "descend",
    "extrapolate",
    "follow_load_path",
    "solve_step",
    "tangent_prediction",
]

logger = logging.getLogger("wrinkle")

_END = 1e-12  # a load factor within this of 1 is the end of the path


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


@dataclass(frozen=True)
class StepController:
    """Increments of the load factor.

    first_step: the first increment; min_step: the smallest increment a cut-back may reach
    (a failure below it ends the path); max_step: the largest increment; cutback: factor on
    the increment after a failed step, in (0, 1); growth: factor on the increment after a
    step that converged in at most target_iterations iterations (an easy step), >= 1;
    look_ahead: if the first step fails, try the end of the path from the same start before
    cutting back, and reach the levels below it downwards (``follow_load_path``).
    """

    first_step: float = 1.0
    min_step: float = 1e-4
    max_step: float = 1.0
    cutback: float = 0.5
    growth: float = 2.0
    target_iterations: int = 6
    look_ahead: bool = True

    def first(self) -> float:
        """The first increment."""
        return min(self.first_step, self.max_step)

    def after_failure(self, increment: float) -> float | None:
        """The increment to retry with after a failed step, or None below ``min_step``."""
        smaller = increment * self.cutback
        return None if smaller < self.min_step else smaller

    def after_success(self, increment: float, iterations: int) -> float:
        """The next increment after a step that converged in ``iterations``."""
        if iterations <= self.target_iterations and increment < self.max_step:
            return min(self.max_step, self.growth * increment)
        return increment


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


def solve_step(
    problem: SteppedProblem,
    u: np.ndarray,
    solver: RegularisedSolver,
    predicted: np.ndarray | None = None,
    trusted: bool = False,
    stop: StopRule | None = None,
) -> SolverResult:
    """Solve one load level from the displacements u (n_dofs,).

    predicted: a guess of the solution, (n_dofs,), such as the extrapolation from the
    previous steps. Without one, where the step moves the constrained components, the guess
    is the tangent prediction (``tangent_prediction``; solvers with ``tangent_predictor``
    only). The solve starts from the guess, with the new prescribed values, instead of from
    u if the guess is in balance already (one evaluation of the forces) or its out-of-balance
    force is smaller (two), or, if ``trusted`` (a solution of a coarser mesh), always.
    stop: a rule that may end the solve before the residual test, used from a trusted guess
    only (``wrinkle.solvers.stopping``). Raises ConvergenceError if the solver fails.
    """
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
            return solver.solve(problem, guess, at_guess, stop=stop)
        if at_guess is not None:
            if not is_converged(at_guess, solver.tolerance):
                at_start = try_evaluate(problem, start, stiffness=False)
            if at_start is None or at_guess.residual_norm < at_start.residual_norm:
                logger.info("load factor %.6g starts from the %s", problem.load_factor, source)
                start, at_start = guess, at_guess
    return solver.solve(problem, start, at_start)


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
    ``top`` last, or None if a step fails at the smallest increment. Valid for elastic
    (path-independent) problems, which every material of wrinkle is."""
    factor, u, _ = top
    levels = [top]
    above: tuple[float, np.ndarray] | None = None
    increment = controller.first()
    while factor - increment > _END:
        trial_factor = factor - increment
        problem = _problem_at(system, trial_factor, timer)
        predicted = extrapolate(above, factor, u, trial_factor)
        try:
            solved = solve_step(problem, u, solver, predicted=predicted)
        except ConvergenceError:
            smaller = controller.after_failure(increment)
            if smaller is None:
                return None
            increment = smaller
            logger.info("step down to %.6g failed; increment cut to %.4g", trial_factor, increment)
            continue
        above = (factor, u)
        factor, u = trial_factor, solved.u
        logger.info(
            "load factor %.6g converged in %d iterations (downwards)", factor, solved.iterations
        )
        levels.append((factor, u, solved))
        increment = controller.after_success(increment, solved.iterations)
    return levels[::-1]


def _from_the_end(
    system: LoadLevels,
    solver: RegularisedSolver,
    controller: StepController,
    u: np.ndarray,
    timer: Stopwatch | None,
    first_guess: FirstGuess | None,
    first_stop: FirstStop | None,
) -> list[Level] | None:
    """The look-ahead after a failed first step: the end of the path (load factor 1) solved
    from the start u, then the levels below it (``descend``); None if either fails."""
    logger.info("the first step failed: solving the end of the path first, then downwards")
    problem = _problem_at(system, 1.0, timer)
    predicted = None if first_guess is None else first_guess(1.0)
    stop = None if predicted is None or first_stop is None else first_stop(1.0)
    try:
        solved = solve_step(
            problem, u, solver, predicted=predicted, trusted=predicted is not None, stop=stop
        )
    except ConvergenceError:
        logger.info("the end of the path failed as well; cutting the first step back")
        return None
    logger.info("load factor 1 converged in %d iterations", solved.iterations)
    levels = descend(system, solver, controller, (1.0, solved.u, solved), timer)
    if levels is None:
        logger.info("a step down from the end of the path failed; cutting the first step back")
    return levels


def follow_load_path(
    system: LoadLevels,
    solver: RegularisedSolver,
    controller: StepController,
    u0: np.ndarray | None = None,
    on_step: OnStep | None = None,
    timer: Stopwatch | None = None,
    first_guess: FirstGuess | None = None,
    first_stop: FirstStop | None = None,
) -> np.ndarray:
    """Load control from load factor 0 to 1: increments from ``controller``, each step
    solved by ``solve_step`` from the extrapolation of the last two converged states (u0, or
    zero, being the state at load factor 0) or, for the first, the tangent prediction.

    If the first step fails and ``controller.look_ahead``, load factor 1 is solved from the
    start, and the levels below it downwards (``descend``); if both succeed they are the
    path, reported in increasing load factor; otherwise the first step is cut back as any
    failed step is.
    on_step(load_factor, u, solved) is called after each converged step (u (n_dofs,), solved
    the ``SolverResult``); timer: a stopwatch the problems share (the time of their parts);
    first_guess(load_factor): a start for the first step, (n_dofs,), or None, such as the
    solution of coarser meshes interpolated (``wrinkle.sequencing``), used without the
    comparison of ``solve_step``; first_stop(load_factor): a rule that may end the solve from
    that start (``wrinkle.solvers.stopping``), or None.
    Returns the displacements at load factor 1. Raises ConvergenceError, with ``reached``
    (the last converged load factor) set, when a step fails at the smallest increment.
    """
    u = np.zeros(system.n_dofs) if u0 is None else np.array(u0, dtype=float)
    increment = controller.first()
    factor = 0.0
    previous: tuple[float, np.ndarray] | None = None  # the converged state before the last
    looked_ahead = not controller.look_ahead
    while factor < 1.0 - _END:
        trial_factor = min(1.0, factor + increment)
        problem = _problem_at(system, trial_factor, timer)
        predicted = extrapolate(previous, factor, u, trial_factor)
        trusted, stop = False, None
        if previous is None and first_guess is not None:
            predicted = first_guess(trial_factor)
            trusted = predicted is not None
            if trusted and first_stop is not None:
                stop = first_stop(trial_factor)
        try:
            solved = solve_step(problem, u, solver, predicted=predicted, trusted=trusted, stop=stop)
        except ConvergenceError as error:
            if previous is None and trial_factor >= 1.0 - _END:
                looked_ahead = True  # the end of the path failed from this start already
            elif previous is None and not looked_ahead:
                looked_ahead = True
                levels = _from_the_end(
                    system, solver, controller, u, timer, first_guess, first_stop
                )
                if levels is not None:
                    for level in levels:
                        if on_step is not None:
                            on_step(*level)
                    return levels[-1][1]
            smaller = controller.after_failure(increment)
            if smaller is None:
                failure = ConvergenceError(
                    f"load step to factor {trial_factor:.6g} failed with increment "
                    f"{increment:.3g} (minimum {controller.min_step:.3g}): {error}",
                    error.history,
                )
                failure.reached = factor
                raise failure from error
            increment = smaller
            logger.info("step to %.6g failed; increment cut to %.4g", trial_factor, increment)
            continue
        previous = (factor, u)
        factor, u = trial_factor, solved.u
        logger.info("load factor %.6g converged in %d iterations", factor, solved.iterations)
        if on_step is not None:
            on_step(factor, u, solved)
        increment = controller.after_success(increment, solved.iterations)
    return u
