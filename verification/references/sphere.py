r"""Inflated thin spherical membrane of incompressible neo-Hookean rubber: the closed-form
pressure-stretch curve (the gallery benchmark is ``verification.benchmarks.sphere``).

**The problem.** A spherical membrane of reference radius R and reference thickness T, made of
incompressible neo-Hookean material with shear modulus mu (strain energy per unit reference
volume W = mu/2 (lambda_1^2 + lambda_2^2 + lambda_3^2 - 3)), is inflated by an internal
pressure p (force per unit current area). By symmetry it stays spherical, with current radius
r = lambda R: every point is stretched equibiaxially by lambda in the membrane's plane.

**Kinematics.** Principal stretches lambda_1 = lambda_2 = lambda in the plane;
incompressibility lambda_1 lambda_2 lambda_3 = 1 gives the stretch across the thickness
lambda_3 = lambda^-2, so the current thickness is

    t = T / lambda^2.                                                                    (1)

**Stress.** With plane stress sigma_3 = 0 fixing the hydrostatic pressure of the
incompressible material, the in-plane Cauchy stress is
sigma = lambda dW/dlambda (equibiaxial, W(lambda) = mu/2 (2 lambda^2 + lambda^-4 - 3)):

    sigma = mu (lambda^2 - lambda^-4),                                                   (2)

and the membrane tension (Cauchy stress resultant, force per unit current length)

    N = sigma t = mu T (1 - lambda^-6).                                                  (3)

**Equilibrium (Laplace's law).** Half the sphere: the pressure on the equatorial disk,
p pi r^2, is carried by the tension on the equator, N 2 pi r, so p = 2 N / r = 2 sigma t / r:

    p(lambda) = (2 mu T / R) (lambda^-1 - lambda^-7).                                    (4)

The same follows from the energy principle p = dW_total/dV with the total strain energy
W_total = 4 pi R^2 T W(lambda) and the enclosed volume V = 4/3 pi R^3 lambda^3 (the unit tests
check (4) that way).

**Limit point.** dp/dlambda = (2 mu T / R)(7 lambda^-8 - lambda^-2) vanishes at

    lambda_max = 7^(1/6) = 1.38309,  p_max = (2 mu T / R) (6/7) 7^(-1/6) = 0.61973 (2 mu T / R). (5)

Below lambda_max the pressure rises with the stretch; beyond it the sphere is unstable under
pressure control (the familiar balloon "snap"). On the rising branch the stretch at a given
pressure p <= p_max is the root of (4) in [1, lambda_max]; ``InflatedSphere.stretch`` finds it
by bisection to the floating-point resolution (the semi-analytical reference of the
benchmark).

Sources: J. E. Adkins and R. S. Rivlin, "Large elastic deformations of isotropic materials IX.
The deformation of thin shells", Phil. Trans. R. Soc. Lond. A 244 (1952) 505-531 (inflation of
a thin spherical shell of neo-Hookean and Mooney material); L. R. G. Treloar, The Physics of
Rubber Elasticity, 3rd ed., Clarendon Press, Oxford, 1975 (inflation of a spherical balloon,
with the maximum of the pressure at lambda = 7^(1/6) for the neo-Hookean solid);
R. W. Ogden, Non-linear Elastic Deformations, Ellis Horwood, 1984 (Dover reprint 1997)
(inflation of a spherical membrane).

**The faceted sphere.** The finite-element octant is the polyhedron inscribed in the sphere:
its volume-to-area ratio is that of a sphere of the smaller radius R_eff = 3 V / A
(``effective_radius``), so for a uniform inflation x = lambda X of the facets the energy
principle gives p = (R / R_eff) p(lambda).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrinkle.mesh import Mesh

__all__ = ["LIMIT_STRETCH", "InflatedSphere", "effective_radius"]

LIMIT_STRETCH = 7.0 ** (1.0 / 6.0)  # eq. (5): the maximum of p(lambda)

_BISECTIONS = 80  # halves [1, 7^(1/6)] down to below the spacing of doubles near 1.4


@dataclass(frozen=True)
class InflatedSphere:
    """Thin spherical membrane of incompressible neo-Hookean material under internal pressure
    (module docstring, eqs. (1)-(5)).

    mu: shear modulus (force/area); thickness: reference thickness T (length); radius:
    reference radius R (length). Consistent units; pressures are force/area, tensions
    force/length. Stretch arguments are arrays (or scalars) lambda >= 1.
    """

    mu: float
    thickness: float
    radius: float

    def __post_init__(self):
        for name in ("mu", "thickness", "radius"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"InflatedSphere: {name} must be finite and > 0, got {value!r}")

    @property
    def pressure_scale(self) -> float:
        """2 mu T / R (force/area), the factor of eq. (4)."""
        return 2.0 * self.mu * self.thickness / self.radius

    def pressure(self, stretch):
        """Eq. (4): p = (2 mu T / R)(lambda^-1 - lambda^-7), force/area, shaped like stretch."""
        stretch = np.asarray(stretch, dtype=float)
        return self.pressure_scale * (1.0 / stretch - stretch**-7)

    def cauchy_stress(self, stretch):
        """Eq. (2): in-plane Cauchy stress sigma = mu (lambda^2 - lambda^-4), force/area."""
        stretch = np.asarray(stretch, dtype=float)
        return self.mu * (stretch**2 - stretch**-4)

    def current_thickness(self, stretch):
        """Eq. (1): t = T / lambda^2, length."""
        return self.thickness / np.asarray(stretch, dtype=float) ** 2

    def tension(self, stretch):
        """Eq. (3): membrane tension N = sigma t = mu T (1 - lambda^-6), force per unit
        current length (equal in every in-plane direction)."""
        stretch = np.asarray(stretch, dtype=float)
        return self.mu * self.thickness * (1.0 - stretch**-6)

    @property
    def limit_pressure(self) -> float:
        """Eq. (5): the largest pressure the sphere carries, p(7^(1/6)), force/area."""
        return float(self.pressure(LIMIT_STRETCH))

    def stretch(self, pressure):
        """The stretch 1 <= lambda <= 7^(1/6) of the rising branch at which eq. (4) gives
        ``pressure`` (force/area, array or scalar, 0 <= p <= p_max), by bisection to the
        resolution of doubles (p is increasing on that interval). ValueError for a pressure
        outside [0, p_max]."""
        pressure = np.asarray(pressure, dtype=float)
        limit = self.limit_pressure
        bad = ~((pressure >= 0.0) & (pressure <= limit))
        if np.any(bad):
            raise ValueError(
                f"InflatedSphere.stretch: pressure {pressure[bad].ravel()[0]!r} is outside "
                f"0 .. p_max = {limit!r} (no equilibrium on the rising branch)"
            )
        low = np.ones_like(pressure)
        high = np.full_like(pressure, LIMIT_STRETCH)
        for _ in range(_BISECTIONS):
            middle = 0.5 * (low + high)
            below = self.pressure(middle) < pressure
            low = np.where(below, middle, low)
            high = np.where(below, high, middle)
        return 0.5 * (low + high)


def effective_radius(mesh: Mesh) -> float:
    """3 V / A of a faceted octant (or any surface closed by planes through the origin):
    V the volume of the cones from the origin over its triangles, sum X1 . (X2 x X3) / 6, A
    its area. For the sphere |X| = R this is R; for the inscribed polyhedron it is smaller by a
    relative amount of order (h/R)^2 (length)."""
    X = mesh.nodes[mesh.triangles]
    normal = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    volume = np.einsum("ni,ni->", normal, X[:, 0]) / 6.0
    area = 0.5 * np.linalg.norm(normal, axis=1).sum()
    return float(3.0 * volume / area)
