"""Newton's method on the balance plus one scalar equation, for one more unknown.

Arc length, enclosed-volume control, gas loads and a stop at a probe's displacement all solve

    R(u, mu) = f(u, mu) - f*(u) = 0,        c(u, mu) = 0,

for the displacements u (n_dofs,) and one scalar mu (the load factor, or the factor on the
pressures), with c one scalar equation (``Constraint``): the arc length, the volume to
enclose, the gas law, the probe's displacement. Newton's step on the bordered system

    [ K    -q ] [du ]   [ R ]        K = -dR/du (the consistent tangent, the follower loads'
    [ g^T  c' ] [dmu] = [-c ],       stiffness included), q = dR/dmu, g = dc/du, c' = dc/dmu,

is found with one factorisation of K and two solves (block elimination, as in Crisfield,
Non-linear Finite Element Analysis of Solids and Structures, vol. 1, 1991, section 9.3):
K a = R, K b = q, dmu = -(c + g.a) / (g.b + c'), du = a + dmu b.

The bordered system is not, in general, the stationarity of one potential (the
volume-controlled balloon on its falling branch is a saddle of the energy), so each equation
brings its own merit (``Merit``): the residual's |R|^2 + (w c)^2 (``ResidualMerit``, w = F /
c_scale converting c to a force, F the force scale of the first step), or, where there is a
potential, one built on the energy (the augmented Lagrangian of volume control, the total
energy of a gas load: ``wrinkle.solvers.control``). K is regularised, K + theta M, and the
step judged, by the Newton solver's own rules (``RegularisedNewton``: theta from 1e-8 of its
metric; the gain ratio of the merit's decrease to its quadratic model's, -slope/2 for the
Newton step; theta grown after a poor ratio, cut after a good one); a full step that does
not lower the merit is halved up to six times (Armijo's test, Nocedal & Wright, Numerical
Optimization, 2006, section 3.1) before theta grows and the step is factorised again.
Where the merit's change is at round-off in its value (close to convergence), it is measured
from the merit's derivatives along the step at both ends by the trapezoidal rule, as the
Newton solver measures the energy's, -alpha (d(0) + d(alpha)) / 2 for the point alpha (du,
dmu): d from the forces and the constraint (``Merit.derivative``); only a merit without one
(the residual's) hands the judgement to the residual merit. (Before 6 December 2026 every
such change was judged by the residual merit, which accepts steps towards any balanced
state: a gas-loaded double well ended on its hilltop, a maximum of the energy, and the
8,192-element gas airbag stalled at 1.3e-7 of its force scale.) A solve ends where the residual
passes the usual test (``is_converged``) and |c| <= tolerance times the constraint's scale,
in an admissible state.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from wrinkle.memory import kept_memory
from wrinkle.solvers.base import (
    ConvergenceError,
    Evaluation,
    InadmissibleState,
    SolverResult,
    is_converged,
    log_iteration,
    try_evaluate,
)
from wrinkle.solvers.newton import RegularisedNewton
from wrinkle.solvers.stepping import SteppedProblem
from wrinkle.threads import blas_threads

__all__ = [
    "BorderedResult",
    "Constraint",
    "Family",
    "Linearised",
    "Merit",
    "ProbeDisplacement",
    "ResidualMerit",
    "solve_bordered",
]

logger = logging.getLogger("wrinkle.solver")

_HALVINGS = 6  # step fractions 1, 1/2, ..., 1/32 tried before the tangent is regularised
_SUFFICIENT = 1e-4  # Armijo's fraction of the predicted decrease of the merit
_ROUND_OFF = 1e-12  # a merit change below this fraction of it is round-off


@dataclass(frozen=True)
class Linearised:
    """A scalar equation c(u, mu) = 0 at one point: its value c, its gradient dc/du
    (n_dofs,), zero at the constrained components (None: zero), and dc/dmu."""

    value: float
    gradient: np.ndarray | None
    derivative: float


class Constraint(Protocol):
    """The scalar equation of a bordered solve. ``scale``: the size of c below which
    ``tolerance * scale`` counts as satisfied; ``admits(mu)``: whether mu is a value the
    equation is defined at (a gas pressure above minus the ambient one); called at (u, mu)
    it gives the ``Linearised`` equation."""

    @property
    def scale(self) -> float: ...

    def admits(self, mu: float) -> bool: ...

    def __call__(self, u: np.ndarray, mu: float) -> Linearised: ...


class Family(Protocol):
    """The problems R(u, mu) = 0 of one scalar mu: ``at(mu)`` the step problem at mu,
    ``derivative(u)`` q = dR/dmu at u (n_dofs,), zero at the constrained components."""

    def at(self, mu: float) -> SteppedProblem: ...

    def derivative(self, u: np.ndarray) -> np.ndarray: ...


@dataclass
class BorderedResult(SolverResult):
    """A converged bordered solve: ``SolverResult`` and the scalar unknown mu."""

    mu: float = math.nan
    constraint_history: list[float] = field(default_factory=list)


@dataclass(frozen=True)
class ProbeDisplacement:
    """c = |mean displacement of the probe's nodes| - target: a path's end at a probe's
    displacement (``[solver] stop``). nodes: (k,) node indices; target > 0 (length)."""

    nodes: np.ndarray
    target: float

    @property
    def scale(self) -> float:
        return self.target

    def admits(self, mu: float) -> bool:
        return True

    def displacement(self, u: np.ndarray) -> float:
        """|mean displacement| of the probe's nodes at u (n_dofs,)."""
        return float(np.linalg.norm(u.reshape(-1, 3)[self.nodes].mean(axis=0)))

    def __call__(self, u: np.ndarray, mu: float) -> Linearised:
        mean = u.reshape(-1, 3)[self.nodes].mean(axis=0)
        size = float(np.linalg.norm(mean))
        gradient = np.zeros_like(u).reshape(-1, 3)
        if size > 0.0:
            np.add.at(gradient, self.nodes, mean / (size * len(self.nodes)))
        return Linearised(size - self.target, gradient.ravel(), 0.0)


class Merit(Protocol):
    """How a bordered solve judges a trial point (module docstring).

    project(u, mu): the unknown at a trial point (mu itself, or the value the constraint
    fixes for u, as a gas law does; nan: none); value(ev, u, mu, c): the merit there (inf
    where it is not defined); slope(ev, c, du, dmu, K_du): its derivative along the step
    (du, dmu) by the step's linear model, with K_du the regularised tangent times du (it may
    adjust a penalty), or None where the merit cannot judge the step (then the residual
    merit does); derivative(ev, lin, du, dmu): its derivative along (du, dmu) at any point,
    from the point's forces and constraint (``Linearised``), or None: where the merit's
    change is at round-off in its value, the change is measured from these (module
    docstring)."""

    def project(self, u: np.ndarray, mu: float) -> float: ...

    def value(self, ev: Evaluation, u: np.ndarray, mu: float, c: float) -> float: ...

    def slope(
        self, ev: Evaluation, c: float, du: np.ndarray, dmu: float, K_du: np.ndarray
    ) -> float | None: ...

    def derivative(
        self, ev: Evaluation, lin: Linearised, du: np.ndarray, dmu: float
    ) -> float | None: ...


@dataclass
class ResidualMerit:
    """|R|^2 + (w c)^2 with w = F / c_scale, F the force scale at the first step, fixed for
    the solve (module docstring); its Gauss-Newton slope along Newton's step is -2 merit."""

    scale: float
    weight: float | None = None

    def project(self, u: np.ndarray, mu: float) -> float:
        return mu

    def fix_weight(self, ev: Evaluation, q: np.ndarray, dmu: float) -> None:
        if self.weight is None:
            force = max(ev.force_scale, float(np.linalg.norm(q)) * abs(dmu))
            if force > 0 and self.scale > 0:
                self.weight = force / self.scale

    def value(self, ev: Evaluation, u: np.ndarray, mu: float, c: float) -> float:
        return ev.residual_norm**2 + ((self.weight or 0.0) * c) ** 2

    def slope(
        self, ev: Evaluation, c: float, du: np.ndarray, dmu: float, K_du: np.ndarray
    ) -> float | None:
        return -2.0 * (ev.residual_norm**2 + ((self.weight or 0.0) * c) ** 2)

    def derivative(
        self, ev: Evaluation, lin: Linearised, du: np.ndarray, dmu: float
    ) -> float | None:
        return None  # (never at round-off: it is the residual's square)


def solve_bordered(
    family: Family,
    constraint: Constraint,
    u0: np.ndarray,
    mu0: float,
    solver: RegularisedNewton,
    timer_owner: Callable[[SteppedProblem], None] | None = None,
    merit: Merit | None = None,
    iterations: int | None = None,
) -> BorderedResult:
    """Solve R(u, mu) = 0, c(u, mu) = 0 from (u0, mu0) (module docstring) with the linear
    back-end, tolerance and iteration limit of ``solver``. timer_owner(problem) is called on
    each problem made (to share a stopwatch). merit: how steps are judged (default
    ``ResidualMerit``; a merit with a potential, such as the Lagrangian of volume
    control, finds the inflated shape from a flat sheet where the residual cannot).
    iterations: the most iterations of this solve (None: ``solver.max_iterations``). Raises
    ConvergenceError if it fails, InadmissibleState if it balances in a state that is not
    physical. OpenBLAS runs on ``solver.blas_threads`` threads meanwhile, and freed memory
    stays with the process (``wrinkle.memory``)."""
    limit = solver.max_iterations if iterations is None else int(iterations)
    with blas_threads(solver.blas_threads), kept_memory():
        return _solve_bordered(family, constraint, u0, mu0, solver, timer_owner, merit, limit)


def _solve_bordered(
    family: Family,
    constraint: Constraint,
    u0: np.ndarray,
    mu0: float,
    solver: RegularisedNewton,
    timer_owner: Callable[[SteppedProblem], None] | None,
    merit: Merit | None,
    limit: int,
) -> BorderedResult:
    """``solve_bordered`` in at most ``limit`` iterations."""

    def problem_at(mu: float) -> SteppedProblem:
        problem = family.at(mu)
        if timer_owner is not None:
            timer_owner(problem)
        return problem

    method = f"{solver.method} (bordered)"
    u = np.array(u0, dtype=float)
    mu = float(mu0)
    if merit is not None:
        projected = merit.project(u, mu)
        mu = projected if math.isfinite(projected) else mu
    problem = problem_at(mu)
    ev = try_evaluate(problem, u)
    if ev is None or not constraint.admits(mu):
        raise ConvergenceError(f"{method}: the starting point cannot be evaluated", [])
    solver.time_with(problem)
    lin = constraint(u, mu)
    history, constraint_history = [ev.residual_norm], [lin.value]
    free = problem.free
    theta = solver.initial_theta(ev.tangent, free)
    fallback = ResidualMerit(constraint.scale)
    merit = fallback if merit is None else merit
    for iteration in range(limit + 1):
        log_iteration(method, iteration, ev, theta)
        if is_converged(ev, solver.tolerance) and abs(lin.value) <= (
            solver.tolerance * constraint.scale
        ):
            reason = ev.inadmissible
            if reason is not None:
                raise InadmissibleState(
                    f"{method}: the balanced state is not admissible: {reason}", history
                )
            return BorderedResult(
                u, iteration, history, ev, mu=mu, constraint_history=constraint_history
            )
        if iteration == limit:
            break
        q = family.derivative(u)
        g = np.zeros_like(u) if lin.gradient is None else lin.gradient
        accepted = None
        for _ in range(solver.max_rejections):
            step = _bordered_step(solver, ev, theta, free, q, g, lin)
            if step is None:
                theta = solver.increase(theta)
                continue
            du, dmu = step
            fallback.fix_weight(ev, q, dmu)
            K_du = ev.residual + dmu * q  # the regularised tangent times du
            judge: Merit = merit
            slope = merit.slope(ev, lin.value, du, dmu, K_du)
            current = merit.value(ev, u, mu, lin.value)
            start: float | None = None  # the merit's derivative at u, near round-off
            if not math.isfinite(current):
                slope = -1.0  # a start where the merit is not defined: any point will do
            elif slope is None or abs(slope) <= _ROUND_OFF * abs(current):
                if slope is not None:  # a change at round-off: measured from the forces
                    start = merit.derivative(ev, lin, du, dmu)
                if start is None:  # or, where the merit cannot, judged by the residual
                    judge = fallback
                    slope = fallback.slope(ev, lin.value, du, dmu, K_du)
                    current = fallback.value(ev, u, mu, lin.value)
            if slope is None or not slope < 0.0:
                theta = solver.increase(theta)
                continue
            measure = _Decrease(judge, current, start, du, dmu)
            accepted, value = _try(problem_at, constraint, judge, u, mu, du, dmu, 1.0, current)
            if accepted is None:
                rho = -math.inf
            elif not math.isfinite(current):
                rho = 1.0  # from a start where the merit is not defined
            else:
                rho = measure(accepted, value, 1.0) / (-0.5 * slope)
            if rho < 0.25:  # the trust rules of the Newton solver (``RegularisedSolver``)
                theta = solver.increase(theta)
            elif rho > 0.75:
                theta = solver.decrease(theta)
            if accepted is None or rho <= 0.0:
                accepted = _line_search(
                    problem_at, constraint, judge, u, mu, du, dmu, measure, slope
                )
            if accepted is not None:
                break
        if accepted is None:
            raise ConvergenceError(
                f"{method}: no step reduces the out-of-balance force and the constraint's "
                f"error (residual {ev.residual_norm:.3e}, constraint {lin.value:.3e})",
                history,
            )
        u, mu, problem, ev, lin = accepted
        history.append(ev.residual_norm)
        constraint_history.append(lin.value)
    raise ConvergenceError(
        f"{method}: not converged in {limit} iterations (residual "
        f"{ev.residual_norm:.3e}, needed {solver.tolerance * ev.force_scale:.3e}; constraint "
        f"{lin.value:.3e}, needed {solver.tolerance * constraint.scale:.3e})",
        history,
    )


def _bordered_step(
    solver: RegularisedNewton,
    ev: Evaluation,
    theta: float,
    free: np.ndarray,
    q: np.ndarray,
    g: np.ndarray,
    lin: Linearised,
) -> tuple[np.ndarray, float] | None:
    """(du, dmu) of the bordered Newton step with the tangent regularised by theta
    (``RegularisedNewton.regularised``), by one factorisation and two solves; None if it is
    singular."""
    K = solver.regularised(ev, theta, free)
    solve = solver.factorise(K, ev.symmetric, free)
    if solve is None:
        return None
    a = solve(ev.residual)
    b = solve(q)
    denominator = float(g @ b) + lin.derivative
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))) or denominator == 0.0:
        return None
    dmu = -(lin.value + float(g @ a)) / denominator
    if not math.isfinite(dmu):
        return None
    return a + dmu * b, dmu


Trial = tuple[np.ndarray, float, SteppedProblem, Evaluation, Linearised]


def _try(
    problem_at: Callable[[float], SteppedProblem],
    constraint: Constraint,
    merit: Merit,
    u: np.ndarray,
    mu: float,
    du: np.ndarray,
    dmu: float,
    alpha: float,
    current: float,
    stiffness: bool = True,
) -> tuple[Trial | None, float]:
    """The point alpha (du, dmu) along the step and its merit (None and inf where it cannot
    be evaluated or its merit is not defined); its evaluation with the tangent if
    ``stiffness``."""
    trial_u = u + alpha * du
    trial_mu = merit.project(trial_u, mu + alpha * dmu)
    if not (math.isfinite(trial_mu) and constraint.admits(trial_mu)):
        return None, math.inf
    problem = problem_at(trial_mu)
    trial = try_evaluate(problem, trial_u, stiffness=stiffness)
    if trial is None:
        return None, math.inf
    lin = constraint(trial_u, trial_mu)
    value = merit.value(trial, trial_u, trial_mu, lin.value)
    if not math.isfinite(value):
        return None, math.inf
    return (trial_u, trial_mu, problem, trial, lin), value


@dataclass(frozen=True)
class _Decrease:
    """The merit's decrease from u to a trial point alpha (du, dmu) along the step: current
    minus the trial's value; where the change is at round-off in the merit (``start``, the
    merit's derivative along the step at u, is given), by the trapezoidal rule from the
    derivatives at both ends, -alpha (d(0) + d(alpha)) / 2: exact for a quadratic merit,
    and as precise as the forces (module docstring)."""

    merit: Merit
    current: float
    start: float | None
    du: np.ndarray
    dmu: float

    def __call__(self, found: Trial, value: float, alpha: float) -> float:
        if self.start is None:
            return self.current - value
        _, _, _, trial, lin = found
        end = self.merit.derivative(trial, lin, self.du, self.dmu)
        if end is None:
            return self.current - value
        return -0.5 * alpha * (self.start + end)


def _line_search(
    problem_at: Callable[[float], SteppedProblem],
    constraint: Constraint,
    merit: Merit,
    u: np.ndarray,
    mu: float,
    du: np.ndarray,
    dmu: float,
    measure: _Decrease,
    slope: float,
) -> Trial | None:
    """The longest of the fractions 1/2, 1/4, ... of a step whose full length was rejected
    that lowers the merit (as ``measure`` measures it) by Armijo's fraction of what its
    slope predicts; the new point, its problem, evaluation and constraint, or None."""
    alpha = 0.5
    current = measure.current
    for _ in range(_HALVINGS):
        found, value = _try(problem_at, constraint, merit, u, mu, du, dmu, alpha, current, False)
        if found is not None and (
            not math.isfinite(current)
            or measure(found, value, alpha) >= -_SUFFICIENT * alpha * slope
        ):
            trial_u, trial_mu, problem, _, lin = found
            trial = try_evaluate(problem, trial_u)  # now with the tangent
            return None if trial is None else (trial_u, trial_mu, problem, trial, lin)
        alpha *= 0.5
    return None
