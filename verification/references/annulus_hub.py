r"""Annulus with a rotated hub: the tension-field solution (the gallery benchmark is
``verification.benchmarks.annulus_hub``).

The problem (Mikulas, NASA TN D-2456, 1964; Miller & Hedgepeth, AIAA J. 20(12), 1982). A flat
isotropic membrane annulus a <= r <= b is bonded at r = a to a rigid hub. Its outer edge
r = b carries a radial tension N0 (force per unit length) and is held against turning; the hub
turns by the angle phi relative to the outer edge and transmits the torque T. Linear elasticity,
small strain, plane stress: stretching stiffness Y = E t, Poisson's ratio nu. All quantities
are stress resultants (force per unit length); polar components (r, theta) about the hub axis.

Sign convention used throughout: the outer edge turns by phi > 0 counterclockwise relative to
the hub (the hub turns clockwise relative to the edge), the torque T > 0 is applied
counterclockwise at the outer edge and reacted by the hub, and the shear resultant is positive,
N_rtheta = T / (2 pi r^2). The circumferential displacement v is measured from the hub
(v(a) = 0, v(b) = b phi) and w = v / r.

Equilibrium (axisymmetric): d(r N_r)/dr = N_theta and d(r^2 N_rtheta)/dr = 0, so
N_rtheta = T / (2 pi r^2) at every radius, whatever the state of the membrane.

**Taut (Lame) solution, below the onset.** Hooke's law N_r = Y/(1-nu^2) (e_r + nu e_theta), ...,
N_rtheta = Y/(2(1+nu)) gamma, with e_r = u_r', e_theta = u_r/r, gamma = r w', gives

    N_r = A + B/r^2,   N_theta = A - B/r^2,   u_r = ((1-nu) A r - (1+nu) B / r) / Y,
    w = C - (1+nu) T / (2 pi Y r^2).

The hub holds u_r(a) = 0, so B = kappa A a^2 with kappa = (1-nu)/(1+nu); N_r(b) = N0 gives
A = N0 / (1 + kappa a^2/b^2). The torque does not change the radial stresses, and the rotation
is linear in the torque:

    phi = (1+nu) T / (2 pi Y) (1/a^2 - 1/b^2).                                        (1)

The minor principal stress, A - sqrt(B^2/r^4 + N_rtheta^2), is smallest at the hub; it reaches
zero, and the membrane begins to wrinkle there, at the onset torque

    T_onset = 2 pi a^2 sqrt(A^2 - B^2/a^4) = 4 pi a^2 A sqrt(nu) / (1 + nu).            (2)

**Above the onset: wrinkled zone a < r < R (R the wrinkle radius).** The stress is a uniaxial
tension sigma t(x)t along the direction t at the angle psi to the radius. A uniaxial field in
equilibrium without body force has straight tension lines (the equilibrium across t is
sigma times the curvature of the line); axisymmetric straight lines are tangent to one circle,
of radius rho < a, so sin(psi) = rho/r. With c = sqrt(r^2 - rho^2), N_rtheta = sigma sin(psi)
cos(psi) = T / (2 pi r^2) gives sigma = T / (2 pi rho c) and

    N_r = T c / (2 pi rho r^2),   N_theta = T rho / (2 pi c r^2),   N_rtheta = T / (2 pi r^2),  (3)

which satisfy d(r N_r)/dr = N_theta identically (this is where rho must be a constant).
Kinematics of the tension field (Mansfield; Roddeman et al. 1987, Part I): along the tension
lines the strain is elastic, e_tt = sigma/Y, and t is a principal direction of the strain,
e_tn = 0; across them the membrane is over-contracted by the wrinkles, e_nn = -nu sigma/Y - beta
with beta >= 0. The two conditions (e - s I) t = 0, s = sigma/Y, read

    u_r' cos^2(psi) - (u_r/r) sin^2(psi) = s cos(2 psi),     gamma = r w' = 2 (s - u_r/r) tan(psi).

With the hub condition u_r(a) = 0 the first integrates in closed form (integrating factor r/c),
and then the second:

    u_r = T c / (4 pi Y rho r) L(r),    L(r) = ln(c^2/c_a^2) + rho^2/c^2 - rho^2/c_a^2,     (4)
    w(r) - w(a) = T / (4 pi Y) (L(r)/r^2 + 1/c_a^2 - 1/c^2),                             (5)

with c_a = sqrt(a^2 - rho^2).

**Taut zone R < r < b** is the Lame solution with new constants A, B. At r = R the traction
(N_r, N_rtheta) is continuous, and so is e_theta = u_r/r; since the taut stress has a
non-negative minor principal value and the wrinkled one a zero minor value, e_theta continuity
with beta >= 0 forces N_theta to be continuous and beta(R) = 0: the taut stress at R is the
wrinkled one, whose minor principal stress is zero. From (3) at r = R:

    A = T / (4 pi rho c_R),    B = T (R^2 - 2 rho^2) / (4 pi rho c_R).                   (6)

The radial displacement is continuous at R; with (4) and (6) this condition loses T:

    g(rho, R) = c_R^2 ln(c_R^2/c_a^2) - rho^2 (R^2 - a^2)/c_a^2 + 2 nu R^2
                - 2 (1 + nu) rho^2 = 0,                                                   (7)

and the outer edge, N_r(b) = A + B/b^2 = N0, gives the torque explicitly:

    T = 4 pi rho c_R N0 / (1 + (R^2 - 2 rho^2)/b^2).                                      (8)

Equation (7) fixes rho(R) (one root in 0 < rho < a: g > 0 as rho -> 0, g -> -infinity as
rho -> a); (8) then gives T(R), which increases from T_onset at R = a (where (7) gives
rho^2 = nu a^2/(1+nu) and (8) reduces to (2)) to its value at R = b, beyond which the wrinkled
zone would reach the outer edge. For a given torque the pair (rho, R) is found by nested
bracketing root finders (scipy.optimize.brentq) to 1e-14 a, well below the 1e-10 asked. The
rotation is the sum of (5) at R and the taut part of (1) between R and b:

    phi = T/(4 pi Y) (L(R)/R^2 + 1/c_a^2 - 1/c_R^2) + (1+nu) T/(2 pi Y) (1/R^2 - 1/b^2).   (9)

The solution is homogeneous of degree one in (N0, T): R and rho depend on T/N0 only, and the
stresses and phi scale with N0. The relaxed (tension-field) energy is convex in the strain, so
the small-strain equilibrium does not depend on the loading path: loading N0 and T together
from zero (one proportional step) reaches the same state as stretching first and then turning.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

__all__ = ["HubAnnulus", "HubSolution"]

# bracketing root finders: absolute tolerance in units of the hub radius, and the finest
# relative tolerance brentq accepts
_XTOL = 1e-14
_RTOL = 4.0 * np.finfo(float).eps


@dataclass(frozen=True)
class HubAnnulus:
    """The annulus with a rotated hub, small-strain tension-field theory (module docstring).

    inner_radius a and outer_radius b (length, 0 < a < b); poisson_ratio nu (0 < nu < 1/2 for
    the formulas; the tension-field solution needs nu > 0); stretching_stiffness Y = E t (force
    per length); edge_tension N0 > 0 (force per length), the radial tension at r = b.
    """

    inner_radius: float
    outer_radius: float
    poisson_ratio: float
    stretching_stiffness: float
    edge_tension: float

    def __post_init__(self):
        a, b = self.inner_radius, self.outer_radius
        if not 0.0 < a < b:
            raise ValueError(f"need 0 < inner_radius < outer_radius, got {a}, {b}")
        if not 0.0 < self.poisson_ratio < 0.5:
            raise ValueError(f"poisson_ratio must be in (0, 0.5), got {self.poisson_ratio}")
        if not self.stretching_stiffness > 0 or not self.edge_tension > 0:
            raise ValueError("stretching_stiffness and edge_tension must be > 0")

    # -- below the onset ----------------------------------------------------------------
    @property
    def lame_constants(self) -> tuple[float, float]:
        """(A, B) of the taut solution N_r = A + B/r^2, N_theta = A - B/r^2 (force per length,
        force): u_r(a) = 0 and N_r(b) = N0."""
        a, b, nu = self.inner_radius, self.outer_radius, self.poisson_ratio
        kappa = (1.0 - nu) / (1.0 + nu)
        A = self.edge_tension / (1.0 + kappa * a * a / (b * b))
        return A, kappa * A * a * a

    @property
    def onset_torque(self) -> float:
        """Torque (force x length) at which the hub edge starts to wrinkle, eq. (2)."""
        A, _ = self.lame_constants
        nu = self.poisson_ratio
        return 4.0 * math.pi * self.inner_radius**2 * A * math.sqrt(nu) / (1.0 + nu)

    @property
    def torsional_stiffness(self) -> float:
        """T / phi of the taut membrane, eq. (1) (force x length per radian)."""
        a, b, nu = self.inner_radius, self.outer_radius, self.poisson_ratio
        return 2.0 * math.pi * self.stretching_stiffness / ((1.0 + nu) * (1.0 / a**2 - 1.0 / b**2))

    # -- the wrinkled solution ------------------------------------------------------------
    def continuity_residual(self, line_radius: float, wrinkle_radius: float) -> float:
        """g(rho, R) of eq. (7), length^2: zero when u_r is continuous at R."""
        a, nu = self.inner_radius, self.poisson_ratio
        rho2, R2 = line_radius**2, wrinkle_radius**2
        cR2, ca2 = R2 - rho2, a * a - rho2
        return (
            cR2 * math.log(cR2 / ca2)
            - rho2 * (R2 - a * a) / ca2
            + 2.0 * nu * R2
            - 2.0 * (1.0 + nu) * rho2
        )

    def line_radius(self, wrinkle_radius: float) -> float:
        """rho(R): radius of the circle the tension lines touch, root of eq. (7) in (0, a)."""
        a, b = self.inner_radius, self.outer_radius
        if not a <= wrinkle_radius <= b:
            raise ValueError(f"wrinkle radius {wrinkle_radius} outside [{a}, {b}]")
        return brentq(
            self.continuity_residual,
            1e-9 * a,
            a * (1.0 - 1e-13),
            args=(wrinkle_radius,),
            xtol=_XTOL * a,
            rtol=_RTOL,
        )

    def torque_at(self, wrinkle_radius: float) -> float:
        """Torque T(R) for which the wrinkled zone ends at R, eq. (8)."""
        rho = self.line_radius(wrinkle_radius)
        cR = math.sqrt(wrinkle_radius**2 - rho**2)
        return (
            4.0
            * math.pi
            * rho
            * cR
            * self.edge_tension
            / (1.0 + (wrinkle_radius**2 - 2.0 * rho**2) / self.outer_radius**2)
        )

    @property
    def largest_torque(self) -> float:
        """T(b): above it the wrinkled zone would reach the outer edge (outside this model)."""
        return self.torque_at(self.outer_radius)

    def solve(self, torque: float) -> HubSolution:
        """The solution for a transmitted torque T >= 0 (force x length)."""
        a = self.inner_radius
        if torque < 0:
            raise ValueError(f"torque must be >= 0 (sign convention of the module), got {torque}")
        if torque <= self.onset_torque:
            A, B = self.lame_constants
            return HubSolution(
                self, float(torque), float(torque) / self.torsional_stiffness, a, math.nan, A, B
            )
        top = self.largest_torque
        if torque > top:
            raise ValueError(
                f"torque {torque:.6g} exceeds {top:.6g}: the wrinkled zone would reach the "
                "outer edge"
            )
        R = brentq(
            lambda radius: self.torque_at(radius) - torque,
            a,
            self.outer_radius,
            xtol=_XTOL * a,
            rtol=_RTOL,
        )
        rho = self.line_radius(R)
        cR = math.sqrt(R * R - rho * rho)
        A = torque / (4.0 * math.pi * rho * cR)  # eq. (6)
        B = A * (R * R - 2.0 * rho * rho)
        unrotated = HubSolution(self, float(torque), math.nan, R, rho, A, B)
        phi = float(unrotated.rotation_of(self.outer_radius)[0])  # eq. (9)
        return HubSolution(self, float(torque), phi, R, rho, A, B)

    def solve_rotation(self, rotation: float) -> HubSolution:
        """The solution for a rotation phi >= 0 of the outer edge relative to the hub (rad)."""
        if rotation < 0:
            raise ValueError(f"rotation must be >= 0, got {rotation}")
        linear = rotation * self.torsional_stiffness
        if linear <= self.onset_torque:
            return self.solve(linear)
        top = self.largest_torque
        if self.solve(top).rotation < rotation:
            raise ValueError(f"rotation {rotation:.6g} puts the wrinkled zone beyond the edge")
        torque = brentq(
            lambda t: self.solve(t).rotation - rotation,
            self.onset_torque,
            top,
            xtol=1e-14 * top,
            rtol=_RTOL,
        )
        return self.solve(torque)


@dataclass(frozen=True)
class HubSolution:
    """The state at one torque: torque T (force x length), rotation phi (rad) of the outer
    edge relative to the hub, wrinkle_radius R (length; = a below the onset), line_radius rho
    (length; NaN below the onset) and the constants A (force/length), B (force) of the taut
    zone r >= R."""

    problem: HubAnnulus
    torque: float
    rotation: float
    wrinkle_radius: float
    line_radius: float
    A: float
    B: float

    @property
    def wrinkled(self) -> bool:
        """Whether the membrane wrinkles (torque above the onset)."""
        return self.wrinkle_radius > self.problem.inner_radius

    def _line_terms(self, r: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
        """c^2 = r^2 - rho^2, c_a^2 = a^2 - rho^2 and L(r) of eq. (4), for r (m,) in the
        wrinkled zone."""
        a, rho = self.problem.inner_radius, self.line_radius
        c2, ca2 = r * r - rho * rho, a * a - rho * rho
        return c2, ca2, np.log(c2 / ca2) + rho * rho / c2 - rho * rho / ca2

    def stress(self, r) -> np.ndarray:
        """(m, 3) N_r, N_theta, N_rtheta (force per length) at radii r (m,), a <= r <= b."""
        r = np.atleast_1d(np.asarray(r, dtype=float))
        T = self.torque
        shear = T / (2.0 * math.pi * r * r)
        N_r, N_theta = self.A + self.B / r**2, self.A - self.B / r**2
        inside = r < self.wrinkle_radius
        if np.any(inside):
            rho = self.line_radius
            c = np.sqrt(r[inside] ** 2 - rho * rho)
            N_r[inside] = T * c / (2.0 * math.pi * rho * r[inside] ** 2)
            N_theta[inside] = T * rho / (2.0 * math.pi * c * r[inside] ** 2)
        return np.column_stack([N_r, N_theta, shear])

    def radial_displacement(self, r) -> np.ndarray:
        """u_r (length) at radii r (m,): eq. (4) in the wrinkled zone, Lame outside."""
        r = np.atleast_1d(np.asarray(r, dtype=float))
        nu, Y = self.problem.poisson_ratio, self.problem.stretching_stiffness
        u = ((1.0 - nu) * self.A * r - (1.0 + nu) * self.B / r) / Y
        inside = r < self.wrinkle_radius
        if np.any(inside):
            c2, _, L = self._line_terms(r[inside])
            u[inside] = (
                self.torque * np.sqrt(c2) * L / (4.0 * math.pi * Y * self.line_radius * r[inside])
            )
        return u

    def rotation_of(self, r) -> np.ndarray:
        """w = v/r (rad) at radii r (m,), relative to the hub (w(a) = 0): eqs. (5) and (1)."""
        r = np.atleast_1d(np.asarray(r, dtype=float))
        nu, Y, T = self.problem.poisson_ratio, self.problem.stretching_stiffness, self.torque
        R = self.wrinkle_radius
        w_R = 0.0
        if self.wrinkled:
            c2, ca2, L = self._line_terms(np.array([R]))
            w_R = float(T / (4.0 * math.pi * Y) * (L[0] / R**2 + 1.0 / ca2 - 1.0 / c2[0]))
        w = w_R + (1.0 + nu) * T / (2.0 * math.pi * Y) * (1.0 / R**2 - 1.0 / r**2)
        inside = r < R
        if np.any(inside):
            c2, ca2, L = self._line_terms(r[inside])
            w[inside] = T / (4.0 * math.pi * Y) * (L / r[inside] ** 2 + 1.0 / ca2 - 1.0 / c2)
        return w

    def overcontraction(self, r) -> np.ndarray:
        """Wrinkling strain beta = -nu sigma/Y - e_nn >= 0 across the tension lines (m,),
        from the displacement field (4)-(5); zero in the taut zone."""
        r = np.atleast_1d(np.asarray(r, dtype=float))
        beta = np.zeros_like(r)
        inside = r < self.wrinkle_radius
        if not np.any(inside):
            return beta
        ri, rho = r[inside], self.line_radius
        c2 = ri * ri - rho * rho
        # s = sigma / Y, the elastic strain along the tension lines
        s = self.torque / (2.0 * math.pi * self.problem.stretching_stiffness * rho * np.sqrt(c2))
        sin2, cos2 = rho * rho / ri**2, c2 / ri**2
        e_theta = self.radial_displacement(ri) / ri
        e_r = (s * (cos2 - sin2) + e_theta * sin2) / cos2  # first kinematic condition
        gamma = 2.0 * (s - e_theta) * rho / np.sqrt(c2)  # second: 2 (s - e_theta) tan(psi)
        e_nn = e_r * sin2 + e_theta * cos2 - gamma * np.sqrt(sin2 * cos2)
        beta[inside] = -self.problem.poisson_ratio * s - e_nn
        return beta
