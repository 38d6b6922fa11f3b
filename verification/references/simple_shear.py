"""Simple shear of a membrane at small strain: the tension-field solution and the exact
homogeneous one.

Mansfield (The Bending and Stretching of Plates, 2nd ed. 1989, ch. 9) and Wong & Pellegrino
(J. Mech. Mater. Struct. 1, 2006, 3-25). All edges follow x = X + gamma Y, y = Y. At small
strain the strain is eps_xx = eps_yy = 0, eps_xy = gamma / 2, with principal strains
+-gamma/2 along the diagonals (45 and 135 degrees). Taut, the stress would be
N_1,2 = E t (eps_1 + nu eps_2) / (1 - nu^2) = +-E t gamma / (2 (1 + nu)): the minor one is
compressive, so the sheet wrinkles. In the wrinkled state the stress is uniaxial along the
major principal strain direction (for an isotropic material the wrinkle direction is the
minor principal strain direction), and the tension-field strain along it is the total strain
eps_1 = gamma / 2, so

    N1 = E t gamma / 2,    N_xx = N_yy = N_xy = N1 cos 45 sin 45 = E t gamma / 4,

with the tension at 45 degrees to x. The Green-Lagrange (finite-strain) homogeneous solution
differs from these by O(gamma): ``exact_homogeneous`` computes it independently by minimising
the relaxed energy at one material point (``verification.references.relax``).
"""

from __future__ import annotations

import numpy as np

from verification.references.relaxed_energy import relax

__all__ = ["exact_homogeneous", "tension_field"]


def tension_field(E: float, thickness: float, gamma: float) -> dict[str, float]:
    """Small-strain tension-field solution of simple shear gamma: N1, N_xy (force per length)
    and the tension angle (degrees from x)."""
    return {"N1": E * thickness * gamma / 2.0, "N_xy": E * thickness * gamma / 4.0, "angle": 45.0}


def exact_homogeneous(material, gamma: float) -> dict[str, float]:
    """Exact (finite-strain) homogeneous solution of simple shear F = [[1, gamma], [0, 1]] from
    the relaxed energy: major principal Cauchy stress resultant N1 and shear N_xy (per unit
    current length; det F = 1) and the tension angle (degrees in (0, 180))."""
    F = np.array([[1.0, gamma], [0.0, 1.0]])
    state = relax(material, F.T @ F)
    cauchy = F @ state.stress @ F.T / np.linalg.det(F)
    values, vectors = np.linalg.eigh(cauchy)
    angle = np.degrees(np.arctan2(vectors[1, 1], vectors[0, 1])) % 180.0
    return {
        "N1": float(values[1]),
        "N_xy": float(cauchy[0, 1]),
        "angle": float(angle),
        "state": state.state,
    }
