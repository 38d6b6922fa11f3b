r"""Lamé annulus under differential tension: the tension-field solution (the gallery benchmark
is ``verification.benchmarks.lame_annulus``).

The problem (Davidovitch, Schroll, Vella, Adda-Bedia & Cerda, "Prototypical model for tensional
wrinkling in thin sheets", PNAS 108(45) (2011) 18227-18232). A flat annular sheet
R_in <= r <= R_out is pulled by a radial tension T_in (force per unit length) along its inner
edge, towards the centre, and by T_out along its outer edge, outwards. With the tension ratio
tau = T_in / T_out large enough the hoop stress near the hole would be compressive: the sheet
wrinkles radially in R_in < r < L. Davidovitch et al. study the wrinkle pattern from onset to
"far from threshold"; in the far-from-threshold limit (vanishing bending stiffness) the stress
is the tension-field (compression-free) one derived below, which is what wrinkle computes.
Linear theory (small strain), plane stress, isotropic: stretching stiffness Y = E t, Poisson's
ratio nu. N_r, N_theta are the radial and hoop stress resultants (force per unit length), u the
radial displacement (positive outwards). The derivation is ours, from first principles.

**Equilibrium** of an axisymmetric membrane without body force:

    d(r N_r)/dr = N_theta.                                                                  (1)

**Taut annulus (Lamé).** Hooke's law N_r = Y/(1-nu^2) (u' + nu u/r),
N_theta = Y/(1-nu^2) (u/r + nu u') with (1) gives u'' + u'/r - u/r^2 = 0, u = a r + b/r, so

    N_r = A + B/r^2,   N_theta = A - B/r^2,   u = ((1-nu) A r - (1+nu) B/r) / Y.           (2)

The traction conditions N_r(R_in) = T_in, N_r(R_out) = T_out give

    A = (T_out R_out^2 - T_in R_in^2) / (R_out^2 - R_in^2),
    B = (T_in - T_out) R_in^2 R_out^2 / (R_out^2 - R_in^2):                                  (3)

the stresses do not depend on E or nu. The hoop stress is smallest at the hole,
N_theta(R_in) = T_in - 2 (T_in - T_out) R_out^2 / (R_out^2 - R_in^2), and vanishes at the
**onset ratio**

    tau_c = 2 R_out^2 / (R_in^2 + R_out^2)        (-> 2 for R_out >> R_in).               (4)

**Beyond onset: the tension field.** In the wrinkled zone R_in < r < L the sheet carries no
hoop stress, N_theta = 0, and (1) gives

    N_r = T_in R_in / r.                                                                     (5)

Outside, L < r < R_out, the sheet is taut: (2) with new constants A, B. Three conditions fix A,
B and L: the radial traction is continuous, N_r(L) = T_in R_in / L; the outer edge carries
T_out, N_r(R_out) = T_out; and the hoop stress of the taut side vanishes at L,

    N_theta(L+) = A - B/L^2 = 0.                                                             (6)

Why (6): u is continuous. In the wrinkled zone the radial fibres carry the uniaxial tension N_r,
whose elastic hoop strain is -nu N_r / Y; the mean surface is shorter by the wrinkling strain
w >= 0 (the excess length gathered into the wrinkles): u/r = -nu N_r/Y - w. On the taut side
u/L = (N_theta - nu N_r)/Y. With N_r continuous, w(L-) = -N_theta(L+)/Y, and w >= 0 together
with N_theta >= 0 leave N_theta(L+) = 0. So B = A L^2, 2 A = T_in R_in / L and
A + B/R_out^2 = T_out, which is the quadratic

    tau R_in L^2 - 2 R_out^2 L + tau R_in R_out^2 = 0.                                     (7)

Its roots multiply to R_out^2, so only the smaller lies in the sheet:

    L = tau R_in / (1 + sqrt(1 - (tau R_in / R_out)^2)),                                    (8)
    A = T_in R_in / (2 L),   B = T_in R_in L / 2.

L = R_in at tau = tau_c, and L -> tau R_in / 2 as R_out -> infinity (the infinite-sheet
tension-field result). For tau > R_out / R_in no tension-only equilibrium exists (N_r of (5)
cannot fall to T_out).

**Displacement** (depends on E t and nu). Taut zone: (2). Wrinkled zone: the radial fibres are
straight and elastic, du/dr = N_r / Y; from u(L) = -2 nu A L / Y = -nu T_in R_in / Y,

    u(r) = -(T_in R_in / Y) (nu + ln(L / r)),                                               (9)
    w(r) = -nu N_r / Y - u / r = (T_in R_in / (Y r)) ln(L / r).                              (10)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LameAnnulus", "onset_ratio", "wrinkle_radius"]


# -- the analytical solution -------------------------------------------------------------------


def onset_ratio(inner_radius: float, outer_radius: float) -> float:
    """Tension ratio T_in/T_out at which the hoop stress of the taut (Lamé) annulus first
    vanishes, at the hole: tau_c = 2 R_out^2 / (R_in^2 + R_out^2), eq. (4). Radii in one
    length unit; the result is dimensionless."""
    return 2.0 * outer_radius**2 / (inner_radius**2 + outer_radius**2)


def wrinkle_radius(inner_radius: float, outer_radius: float, ratio) -> np.ndarray | float:
    """Outer radius L of the wrinkled zone, eq. (8): L = tau R_in / (1 + sqrt(1 - (tau R_in /
    R_out)^2)) for tau_c < tau <= R_out/R_in, and R_in (no wrinkles) for tau <= tau_c.

    ratio: tau = T_in/T_out, a number or an array; the result has its shape, in the unit of
    the radii. Raises ValueError for tau <= 0 or tau > R_out/R_in (no tension-only
    equilibrium).
    """
    tau = np.asarray(ratio, dtype=float)
    if np.any(~(tau > 0)):
        raise ValueError(f"tension ratio must be > 0, got {ratio!r}")
    if np.any(tau * inner_radius > outer_radius):
        raise ValueError(
            f"tension ratio {np.max(tau):g} exceeds R_out/R_in = {outer_radius / inner_radius:g}:"
            " no tension-field equilibrium (N_r = T_in R_in / r cannot fall to T_out)"
        )
    root = np.sqrt(1.0 - (tau * inner_radius / outer_radius) ** 2)
    radius = np.where(
        tau > onset_ratio(inner_radius, outer_radius),
        tau * inner_radius / (1.0 + root),
        inner_radius,
    )
    return float(radius) if radius.ndim == 0 else radius


@dataclass(frozen=True)
class LameAnnulus:
    """The annulus R_in <= r <= R_out under the radial edge tensions T_in (inner edge, pulling
    towards the centre) and T_out (outer edge, outwards): the taut Lamé solution up to the
    onset ratio, the tension-field solution beyond it (module docstring, eqs. 1-10).

    Radii in one length unit, tensions in force per unit length; stresses are stress resultants
    (force per unit length). Methods take radii as numbers or arrays and return arrays of the
    same shape.
    """

    inner_radius: float
    outer_radius: float
    inner_tension: float
    outer_tension: float

    def __post_init__(self):
        if not 0 < self.inner_radius < self.outer_radius:
            raise ValueError(
                f"LameAnnulus: need 0 < inner_radius < outer_radius, got "
                f"{self.inner_radius!r}, {self.outer_radius!r}"
            )
        if not (self.inner_tension > 0 and self.outer_tension > 0):
            raise ValueError(
                f"LameAnnulus: tensions must be > 0, got {self.inner_tension!r}, "
                f"{self.outer_tension!r}"
            )
        wrinkle_radius(self.inner_radius, self.outer_radius, self.ratio)  # checks the ratio

    @property
    def ratio(self) -> float:
        """tau = T_in / T_out."""
        return self.inner_tension / self.outer_tension

    @property
    def onset_ratio(self) -> float:
        """tau_c, eq. (4)."""
        return onset_ratio(self.inner_radius, self.outer_radius)

    @property
    def wrinkled(self) -> bool:
        """True beyond the onset, tau > tau_c."""
        return self.ratio > self.onset_ratio

    @property
    def wrinkle_radius(self) -> float:
        """L, eq. (8); R_in when not wrinkled."""
        return wrinkle_radius(self.inner_radius, self.outer_radius, self.ratio)

    @property
    def lame_constants(self) -> tuple[float, float]:
        """(A, B) of the taut zone, N_r = A + B/r^2, N_theta = A - B/r^2: eq. (3) up to the
        onset, A = T_in R_in / (2 L), B = A L^2 beyond it. A: force/length; B: force."""
        a, b = self.inner_radius, self.outer_radius
        t_in, t_out = self.inner_tension, self.outer_tension
        if not self.wrinkled:
            return (
                (t_out * b**2 - t_in * a**2) / (b**2 - a**2),
                (t_in - t_out) * a**2 * b**2 / (b**2 - a**2),
            )
        L = self.wrinkle_radius
        A = t_in * a / (2.0 * L)
        return A, A * L**2

    def _radii(self, r) -> tuple[np.ndarray, np.ndarray]:
        """r as an array (checked to lie in the sheet) and the mask of the wrinkled zone."""
        r = np.asarray(r, dtype=float)
        if np.any((r < self.inner_radius * (1 - 1e-12)) | (r > self.outer_radius * (1 + 1e-12))):
            raise ValueError("LameAnnulus: a radius lies outside R_in <= r <= R_out")
        return r, r < self.wrinkle_radius

    def radial_stress(self, r) -> np.ndarray:
        """N_r(r): eq. (5) in the wrinkled zone, eq. (2) in the taut zone."""
        r, wrinkled = self._radii(r)
        A, B = self.lame_constants
        return np.where(wrinkled, self.inner_tension * self.inner_radius / r, A + B / r**2)

    def hoop_stress(self, r) -> np.ndarray:
        """N_theta(r): 0 in the wrinkled zone, eq. (2) in the taut zone."""
        r, wrinkled = self._radii(r)
        A, B = self.lame_constants
        return np.where(wrinkled, 0.0, A - B / r**2)

    def radial_displacement(
        self, r, stretching_stiffness: float, poisson_ratio: float
    ) -> np.ndarray:
        """u(r), positive outwards, in the unit of the radii: eq. (9) in the wrinkled zone,
        eq. (2) in the taut zone. stretching_stiffness: Y = E t (force/length)."""
        r, wrinkled = self._radii(r)
        A, B = self.lame_constants
        Y, nu = stretching_stiffness, poisson_ratio
        taut = ((1 - nu) * A * r - (1 + nu) * B / r) / Y
        ratio_inside = np.where(wrinkled, self.wrinkle_radius / r, 1.0)
        inside = -(self.inner_tension * self.inner_radius / Y) * (nu + np.log(ratio_inside))
        return np.where(wrinkled, inside, taut)

    def wrinkling_strain(self, r, stretching_stiffness: float) -> np.ndarray:
        """w(r), eq. (10): the hoop length gathered into wrinkles per unit length (0 where
        taut). stretching_stiffness: Y = E t (force/length)."""
        r, wrinkled = self._radii(r)
        ratio_inside = np.where(wrinkled, self.wrinkle_radius / r, 1.0)
        return (
            self.inner_tension
            * self.inner_radius
            / (stretching_stiffness * r)
            * np.log(ratio_inside)
        )
