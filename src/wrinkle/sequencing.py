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

With ``[solver] convergence = "accuracy"`` every level above the coarsest may end early, by the
accuracy stop (``wrinkle.solvers.stopping``): the level below gives the energy against which
the mesh's discretisation error is estimated, and the quantities watched are, beside every
displacement component, the probes' mean displacements and the supports' reactions
(``quantities_of``).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from wrinkle.post import support_reactions
from wrinkle.refinement import Refinement, refine
from wrinkle.solvers.base import ConvergenceError, Evaluation
from wrinkle.solvers.settings import SolverSettings
from wrinkle.solvers.stepping import solve_step
from wrinkle.solvers.stopping import AccuracyStop, Quantities
from wrinkle.timing import Stopwatch

if TYPE_CHECKING:
    from wrinkle.model import Model

__all__ = ["NestedStart", "quantities_of"]

logger = logging.getLogger("wrinkle")


def quantities_of(model: Model, probes: Mapping[str, np.ndarray] | None = None) -> Quantities:
    """The quantities of interest that the accuracy stop watches on ``model``, beside every
    displacement component: each probe's mean displacement (x, y, z; probes: {name: node
    indices}) and each support's reaction (Fx, Fy, Fz). Their scales: the largest nodal
    displacement (length), and the larger of the support's resultant and the evaluation's
    force scale (force)."""
    probes = dict(probes or {})
    supports = list(model.supports)

    def quantities(u: np.ndarray, ev: Evaluation) -> tuple[list[str], np.ndarray, np.ndarray]:
        nodal = u.reshape(-1, 3)
        largest = float(np.linalg.norm(nodal, axis=1).max(initial=0.0))
        names: list[str] = []
        values: list[float] = []
        scales: list[float] = []
        for name, nodes in probes.items():
            names += [f"{name}_ux", f"{name}_uy", f"{name}_uz"]
            values += nodal[nodes].mean(axis=0).tolist()
            scales += [largest] * 3
        if ev.reactions is not None:
            for label, force in support_reactions(supports, ev.reactions).items():
                names += [f"{label}_Fx", f"{label}_Fy", f"{label}_Fz"]
                values += force
                scales += [max(float(np.linalg.norm(force)), ev.force_scale)] * 3
        return names, np.array(values), np.array(scales)

    return quantities


class NestedStart:
    """The first step's start from coarser models (the module docstring), a ``first_guess``
    of ``wrinkle.solvers.stepping.follow_load_path``.

    coarse: the models of the coarser meshes, coarsest first, each mesh refined once
    (``wrinkle.refinement.refine``) being the next one's and the last one's being ``fine``'s
    (ValueError otherwise); settings: how each level is solved; timer: the stopwatch the
    levels' work is charged to; probes: {name: node indices of ``fine``'s mesh}, watched by
    the accuracy stop (``settings.convergence == "accuracy"``, ``stop``) on the finest level.
    """

    def __init__(
        self,
        coarse: Sequence[Model],
        fine: Model,
        settings: SolverSettings,
        timer: Stopwatch | None = None,
        probes: Mapping[str, np.ndarray] | None = None,
    ):
        if not coarse:
            raise ValueError("nested: give at least one coarser model")
        self.coarse = list(coarse)
        self.fine = fine
        self.settings = settings
        self.timer = timer
        self.probes = dict(probes or {})
        # load factor -> the energy of the finest coarse level converged there
        self.energies: dict[float, float] = {}
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
        energy = float("nan")
        for level, model in enumerate(self.coarse):
            system = model.discretise()
            start = np.zeros(system.n_dofs)
            if u is not None:
                start = self.refinements[level - 1].prolong(u.reshape(-1, 3)).ravel()
            problem = system.at(load_factor)
            if self.timer is not None:
                problem.timer = self.timer
            solver = self.settings.solver()
            stop = None if u is None else self._accuracy_stop(energy, model)
            try:
                solved = solve_step(
                    problem,
                    start,
                    solver,
                    predicted=None if u is None else start,
                    trusted=u is not None,
                    stop=stop,
                )
            except ConvergenceError as error:
                logger.info("nested: level %d did not converge (%s); not used", level, error)
                return None
            finally:
                solver.release()  # the finer levels need the memory
                model.release()
            u, energy = solved.u, solved.evaluation.energy
            logger.info(
                "nested: level %d (%d elements) converged in %d iterations (stopped by the "
                "%s test)",
                level,
                model.mesh.n_elements,
                solved.iterations,
                solved.stopped_by,
            )
        if u is None:  # (no coarse level: not reached, the constructor refuses it)
            return None
        self.energies[load_factor] = energy
        return self.refinements[-1].prolong(u.reshape(-1, 3)).ravel()

    def _accuracy_stop(
        self, coarse_energy: float, model: Model, probes: Mapping[str, np.ndarray] | None = None
    ) -> AccuracyStop | None:
        """The accuracy stop of a level solved from the level below (energy coarse_energy),
        or None unless the settings ask for it."""
        if self.settings.convergence != "accuracy":
            return None
        return AccuracyStop(
            coarse_energy,
            quantities_of(model, probes),
            energy=self.settings.accuracy_energy,
            change=self.settings.accuracy_change,
        )

    def stop(self, load_factor: float) -> AccuracyStop | None:
        """The accuracy stop of the finest mesh's solve at ``load_factor`` from the start
        this object gave (None if it gave none there, or the settings do not ask for it); a
        ``first_stop`` of ``wrinkle.solvers.stepping.follow_load_path``."""
        if load_factor not in self.energies:
            return None
        return self._accuracy_stop(self.energies[load_factor], self.fine, self.probes)
