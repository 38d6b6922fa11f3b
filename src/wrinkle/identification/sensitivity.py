"""Measured quantities along a load path and their derivatives by the adjoint method.

An experiment's case is solved under load control to the load factors of its measured points,
one after the other (each from the state at the one before: ``LoadSegment``), and at each
converged state u the model's measured quantities are read. A quantity is linear in the
displacements or in the support reactions: q = c . u (a probe's mean displacement component,
``<probe>_ux``) or q = c . R_c (the sum of a support's reactions in one direction,
``<support>_Fx``), with R(u, p) = f*(u, p) - f(u, p) the internal minus the external forces
and c (n_dofs,) the quantity's weights (``Functional``).

Balance R_f(u, p) = 0 on the free components fixes u(p). With the tangent K = dR/du, the
derivative of q with respect to a parameter p is, by the adjoint method (one solve per quantity
with the tangent factorised once per state, whatever the number of parameters),

    K_ff^T z = dq/du_f            (dq/du_f = c_f for a displacement, (K^T c)_f for a reaction)
    dq/dp    = c . dR_c/dp - z . dR_f/dp     (the first term for a reaction only)

where dR/dp is the change of the forces at fixed displacements: the derivative of the element
forces (and of the loads, if they depend on p) with respect to the parameter, here by central
differences of R(u, p +- h) (``force_derivatives``), which take no solve and, R being smooth in
p at a fixed state of every element, are exact to about h^2 (h = 1e-5 of the parameter).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from wrinkle.case import Case
from wrinkle.identification.explicit import force_derivatives as force_derivatives_at
from wrinkle.solvers import ConvergenceError
from wrinkle.solvers.base import Evaluation, RegularisedSolver, SolverResult, try_evaluate
from wrinkle.solvers.linear import make_linear_solver
from wrinkle.solvers.stepping import (
    StepController,
    SteppedProblem,
    extrapolate,
    follow_load_path,
)
from wrinkle.system import DiscreteSystem

__all__ = [
    "Functional",
    "LoadSegment",
    "State",
    "force_derivatives",
    "functional",
    "quantity_names",
    "quantity_values",
    "solve_to",
    "state_sensitivities",
    "tangent_at",
]

COMPONENTS = "xyz"
# a free component whose tangent row is below this fraction of the largest has no stiffness
IDLE_STIFFNESS = 1e-12
# the adjoint solve must satisfy its equations to this fraction of the right-hand side
CONSISTENT = 1e-6


@dataclass(frozen=True)
class Functional:
    """A measured model quantity q = weights . v with v the displacements (``of_reactions``
    False) or the reactions R = f* - f at the constrained components (True); weights
    (n_dofs,)."""

    name: str
    weights: np.ndarray
    of_reactions: bool


def quantity_names(case: Case) -> list[str]:
    """The quantities an experiment may measure: ``<support>_Fx/_Fy/_Fz`` for each support
    label and ``<probe>_ux/_uy/_uz`` for each probe (the history.csv columns of the same
    names)."""
    labels = dict.fromkeys(str(support.label) for support in case.model.supports)
    names = [f"{label}_F{c}" for label in labels for c in COMPONENTS]
    return names + [f"{probe}_u{c}" for probe in case.probes for c in COMPONENTS]


def functional(case: Case, name: str) -> Functional:
    """The ``Functional`` of the quantity ``name`` (``quantity_names``) in ``case``:
    reactions summed over the distinct dofs a support label holds in that direction (as
    history.csv's ``_F`` columns), a probe's mean displacement (``_u`` columns). ValueError
    naming the known quantities for any other name."""
    n_dofs = case.model.n_dofs
    weights = np.zeros(n_dofs)
    stem, _, component = name.rpartition("_")
    if len(component) == 2 and component[1] in COMPONENTS:
        axis = COMPONENTS.index(component[1])
        if component[0] == "F":
            held = [np.asarray(s.dofs).ravel() for s in case.model.supports if str(s.label) == stem]
            if held:
                dofs = np.unique(np.concatenate(held)).astype(np.int64)
                weights[dofs[dofs % 3 == axis]] = 1.0
                return Functional(name, weights, True)
        elif component[0] == "u" and stem in case.probes:
            nodes = np.asarray(case.probes[stem], dtype=np.int64)
            weights[3 * nodes + axis] = 1.0 / nodes.size
            return Functional(name, weights, False)
    raise ValueError(
        f"{name!r} is not a quantity of the case (quantities: {', '.join(quantity_names(case))})"
    )


class LoadSegment:
    """The load levels between load factors ``start`` and ``end`` of ``system``, as a path
    from 0 to 1 (``wrinkle.solvers.stepping.LoadLevels``): level t is the system's load factor
    start + t (end - start)."""

    def __init__(self, system: DiscreteSystem, start: float, end: float):
        self.system = system
        self.start = start
        self.end = end
        self.n_dofs = system.n_dofs

    def at(self, load_factor: float = 1.0, prescribed: np.ndarray | None = None) -> SteppedProblem:
        return self.system.at(self.start + load_factor * (self.end - self.start), prescribed)


# the tolerance of a warm-started solve, relative to the case's (``solve_to``)
WARM_TOLERANCE = 1e-2


@dataclass
class State:
    """A converged state: the load factor and the displacements u (n_dofs,); reactions:
    the support reactions there, (n_dofs,), zero at the free components, if the solve that
    reached it gave them (its last evaluation, at u)."""

    load_factor: float
    u: np.ndarray
    iterations: int = 0
    reactions: np.ndarray | None = None


@dataclass
class _Counter:
    iterations: int = 0
    last: SolverResult | None = None  # the last converged step


def _warm_guesses(
    warm: Sequence[State], states: list[State], u: np.ndarray, factor: float
) -> list[np.ndarray]:
    """The starts of level len(states) at load factor ``factor`` from the warm states: the
    warm state moved as the level before moved from its own (u, the level before, (n_dofs,))
    and the extrapolation of the two levels before."""
    index = len(states)
    if index == 0:
        return [warm[0].u]
    guesses = [warm[index].u + (u - warm[index - 1].u)]
    before = (0.0, np.zeros_like(u)) if index == 1 else (states[-2].load_factor, states[-2].u)
    guesses.append(extrapolate(before, states[-1].load_factor, u, factor))
    return guesses


def _from_warm(
    segment: LoadSegment, guesses: list[np.ndarray], solver: RegularisedSolver
) -> tuple[SolverResult | None, int]:
    """The end of a segment solved in one step from the guess (n_dofs,) closest to balance,
    and the Newton iterations taken; no result if it fails."""
    problem = segment.at(1.0)
    constrained = ~problem.free
    best = None
    for guess in guesses:
        start = np.where(constrained, problem.prescribed, guess)
        at_guess = try_evaluate(problem, start, stiffness=False)
        if at_guess is not None and (
            best is None or at_guess.residual_norm < best[1].residual_norm
        ):
            best = (start, at_guess)
    if best is None:
        return None, 0
    try:
        solved = solver.solve(problem, *best)
    except ConvergenceError as error:
        return None, len(error.history)
    return solved, solved.iterations


def solve_to(
    case: Case,
    system: DiscreteSystem,
    load_factors: Sequence[float] | np.ndarray,
    warm: Sequence[State] | None = None,
) -> list[State]:
    """The converged states at the increasing ``load_factors`` (each > 0), by load control
    with the case's solver settings: each segment from the state before (the first from the
    reference state) with the step controller's cut-backs inside it. warm: states at the
    same load factors of a nearby problem (the same case at other parameter values): each
    segment is first tried in one step from the warm start closest to balance
    (``_warm_guesses``), converged to WARM_TOLERANCE times the
    case's tolerance, then, if that fails, by load control. Not for a membrane that encloses
    a volume (whose states are checked for stability on the way). Raises ConvergenceError
    where a segment cannot be solved."""
    settings = case.settings
    solver = settings.solver()
    controller = StepController(
        first_step=1.0,
        min_step=settings.min_step,
        max_step=1.0,
        cutback=settings.cutback,
        growth=settings.growth,
        target_iterations=settings.target_iterations,
        regrow_after=settings.regrow_after,
        look_ahead=settings.look_ahead,
    )
    states: list[State] = []
    u = np.zeros(system.n_dofs)
    usable = (
        warm is not None
        and len(warm) == len(load_factors)
        and all(state.u.shape == u.shape for state in warm)
        and not system.encloses_volume  # (its states are checked for stability)
    )
    # a warm start converges to a tighter tolerance: the state then differs from a solve
    # from the reference state by round-off, not by the solver's tolerance, and the fit's
    # residuals do not depend on the path of the solves
    tight = None
    if usable:
        tight = replace(settings, tolerance=settings.tolerance * WARM_TOLERANCE).solver()
    reached = 0.0
    try:
        for factor in load_factors:
            counter = _Counter()
            segment = LoadSegment(system, reached, float(factor))
            warmed = None
            if tight is not None and warm is not None:
                guesses = _warm_guesses(warm, states, u, float(factor))
                warmed, counter.iterations = _from_warm(segment, guesses, tight)
            if warmed is not None:
                u = warmed.u
                counter.last = warmed
            else:

                def count(_t: float, _u: np.ndarray, solved, counter: _Counter = counter) -> None:
                    counter.iterations += solved.iterations
                    counter.last = solved

                u = follow_load_path(
                    segment,
                    solver,
                    controller,
                    u0=u,
                    on_step=count,
                    stability=system.encloses_volume,
                )
            last = counter.last
            reactions = None
            if last is not None and np.array_equal(last.u, u):
                reactions = last.evaluation.reactions
            states.append(State(float(factor), u.copy(), counter.iterations, reactions))
            reached = float(factor)
    except ConvergenceError as error:
        raise ConvergenceError(
            f"the load path failed between load factors {reached:.6g} and {factor:.6g}: {error}",
            error.history,
        ) from None
    finally:
        solver.release()
        if tight is not None:
            tight.release()
    return states


def _balance_forces(system: DiscreteSystem, state: State) -> np.ndarray:
    """R = f* - f at the state, every component, (n_dofs,) (one evaluation, no tangent)."""
    problem = system.at(state.load_factor, system.prescribed_at(state.load_factor))
    problem.motion_force = 0.0  # (the force scale, which takes a solve, is not wanted here)
    evaluation = problem.evaluate(state.u, stiffness=False)
    reactions = evaluation.reactions if evaluation.reactions is not None else 0.0
    return np.where(system.constrained, reactions, -evaluation.residual)


def quantity_values(
    system: DiscreteSystem, state: State, functionals: Sequence[Functional]
) -> np.ndarray:
    """The quantities at a converged state, (n_quantities,) (its reactions, if it has
    them, else from one evaluation)."""
    R = None
    if any(f.of_reactions for f in functionals):
        R = state.reactions if state.reactions is not None else _balance_forces(system, state)
    return np.array(
        [f.weights @ (R if f.of_reactions and R is not None else state.u) for f in functionals]
    )


def force_derivatives(
    system: DiscreteSystem,
    state: State,
    perturbed: Sequence[tuple[DiscreteSystem, DiscreteSystem, float]],
    evaluation: Evaluation | None = None,
) -> np.ndarray:
    """dR/dp at fixed displacements, (n_dofs, n_parameters): for each parameter the systems
    made with it at p + h and p - h, and h. Where those differ from ``system`` only in their
    materials, frames and loads, from the element states at the state without a wrinkling
    solve (``wrinkle.identification.explicit``; evaluation: ``tangent_at`` the state, whose
    elements it then takes); otherwise (R(u, p + h) - R(u, p - h)) / (2 h)."""
    elements = None if evaluation is None else evaluation.elements
    explicit = force_derivatives_at(system, state.u, state.load_factor, perturbed, elements)
    columns = [
        (_balance_forces(plus, state) - _balance_forces(minus, state)) / (2.0 * h)
        if column is None
        else column
        for column, (plus, minus, h) in zip(explicit, perturbed, strict=True)
    ]
    return np.stack(columns, axis=1) if columns else np.zeros((state.u.size, 0))


def tangent_at(system: DiscreteSystem, state: State) -> Evaluation:
    """The evaluation at a converged state with the whole tangent d(f* - f)/du, its
    constrained rows and columns kept, and the element results (``state_sensitivities``,
    ``force_derivatives``)."""
    return system.at(state.load_factor).evaluate(state.u, keep_constrained=True, keep_elements=True)


def state_sensitivities(
    system: DiscreteSystem,
    state: State,
    functionals: Sequence[Functional],
    dR: np.ndarray,
    linear_solver: str = "auto",
    evaluation: Evaluation | None = None,
    displacements: bool = False,
) -> tuple[np.ndarray, np.ndarray | None]:
    """dq/dp of every quantity at a converged state (module docstring), (n_quantities,
    n_parameters), from dR/dp (n_dofs, n_parameters) (``force_derivatives``): the tangent at
    the state (``tangent_at``, made here unless given as ``evaluation``) is factorised once
    (``linear_solver``, ``wrinkle.solvers.linear``) and each quantity takes one solve with
    its transpose. If ``displacements`` and the tangent is symmetric, also the displacements'
    derivatives du/dp = -K_aa^-1 dR_a/dp (n_dofs, n_parameters) from the same factorisation,
    zero at the supports and the unstiffened components (the first-order prediction of the
    state at other parameter values); else, or where it is not finite, None.

    Free components that no element stiffens (the nodes of a wholly slack region: rows of
    the tangent zero to round-off) move without force and change no reaction; the solve
    leaves them out (their z is zero), where K_ff alone would be singular. ConvergenceError
    if the tangent on the others is singular (a mechanism the supports allow)."""
    if evaluation is None:
        evaluation = tangent_at(system, state)
    K = evaluation.stiffness
    assert K is not None
    K = sp.csr_matrix(K)
    size = abs(K).max(axis=1).toarray().ravel()
    active = ~system.constrained & (size > IDLE_STIFFNESS * max(float(size.max()), 1e-300))
    keep = sp.diags(active.astype(float))
    # K on the active components, the identity on the others: K_aa^T z_a = b_a
    reduced = (
        keep @ (K.T if not evaluation.symmetric else K) @ keep + sp.diags((~active).astype(float))
    ).tocsr()
    reduced.sort_indices()
    backend = make_linear_solver(linear_solver, system.n_dofs, one_off=True)
    try:
        solve = backend.factorise(reduced, bool(evaluation.symmetric))
        if solve is None:
            raise ConvergenceError(
                "the tangent at a converged state is singular: the supports leave a "
                f"mechanism (load factor {state.load_factor:.6g}); no gradient",
                [],
            )
        gradients = np.empty((len(functionals), dR.shape[1]))
        for row, f in enumerate(functionals):
            if f.of_reactions:
                along = K.T @ f.weights
                explicit = f.weights @ dR
            else:
                along = f.weights.copy()
                explicit = np.zeros(dR.shape[1])
            along[~active] = 0.0
            z = np.real(solve(along)) if np.any(along) else np.zeros(system.n_dofs)
            if np.linalg.norm(reduced @ z - along) > CONSISTENT * np.linalg.norm(along):
                raise ConvergenceError(
                    f"{f.name}: no gradient at load factor {state.load_factor:.6g}: the "
                    "quantity moves with a motion the membrane does not resist (a slack or "
                    "wrinkled free edge); measure it where the membrane is held taut",
                    [],
                )
            gradients[row] = explicit - z[active] @ dR[active]
        du = None
        if displacements and evaluation.symmetric:
            du = np.zeros_like(dR)
            for column in range(dR.shape[1]):
                load = np.where(active, dR[:, column], 0.0)
                du[:, column] = -np.real(solve(load)) if np.any(load) else 0.0
            du[~active] = 0.0
            if not np.all(np.isfinite(du)):
                du = None  # no prediction rather than a start that cannot be evaluated
    finally:
        backend.release()
    return gradients, du
