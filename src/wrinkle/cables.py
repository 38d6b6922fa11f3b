"""Tension-only cables: two-node elements along mesh edges, with an axial stiffness and a
prestress force, slack in compression, for large displacements.

A cable segment from node a to node b of reference length L0 and current length
l = |x_b - x_a| carries the axial force

    N(l) = max(0, N0 + EA (l - L0) / L0) = (EA / L0) max(0, l - l_s),  l_s = L0 (1 - N0 / EA),

(N0 the prestress force at the reference length, EA the axial stiffness, l_s the slack
length), the derivative of the energy W(l) = (EA / 2 L0) max(0, l - l_s)^2. With the unit
vector n = (x_b - x_a) / l the nodal forces are f_b = N n = -f_a, and the tangent of a taut
segment is the 6 x 6 matrix [[k, -k], [-k, k]] with

    k = (EA / L0) n n^T + (N / l) (I - n n^T)

(material and geometric parts); a slack segment (l <= l_s) has none. Everything is evaluated
for all segments at once.

Cables run along mesh edges: ``cable_edges`` finds the edges of the triangles whose two
nodes are both in a node selection (a selector such as "y == 0" or a gmsh line physical
group), and refuses a selection whose nodes do not form one connected path of such edges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

__all__ = ["Cable", "CableState", "Cables", "cable_edges"]


@dataclass(frozen=True)
class Cable:
    """One cable as defined (``Model.add_cables``): its label, its mesh edges (m, 2), axial
    stiffness EA (force), prestress N0 (force at the reference length) and mass per unit
    reference length (mass / length; 0 for a massless cable)."""

    label: str
    edges: np.ndarray
    EA: float
    prestress: float
    mass_per_length: float = 0.0


def cable_edges(triangles: np.ndarray, nodes: np.ndarray, n_nodes: int) -> np.ndarray:
    """The mesh edges (m, 2) whose two nodes are both in ``nodes`` (indices), each once,
    sorted. ValueError if there are none, if a selected node is on none of them, or if they
    do not form one connected set (a cable is one connected line of segments)."""
    nodes = np.unique(np.asarray(nodes, dtype=np.int64))
    selected = np.zeros(n_nodes, dtype=bool)
    selected[nodes] = True
    pairs = np.sort(triangles[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    pairs = np.unique(pairs[selected[pairs].all(axis=1)], axis=0)
    if pairs.size == 0:
        raise ValueError(
            f"the {nodes.size} selected node(s) share no element edge: a cable runs along "
            "mesh edges"
        )
    on_edge = np.zeros(n_nodes, dtype=bool)
    on_edge[pairs.ravel()] = True
    lonely = nodes[~on_edge[nodes]]
    if lonely.size:
        raise ValueError(
            f"node {int(lonely[0])} is selected but on no mesh edge to another selected node: "
            "the cable's nodes are not connected"
        )
    local = np.searchsorted(nodes, pairs)
    graph = sp.coo_matrix(
        (np.ones(len(pairs)), (local[:, 0], local[:, 1])), shape=(nodes.size, nodes.size)
    )
    count, _ = connected_components(graph, directed=False)
    if count > 1:
        raise ValueError(
            f"the selected nodes form {count} separate pieces along the mesh edges: the "
            "cable's nodes are not connected (give each piece its own [[cable]])"
        )
    return pairs


@dataclass(frozen=True)
class CableState:
    """The cables at one configuration: forces (n_dofs,) on the nodes (internal, like the
    membrane's), energy W (force x length), axial force N (m,) of each segment (force, >= 0),
    taut (m,) bool, and the tangent blocks (m, 6, 6) (None if not asked)."""

    forces: np.ndarray
    energy: float
    axial: np.ndarray
    taut: np.ndarray
    blocks: np.ndarray | None


@dataclass(frozen=True)
class Cables:
    """Cable segments of a model (module docstring). edges (m, 2) node pairs; length (m,)
    reference lengths L0 (> 0); stiffness (m,) EA (> 0, force); prestress (m,) N0 (>= 0,
    force); group (m,) index of each segment's cable in ``labels``; mass (m,) mass per unit
    reference length (None: massless)."""

    edges: np.ndarray
    length: np.ndarray
    stiffness: np.ndarray
    prestress: np.ndarray
    group: np.ndarray
    labels: tuple[str, ...]
    mass: np.ndarray | None = None

    @classmethod
    def of(cls, cables: list[Cable], nodes: np.ndarray) -> Cables:
        """The segments of the cables defined (``Cable``) on the reference nodes (n_nodes, 3)."""
        counts = [len(cable.edges) for cable in cables]
        edges = np.concatenate([cable.edges for cable in cables])
        return cls(
            edges,
            np.linalg.norm(nodes[edges[:, 1]] - nodes[edges[:, 0]], axis=1),
            np.repeat([cable.EA for cable in cables], counts),
            np.repeat([cable.prestress for cable in cables], counts),
            np.repeat(np.arange(len(cables)), counts),
            tuple(cable.label for cable in cables),
            np.repeat([cable.mass_per_length for cable in cables], counts),
        )

    @property
    def n_segments(self) -> int:
        return int(self.edges.shape[0])

    def state(self, x_nodes: np.ndarray, tangent: bool = True) -> CableState:
        """Forces, energy, axial forces, states and tangent at the current nodal coordinates
        x_nodes (n_nodes, 3) (module docstring)."""
        a, b = self.edges[:, 0], self.edges[:, 1]
        d = x_nodes[b] - x_nodes[a]
        current = np.linalg.norm(d, axis=1)
        if np.any(current <= 0.0):
            raise ValueError("a cable segment has collapsed to zero length")
        n = d / current[:, None]
        slack_length = self.length * (1.0 - self.prestress / self.stiffness)
        stretch = np.maximum(current - slack_length, 0.0)
        modulus = self.stiffness / self.length
        axial = modulus * stretch
        energy = float(0.5 * np.sum(modulus * stretch**2))
        segment = axial[:, None] * n
        dofs = (3 * self.edges[:, :, None] + np.arange(3)).reshape(-1, 6)
        values = np.concatenate([-segment, segment], axis=1)
        forces = np.bincount(dofs.ravel(), values.ravel(), minlength=x_nodes.size)
        taut = stretch > 0.0
        blocks = None
        if tangent:
            outer = n[:, :, None] * n[:, None, :]
            k = modulus[:, None, None] * outer + (axial / current)[:, None, None] * (
                np.eye(3) - outer
            )
            k[~taut] = 0.0
            blocks = np.zeros((self.n_segments, 6, 6))
            blocks[:, :3, :3] = blocks[:, 3:, 3:] = k
            blocks[:, :3, 3:] = blocks[:, 3:, :3] = -k
        return CableState(forces, energy, axial, taut, blocks)

    def mass_matrix(self, kind: str, n_dofs: int) -> sp.csr_matrix:
        """The cables' mass matrix (n_dofs, n_dofs), mass units, of the linear two-node
        segment with m = mass per length x L0: consistent (m / 6) [[2 I, I], [I, 2 I]], or
        lumped m / 2 I on each node ("consistent" or "lumped", as ``wrinkle.modes``)."""
        mass = np.zeros(self.n_segments) if self.mass is None else self.mass
        segment = mass * self.length
        if kind == "consistent":
            local = np.kron(np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0, np.eye(3))
        elif kind == "lumped":
            local = np.eye(6) / 2.0
        else:
            raise ValueError(f"unknown mass '{kind}'")
        dofs = (3 * self.edges[:, :, None] + np.arange(3)).reshape(-1, 6)
        rows = np.repeat(dofs, 6, axis=1).ravel()
        cols = np.tile(dofs, (1, 6)).ravel()
        values = (segment[:, None, None] * local).ravel()
        return sp.coo_matrix((values, (rows, cols)), shape=(n_dofs, n_dofs)).tocsr()

    def summary(self, axial: np.ndarray, taut: np.ndarray) -> dict[str, dict[str, float]]:
        """Per cable label: the smallest, largest and mean axial force of its segments
        (force) and the number of slack segments."""
        out = {}
        for index, label in enumerate(self.labels):
            mine = self.group == index
            forces = axial[mine]
            out[label] = {
                "min_force": float(forces.min()),
                "max_force": float(forces.max()),
                "mean_force": float(forces.mean()),
                "slack_segments": int(np.count_nonzero(~taut[mine])),
            }
        return out
