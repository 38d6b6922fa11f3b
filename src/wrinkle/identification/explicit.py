"""dR/dp at fixed displacements from the element states, without re-solving the wrinkling
conditions (``sensitivity.force_derivatives``' fast path).

R(u, p) = f*(u, p) - f(u, p) splits into the membrane's internal forces, which cost a
solve of the wrinkling conditions in every wrinkled element, and the rest (bending, cables,
dead and follower loads), which cost little. For a parameter p whose systems at p +- h have
the same mesh, element groups, areas and normals as the system at p, the membrane part is

    dR_m/dp = sum_e A0 F dN/dp grad psi_k        (the nodal forces of ``wrinkle.element``)

with dN/dp the derivative of each element's relaxed stress at fixed C, made of two terms:

- the law's parameters (``Wrinkling.parameter_derivative``: the plain law's central
  difference at C, or at the wrinkled C' = C + b w (x) w projected on the wrinkling
  conditions by the implicit function theorem);
- a turn of the material frame by delta per unit of p (the fibre angle or direction):
  with the frame turned by delta, F -> F Q, grad psi -> Q^T grad psi, C -> Q^T C Q, and the
  forces are those of Q N(Q^T C Q) Q^T in the old frame; at delta = 0, with A = dQ/ddelta =
  [[0, -1], [1, 0]],

      dN/ddelta = A N - N A + D (C A - A C) / 2 = (-2 N12, 2 N12, N11 - N22)
                  + D (C12, -C12, C22 - C11)        (Voigt 11, 22, 12; D the tangent),

  zero for an isotropic law.

The rest is differenced as it is, (R_o(u, p + h) - R_o(u, p - h)) / (2 h). Both are exact to
h^2, as the central difference of the whole R is, and take no Newton iteration.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import fields
from typing import Any

import numpy as np

from wrinkle.element import ElementResult, nodal_forces
from wrinkle.kinematics import right_cauchy_green
from wrinkle.system import DiscreteSystem
from wrinkle.wrinkling import WrinklingResponse

__all__ = ["ElementStates", "force_derivatives", "frame_turn"]

# frames and shape gradients that agree to this fraction of their size are the same
SAME = 1e-12


class ElementStates:
    """The membrane elements of a system at displacements u (n_dofs,), evaluated once for
    the derivatives of any number of parameters: per group, F (m, 3, 2), C (m, 2, 2) and the
    wrinkling response with its tangent. elements: the system's ``ElementResult`` at u with
    the tangent, if the caller has it (then nothing is evaluated again)."""

    def __init__(
        self, system: DiscreteSystem, u: np.ndarray, elements: ElementResult | None = None
    ):
        self.system = system
        self.u = u
        if elements is None or elements.response.tangent is None:
            elements = system.evaluate_elements(u, stiffness=True, stiffness_sink=_discard)
        whole = len(system.groups) == 1
        self.groups = []
        for rows, _ in system.groups:
            F = elements.deformation_gradient if whole else elements.deformation_gradient[rows]
            response = elements.response if whole else _rows(elements.response, rows)
            self.groups.append((F, right_cauchy_green(F), response))


def _discard(_elements: np.ndarray | slice, _K: np.ndarray) -> None:
    """A stiffness sink that keeps nothing (only the elements' tangents are wanted)."""


def _rows(response: WrinklingResponse, rows: np.ndarray) -> WrinklingResponse:
    """The response of some elements (indices), in that order."""
    values: dict[str, Any] = {}
    for f in fields(response):
        array = getattr(response, f.name)
        values[f.name] = None if array is None else array[rows]
    return WrinklingResponse(**values)


def frame_turn(system: DiscreteSystem, other: DiscreteSystem) -> np.ndarray | None:
    """The angle (radians, about each element's normal) by which ``other``'s material frames
    are turned from ``system``'s, (n_elements,), where the two have the same mesh, element
    groups, areas, normals and (turned) shape gradients; None where they differ otherwise."""
    if other.n_dofs != system.n_dofs or len(other.groups) != len(system.groups):
        return None
    mesh, others = system.mesh, other.mesh
    if not (
        np.array_equal(mesh.triangles, others.triangles)
        and np.array_equal(mesh.nodes, others.nodes)
        and np.array_equal(system.constrained, other.constrained)
        and np.array_equal(system.prescribed, other.prescribed)
    ):
        return None
    for (elements, _), (other_elements, _) in zip(system.groups, other.groups, strict=True):
        if not np.array_equal(elements, other_elements):
            return None
    g, h = system.geometry, other.geometry
    if not (np.array_equal(g.area, h.area) and np.array_equal(g.normal, h.normal)):
        return None
    a1, b1 = g.frame[:, 0], h.frame[:, 0]
    sine = np.einsum("ij,ij->i", np.cross(a1, b1), g.normal)
    turn = np.arctan2(sine, np.einsum("ij,ij->i", a1, b1))
    c, s = np.cos(turn), np.sin(turn)
    # grad psi in the turned frame: Q^T grad psi, Q = [[c, -s], [s, c]]
    sg = g.shape_gradient
    turned = np.stack(
        [
            c[:, None] * sg[..., 0] + s[:, None] * sg[..., 1],
            c[:, None] * sg[..., 1] - s[:, None] * sg[..., 0],
        ],
        axis=-1,
    )
    if np.max(np.abs(turned - h.shape_gradient)) > SAME * max(np.max(np.abs(sg)), 1e-300):
        return None
    return turn


def _turn_derivative(C: np.ndarray, response: WrinklingResponse) -> np.ndarray:
    """dN/ddelta of the relaxed stress for a turn delta of the material frame (module
    docstring), (m, 2, 2); C (m, 2, 2), the response with its tangent."""
    N, D = response.stress, response.tangent
    assert D is not None
    dE = (C[:, 0, 1], -C[:, 0, 1], C[:, 1, 1] - C[:, 0, 0])
    DdE = [D[:, i, 0] * dE[0] + D[:, i, 1] * dE[1] + D[:, i, 2] * dE[2] for i in range(3)]
    out = np.empty_like(C)
    out[:, 0, 0] = DdE[0] - 2.0 * N[:, 0, 1]
    out[:, 1, 1] = DdE[1] + 2.0 * N[:, 0, 1]
    out[:, 0, 1] = out[:, 1, 0] = DdE[2] + N[:, 0, 0] - N[:, 1, 1]
    return out


def _other_forces(system: DiscreteSystem, u: np.ndarray, load_factor: float) -> np.ndarray:
    """R less the membrane's internal forces at u: bending and cables minus the dead and
    follower loads, (n_dofs,)."""
    forces = np.zeros(system.n_dofs)
    system.add_bending(u, forces, None)
    system.add_cables(u, forces, None)
    forces -= system.forces_at(load_factor)
    if system.has_follower_loads:
        forces -= system.follower_forces(u, load_factor, stiffness=False)[0]
    return forces


def _derivative(
    states: ElementStates,
    load_factor: float,
    plus: DiscreteSystem,
    minus: DiscreteSystem,
    step: float,
    rate: np.ndarray,
) -> np.ndarray:
    """dR/dp (n_dofs,) for the systems made with p + step and p - step, whose frames turn
    by ``rate`` radians per unit of p, (n_elements,) (module docstring)."""
    system, u = states.system, states.u
    forces = np.empty((system.mesh.n_elements, 9))
    for (elements, group), (F, C, response), (_, up), (_, down) in zip(
        system.groups, states.groups, plus.groups, minus.groups, strict=True
    ):
        dN = group.material.parameter_derivative(
            C, response, up.material.material, down.material.material, step
        )
        turning = rate[elements]
        if np.any(turning != 0.0):
            dN += turning[:, None, None] * _turn_derivative(C, response)
        g = group.geometry
        forces[elements] = nodal_forces(g.area, F, g.shape_gradient, dN, np.empty((F.shape[0], 9)))
    others = _other_forces(plus, u, load_factor) - _other_forces(minus, u, load_factor)
    return system.pattern.assemble_vector(forces) + others / (2.0 * step)


def force_derivatives(
    system: DiscreteSystem,
    u: np.ndarray,
    load_factor: float,
    perturbed: Sequence[tuple[DiscreteSystem, DiscreteSystem, float]],
    elements: ElementResult | None = None,
) -> list[np.ndarray | None]:
    """dR/dp at displacements u (n_dofs,) and ``load_factor`` for each (plus, minus, step)
    of ``perturbed``, the systems made with a parameter at p + step and p - step, (n_dofs,)
    each (module docstring); None for a parameter whose systems differ from ``system`` in
    more than their materials, frames and loads (the caller then differences the whole R).
    The elements at u are evaluated once, if some parameter takes this path and they are
    not given (``elements``: ``ElementStates``)."""
    states: ElementStates | None = None
    out: list[np.ndarray | None] = []
    for plus, minus, step in perturbed:
        up, down = frame_turn(system, plus), frame_turn(system, minus)
        if up is None or down is None:
            out.append(None)
            continue
        if states is None:
            states = ElementStates(system, u, elements)
        out.append(_derivative(states, load_factor, plus, minus, step, (up - down) / (2.0 * step)))
    return out
