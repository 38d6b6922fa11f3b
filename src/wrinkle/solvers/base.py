"""What the nonlinear solvers need from a problem, and what they give back."""

from __future__ import annotations

import logging
import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, replace
from typing import Any, Protocol

import numpy as np
import scipy.sparse as sp

from wrinkle.memory import kept_memory
from wrinkle.solvers.linear import (
    FreeBlock,
    Matrix,
    SuperLU,
    SymmetryCheck,
    diagonal_positions,
    make_linear_solver,
    with_values,
)
from wrinkle.threads import blas_threads
from wrinkle.timing import LINEAR, Stopwatch

__all__ = [
    "AcceptedStep",
    "ConvergenceError",
    "Diverging",
    "Evaluation",
    "EvaluationFailure",
    "InadmissibleState",
    "LinearSolver",
    "Problem",
    "RegularisedSolver",
    "SolverResult",
    "StopRule",
    "deferring",
    "is_converged",
    "IterationListener",
    "listening",
    "log_iteration",
    "shifted",
    "stiffness_scale",
    "try_evaluate",
    "with_values",
]

logger = logging.getLogger("wrinkle.solver")


@dataclass
class Evaluation:
    """A problem evaluated at one displacement vector.

    residual: (n_dofs,) out-of-balance force f - f* (external minus internal), zero at
        constrained dofs; force units.
    energy: potential energy (nan where the loads have no potential).
    force_scale: size of the applied and reaction forces and of the prescribed motion,
        max(|f_ext|, |reactions|, F_motion) (``DiscreteSystem.motion_force``), for the
        convergence criterion.
    states: (taut, wrinkled, slack) element counts.
    stiffness: tangent stiffness dF*/du with constrained rows and columns replaced by the
        identity, CSR; None unless asked for.
    round_off: residual norm that round-off alone can produce (force); a residual below it
        counts as converged whatever the tolerance.
    symmetric: whether the stiffness is symmetric (no follower loads).
    diagonal: (n_dofs,) positions of the diagonal entries in stiffness.data, if the problem
        knows them (its fixed sparsity pattern); found from the matrix otherwise.
    metric: data, on the stiffness' own sparsity pattern, of a positive semidefinite matrix
        (zero in constrained rows and columns) in which the Newton solver measures its steps;
        None for the identity.
    reactions: (n_dofs,) internal minus external force at the constrained dofs, zero
        elsewhere (the support reactions), if the problem gives them.
    admissibility: a function giving why the state is not a physical one (collapsed
        elements or enclosed volume), or None if it is one; called only for a balanced state
        (``inadmissible``), not for every trial point. None: every state is physical.
    elements: the problem's element results at u, where the caller asked it to keep them
        (the sensitivities of ``wrinkle.identification``); None otherwise.
    later: where the stiffness was deferred (``wrinkle.system.StepProblem.evaluate`` with
        ``defer``), the function that forms it (``with_stiffness``); None otherwise.
    divergence: a function giving why the state shows the solve diverging (an element
        stretched beyond any membrane), or None; called for accepted iterates
        (``diverging``). None: never.
    """

    residual: np.ndarray
    energy: float
    force_scale: float
    states: tuple[int, int, int]
    stiffness: sp.csr_matrix | None = None
    round_off: float = 0.0
    symmetric: bool = True
    diagonal: np.ndarray | None = None
    metric: np.ndarray | None = None
    reactions: np.ndarray | None = None
    admissibility: Callable[[], str | None] | None = None
    elements: Any = None
    later: Callable[[], sp.csr_matrix] | None = None
    divergence: Callable[[], str | None] | None = None

    def with_stiffness(self) -> Evaluation:
        """This evaluation with its deferred stiffness formed (``later``); itself where the
        stiffness is there already or was not asked for."""
        if self.stiffness is not None or self.later is None:
            return self
        return replace(self, stiffness=self.later(), later=None)

    @property
    def inadmissible(self) -> str | None:
        """Why the state is not a physical one, or None (``admissibility``); a solve never
        ends on such a state."""
        return None if self.admissibility is None else self.admissibility()

    @property
    def diverging(self) -> str | None:
        """Why the state shows the solve diverging, or None (``divergence``): a solve stops
        there."""
        return None if self.divergence is None else self.divergence()

    @property
    def residual_norm(self) -> float:
        return float(np.linalg.norm(self.residual))

    @property
    def tangent(self) -> sp.csr_matrix:
        """The stiffness of an evaluation made with it (ValueError if made without)."""
        if self.stiffness is None:
            raise ValueError("this evaluation was made without the stiffness")
        return self.stiffness


class LinearSolver(Protocol):
    """A sparse linear back-end (``wrinkle.solvers.linear``): a solve function for A, or None
    if A is singular."""

    def factorise(
        self, A: Matrix, symmetric: bool
    ) -> Callable[[np.ndarray], np.ndarray] | None: ...

    def release(self) -> None:
        """Free the memory of its factorisations (PARDISO's is outside Python's reach)."""
        ...


class Problem(Protocol):
    """A discretised nonlinear problem with fixed constraints."""

    free: np.ndarray  # (n_dofs,) bool

    def evaluate(self, u: np.ndarray, stiffness: bool = True) -> Evaluation: ...


@dataclass(frozen=True)
class AcceptedStep:
    """One accepted iteration of a solve.

    energy: the potential energy after it (J; nan without a potential); predicted: the
    decrease of the merit its model predicted for the full step; rho: actual over predicted
    decrease; full: whether the full step was taken (not a shortened one, ``backtrack``);
    theta: its regularisation; u: the displacements after it (n_dofs,); evaluation: there.
    """

    energy: float
    predicted: float
    rho: float
    full: bool
    theta: float
    u: np.ndarray
    evaluation: Evaluation


class StopRule(Protocol):
    """A test that may end a solve before the residual test does
    (``wrinkle.solvers.stopping.AccuracyStop``): called with the start of one solve (as a
    step with rho nan) and then after each accepted iteration, it returns a report (a dict
    of the numbers it decided on) to stop at that step, or None to go on. A rule keeps what
    it needs of earlier steps; one rule serves one solve."""

    def __call__(self, step: AcceptedStep) -> dict[str, Any] | None: ...


@dataclass
class SolverResult:
    """A converged solve: displacements (n_dofs,), iteration count, residual history, the
    last evaluation, which test ended it (``stopped_by``: "residual", or "accuracy" with
    ``stop_report`` the numbers the stop rule decided on); ``path_state``: where a load path
    solved it, the step controller's state after it (``stepping._Increments.state``), which a
    restart continues from."""

    u: np.ndarray
    iterations: int
    residual_norms: list[float]
    evaluation: Evaluation  # at u
    stopped_by: str = "residual"
    stop_report: dict[str, Any] | None = None
    path_state: dict[str, Any] | None = None


class ConvergenceError(RuntimeError):
    """The solver did not converge; ``history`` holds the residual norms it reached,
    ``reached`` (set by a path follower) the last converged load factor, ``limit_point``
    (set by a path follower) that load factor where the path failed at a limit point of the
    load, and ``results`` (set by ``Model.solve``) the load steps that did converge."""

    def __init__(self, message: str, history: list[float]):
        super().__init__(message)
        self.history = history
        self.reached: float | None = None
        self.limit_point: float | None = None
        self.results: Any = None


class InadmissibleState(ConvergenceError):
    """A solve reached balance in a state that is not physical (collapsed elements or a
    collapsed enclosed volume): a failure, never an answer."""


class Diverging(ConvergenceError):
    """A solve's iterate left every membrane state behind (an element stretched beyond
    ``wrinkle.system.MAX_AREA_RATIO``): the load may exceed what the membrane can carry."""


class EvaluationFailure(RuntimeError):
    """A trial configuration could not be evaluated (e.g. a collapsed element)."""


def try_evaluate(
    problem: Problem, u: np.ndarray, stiffness: bool = True, **options
) -> Evaluation | None:
    """Evaluate a trial point; None if it is not admissible (the solver then shortens the step).
    ``options`` go to ``problem.evaluate``. A trial point far out (a step past a limit point)
    may overflow: NumPy's warnings are silenced meanwhile, and a point whose forces are not
    finite is refused."""
    try:
        with np.errstate(all="ignore"):
            evaluation = problem.evaluate(u, stiffness=stiffness, **options)
            finite = bool(np.all(np.isfinite(evaluation.residual)))
            # forces so large that their norm overflows
            finite = finite and math.isfinite(evaluation.residual_norm)
    except (EvaluationFailure, ArithmeticError, ValueError, RuntimeError) as error:
        logger.debug("trial point rejected: %s", error)
        return None
    if not (finite and math.isfinite(evaluation.force_scale)):
        return None
    return evaluation


def deferring(problem: Problem) -> dict[str, bool]:
    """The options of ``problem.evaluate`` that defer the stiffness of a trial point until
    it is accepted (``Evaluation.with_stiffness``), where the problem can
    (``defers_stiffness``); none otherwise."""
    return {"defer": True} if getattr(problem, "defers_stiffness", False) else {}


def is_converged(evaluation: Evaluation, tolerance: float) -> bool:
    """Residual-force criterion |f - f*| <= tolerance * max(|f_ext|, |reactions|, F_motion),
    or a residual at the level of round-off; never true where the residual or the scale is
    not finite (a test that infinite forces would pass)."""
    residual, scale = evaluation.residual_norm, evaluation.force_scale
    if not (math.isfinite(residual) and math.isfinite(scale)):
        return False
    return residual <= max(tolerance * scale, evaluation.round_off)


def stiffness_scale(K: sp.csr_matrix, free: np.ndarray) -> float:
    """Mean absolute diagonal stiffness of the free dofs (1.0 if it is zero)."""
    diagonal = np.abs(K.diagonal()[free])
    scale = float(diagonal.mean()) if diagonal.size else 0.0
    return scale if scale > 0.0 else 1.0


def _with_held(
    solve: Callable[[np.ndarray], np.ndarray], free: np.ndarray, held: np.ndarray
) -> Callable[[np.ndarray], np.ndarray]:
    """The solve of A x = b from the solve of its free block: x_f = A_ff^-1 b_f and
    x_c = b_c / A_cc (``FreeBlock``). (n_dofs,) in and out."""

    def solve_all(b: np.ndarray) -> np.ndarray:
        x_free = solve(np.ascontiguousarray(b[free]))
        x = np.empty(b.shape, dtype=np.result_type(x_free, b, held))
        x[free] = x_free
        x[~free] = b[~free] / held
        return x

    return solve_all


def shifted(
    K: sp.csr_matrix, shift: complex, free: np.ndarray, diagonal: np.ndarray | None = None
) -> sp.csr_matrix:
    """K + shift I on the free dofs (the constrained diagonal stays one), on K's own pattern.

    diagonal: (n_dofs,) positions of the diagonal entries in K.data (computed if None).
    """
    if diagonal is None:
        diagonal = diagonal_positions(K)
    data = K.data.astype(np.result_type(K.data, shift))
    data[diagonal[free]] += shift
    return with_values(K, data)


IterationListener = Callable[[str, int, float, tuple[int, int, int]], None]
"""Called after each nonlinear iteration with the solver's name, the iteration number, the
residual relative to the force scale and the (taut, wrinkled, slack) element counts."""

_listeners: ContextVar[tuple[IterationListener, ...]] = ContextVar("listeners", default=())


@contextmanager
def listening(listener: IterationListener) -> Iterator[None]:
    """Within the block, every nonlinear iteration of every solver (in this thread or task)
    is reported to ``listener`` (a progress display, say), as ``log_iteration`` logs it."""
    token = _listeners.set((*_listeners.get(), listener))
    try:
        yield
    finally:
        _listeners.reset(token)


def log_iteration(method: str, iteration: int, evaluation: Evaluation, theta: float | None) -> None:
    """One line per iteration on the ``wrinkle.solver`` logger (theta None: not yet chosen),
    and the same to the listeners of ``listening``."""
    taut, wrinkled, slack = evaluation.states
    listeners = _listeners.get()
    if listeners:
        scale = evaluation.force_scale
        relative = evaluation.residual_norm / scale if scale > 0 else evaluation.residual_norm
        for listener in listeners:
            listener(method, iteration, float(relative), (taut, wrinkled, slack))
    logger.info(
        "%s iteration %3d: residual %.3e (scale %.3e), theta %s, taut %d, wrinkled %d, slack %d",
        method,
        iteration,
        evaluation.residual_norm,
        evaluation.force_scale,
        "-" if theta is None else f"{theta:.2e}",
        taut,
        wrinkled,
        slack,
    )


class RegularisedSolver(ABC):
    """Common loop of the two solvers: a regularised step, accepted or not by a gain ratio.

    Each iteration solves for a trial step with regularisation theta, compares the actual
    decrease of the merit function with the decrease its local model predicts (gain ratio rho)
    and, as in Fletcher (Practical Methods of Optimization, vol. 1, 1980, section 5.2), accepts
    the step if rho > 0 and makes theta larger (rho < 0.25) or smaller (rho > 0.75). A
    rejected step is first offered to ``backtrack`` (shorter steps along it, no factorisation).
    Subclasses define ``method``, ``trial_step`` and ``merit`` and the theta rules.
    """

    method = "solver"
    default_max_iterations = 50
    # whether a load step that moves supports starts from the tangent prediction
    # (``Model.tangent_prediction``)
    tangent_predictor = True
    max_rejections = 40
    #: nonlinear elimination after each global step (``wrinkle.solvers.elimination``), or None
    elimination: Any = None
    #: no log line per iteration (the local solves of nonlinear elimination)
    quiet = False
    #: factorise the free block of a matrix whose constrained rows and columns hold only
    #: their diagonal (``FreeBlock``; False: the whole matrix, as before 4 December 2026)
    free_block = True
    #: OpenBLAS threads during a solve (``wrinkle.threads``; None: as many as it starts,
    #: before the parallel kernels of 4 December 2026)
    blas_threads: int | None = 1

    def __init__(
        self,
        tolerance: float = 1e-6,
        max_iterations: int | None = None,
        linear_solver: str = "auto",
    ):
        if not tolerance > 0:
            raise ValueError(f"solver tolerance must be > 0, got {tolerance}")
        #: whether max_iterations is the method's default (not the user's own limit)
        self.limit_is_default = max_iterations is None
        if max_iterations is None:
            max_iterations = self.default_max_iterations
        if int(max_iterations) < 1:
            raise ValueError(f"solver max_iterations must be >= 1, got {max_iterations}")
        self.tolerance = tolerance
        self.max_iterations = int(max_iterations)
        self.linear_solver = linear_solver
        # the back-end, made at the first solve (it depends on the size)
        self.linear: LinearSolver | None = None
        self._is_symmetric = SymmetryCheck()
        self._free_block = FreeBlock()
        self._timer = Stopwatch()

    def factorise(
        self, A: Matrix, symmetric: bool, free: np.ndarray | None = None
    ) -> Callable[[np.ndarray], np.ndarray] | None:
        """Solve function of the linear back-end for A (None if A is singular); the time of
        both goes to the problem's stopwatch. A matrix not known to be symmetric is checked
        (``SymmetryCheck``): the assembled tangent under follower pressure often is (the
        airbag's, to round-off), and the back-ends factorise symmetric matrices faster.
        free: (n_dofs,) bool, the free components; where A's constrained rows and columns
        hold only their diagonal, the back-end factorises the free block alone
        (``FreeBlock``)."""
        if self.linear is None:
            self.linear = make_linear_solver(self.linear_solver, A.shape[0])
        linear, timer = self.linear, self._timer
        with timer.part(LINEAR):
            if not symmetric and not np.issubdtype(A.dtype, np.complexfloating):
                symmetric = self._is_symmetric(A)
            split = self._split(A, free)
            if split is None:
                solve = linear.factorise(A, symmetric)
            else:
                block, held = split
                solve = linear.factorise(block, symmetric)
                if solve is not None and free is not None:
                    solve = _with_held(solve, free, held)
        timer.factorisations += 1
        if solve is None:
            return None
        factorised = solve

        def timed_solve(b: np.ndarray) -> np.ndarray:
            with timer.part(LINEAR):
                return factorised(b)

        return timed_solve

    def _split(self, A: Matrix, free: np.ndarray | None) -> tuple[sp.csr_matrix, np.ndarray] | None:
        """``FreeBlock.split`` of A, or None where there is nothing held or no block."""
        if not self.free_block or free is None or bool(np.all(free)):
            return None
        return self._free_block.split(A, free)

    def is_symmetric(self, A: Matrix) -> bool:
        """Whether A is symmetric to round-off (``SymmetryCheck``)."""
        return bool(self._is_symmetric(A))

    def negative_eigenvalues(self, A: sp.csr_matrix, free: np.ndarray | None = None) -> int | None:
        """The number of negative eigenvalues of the symmetric matrix A, from a
        factorisation by the linear back-end (PARDISO's or SuperLU's inertia; the other
        back-ends hand the matrix to SuperLU); None where it cannot be had. The time and
        the factorisation go to the problem's stopwatch."""
        if self.linear is None:
            self.linear = make_linear_solver(self.linear_solver, A.shape[0])
        count = getattr(self.linear, "negative_pivots", None)
        if count is None:
            count = SuperLU().negative_pivots
        with self._timer.part(LINEAR):
            split = self._split(A, free)
            if split is None:
                negative = count(A)
            else:  # the held diagonal's own signs, by Sylvester's law
                block, held = split
                negative = count(block)
                if negative is not None:
                    negative += int(np.count_nonzero(held < 0.0))
        self._timer.factorisations += 1
        return negative

    def release(self) -> None:
        """Free the linear back-end's factorisations; the solver stays usable."""
        if self.linear is not None:
            self.linear.release()

    def time_with(self, problem: Problem) -> None:
        """Charge the factorisations and solves to the problem's stopwatch (if it has one)."""
        self._timer = getattr(problem, "timer", None) or Stopwatch()

    def tangent_step(self, problem: Problem, ev: Evaluation) -> np.ndarray | None:
        """One step from ev (an evaluation of problem) with the initial regularisation and no
        acceptance test, for a predictor; None if the regularised tangent cannot be
        factorised. (n_dofs,)"""
        self.time_with(problem)
        step, _ = self.trial_step(ev, self.initial_theta(ev.tangent, problem.free), problem.free)
        return step

    # to be defined by subclasses
    @abstractmethod
    def initial_theta(self, K: sp.csr_matrix, free: np.ndarray) -> float:
        """The regularisation of the first trial step of a solve."""

    @abstractmethod
    def trial_step(
        self, ev: Evaluation, theta: float, free: np.ndarray
    ) -> tuple[np.ndarray | None, float]:
        """A trial step (n_dofs,) from ev with regularisation theta (None if the regularised
        tangent cannot be factorised) and the decrease of the merit its model predicts."""

    @abstractmethod
    def gain_ratio(self, ev: Evaluation, trial: Evaluation, predicted: float) -> float:
        """Actual over predicted decrease of the merit from ev to the trial point."""

    @abstractmethod
    def increase(self, theta: float) -> float:
        """Theta after a poor step (gain ratio below 0.25)."""

    @abstractmethod
    def decrease(self, theta: float) -> float:
        """Theta after a good step (gain ratio above 0.75)."""

    def moved(self, displacement: np.ndarray) -> None:
        """The trial point of the last step is u + displacement (n_dofs,), not u + step:
        nonlinear elimination moved it (a ``gain_ratio`` may measure along it)."""
        self._moved = displacement

    def backtrack(
        self, problem: Problem, u: np.ndarray, ev: Evaluation, step: np.ndarray
    ) -> tuple[np.ndarray, Evaluation] | None:
        """After a rejected step: (u, evaluation) of an acceptable point on a shorter step in
        the same direction, found without a new factorisation, or None (then theta grows and
        a new step is factorised). None here; a subclass may search."""
        return None

    def _refuse_inadmissible(self, ev: Evaluation, history: list[float]) -> None:
        """Raise ConvergenceError if the balanced state of ev is not a physical one: a solve
        must not end there (``Evaluation.inadmissible``)."""
        reason = ev.inadmissible
        if reason is not None:
            raise InadmissibleState(
                f"{self.method}: the balanced state is not admissible: {reason}", history
            )

    def solve(
        self,
        problem: Problem,
        u0: np.ndarray,
        at_start: Evaluation | None = None,
        stop: StopRule | None = None,
        iterations: int | None = None,
    ) -> SolverResult:
        """Solve from u0 (prescribed values already set); raise ConvergenceError if it fails.
        at_start: problem's evaluation at u0 if the caller has it, with or without stiffness;
        a start already in balance then costs no evaluation of the stiffness. stop: a rule
        that may end the solve before the residual test (``StopRule``), asked after each
        accepted iteration. iterations: the most iterations of this solve (None:
        ``max_iterations``). OpenBLAS runs on ``blas_threads`` threads meanwhile, and freed
        memory stays with the process (``wrinkle.memory``)."""
        limit = self.max_iterations if iterations is None else int(iterations)
        with blas_threads(self.blas_threads), kept_memory():
            return self._solve(problem, u0, at_start, stop, limit)

    def _solve(
        self,
        problem: Problem,
        u0: np.ndarray,
        at_start: Evaluation | None,
        stop: StopRule | None,
        limit: int,
    ) -> SolverResult:
        """``solve`` in at most ``limit`` iterations."""
        self.time_with(problem)
        u = np.array(u0, dtype=float)
        if at_start is not None and is_converged(at_start, self.tolerance):
            log_iteration(self.method, 0, at_start, None)
            self._refuse_inadmissible(at_start, [at_start.residual_norm])
            return SolverResult(u, 0, [at_start.residual_norm], at_start)
        start = at_start
        if start is None or start.stiffness is None:
            start = try_evaluate(problem, u)
        if start is None:
            raise ConvergenceError(f"{self.method}: the starting point cannot be evaluated", [])
        ev = start
        history = [ev.residual_norm]
        theta = self.initial_theta(ev.tangent, problem.free)
        accepted = AcceptedStep(ev.energy, math.nan, math.nan, False, theta, u, ev)
        for iteration in range(limit + 1):
            if not self.quiet:
                log_iteration(self.method, iteration, ev, theta)
            if is_converged(ev, self.tolerance):
                self._refuse_inadmissible(ev, history)
                if self.elimination is not None:
                    logger.info(
                        "%s: nonlinear elimination so far: %d patches, %d local iterations",
                        self.method,
                        self._timer.patches,
                        self._timer.local_iterations,
                    )
                return SolverResult(u, iteration, history, ev)
            if stop is not None:
                report = stop(accepted)
                if report is not None:
                    self._refuse_inadmissible(ev, history)
                    if not self.quiet:
                        logger.info("%s: stopped by the accuracy rule: %s", self.method, report)
                    return SolverResult(u, iteration, history, ev, "accuracy", report)
            if iteration == limit:
                break
            for _ in range(self.max_rejections):
                step_theta = theta
                step, predicted = self.trial_step(ev, theta, problem.free)
                trial, point = None, None
                if step is not None and predicted > 0:
                    # the tangent formed only if the point is accepted, where the problem can
                    point = u + step
                    trial = try_evaluate(problem, point, **deferring(problem))
                    if trial is not None and self.elimination is not None:
                        point, trial = self.elimination.relax(
                            problem, point, trial, self.tolerance, self.linear_solver
                        )
                        self.moved(point - u)
                rho = -np.inf if trial is None else self.gain_ratio(ev, trial, predicted)
                if rho < 0.25:
                    theta = self.increase(theta)
                elif rho > 0.75:
                    theta = self.decrease(theta)
                if rho > 0.0 and point is not None and trial is not None:
                    u = point
                    ev = trial.with_stiffness()
                    full = True
                    break
                shorter = None if step is None else self.backtrack(problem, u, ev, step)
                if shorter is not None:
                    u, ev = shorter
                    full = False
                    break
            else:
                raise ConvergenceError(
                    f"{self.method}: no acceptable step after {self.max_rejections} "
                    f"increases of theta (residual {ev.residual_norm:.3e})",
                    history,
                )
            history.append(ev.residual_norm)
            reason = ev.diverging
            if reason is not None:  # (a load above what the membrane can carry)
                raise Diverging(f"{self.method}: the solve diverges: {reason}", history)
            accepted = AcceptedStep(ev.energy, predicted, rho, full, step_theta, u, ev)
        raise ConvergenceError(
            f"{self.method}: not converged in {limit} iterations "
            f"(residual {ev.residual_norm:.3e}, needed {self.tolerance * ev.force_scale:.3e})",
            history,
        )
