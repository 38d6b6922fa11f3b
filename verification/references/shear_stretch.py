"""Analytic (homogeneous) solution of the paper's shear-and-stretch test (docs/method.md section 8).

The square 0 <= X, Y <= L is sheared and then stretched while the shear is held:

    x = X + gamma Y,    y = (1 + v/L) Y,

with the material fibre along X (so the material frame is the (X, Y) frame). The deformation is
homogeneous, F = [[1, gamma], [0, 1 + v/L]], and so is the relaxed stress N (from ``relax``,
independent of the element's wrinkling routine). The force on the top edge Y = L is the first
Piola-Kirchhoff traction integrated over the reference edge:

    (F1, F2) = L * P e_Y,    P = F N,

F1 along the shear (x), F2 along the stretch (y); N and P are per unit reference length, so the
forces are in force units (consistent units).

Why the finite-element edge reactions equal ``L * P e_Y`` exactly. For a homogeneous state every
constant-strain triangle carries the same P, so the internal force of node l is
f_l = sum_e A0_e P grad(psi_l)|_e (docs/method.md section 2), interior nodes are in equilibrium
and the reaction of a boundary node is its internal force. Summing over the set T of top-edge nodes,
corners included, gives P times the integral over the square of grad(phi_T), phi_T = sum_{l in T}
psi_l, which by the divergence theorem is the boundary integral of phi_T n. phi_T is 1 on the top
edge, 0 on the bottom edge, and on each side edge it falls linearly from 1 at the top corner to 0
at the next node down. The left side (n = -e_X) and the right side (n = +e_X) therefore contribute
-h/2 e_X and +h/2 e_X, which cancel when the first element below the two top corners has the same
height h on both sides (true for the paper's regular 3x3 mesh); what remains is L e_Y from the top
edge. So the sum of the top-edge nodal reactions is exactly L P e_Y, whatever the mesh inside
(with unequal heights h_left, h_right it is off by P e_X (h_right - h_left)/2). Without the
corner nodes the sum would miss their reactions, which are not zero.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from verification.references.relaxed_energy import RelaxedState, relax
from wrinkle.materials.base import Material

__all__ = [
    "ShearStretchCurves",
    "deformation_gradient",
    "homogeneous_edge_forces",
    "shear_stretch_curves",
]


def deformation_gradient(gamma: float, v: float, length: float = 1.0) -> np.ndarray:
    """In-plane deformation gradient (2, 2) of x = X + gamma Y, y = (1 + v/L) Y.

    gamma: shear (dimensionless); v: stretching distance of the top edge (length);
    length: side L of the square (same length unit as v).
    """
    return np.array([[1.0, gamma], [0.0, 1.0 + v / length]])


def homogeneous_edge_forces(
    material: Material, gamma: float, v: float, length: float = 1.0
) -> tuple[float, float, RelaxedState]:
    """Analytic top-edge forces (F1, F2) of the shear-and-stretch test, and the relaxed state.

    F1, F2 are the x and y components of length * F N e_Y (force, consistent units), N the
    relaxed stress resultant (force per unit reference length) of C = F^T F in the material
    frame (fibre along X). The state tells whether the membrane is taut, wrinkled or slack.
    """
    F = deformation_gradient(gamma, v, length)
    state = relax(material, F.T @ F)
    force = length * (F @ state.stress)[:, 1]
    return float(force[0]), float(force[1]), state


@dataclass
class ShearStretchCurves:
    """Analytic curves F1(v), F2(v) of the shear-and-stretch test.

    v: (m,) stretching distances (length); F1, F2: (m,) top-edge forces along x and y (force);
    state: (m,) "taut", "wrinkled" or "slack"; wrinkle_angle: (m,) radians in the material
    frame, NaN where not wrinkled.
    """

    v: np.ndarray
    F1: np.ndarray
    F2: np.ndarray
    state: np.ndarray
    wrinkle_angle: np.ndarray


def shear_stretch_curves(
    material: Material, gamma: float, v_values: np.ndarray, length: float = 1.0
) -> ShearStretchCurves:
    """F1 and F2 against v (as in the paper's figures 6 and 7) for one material and shear."""
    v = np.asarray(v_values, dtype=float).ravel()
    F1, F2 = np.empty_like(v), np.empty_like(v)
    states, angles = [], np.full_like(v, np.nan)
    for i, vi in enumerate(v):
        F1[i], F2[i], state = homogeneous_edge_forces(material, gamma, vi, length)
        states.append(state.state)
        if state.wrinkle_angle is not None:
            angles[i] = state.wrinkle_angle
    return ShearStretchCurves(v, F1, F2, np.array(states), angles)
