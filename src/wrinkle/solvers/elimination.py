"""Nonlinear elimination: the part of the sheet out of balance solved on its own after each
global Newton step (issue 18, item 3; docs/solvers.md, Nonlinear elimination).

A global step u -> u + du of the regularised Newton method leaves most of the residual
r = f - f* on a few elements: the tips of folds and the edges of taut pockets, whose state
changed within the step. Nonlinear elimination (Lanzkron, Rose & Wilkes, SIAM J. Sci. Comput.
17, 1996; Cai & Li, SIAM J. Sci. Comput. 33, 2011) removes it before the global acceptance
test: the nodes that carry ``share`` of |r(u + du)|^2, at most ``most`` of the nodes, grown by
``layers`` rings of elements, are a patch; the potential energy is minimised over the patch's
free components with every other component held at its value at u + du (the same regularised
Newton method on the patch's own sub-system, ``wrinkle.system.DiscreteSystem.patch``), until
the patch's residual is below the global target tolerance x force scale or ``iterations`` are
spent; the global step's gain ratio is then taken at the relaxed point. Each local iterate
lowers the energy, so the relaxed point is never worse than u + du by the energy; a patch
whose solve fails leaves u + du as it was.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from wrinkle.solvers.base import (
    AcceptedStep,
    ConvergenceError,
    Evaluation,
    Problem,
    deferring,
    try_evaluate,
)
from wrinkle.solvers.newton import RegularisedNewton
from wrinkle.timing import Stopwatch

__all__ = ["Elimination", "seed_nodes"]


def seed_nodes(residual: np.ndarray, share: float, most: float) -> np.ndarray | None:
    """The fewest nodes whose residual forces carry ``share`` of |r|^2, at most ``most`` of
    the nodes (at least one), as (n_nodes,) bool; residual (n_dofs,) node by node. None where
    the residual is zero."""
    per_node = np.sum(residual.reshape(-1, 3) ** 2, axis=1)
    total = float(per_node.sum())
    if not total > 0.0:
        return None
    order = np.argsort(per_node)[::-1]
    needed = int(np.searchsorted(np.cumsum(per_node[order]), share * total)) + 1
    count = min(needed, max(1, int(most * per_node.size)))
    nodes = np.zeros(per_node.size, dtype=bool)
    nodes[order[:count]] = True
    return nodes


class _Balanced:
    """The local solve's stop (``wrinkle.solvers.base.StopRule``): its residual at most
    ``target`` (force), or ``budget`` accepted iterations made."""

    def __init__(self, target: float, budget: int):
        self.target, self.budget, self.calls = target, budget, 0

    def __call__(self, step: AcceptedStep) -> dict[str, Any] | None:
        self.calls += 1
        if step.evaluation.residual_norm <= self.target or self.calls > self.budget:
            return {"residual": step.evaluation.residual_norm}
        return None


@dataclass(frozen=True)
class Elimination:
    """The settings of nonlinear elimination (module docstring).

    share: of the trial point's squared residual the patch's seed nodes carry; most: the
    largest share of the nodes seeded; layers: rings of elements grown around the seeds;
    iterations: the most local Newton iterations of one patch. The work goes to the
    problem's stopwatch (``wrinkle.timing.Stopwatch``: patches tried, local iterations and
    factorisations, and the local solves' times in their parts).
    """

    share: float = 0.9
    most: float = 0.1
    layers: int = 2
    iterations: int = 100

    def relax(
        self,
        problem: Problem,
        point: np.ndarray,
        trial: Evaluation,
        tolerance: float,
        linear_solver: str = "auto",
    ) -> tuple[np.ndarray, Evaluation]:
        """(point, evaluation) after the patch of ``trial`` (problem's evaluation at point,
        (n_dofs,)) is solved to tolerance x the trial's force scale, with the linear solver
        named (``wrinkle.solvers.linear``); point and trial as they were where the problem
        has no patches (``patch``, ``grow``), the residual is zero, or the patch's solve
        fails."""
        patch, grow = getattr(problem, "patch", None), getattr(problem, "grow", None)
        seeds = seed_nodes(trial.residual, self.share, self.most)
        if patch is None or grow is None or seeds is None:
            return point, trial
        try:
            local, start, dofs = patch(grow(seeds, self.layers), point)
        except ValueError:  # bending, cables or edge loads: no patch
            return point, trial
        solver = RegularisedNewton(
            tolerance=1e-16, max_iterations=self.iterations + 1, linear_solver=linear_solver
        )
        solver.quiet, solver.elimination = True, None
        timer = getattr(problem, "timer", None) or Stopwatch()
        before = timer.factorisations
        timer.patches += 1
        try:
            solved = solver.solve(
                local, start, stop=_Balanced(tolerance * trial.force_scale, self.iterations)
            )
        except ConvergenceError as error:  # no acceptable local step: the point as it was
            timer.local_iterations += max(len(error.history) - 1, 0)
            return point, trial
        finally:
            timer.local_factorisations += timer.factorisations - before
            solver.release()  # (PARDISO keeps MKL's memory until released)
        timer.local_iterations += solved.iterations
        if solved.iterations == 0:
            return point, trial
        relaxed = point.copy()
        relaxed[dofs] = solved.u
        evaluation = try_evaluate(problem, relaxed, **deferring(problem))
        return (point, trial) if evaluation is None else (relaxed, evaluation)
