"""Inflated square airbag (Contri & Schrefler 1988): what its benchmark is compared with.

The published reference is a number, the centre deflection 217 mm (see
``verification.benchmarks.airbag`` for the problem and its source), not a closed form. This
module holds the mathematics that the benchmark adds to the finite-element runs: Richardson
extrapolation of the mesh sequence and the exact equilibrium of the quarter sheet in z.

*Richardson extrapolation* of a quantity q computed on three meshes of sizes h1 > h2 > h3 (any
ratios): with q(h) = q_inf + c h^p,

    (q1 - q2) / (q2 - q3) = (h1^p - h2^p) / (h2^p - h3^p)                                 (1)

is solved for the observed order p (one scalar equation, bracketed and solved by Brent's method
to 1e-12), then

    q_inf = q3 - (q2 - q3) h3^p / (h2^p - h3^p).                                         (2)

For h1/h2 = h2/h3 = r, (1) reduces to the familiar p = log((q1 - q2)/(q2 - q3)) / log r.
(1) has a positive root only if the differences have the same sign and shrink faster than the
mesh-size differences allow for p -> 0; otherwise the sequence is not (yet) in its asymptotic
range and no extrapolation is returned.

*Equilibrium of the quarter sheet in z*: the follower pressure on a flat triangle is p times its
current area along its normal, so its z force is p times the area of the triangle projected on
the xy plane; the symmetry supports take no z force, so the seam's z reaction must be

    R_z = -p A_xy,      A_xy = sum over elements of (x2 - x1) x (x3 - x1) . e_z / 2,      (3)

with A_xy the deformed quarter sheet's projected area (exact for the discrete surface).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

__all__ = ["Richardson", "projected_area", "richardson"]


@dataclass(frozen=True)
class Richardson:
    """Richardson extrapolation of three values: limit q_inf (eq. 2, the quantity's unit) and
    observed order p (eq. 1); both NaN if the sequence is not in its asymptotic range."""

    limit: float
    order: float


def richardson(sizes, values) -> Richardson:
    """Extrapolate q(h) = q_inf + c h^p from the last three (h, q) pairs (eqs. 1-2).

    sizes: mesh sizes h (decreasing, any ratios; length); values: q on those meshes. Returns
    ``Richardson(nan, nan)`` when (q1 - q2)/(q2 - q3) admits no order p in (0.05, 20).
    """
    h = np.asarray(sizes, dtype=float)[-3:]
    q = np.asarray(values, dtype=float)[-3:]
    if h.size != 3 or not (h[0] > h[1] > h[2] > 0):
        raise ValueError(f"richardson: need three decreasing positive sizes, got {sizes}")
    if q[1] == q[2]:
        return Richardson(float(q[2]), math.inf) if q[0] == q[1] else Richardson(math.nan, math.nan)
    ratio = (q[0] - q[1]) / (q[1] - q[2])

    def mismatch(p: float) -> float:
        return (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p) - ratio

    low, high = 0.05, 20.0
    if not (np.isfinite(ratio) and ratio > 0 and mismatch(low) * mismatch(high) < 0):
        return Richardson(math.nan, math.nan)
    p = brentq(mismatch, low, high, xtol=1e-12, rtol=1e-12)
    limit = q[2] - (q[1] - q[2]) * h[2] ** p / (h[1] ** p - h[2] ** p)
    return Richardson(float(limit), float(p))


def projected_area(x: np.ndarray, triangles: np.ndarray) -> float:
    """Signed area of the triangles (m, 3) of the nodes x (n, 3) projected on the xy plane
    (positive for counter-clockwise triangles seen from +z), eq. (3); length^2."""
    corners = x[triangles]
    edge1, edge2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    return float(0.5 * np.sum(edge1[:, 0] * edge2[:, 1] - edge1[:, 1] * edge2[:, 0]))
