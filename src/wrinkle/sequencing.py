"""Mesh sequencing: the first load step started from the solutions of coarser meshes.

A model can be solved level by level (nested iteration) on a hierarchy of meshes of one
reference surface, coarsest first: meshes refined k times (``[mesh] refine = k``,
``wrinkle.refinement``), independent meshes (``[mesh] levels``, such as gmsh meshes of
decreasing size), or both. The first load step is solved on the coarsest mesh from the
reference state, its solution interpolated onto the next mesh and solved there, and so on;
the finest mesh, the model's own, starts from the interpolated solution of the level below
and is solved to the case's tolerance like any other step. Between a mesh and the same mesh
refined once the interpolation is ``Refinement.prolong`` (exact for the linear elements'
fields); between any other two levels it is ``wrinkle.transfer.PointTransfer``, linear at
each fine node's closest point on the coarser surface. The coarse levels only provide a
start: the answer is the finest mesh's, to its own convergence test. A coarse level that does
not converge ends the sequence, and the step starts as without it.

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

from wrinkle.mesh import Mesh
from wrinkle.post import support_reactions
from wrinkle.refinement import Refinement, refine
from wrinkle.solvers.base import ConvergenceError, Evaluation
from wrinkle.solvers.settings import SolverSettings
from wrinkle.solvers.stepping import solve_step
from wrinkle.solvers.stopping import AccuracyStop, Quantities
from wrinkle.timing import Stopwatch
from wrinkle.transfer import PointTransfer

if TYPE_CHECKING:
    from wrinkle.model import Model

__all__ = ["NestedStart", "level_transfer", "quantities_of"]

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


def level_transfer(coarse: Mesh, fine: Mesh, level: int) -> Refinement | PointTransfer:
    """The interpolation from the mesh of level ``level - 1``, ``coarse``, onto the next one,
    ``fine``: ``Refinement.prolong`` where ``fine`` is ``coarse`` refined once
    (``wrinkle.refinement.refine``), ``PointTransfer`` otherwise. Raises ValueError (naming
    the levels) where ``fine`` has no more elements than ``coarse`` or leaves its surface."""
    if fine.n_elements <= coarse.n_elements:
        raise ValueError(
            f"nested: level {level} ({fine.n_elements:,} elements) is not finer than level "
            f"{level - 1} ({coarse.n_elements:,} elements)"
        )
    if fine.n_elements == 4 * coarse.n_elements:
        refinement = refine(coarse)
        same = refinement.mesh.n_nodes == fine.n_nodes and np.array_equal(
            refinement.mesh.triangles, fine.triangles
        )
        if same and np.allclose(refinement.mesh.nodes, fine.nodes):
            return refinement
    try:
        return PointTransfer(coarse, fine, names=(f"level {level - 1}", f"level {level}"))
    except ValueError as error:
        raise ValueError(f"nested: {error}") from None


class NestedStart:
    """The first step's start from coarser models (the module docstring), a ``first_guess``
    of ``wrinkle.solvers.stepping.follow_load_path``.

    coarse: the models of the coarser meshes of the same reference surface, coarsest first,
    each with fewer elements than the next, the last one's fewer than ``fine``'s (levels 0 ..
    len(coarse) - 1, ``fine`` being level len(coarse)); between two levels the solution is
    moved by ``level_transfer``. settings: how each level is solved; timer: the stopwatch the
    levels' work is charged to; probes: {name: node indices of ``fine``'s mesh}, watched by
    the accuracy stop (``settings.convergence == "accuracy"``, ``stop``) on the finest level.
    Raises ValueError for an empty ``coarse``, a level not finer
    than the one below, or a level off the surface of the one below.
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
        chain = [*self.coarse, fine]
        self.transfers: list[Refinement | PointTransfer] = [
            level_transfer(lower.mesh, upper.mesh, level + 1)
            for level, (lower, upper) in enumerate(zip(chain[:-1], chain[1:]))
        ]

    def __call__(self, load_factor: float) -> np.ndarray | None:
        """The start of the finest mesh at ``load_factor``, (n_dofs,), or None if a coarse
        level does not converge."""
        u: np.ndarray | None = None
        energy = float("nan")
        for level, model in enumerate(self.coarse):
            system = model.discretise()
            start = np.zeros(system.n_dofs)
            if u is not None:
                start = self.transfers[level - 1].prolong(u.reshape(-1, 3)).ravel()
            problem = system.at(load_factor)
            if self.timer is not None:
                problem.timer = self.timer
            solver = self.settings.solver()
            stop = None
            if u is not None:
                stop = self._accuracy_stop(energy, self.coarse[level - 1], model)
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
        return self.transfers[-1].prolong(u.reshape(-1, 3)).ravel()

    def _accuracy_stop(
        self,
        coarse_energy: float,
        lower: Model,
        model: Model,
        probes: Mapping[str, np.ndarray] | None = None,
    ) -> AccuracyStop | None:
        """The accuracy stop of ``model`` solved from the level below, ``lower``, which
        converged with energy coarse_energy; None unless the settings ask for it. The
        energy error of linear elements falls at most like h^2, as 1 / (number of
        elements), so the level's share of the difference is 1 / (n / n_lower - 1)."""
        if self.settings.convergence != "accuracy":
            return None
        ratio = model.mesh.n_elements / lower.mesh.n_elements
        return AccuracyStop(
            coarse_energy,
            quantities_of(model, probes),
            energy=self.settings.accuracy_energy,
            change=self.settings.accuracy_change,
            order_factor=ratio - 1.0,
        )

    def stop(self, load_factor: float) -> AccuracyStop | None:
        """The accuracy stop of the finest mesh's solve at ``load_factor`` from the start
        this object gave (None if it gave none there, or the settings do not ask for it); a
        ``first_stop`` of ``wrinkle.solvers.stepping.follow_load_path``."""
        if load_factor not in self.energies:
            return None
        return self._accuracy_stop(
            self.energies[load_factor], self.coarse[-1], self.fine, self.probes
        )
