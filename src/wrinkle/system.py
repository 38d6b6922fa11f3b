"""The discrete system of a model: what the solvers evaluate at a displacement vector.

A ``DiscreteSystem`` is made from a model's definition (``Model.discretise``): the sparsity
pattern, the reference geometry, the element groups (one per material), the kernel set (NumPy
or compiled, chosen once for the mesh), the round-off floor of the convergence test, the step
metric and the positions of the constrained entries. It takes the definition as arrays and
reads nothing of the model. ``evaluate(u, load_factor)`` gives the residual, the energy, the
element states and the tangent stiffness; ``at(load_factor)`` the ``StepProblem`` of one load
level, which is what the nonlinear solvers (``wrinkle.solvers``) take.

Units are consistent units; displacement vectors are (n_dofs,) = (3 n_nodes,), node by node.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields

import numpy as np
import scipy.sparse as sp

from wrinkle import compiled
from wrinkle.assembly import DOFS_PER_NODE, SparsityPattern
from wrinkle.bending import Bending
from wrinkle.cables import Cables, CableState
from wrinkle.element import (
    KERNEL_BLOCK,
    ElementResult,
    MembraneElements,
    unit_tension_stiffness,
)
from wrinkle.kinematics import ReferenceGeometry, element_coordinates
from wrinkle.loads import (
    edge_follower_forces,
    pressure_forces,
    pressure_volume,
    pressure_volume_gradient,
    subtract_pressure_stiffness,
    unclosed_edges,
)
from wrinkle.mesh import Mesh
from wrinkle.solvers.base import Evaluation, EvaluationFailure
from wrinkle.solvers.linear import make_linear_solver
from wrinkle.timing import ASSEMBLY, ELEMENTS, Stopwatch
from wrinkle.wrinkling import SLACK, TAUT, WRINKLED, Wrinkling, WrinklingError

__all__ = [
    "MIN_AREA_RATIO",
    "MIN_VOLUME_RATIO",
    "DiscreteSystem",
    "FollowerEdgeLoad",
    "LoadState",
    "Loading",
    "StepStart",
    "StepProblem",
]

# An element whose current area is below this fraction of its reference area has collapsed
# (a triangle shrunk a thousandfold across in both directions): no membrane state, slack or
# not, is that, and a solve that ends there has found the spurious equilibrium of a sheet
# crushed to a point, which carries no load (a balloon past its limit point).
MIN_AREA_RATIO = 1e-6
# likewise for the volume a pressurised membrane encloses (against the origin, so against
# symmetry planes through it), where its reference state encloses one
MIN_VOLUME_RATIO = 1e-6
# An element stretched to more than this many times its reference area (a triangle stretched
# a thousandfold in both directions) is beyond any membrane: a solve whose iterate gets there
# is diverging, as a balloon above its limit pressure inflates without bound.
MAX_AREA_RATIO = 1e6

StiffnessSink = Callable[[np.ndarray | slice, np.ndarray], None]


@dataclass(frozen=True)
class FollowerEdgeLoad:
    """A normal edge load that follows the deformed edge, on m boundary edges.

    edges: (m, 3) node triples (edge node a, edge node b, third node of the triangle);
    normal: (m,) force per unit current length, in the membrane plane, positive outwards;
    owner: (m,) the triangle of each edge; local_dofs: (m, 9) places of the triple's dofs
    among the owner triangle's 9, for its load stiffness.
    """

    edges: np.ndarray
    normal: np.ndarray
    owner: np.ndarray
    local_dofs: np.ndarray


@dataclass
class Loading:
    """The loads of a model at load factor 1.

    forces: (n_dofs,) dead nodal forces; pressure: (n_elements,) follower pressure per element
    (force per unit current area, along the element normal); follower_edges: normal edge loads
    that follow the deformed edges.
    """

    forces: np.ndarray
    pressure: np.ndarray
    follower_edges: list[FollowerEdgeLoad] = field(default_factory=list)

    @property
    def has_followers(self) -> bool:
        return bool(np.any(self.pressure != 0) or self.follower_edges)

    @classmethod
    def total(cls, parts: Sequence[Loading], n_dofs: int, n_elements: int) -> Loading:
        """The sum of several loadings (zero loads if there are none)."""
        forces, pressure = np.zeros(n_dofs), np.zeros(n_elements)
        edges: list[FollowerEdgeLoad] = []
        for part in parts:
            forces += part.forces
            pressure += part.pressure
            edges += part.follower_edges
        return cls(forces, pressure, edges)


@dataclass(frozen=True)
class LoadState:
    """The loads and the supported values of a model at one instant of a staged analysis
    (the end of an analysis step, ``Model.load_state``).

    parts: {load label: its ``Loading`` as applied then} for the loads applied so far (a load
    not in it is at zero); constrained (n_dofs,) bool and prescribed (n_dofs,) the held
    components and their values then (displacements); supports: the labels of the supports
    moved to their own values so far.
    """

    parts: Mapping[str, Loading]
    constrained: np.ndarray
    prescribed: np.ndarray
    supports: frozenset[str] = frozenset()

    def loading(self, n_elements: int) -> Loading:
        """The sum of the applied loads (``Loading.total``)."""
        return Loading.total(list(self.parts.values()), self.prescribed.size, n_elements)


@dataclass(frozen=True)
class StepStart:
    """Where an analysis step starts: the loads and supported values there (``LoadState``),
    the displacement there (n_dofs,) and the number of the analysis step that ended there
    (0: the reference state)."""

    state: LoadState
    displacement: np.ndarray
    analysis_step: int


def _concatenate_results(results: list[ElementResult], inverse: np.ndarray) -> ElementResult:
    """Element results of several material groups in mesh order."""

    def join(values):
        if values[0] is None:
            return None
        return np.concatenate(values)[inverse]

    responses = [r.response for r in results]
    response = type(responses[0])(
        **{f.name: join([getattr(r, f.name) for r in responses]) for f in fields(responses[0])}
    )
    return ElementResult(
        join([r.deformation_gradient for r in results]),
        response,
        join([r.forces for r in results]),
        join([r.stiffness for r in results]),
        join([r.energy for r in results]),
    )


# check_resolvable: the material stiffness (force/length) double precision can evaluate (its
# squares, in the energy, and its products with strains of 1e-16 must stay normal numbers);
# the largest prescribed displacement, in mesh sizes; the largest round-off floor of the
# convergence test, relative to the force scale of the loads (an answer to 1 %)
STIFFNESS_RANGE = (1e-100, 1e100)
MAX_MOTION = 1e6
MAX_ROUND_OFF = 1e-2


class DiscreteSystem:
    """The discretised membrane: element groups, loads and supports on a fixed pattern.

    mesh: the ``Mesh``; pattern: its ``SparsityPattern``; geometry: the ``ReferenceGeometry``
    of all elements (material frames included); materials: one ``Wrinkling`` per group and
    material_of_element (n_elements,) the group of each element; constrained (n_dofs,) bool
    and prescribed (n_dofs,) the supported components and their values at load factor 1;
    loading: the ``Loading`` at load factor 1; cables: the model's tension-only cables
    (``wrinkle.cables``), if any, along mesh edges; bending: the bending energy of the mean
    surface (``wrinkle.bending``), if the model has one; the pattern must then hold the node
    pairs it couples; pressurised: (n_elements,) bool, the elements some pressure load acts on
    (default: those with a pressure in ``loading``).

    The loads and supported values at load factor lambda are those at 1 times lambda, or,
    on the path of an analysis step (``along``), L(lambda) = L0 + lambda (L1 - L0) from the
    values L0 at its start to L1 = ``loading``, ``prescribed`` at its end.
    """

    def __init__(
        self,
        mesh: Mesh,
        pattern: SparsityPattern,
        geometry: ReferenceGeometry,
        materials: Sequence[Wrinkling],
        material_of_element: np.ndarray,
        constrained: np.ndarray,
        prescribed: np.ndarray,
        loading: Loading,
        bending: Bending | None = None,
        cables: Cables | None = None,
        pressurised: np.ndarray | None = None,
    ):
        self.mesh = mesh
        # (n_elements,) bool: the elements some pressure load acts on, in any analysis step
        # (their enclosed volume is reported, their closure checked, even where the loads
        # are zero or cancel)
        self.pressure_extent = pressurised
        self.pattern = pattern
        self.geometry = geometry
        self.n_dofs = pattern.n_dofs
        self.constrained = constrained
        self.prescribed = prescribed
        self.loading = loading
        # the kernel set, chosen once for the mesh (wrinkle.compiled.enabled)
        self.compiled = compiled.enabled(mesh.n_elements)
        self.groups: list[tuple[np.ndarray, MembraneElements]] = []
        for index, material in enumerate(materials):
            elements = np.flatnonzero(material_of_element == index)
            if elements.size:
                self.groups.append(
                    (
                        elements,
                        MembraneElements(
                            geometry.subset(elements), material, compiled=self.compiled
                        ),
                    )
                )
        order = np.concatenate([elements for elements, _ in self.groups])
        self._inverse_order = np.argsort(order) if len(self.groups) > 1 else None
        self.force_round_off = self._force_round_off()
        self._reference_volume: float | None = None  # enclosed by the pressurised elements
        self._motion_bound: float | None = None  # ``_free_motion``
        self.cables = cables
        self._pressure_potential: bool | None = None  # pressure_has_potential, once
        if cables is not None:
            # the data positions of each segment's 6 x 6 tangent block
            positions = np.empty((cables.n_segments, 6, 6), dtype=np.int64)
            for i in (0, 1):
                for j in (0, 1):
                    positions[:, 3 * i : 3 * i + 3, 3 * j : 3 * j + 3] = pattern.block_positions(
                        cables.edges[:, i], cables.edges[:, j]
                    )
            self._cable_positions = positions.ravel()
        self.bending = bending
        if bending is not None:
            rows, columns, values = bending.entries()
            # the constant bending stiffness, added to the tangent's data at these positions
            self._bending_positions = pattern.pair_positions(rows, columns).ravel()
            self._bending_values = np.repeat(values, 3)
        self._constraint_data: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._motion_force_at_full: float | None = None
        # the loads and supported values at load factor 0 (``along``): None, all zero
        self.initial: Loading | None = None
        self.initial_prescribed: np.ndarray | None = None
        self._motion_reactions: tuple[np.ndarray, np.ndarray] | None = None  # at 0 and 1
        self._incidence: sp.csr_matrix | None = None  # ``grow``

    def along(
        self,
        initial: Loading,
        initial_prescribed: np.ndarray,
        loading: Loading,
        prescribed: np.ndarray,
    ) -> DiscreteSystem:
        """The same discrete system on the path of an analysis step: its loads and supported
        values (n_dofs,) go from ``initial``, ``initial_prescribed`` at load factor 0 to
        ``loading``, ``prescribed`` at 1, linearly. It shares the mesh, pattern, elements
        and supports (``constrained``) of this one."""
        path = copy.copy(self)
        path.initial, path.initial_prescribed = initial, np.asarray(initial_prescribed, float)
        path.loading, path.prescribed = loading, np.asarray(prescribed, dtype=float)
        path._reference_volume = path._pressure_potential = path._motion_force_at_full = None
        path._motion_reactions = None
        return path

    def forces_at(self, load_factor: float) -> np.ndarray:
        """The dead nodal forces at ``load_factor``, (n_dofs,)."""
        if self.initial is None:
            return load_factor * self.loading.forces
        start = self.initial.forces
        return start + load_factor * (self.loading.forces - start)

    def pressure_at(self, pressure_factor: float) -> np.ndarray:
        """The follower pressure of each element at ``pressure_factor`` (the load factor, or
        the unknown of volume control and gas loads), (n_elements,)."""
        if self.initial is None:
            return pressure_factor * self.loading.pressure
        start = self.initial.pressure
        return start + pressure_factor * (self.loading.pressure - start)

    def prescribed_at(self, load_factor: float) -> np.ndarray:
        """The values of the supported components at ``load_factor``, (n_dofs,)."""
        if self.initial_prescribed is None:
            return load_factor * self.prescribed
        start = self.initial_prescribed
        return start + load_factor * (self.prescribed - start)

    def _edge_terms(self, load_factor: float) -> list[tuple[FollowerEdgeLoad, float]]:
        """The follower edge loads at ``load_factor``, each with the factor on its values."""
        terms = [(edge, load_factor) for edge in self.loading.follower_edges]
        if self.initial is not None:
            terms += [(edge, 1.0 - load_factor) for edge in self.initial.follower_edges]
        return terms

    @property
    def has_follower_edges(self) -> bool:
        """Whether follower edge loads act anywhere on the path (they have no potential)."""
        return bool(self._edge_terms(0.5))

    @property
    def moves_supports(self) -> bool:
        """Whether the supported values change along the path."""
        end = self.prescribed[self.constrained]
        if self.initial_prescribed is None:
            return bool(np.any(end))
        return bool(np.any(end != self.initial_prescribed[self.constrained]))

    @property
    def elements(self) -> MembraneElements:
        """The elements of a single-material system."""
        if len(self.groups) != 1:
            raise ValueError("the model has several materials: use system.groups")
        return self.groups[0][1]

    @property
    def has_follower_loads(self) -> bool:
        return self.loading.has_followers or (
            self.initial is not None and self.initial.has_followers
        )

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
        for indices, elements in self.groups:
            g = elements.geometry
            stiffness = elements.material.reference_stiffness
            extent = np.abs(nodes[self.mesh.triangles[indices]]).max(axis=(1, 2))
            coordinate_noise = extent * np.abs(g.shape_gradient).max(axis=(1, 2))
            per_element = g.area * np.linalg.norm(g.shape_gradient.reshape(-1, 6), axis=1)
            total += float(stiffness * np.linalg.norm(per_element * (1.0 + coordinate_noise))) ** 2
        return float(10 * np.finfo(float).eps * np.sqrt(total))

    def check_resolvable(self) -> None:
        """Raise ValueError, naming the input, if the problem cannot be solved in double
        precision: a material stiffness (its reference stiffness, N/m) outside
        [STIFFNESS_RANGE]; prescribed displacements more than MAX_MOTION times the mesh's
        size; loads whose forces overflow; or loads so small beside the stiffness that the
        round-off floor of the convergence test (``force_round_off``) is more than
        MAX_ROUND_OFF of their force scale (the scale of the reference state at load factor 1,
        ``StepProblem.evaluate``): the test could not tell such loads from none."""
        low, high = STIFFNESS_RANGE
        for index, (_, elements) in enumerate(self.groups):
            k = elements.material.reference_stiffness
            if not (math.isfinite(k) and low <= k <= high):
                raise ValueError(
                    f"material {index + 1}: its stiffness (E t, about {k:.3g} force/length) is "
                    f"outside what double precision can evaluate ({low:.0e} to {high:.0e}); "
                    "check the units of E and thickness"
                )
        extent = float(np.ptp(self.mesh.nodes, axis=0).max())
        largest = float(np.abs(np.where(self.constrained, self.prescribed, 0.0)).max(initial=0.0))
        if largest > MAX_MOTION * extent:
            raise ValueError(
                f"a prescribed displacement of {largest:.3g} is more than {MAX_MOTION:.0e} times "
                f"the mesh's size ({extent:.3g}); check the units of the displacements"
            )
        try:
            reference = self.at(1.0).evaluate(np.zeros(self.n_dofs), stiffness=False)
        except EvaluationFailure as error:
            raise ValueError(
                f"the model cannot be evaluated at its reference state: {error}"
            ) from None
        forces = np.concatenate([reference.residual, reference.reactions])
        if not (np.all(np.isfinite(forces)) and math.isfinite(reference.force_scale)):
            raise ValueError(
                "the loads are too large to evaluate in double precision (their forces "
                "overflow); check the units of the loads"
            )
        scale, floor = reference.force_scale, self.force_round_off
        if scale > 0 and floor > MAX_ROUND_OFF * scale:
            raise ValueError(
                f"the loads are too small for the sheet's stiffness: the round-off of the "
                f"sheet's forces ({floor:.3g}) is more than {MAX_ROUND_OFF:g} of the loads' "
                f"force scale ({scale:.3g}), so equilibrium cannot be resolved in double "
                "precision; check the units of E, thickness, the loads and the displacements"
            )

    def motion_force(self, prescribed: np.ndarray | None = None) -> float:
        """The force scale of a prescribed motion, force: the norm of the reactions of a
        sheet under the isotropic tension k (each element's material reference stiffness,
        N/m) when its constrained components take the values ``prescribed`` (n_dofs,;
        default: those at load factor 1, computed once) and its free ones the harmonic
        extension of them, L_ff v_f = -L_fc v_c, with L = sum_e k_e A_e grad psi_a . grad psi_b
        for each displacement component (a Laplacian). It is the order of the forces the motion
        needs in the taut sheet, linear in the motion and zero for a rigid translation; the
        convergence test uses it so that a sheet moved into slack, carrying no force, can
        converge. Zero without prescribed motion."""
        if prescribed is None:
            if self._motion_force_at_full is None:
                self._motion_force_at_full = self.motion_force(self.prescribed)
            return self._motion_force_at_full
        return float(np.linalg.norm(self._motion_reaction_field(prescribed)))

    def motion_force_at(self, load_factor: float) -> float:
        """The force scale of the prescribed motion at ``load_factor``: ``motion_force`` of
        the supported values there (``prescribed_at``) or, if larger, of their change since
        the path's start (from the reactions at its two ends, combined linearly). A path that
        moves a support back through its reference position (a node pulled, then pushed) has
        values of zero half-way, but not a motion of zero: the change keeps the scale."""
        if self.initial_prescribed is None:
            return abs(load_factor) * self.motion_force()
        if self._motion_reactions is None:
            self._motion_reactions = (
                self._motion_reaction_field(self.initial_prescribed),
                self._motion_reaction_field(self.prescribed),
            )
        start, end = self._motion_reactions
        change = load_factor * (end - start)
        return float(max(np.linalg.norm(start + change), np.linalg.norm(change)))

    def _motion_reaction_field(self, prescribed: np.ndarray) -> np.ndarray:
        """The reactions of ``motion_force`` at every node, (n_nodes, 3) (zero where free)."""
        values = np.where(self.constrained, prescribed, 0.0).reshape(-1, 3)
        field_ = np.zeros_like(values)
        if not np.any(values):
            return field_
        laplacian = self._stiffness_laplacian()
        constrained = self.constrained.reshape(-1, 3)
        moved = [c for c in range(3) if np.any(values[constrained[:, c], c])]
        while moved:  # the components held at the same nodes share one factorisation
            held = constrained[:, moved[0]]
            same = [c for c in moved if np.array_equal(constrained[:, c], held)]
            moved = [c for c in moved if c not in same]
            v_held = values[held][:, same]  # (n_held, len(same))
            L_free = laplacian[~held]
            v_free = np.zeros((int(np.count_nonzero(~held)), len(same)))
            if v_free.size:
                L_ff = L_free[:, ~held]
                # a free region that touches no held node (an island) has a singular block:
                # a shift of 10^-12 of the diagonal gives it the extension zero
                shift = 1e-12 * float(np.abs(L_ff.diagonal()).max())
                L_ff = (L_ff + sp.identity(L_ff.shape[0], format="csr") * shift).tocsr()
                linear = make_linear_solver("auto", L_ff.shape[0], one_off=True)
                solve = linear.factorise(L_ff, True)
                if solve is None:
                    raise EvaluationFailure("the prescribed motion's force scale: singular L")
                right = -(L_free[:, held] @ v_held)
                for column in range(len(same)):
                    v_free[:, column] = solve(right[:, column])
                linear.release()
            L_held = laplacian[held]
            reactions = L_held[:, ~held] @ v_free + L_held[:, held] @ v_held
            rows = np.flatnonzero(held)
            for column, c in enumerate(same):
                field_[rows, c] = reactions[:, column]
        return field_

    def _stiffness_laplacian(self) -> sp.csr_matrix:
        """L of ``motion_force``, (n_nodes, n_nodes), N/m: the step metric under each
        element's reference stiffness as its tension, one displacement component of it (the
        three are alike and uncoupled)."""
        tension = np.zeros(self.mesh.n_elements)
        for indices, elements in self.groups:
            tension[indices] = elements.material.reference_stiffness
        return self.pattern.matrix(self.step_metric(tension))[0::3, 0::3].tocsr()

    def step_metric(self, tension: np.ndarray | None = None) -> np.ndarray:
        """CSR data, on ``pattern``, of the unit-tension stiffness (``unit_tension_stiffness``
        assembled: a Laplacian on each displacement component), (nnz,); with ``tension``
        (n_elements,), of each element's isotropic tension of that size instead of 1."""
        g = self.geometry
        area = g.area if tension is None else g.area * tension
        data = np.zeros(self.pattern.nnz)
        if self.compiled:  # in parallel, without the elements' (m, 9, 9) matrices
            pattern = self.pattern
            compiled.assemble_laplacian(
                data,
                (pattern.element_block_base, pattern.element_row_step),
                area,
                g.shape_gradient,
                pattern.colouring,
            )
            return data
        for start in range(0, g.n_elements, KERNEL_BLOCK):
            block = slice(start, min(start + KERNEL_BLOCK, g.n_elements))
            self.pattern.add_to_data(
                data,
                block,
                unit_tension_stiffness(area[block], g.shape_gradient[block]),
                compiled=self.compiled,
            )
        return data

    def constraint_data(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """What every load step's problem needs of the supports: positions in ``pattern``'s
        data of the constrained rows and columns and of the constrained diagonal entries, and
        the step metric (``step_metric``) with those rows and columns zeroed, (nnz,). Made
        once, at the first use."""
        if self._constraint_data is None:
            positions = self.pattern.constraint_positions(self.constrained)
            metric = self.step_metric()
            metric[positions] = 0.0
            self._constraint_data = (positions, self.pattern.diagonal[self.constrained], metric)
        return self._constraint_data

    # -- evaluation ---------------------------------------------------------------------
    def element_coordinates(self, u: np.ndarray) -> np.ndarray:
        """Current node coordinates of every triangle at displacements u, (n_elements, 3, 3)."""
        if self.compiled:
            return compiled.element_coordinates(
                self.mesh.nodes, u.reshape(-1, 3), self.mesh.triangles
            )
        return element_coordinates(self.mesh.nodes + u.reshape(-1, 3), self.mesh.triangles)

    def evaluate_elements(
        self,
        u: np.ndarray,
        stiffness: bool = True,
        stiffness_sink: StiffnessSink | None = None,
        x_elements: np.ndarray | None = None,
        matrices: bool = True,
    ) -> ElementResult:
        """Element forces, stiffness and states at displacements u, (n_dofs,).

        stiffness_sink(elements, K): if given, receives the stiffness block by block (mesh
        element indices or a slice, (m, 9, 9)) instead of the result holding all of it.
        matrices: False to form no element matrices, only the material tangent the result
        holds (``assemble_stiffness`` forms and adds them). x_elements:
        ``element_coordinates(u)`` if the caller has them. Raises EvaluationFailure naming
        the elements whose wrinkling conditions could not be solved.
        """
        x = self.element_coordinates(u) if x_elements is None else x_elements
        groups = self.groups
        results = []
        for index, elements in groups:
            sink = stiffness_sink
            if stiffness_sink is not None and len(groups) > 1:

                def sink(rows, K, index=index, outer=stiffness_sink):
                    outer(index[rows], K)

            try:
                results.append(
                    elements.evaluate(
                        x if len(groups) == 1 else x[index],
                        stiffness=stiffness,
                        stiffness_sink=sink,
                        matrices=matrices,
                    )
                )
            except WrinklingError as error:  # group rows -> mesh elements
                raise EvaluationFailure(str(WrinklingError(index[error.elements]))) from error
        if self._inverse_order is None:
            return results[0]
        return _concatenate_results(results, self._inverse_order)

    def _pressurised(self) -> slice | np.ndarray | None:
        """The elements under pressure: their indices, a slice if they are all of them, None if
        there are none."""
        pressure = self.loading.pressure
        if self.initial is not None:
            pressure = np.abs(pressure) + np.abs(self.initial.pressure)
        if self.pressure_extent is not None:
            pressure = np.abs(pressure) + self.pressure_extent
        loaded = np.flatnonzero(pressure)
        if loaded.size == 0:
            return None
        return slice(0, loaded.size) if loaded.size == self.mesh.n_elements else loaded

    def _loaded_coordinates(
        self, u: np.ndarray, loaded: slice | np.ndarray, x_elements: np.ndarray | None
    ) -> np.ndarray:
        """Current coordinates (m, 3, 3) of the pressurised elements ``loaded`` (from
        ``_pressurised``): taken from x_elements (``element_coordinates(u)``) if given, else
        gathered at the displacements u."""
        if x_elements is not None:
            return x_elements[loaded]
        return (self.mesh.nodes + u.reshape(-1, 3))[self.mesh.triangles[loaded]]

    def follower_forces(
        self,
        u: np.ndarray,
        load_factor: float,
        stiffness: bool = True,
        stiffness_sink: StiffnessSink | None = None,
        pressure_stiffness: bool = True,
        x_elements: np.ndarray | None = None,
        pressure_factor: float | None = None,
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Assembled follower loads at u: forces (n_dofs,) and their load stiffness d f / d u,
        element-wise (n, 9, 9) on the triangles (None if not asked or no follower load), or
        handed block by block to ``stiffness_sink(elements, K)`` (then None is returned).
        pressure_stiffness=False leaves the pressure's out (``subtract_pressure_stiffness``
        takes it into the element blocks instead). x_elements: ``element_coordinates(u)`` if
        the caller has them. pressure_factor: the factor on the pressures (default
        load_factor; the unknown of volume control and gas loads)."""
        if pressure_factor is None:
            pressure_factor = load_factor
        return self._follower_forces(
            u,
            self.pressure_at(pressure_factor),
            self._edge_terms(load_factor),
            stiffness,
            stiffness_sink,
            pressure_stiffness,
            x_elements,
        )

    def _follower_forces(
        self,
        u: np.ndarray,
        pressures: np.ndarray,
        edge_terms: list[tuple[FollowerEdgeLoad, float]],
        stiffness: bool,
        stiffness_sink: StiffnessSink | None,
        pressure_stiffness: bool,
        x_elements: np.ndarray | None,
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """``follower_forces`` of the element pressures (n_elements,) and the follower edge
        loads, each with the factor on its values."""
        x_nodes = self.mesh.nodes + u.reshape(-1, 3)
        forces = np.zeros(self.n_dofs)
        blocks: list[tuple[np.ndarray | slice, np.ndarray]] = []  # when no sink is given

        def keep(elements: np.ndarray | slice, k: np.ndarray) -> None:
            blocks.append((elements, k.copy()))

        sink = stiffness_sink or keep
        loaded = self._pressurised()
        if loaded is not None:
            x = self._loaded_coordinates(u, loaded, x_elements)
            pressure = pressures[loaded]
            if self.compiled:
                compiled.add_pressure_forces(forces, self.pattern.element_dofs[loaded], x, pressure)
            else:
                f, _ = pressure_forces(x, pressure, stiffness=False)
                forces += np.bincount(
                    self.pattern.element_dofs[loaded].ravel(), f.ravel(), minlength=self.n_dofs
                )
            if stiffness and pressure_stiffness:
                for start in range(0, x.shape[0], KERNEL_BLOCK):
                    block = slice(start, min(start + KERNEL_BLOCK, x.shape[0]))
                    elements = block if isinstance(loaded, slice) else loaded[block]
                    sink(elements, pressure_forces(x[block], pressure[block])[1])
        for edge_load, factor in edge_terms:
            triples = edge_load.edges
            f, k = edge_follower_forces(x_nodes[triples], factor * edge_load.normal, stiffness)
            dofs = (3 * triples[:, :, None] + np.arange(3)).reshape(-1, 9)
            forces += np.bincount(dofs.ravel(), f.ravel(), minlength=self.n_dofs)
            if stiffness:
                in_triangle = np.zeros((k.shape[0], 9, 9))
                rows = np.arange(k.shape[0])[:, None, None]
                local = edge_load.local_dofs
                in_triangle[rows, local[:, :, None], local[:, None, :]] = k
                sink(edge_load.owner, in_triangle)
        if not blocks:
            return forces, None
        K = np.zeros((self.mesh.n_elements, 9, 9))
        for elements, k in blocks:
            if isinstance(elements, slice):
                K[elements] += k
            else:
                np.add.at(K, elements, k)
        return forces, K

    def assemble_stiffness(
        self,
        data: np.ndarray,
        result: ElementResult,
        x: np.ndarray,
        pressures: np.ndarray,
        kept: np.ndarray,
    ) -> None:
        """Form the element stiffness matrices from the material tangent of ``result`` (an
        ``evaluate_elements`` with ``matrices=False``, mesh order) and add them to the CSR
        data (nnz,) in place, the pressure's load stiffness subtracted (``pressures``
        (n_elements,), ``pressure_at``); x (n_elements, 3, 3) the current coordinates; kept
        (n_elements, 9) bool, the element dofs whose rows and columns are added (all, or the
        free ones where the caller zeroes the constrained rows and columns). The compiled
        kernel, in parallel over chunks of elements that share no node
        (``SparsityPattern.colouring``)."""
        tangent = result.response.tangent
        if tangent is None:
            raise ValueError("the element result holds no material tangent")
        compiled.assemble_stiffness(
            data,
            (self.pattern.element_block_base, self.pattern.element_row_step),
            self.geometry.area,
            result.deformation_gradient,
            self.geometry.shape_gradient,
            tangent,
            result.response.stress,
            x,
            pressures,
            self.pattern.colouring,
            kept,
        )

    def subtract_pressure_stiffness(
        self, K: np.ndarray, x: np.ndarray, elements: np.ndarray | slice, pressures: np.ndarray
    ) -> None:
        """Subtract the pressure's load stiffness from the element matrices K (m, 9, 9) of
        ``elements`` (a slice or indices) in place; x (m, 3, 3) their current coordinates,
        pressures (n_elements,) every element's pressure (``pressure_at``)."""
        pressure = pressures[elements]
        if np.any(pressure):
            if self.compiled:
                compiled.subtract_pressure_stiffness(K, x, pressure)
            else:
                subtract_pressure_stiffness(K, x, pressure)

    @property
    def encloses_volume(self) -> bool:
        """Whether pressurised elements enclose a volume in the reference state (against the
        origin, so against symmetry planes through it): a balloon or an inflatable tube,
        whose pressure can pass a maximum, not a flat sheet inflated (``Model.solve`` checks
        such a model's states for stability, ``wrinkle.solvers.stability``)."""
        return bool(self.reference_volume != 0.0)

    @property
    def reference_volume(self) -> float:
        """The signed volume the pressurised elements enclose in the reference state (the
        sum of their cone volumes from the origin, ``pressure_volume``); 0 without them."""
        if self._reference_volume is None:
            loaded = self._pressurised()
            volume = 0.0
            if loaded is not None:
                x0 = self.mesh.nodes[self.mesh.triangles[loaded]]
                volume = float(np.sum(pressure_volume(x0)))
            self._reference_volume = volume
        return self._reference_volume

    def enclosed_volume(self, u: np.ndarray) -> float:
        """The signed volume the pressurised elements enclose at u (n_dofs,), counted
        against the origin (``pressure_volume``): the volume of a closed membrane, or of a
        part of one closed by symmetry planes through the origin (``volume_closure``)."""
        loaded = self._pressurised()
        if loaded is None:
            return 0.0
        return float(np.sum(pressure_volume(self._loaded_coordinates(u, loaded, None))))

    def volume_gradient(self, u: np.ndarray) -> np.ndarray:
        """d ``enclosed_volume`` / du at u, (n_dofs,), zero at the constrained components."""
        gradient: np.ndarray = np.zeros(self.n_dofs)
        loaded = self._pressurised()
        if loaded is not None:
            x = self._loaded_coordinates(u, loaded, None)
            dofs = self.pattern.element_dofs[loaded]
            gradient = np.bincount(
                dofs.ravel(),
                pressure_volume_gradient(x).reshape(dofs.shape).ravel(),
                minlength=self.n_dofs,
            )
        return np.where(self.constrained, 0.0, gradient)

    @property
    def pressure_has_potential(self) -> bool:
        """Whether the follower pressure has a potential, -p V with V the enclosed volume:
        when there is none, or its surface is closed (``volume_closure``). On an open
        surface (a sail whose cable edges move) the work of the pressure depends on the
        path, and the solvers use the residual as their merit instead."""
        if self._pressure_potential is None:
            closure = self.volume_closure()
            self._pressure_potential = closure is None or self._pressurised() is None
        return self._pressure_potential

    def volume_closure(self) -> str | None:
        """Why the pressurised elements do not enclose a volume that ``enclosed_volume``
        measures, or None if they do: none are pressurised, or a boundary edge is neither
        held nor in a symmetry plane through the origin whose normal component is held
        (``wrinkle.loads.unclosed_edges``)."""
        loaded = self._pressurised()
        if loaded is None:
            return "no element is under pressure"
        nodes = self.mesh.nodes
        size = float(np.ptp(nodes, axis=0).max(initial=0.0))
        tolerance = 1e-9 * (size if size > 0 else 1.0)
        unclosed = unclosed_edges(nodes, self.mesh.triangles[loaded], self.constrained, tolerance)
        if unclosed.size:
            a, b = (int(node) for node in unclosed[0])
            return (
                f"{len(unclosed)} boundary edge(s) of the pressurised surface, the first from "
                f"node {a} to node {b}, are neither held nor in a symmetry plane through the "
                "origin with their normal component held: the surface encloses no volume"
            )
        return None

    def inadmissible(self, x_elements: np.ndarray) -> str | None:
        """Why the state with element coordinates x_elements (n_elements, 3, 3) is not a
        membrane state, or None if it is one: an element whose area ratio a / A0 is below
        MIN_AREA_RATIO (collapsed), or an enclosed volume (the signed cone volumes of the
        pressurised elements, ``pressure_volume``) below MIN_VOLUME_RATIO of the reference
        one, where that is not zero. Non-finite coordinates are inadmissible too."""
        if not np.all(np.isfinite(x_elements)):
            return "the coordinates are not finite"
        ratio = self._area_ratios(x_elements)
        collapsed = np.flatnonzero(ratio < MIN_AREA_RATIO)
        if collapsed.size:
            worst = int(collapsed[np.argmin(ratio[collapsed])])
            return (
                f"{collapsed.size} element(s) collapsed, element {worst} to an area ratio of "
                f"{ratio[worst]:.3g} (below {MIN_AREA_RATIO:g})"
            )
        loaded = self._pressurised()
        reference = self.reference_volume
        if loaded is None or reference == 0.0:
            return None
        volume = float(np.sum(pressure_volume(x_elements[loaded])))
        if volume / reference < MIN_VOLUME_RATIO:
            return (
                f"the enclosed volume collapsed to {volume / reference:.3g} of its reference "
                f"value {abs(reference):.3g} (below {MIN_VOLUME_RATIO:g})"
            )
        return None

    def diverging(self, u: np.ndarray) -> str | None:
        """Why the displacements u (n_dofs,) of a solve's iterate show it diverging, or
        None: an element stretched to more than MAX_AREA_RATIO times its reference area.
        Only where some component of u exceeds ``_free_motion`` are the areas computed."""
        if not float(np.max(np.abs(u), initial=0.0)) > self._free_motion:
            return None
        ratio = self._area_ratios(self.element_coordinates(u))
        worst = int(np.argmax(ratio))
        if not ratio[worst] > MAX_AREA_RATIO:
            return None
        return (
            f"element {worst} stretched to {ratio[worst]:.3g} times its reference area (more "
            f"than {MAX_AREA_RATIO:g}), beyond any membrane"
        )

    def _area_ratios(self, x_elements: np.ndarray) -> np.ndarray:
        """Each element's current over reference area, (n_elements,), from its current node
        coordinates x_elements (n_elements, 3, 3)."""
        edges = x_elements[:, :2] - x_elements[:, 2:3]
        area = np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1)
        return area / (2.0 * self.geometry.area)

    @property
    def _free_motion(self) -> float:
        """The largest displacement component (length units) below which no element can exceed
        MAX_AREA_RATIO: an edge of reference length L is then at most L + 2 sqrt(3) U long,
        and an element's area at most (L_e + 2 sqrt(3) U)^2 / 2, L_e its longest edge."""
        if self._motion_bound is None:
            nodes = self.mesh.nodes[self.mesh.triangles]  # (n_elements, 3, 3)
            longest = np.max(np.linalg.norm(nodes - np.roll(nodes, 1, axis=1), axis=2), axis=1)
            reach = np.sqrt(2.0 * MAX_AREA_RATIO * self.geometry.area) - longest
            self._motion_bound = max(float(np.min(reach)) / (2.0 * math.sqrt(3.0)), 0.0)
        return self._motion_bound

    def pressure_work(
        self, u: np.ndarray, x_elements: np.ndarray | None = None, pressure_factor: float = 1.0
    ) -> float:
        """Sum of p V_cone over the pressurised elements at ``pressure_factor``
        (``pressure_at``, ``pressure_volume``): the pressure's potential is minus this; exact
        when the boundary is held or moves in planes through the origin (symmetry planes),
        otherwise a merit for the solver only. x_elements: ``element_coordinates(u)`` if the
        caller has them."""
        loaded = self._pressurised()
        if loaded is None:
            return 0.0
        x = self._loaded_coordinates(u, loaded, x_elements)
        pressure = self.pressure_at(pressure_factor)[loaded]
        if self.compiled:
            return compiled.pressure_work(x, pressure)
        return float(pressure @ pressure_volume(x))

    def internal_forces(self, u: np.ndarray) -> np.ndarray:
        """Global internal force vector f* (membrane, bending and cables), (n_dofs,)."""
        return self.strain_energy_and_forces(u)[1]

    def strain_energy_and_forces(
        self, u: np.ndarray, elements: ElementResult | None = None
    ) -> tuple[float, np.ndarray]:
        """The stored energy at u (n_dofs,): the membrane's relaxed strain energy (with its
        prestress's work) plus the bending and the cables' energies (energy units), and the
        internal force vector f* = dU/du, (n_dofs,), from one evaluation of the elements
        (``elements``, that of ``evaluate_elements(u, stiffness=False)``, if the caller has
        it)."""
        result = self.evaluate_elements(u, stiffness=False) if elements is None else elements
        forces = self.pattern.assemble_vector(result.forces)
        energy = float(np.sum(result.energy))
        energy += self.add_bending(u, forces, None)
        if self.cables is not None:
            state = self.cable_state(u, tangent=False)
            forces += state.forces
            energy += state.energy
        return energy, forces

    def cable_state(self, u: np.ndarray, tangent: bool = True) -> CableState:
        """The cables at the displacements u (n_dofs,) (``Cables.state``); ValueError
        without cables."""
        if self.cables is None:
            raise ValueError("the model has no cables")
        return self.cables.state(self.mesh.nodes + u.reshape(-1, 3), tangent)

    def add_cables(self, u: np.ndarray, internal: np.ndarray, data: np.ndarray | None) -> float:
        """Add the cables' internal forces at u (n_dofs,) to ``internal`` and their tangent
        to the stiffness' CSR data (None: no tangent), in place; returns their energy (zero
        without cables). A collapsed segment raises EvaluationFailure (the trial point is
        then refused)."""
        if self.cables is None:
            return 0.0
        try:
            state = self.cable_state(u, tangent=data is not None)
        except ValueError as error:
            raise EvaluationFailure(str(error)) from None
        internal += state.forces
        if data is not None and state.blocks is not None:
            np.add.at(data, self._cable_positions, state.blocks.ravel())
        return state.energy

    def add_bending(self, u: np.ndarray, internal: np.ndarray, data: np.ndarray | None) -> float:
        """Add the bending's internal forces at u (n_dofs,) to ``internal`` and its stiffness
        to the tangent's CSR data (None: no tangent), in place; returns its energy (zero
        without bending)."""
        if self.bending is None:
            return 0.0
        forces = self.bending.forces(u)
        internal += forces
        if data is not None:
            self.add_bending_stiffness(data)
        return 0.5 * float(u @ forces)

    def add_bending_stiffness(self, data: np.ndarray) -> None:
        """Add the constant bending stiffness to the tangent's CSR data in place (nothing
        without bending)."""
        if self.bending is None:
            return
        if self.compiled:  # the positions hold no index twice
            compiled.add_unique(data, self._bending_positions, self._bending_values)
        else:
            data[self._bending_positions] += self._bending_values

    def reactions(self, u: np.ndarray, load_factor: float) -> np.ndarray:
        """Support reactions f* - f_ext at the constrained dofs (zero elsewhere), (n_dofs,)."""
        external = self.forces_at(load_factor)
        if self.has_follower_loads:
            external = external + self.follower_forces(u, load_factor, stiffness=False)[0]
        return np.where(self.constrained, self.internal_forces(u) - external, 0.0)

    def grow(self, nodes: np.ndarray, layers: int) -> np.ndarray:
        """Nodes (n_nodes,) bool with ``layers`` rings of elements added around them: each
        ring adds the nodes of every element that touches a node already in."""
        if self._incidence is None:  # (n_elements, n_nodes) element-node incidence
            triangles = self.mesh.triangles
            n = triangles.shape[0]
            self._incidence = sp.csr_matrix(
                (np.ones(3 * n), triangles.ravel(), np.arange(0, 3 * n + 1, 3)),
                shape=(n, self.mesh.n_nodes),
            )
        grown = np.asarray(nodes, dtype=bool).copy()
        for _ in range(layers):
            touching = self._incidence @ grown.astype(float) > 0
            grown = self._incidence.T @ touching.astype(float) > 0
        return grown

    def patch(
        self, nodes: np.ndarray, u: np.ndarray, forces: np.ndarray, pressures: np.ndarray
    ) -> tuple[DiscreteSystem, np.ndarray, np.ndarray]:
        """The sub-system of the elements that touch ``nodes`` (n_nodes,) bool, for a
        nonlinear solve on that patch alone (``wrinkle.solvers.elimination``): the free
        components of those nodes stay free; every other component of the patch's nodes is
        held at its value in u (n_dofs,). Its loads are ``forces`` (n_dofs,) and ``pressures``
        (n_elements,), those of one load level, at its load factor 1. Every element whose
        nodes can move is in the patch, so the patch's energy changes as the whole system's
        does when only those nodes move. Returns (sub-system, its displacements at u, the
        global dof of each of its dofs); no bending or cables (ValueError)."""
        if self.bending is not None or self.cables is not None or self.has_follower_edges:
            raise ValueError("a patch of a sheet with bending, cables or edge loads")
        triangles = self.mesh.triangles
        elements = np.flatnonzero(nodes[triangles].any(axis=1))
        kept, local = np.unique(triangles[elements], return_inverse=True)
        dofs = (DOFS_PER_NODE * kept[:, None] + np.arange(DOFS_PER_NODE)).ravel()
        group = np.empty(self.mesh.n_elements, dtype=np.int64)
        for index, (indices, _) in enumerate(self.groups):
            group[indices] = index
        mesh = Mesh(self.mesh.nodes[kept], local.reshape(-1, 3))
        free = ~self.constrained[dofs] & np.repeat(nodes[kept], DOFS_PER_NODE)
        held = u[dofs]
        sub = DiscreteSystem(
            mesh,
            SparsityPattern(mesh.triangles, mesh.n_nodes),
            self.geometry.subset(elements),
            [elements_.material for _, elements_ in self.groups],
            group[elements],
            ~free,
            np.where(free, 0.0, held),
            Loading(forces[dofs], pressures[elements]),
        )
        return sub, held, dofs

    def at(
        self,
        load_factor: float = 1.0,
        prescribed: np.ndarray | None = None,
        pressure_factor: float | None = None,
    ) -> StepProblem:
        """The nonlinear problem at one load level (``StepProblem``); prescribed: (n_dofs,)
        values of the constrained components (default those at load_factor,
        ``prescribed_at``); pressure_factor: the factor on the pressures (default
        load_factor)."""
        if prescribed is None:
            problem = StepProblem(
                self, load_factor, self.prescribed_at(load_factor), pressure_factor
            )
            problem.motion_force = self.motion_force_at(load_factor)
            return problem
        return StepProblem(self, load_factor, np.asarray(prescribed, dtype=float), pressure_factor)

    def load_derivative(self, u: np.ndarray, pressure_only: bool = False) -> np.ndarray:
        """d(f - f*)/d factor at u, (n_dofs,), zero at the constrained components: the loads
        at factor 1 (dead and follower; the pressures alone if ``pressure_only``), which
        the load factor or the pressure factor multiplies (the bordered solves of
        ``wrinkle.solvers.bordered``)."""
        dead = 0.0 if pressure_only else 1.0
        forces = dead * (self.forces_at(1.0) - self.forces_at(0.0))
        if self.has_follower_loads:
            edges = [] if pressure_only else self._edge_terms(1.0)
            if self.initial is not None and not pressure_only:
                edges += [(edge, -1.0) for edge in self.initial.follower_edges]
            edges = [(edge, factor) for edge, factor in edges if factor != 0.0]
            pressures = self.pressure_at(1.0) - self.pressure_at(0.0)
            follower = self._follower_forces(u, pressures, edges, False, None, True, None)[0]
            forces = forces + follower
        return np.where(self.constrained, 0.0, forces)

    def evaluate(
        self,
        u: np.ndarray,
        load_factor: float = 1.0,
        prescribed: np.ndarray | None = None,
        stiffness: bool = True,
        lift: np.ndarray | None = None,
    ) -> Evaluation:
        """``at(load_factor, prescribed).evaluate(u, stiffness, lift)``."""
        return self.at(load_factor, prescribed).evaluate(u, stiffness=stiffness, lift=lift)


class StepProblem:
    """Residual, stiffness and potential energy at one load level (the solvers' ``Problem``).

    load_factor scales the dead forces and the follower loads; prescribed: (n_dofs,) values of
    the constrained displacement components; pressure_factor scales the pressures (default
    load_factor: under volume control and gas loads it is the unknown pressure).
    """

    def __init__(
        self,
        system: DiscreteSystem,
        load_factor: float,
        prescribed: np.ndarray,
        pressure_factor: float | None = None,
    ):
        self.system = system
        self.load_factor = load_factor
        self.pressure_factor = load_factor if pressure_factor is None else pressure_factor
        self.forces = system.forces_at(load_factor)
        self.pressures = system.pressure_at(self.pressure_factor)  # (n_elements,)
        self.prescribed = prescribed
        self.free = ~system.constrained
        self.symmetric = not system.has_follower_loads
        # the solver's step metric has the constrained rows and columns zeroed
        self._constraint_positions, self._constrained_diagonal, self.metric = (
            system.constraint_data()
        )
        self.timer = Stopwatch()  # a path follower shares one across the steps
        self._kept: dict[bool, np.ndarray] = {}  # ``_kept_dofs``
        # the force scale of the prescribed motion (DiscreteSystem.motion_force), made at the
        # first evaluation unless given
        self.motion_force: float | None = None

    #: ``evaluate`` takes ``defer`` (``wrinkle.solvers.base.deferring``)
    defers_stiffness = True

    def _kept_dofs(self, everything: bool) -> np.ndarray:
        """(n_elements, 9) bool: the element dofs whose stiffness rows and columns are
        assembled, every one or the free ones (``DiscreteSystem.assemble_stiffness``)."""
        if everything not in self._kept:
            dofs = self.system.pattern.element_dofs
            self._kept[everything] = np.ones(dofs.shape, bool) if everything else self.free[dofs]
        return self._kept[everything]

    def evaluate(
        self,
        u: np.ndarray,
        stiffness: bool = True,
        lift: np.ndarray | None = None,
        keep_constrained: bool = False,
        keep_elements: bool = False,
        defer: bool = False,
    ) -> Evaluation:
        """Residual, energy, element states and (``stiffness``) the tangent at u, (n_dofs,).

        defer: with ``stiffness``, leave the tangent to be formed when it is asked for
        (``Evaluation.with_stiffness``) where that costs nothing more (the compiled kernels,
        no lift, nothing kept, no cables or follower edge loads): the evaluation keeps the
        elements' material tangent, and a solver that rejects the point never assembles it.
        lift: (n_dofs,) an increment of the constrained components (zero elsewhere); the
        residual is then the out-of-balance force linearised at u + lift,
        f - f*(u) - K lift on the free rows, from the tangent K at u before its constrained
        rows and columns are replaced (needs ``stiffness``). keep_constrained: return the
        whole tangent d(f* - f)/du, its constrained rows and columns kept (the sensitivities
        of the reactions, ``wrinkle.identification.sensitivity``). keep_elements: the
        evaluation holds the ``ElementResult`` (its ``elements``).
        """
        system, timer = self.system, self.timer
        pattern = system.pattern
        # compiled kernels: the element matrices formed and added in one parallel pass, now
        # or (deferred) when the tangent is asked for
        fused = stiffness and system.compiled
        deferred = (
            defer
            and fused
            and lift is None
            and not keep_constrained
            and system.cables is None
            and not system.has_follower_edges
        )
        assemble = stiffness and not deferred
        data = np.zeros(pattern.nnz) if assemble else np.empty(0)  # the stiffness' CSR data

        with timer.part(ELEMENTS):
            x = system.element_coordinates(u)  # shared by the elements and the pressure

        def add_element_stiffness(elements: np.ndarray | slice, K: np.ndarray) -> None:
            # assembled block by block as evaluated
            system.subtract_pressure_stiffness(K, x[elements], elements, self.pressures)
            with timer.part(ASSEMBLY):
                pattern.add_to_data(data, elements, K, compiled=system.compiled)

        def subtract_load_stiffness(elements: np.ndarray | slice, K: np.ndarray) -> None:
            with timer.part(ASSEMBLY):
                pattern.add_to_data(data, elements, -K, compiled=system.compiled)

        with timer.part(ELEMENTS):
            result = system.evaluate_elements(
                u,
                stiffness=stiffness,
                stiffness_sink=add_element_stiffness if stiffness and not fused else None,
                x_elements=x,
                matrices=not fused,
            )
        # the constrained rows and columns are zeroed below: the compiled kernel adds nothing
        # to them unless they are kept or the lift needs them, and then, if nothing else adds
        # to them, they need no zeroing
        everything = keep_constrained or lift is not None
        free_rows_only = fused and not everything and not self._others_add_stiffness()
        with timer.part(ASSEMBLY):
            if fused and not deferred:
                system.assemble_stiffness(
                    data, result, x, self.pressures, self._kept_dofs(everything)
                )
            internal = pattern.assemble_vector(result.forces, compiled=system.compiled)
            other_energy = system.add_bending(u, internal, data if assemble else None)
            other_energy += system.add_cables(u, internal, data if assemble else None)
        external = self.forces
        energy = float(np.sum(result.energy) + other_energy - self.forces @ u)
        if system.has_follower_loads:
            with timer.part(ELEMENTS):
                follower, _ = system.follower_forces(
                    u,
                    self.load_factor,
                    stiffness,
                    subtract_load_stiffness if stiffness else None,
                    pressure_stiffness=False,
                    x_elements=x,
                    pressure_factor=self.pressure_factor,
                )
            external = external + follower
            energy -= system.pressure_work(u, x, self.pressure_factor)
            if system.has_follower_edges or not system.pressure_has_potential:
                energy = np.nan  # follower edge loads, an open pressurised surface: none
        residual = np.where(self.free, external - internal, 0.0)
        reactions = np.where(self.free, 0.0, internal - external)
        if self.motion_force is None:
            self.motion_force = system.motion_force(self.prescribed)
        scale = max(
            float(np.linalg.norm(external)), float(np.linalg.norm(reactions)), self.motion_force
        )
        state = result.response.state
        counts = (
            int(np.count_nonzero(state == TAUT)),
            int(np.count_nonzero(state == WRINKLED)),
            int(np.count_nonzero(state == SLACK)),
        )
        K = None
        if assemble:
            with timer.part(ASSEMBLY):
                if lift is not None:
                    coupling = pattern.matrix(data) @ lift
                    residual = np.where(self.free, residual - coupling, 0.0)
                if not keep_constrained:
                    self._zero_constrained(data, written=not free_rows_only)
                K = pattern.matrix(data)
        later = None
        if deferred:

            def later() -> sp.csr_matrix:
                return self._deferred_stiffness(result, x)

        return Evaluation(
            residual,
            energy,
            float(scale),
            counts,
            K,
            system.force_round_off,
            self.symmetric,
            pattern.diagonal,
            self.metric,
            reactions,
            lambda: system.inadmissible(system.element_coordinates(u)),
            result if keep_elements else None,
            later,
            lambda: system.diverging(u),
        )

    def patch(self, nodes: np.ndarray, u: np.ndarray) -> tuple[StepProblem, np.ndarray, np.ndarray]:
        """This level's problem on the patch of elements that touch ``nodes`` (n_nodes,) bool,
        every component of the patch held at its value in u (n_dofs,) but the free ones of
        those nodes (``DiscreteSystem.patch``): (problem, its displacements at u, the global
        dof of each of its dofs). Its force scale is that of its own loads and reactions, and
        its parts' times go to this problem's stopwatch."""
        sub, held, dofs = self.system.patch(nodes, u, self.forces, self.pressures)
        problem = StepProblem(sub, 1.0, sub.prescribed)
        problem.motion_force = 0.0  # the held values are no motion of the sheet's supports
        problem.timer = self.timer
        return problem, held, dofs

    def grow(self, nodes: np.ndarray, layers: int) -> np.ndarray:
        """``DiscreteSystem.grow``."""
        return self.system.grow(nodes, layers)

    def _others_add_stiffness(self) -> bool:
        """Whether parts besides the membrane elements (bending, cables, follower edge loads)
        add to the tangent, on its constrained rows and columns too."""
        system = self.system
        return system.bending is not None or system.cables is not None or system.has_follower_edges

    def _zero_constrained(self, data: np.ndarray, written: bool = True) -> None:
        """The constrained rows and columns of the tangent's data zeroed, their diagonal one.
        written: whether anything was added to those entries; if not (data began as zeros and
        only the free rows and columns were added), they are zero already and only the
        diagonal is set (the 320 x 160 rectangle: 1.6 ms a tangent)."""
        if self.system.compiled:
            if written:
                compiled.put(data, self._constraint_positions, 0.0)
            compiled.put(data, self._constrained_diagonal, 1.0)
        else:
            if written:
                data[self._constraint_positions] = 0.0
            data[self._constrained_diagonal] = 1.0

    def _deferred_stiffness(self, result: ElementResult, x: np.ndarray) -> sp.csr_matrix:
        """The tangent of an evaluation made with ``defer``: the element matrices from its
        material tangent (result, x its coordinates), the constant bending stiffness, the
        constrained rows and columns zeroed; what ``evaluate`` forms at once otherwise."""
        system, pattern = self.system, self.system.pattern
        with self.timer.part(ASSEMBLY):
            data = np.zeros(pattern.nnz)
            system.assemble_stiffness(data, result, x, self.pressures, self._kept_dofs(False))
            system.add_bending_stiffness(data)
            self._zero_constrained(data, written=self._others_add_stiffness())
            return pattern.matrix(data)
