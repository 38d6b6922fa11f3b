r"""Inflated thin spherical membrane of incompressible Mooney-Rivlin rubber: the closed-form
pressure-stretch curve, its limit point (maximum) and its minimum.

**The problem.** A spherical membrane of reference radius R and reference thickness T, of
incompressible Mooney-Rivlin material (strain energy per unit reference volume
W = C10 (I1 - 3) + C01 (I2 - 3)), inflated by an internal pressure p (force per unit current
area), stays spherical with current radius r = lambda R: every point is stretched
equibiaxially by lambda in the membrane's plane, lambda_3 = lambda^-2 across the thickness.

**Stress.** The in-plane membrane C is lambda^2 I, so J = det C = lambda^4, C^-1 = lambda^-2 I
and tr C = 2 lambda^2. The membrane stress resultant of ``wrinkle.materials.mooney_rivlin``,
N = 2 T [C10 (I - C^-1/J) + C01 (I/J - tr C C^-1/J + J C^-1)], is then

    N = 2 T (1 - lambda^-6)(C10 + lambda^2 C01) I                                        (1)

(the C01 bracket is lambda^-4 - 2 lambda^-4 + lambda^2 = lambda^2 (1 - lambda^-6)). Its
Cauchy resultant per unit current length, F N F^T / det F = lambda^2 N / lambda^2, is the same
tension n = N11.

**Equilibrium (Laplace's law).** p pi r^2 = n 2 pi r, so p = 2 n / r:

    p(lambda) = (4 T / R)(lambda^-1 - lambda^-7)(C10 + lambda^2 C01),                   (2)

Adkins & Rivlin's result for the thin Mooney shell; C01 = 0 gives the neo-Hookean
p = (2 mu T / R)(lambda^-1 - lambda^-7) with mu = 2 C10 (``verification.references.sphere``).

**Turning points.** With x = lambda^2, lambda^8 dp/dlambda = (4 T / R) g(x),

    g(x) = C01 x^4 - C10 x^3 + 5 C01 x + 7 C10.                                         (3)

For C01 = 0 the only root is x^3 = 7, lambda = 7^(1/6) (the neo-Hookean limit point). For
C01 > 0: g > 0 on 0 < x <= 1 and at x = C10/C01 (g = 12 C10 there); g'' = 6 x (2 C01 x - C10)
makes g' smallest at x* = C10 / (2 C01), so if g'(x*) >= 0 the pressure rises for ever.
Otherwise g has its one local minimum in x > x* at the root x_m of g' in [x*, C10/C01], and if
g(x_m) < 0 the pressure rises to a maximum at the root of g in [1, x_m], falls to a minimum at
the root in [x_m, C10/C01] and then rises without bound (like lambda) — the balloon's snap
and recovery. Each root is found by ``scipy.optimize.brentq`` in its bracket. The maximum and
the minimum exist for C01/C10 below 0.2145 (where they merge; bisection on the ratio with
``turning_points``): C01/C10 = 0.1 has them at lambda = 1.4761 and 3.1426.

Sources: J. E. Adkins and R. S. Rivlin, "Large elastic deformations of isotropic materials IX.
The deformation of thin shells", Phil. Trans. R. Soc. Lond. A 244 (1952) 505-531; the
derivation above is ours and the tests check (2) against the energy principle p = dW/dV
with wrinkle's Mooney-Rivlin energy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import brentq

__all__ = ["MooneyRivlinSphere"]


@dataclass(frozen=True)
class MooneyRivlinSphere:
    """Thin spherical membrane of incompressible Mooney-Rivlin material under internal
    pressure (module docstring, eqs. (1)-(3)).

    C10 > 0, C01 >= 0 (force/area); thickness T > 0 and radius R > 0 (length). Consistent
    units: pressures force/area, tensions force/length. Stretches lambda >= 1.
    """

    C10: float
    C01: float
    thickness: float
    radius: float

    def __post_init__(self) -> None:
        for name in ("C10", "thickness", "radius"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"MooneyRivlinSphere: {name} must be finite and > 0, got {value}")
        if not (math.isfinite(self.C01) and self.C01 >= 0):
            raise ValueError(f"MooneyRivlinSphere: C01 must be finite and >= 0, got {self.C01}")

    def pressure(self, stretch: ArrayLike) -> np.ndarray:
        """Eq. (2): p = (4 T / R)(lambda^-1 - lambda^-7)(C10 + lambda^2 C01), force/area,
        shaped like ``stretch``."""
        lam = np.asarray(stretch, dtype=float)
        return (
            4.0
            * self.thickness
            / self.radius
            * (1.0 / lam - lam**-7)
            * (self.C10 + lam**2 * self.C01)
        )

    def tension(self, stretch: ArrayLike) -> np.ndarray:
        """Eq. (1): n = 2 T (1 - lambda^-6)(C10 + lambda^2 C01), force per current length."""
        lam = np.asarray(stretch, dtype=float)
        return 2.0 * self.thickness * (1.0 - lam**-6) * (self.C10 + lam**2 * self.C01)

    def _g(self, x: float) -> float:
        """Eq. (3): lambda^8 dp/dlambda / (4 T / R) at x = lambda^2."""
        return self.C01 * x**4 - self.C10 * x**3 + 5.0 * self.C01 * x + 7.0 * self.C10

    def _g_slope(self, x: float) -> float:
        return 4.0 * self.C01 * x**3 - 3.0 * self.C10 * x**2 + 5.0 * self.C01

    def turning_points(self) -> tuple[float | None, float | None]:
        """(lambda at the pressure maximum, lambda at the following minimum), each None where
        there is none: (7^(1/6), None) for C01 = 0 (found by the root finder too), (None, None)
        when p rises for ever."""
        tight = {"xtol": 1e-15, "rtol": 4 * np.finfo(float).eps}
        if self.C01 == 0.0:  # g = C10 (7 - x^3): g(1) > 0 > g(4)
            return math.sqrt(brentq(self._g, 1.0, 4.0, **tight)), None
        x_star = self.C10 / (2.0 * self.C01)
        x_top = self.C10 / self.C01
        if self._g_slope(x_star) >= 0.0:
            return None, None
        x_m = brentq(self._g_slope, x_star, x_top, **tight)
        if self._g(x_m) >= 0.0:
            return None, None
        x_max = brentq(self._g, 1.0, x_m, **tight)
        x_min = brentq(self._g, x_m, x_top, **tight)
        return math.sqrt(x_max), math.sqrt(x_min)

    def stretch(self, pressure: float) -> float:
        """The stretch lambda >= 1 on the first rising branch at which eq. (2) gives
        ``pressure`` (force/area, 0 <= p <= p at the maximum, if there is one), by ``brentq``
        to round-off. ValueError for a pressure outside that range."""
        if not (math.isfinite(pressure) and pressure >= 0.0):
            raise ValueError(f"MooneyRivlinSphere.stretch: pressure must be >= 0, got {pressure}")
        if pressure == 0.0:
            return 1.0
        top, _ = self.turning_points()
        if top is None:  # rising for ever: widen the bracket until it holds the pressure
            top = 2.0
            while float(self.pressure(top)) < pressure:
                top *= 2.0
        elif pressure > float(self.pressure(top)):
            raise ValueError(
                f"MooneyRivlinSphere.stretch: pressure {pressure!r} is above the limit "
                f"pressure {float(self.pressure(top))!r}"
            )
        return float(
            brentq(
                lambda lam: float(self.pressure(lam)) - pressure,
                1.0,
                top,
                xtol=1e-15,
                rtol=4 * np.finfo(float).eps,
            )
        )
