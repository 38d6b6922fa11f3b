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

from wrinkle import compiled
from wrinkle.assembly import DOFS_PER_NODE, SparsityPattern
from wrinkle.element import (
    KERNEL_BLOCK,
    ElementResult,
    MembraneElements,
    unit_tension_stiffness,
)
from wrinkle.kinematics import ReferenceGeometry, element_coordinates, reference_geometry
from wrinkle.loads import (
    boundary_edges,
    edge_dead_forces,
    edge_follower_forces,
    pressure_forces,
    pressure_volume,
    subtract_pressure_stiffness,
)
from wrinkle.materials.base import Material
from wrinkle.mesh import Mesh
from wrinkle.solvers import ConvergenceError, make_solver
from wrinkle.solvers.base import Evaluation, EvaluationFailure, is_converged, try_evaluate
from wrinkle.timing import ASSEMBLY, ELEMENTS, Stopwatch
from wrinkle.wrinkling import SLACK, TAUT, WRINKLED, Wrinkling, WrinklingError

logger = logging.getLogger("wrinkle")

COMPONENTS = {"x": 0, "y": 1, "z": 2}
SOLVE_DEFAULTS = {"steps": 1, "method": "newton", "tolerance": 1e-6, "max_iterations": None,
                  "min_step": 1e-4, "linear_solver": "auto"}


def _component_indices(components: str | Sequence[str]) -> list[int]:
    try:
        return [COMPONENTS[c] for c in components]
    except KeyError:
        raise ValueError(f"components must be drawn from 'x', 'y', 'z', got {components!r}") from None


@dataclass
class Support:
    """A named set of supported nodes and the dofs it holds; its reaction is the sum over
    those dofs (a node held by two supports in different directions counts in each for the
    directions it holds there)."""

    label: str
    nodes: np.ndarray
    dofs: np.ndarray


def _indices(selection, count: int, what: str) -> np.ndarray:
    """Indices (k,) int64 of a selection of nodes or elements given as indices or a mask."""
    selection = np.atleast_1d(np.asarray(selection))
    if selection.dtype == bool:
        selection = np.flatnonzero(selection)
    if selection.size == 0:
        raise ValueError(f"no {what}s selected")
    bad = (selection < 0) | (selection >= count)
    if np.any(bad):
        raise ValueError(f"{what} {selection[bad][0]} does not exist (mesh has {count})")
    return selection.astype(np.int64)


class Model:
    """A membrane model: mesh, materials with wrinkling, supports and loads.

    mesh: ``Mesh``; material: a ``Material`` (wrapped in ``Wrinkling``) or a ``Wrinkling`` for
    all elements (or None, then ``assign_material`` for each region); fibre_direction: (3,) or
    (n_elements, 3) vector projected onto each element as the material axis 1; fibre_angle:
    radians (scalar or (n_elements,)) turning it about the element normal.
    """

    def __init__(
        self,
        mesh: Mesh,
        material: Material | Wrinkling | None = None,
        fibre_direction: Sequence[float] | np.ndarray = (1.0, 0.0, 0.0),
        fibre_angle: float | np.ndarray = 0.0,
    ):
        self.mesh = mesh
        n = mesh.n_elements
        self._fibre_direction = np.tile(np.asarray(fibre_direction, dtype=float), (n, 1)) if (
            np.ndim(fibre_direction) == 1) else np.array(fibre_direction, dtype=float)
        self._fibre_angle = np.broadcast_to(np.asarray(fibre_angle, dtype=float), (n,)).copy()
        self._material_of_element = np.full(n, -1)
        self._materials: list[Wrinkling] = []
        self._groups = None
        self._constraint_data = None  # see constraint_data
        self.pattern = SparsityPattern(mesh.triangles, mesh.n_nodes)
        self.n_dofs = DOFS_PER_NODE * mesh.n_nodes
        self.constrained = np.zeros(self.n_dofs, dtype=bool)
        self.prescribed = np.zeros(self.n_dofs)  # displacement at full load
        self.forces = np.zeros(self.n_dofs)  # dead nodal forces at full load
        self.supports: list[Support] = []
        self._pressure = np.zeros(n)  # follower pressure at full load, per element
        self._edge_follower: list[tuple] = []  # (node triples, q, triangle, local dofs)
        # what a case file adds: defaults of solve(), probes and units for the output
        self.solver_settings: dict = {}
        self.probes: dict[str, np.ndarray] = {}
        self.units: dict[str, str] = {}
        self.source = None
        self.verification: dict = {}  # a case file's [verification] table
        if material is not None:
            self.assign_material(material)

    # -- materials ----------------------------------------------------------------------
    def _element_indices(self, elements) -> np.ndarray:
        if elements is None:
            return np.arange(self.mesh.n_elements)
        return _indices(elements, self.mesh.n_elements, "element")

    def assign_material(
        self,
        material: Material | Wrinkling,
        elements=None,
        fibre_direction: Sequence[float] | np.ndarray | None = None,
        fibre_angle: float | np.ndarray | None = None,
    ) -> None:
        """Give ``elements`` (indices or mask; None = all) a material and, optionally, their
        own fibre direction ((3,) or (k, 3)) and angle (radians)."""
        elements = self._element_indices(elements)
        wrinkling = material if isinstance(material, Wrinkling) else Wrinkling(material)
        self._materials.append(wrinkling)
        self._material_of_element[elements] = len(self._materials) - 1
        if fibre_direction is not None:
            self._fibre_direction[elements] = fibre_direction
        if fibre_angle is not None:
            self._fibre_angle[elements] = fibre_angle
        self._groups = None
        self._constraint_data = None

    def _build(self) -> None:
        missing = np.flatnonzero(self._material_of_element < 0)
        if missing.size:
            raise ValueError(
                f"{missing.size} element(s) have no material, first: element {missing[0]}"
            )
        self._geometry = reference_geometry(
            self.mesh.nodes, self.mesh.triangles, self._fibre_direction, self._fibre_angle
        )
        groups = []
        for index, material in enumerate(self._materials):
            elements = np.flatnonzero(self._material_of_element == index)
            if elements.size:
                groups.append((elements, MembraneElements(self._geometry.subset(elements), material)))
        self._groups = groups
        order = np.concatenate([e for e, _ in groups])
        self._inverse_order = np.argsort(order) if len(groups) > 1 else None
        self.force_round_off = self._force_round_off()

    @property
    def geometry(self) -> ReferenceGeometry:
        """Reference geometry (areas, frames, shape gradients) of all elements."""
        if self._groups is None:
            self._build()
        return self._geometry

    @property
    def groups(self) -> list[tuple[np.ndarray, MembraneElements]]:
        """(element indices, MembraneElements) of each material."""
        if self._groups is None:
            self._build()
        return self._groups

    @property
    def elements(self) -> MembraneElements:
        """The elements of a single-material model."""
        if len(self.groups) != 1:
            raise ValueError("the model has several materials: use model.groups")
        return self.groups[0][1]

    def _force_round_off(self) -> float:
        """Residual norm that round-off alone can produce, force: 10 eps |dN/dE at C = I|
        (sum over elements of (A0 |grad psi| (1 + |X| max|grad psi|))^2)^(1/2). An element's
        strains carry a round-off of eps (1 + |X| max|grad psi|): its node coordinates are
        rounded to eps |X|, which over an edge of length 1 / max|grad psi| is a strain, so the
        floor rises with the mesh's fineness and its distance from the origin. (The factor 10
        leaves a margin of 20 to 40 over the smallest residual Newton reaches on the
        shear-stretch square, 7e-15 to 3e-13 N from 10^3 to 10^6 elements.)"""
        total = 0.0
        nodes = self.mesh.nodes
        for indices, elements in self._groups:
            g = elements.geometry
            material = elements.material.material
            stiffness = np.linalg.norm(material.response(np.eye(2)[None]).tangent)
            extent = np.abs(nodes[self.mesh.triangles[indices]]).max(axis=(1, 2))
            coordinate_noise = extent * np.abs(g.shape_gradient).max(axis=(1, 2))
            per_element = g.area * np.linalg.norm(g.shape_gradient.reshape(-1, 6), axis=1)
            total += (stiffness * np.linalg.norm(per_element * (1.0 + coordinate_noise))) ** 2
        return float(10 * np.finfo(float).eps * np.sqrt(total))

    def step_metric(self) -> np.ndarray:
        """CSR data, on ``pattern``, of the unit-tension stiffness (``unit_tension_stiffness``
        assembled: a Laplacian on each displacement component), (nnz,)."""
        g = self.geometry
        data = np.zeros(self.pattern.nnz)
        for start in range(0, g.n_elements, KERNEL_BLOCK):
            block = slice(start, min(start + KERNEL_BLOCK, g.n_elements))
            self.pattern.add_to_data(
                data, block, unit_tension_stiffness(g.area[block], g.shape_gradient[block])
            )
        return data

    def constraint_data(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """What every load step's problem needs of the supports: positions in ``pattern``'s
        data of the constrained rows and columns and of the constrained diagonal entries, and
        the step metric (``step_metric``) with those rows and columns zeroed, (nnz,). Made
        once, and again only when the supports change."""
        cached = self._constraint_data
        if cached is None or not np.array_equal(cached[0], self.constrained):
            positions = self.pattern.constraint_positions(self.constrained)
            metric = self.step_metric()
            metric[positions] = 0.0
            cached = (self.constrained.copy(), positions,
                      self.pattern.diagonal[self.constrained], metric)
            self._constraint_data = cached
        return cached[1:]

    # -- supports and loads -------------------------------------------------------------
    def _node_indices(self, nodes) -> np.ndarray:
        return _indices(nodes, self.mesh.n_nodes, "node")

    def _add_support(self, nodes: np.ndarray, dofs: np.ndarray, label: str | None) -> None:
        label = label or f"support {len(self.supports) + 1}"
        self.supports.append(Support(label, nodes, np.unique(dofs)))

    def fix(self, nodes, components: str | Sequence[str] = "xyz", label: str | None = None) -> None:
        """Hold the given displacement components of ``nodes`` at zero."""
        nodes = self._node_indices(nodes)
        dofs = (DOFS_PER_NODE * nodes[:, None] + np.array(_component_indices(components))).ravel()
        self.constrained[dofs] = True
        self.prescribed[dofs] = 0.0
        self._add_support(nodes, dofs, label)

    def prescribe(self, nodes, displacement, label: str | None = None) -> None:
        """Prescribe displacements reached at load factor 1.

        displacement: (3,) for all nodes or (k, 3) per node; a NaN component is left free.
        """
        nodes = self._node_indices(nodes)
        values = np.broadcast_to(np.asarray(displacement, dtype=float), (nodes.size, 3))
        dofs = DOFS_PER_NODE * nodes[:, None] + np.arange(3)
        set_ = ~np.isnan(values)
        self.constrained[dofs[set_]] = True
        self.prescribed[dofs[set_]] = values[set_]
        self._add_support(nodes, dofs[set_], label)

    def add_nodal_force(self, nodes, force) -> None:
        """Add a dead nodal force (3,) or (k, 3), reached at load factor 1."""
        nodes = self._node_indices(nodes)
        values = np.broadcast_to(np.asarray(force, dtype=float), (nodes.size, 3))
        if not np.all(np.isfinite(values)):
            raise ValueError("nodal force must be finite")
        np.add.at(self.forces, DOFS_PER_NODE * nodes[:, None] + np.arange(3), values)

    def add_pressure(self, value: float, elements=None) -> None:
        """Follower pressure (force per unit current area) on ``elements`` (None = all),
        positive along the element normal (x2 - x1) x (x3 - x1), reached at load factor 1."""
        if not np.isfinite(value):
            raise ValueError("pressure must be finite")
        self._pressure[self._element_indices(elements)] += value

    def add_gravity(self, acceleration, density: float, elements=None) -> None:
        """Dead weight density * reference thickness * A0 * acceleration, a third to each
        node; acceleration (3,) (length / time^2), density mass per unit volume."""
        if not density > 0:
            raise ValueError(f"density must be > 0, got {density}")
        elements = self._element_indices(elements)
        thickness = np.array([m.thickness for m in self._materials])[
            self._material_of_element[elements]
        ]
        area = self.geometry.area[elements]
        weight = (density * thickness * area / 3.0)[:, None] * np.asarray(acceleration, float)
        for k in range(3):
            np.add.at(self.forces.reshape(-1, 3), self.mesh.triangles[elements, k], weight)

    def add_edge_load(self, nodes, traction=None, normal: float | None = None,
                      follow: bool = False) -> None:
        """Load on the boundary edges whose two nodes are both in ``nodes``.

        traction: (3,) dead force per unit reference length; normal: force per unit length
        along the edge's outward normal in the membrane plane, positive pulling outwards (dead:
        per reference length, reference direction; follow=True: per current length, turning
        with the deformed edge).
        """
        nodes = self._node_indices(nodes)
        selected = np.zeros(self.mesh.n_nodes, dtype=bool)
        selected[nodes] = True
        triples, owner = boundary_edges(self.mesh.triangles)
        chosen = selected[triples[:, 0]] & selected[triples[:, 1]]
        triples, owner = triples[chosen], owner[chosen]
        if triples.shape[0] == 0:
            raise ValueError("the selected nodes contain no boundary edge")
        if (traction is None) == (normal is None):
            raise ValueError("an edge load needs either traction or normal")
        X = self.mesh.nodes[triples]
        length = np.linalg.norm(X[:, 1] - X[:, 0], axis=1)
        if normal is not None and follow:
            # place of the edge's nodes (a, b, third) in their triangle's dofs, for the stiffness
            position = np.argmax(self.mesh.triangles[owner][:, None, :] == triples[:, :, None], 2)
            dofs = (3 * position[:, :, None] + np.arange(3)).reshape(-1, 9)
            self._edge_follower.append(
                (triples, np.full(triples.shape[0], float(normal)), owner, dofs)
            )
            return
        if normal is not None:
            forces, _ = edge_follower_forces(X, np.full(triples.shape[0], float(normal)), False)
            forces = forces[:, :6]
        else:
            traction = np.broadcast_to(np.asarray(traction, dtype=float), (triples.shape[0], 3))
            forces = edge_dead_forces(length, traction)
        for k in range(2):
            np.add.at(self.forces.reshape(-1, 3), triples[:, k], forces[:, 3 * k:3 * k + 3])

    @property
    def has_follower_loads(self) -> bool:
        return bool(np.any(self._pressure != 0) or self._edge_follower)

    # -- evaluation ---------------------------------------------------------------------
    def element_coordinates(self, u: np.ndarray) -> np.ndarray:
        """Current node coordinates of every triangle at displacements u, (n_elements, 3, 3)."""
        return element_coordinates(self.mesh.nodes + u.reshape(-1, 3), self.mesh.triangles)

    def evaluate_elements(self, u: np.ndarray, stiffness: bool = True,
                          stiffness_sink=None, x_elements: np.ndarray | None = None
                          ) -> ElementResult:
        """Element forces, stiffness and states at displacements u, (n_dofs,).

        stiffness_sink(elements, K): if given, receives the stiffness block by block (mesh
        element indices or a slice, (m, 9, 9)) instead of the result holding all of it.
        x_elements: ``element_coordinates(u)`` if the caller has them.
        """
        x = self.element_coordinates(u) if x_elements is None else x_elements
        groups = self.groups
        results = []
        for index, elements in groups:
            sink = stiffness_sink
            if sink is not None and len(groups) > 1:
                def sink(rows, K, index=index):
                    stiffness_sink(index[rows], K)
            try:
                results.append(elements.evaluate(
                    x if len(groups) == 1 else x[index], stiffness=stiffness, stiffness_sink=sink
                ))
            except WrinklingError as error:  # group rows -> mesh elements
                raise EvaluationFailure(str(WrinklingError(index[error.elements]))) from error
        if len(results) == 1:
            return results[0]
        return _concatenate_results(results, self._inverse_order)

    def _pressurised(self):
        """The elements under pressure: their indices, a slice if they are all of them, None if
        there are none."""
        loaded = np.flatnonzero(self._pressure)
        if loaded.size == 0:
            return None
        return slice(0, loaded.size) if loaded.size == self.mesh.n_elements else loaded

    def _loaded_coordinates(self, u: np.ndarray, loaded, x_elements: np.ndarray | None):
        """Current coordinates (m, 3, 3) of the pressurised elements ``loaded`` (from
        ``_pressurised``): taken from x_elements (``element_coordinates(u)``) if given, else
        gathered at the displacements u."""
        if x_elements is not None:
            return x_elements[loaded]
        return (self.mesh.nodes + u.reshape(-1, 3))[self.mesh.triangles[loaded]]

    def follower_forces(self, u: np.ndarray, load_factor: float, stiffness: bool = True,
                        stiffness_sink=None, pressure_stiffness: bool = True,
                        x_elements: np.ndarray | None = None):
        """Assembled follower loads at u: forces (n_dofs,) and their load stiffness d f / d u,
        element-wise (n, 9, 9) on the triangles (None if not asked or no follower load), or
        handed block by block to ``stiffness_sink(elements, K)`` (then None is returned).
        pressure_stiffness=False leaves the pressure's out (``subtract_pressure_stiffness``
        takes it into the element blocks instead). x_elements: ``element_coordinates(u)`` if
        the caller has them."""
        x_nodes = self.mesh.nodes + u.reshape(-1, 3)
        forces = np.zeros(self.n_dofs)
        blocks = []  # (elements, K) when no sink is given
        sink = stiffness_sink or (lambda elements, k: blocks.append((elements, k.copy())))
        loaded = self._pressurised()
        if loaded is not None:
            x = self._loaded_coordinates(u, loaded, x_elements)
            pressure = load_factor * self._pressure[loaded]
            if compiled.enabled(self.mesh.n_elements):
                compiled.add_pressure_forces(forces, self.pattern.element_dofs[loaded], x,
                                             pressure)
            else:
                f, _ = pressure_forces(x, pressure, stiffness=False)
                forces += np.bincount(self.pattern.element_dofs[loaded].ravel(), f.ravel(),
                                      minlength=self.n_dofs)
            for start in range(0, x.shape[0], KERNEL_BLOCK) if stiffness and pressure_stiffness \
                    else ():
                block = slice(start, min(start + KERNEL_BLOCK, x.shape[0]))
                elements = block if isinstance(loaded, slice) else loaded[block]
                sink(elements, pressure_forces(x[block], pressure[block])[1])
        for triples, q, owner, local_dofs in self._edge_follower:
            f, k = edge_follower_forces(x_nodes[triples], load_factor * q, stiffness)
            dofs = (3 * triples[:, :, None] + np.arange(3)).reshape(-1, 9)
            forces += np.bincount(dofs.ravel(), f.ravel(), minlength=self.n_dofs)
            if stiffness:
                in_triangle = np.zeros((k.shape[0], 9, 9))
                rows = np.arange(k.shape[0])[:, None, None]
                in_triangle[rows, local_dofs[:, :, None], local_dofs[:, None, :]] = k
                sink(owner, in_triangle)
        if not blocks:
            return forces, None
        K = np.zeros((self.mesh.n_elements, 9, 9))
        for elements, k in blocks:
            np.add.at(K, elements, k)
        return forces, K

    def subtract_pressure_stiffness(self, K: np.ndarray, x: np.ndarray, elements,
                                    load_factor: float) -> None:
        """Subtract the pressure's load stiffness from the element matrices K (m, 9, 9) of
        ``elements`` (a slice or indices) in place; x (m, 3, 3) their current coordinates."""
        pressure = self._pressure[elements]
        if np.any(pressure):
            if compiled.enabled(self.mesh.n_elements):
                compiled.subtract_pressure_stiffness(K, x, load_factor * pressure)
            else:
                subtract_pressure_stiffness(K, x, load_factor * pressure)

    def pressure_work(self, u: np.ndarray, x_elements: np.ndarray | None = None) -> float:
        """Sum of p V_cone over the pressurised elements at full load (``pressure_volume``):
        the pressure's potential is minus this; exact when the boundary is held or moves in
        planes through the origin (symmetry planes), otherwise a merit for the solver only.
        x_elements: ``element_coordinates(u)`` if the caller has them."""
        loaded = self._pressurised()
        if loaded is None:
            return 0.0
        x = self._loaded_coordinates(u, loaded, x_elements)
        return float(self._pressure[loaded] @ pressure_volume(x))

    def internal_forces(self, u: np.ndarray) -> np.ndarray:
        """Global internal force vector f*, (n_dofs,)."""
        return self.pattern.assemble_vector(self.evaluate_elements(u, stiffness=False).forces)

    def reactions(self, u: np.ndarray, load_factor: float) -> np.ndarray:
        """Support reactions f* - f_ext at the constrained dofs (zero elsewhere), (n_dofs,)."""
        external = load_factor * self.forces
        if self.has_follower_loads:
            external = external + self.follower_forces(u, load_factor, stiffness=False)[0]
        return np.where(self.constrained, self.internal_forces(u) - external, 0.0)

    def support_reactions(self, reactions: np.ndarray) -> dict[str, list[float]]:
        """Sum of the reactions (n_dofs,) over the dofs each support holds (supports with the
        same label together, a component they share counted once): label -> [Fx, Fy, Fz]."""
        held: dict[str, list[np.ndarray]] = {}
        for support in self.supports:
            held.setdefault(support.label, []).append(support.dofs)
        out = {}
        for label, dofs in held.items():
            dofs = np.unique(np.concatenate(dofs))
            out[label] = np.bincount(dofs % 3, reactions[dofs], minlength=3).tolist()
        return out

    def problem(self, load_factor: float = 1.0, prescribed: np.ndarray | None = None):
        """The nonlinear problem at one load level (see ``StepProblem``)."""
        if prescribed is None:
            prescribed = load_factor * self.prescribed
        return StepProblem(self, load_factor, prescribed)

    def check_supports(self) -> None:
        """Raise ValueError if the supports leave a rigid-body motion free: the six motions
        (three translations, three rotations about the centroid) must have no combination
        that moves no supported component."""
        X = self.mesh.nodes - self.mesh.nodes.mean(axis=0)
        modes = np.zeros((self.mesh.n_nodes, 3, 6))
        modes[:, :, :3] = np.eye(3)
        for axis in range(3):
            modes[:, :, 3 + axis] = np.cross(np.eye(3)[axis], X)  # rotation about the axis
        held = modes.reshape(-1, 6)[self.constrained]
        size = np.abs(X).max() if X.size else 1.0
        held[:, 3:] /= max(size, 1e-300)
        if held.shape[0] >= 6:
            _, singular, vt = np.linalg.svd(held, full_matrices=False)
            if singular[-1] > 1e-8 * singular[0]:
                return
            free = vt[-1]
        else:
            free = np.linalg.svd(held if held.size else np.zeros((1, 6)))[2][-1]
        names = np.array(["translation in x", "translation in y", "translation in z",
                          "rotation about x", "rotation about y", "rotation about z"])
        scale = np.abs(held).max() if held.size else 1.0
        pure = np.all(np.abs(held) <= 1e-12 * scale, axis=0)  # modes no support touches
        if np.any(pure):
            motion = ", ".join(names[pure])
        else:
            motion = "a motion combining " + " and ".join(names[np.abs(free) > 0.3 * np.abs(free).max()])
        raise ValueError(
            f"rigid-body motion is unrestrained: the supports do not prevent {motion}"
        )

    # -- solution -----------------------------------------------------------------------
    def solve(
        self,
        steps: int | None = None,
        method: str | None = None,
        tolerance: float | None = None,
        max_iterations: int | None = None,
        min_step: float | None = None,
        u0: np.ndarray | None = None,
        on_step=None,
        linear_solver: str | None = None,
    ) -> Results:
        """Proportional stepping of loads and prescribed displacements from 0 to 1.

        ``steps`` equal increments of the load factor are the aim (default 1); a step that
        fails is cut in half (down to ``min_step``, default 1e-4) and the increment grows again
        after easy steps (at most back to 1/steps). From the second step on, a step starts from
        the linear extrapolation of the last two converged states (u0 being the state at load
        factor 0) where that is closer to balance than the last one, and the first step, if it
        moves supports, from the tangent prediction (``solve_step``).
        ``method`` "newton" (default) or "restricted-step"; ``tolerance`` on the residual
        force relative to the applied and reaction forces (default 1e-6); ``max_iterations``
        per step (default: the method's); ``linear_solver`` "auto" (default), "superlu",
        "pardiso", "cholmod" or "amg" (``wrinkle.solvers.linear``).
        Arguments left None take ``solver_settings`` (from a case file), then the defaults.
        ``on_step(step_result)`` is called after each converged step. Raises
        ConvergenceError, with the converged steps in its ``results`` attribute, if a step
        cannot be solved.
        """
        given = {"steps": steps, "method": method, "tolerance": tolerance,
                 "max_iterations": max_iterations, "min_step": min_step,
                 "linear_solver": linear_solver}
        settings = {**SOLVE_DEFAULTS, **self.solver_settings,
                    **{k: v for k, v in given.items() if v is not None}}
        steps, min_step = settings["steps"], settings["min_step"]
        if int(steps) < 1:
            raise ValueError(f"steps must be >= 1, got {steps}")
        self.check_supports()
        solver = make_solver(settings["method"], settings["tolerance"], settings["max_iterations"],
                             settings["linear_solver"])
        u = np.zeros(self.n_dofs) if u0 is None else np.array(u0, dtype=float)
        results = Results(self)
        timer = results.stopwatch
        target = 1.0 / steps
        increment = target
        factor = 0.0
        previous = None  # (load factor, displacements) of the converged state before the last
        while factor < 1.0 - 1e-12:
            trial_factor = min(1.0, factor + increment)
            predicted = None
            if previous is not None:  # linear extrapolation from the last two converged states
                previous_factor, previous_u = previous
                ratio = (trial_factor - factor) / (factor - previous_factor)
                predicted = u + ratio * (u - previous_u)
            try:
                converged_u, solved = self.solve_step(u, trial_factor, solver, timer=timer,
                                                      predicted=predicted)
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
            previous = (factor, u)
            factor, u = trial_factor, converged_u
            step = results.append(factor, u, solved)
            logger.info(
                "load factor %.6g converged in %d iterations", factor, solved.iterations
            )
            if on_step is not None:
                on_step(step)
            if solved.iterations <= 6 and increment < target:
                increment = min(target, 2 * increment)
        return results

    def solve_step(self, u: np.ndarray, load_factor: float, solver, prescribed=None,
                   timer: Stopwatch | None = None, predicted: np.ndarray | None = None):
        """Solve one load level from the displacements u; returns (u, SolverResult). ``timer``
        accumulates the time of its parts. ``predicted``: a guess of the solution, (n_dofs,),
        such as ``Model.solve``'s extrapolation from the previous steps. Without one, where the
        step moves the constrained components, the guess is the tangent prediction
        (``tangent_prediction``; Newton solver only). The solve starts from the guess, with
        the new prescribed values, instead of from u if the guess is in balance already (one
        evaluation of the forces) or its out-of-balance force is smaller (two)."""
        problem = self.problem(load_factor, prescribed)
        if timer is not None:
            problem.timer = timer
        start = np.where(self.constrained, problem.prescribed, u)
        source = "extrapolated displacements"
        if predicted is None and solver.tangent_predictor:
            predicted = self.tangent_prediction(problem, u, solver)
            source = "tangent prediction"
        at_start = None
        if predicted is not None:
            guess = np.where(self.constrained, problem.prescribed, predicted)
            at_guess = try_evaluate(problem, guess, stiffness=False)
            if at_guess is not None:
                if not is_converged(at_guess, solver.tolerance):
                    at_start = try_evaluate(problem, start, stiffness=False)
                if at_start is None or at_guess.residual_norm < at_start.residual_norm:
                    logger.info("load factor %.6g starts from the %s", load_factor, source)
                    start, at_start = guess, at_guess
        solved = solver.solve(problem, start, at_start)
        return solved.u, solved

    def tangent_prediction(self, problem: StepProblem, u: np.ndarray, solver):
        """The step's first Newton iteration taken from the last converged state u: the
        increment of the prescribed components spread over the free ones through the tangent
        at u, K_ff du_f = f - f*(u) - K_fc du_c (the load increment included), with the
        solver's initial regularisation. Moving the supported nodes alone would strain only the
        elements beside them, which may wrinkle or go slack and lose the stiffness that spreads
        the motion; at u they still have it. None where the prescribed values do not change or
        the tangent cannot be factorised. (n_dofs,) displacements."""
        lift = np.where(self.constrained, problem.prescribed - u, 0.0)
        if not np.any(lift):
            return None  # the first iteration from u is this prediction already
        at_u = try_evaluate(problem, u, lift=lift)
        if at_u is None:
            return None
        step = solver.tangent_step(problem, at_u)
        return None if step is None else u + lift + step


def _concatenate_results(results: list[ElementResult], inverse: np.ndarray) -> ElementResult:
    """Element results of several material groups in mesh order."""

    def join(values):
        if values[0] is None:
            return None
        return np.concatenate(values)[inverse]

    responses = [r.response for r in results]
    response = type(responses[0])(
        **{name: join([getattr(r, name) for r in responses])
           for name in responses[0].__dataclass_fields__}
    )
    return ElementResult(
        join([r.deformation_gradient for r in results]),
        response,
        join([r.forces for r in results]),
        join([r.stiffness for r in results]),
        join([r.energy for r in results]),
    )


class StepProblem:
    """Residual, stiffness and potential energy at one load level (the solvers' ``Problem``).

    load_factor scales the dead forces and the follower loads; prescribed: (n_dofs,) values of
    the constrained displacement components.
    """

    def __init__(self, model: Model, load_factor: float, prescribed: np.ndarray):
        self.model = model
        self.load_factor = load_factor
        self.forces = load_factor * model.forces
        self.prescribed = prescribed
        self.free = ~model.constrained
        self.symmetric = not model.has_follower_loads
        # the solver's step metric has the constrained rows and columns zeroed
        self._constraint_positions, self._constrained_diagonal, self.metric = (
            model.constraint_data()
        )
        self.timer = Stopwatch()  # Model.solve shares one across the steps

    def evaluate(self, u: np.ndarray, stiffness: bool = True,
                 lift: np.ndarray | None = None) -> Evaluation:
        """Residual, energy, element states and (``stiffness``) the tangent at u, (n_dofs,).

        lift: (n_dofs,) an increment of the constrained components (zero elsewhere); the
        residual is then the out-of-balance force linearised at u + lift,
        f - f*(u) - K lift on the free rows, from the tangent K at u before its constrained
        rows and columns are replaced (needs ``stiffness``).
        """
        model, timer = self.model, self.timer
        pattern = model.pattern
        data = np.zeros(pattern.nnz) if stiffness else None

        with timer.part(ELEMENTS):
            x = model.element_coordinates(u)  # shared by the elements and the pressure

        def add_element_stiffness(elements, K):  # assembled block by block as evaluated
            model.subtract_pressure_stiffness(K, x[elements], elements, self.load_factor)
            with timer.part(ASSEMBLY):
                pattern.add_to_data(data, elements, K)

        def subtract_load_stiffness(elements, K):
            with timer.part(ASSEMBLY):
                pattern.add_to_data(data, elements, -K)

        with timer.part(ELEMENTS):
            result = model.evaluate_elements(
                u, stiffness=stiffness, stiffness_sink=add_element_stiffness if stiffness else None,
                x_elements=x,
            )
        with timer.part(ASSEMBLY):
            internal = pattern.assemble_vector(result.forces)
        external = self.forces
        energy = float(np.sum(result.energy) - self.forces @ u)
        if model.has_follower_loads:
            with timer.part(ELEMENTS):
                follower, _ = model.follower_forces(
                    u, self.load_factor, stiffness, subtract_load_stiffness if stiffness else None,
                    pressure_stiffness=False, x_elements=x,
                )
            external = external + follower
            energy -= self.load_factor * model.pressure_work(u, x_elements=x)
            if model._edge_follower:
                energy = np.nan  # follower edge loads have no potential
        residual = np.where(self.free, external - internal, 0.0)
        reactions = np.where(self.free, 0.0, internal - external)
        scale = max(np.linalg.norm(external), np.linalg.norm(reactions))
        state = result.response.state
        counts = (
            int(np.count_nonzero(state == TAUT)),
            int(np.count_nonzero(state == WRINKLED)),
            int(np.count_nonzero(state == SLACK)),
        )
        K = None
        if stiffness:
            with timer.part(ASSEMBLY):
                if lift is not None:
                    coupling = model.pattern.matrix(data) @ lift
                    residual = np.where(self.free, residual - coupling, 0.0)
                data[self._constraint_positions] = 0.0
                data[self._constrained_diagonal] = 1.0
                K = model.pattern.matrix(data)
        return Evaluation(
            residual, energy, scale, counts, K, model.force_round_off, self.symmetric,
            model.pattern.diagonal, self.metric, reactions,
        )


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
        self.stopwatch = Stopwatch()

    @property
    def timings(self) -> dict[str, float]:
        """Wall seconds so far in element evaluation, assembly, linear solves, the rest, and
        in total (``wrinkle.timing``)."""
        return self.stopwatch.summary()

    def append(self, load_factor: float, u: np.ndarray, solved) -> StepResult:
        """Add the converged step u (n_dofs,); its reactions come from the solver's last
        evaluation, at u, where it has them."""
        ev = solved.evaluation
        reactions = ev.reactions
        if reactions is None:
            reactions = self.model.reactions(u, load_factor)
        step = StepResult(
            load_factor, u.copy(), solved.iterations, ev.residual_norm, reactions, ev.states,
        )
        self.steps.append(step)
        return step

    def save(self, directory, probes=None, units=None) -> None:
        """Write every step (ParaView files, summary.json, history.csv) into ``directory``;
        probes and units default to the model's (from its case file)."""
        from wrinkle.output import save_results

        model = self.model
        save_results(self, directory, probes=model.probes if probes is None else probes,
                     units=model.units if units is None else units, case=model.source)

    @property
    def final(self) -> StepResult:
        return self.steps[-1]

    def __len__(self) -> int:
        return len(self.steps)
