r"""Inflated thin spherical membrane of incompressible Ogden rubber: the closed-form
pressure-stretch curve.

**The problem.** A spherical membrane of reference radius R and thickness T, of the
incompressible Ogden material W = sum_k mu_k / alpha_k (lambda_1^alpha_k + lambda_2^alpha_k +
lambda_3^alpha_k - 3) per unit reference volume (``wrinkle.materials.ogden``), inflated by an
internal pressure p, stays spherical with current radius r = lambda R: the principal stretches
are lambda, lambda in the plane and lambda^-2 across it.

**Energy principle.** The strain energy of the sphere is 4 pi R^2 T W(lambda) with
W(lambda) = sum_k mu_k / alpha_k (2 lambda^alpha_k + lambda^(-2 alpha_k) - 3), and the enclosed
volume V = 4/3 pi R^3 lambda^3, so p = dW_total / dV = T W'(lambda) / (R lambda^2):

    p(lambda) = (2 T / R) sum_k mu_k (lambda^(alpha_k - 3) - lambda^(-2 alpha_k - 3)).    (1)

One term with alpha = 2 is the neo-Hookean p = (2 mu T / R)(lambda^-1 - lambda^-7)
(``verification.references.sphere``, eq. (4)); the terms alpha = 2, -2 are Mooney-Rivlin's
(``verification.references.mooney_rivlin_sphere``). With Ogden's fit of Treloar's rubber
(``TRELOAR``) the pressure has a maximum and then stiffens again, through the alpha = 5 term.

Sources: R. W. Ogden, "Large deformation isotropic elasticity - on the correlation of theory
and experiment for incompressible rubberlike solids", Proc. R. Soc. Lond. A 326 (1972)
565-584 (the three-term fit of Treloar's data: mu = 0.63, 0.0012, -0.01 MPa, alpha = 1.3,
5.0, -2.0); the inflation of a spherical membrane of Ogden material: Ogden, Non-linear
Elastic Deformations, 1984, section 7.2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["TRELOAR", "OgdenSphere"]

# Ogden (1972): (mu_k in N/m^2, alpha_k), shear modulus sum mu_k alpha_k / 2 = 0.4225 MPa
TRELOAR = ((6.3e5, 1.3), (1.2e3, 5.0), (-1.0e4, -2.0))


@dataclass(frozen=True)
class OgdenSphere:
    """Thin spherical Ogden membrane under internal pressure (module docstring, eq. (1)).
    mu, alpha: the terms (force/area, dimensionless); thickness T and radius R > 0."""

    mu: tuple[float, ...]
    alpha: tuple[float, ...]
    thickness: float
    radius: float

    def __post_init__(self) -> None:
        if len(self.mu) != len(self.alpha) or not self.mu:
            raise ValueError("OgdenSphere: mu and alpha need the same, non-zero length")
        for name in ("thickness", "radius"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"OgdenSphere: {name} must be finite and > 0, got {value}")

    def pressure(self, stretch: ArrayLike) -> np.ndarray:
        """Eq. (1), force/area, shaped like ``stretch``."""
        lam = np.asarray(stretch, dtype=float)
        total = np.zeros_like(lam)
        for mu, alpha in zip(self.mu, self.alpha, strict=True):
            total = total + mu * (lam ** (alpha - 3.0) - lam ** (-2.0 * alpha - 3.0))
        return 2.0 * self.thickness / self.radius * total

    def energy(self, stretch: float) -> float:
        """The sphere's strain energy 4 pi R^2 T W(lambda) (force x length)."""
        W = sum(
            mu / alpha * (2.0 * stretch**alpha + stretch ** (-2.0 * alpha) - 3.0)
            for mu, alpha in zip(self.mu, self.alpha, strict=True)
        )
        return 4.0 * math.pi * self.radius**2 * self.thickness * W
