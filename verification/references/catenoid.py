r"""The catenoid between two coaxial rings: the form of an isotropic prestress (the gallery
benchmark is ``verification.benchmarks.catenoid``).

**The problem.** A membrane spans two coaxial rings of radius R a distance h apart, under the
isotropic prestress N0 = n I (force per unit length), and nothing else. Its form, the shape
in which that stress is in balance, is a surface of zero mean curvature: the membrane's
balance normal to itself is n (k_1 + k_2) = 0, with k_1, k_2 the principal curvatures (a
soap film, whose surface tension is such a stress).

**The form.** Among surfaces of revolution r(x) about the rings' axis, the area
A = 2 pi int r sqrt(1 + r'^2) dx is stationary (its first variation is the balance above)
where the Euler-Lagrange equation holds; its first integral, r / sqrt(1 + r'^2) = r_0, gives
the catenary of revolution

    r(x) = r_0 cosh((x - h/2) / r_0),                                                  (1)

with the neck radius r_0 at mid-span, x = h/2. The rings, r(0) = r(h) = R, fix r_0 by

    h / 2 = r_0 arccosh(R / r_0).                                                      (2)

**The roots.** The right-hand side of (2) rises from 0 at r_0 -> 0 to a maximum and falls to
0 at r_0 = R: for h below about 1.3255 R there are two roots; the larger is the stable
catenoid (a minimum of the area), the smaller an unstable one; beyond that span there is
none and the film breaks onto two disks. ``neck_radius`` returns the larger root: R = 1,
h = 1 gives r_0 = 0.848338.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

__all__ = ["neck_radius", "profile"]


def neck_radius(radius: float, span: float) -> float:
    """r_0 (length), the larger root of h/2 = r_0 arccosh(R / r_0), eq. (2), for rings of
    radius R = ``radius`` a distance h = ``span`` apart; ValueError beyond the largest span."""

    def slope(r: float) -> float:  # d/dr of r arccosh(R / r): zero at the fold of the roots
        ratio = radius / r
        return math.acosh(ratio) - ratio / math.sqrt(ratio**2 - 1.0)

    fold = brentq(slope, 1e-9 * radius, radius * (1.0 - 1e-12))
    if fold * math.acosh(radius / fold) < span / 2.0:
        raise ValueError(f"no catenoid spans rings of radius {radius:g} at {span:g} apart")
    return float(
        brentq(lambda r: r * math.acosh(radius / r) - span / 2.0, fold, radius * (1 - 1e-15))
    )


def profile(x: np.ndarray, radius: float, span: float) -> np.ndarray:
    """r(x) = r_0 cosh((x - h/2) / r_0), eq. (1), at the axial positions x (length)."""
    r0 = neck_radius(radius, span)
    return r0 * np.cosh((np.asarray(x, dtype=float) - span / 2.0) / r0)
