"""The model: a mesh, a material, supports and loads, solved in load steps.

Example::

    mesh = wrinkle.mesh.rectangle(1.0, 1.0, 10, 10)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1e3, nu=0.3, thickness=0.1))
    model.fix(mesh.node_sets["bottom"])
    model.prescribe(mesh.node_sets["top"], displacement=(0.05, 0.02, 0.0))
    results = model.solve(steps=5)
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from wrinkle.assembly import DOFS_PER_NODE, SparsityPattern
from wrinkle.element import ElementResult, MembraneElements
from wrinkle.kinematics import element_coordinates, reference_geometry
from wrinkle.materials.base import Material
from wrinkle.mesh import Mesh
from wrinkle.solvers import ConvergenceError, make_solver
from wrinkle.solvers.base import Evaluation, EvaluationFailure
from wrinkle.wrinkling import SLACK, TAUT, WRINKLED, Wrinkling, WrinklingError

logger = logging.getLogger("wrinkle")

COMPONENTS = {"x": 0, "y": 1, "z": 2}


def _component_indices(components: str | Sequence[str]) -> list[int]:
    try:
        return [COMPONENTS[c] for c in components]
    except KeyError:
        raise ValueError(f"components must be drawn from 'x', 'y', 'z', got {components!r}") from None


class Model:
    """A membrane model: mesh, material with wrinkling, supports and loads.

    mesh: ``Mesh``; material: a ``Material`` (wrapped in ``Wrinkling``) or a ``Wrinkling``;
    fibre_direction: (3,) or (n_elements, 3) vector projected onto each element as the
    material axis 1; fibre_angle: radians (scalar or (n_elements,)) turning it about the normal.
    """

    def __init__(
        self,
        mesh: Mesh,
        material: Material | Wrinkling,
        fibre_direction: Sequence[float] | np.ndarray = (1.0, 0.0, 0.0),
        fibre_angle: float | np.ndarray = 0.0,
    ):
        self.mesh = mesh
        wrinkling = material if isinstance(material, Wrinkling) else Wrinkling(material)
        geometry = reference_geometry(mesh.nodes, mesh.triangles, fibre_direction, fibre_angle)
        self.elements = MembraneElements(geometry, wrinkling)
        self.pattern = SparsityPattern(mesh.triangles, mesh.n_nodes)
        self.n_dofs = DOFS_PER_NODE * mesh.n_nodes
        self.constrained = np.zeros(self.n_dofs, dtype=bool)
        self.prescribed = np.zeros(self.n_dofs)  # displacement at full load
        self.forces = np.zeros(self.n_dofs)  # nodal forces at full load
        self.force_round_off = self._force_round_off()

    def _force_round_off(self) -> float:
        """Residual norm that round-off in the strains E = (C - I)/2 alone can produce:
        100 eps |dN/dE at C = I| (sum over elements of (A0 |grad psi|)^2)^(1/2), force."""
        g = self.elements.geometry
        material = self.elements.material.material
        stiffness = np.linalg.norm(material.response(np.eye(2)[None]).tangent)
        per_element = g.area * np.linalg.norm(g.shape_gradient.reshape(-1, 6), axis=1)
        return float(100 * np.finfo(float).eps * stiffness * np.linalg.norm(per_element))

    # -- supports and loads -------------------------------------------------------------
    def _node_indices(self, nodes) -> np.ndarray:
        nodes = np.atleast_1d(np.asarray(nodes))
        if nodes.dtype == bool:
            nodes = np.flatnonzero(nodes)
        if nodes.size == 0:
            raise ValueError("no nodes selected")
        bad = (nodes < 0) | (nodes >= self.mesh.n_nodes)
        if np.any(bad):
            raise ValueError(f"node {nodes[bad][0]} does not exist (mesh has {self.mesh.n_nodes})")
        return nodes.astype(np.int64)

    def fix(self, nodes, components: str | Sequence[str] = "xyz") -> None:
        """Hold the given displacement components of ``nodes`` at zero."""
        nodes = self._node_indices(nodes)
        for c in _component_indices(components):
            self.constrained[DOFS_PER_NODE * nodes + c] = True
            self.prescribed[DOFS_PER_NODE * nodes + c] = 0.0

    def prescribe(self, nodes, displacement) -> None:
        """Prescribe displacements reached at load factor 1.

        displacement: (3,) for all nodes or (k, 3) per node; a NaN component is left free.
        """
        nodes = self._node_indices(nodes)
        values = np.broadcast_to(np.asarray(displacement, dtype=float), (nodes.size, 3))
        dofs = DOFS_PER_NODE * nodes[:, None] + np.arange(3)
        set_ = ~np.isnan(values)
        self.constrained[dofs[set_]] = True
        self.prescribed[dofs[set_]] = values[set_]

    def add_nodal_force(self, nodes, force) -> None:
        """Add a dead nodal force (3,) or (k, 3), reached at load factor 1."""
        nodes = self._node_indices(nodes)
        values = np.broadcast_to(np.asarray(force, dtype=float), (nodes.size, 3))
        if not np.all(np.isfinite(values)):
            raise ValueError("nodal force must be finite")
        np.add.at(self.forces, DOFS_PER_NODE * nodes[:, None] + np.arange(3), values)

    # -- evaluation ---------------------------------------------------------------------
    def evaluate_elements(self, u: np.ndarray, stiffness: bool = True) -> ElementResult:
        """Element forces, stiffness and states at displacements u, (n_dofs,)."""
        x = self.mesh.nodes + u.reshape(-1, 3)
        try:
            return self.elements.evaluate(
                element_coordinates(x, self.mesh.triangles), stiffness=stiffness
            )
        except WrinklingError as error:
            raise EvaluationFailure(str(error)) from error

    def internal_forces(self, u: np.ndarray) -> np.ndarray:
        """Global internal force vector f*, (n_dofs,)."""
        return self.pattern.assemble_vector(self.evaluate_elements(u, stiffness=False).forces)

    def problem(self, load_factor: float = 1.0, prescribed: np.ndarray | None = None):
        """The nonlinear problem at one load level (see ``StepProblem``)."""
        if prescribed is None:
            prescribed = load_factor * self.prescribed
        return StepProblem(self, load_factor * self.forces, prescribed)

    def check_supports(self) -> None:
        """Raise ValueError if no displacement component is supported at all."""
        for c, name in enumerate("xyz"):
            if not np.any(self.constrained[c::3]):
                raise ValueError(
                    f"no node is supported in {name}: rigid-body motion is unrestrained"
                )

    # -- solution -----------------------------------------------------------------------
    def solve(
        self,
        steps: int = 1,
        method: str = "newton",
        tolerance: float = 1e-8,
        max_iterations: int | None = None,
        min_step: float = 1e-4,
        u0: np.ndarray | None = None,
    ) -> Results:
        """Proportional stepping of loads and prescribed displacements from 0 to 1.

        ``steps`` equal increments of the load factor are the aim; a step that fails is cut in
        half (down to ``min_step``) and the increment grows again after easy steps (at most
        back to 1/steps). Raises ConvergenceError, with the converged steps in its
        ``results`` attribute, if a step cannot be solved. ``max_iterations`` None takes the
        method's default.
        """
        self.check_supports()
        solver = make_solver(method, tolerance, max_iterations)
        u = np.zeros(self.n_dofs) if u0 is None else np.array(u0, dtype=float)
        results = Results(self)
        target = 1.0 / steps
        increment = target
        factor = 0.0
        while factor < 1.0 - 1e-12:
            trial_factor = min(1.0, factor + increment)
            try:
                u, solved = self.solve_step(u, trial_factor, solver)
            except ConvergenceError as error:
                if increment / 2 < min_step:
                    failure = ConvergenceError(
                        f"load step to factor {trial_factor:.6g} failed with increment "
                        f"{increment:.3g} (minimum {min_step:.3g}): {error}",
                        error.history,
                    )
                    failure.results = results
                    raise failure from error
                increment /= 2
                logger.info("step to %.6g failed; increment cut to %.4g", trial_factor, increment)
                continue
            factor = trial_factor
            results.append(factor, u, solved)
            logger.info(
                "load factor %.6g converged in %d iterations", factor, solved.iterations
            )
            if solved.iterations <= 6 and increment < target:
                increment = min(target, 2 * increment)
        return results

    def solve_step(self, u: np.ndarray, load_factor: float, solver, prescribed=None):
        """Solve one load level from the displacements u; returns (u, SolverResult)."""
        problem = self.problem(load_factor, prescribed)
        start = np.where(self.constrained, problem.prescribed, u)
        solved = solver.solve(problem, start)
        return solved.u, solved


class StepProblem:
    """Residual, stiffness and potential energy at one load level (the solvers' ``Problem``).

    forces: (n_dofs,) external nodal forces; prescribed: (n_dofs,) values of the constrained
    displacement components.
    """

    def __init__(self, model: Model, forces: np.ndarray, prescribed: np.ndarray):
        self.model = model
        self.forces = forces
        self.prescribed = prescribed
        self.free = ~model.constrained
        pattern = model.pattern
        self._constraint_positions = pattern.constraint_positions(model.constrained)
        self._constrained_diagonal = pattern.diagonal[model.constrained]

    def evaluate(self, u: np.ndarray, stiffness: bool = True) -> Evaluation:
        model = self.model
        result = model.evaluate_elements(u, stiffness=stiffness)
        internal = model.pattern.assemble_vector(result.forces)
        residual = np.where(self.free, self.forces - internal, 0.0)
        reactions = internal[~self.free] - self.forces[~self.free]
        scale = max(np.linalg.norm(self.forces), np.linalg.norm(reactions))
        energy = float(np.sum(result.energy) - self.forces @ u)
        state = result.response.state
        counts = (
            int(np.count_nonzero(state == TAUT)),
            int(np.count_nonzero(state == WRINKLED)),
            int(np.count_nonzero(state == SLACK)),
        )
        K = None
        if stiffness:
            data = model.pattern.assemble_data(result.stiffness)
            data[self._constraint_positions] = 0.0
            data[self._constrained_diagonal] = 1.0
            K = model.pattern.matrix(data)
        return Evaluation(residual, energy, scale, counts, K, model.force_round_off)


@dataclass
class StepResult:
    """One converged load step: load factor, displacements (n_dofs,), solver information."""

    load_factor: float
    displacement: np.ndarray
    iterations: int
    residual: float
    reactions: np.ndarray  # (n_dofs,) internal minus external force, nonzero at supports
    states: tuple[int, int, int]


class Results:
    """Converged load steps of a model, in order."""

    def __init__(self, model: Model):
        self.model = model
        self.steps: list[StepResult] = []

    def append(self, load_factor: float, u: np.ndarray, solved) -> None:
        ev = solved.evaluation
        internal = self.model.internal_forces(u)
        reactions = np.where(self.model.constrained, internal - load_factor * self.model.forces, 0)
        self.steps.append(
            StepResult(load_factor, u.copy(), solved.iterations, ev.residual_norm, reactions,
                       ev.states)
        )

    @property
    def final(self) -> StepResult:
        return self.steps[-1]

    def __len__(self) -> int:
        return len(self.steps)
