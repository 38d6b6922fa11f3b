"""The model: what the engineer defines — a mesh, materials with their fibre frames, supports
and loads — and ``solve``, a front end to the load-path follower.

Example::

    mesh = wrinkle.rectangle(1.0, 1.0, 10, 10)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1e3, nu=0.3, thickness=0.1))
    model.fix("bottom")
    model.prescribe("top", displacement=(0.05, 0.02, 0.0))
    results = model.solve(steps=5)

Nodes are given as indices, a boolean mask, a node-set name or a selector such as "x == 0"
(``wrinkle.selectors``); elements as indices, a mask or an element-set name (a physical group).
``discretise`` makes the ``DiscreteSystem`` the solvers work on (``wrinkle.system``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from wrinkle.assembly import DOFS_PER_NODE, SparsityPattern
from wrinkle.bending import Bending, bending_stiffness, check_flat
from wrinkle.cables import Cable, Cables, cable_edges
from wrinkle.gas import Gas
from wrinkle.kinematics import (
    ReferenceGeometry,
    material_frame,
    reference_geometry,
    reference_normals,
)
from wrinkle.loads import boundary_edges, edge_dead_forces, edge_follower_forces
from wrinkle.materials.base import Material
from wrinkle.memory import kept_memory
from wrinkle.mesh import Mesh
from wrinkle.post import support_moments, support_reactions
from wrinkle.results import Results, StepResult
from wrinkle.selectors import select_nodes
from wrinkle.sequencing import NestedStart
from wrinkle.solvers.arc_length import follow_arc_length
from wrinkle.solvers.base import ConvergenceError, SolverResult
from wrinkle.solvers.bordered import ProbeDisplacement
from wrinkle.solvers.control import (
    EnclosedVolume,
    GasEnergy,
    PathEnd,
    VolumeLagrangian,
    follow_load_path_to,
    follow_volume_path,
)
from wrinkle.solvers.settings import ARC_LENGTH_STEPS, SolverSettings
from wrinkle.solvers.stepping import Resume, follow_load_path
from wrinkle.system import DiscreteSystem, FollowerEdgeLoad, Loading, LoadState, StepStart
from wrinkle.wrinkling import Wrinkling

__all__ = ["COMPONENTS", "Model", "StepStart", "Support"]

COMPONENTS = {"x": 0, "y": 1, "z": 2}

NodeSelection = str | ArrayLike
ElementSelection = str | ArrayLike | None


def _component_indices(components: str | Sequence[str]) -> list[int]:
    try:
        return [COMPONENTS[c] for c in components]
    except KeyError:
        raise ValueError(
            f"components must be drawn from 'x', 'y', 'z', got {components!r}"
        ) from None


@dataclass
class Support:
    """A named set of supported nodes and the dofs it holds; its reaction is the sum over
    those dofs (a node held by two supports in different directions counts in each for the
    directions it holds there). values: the displacements it prescribes at its dofs at load
    factor 1 (zero for ``fix``), which an analysis step that names it moves them to."""

    label: str
    nodes: np.ndarray
    dofs: np.ndarray
    moment_about: np.ndarray | None = None  # (3,): report the reaction's moment about it
    values: np.ndarray | None = None  # (len(dofs),); None: zero

    def prescribed(self) -> np.ndarray:
        """The values at its dofs, (len(dofs),)."""
        return np.zeros(self.dofs.size) if self.values is None else self.values


def _indices(selection: ArrayLike, count: int, what: str) -> np.ndarray:
    """Indices (k,) int64 of a selection of nodes or elements given as indices or a mask."""
    selection = np.atleast_1d(np.asarray(selection))
    if selection.dtype == bool:
        if selection.shape != (count,):
            raise ValueError(f"a {what} mask must have {count} entries, got {selection.shape}")
        selection = np.flatnonzero(selection)
    if selection.size == 0:
        raise ValueError(f"no {what}s selected")
    if not np.issubdtype(selection.dtype, np.integer):
        raise ValueError(f"{what}s must be given as integer indices, a mask or a name")
    bad = (selection < 0) | (selection >= count)
    if np.any(bad):
        raise ValueError(f"{what} {selection[bad][0]} does not exist (mesh has {count})")
    return selection.astype(np.int64)


class Model:
    """A membrane model: mesh, materials with wrinkling, supports and loads.

    mesh: ``Mesh``; material: a ``Material`` (wrapped in ``Wrinkling``) or a ``Wrinkling`` for
    all elements (or None, then ``assign_material`` for each region); fibre_direction: (3,) or
    (n_elements, 3) vector projected onto each element as the material axis 1; fibre_angle:
    radians (scalar or (n_elements,)) turning it about the element normal; density: the
    material's mass per unit volume, for the natural modes (``wrinkle.modes``).

    Attributes: ``constrained`` (n_dofs,) bool and ``prescribed`` (n_dofs,) the supported
    components and their values at load factor 1, ``forces`` (n_dofs,) the dead nodal forces
    at load factor 1, ``supports`` (``Support``), ``pressure`` (n_elements,) the follower
    pressure at load factor 1, ``bending`` (n_elements,) the bending stiffness D of the mean
    surface (zero: a membrane; ``add_bending``), ``density`` (n_elements,) the mass per unit
    volume (NaN where not given; ``assign_material``). Change them through the methods, which keep
    the discrete system (``discretise``) up to date.
    """

    def __init__(
        self,
        mesh: Mesh,
        material: Material | Wrinkling | None = None,
        fibre_direction: ArrayLike = (1.0, 0.0, 0.0),
        fibre_angle: ArrayLike = 0.0,
        density: float | None = None,
    ):
        self.mesh = mesh
        n = mesh.n_elements
        direction = np.asarray(fibre_direction, dtype=float)
        self._fibre_direction = (
            np.tile(direction, (n, 1)) if direction.ndim == 1 else direction.copy()
        )
        self._fibre_angle = np.broadcast_to(np.asarray(fibre_angle, dtype=float), (n,)).copy()
        self._material_of_element = np.full(n, -1)
        self._materials: list[Wrinkling] = []
        self.n_dofs = DOFS_PER_NODE * mesh.n_nodes
        self.constrained = np.zeros(self.n_dofs, dtype=bool)
        self.prescribed = np.zeros(self.n_dofs)  # displacement at full load
        self.forces = np.zeros(self.n_dofs)  # dead nodal forces at full load
        self.supports: list[Support] = []
        self.pressure = np.zeros(n)  # follower pressure at full load, per element
        self._pressure_extent = np.zeros(n, dtype=bool)  # under some pressure load
        self.gas: Gas | None = None  # a gas load (add_gas): its pressure on the elements above
        self._edge_follower: list[FollowerEdgeLoad] = []
        # each load's contributions by its label, for analysis steps (``load_state``): dead
        # forces (dofs, values), pressures (elements, values), follower edge loads
        self._load_parts: dict[str, list[tuple[str, Any, Any]]] = {}
        self._load_count = 0
        self.cables: list[Cable] = []  # the cables (add_cables)
        self.bending = np.zeros(n)  # bending stiffness D per element (add_bending)
        self.density = np.full(n, np.nan)  # mass per unit volume per element (assign_material)
        self._bending: Bending | None = None  # kept until the bending stiffness changes
        self._pattern: SparsityPattern | None = None  # the mesh's, kept while it lives
        self._geometry: ReferenceGeometry | None = None  # kept until the materials change
        self._system: DiscreteSystem | None = None  # kept until anything changes
        if material is not None:
            self.assign_material(material, density=density)

    def _changed(self) -> None:
        self._system = None

    # -- selections ---------------------------------------------------------------------
    def _node_indices(self, nodes: NodeSelection) -> np.ndarray:
        """Indices (k,) of nodes given as indices, a mask, a node-set name or a selector."""
        if isinstance(nodes, str):
            return select_nodes(self.mesh, nodes)
        return _indices(nodes, self.mesh.n_nodes, "node")

    def _element_indices(self, elements: ElementSelection) -> np.ndarray:
        """Indices (k,) of elements given as indices, a mask or an element-set name (None:
        all)."""
        if elements is None:
            return np.arange(self.mesh.n_elements)
        if isinstance(elements, str):
            if elements not in self.mesh.element_sets:
                known = ", ".join(sorted(self.mesh.element_sets)) or "none"
                raise ValueError(
                    f"'{elements}' is not an element set of the mesh (it has: {known})"
                )
            return np.asarray(self.mesh.element_sets[elements], dtype=np.int64)
        return _indices(elements, self.mesh.n_elements, "element")

    # -- materials ----------------------------------------------------------------------
    def assign_material(
        self,
        material: Material | Wrinkling,
        elements: ElementSelection = None,
        fibre_direction: ArrayLike | None = None,
        fibre_angle: ArrayLike | None = None,
        density: float | None = None,
    ) -> None:
        """Give ``elements`` (indices, mask or element-set name; None = all) a material and,
        optionally, their own fibre direction ((3,) or (k, 3)) and angle (radians), and the
        material's density (mass per unit volume, > 0), which the natural modes need
        (``wrinkle.modes``; None: unknown).

        An isotropic material (``is_isotropic``) needs no fibre direction. For an anisotropic
        one the direction is checked here: ValueError naming the first element whose plane it
        is perpendicular to (or if it is zero), and what to set."""
        chosen = self._element_indices(elements)
        if density is not None and not (math.isfinite(density) and density > 0):
            raise ValueError(f"density must be finite and > 0, got {density}")
        wrinkling = material if isinstance(material, Wrinkling) else Wrinkling(material)
        direction = self._fibre_direction[chosen]
        if fibre_direction is not None:
            direction = np.broadcast_to(np.asarray(fibre_direction, dtype=float), direction.shape)
        if not wrinkling.is_isotropic:
            _, _, _, normal = reference_normals(self.mesh.nodes, self.mesh.triangles[chosen])
            flat = ~np.all(np.isfinite(normal), axis=1)  # zero area: reported by the geometry
            material_frame(
                np.where(flat[:, None], 0.0, normal),
                direction,
                isotropic=flat,
                element_numbers=chosen,
            )
        self._materials.append(wrinkling)
        self._material_of_element[chosen] = len(self._materials) - 1
        if fibre_direction is not None:
            self._fibre_direction[chosen] = direction
        if fibre_angle is not None:
            self._fibre_angle[chosen] = fibre_angle
        self.density[chosen] = np.nan if density is None else float(density)
        self._geometry = None
        self._changed()

    @property
    def materials(self) -> list[Wrinkling]:
        """The materials assigned, in order (``assign_material``)."""
        return list(self._materials)

    def mass_per_area(self) -> np.ndarray:
        """Mass per unit reference area of each element, rho t0 (n_elements,): its
        material's density times its reference thickness. ValueError naming the first element
        without a density (``assign_material(density=...)``)."""
        missing = np.flatnonzero(~(self.density > 0))
        if missing.size:
            raise ValueError(
                f"{missing.size} element(s) have no density, first: element {missing[0]}; give "
                "the material's density (case file: [material] density; Python: "
                "assign_material(..., density=...))"
            )
        thickness = np.array([m.thickness for m in self._materials])
        return self.density * thickness[self._material_of_element]

    def _reference_geometry(self) -> ReferenceGeometry:
        if self._geometry is None:
            self._geometry = self.geometry_on(self.mesh.nodes)
        return self._geometry

    def geometry_on(self, nodes: np.ndarray) -> ReferenceGeometry:
        """The reference geometry (``wrinkle.kinematics``) of the mesh's triangles on the
        node positions ``nodes`` (n_nodes, 3), with the materials' fibre frames projected
        onto them. ValueError for an element without a material or of zero area."""
        missing = np.flatnonzero(self._material_of_element < 0)
        if missing.size:
            raise ValueError(
                f"{missing.size} element(s) have no material, first: element {missing[0]}"
            )
        isotropic = np.array([m.is_isotropic for m in self._materials], dtype=bool)
        return reference_geometry(
            nodes,
            self.mesh.triangles,
            self._fibre_direction,
            self._fibre_angle,
            isotropic=isotropic[self._material_of_element],
        )

    def element_prestress(self) -> np.ndarray:
        """The prestress N0 (n_elements, 2, 2) of each element's material in its material
        frame, force per unit length (``Prestressed``; zero for a material without one)."""
        own = np.array(
            [getattr(m.material, "prestress", np.zeros((2, 2))) for m in self._materials]
        ).reshape(-1, 2, 2)
        return own[self._material_of_element]

    def pattern(self) -> SparsityPattern:
        """The sparsity pattern of the model's stiffness (kept while the mesh and the bending
        stiffness do not change)."""
        self.discretise()
        assert self._pattern is not None
        return self._pattern

    # -- supports and loads -------------------------------------------------------------
    def _add_support(
        self,
        nodes: np.ndarray,
        dofs: np.ndarray,
        label: str | None,
        moment_about: ArrayLike | None = None,
        values: np.ndarray | None = None,
    ) -> None:
        label = label or f"support {len(self.supports) + 1}"
        point = None
        if moment_about is not None:
            point = np.asarray(moment_about, dtype=float)
            if point.shape != (3,) or not np.all(np.isfinite(point)):
                raise ValueError(f"moment_about must be a point [x, y, z], got {moment_about!r}")
        dofs, first = np.unique(dofs, return_index=True)
        held = np.zeros(dofs.size) if values is None else np.asarray(values, float)[first]
        self.supports.append(Support(label, nodes, dofs, point, held))
        self._changed()

    def fix(
        self,
        nodes: NodeSelection,
        components: str | Sequence[str] = "xyz",
        label: str | None = None,
        moment_about: ArrayLike | None = None,
    ) -> None:
        """Hold the given displacement components of ``nodes`` at zero. moment_about: a point
        (3,) about which the results report the support's reaction moment."""
        chosen = self._node_indices(nodes)
        dofs = (DOFS_PER_NODE * chosen[:, None] + np.array(_component_indices(components))).ravel()
        self.constrained[dofs] = True
        self.prescribed[dofs] = 0.0
        self._add_support(chosen, dofs, label, moment_about)

    def hold_in_place(self) -> None:
        """Make every prescribed displacement zero: the supports then hold their components
        where the reference mesh has them (a form-found mesh, whose boundary the prescribed
        displacements moved into place, ``wrinkle.formfinding``)."""
        self.prescribed[:] = 0.0
        for support in self.supports:
            support.values = np.zeros(support.dofs.size)
        self._changed()

    def prescribe(
        self,
        nodes: NodeSelection,
        displacement: ArrayLike,
        label: str | None = None,
        moment_about: ArrayLike | None = None,
    ) -> None:
        """Prescribe displacements reached at load factor 1.

        displacement: (3,) for all nodes or (k, 3) per node; a NaN component is left free.
        moment_about: as for ``fix``.
        """
        chosen = self._node_indices(nodes)
        values = np.broadcast_to(np.asarray(displacement, dtype=float), (chosen.size, 3))
        dofs = DOFS_PER_NODE * chosen[:, None] + np.arange(3)
        set_ = ~np.isnan(values)
        self.constrained[dofs[set_]] = True
        self.prescribed[dofs[set_]] = values[set_]
        self._add_support(chosen, dofs[set_], label, moment_about, values[set_])

    def _load_part(self, label: str | None) -> list[tuple[str, Any, Any]]:
        """The contributions of the load labelled ``label`` (default "load N", N counting
        the loads added), to which a new load adds its own."""
        self._load_count += 1
        name = f"load {self._load_count}" if label is None else str(label)
        return self._load_parts.setdefault(name, [])

    def _add_forces(self, dofs: np.ndarray, values: np.ndarray, label: str | None) -> None:
        """Add dead forces ``values`` at the components ``dofs`` (same shape) as a load."""
        dofs, values = np.asarray(dofs).ravel(), np.asarray(values, dtype=float).ravel()
        np.add.at(self.forces, dofs, values)
        self._load_part(label).append(("forces", dofs.copy(), values.copy()))
        self._changed()

    @property
    def load_labels(self) -> list[str]:
        """The labels of the loads, in the order they were first added."""
        return list(self._load_parts)

    def add_nodal_force(
        self, nodes: NodeSelection, force: ArrayLike, label: str | None = None
    ) -> None:
        """Add a dead nodal force (3,) or (k, 3), reached at load factor 1. label: the
        load's name for analysis steps (``solve(loads=...)``; default "load N")."""
        chosen = self._node_indices(nodes)
        values = np.broadcast_to(np.asarray(force, dtype=float), (chosen.size, 3))
        if not np.all(np.isfinite(values)):
            raise ValueError("nodal force must be finite")
        self._add_forces(DOFS_PER_NODE * chosen[:, None] + np.arange(3), values, label)

    def set_nodal_forces(self, forces: ArrayLike, label: str = "nodal forces") -> None:
        """Replace all dead nodal forces at load factor 1 (those of ``add_nodal_force``, dead
        edge loads and gravity) by ``forces``, (n_dofs,) or (n_nodes, 3), one load labelled
        ``label``."""
        values = np.asarray(forces, dtype=float).reshape(-1)
        if values.shape != self.forces.shape:
            raise ValueError(f"nodal forces must have {self.n_dofs} components, got {values.size}")
        if not np.all(np.isfinite(values)):
            raise ValueError("nodal force must be finite")
        for name in list(self._load_parts):
            kept = [part for part in self._load_parts[name] if part[0] != "forces"]
            if kept:
                self._load_parts[name] = kept
            else:
                del self._load_parts[name]
        self.forces[:] = 0.0
        self._add_forces(np.arange(self.n_dofs), values, label)

    def set_prescribed(self, nodes: NodeSelection, displacement: ArrayLike) -> None:
        """Change the values at load factor 1 of components already held (by ``fix`` or
        ``prescribe``): displacement (3,) or (k, 3), a NaN component left as it is. The
        supports and their labels stay; ValueError for a value on a free component."""
        chosen = self._node_indices(nodes)
        values = np.broadcast_to(np.asarray(displacement, dtype=float), (chosen.size, 3))
        dofs = DOFS_PER_NODE * chosen[:, None] + np.arange(3)
        given = ~np.isnan(values)
        free = given & ~self.constrained[dofs]
        if np.any(free):
            node, component = np.argwhere(free)[0]
            raise ValueError(
                f"node {chosen[node]} is free in {'xyz'[component]}: prescribe it to hold it"
            )
        self.prescribed[dofs[given]] = values[given]
        changed = np.zeros(self.n_dofs)
        changed[dofs[given]] = values[given]
        mask = np.zeros(self.n_dofs, dtype=bool)
        mask[dofs[given]] = True
        for support in self.supports:  # every support holding a changed component
            inside = mask[support.dofs]
            if np.any(inside):
                own = np.zeros(support.dofs.size) if support.values is None else support.values
                support.values = np.where(inside, changed[support.dofs], own)
        self._changed()

    def add_pressure(
        self, value: float, elements: ElementSelection = None, label: str | None = None
    ) -> None:
        """Follower pressure (force per unit current area) on ``elements`` (None = all),
        positive along the element normal (x2 - x1) x (x3 - x1), reached at load factor 1;
        label as for ``add_nodal_force``."""
        if not np.isfinite(value):
            raise ValueError("pressure must be finite")
        if self.gas is not None:
            raise ValueError("a model with a gas load can have no other pressure load")
        chosen = self._element_indices(elements)
        self.pressure[chosen] += value
        self._pressure_extent[chosen] |= value != 0
        self._load_part(label).append(("pressure", chosen.copy(), float(value)))
        self._changed()

    def add_cables(
        self,
        nodes: NodeSelection,
        EA: float,
        prestress: float = 0.0,
        label: str | None = None,
        mass_per_length: float = 0.0,
    ) -> None:
        """A tension-only cable along the mesh edges between the selected nodes (a selector,
        a node set such as a gmsh line physical group, indices or a mask), which must form
        one connected path (``wrinkle.cables.cable_edges``): axial stiffness EA > 0 (force),
        prestress N0 >= 0 (the force at its reference length), mass per unit length >= 0
        (for the natural modes). label: its name in the summary (default "cable N").
        ValueError for bad values or unconnected nodes."""
        if not (np.isfinite(EA) and EA > 0):
            raise ValueError(f"cable EA must be finite and > 0, got {EA!r}")
        if not (np.isfinite(prestress) and prestress >= 0):
            raise ValueError(f"cable prestress must be finite and >= 0, got {prestress!r}")
        if not (np.isfinite(mass_per_length) and mass_per_length >= 0):
            raise ValueError(
                f"cable mass_per_length must be finite and >= 0, got {mass_per_length!r}"
            )
        edges = cable_edges(self.mesh.triangles, self._node_indices(nodes), self.mesh.n_nodes)
        name = label if label is not None else f"cable {len(self.cables) + 1}"
        if any(cable.label == name for cable in self.cables):
            raise ValueError(f"cable label {name!r} is used twice")
        self.cables.append(Cable(name, edges, float(EA), float(prestress), float(mass_per_length)))
        self._changed()

    def _cable_segments(self) -> Cables | None:
        """The segments of every cable (``wrinkle.cables.Cables``), None without cables."""
        if not self.cables:
            return None
        return Cables.of(self.cables, self.mesh.nodes)

    def add_gas(
        self, gas: Gas, elements: ElementSelection = None, label: str | None = None
    ) -> None:
        """An enclosed gas (``wrinkle.gas.Gas``) on ``elements`` (None = all): its gauge
        pressure, set by the volume they enclose, acts along the element normals as a
        follower pressure does. One gas load per model, and no other pressure load; solved
        under load control, the load factor pumping the gas in."""
        if self.gas is not None or np.any(self.pressure):
            raise ValueError("a model has at most one gas load and then no other pressure load")
        chosen = self._element_indices(elements)
        self.pressure[chosen] = 1.0  # the gauge pressure's factor
        self._pressure_extent[chosen] = True
        self._load_part(label).append(("pressure", chosen.copy(), 1.0))
        self.gas = gas
        self._changed()

    @property
    def pressure_element(self) -> int | None:
        """The element whose pressure the results report (``pressure``): that of the largest
        pressure at load factor 1, or, where the pressure loads cancel, the first element
        under one; None without pressure loads."""
        if np.any(self.pressure):
            return int(np.argmax(np.abs(self.pressure)))
        if np.any(self._pressure_extent):
            return int(np.argmax(self._pressure_extent))
        return None

    @property
    def pressure_value(self) -> float | None:
        """The value at load factor 1 of the pressure loads (the one of largest magnitude
        where they differ), which the ``pressure`` of the results reports times the load or
        pressure factor; 1 for a gas load (the factor is then its gauge pressure); 0 where
        the pressure loads cancel; None without pressure loads."""
        element = self.pressure_element
        return None if element is None else float(self.pressure[element])

    def add_bending(
        self, stiffness: float | None = None, elements: ElementSelection = None
    ) -> None:
        """Give ``elements`` (None = all) a bending stiffness on the mean surface
        (``wrinkle.bending``): ``stiffness`` D (force x length), or None for each element's
        material's own, t^2/12 times its in-plane stiffness (E t^3 / 12 (1 - nu^2) for an
        isotropic sheet; ``bending_stiffness``). Replaces an earlier value on those elements.
        For flat reference meshes only; ValueError for a curved one, a negative or non-finite
        D, or an element without a material when D is None."""
        check_flat(self.mesh)
        chosen = self._element_indices(elements)
        if stiffness is None:
            groups = self._material_of_element[chosen]
            if np.any(groups < 0):
                first = chosen[groups < 0][0]
                raise ValueError(
                    f"element {first} has no material: assign it before add_bending(), or "
                    "give the stiffness"
                )
            own = np.array([bending_stiffness(m.material) for m in self._materials])
            values = own[groups]
        else:
            if not (np.isfinite(stiffness) and stiffness >= 0):
                raise ValueError(f"bending stiffness must be finite and >= 0, got {stiffness}")
            values = np.full(chosen.size, float(stiffness))
        self.bending[chosen] = values
        self._bending = None
        self._pattern = None
        self._changed()

    def add_gravity(
        self,
        acceleration: ArrayLike,
        density: float,
        elements: ElementSelection = None,
        label: str | None = None,
    ) -> None:
        """Dead weight density * reference thickness * A0 * acceleration, a third to each
        node; acceleration (3,) (length / time^2), density mass per unit volume; label as
        for ``add_nodal_force``."""
        if not density > 0:
            raise ValueError(f"density must be > 0, got {density}")
        chosen = self._element_indices(elements)
        thickness = np.array([m.thickness for m in self._materials])[
            self._material_of_element[chosen]
        ]
        area = self._reference_geometry().area[chosen]
        weight = (density * thickness * area / 3.0)[:, None] * np.asarray(acceleration, float)
        triangles = self.mesh.triangles[chosen]
        dofs = DOFS_PER_NODE * triangles[:, :, None] + np.arange(3)  # (k, 3 nodes, 3)
        self._add_forces(dofs, np.broadcast_to(weight[:, None, :], dofs.shape), label)

    def add_edge_load(
        self,
        nodes: NodeSelection,
        traction: ArrayLike | None = None,
        normal: float | None = None,
        follow: bool = False,
        label: str | None = None,
    ) -> None:
        """Load on the boundary edges whose two nodes are both in ``nodes``; label as for
        ``add_nodal_force``.

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
            edge_load = FollowerEdgeLoad(
                triples, np.full(triples.shape[0], float(normal)), owner, dofs
            )
            self._edge_follower.append(edge_load)
            self._load_part(label).append(("edges", edge_load, None))
            self._changed()
            return
        if normal is not None:
            forces, _ = edge_follower_forces(X, np.full(triples.shape[0], float(normal)), False)
            forces = forces[:, :6]
        else:
            traction = np.broadcast_to(np.asarray(traction, dtype=float), (triples.shape[0], 3))
            forces = edge_dead_forces(length, traction)
        dofs = DOFS_PER_NODE * triples[:, :2, None] + np.arange(3)  # (m, 2 nodes, 3)
        self._add_forces(dofs, forces.reshape(-1, 2, 3), label)

    @property
    def has_follower_loads(self) -> bool:
        """Whether a load follows the deformation (pressure, following edge loads)."""
        return bool(np.any(self.pressure != 0) or self._edge_follower)

    def _loading_of(self, label: str) -> Loading:
        """The ``Loading`` at load factor 1 of the loads labelled ``label``."""
        forces, pressure = np.zeros(self.n_dofs), np.zeros(self.mesh.n_elements)
        edges: list[FollowerEdgeLoad] = []
        for kind, where, values in self._load_parts[label]:
            if kind == "forces":
                np.add.at(forces, where, values)
            elif kind == "pressure":
                pressure[where] += values
            else:
                edges.append(where)
        return Loading(forces, pressure, edges)

    def load_state(
        self,
        loads: Sequence[str] | None = None,
        supports: Sequence[str] | None = None,
        start: StepStart | None = None,
    ) -> LoadState:
        """The loads and supported values at the end of an analysis step from ``start``
        (None: the reference state, all loads zero) in which the loads labelled ``loads``
        and the supports labelled ``supports`` reach their values as the model has them now
        (None for both: every load and support); the others keep their values at the start.
        A component held now but free at the start keeps its displacement there. ValueError
        naming an unknown label."""
        if loads is None and supports is None:
            loads, supports = self.load_labels, [s.label for s in self.supports]
        loads, supports = list(loads or ()), list(supports or ())
        for label in loads:
            if label not in self._load_parts:
                known = ", ".join(repr(name) for name in self._load_parts) or "none"
                raise ValueError(f"no load is labelled {label!r} (loads: {known})")
        labels = {s.label for s in self.supports}
        for label in supports:
            if label not in labels:
                known = ", ".join(repr(name) for name in dict.fromkeys(labels)) or "none"
                raise ValueError(f"no support is labelled {label!r} (supports: {known})")
        parts = dict(start.state.parts) if start is not None else {}
        parts.update({label: self._loading_of(label) for label in loads})
        prescribed = self._start_prescribed(start)
        for support in self.supports:
            if support.label in supports:
                prescribed[support.dofs] = support.prescribed()
        moved = frozenset(supports) | (start.state.supports if start is not None else frozenset())
        return LoadState(parts, self.constrained.copy(), prescribed, moved)

    def _start_prescribed(self, start: StepStart | None) -> np.ndarray:
        """The supported values at the start of an analysis step, (n_dofs,): zero from the
        reference state; else those at ``start`` where it held them, its displacement
        elsewhere."""
        if start is None:
            return np.zeros(self.n_dofs)
        held = start.state.constrained
        return np.where(held, start.state.prescribed, start.displacement).astype(float)

    def support_reactions(self, reactions: np.ndarray) -> dict[str, list[float]]:
        """Sum of the reactions (n_dofs,) over the dofs each support holds (supports with the
        same label together, a component they share counted once): label -> [Fx, Fy, Fz]."""
        return support_reactions(self.supports, reactions)

    def support_moments(
        self, reactions: np.ndarray, displacement: np.ndarray
    ) -> dict[str, list[float]]:
        """The moment of each support's reactions (n_dofs,) about its ``moment_about`` point,
        at the nodes' positions X + u (u = displacement, (n_dofs,)): label -> [Mx, My, Mz],
        for the supports that name a point (``wrinkle.post.support_moments``)."""
        positions = self.mesh.nodes + np.asarray(displacement, dtype=float).reshape(-1, 3)
        return support_moments(self.supports, reactions, positions)

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
        names = np.array(
            [
                "translation in x",
                "translation in y",
                "translation in z",
                "rotation about x",
                "rotation about y",
                "rotation about z",
            ]
        )
        scale = np.abs(held).max() if held.size else 1.0
        pure = np.all(np.abs(held) <= 1e-12 * scale, axis=0)  # modes no support touches
        if np.any(pure):
            motion = ", ".join(names[pure])
        else:
            motion = "a motion combining " + " and ".join(
                names[np.abs(free) > 0.3 * np.abs(free).max()]
            )
        raise ValueError(f"rigid-body motion is unrestrained: the supports do not prevent {motion}")

    # -- discretisation and solution ----------------------------------------------------
    def release(self) -> None:
        """Forget the discrete system, its pattern and geometry (made again by
        ``discretise``), to free their memory."""
        self._system = self._pattern = self._geometry = self._bending = None

    def elimination_obstacle(self) -> str | None:
        """Why nonlinear elimination (``wrinkle.solvers.elimination``) cannot solve patches
        of this model, or None: it solves a pure membrane's."""
        parts = [
            name
            for name, present in (
                ("bending stiffness", bool(np.any(self.bending > 0))),
                ("cables", bool(self.cables)),
                ("follower edge loads", bool(self._edge_follower)),
                ("a gas load (its solves are bordered ones)", self.gas is not None),
            )
            if present
        ]
        if not parts:
            return None
        return "it solves patches of a pure membrane, and this model has " + " and ".join(parts)

    def discretise(self) -> DiscreteSystem:
        """The discrete system of the model as it stands (made again after a change)."""
        if self._system is None:
            if self._bending is None and np.any(self.bending > 0):
                self._bending = Bending(self.mesh, self.bending)
            if self._pattern is None:
                coupled = None if self._bending is None else self._bending.coupled_pairs()
                self._pattern = SparsityPattern(
                    self.mesh.triangles, self.mesh.n_nodes, coupled=coupled
                )
            self._system = DiscreteSystem(
                self.mesh,
                self._pattern,
                self._reference_geometry(),
                self._materials,
                self._material_of_element.copy(),
                self.constrained.copy(),
                self.prescribed.copy(),
                Loading(self.forces.copy(), self.pressure.copy(), list(self._edge_follower)),
                self._bending,
                self._cable_segments(),
                self._pressure_extent.copy() if np.any(self._pressure_extent) else None,
            )
        return self._system

    def _describe_load(self, load_factor: float) -> str:
        """The loads at ``load_factor`` in words, for messages: the largest pressure, else
        the largest nodal force, else the load factor alone."""
        pressure = float(np.abs(self.pressure).max(initial=0.0))
        if pressure > 0:
            return f"pressure {load_factor * pressure:.4g}"
        force = float(np.abs(self.forces).max(initial=0.0))
        if force > 0:
            return f"largest nodal force {load_factor * force:.4g}"
        return f"load factor {load_factor:.4g}"

    def _follow(
        self,
        system: DiscreteSystem,
        settings: SolverSettings,
        solver: Any,
        u0: np.ndarray | None,
        record: Callable[[float, np.ndarray, SolverResult], None],
        results: Results,
        first_guess: NestedStart | None,
        probes: Mapping[str, np.ndarray] | None,
        resume: Resume | None = None,
    ) -> PathEnd:
        """Follow the path ``settings.control`` names (``solve``), with the stop, a gas
        load's law; returns how it ended. ValueError for a control or stop the model cannot
        have."""
        stop = None
        if settings.stop is not None:
            name, displacement = settings.stop
            if not probes or name not in probes:
                known = ", ".join(probes or {}) or "none"
                raise ValueError(f"solver stop: no probe named {name!r} (probes: {known})")
            stop = ProbeDisplacement(np.asarray(probes[name]), float(displacement))
        timer, controller = results.stopwatch, settings.controller()
        control = settings.control
        if resume is not None and (control != "load" or stop is not None or self.gas is not None):
            raise ValueError(
                "restart: only a load-controlled path without a stop or gas load can be "
                "continued (solver control = 'load')"
            )
        if self.gas is not None or control == "volume":
            what = "[[load]] kind = 'gas'" if self.gas is not None else "solver control = 'volume'"
            if self.gas is not None and control != "load":
                raise ValueError(f"{what}: a gas load is solved under control = 'load'")
            open_surface = system.volume_closure()
            if open_surface is not None:
                raise ValueError(f"{what}: {open_surface}")
            start = np.zeros(system.n_dofs) if u0 is None else u0
            if not np.any(system.volume_gradient(start)):
                raise ValueError(
                    f"{what}: the enclosed volume cannot change: the supports hold every "
                    "component that would change it"
                )
            constraint_at = self._volume_constraints(system, settings, what)
            return follow_volume_path(
                system, solver, controller, constraint_at, record, u0, 0.0, timer, stop
            )
        if control == "arc-length":
            if system.moves_supports:
                raise ValueError(
                    "solver control = 'arc-length': the loads alone may follow the load factor; "
                    "the model prescribes displacements (use control = 'load')"
                )
            max_steps = settings.steps if stop is not None else ARC_LENGTH_STEPS * settings.steps
            return follow_arc_length(
                system,
                solver,
                controller,
                record,
                max_steps,
                u0,
                timer,
                stop,
                self._describe_load,
            )
        options: dict[str, Any] = {
            "first_guess": first_guess,
            "first_stop": None if first_guess is None else first_guess.stop,
            "describe_load": self._describe_load,
            "stability": system.encloses_volume,
        }
        if stop is not None:
            return follow_load_path_to(
                system, solver, controller, stop, record, u0, timer, **options
            )
        follow_load_path(
            system,
            solver,
            controller,
            u0=u0,
            on_step=record,
            timer=timer,
            resume=resume,
            **options,
        )
        return PathEnd("converged to load factor 1")

    def _volume_constraints(
        self, system: DiscreteSystem, settings: SolverSettings, what: str
    ) -> Callable[[float], tuple[EnclosedVolume, GasEnergy | VolumeLagrangian]]:
        """The equation of each path parameter t of volume control or a gas load
        (``wrinkle.solvers.control``): the volume to enclose."""
        initial = system.reference_volume
        gas = self.gas
        if gas is not None:
            if gas.p0 is not None and not initial > 0:
                raise ValueError(
                    f"{what}: 'p0' needs a membrane that encloses a positive volume in its "
                    f"reference state (it encloses {initial:.3g}); give 'amount' instead"
                )
            reference = max(initial, 0.0)

            def gas_volume(t: float) -> tuple[EnclosedVolume, GasEnergy]:
                at_ambient = gas.volume(t, reference, 0.0)[0]
                constraint = EnclosedVolume(
                    system,
                    lambda mu: gas.volume(t, reference, mu),
                    max(abs(initial), at_ambient),
                    least_mu=-gas.ambient,
                )
                return constraint, GasEnergy(system, gas, t, reference)

            return gas_volume
        if settings.volume is not None:
            final = float(settings.volume)
        else:
            if initial == 0.0:
                raise ValueError(
                    "solver volume_ratio: the membrane encloses no volume in its reference "
                    "state (a flat sheet); give an absolute volume = V instead"
                )
            final = float(settings.volume_ratio or 1.0) * initial
        scale = max(abs(initial), abs(final))
        values = np.unique(self.pressure[self.pressure != 0])
        if values.size != 1:
            raise ValueError(
                f"{what}: the pressure loads must have one value (the unknown pressure is "
                f"their common factor), got {values.size} different values"
            )
        pressure = float(values[0])

        def volume_at(t: float) -> tuple[EnclosedVolume, VolumeLagrangian]:
            target = initial + t * (final - initial)
            constraint = EnclosedVolume(system, lambda mu: (target, 0.0), scale)
            return constraint, VolumeLagrangian(pressure, target)

        return volume_at

    def solve(
        self,
        settings: SolverSettings | None = None,
        *,
        u0: np.ndarray | None = None,
        on_step: Callable[[StepResult], None] | None = None,
        coarse: Sequence[Model] | None = None,
        probes: Mapping[str, np.ndarray] | None = None,
        resume: Resume | None = None,
        start: Results | StepStart | None = None,
        loads: Sequence[str] | None = None,
        supports: Sequence[str] | None = None,
        **options: Any,
    ) -> Results:
        """Proportional stepping of loads and prescribed displacements from 0 to 1, or one
        analysis step of a staged analysis.

        settings: ``SolverSettings`` (default: its defaults); options: any of its fields,
        overriding it (``steps=5``, ``method="restricted-step"``, ``tolerance=1e-8``, ...).
        The increments follow the step controller (``wrinkle.solvers.stepping``): steps
        equal increments are the aim, a failed step is cut back (down to ``min_step``) and the
        increment grows again after easy steps; each step starts from the extrapolation of the
        last two converged states (u0 being the state at load factor 0) or, if it moves
        supports, from the tangent prediction, where that is closer to balance.
        ``on_step(step_result)`` is called after each converged step. coarse: models of
        coarser meshes of the same reference surface, coarsest first, each with fewer
        elements than the next and the last fewer than this model's (nested by refinement or
        not: ``wrinkle.sequencing.level_transfer``), from which the first step starts: used
        by ``nested=True`` (which needs them) and ``nested="auto"`` (the default), from the
        reference state only (u0 None). probes:
        {name: node indices} watched, with every displacement and the reactions, by the
        accuracy stop (``convergence="accuracy"``) on the finer levels of a nested first
        step. resume: continue the path from its last converged state instead
        (``wrinkle.solvers.stepping.Resume``, load control only; the results hold the new
        steps).

        Analysis steps: ``start``, the results of the step before (or a ``StepStart``), and
        ``loads`` and ``supports``, the labels of the loads and supports that grow in this
        step, from their values at the start to their values in the model now (None for
        both: all of them); the others keep their values at the start (zero from the
        reference state), and the path starts from the displacement there. The load factor
        of the results runs from 0 to 1 over the step, whose number (``analysis_step``) is
        the start's plus one. Not with volume control, a gas load or a nested start.

        Raises
        ConvergenceError, with the converged steps in its ``results`` attribute, if a step
        cannot be solved; ValueError for a bad setting, unrestrained rigid-body motion, a
        coarse model not coarser than the next or off its surface, or an unknown label.
        """
        settings = (settings or SolverSettings()).replace(**options)
        staged = start is not None or loads is not None or supports is not None
        if staged and (self.gas is not None or settings.control == "volume"):
            raise ValueError(
                "analysis steps: a gas load or control = 'volume' is solved in one "
                "proportional path (without [[step]], start, loads or supports)"
            )
        if staged and settings.nested is True:
            raise ValueError("analysis steps: nested = true is for one proportional path only")
        if settings.convergence == "accuracy" and not coarse:
            raise ValueError(
                "convergence = 'accuracy' needs the models of the coarser meshes (coarse=...): "
                "the discretisation error is estimated from them"
            )
        if settings.nested is True and not coarse:
            raise ValueError(
                "nested needs the models of the coarser meshes (coarse=...); a case file makes "
                "them from [mesh] refine or [mesh] levels"
            )
        self.check_supports()
        system = self.discretise()
        obstacle = self.elimination_obstacle()
        if settings.elimination and obstacle is not None:
            raise ValueError(f"solver elimination = true: {obstacle}")
        system.check_resolvable()
        if isinstance(start, Results):
            start = start.step_start()
        if start is not None and u0 is not None:
            raise ValueError("give either u0 or start (whose displacement the step starts from)")
        end = self.load_state(loads, supports, start)
        if staged:
            initial = (
                Loading.total([], self.n_dofs, self.mesh.n_elements)
                if start is None
                else start.state.loading(self.mesh.n_elements)
            )
            system = system.along(
                initial,
                self._start_prescribed(start),
                end.loading(self.mesh.n_elements),
                end.prescribed,
            )
            if start is not None:
                u0 = np.asarray(start.displacement, dtype=float).copy()
        step_number = 1 if start is None else start.analysis_step + 1
        results = Results(self, system, step_number, end)
        first_guess = None
        if coarse and settings.nested is not False and u0 is None and resume is None and not staged:
            first_guess = NestedStart(coarse, self, settings, results.stopwatch, probes)

        pressure_unknown = self.gas is not None or settings.control == "volume"

        def record(load_factor: float, u: np.ndarray, solved: SolverResult) -> None:
            # under volume control and gas loads the pressure factor is the solve's unknown
            factor = getattr(solved, "mu", load_factor) if pressure_unknown else load_factor
            step = results.append(load_factor, u, solved, pressure_factor=factor)
            if on_step is not None:
                on_step(step)

        solver = settings.solver()
        try:
            with kept_memory():  # the freed arrays' pages kept from step to step
                results.end = self._follow(
                    system, settings, solver, u0, record, results, first_guess, probes, resume
                )
        except ConvergenceError as error:
            error.results = results
            raise
        finally:
            solver.release()
        return results
