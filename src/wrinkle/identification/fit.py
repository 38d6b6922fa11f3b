"""The least-squares fit of a model's parameters to measured curves, with adjoint gradients.

The residuals are, for each experiment e, measured column k and point i,

    r = w_e (q_k(p; x_i) - m_ik) / max_i |m_ik|

(the model quantity at the point's load factor minus the measured value, relative to the
curve's largest measured value, times the experiment's weight), and SciPy's ``least_squares``
(trust-region reflective, within the parameters' bounds) minimises 1/2 sum r^2 in the
parameters measured in their scales, theta = p / scale (``FitParameter.scale``).

Their Jacobian comes by the adjoint method (``sensitivity.state_sensitivities``) from the
converged states of the residuals' own forward solves, kept for the Jacobian of the same
point: one factorised tangent per measured state, whatever the number of parameters. A
parameter that changes the mesh or the supported values (``gradient = 'finite-difference'``)
takes a forward difference of its own forward solves, step ``DIFFERENCE_STEP`` of its scale.

Engines: in this process (``LocalEngine``), or on a Dask cluster (``DaskEngine``: the
experiments' forward solves and their adjoint gradients as one task each, the
finite-difference solves as one task per parameter and experiment).

The report (``FitResult``): the parameters, their standard errors and 95 % confidence
intervals from the Jacobian at the solution, cov = s^2 (J^T J)^-1 with s^2 = sum r^2 / (m - n)
and the Student t quantile of m - n degrees of freedom (m residuals, n parameters), their
correlation matrix, and each experiment's curves at the start and at the solution.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from wrinkle.case import Case
from wrinkle.identification.problem import Experiment, FitProblem, case_of
from wrinkle.identification.sensitivity import (
    State,
    force_derivatives,
    functional,
    quantity_values,
    solve_to,
    state_sensitivities,
    tangent_at,
)
from wrinkle.solvers import ConvergenceError
from wrinkle.system import DiscreteSystem

__all__ = [
    "DIFFERENCE_STEP",
    "DaskEngine",
    "ExperimentAnswer",
    "ExperimentTask",
    "FitResult",
    "LocalEngine",
    "run_fit",
    "solve_experiment",
    "tasks_for",
]

# the central-difference step of dR/dp at fixed displacements, relative to the parameter's
# scale: the truncation error ~1e-10, the round-off ~1e-11 (sensitivity.force_derivatives)
FORCE_STEP = 1e-5
# the forward-difference step of a parameter without an adjoint gradient, relative to its
# scale: solves converged to 1e-10 leave an error of about 1e-5 in the derivative
DIFFERENCE_STEP = 1e-5
# the largest move of a parameter, relative to its scale, over which the fit's next forward
# solve starts from the states predicted to first order (``LocalEngine``): beyond it, the
# optimiser's first steps of 26-35 % on the 4,096-element sheet of benchmarks/fit_cost.py,
# the predicted starts cost more factorisations than the last states (docs/fit.md, Cost)
LINEAR_RANGE = 0.1
# a residual vector this many times the start's stands for a point whose solve failed: the
# optimiser takes a shorter step
FAILED_POINT = 1e3


@dataclass(frozen=True)
class ExperimentTask:
    """One experiment solved at the parameter values ``assignment`` ({path: value}):
    ``adjoint``, the paths whose gradients to find by the adjoint method, each with the
    step ``steps`` of its force derivative (empty: the values only)."""

    experiment: Experiment
    assignment: dict[str, float]
    tolerance: float
    adjoint: tuple[str, ...] = ()
    steps: tuple[float, ...] = ()


@dataclass
class ExperimentAnswer:
    """The model's quantities at the experiment's points, (n_points, n_quantities), their
    gradients with respect to the adjoint paths, (n_points, n_quantities, n_adjoint), or
    None; ``error``, why the solve failed (then no values); the Newton iterations and the
    wall seconds it took."""

    values: np.ndarray | None
    gradients: np.ndarray | None = None
    error: str | None = None
    iterations: int = 0
    seconds: float = 0.0


@dataclass
class _Solved:
    """An experiment's forward solve kept for its adjoint: its case, system, states."""

    case: Case
    system: DiscreteSystem
    states: list[State]


def _forward(
    task: ExperimentTask, warm: list[State] | None = None
) -> tuple[ExperimentAnswer, _Solved | None]:
    """The task's forward solve (warm: the states of the same experiment at other
    parameter values, to start each load level from, ``solve_to``)."""
    started = time.perf_counter()
    experiment = task.experiment
    try:
        case = case_of(experiment, task.assignment, task.tolerance)
        system = case.model.discretise()
        states = solve_to(case, system, experiment.load_factors, warm)
    except (ConvergenceError, ValueError) as error:
        return ExperimentAnswer(None, error=str(error), seconds=time.perf_counter() - started), None
    functionals = [functional(case, name) for name in experiment.quantities]
    values = np.array([quantity_values(system, state, functionals) for state in states])
    if not np.all(np.isfinite(values)):
        message = "a quantity is not finite at a converged state"
        return ExperimentAnswer(None, error=message, seconds=time.perf_counter() - started), None
    answer = ExperimentAnswer(
        values,
        iterations=sum(state.iterations for state in states),
        seconds=time.perf_counter() - started,
    )
    return answer, _Solved(case, system, states)


def _adjoint(
    task: ExperimentTask, solved: _Solved, displacements: bool = False
) -> tuple[np.ndarray, list[np.ndarray | None]]:
    """dq/dp of the adjoint paths at every state, (n_points, n_quantities, n_adjoint), and,
    if ``displacements``, each state's du/dp (n_dofs, n_adjoint) or None where the tangent is
    not symmetric (``state_sensitivities``); an empty list otherwise."""
    experiment = task.experiment
    perturbed = []
    for path, h in zip(task.adjoint, task.steps, strict=True):
        pair = [
            case_of(
                experiment,
                {**task.assignment, path: task.assignment[path] + sign * h},
                task.tolerance,
            ).model.discretise()
            for sign in (1.0, -1.0)
        ]
        perturbed.append((pair[0], pair[1], h))
    functionals = [functional(solved.case, name) for name in experiment.quantities]
    linear_solver = solved.case.settings.linear_solver
    gradients, slopes = [], []
    for state in solved.states:
        evaluation = tangent_at(solved.system, state)  # shared by dR/dp and the adjoint
        dR = force_derivatives(solved.system, state, perturbed, evaluation)
        gradient, du = state_sensitivities(
            solved.system, state, functionals, dR, linear_solver, evaluation, displacements
        )
        gradients.append(gradient)
        if displacements:
            slopes.append(du)
    return np.array(gradients), slopes


def solve_experiment(task: ExperimentTask) -> ExperimentAnswer:
    """The task's forward solve and, for its adjoint paths, its gradients (a worker's
    task; the values alone where the solve failed)."""
    answer, solved = _forward(task)
    if solved is not None and task.adjoint:
        started = time.perf_counter()
        try:
            answer.gradients = _adjoint(task, solved)[0]
            if not np.all(np.isfinite(answer.gradients)):
                raise ValueError("a gradient is not finite")
        except (ConvergenceError, ValueError) as error:
            answer.values, answer.error = None, f"no gradient: {error}"
        answer.seconds += time.perf_counter() - started
    return answer


@dataclass
class _Slopes:
    """An experiment's states at the parameter values ``assignment`` with their derivatives
    du/dp (n_dofs, n_paths) along ``paths`` (None where not known)."""

    assignment: dict[str, float]
    paths: tuple[str, ...]
    scales: np.ndarray  # of the paths (``FitParameter.scale``), (n_paths,)
    states: list[State]
    du: list[np.ndarray | None]

    def predict(self, assignment: dict[str, float]) -> list[State] | None:
        """The states at other values, to first order: u + du/dp (p - p0); None where a
        parameter has moved by more than LINEAR_RANGE of its scale, or is not given."""
        if not all(path in assignment for path in self.paths):
            return None
        dp = np.array([assignment[path] - self.assignment[path] for path in self.paths])
        if np.any(np.abs(dp) > LINEAR_RANGE * self.scales):
            return None
        return [
            State(state.load_factor, state.u if du is None else state.u + du @ dp)
            for state, du in zip(self.states, self.du, strict=True)
        ]


class LocalEngine:
    """Solves in this process; the states of the last forward solves are kept, so that the
    Jacobian at the same point takes only the adjoint solves, and the next forward solve of
    each experiment starts its load levels from them (``solve_to``'s warm states): from the
    states of the last Jacobian moved by their derivatives along the adjoint paths to first
    order, where there are such and no parameter has moved by more than LINEAR_RANGE of its
    scale since, else from the last forward solve's."""

    def __init__(self) -> None:
        self._kept: dict[int, tuple[ExperimentTask, _Solved]] = {}
        self._warm: dict[int, list[State]] = {}  # by id of the experiment
        self._slopes: dict[int, _Slopes] = {}  # by id of the experiment

    def _start(self, task: ExperimentTask) -> list[State] | None:
        """The warm states of the task's solve (class docstring)."""
        slopes = self._slopes.get(id(task.experiment))
        predicted = None if slopes is None else slopes.predict(task.assignment)
        return predicted if predicted is not None else self._warm.get(id(task.experiment))

    def forward(self, tasks: list[ExperimentTask]) -> list[ExperimentAnswer]:
        self._kept.clear()
        answers = []
        for index, task in enumerate(tasks):
            answer, solved = _forward(task, self._start(task))
            if solved is not None:
                self._kept[index] = (task, solved)
                self._warm[id(task.experiment)] = solved.states
            answers.append(answer)
        return answers

    def adjoint(self, tasks: list[ExperimentTask]) -> list[np.ndarray]:
        """The adjoint gradients of the tasks last solved by ``forward`` (the same tasks)."""
        gradients = []
        for index, task in enumerate(tasks):
            kept = self._kept.get(index)
            if kept is None or kept[0].assignment != task.assignment:
                answer = solve_experiment(task)
                if answer.gradients is None:
                    raise ConvergenceError(
                        f"experiment '{task.experiment.name}': {answer.error}", []
                    )
                gradients.append(answer.gradients)
            else:
                gradient, du = _adjoint(task, kept[1], displacements=True)
                scales = np.array(task.steps) / FORCE_STEP
                self._slopes[id(task.experiment)] = _Slopes(
                    dict(task.assignment), tuple(task.adjoint), scales, kept[1].states, du
                )
                if not np.all(np.isfinite(gradient)):
                    raise ConvergenceError(
                        f"experiment '{task.experiment.name}': a gradient is not finite", []
                    )
                gradients.append(gradient)
        return gradients

    def values(self, tasks: list[ExperimentTask]) -> list[ExperimentAnswer]:
        """Forward solves whose states are not kept (finite differences), each started
        from the last kept states of its experiment."""
        return [_forward(task, self._start(task))[0] for task in tasks]

    def close(self) -> None:
        self._kept.clear()
        self._warm.clear()
        self._slopes.clear()


class DaskEngine:
    """Solves on a Dask cluster (``distributed.Client``): each forward solve with its
    adjoint gradients as one task, the finite-difference solves as tasks too."""

    def __init__(self, client: Any, owns_cluster: bool):
        self.client = client
        self.owns_cluster = owns_cluster
        self._last: list[tuple[ExperimentTask, ExperimentAnswer]] = []

    def forward(self, tasks: list[ExperimentTask]) -> list[ExperimentAnswer]:
        answers = self.client.gather(self.client.map(solve_experiment, tasks, pure=False))
        self._last = list(zip(tasks, answers, strict=True))
        return answers

    def adjoint(self, tasks: list[ExperimentTask]) -> list[np.ndarray]:
        known = {id(t.experiment): (t, a) for t, a in self._last}
        gradients = []
        missing = [
            task
            for task in tasks
            if id(task.experiment) not in known
            or known[id(task.experiment)][0].assignment != task.assignment
        ]
        if missing:
            self.forward(missing)
            known.update({id(t.experiment): (t, a) for t, a in self._last})
        for task in tasks:
            answer = known[id(task.experiment)][1]
            if answer.gradients is None:
                raise ConvergenceError(f"experiment '{task.experiment.name}': {answer.error}", [])
            gradients.append(answer.gradients)
        return gradients

    def values(self, tasks: list[ExperimentTask]) -> list[ExperimentAnswer]:
        plain = [ExperimentTask(t.experiment, t.assignment, t.tolerance) for t in tasks]
        return self.client.gather(self.client.map(solve_experiment, plain, pure=False))

    def close(self) -> None:
        cluster = getattr(self.client, "cluster", None)
        self.client.close()
        if self.owns_cluster and cluster is not None:
            cluster.close()


@dataclass
class FitResult:
    """A finished fit: the parameters found ({path: value}); ``converged``, whether the
    optimiser met its tolerance with every solve converged; its message, the number of
    residual and Jacobian evaluations; the cost 1/2 sum r^2 at the start and at the end;
    the standard errors and 95 % intervals ({path: value, [low, high]}, None where the
    Jacobian cannot give them, ``interval_note`` says why), the correlation matrix
    (n_parameters, n_parameters); per experiment the RMS of its residuals and its model
    curves at the start and at the end (n_points, n_quantities); the gradient method of each
    parameter, the Newton iterations and wall seconds of the fit."""

    problem: FitProblem
    parameters: dict[str, float]
    converged: bool
    message: str
    evaluations: int
    jacobians: int
    start_cost: float
    cost: float
    standard_errors: dict[str, float | None]
    intervals: dict[str, list[float] | None]
    interval_note: str
    correlation: np.ndarray
    rms: dict[str, float]
    start_curves: list[np.ndarray]
    curves: list[np.ndarray]
    gradients: dict[str, str]
    iterations: int = 0
    seconds: float = 0.0
    history: list[dict[str, Any]] = field(default_factory=list)


def tasks_for(
    problem: FitProblem, assignment: dict[str, float], adjoint: bool = True
) -> list[ExperimentTask]:
    """The problem's experiments at the parameter values ``assignment``, each with its
    adjoint paths and force-derivative steps (or none: the values only)."""
    paths = tuple(p.path for p in problem.parameters if p.gradient == "adjoint")
    steps = tuple(FORCE_STEP * p.scale for p in problem.parameters if p.gradient == "adjoint")
    return [
        ExperimentTask(
            e, assignment, problem.tolerance, paths if adjoint else (), steps if adjoint else ()
        )
        for e in problem.experiments
    ]


def _scales(experiment: Experiment) -> np.ndarray:
    """The size of each measured column, max |m| (1 where a column is all zero),
    (n_quantities,)."""
    size = np.abs(experiment.measured).max(axis=0)
    return np.where(size > 0, size, 1.0)


def _statistics(
    jacobian: np.ndarray, residuals: np.ndarray, scale: np.ndarray
) -> tuple[np.ndarray | None, np.ndarray | None, str]:
    """Standard errors (n,) and the covariance (n, n) of the parameters from the Jacobian
    (m, n) in the scaled parameters at the solution; None and why where they are not
    defined."""
    m, n = jacobian.shape
    if m <= n:
        return None, None, f"{m} residuals for {n} parameters: no degrees of freedom left"
    singular = np.linalg.svd(jacobian, compute_uv=False)
    if singular[-1] <= 1e-10 * singular[0]:
        return None, None, "the Jacobian is singular: the data do not fix every parameter"
    variance = float(residuals @ residuals) / (m - n)
    inverse = np.linalg.inv(jacobian.T @ jacobian)
    covariance = variance * inverse * np.outer(scale, scale)
    return np.sqrt(np.diag(covariance)), covariance, ""


def run_fit(
    problem: FitProblem,
    engine: LocalEngine | DaskEngine | None = None,
    on_evaluation: Callable[[dict[str, Any]], None] | None = None,
) -> FitResult:
    """Fit the problem's parameters to its experiments (the module docstring), in
    ``engine`` (this process by default), ``on_evaluation`` called after each residual
    evaluation with {"evaluation", "cost", "parameters", "failed"}. Raises ConvergenceError if the
    start itself cannot be solved."""
    from scipy.optimize import least_squares
    from scipy.stats import t as student

    engine = engine or LocalEngine()
    started = time.perf_counter()
    parameters = problem.parameters
    paths = [p.path for p in parameters]
    scale = np.array([p.scale for p in parameters])
    adjoint_paths = tuple(p.path for p in parameters if p.gradient == "adjoint")
    adjoint_columns = [paths.index(path) for path in adjoint_paths]
    difference_columns = [j for j, p in enumerate(parameters) if p.gradient != "adjoint"]
    experiments = problem.experiments
    sizes = [_scales(e) for e in experiments]
    counts = [e.measured.size for e in experiments]
    history: list[dict[str, Any]] = []
    iterations = [0]
    failed_size = [math.inf]

    def assignment_of(theta: np.ndarray) -> dict[str, float]:
        return {path: float(v) for path, v in zip(paths, theta * scale, strict=True)}

    def tasks_at(assignment: dict[str, float], adjoint: bool = True) -> list[ExperimentTask]:
        return tasks_for(problem, assignment, adjoint)

    def residual_of(answers: list[ExperimentAnswer]) -> np.ndarray | None:
        parts = []
        for e, size, answer in zip(experiments, sizes, answers, strict=True):
            if answer.values is None:
                return None
            iterations[0] += answer.iterations
            parts.append((e.weight * (answer.values - e.measured) / size).ravel())
        return np.concatenate(parts)

    curves: dict[bytes, list[np.ndarray]] = {}  # the model curves at each point evaluated

    def residuals(theta: np.ndarray) -> np.ndarray:
        assignment = assignment_of(theta)
        answers = engine.forward(tasks_at(assignment))
        r = residual_of(answers)
        failed = r is None
        if r is None:
            if not history:
                errors = [
                    f"experiment '{e.name}': {a.error}"
                    for e, a in zip(experiments, answers, strict=True)
                    if a.error is not None
                ]
                raise ConvergenceError(f"the start values cannot be solved: {errors[0]}", [])
            r = np.full(sum(counts), failed_size[0])
        else:
            curves[theta.tobytes()] = [a.values for a in answers if a.values is not None]
            curves.setdefault(b"start", curves[theta.tobytes()])
            if not math.isfinite(failed_size[0]):
                failed_size[0] = FAILED_POINT * max(float(np.abs(r).max()), 1.0)
        row = {
            "evaluation": len(history) + 1,
            "cost": 0.5 * float(r @ r),
            "parameters": assignment,
            "failed": failed,
        }
        history.append(row)
        if on_evaluation is not None:
            on_evaluation(row)
        return r

    def jacobian(theta: np.ndarray) -> np.ndarray:
        assignment = assignment_of(theta)
        tasks = tasks_at(assignment)
        J = np.zeros((sum(counts), len(parameters)))
        rows = np.cumsum([0, *counts])
        if adjoint_columns:
            for k, (e, size, grad) in enumerate(
                zip(experiments, sizes, engine.adjoint(tasks), strict=True)
            ):
                block = e.weight * grad / size[None, :, None]  # (points, quantities, adjoint)
                J[rows[k] : rows[k + 1], adjoint_columns] = block.reshape(-1, len(adjoint_columns))
        if difference_columns:  # the point's own values, and one solve per parameter
            base: list[np.ndarray | None] = list(curves.get(theta.tobytes(), []))
            if not base:
                base = [a.values for a in engine.values(tasks_at(assignment, adjoint=False))]
            steps, moved_tasks = [], []
            for j in difference_columns:
                h = DIFFERENCE_STEP * scale[j]
                step = h if assignment[paths[j]] + h <= parameters[j].bounds[1] else -h
                steps.append(step)
                moved = {**assignment, paths[j]: assignment[paths[j]] + step}
                moved_tasks += tasks_at(moved, adjoint=False)
            answers = engine.values(moved_tasks)  # (in parallel on a cluster)
            for c, (j, step) in enumerate(zip(difference_columns, steps, strict=True)):
                for k, (e, size) in enumerate(zip(experiments, sizes, strict=True)):
                    one, other = base[k], answers[c * len(experiments) + k]
                    if one is None or other.values is None:
                        raise ConvergenceError(
                            f"finite difference of '{paths[j]}' in experiment '{e.name}': "
                            f"{other.error}",
                            [],
                        )
                    derivative = (other.values - one) / step
                    J[rows[k] : rows[k + 1], j] = (e.weight * derivative / size).ravel()
        return J * scale[None, :]  # d r / d theta

    theta0 = np.array([p.start for p in parameters]) / scale
    low = np.array([p.bounds[0] for p in parameters]) / scale
    high = np.array([p.bounds[1] for p in parameters]) / scale
    try:
        solution = least_squares(
            residuals,
            theta0,
            jac=jacobian,
            bounds=(low, high),
            method="trf",
            x_scale=1.0,
            ftol=problem.fit_tolerance,
            xtol=problem.fit_tolerance,
            gtol=problem.fit_tolerance,
            max_nfev=problem.max_evaluations,
        )
    finally:
        engine.close()
    found = assignment_of(solution.x)
    final = np.asarray(solution.fun)
    # the solution is a point least_squares evaluated; every solve there converged
    end_curves = curves.get(solution.x.tobytes())
    solved = end_curves is not None
    if end_curves is None:
        end_curves = [np.full(e.measured.shape, np.nan) for e in experiments]
    final_jacobian = np.asarray(solution.jac)
    errors, covariance, note = _statistics(final_jacobian, final, scale)
    m, n = final_jacobian.shape
    quantile = float(student.ppf(0.975, m - n)) if m > n else math.nan
    standard_errors: dict[str, float | None] = {}
    intervals: dict[str, list[float] | None] = {}
    for j, path in enumerate(paths):
        if errors is None:
            standard_errors[path], intervals[path] = None, None
        else:
            half = quantile * float(errors[j])
            standard_errors[path] = float(errors[j])
            intervals[path] = [found[path] - half, found[path] + half]
    if covariance is not None:
        d = np.sqrt(np.diag(covariance))
        correlation = covariance / np.outer(d, d)
    else:
        correlation = np.full((n, n), np.nan)
    rows = np.cumsum([0, *counts])
    rms = {
        e.name: float(np.sqrt(np.mean(final[rows[k] : rows[k + 1]] ** 2)))
        for k, e in enumerate(experiments)
    }
    return FitResult(
        problem,
        found,
        bool(solution.status > 0 and solved),
        str(solution.message),
        int(solution.nfev),
        int(solution.njev or 0),
        history[0]["cost"],
        0.5 * float(final @ final),
        standard_errors,
        intervals,
        note,
        correlation,
        rms,
        curves.get(b"start", end_curves),
        end_curves,
        {p.path: p.gradient for p in parameters},
        iterations[0],
        time.perf_counter() - started,
        history,
    )
