"""Inflated cylindrical beam in bending: Comer & Levy's moment-curvature relation (the
verification-gallery benchmark that checks wrinkle against it is
``verification.benchmarks.inflated_cylinder``).

Reference: R. L. Comer and S. Levy, "Deflections of an inflated circular-cylindrical
cantilever beam", AIAA Journal 1(7), 1963, 1652-1655. A thin circular tube of radius R, closed
at both ends and inflated to the pressure p, is bent by a moment M. Its wall is a membrane: it
carries tension but no compression, and where the axial stress resultant would become
negative it wrinkles. Comer and Levy's assumptions, restated here and derived in our notation
(the equations below are ours; the paper's text was not at hand, its results are the ones
known from it: M_w = pi p R^3 / 2, M_c = pi p R^3 and the relation between them):

- plane sections remain plane: the axial strain of the mean surface is linear over the
  section, eps(theta) = eps_0 + kappa R cos(theta), theta measured around the section from the
  side in tension, kappa the curvature of the tube's axis (1/length);
- the hoop resultant is p R everywhere (equilibrium across the wall; the contribution of
  the axial stress times the axis curvature, of relative order kappa R, is neglected), so in
  the taut wall the axial resultant is linear in the strain, N_x = E t eps + nu p R: the
  bending stiffness of the wall is E t, not E t / (1 - nu^2);
- the wrinkled wall carries no axial stress (tension field: uniaxial hoop tension);
- the axial force is the pressure's end force, P = p pi R^2 (closed ends), and the moment is
  M = integral of N_x R cos(theta) R d(theta).

Taut section (M <= M_w): N_x = p R / 2 + M cos(theta) / (pi R^2) (the beam formula with
I = pi R^3 t), kappa = M / (E t pi R^3). N_x first vanishes at theta = pi when

    M_w = pi p R^3 / 2                                                     (wrinkling moment)

Wrinkled section (M > M_w): the wall is taut on |theta| < alpha (alpha the taut half-angle)
and wrinkled on alpha < |theta| <= pi. N_x is linear in cos(theta) on the taut arc and
vanishes at its ends, N_x = E t kappa R (cos(theta) - cos(alpha)). Axial equilibrium and the
moment give

    P = 2 E t kappa R^2 (sin(alpha) - alpha cos(alpha))                    (1)
    M =   E t kappa R^3 (alpha - sin(alpha) cos(alpha))                    (2)

so that, with f(alpha) = sin(alpha) - alpha cos(alpha), g(alpha) = alpha - sin(alpha)cos(alpha),

    M / (p pi R^3)   = g(alpha) / (2 f(alpha))                             (3)
    kappa E t / p     = pi / (2 f(alpha))                                   (4)

At alpha = pi, (3) and (4) give M_w and the linear curvature p / (2 E t) = M_w / (E t pi R^3):
the relation is continuous. M / (p pi R^3) rises monotonically from 1/2 to 1 as alpha falls
from pi to 0 (g / 2f = (1 - alpha^2/5 + ...) / (1 - alpha^2/10 + ...)), and kappa grows like
3 P / (2 E t R^2 alpha^3): the tube collapses (zero bending stiffness) at

    M_c = pi p R^3                                                         (collapse moment)

Given M, equation (3) is one nonlinear equation for alpha, solved here by bisection to
round-off (|residual| < 1e-10 is checked); (4) then gives the curvature. The strain of the
axis (theta = pi/2) follows from the taut law: eps_axis = -kappa R cos(alpha) - nu p R / (E t)
(wrinkled), (1/2 - nu) p R / (E t) (taut); it places the end plate of the finite-element model
and is not part of the comparison. With an axial force P other than p pi R^2 (``end_force``)
the same equations hold with that P: M_w = P R / 2, M_c = P R.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["InflatedTube", "moment_ratio", "taut_half_angle"]

_SERIES_BELOW = 0.1  # alpha below which f and g are summed from their series (cancellation)


def _taut_arc_force(alpha: np.ndarray) -> np.ndarray:
    """f(alpha) = sin(alpha) - alpha cos(alpha) = integral_0^alpha s sin(s) ds, (n,).

    Below alpha = 0.1 the Taylor series sum_{n>=1} (-1)^(n+1) 2n alpha^(2n+1) / (2n+1)!
    (alpha^3/3 - alpha^5/30 + ...) replaces the difference, which loses digits there."""
    alpha = np.asarray(alpha, dtype=float)
    direct = np.sin(alpha) - alpha * np.cos(alpha)
    series = np.zeros_like(alpha)
    term_power, factorial = alpha**3, 6.0
    for n in range(1, 8):
        series += (-1) ** (n + 1) * 2 * n * term_power / factorial
        term_power = term_power * alpha**2
        factorial *= (2 * n + 2) * (2 * n + 3)
    return np.where(alpha < _SERIES_BELOW, series, direct)


def _taut_arc_moment(alpha: np.ndarray) -> np.ndarray:
    """g(alpha) = alpha - sin(alpha) cos(alpha) = alpha - sin(2 alpha) / 2 = 2 integral_0^alpha
    sin^2(s) ds, (n,); below alpha = 0.1 its series sum_{n>=1} (-1)^(n+1) (2 alpha)^(2n+1) /
    (2 (2n+1)!) (2 alpha^3 / 3 - 2 alpha^5 / 15 + ...)."""
    alpha = np.asarray(alpha, dtype=float)
    direct = alpha - 0.5 * np.sin(2.0 * alpha)
    series = np.zeros_like(alpha)
    term_power, factorial = (2.0 * alpha) ** 3, 6.0
    for n in range(1, 8):
        series += (-1) ** (n + 1) * term_power / (2.0 * factorial)
        term_power = term_power * (2.0 * alpha) ** 2
        factorial *= (2 * n + 2) * (2 * n + 3)
    return np.where(alpha < _SERIES_BELOW, series, direct)


def moment_ratio(alpha) -> np.ndarray:
    """M / (p pi R^3) of a section taut on |theta| < alpha (radians, 0 < alpha <= pi),
    equation (3): g(alpha) / (2 f(alpha)); 1/2 at alpha = pi, tends to 1 as alpha -> 0."""
    alpha = np.asarray(alpha, dtype=float)
    return _taut_arc_moment(alpha) / (2.0 * _taut_arc_force(alpha))


def taut_half_angle(ratio, tolerance: float = 1e-10) -> np.ndarray:
    """The taut half-angle alpha (radians) at which M / (p pi R^3) = ``ratio``, for ratios in
    [1/2, 1): equation (3) solved by bisection on [0, pi] (the ratio falls monotonically with
    alpha) to round-off. Raises ValueError outside [1/2, 1) or if the residual of (3) exceeds
    ``tolerance``."""
    ratio = np.asarray(ratio, dtype=float)
    if np.any(~(ratio >= 0.5)) or np.any(~(ratio < 1.0)):
        raise ValueError(f"moment ratio M / (p pi R^3) must lie in [1/2, 1), got {ratio}")
    low, high = np.zeros_like(ratio), np.full_like(ratio, np.pi)
    for _ in range(64):  # 2^-64 pi: below the spacing of doubles near alpha
        middle = 0.5 * (low + high)
        above = moment_ratio(middle) > ratio  # alpha too small
        low, high = np.where(above, middle, low), np.where(above, high, middle)
    alpha = 0.5 * (low + high)
    residual = np.abs(moment_ratio(alpha) - ratio)
    if np.any(residual > tolerance):
        raise ValueError(f"equation (3) not solved to {tolerance}: residual {residual.max()}")
    return alpha


@dataclass(frozen=True)
class InflatedTube:
    """A closed membrane tube in bending after Comer & Levy (1963), consistent units.

    radius: R (length); pressure: p (force / length^2); membrane_stiffness: E t
    (force / length); poisson: nu (only for ``axis_strain``); end_force: an axial force
    (positive pulling) added to the pressure's end force p pi R^2, e.g. the small net force
    of the end plate of a finite-element model (Comer & Levy's tube has none). Every formula
    uses the axial force P = p pi R^2 + end_force, so that M_w = P R / 2 and M_c = P R; the
    hoop resultant stays p R.
    """

    radius: float
    pressure: float
    membrane_stiffness: float
    poisson: float = 0.0
    end_force: float = 0.0

    @property
    def axial_force(self) -> float:
        """P = p pi R^2 + end_force: the axial force the wall carries (force)."""
        return self.pressure * np.pi * self.radius**2 + self.end_force

    @property
    def wrinkling_moment(self) -> float:
        """M_w = P R / 2 = pi p R^3 / 2 without end force (force x length)."""
        return 0.5 * self.axial_force * self.radius

    @property
    def collapse_moment(self) -> float:
        """M_c = P R = pi p R^3 without end force (force x length)."""
        return self.axial_force * self.radius

    @property
    def bending_stiffness(self) -> float:
        """E I = E t pi R^3 of the taut section (force x length^2)."""
        return self.membrane_stiffness * np.pi * self.radius**3

    def taut_half_angle(self, moment) -> np.ndarray:
        """alpha (radians) for moments M (any shape, |M| < M_c): pi up to M_w, the root of
        equation (3) beyond."""
        moment = np.asarray(moment, dtype=float)
        ratio = np.abs(moment) / self.collapse_moment
        if np.any(~(ratio < 1.0)):
            raise ValueError(
                f"moment {np.max(np.abs(moment))} reaches the collapse moment "
                f"{self.collapse_moment}"
            )
        alpha = np.full_like(ratio, np.pi)
        wrinkled = ratio > 0.5
        if np.any(wrinkled):
            alpha[wrinkled] = taut_half_angle(ratio[wrinkled])
        return alpha

    def curvature(self, moment) -> np.ndarray:
        """Curvature kappa (1/length) of the axis under moments M (any shape, |M| < M_c):
        M / (E t pi R^3) up to M_w, equation (4), P / (2 E t R^2 f(alpha)), beyond; signed
        like M."""
        moment = np.asarray(moment, dtype=float)
        alpha = self.taut_half_angle(moment)
        linear = moment / self.bending_stiffness
        wrinkled = (
            np.sign(moment)
            * self.axial_force
            / (2.0 * self.membrane_stiffness * self.radius**2 * _taut_arc_force(alpha))
        )
        return np.where(alpha < np.pi, wrinkled, linear)

    def moment_of_curvature(self, curvature) -> np.ndarray:
        """The inverse of ``curvature`` for kappa >= 0 (any shape): M = E I kappa up to
        M_w; beyond, f(alpha) = P / (2 E t R^2 kappa) (equation 4, f rising from 0 to pi on
        [0, pi]) solved for alpha by bisection to round-off, then equation (3)."""
        curvature = np.asarray(curvature, dtype=float)
        if np.any(~(curvature >= 0.0)):
            raise ValueError(f"curvature must be >= 0, got {curvature}")
        linear = curvature * self.bending_stiffness
        target = self.axial_force / (
            2.0 * self.membrane_stiffness * self.radius**2 * np.maximum(curvature, 1e-300)
        )
        low, high = np.zeros_like(curvature), np.full_like(curvature, np.pi)
        for _ in range(64):
            middle = 0.5 * (low + high)
            below = _taut_arc_force(middle) < target
            low, high = np.where(below, middle, low), np.where(below, high, middle)
        alpha = 0.5 * (low + high)
        return np.where(
            linear <= self.wrinkling_moment, linear, self.collapse_moment * moment_ratio(alpha)
        )

    def axial_stress(self, theta, moment: float) -> np.ndarray:
        """Axial stress resultant N_x (force / length) at the angles theta (radians from the
        side in tension, any shape) of a section under the moment M (0 <= M < M_c):
        P / (2 pi R) + M cos(theta) / (pi R^2) up to M_w; E t kappa R max(0, cos(theta) -
        cos(alpha)) beyond."""
        theta = np.asarray(theta, dtype=float)
        alpha = float(self.taut_half_angle(moment))
        if alpha == np.pi:
            return self.axial_force / (2.0 * np.pi * self.radius) + moment * np.cos(theta) / (
                np.pi * self.radius**2
            )
        kappa = float(self.curvature(moment))
        return (
            self.membrane_stiffness
            * kappa
            * self.radius
            * np.maximum(np.cos(theta) - np.cos(alpha), 0.0)
        )

    def axis_strain(self, moment) -> np.ndarray:
        """Axial strain of the tube's axis (theta = pi/2) under moments M (any shape):
        (P / (2 pi R) - nu p R) / (E t) up to M_w, -|kappa| R cos(alpha) - nu p R / (E t)
        beyond (from the taut law N_x = E t eps + nu p R)."""
        moment = np.asarray(moment, dtype=float)
        alpha = self.taut_half_angle(moment)
        hoop = self.poisson * self.pressure * self.radius / self.membrane_stiffness
        taut = self.axial_force / (2.0 * np.pi * self.radius * self.membrane_stiffness) - hoop
        wrinkled = -np.abs(self.curvature(moment)) * self.radius * np.cos(alpha) - hoop
        return np.where(alpha < np.pi, wrinkled, taut)
