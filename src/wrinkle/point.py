"""Material-point API: the wrinkling response of one homogeneous in-plane deformation."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrinkle.materials.base import Material
from wrinkle.results import plane_quantities
from wrinkle.wrinkling import STATE_NAMES, Wrinkling


@dataclass
class PointResponse:
    """Response of one material point, material frame (axis 1 = fibre).

    state: "taut", "wrinkled" or "slack".
    stress: (2, 2) second Piola-Kirchhoff stress resultant N, force per unit reference length.
    tangent: (3, 3) consistent dN/dE, Voigt (11, 22, 12) with engineering shear.
    thickness: current thickness D.
    energy: relaxed strain energy per unit reference area.
    tension_direction, wrinkle_direction: (2,) reference unit vectors (zero where undefined).
    wrinkling_strain: beta of F' = (I + beta n1 (x) n1) F (Part II, eq. 12); 0 unless wrinkled.
    principal_stress: (2,) minor and major Cauchy stress resultants, force per current length.
    """

    state: str
    stress: np.ndarray
    tangent: np.ndarray
    thickness: float
    energy: float
    tension_direction: np.ndarray
    wrinkle_direction: np.ndarray
    wrinkling_strain: float
    principal_stress: np.ndarray


def material_response(material: Material | Wrinkling, F) -> PointResponse:
    """Wrinkling response of ``material`` to the in-plane deformation gradient F.

    F: (2, 2) in-plane deformation gradient, or (3, 2) with the images of the material axes as
    columns, in the material frame (axis 1 = fibre direction). The material is wrapped in
    ``Wrinkling`` unless it already is one.
    """
    F = np.asarray(F, dtype=float)
    if F.shape not in ((2, 2), (3, 2)):
        raise ValueError(f"material_response: F must be shaped (2, 2) or (3, 2), got {F.shape}")
    if not np.all(np.isfinite(F)):
        raise ValueError("material_response: F must be finite")
    C = (F.T @ F)[None]
    if not np.linalg.det(C[0]) > 0:
        raise ValueError("material_response: F is singular (the material point is collapsed)")
    wrinkling = material if isinstance(material, Wrinkling) else Wrinkling(material)
    r = wrinkling.response(C, tangent=True)
    q = plane_quantities(C, r)
    return PointResponse(
        state=STATE_NAMES[int(r.state[0])],
        stress=r.stress[0],
        tangent=r.tangent[0],
        thickness=float(r.thickness[0]),
        energy=float(r.energy[0]),
        tension_direction=q.tension_direction[0],
        wrinkle_direction=q.wrinkle_direction[0],
        wrinkling_strain=float(q.wrinkling_strain[0]),
        principal_stress=q.principal_stress[0],
    )
