"""Form finding: the shape in which a membrane's prestress and its cables' forces balance
(issue 21, item 3).

Given the boundary (the supports, with their prescribed displacements moving it), the
prestress N0 of each material (force per current length, in the material frame) and the
prestress force T of each cable, find the surface x on which the Cauchy stress is N0 and
the cable forces are T in equilibrium:

    R(x) = sum_e int_a N0 : grad_x (delta x) da + sum_c T d l_c / dx = 0   (free components).

For an isotropic N0 = n I the membrane part is n dA/dx, so the surface is a minimal surface
(a soap film) with cable edges of constant force. R is the derivative of a function whose
tangential directions are flat (the nodes may slide in the surface without changing it), so
Newton on R is singular. The updated reference strategy (Bletzinger & Ramm 1999) fixes this
by writing the same stress as a second Piola-Kirchhoff stress on a reference, the shape of
the previous iteration x_k, and taking the new shape as the balance of that stress:

    sum_e A_e (grad_k x) N0 (grad_k dx) + sum_c (T / L_c,k) (x_b - x_a).(dx_b - dx_a) = 0

(grad_k the gradient on the triangle of x_k, A_e its area, L_c,k the segment's length). This
is the strategy's homotopy factor lambda = 0. It is linear in x, one scalar Laplace-type
matrix L_k shared by the three coordinates (the prestress acts on each alike), symmetric and
positive definite once the boundary holds each coordinate somewhere. When x_(k+1) = x_k,
grad_k is the gradient on x itself, S = N0 is the Cauchy stress of x and L_k x = R(x): a
fixed point is the form sought. The mesh's tangential motion is fixed by the previous shape
at each iteration, so the elements keep their proportions; the membrane's and the cables'
elastic stiffness never enter, and the found shape does not depend on them.

Each iteration is one factorisation of L_k (per set of held coordinates) and three solves.
The shape converges geometrically, by about half each iteration whatever the mesh. The
nodes' positions within the surface converge far more slowly (a discrete surface's nodes
have almost no preference where they sit in it), and they are not part of the form. So it
stops when the largest move of a node that changes the surface (``shape_part``: along the
node's normal, or across its cable) in one iteration is at most ``tolerance`` times the
size of the form (its bounding box's diagonal). ``form_residual`` reports what is left:
the shape's residual and the whole residual (the mesh's sliding included), relative to the
largest support reaction; an analysis of the found form starts there, and its first
Newton iterations take up the sliding part with the elastic stiffness.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import depth_first_order

from wrinkle.kinematics import reference_normals
from wrinkle.loads import boundary_edges
from wrinkle.mesh import Mesh
from wrinkle.solvers.linear import make_linear_solver

if TYPE_CHECKING:
    from wrinkle.model import Model

__all__ = [
    "FORM_TOLERANCE",
    "MAX_FORM_ITERATIONS",
    "FormFinding",
    "FormFindingError",
    "find_form",
    "form_residual",
]

logger = logging.getLogger(__name__)

FORM_TOLERANCE = 1e-6  # the largest change of the shape in an iteration, relative to its size
MAX_FORM_ITERATIONS = 200


class FormFindingError(RuntimeError):
    """Form finding did not converge; ``form`` holds the last shape and its history."""

    def __init__(self, message: str, form: FormFinding):
        super().__init__(message)
        self.form = form


@dataclass
class FormFinding:
    """The found form. nodes: (n_nodes, 3) the shape; mesh: the case's mesh with these
    nodes (the same elements, node sets and element sets); iterations: the outer iterations
    (factorisations of L_k); residuals: the relative residual of each iterate (module
    docstring), the last one the found form's; moves: the largest nodal move of each
    iteration (length); converged: residual <= tolerance."""

    nodes: np.ndarray
    mesh: Mesh
    iterations: int
    residuals: list[float] = field(default_factory=list)
    moves: list[float] = field(default_factory=list)
    sliding: list[float] = field(default_factory=list)
    converged: bool = False

    @property
    def residual(self) -> float:
        return self.residuals[-1] if self.residuals else float("inf")


def _scalar_operator(model: Model, nodes: np.ndarray) -> sp.csr_matrix:
    """L_k (n_nodes, n_nodes) on the shape ``nodes`` (module docstring): per triangle
    A (G N0 G^T) with G (3, 2) the shape-function gradients in its material frame, per cable
    segment T / L [[1, -1], [-1, 1]], assembled through the mesh's node-pair pattern."""
    geometry = model.geometry_on(nodes)
    prestress = model.element_prestress()  # (n, 2, 2), material frame
    G = geometry.shape_gradient
    element = geometry.area[:, None, None] * np.einsum("nai,nij,nbj->nab", G, prestress, G)
    pairs = values = None
    if model.cables:
        edges = np.concatenate([cable.edges for cable in model.cables])
        force = np.concatenate(
            [np.full(len(cable.edges), cable.prestress) for cable in model.cables]
        )
        length = np.linalg.norm(nodes[edges[:, 1]] - nodes[edges[:, 0]], axis=1)
        density = force / length
        pairs = np.concatenate([edges, edges[:, ::-1], edges[:, [0, 0]], edges[:, [1, 1]]])
        values = np.concatenate([-density, -density, density, density])
    return model.pattern().node_matrix(element, pairs, values)


def form_residual(model: Model, nodes: np.ndarray) -> tuple[float, float, np.ndarray]:
    """The residuals of the shape ``nodes`` (n_nodes, 3) as a form of ``model``, relative to
    the largest support reaction: the shape's (``shape_part`` of the free nodes' forces) and
    the whole (the mesh's: what also slides nodes within the surface), and the nodal forces
    L x (n_nodes, 3) of its prestress and cables."""
    forces = _scalar_operator(model, nodes) @ nodes
    held = model.constrained.reshape(-1, 3)
    free_force = np.where(held, 0.0, forces)
    reaction = max(float(np.abs(forces[held]).max(initial=0.0)), 1e-300)
    shape = shape_part(model, nodes, free_force)
    whole = np.linalg.norm(free_force, axis=1)
    return float(shape.max(initial=0.0)) / reaction, float(whole.max()) / reaction, forces


def shape_part(model: Model, nodes: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """The size (n_nodes,) of the part of nodal vectors (n_nodes, 3) (forces or moves) that
    changes the surface of the shape ``nodes``: along each node's normal (the area-weighted
    mean of its triangles' normals) and, at a node of a cable, everything but the part along
    the cable. The rest only slides nodes within the surface or along the cable."""
    normal = _node_normals(model.mesh.triangles, nodes)
    size = np.abs(np.sum(vectors * normal, axis=1))
    if model.cables:
        tangent = _cable_tangents(model, nodes)
        on_cable = np.any(tangent != 0.0, axis=1)
        across = vectors - np.sum(vectors * tangent, axis=1)[:, None] * tangent
        size = np.where(on_cable, np.linalg.norm(across, axis=1), size)
    return size


def _node_normals(triangles: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Unit normal of each node (n_nodes, 3): the sum of its triangles' area vectors."""
    X = nodes[triangles]
    area_vector = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    total = np.zeros_like(nodes)
    for k in range(3):
        np.add.at(total, triangles[:, k], area_vector)
    length = np.linalg.norm(total, axis=1)
    return total / np.maximum(length, 1e-300)[:, None]


def _cable_tangents(model: Model, nodes: np.ndarray) -> np.ndarray:
    """Unit tangent of the cables at each node (n_nodes, 3), the sum of the directions of
    its segments (oriented along the cable); zero at a node on no cable, or at a corner
    where two cables meet (all of its force then counts)."""
    total = np.zeros_like(nodes)
    count = np.zeros(nodes.shape[0], dtype=np.int64)
    cables = np.zeros(nodes.shape[0], dtype=np.int64)
    for cable in model.cables:
        a, b = _oriented(cable.edges)
        d = nodes[b] - nodes[a]
        d /= np.linalg.norm(d, axis=1)[:, None]
        for end in (a, b):
            np.add.at(total, end, d)
            np.add.at(count, end, 1)
        cables[np.unique(cable.edges)] += 1
    length = np.linalg.norm(total, axis=1)
    smooth = (count == 2) & (cables == 1) & (length > 1e-12)
    return np.where(smooth[:, None], total / np.maximum(length, 1e-300)[:, None], 0.0)


def _oriented(edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The segments of one cable path as (start, end) node arrays, each segment turned to
    run the same way along the path (the edges come sorted by node, not along it): the
    depth-first order of the path's graph from one of its ends (any node of a loop)."""
    edges = np.asarray(edges, dtype=np.int64)
    nodes, local = np.unique(edges, return_inverse=True)
    local = local.reshape(edges.shape)
    graph = sp.coo_matrix(
        (np.ones(len(edges)), (local[:, 0], local[:, 1])), shape=(nodes.size, nodes.size)
    )
    degree = np.bincount(local.ravel(), minlength=nodes.size)
    if degree.max() > 2:  # a branched cable: as given (a node whose two segments disagree
        return edges[:, 0], edges[:, 1]  # gets no tangent, and all its force counts)
    ends = np.flatnonzero(degree == 1)
    start = int(ends[0]) if ends.size else 0
    order = depth_first_order(graph, start, directed=False, return_predecessors=False)
    path = nodes[order]
    if not ends.size:  # a loop: back to the start
        path = np.append(path, path[0])
    return path[:-1], path[1:]


def find_form(
    model: Model,
    *,
    tolerance: float = FORM_TOLERANCE,
    max_iterations: int = MAX_FORM_ITERATIONS,
    linear_solver: str = "auto",
    on_iteration: Callable[[int, float], None] | None = None,
) -> FormFinding:
    """The form of ``model`` (module docstring): its mesh is the first reference, its
    supports' prescribed displacements (at load factor 1) move the boundary there, its
    materials' prestress (``Prestressed``, on every element) and its cables' prestress
    forces (> 0) are the stresses of the form; its loads and elastic stiffness are not used.
    on_iteration(k, residual) is called after each iteration. ValueError for a model that
    cannot be form-found (``check_form_finding``); FormFindingError (with the last shape) if
    the shape still moves by more than ``tolerance`` of its size after ``max_iterations``,
    or if it collapses (a triangle of zero area or folded over: no form exists).
    linear_solver: the back-end of ``wrinkle.solvers.linear`` for L_k."""
    check_form_finding(model)
    mesh = model.mesh
    held = model.constrained.reshape(-1, 3)
    target = mesh.nodes + model.prescribed.reshape(-1, 3)
    x = mesh.nodes.copy()
    x[held] = target[held]
    reference = mesh.nodes  # the first metric: the case's own mesh
    masks = {tuple(column) for column in held.T}
    form = FormFinding(x, mesh, 0)
    for iteration in range(1, max_iterations + 1):
        L = _scalar_operator(model, reference)
        new = x.copy()
        for mask in masks:
            held_c = np.array(mask)
            components = np.array([c for c in range(3) if tuple(held[:, c]) == mask])
            free = np.flatnonzero(~held_c)
            fixed = np.flatnonzero(held_c)
            A = L[free][:, free].tocsr()
            A.sort_indices()
            rhs = -np.asarray(L[free][:, fixed] @ target[np.ix_(fixed, components)])
            solver = make_linear_solver(linear_solver, free.size, one_off=True)
            try:
                solve = solver.factorise(A, True)
                if solve is None:
                    raise ValueError(
                        "form finding: the prestress operator is singular (a node no prestressed "
                        "element or cable holds)"
                    )
                for column, c in enumerate(components):
                    new[free, c] = solve(np.ascontiguousarray(rhs[:, column]))
            finally:
                solver.release()
        move = float(shape_part(model, x, new - x).max(initial=0.0))
        try:
            _check_not_folded(mesh.triangles, reference, new)
            residual, sliding, _ = form_residual(model, new)
        except ValueError as error:  # a triangle of the new shape has collapsed
            raise FormFindingError(
                f"form finding: the shape collapsed in iteration {iteration} ({error}): "
                "no form exists for these prestresses and this boundary (a cable's force "
                "T and the prestress n give an arc of radius T / n, which must span the "
                "cable's chord)",
                form,
            ) from None
        x = reference = new
        form.residuals.append(residual)
        form.sliding.append(sliding)
        form.moves.append(move)
        form.iterations = iteration
        logger.info(
            "form finding iteration %3d: shape moved %.3e, shape residual %.3e, residual %.3e",
            iteration,
            move,
            residual,
            sliding,
        )
        if on_iteration is not None:
            on_iteration(iteration, residual)
        if not np.all(np.isfinite(x)):
            break
        size = float(np.linalg.norm(x.max(axis=0) - x.min(axis=0)))
        if move <= tolerance * size:
            form.converged = True
            break
    form.nodes = x
    form.mesh = replace(mesh, nodes=x) if np.all(np.isfinite(x)) else mesh
    if not form.converged:
        raise FormFindingError(
            f"form finding did not converge: the shape still moved {form.moves[-1]:.3g} in "
            f"iteration {form.iterations} (tolerance {tolerance:g} of its size)",
            form,
        )
    return form


def _check_not_folded(triangles: np.ndarray, before: np.ndarray, after: np.ndarray) -> None:
    """ValueError naming the first triangle whose normal turned by more than 90 degrees
    between two shapes (n_nodes, 3): it has folded over."""
    turned = np.einsum(
        "ni,ni->n", reference_normals(before, triangles)[3], reference_normals(after, triangles)[3]
    )
    folded = np.flatnonzero(~(turned > 0.0))
    if folded.size:
        raise ValueError(f"element {int(folded[0])} has folded over")


def check_form_finding(model: Model) -> None:
    """ValueError, in one line, for a model that has no form: no supports; an element whose
    material has no prestress, or a prestress that is not positive definite; a cable
    without a prestress force; a boundary edge that is neither on a cable nor held across
    (all components of both nodes, or one that both hold along which the edge's in-plane
    normal mostly points, as in a symmetry plane): a free edge cannot carry a prestress,
    it would shrink without end."""
    if not np.any(model.constrained):
        raise ValueError("form finding needs supports: they give the boundary of the form")
    prestress = model.element_prestress()
    smallest = np.linalg.eigvalsh(prestress)[:, 0]
    weak = np.flatnonzero(~(smallest > 0))
    if weak.size:
        raise ValueError(
            f"form finding needs a positive definite prestress on every element; element "
            f"{int(weak[0])} has {prestress[weak[0]].tolist()} (give [material] prestress)"
        )
    for cable in model.cables:
        if not cable.prestress > 0:
            raise ValueError(
                f"form finding needs a prestress force on every cable: cable {cable.label!r} "
                "has none (give [[cable]] prestress)"
            )
    triples = boundary_edges(model.mesh.triangles)[0]
    edges = triples[:, :2]
    if edges.size:
        n = model.mesh.n_nodes
        on_cable = np.zeros(0, dtype=np.int64)
        if model.cables:
            cable_edges = np.sort(np.concatenate([c.edges for c in model.cables]), axis=1)
            on_cable = cable_edges[:, 0] * n + cable_edges[:, 1]
        keys = np.sort(edges, axis=1)
        cabled = np.isin(keys[:, 0] * n + keys[:, 1], on_cable)
        # held across the edge: a component that both nodes hold, along which the edge's
        # in-plane normal m = e x N mostly points (a symmetry plane); or all components
        X = model.mesh.nodes[triples]
        along = X[:, 1] - X[:, 0]
        normal = np.cross(along, X[:, 2] - X[:, 0])
        across = np.cross(along, normal)
        across /= np.linalg.norm(across, axis=1)[:, None]
        held = model.constrained.reshape(-1, 3)
        both = held[edges[:, 0]] & held[edges[:, 1]]
        secured = np.all(both, axis=1) | np.any(both & (np.abs(across) > 0.5), axis=1)
        free = np.flatnonzero(~cabled & ~secured)
        if free.size:
            a, b = edges[free[0]]
            raise ValueError(
                f"form finding: the boundary edge between nodes {int(a)} and {int(b)} is "
                f"neither held nor on a cable ({free.size} such edge(s)); a free edge cannot "
                "carry the prestress: give it a [[cable]] or a [[support]]"
            )
