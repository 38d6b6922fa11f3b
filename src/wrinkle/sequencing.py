"""Mesh sequencing: the first load step started from the solutions of coarser meshes.

A model on a mesh refined k times (``[mesh] refine = k``, ``wrinkle.refinement``) can be
solved level by level (nested iteration): the first load step is solved on the coarsest mesh
from the reference state, its solution interpolated onto the next mesh (``Refinement.prolong``,
exact for the linear elements' fields) and solved there, and so on; the finest mesh, the
model's own, starts from the interpolated solution of the level below and is solved to the
case's tolerance like any other step. The coarse levels only provide a start: the answer is
the finest mesh's, to its own convergence test. A coarse level that does not converge ends
the sequence, and the step starts as without it.

It pays where the coarse solution is close to the fine one, as for a membrane with its
bending stiffness (``wrinkle.bending``): the airbag's 32,768-element level then takes 8
iterations instead of 26 from the flat sheet. For the pure membrane it does not: the
interpolated state has none of the finer mesh's folds, and the iteration from it is longer
than from the flat sheet (docs/notes/2026-12-solver-accuracy.md).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from wrinkle.refinement import Refinement, refine
from wrinkle.solvers.base import ConvergenceError
from wrinkle.solvers.settings import SolverSettings
from wrinkle.solvers.stepping import solve_step
from wrinkle.timing import Stopwatch

if TYPE_CHECKING:
    from wrinkle.model import Model

__all__ = ["NestedStart"]

logger = logging.getLogger("wrinkle")


class NestedStart:
    """The first step's start from coarser models (the module docstring), a ``first_guess``
    of ``wrinkle.solvers.stepping.follow_load_path``.

    coarse: the models of the coarser meshes, coarsest first, each mesh refined once
    (``wrinkle.refinement.refine``) being the next one's and the last one's being ``fine``'s
    (ValueError otherwise); settings: how each level is solved; timer: the stopwatch the
    levels' work is charged to.
    """

    def __init__(
        self,
        coarse: Sequence[Model],
        fine: Model,
        settings: SolverSettings,
        timer: Stopwatch | None = None,
    ):
        if not coarse:
            raise ValueError("nested: give at least one coarser model")
        self.coarse = list(coarse)
        self.settings = settings
        self.timer = timer
        self.refinements: list[Refinement] = []
        chain = [*self.coarse, fine]
        for level, (lower, upper) in enumerate(zip(chain[:-1], chain[1:])):
            refinement = refine(lower.mesh)
            same = refinement.mesh.n_nodes == upper.mesh.n_nodes and np.array_equal(
                refinement.mesh.triangles, upper.mesh.triangles
            )
            if not same or not np.allclose(refinement.mesh.nodes, upper.mesh.nodes):
                raise ValueError(
                    f"nested: the mesh of level {level + 1} is not the mesh of level {level} "
                    "refined once (wrinkle.refinement.refine)"
                )
            self.refinements.append(refinement)

    def __call__(self, load_factor: float) -> np.ndarray | None:
        """The start of the finest mesh at ``load_factor``, (n_dofs,), or None if a coarse
        level does not converge."""
        u: np.ndarray | None = None
        for level, model in enumerate(self.coarse):
            system = model.discretise()
            start = np.zeros(system.n_dofs)
            if u is not None:
                start = self.refinements[level - 1].prolong(u.reshape(-1, 3)).ravel()
            problem = system.at(load_factor)
            if self.timer is not None:
                problem.timer = self.timer
            solver = self.settings.solver()
            try:
                solved = solve_step(
                    problem,
                    start,
                    solver,
                    predicted=None if u is None else start,
                    trusted=u is not None,
                )
            except ConvergenceError as error:
                logger.info("nested: level %d did not converge (%s); not used", level, error)
                return None
            finally:
                solver.release()  # the finer levels need the memory
                model.release()
            u = solved.u
            logger.info(
                "nested: level %d (%d elements) converged in %d iterations",
                level,
                model.mesh.n_elements,
                solved.iterations,
            )
        if u is None:  # (no coarse level: not reached, the constructor refuses it)
            return None
        return self.refinements[-1].prolong(u.reshape(-1, 3)).ravel()
