"""Stein & Hedgepeth's membrane beam: a pretensioned strip, clamped at one end, bent in its plane
by a transverse force at the other.

Reference: M. Stein and J. M. Hedgepeth, "Analysis of partly wrinkled membranes", NASA TR R-100
(1961). Their tension-field hypotheses — a wrinkled membrane carries no compressive stress, only
a uniaxial tension, and the wrinkles take up whatever shortening compatibility asks for — are
applied here to a beam cross-section. The report's own text was not at hand, so no equation
numbers of it are quoted: the one-dimensional theory below is derived from those hypotheses
and the classical beam assumptions, and every step is checked in
``tests/verification/test_membrane_beam.py``.

The one-dimensional tension-field beam
--------------------------------------
A strip of length L, depth h and thickness t (Young's modulus E, shear modulus G) is clamped at
x = 0 and loaded at x = L by an axial force P (tension, along the centre line) and a transverse
force V. Across the depth, s is the distance from the edge that the bending stretches (the
*tension edge*, s = 0) towards the edge that it shortens (the *compressed edge*, s = h). The
bending moment is

    M(x) = V (L - x)                                                               (1)

and the section carries the axial stress resultant N(s) (force per unit length) with

    integral_0^h N ds = P,      integral_0^h N (h/2 - s) ds = M.                    (2)

Compatibility (the assumption used here): the axial strain of the mean surface is linear over the
*whole* depth, eps(s) = eps_0 + kappa (h/2 - s) (plane sections), and the membrane is a
tension-only material, N = E t max(eps, 0). Where eps < 0 the membrane wrinkles, the stress is
zero and the shortening eps is taken up by the wrinkles. This makes the section law (P, M) ->
(eps_0, kappa) derivable from the convex complementary energy u*(M) = integral N^2/(2 E t) ds, so
that kappa = du*/dM (used below for the deflection).

*Taut section*, 0 <= M <= P h/6 (N >= 0 everywhere):

    N(s) = P/h + 12 M (h/2 - s) / h^3,      kappa = M / (E I),   E I = E t h^3 / 12.   (3)

The stress of the compressed edge, N(h) = P/h - 6 M/h^2, vanishes at M = P h / 6: wrinkling
starts at the root when V L = P h / 6, i.e. at the *onset load* V = V_slack / 3, where

    V_slack = P h / (2 L).                                                          (4)

*Wrinkled section*, P h/6 < M < P h/2: the stress is linear over a taut depth c, zero beyond,

    N(s) = 2 P (c - s) / c^2  for 0 <= s <= c,   N(s) = 0  for c < s <= h;          (5)

the first of (2) holds for any c, and the second gives M = P (h/2 - c/3), so

    c = 3 (h/2 - M/P),      kappa = 2 P / (E t c^2),                                (6)

the strain being eps(s) = 2 P (c - s) / (E t c^2) over the whole depth (negative, i.e. wrinkled,
for s > c). At M = P h/6, c = h and (5), (6) join (3) continuously. As M -> P h/2 the taut depth
c -> 0 and the curvature grows without bound: the whole force P would have to pass through the
tension edge. That is the *slack limit*, reached at the root when V -> V_slack. The section is
wrinkled from the root up to the *wrinkled length*

    x_w = max(0, L - P h / (6 V)),                                                  (7)

where M(x_w) = P h/6, and the compressed edge's strain is eps(h) = N(h)/(E t) on the taut side
and 2 P (c - h)/(E t c^2) < 0 on the wrinkled side: it changes sign at x_w.

Shear (Timoshenko, on the taut depth): axial equilibrium dN_xy/ds = -dN/dx with N_xy = 0 at both
ends of the taut depth gives, from (5) and (6) with dc/dx = 3 V/P, the parabola
N_xy(s) = 6 V s (c - s) / c^3 over 0 <= s <= c (zero beyond); the same holds for (3) with c = h.
Its energy-consistent mean shear strain is gamma = (1/V) integral N_xy^2/(G t) ds = 6 V/(5 G t c).

Tip deflection (clamped root, no slope and no deflection at x = 0; the moment-area theorem plus
the shear strain):

    w_L = integral_0^L kappa(x) (L - x) dx + integral_0^L gamma(x) dx.                 (8)

With f = V / V_slack and the taut tip length l = L - x_w = P h/(6 V) (= L when f <= 1/3):

    f <= 1/3:   w_L = V L^3 / (3 E I) + 6 V L / (5 G t h);
    1/3 < f < 1:
        w_L = V l^3/(3 E I) + 6 V l/(5 G t h)
              + 2 P^3/(9 E t V^2) [1/(1 - f) - 3/2 + ln(3 (1 - f)/2)]
              + 2 P/(5 G t) ln(2 / (3 (1 - f))).                                   (9)

(The wrinkled part of the first integral: with the distance from the tip r = L - x,
c = (3 V/P)(3 l - r) and kappa r = 2 P^3 r / (9 E t V^2 (3 l - r)^2), whose antiderivative is
3 l/(3 l - r) + ln(3 l - r); between r = l and r = L this gives the bracket, since
3 l / L = 1/f.) Both brackets vanish at f = 1/3, so w_L is continuous at the onset, and w_L
grows like 2 P^3 / (9 E t V_slack^2 (1 - f)) as f -> 1.

The two-dimensional problem and where it departs
------------------------------------------------
A strip whose long edges are free carries no transverse stress, N_y = 0, so wherever it carries
shear its minor principal stress, about -N_xy^2/N_x, is negative: by the tension-field criterion it
is wrinkled *everywhere* the shear is nonzero, and a wrinkled membrane shears almost freely (a
lateral contraction, taken up by wrinkles along x, relaxes the shear at no cost in energy). The
finite-element strip then deflects several times more than the beam, increasingly so as the mesh
is refined (the full run of ``verification.benchmarks.membrane_beam`` shows it on its two
coarsest meshes). The benchmark strip therefore also carries a small transverse pretension q
(force per unit length) on its long edges, N_y = q, enough to keep the shear from wrinkling the
taut part: with (5) and the
parabolic N_xy, N_x N_y >= N_xy^2 over the taut depth requires

    q >= 8 V^2 / (3 P c),                                                           (10)

(the worst point is a third of c from the unstressed end of the taut depth). With Poisson's
ratio 0 the pretension changes neither N_x nor the axial strains, so (1)-(9) are unchanged; in
the wrinkled part of a section the 2-D state is then a tension field along y (N_y = q, N_x = 0,
N_xy = 0), which is exactly what (5) assumes. The root holds the section's axial displacement
and its deflection, but lets it take the lateral strain q/(E t) of the pretension.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["MembraneBeam"]


# -- the analytical solution -------------------------------------------------------------------
@dataclass(frozen=True)
class MembraneBeam:
    """The one-dimensional tension-field cantilever of the module docstring.

    length L and depth h (length); tension P (force); axial_stiffness E t and shear_stiffness
    G t (force per length). Consistent units throughout. Arrays broadcast; moments M, tip loads V
    and coordinates x, s may be scalars or arrays.
    """

    length: float
    depth: float
    tension: float
    axial_stiffness: float
    shear_stiffness: float

    def __post_init__(self):
        for name in ("length", "depth", "tension", "axial_stiffness", "shear_stiffness"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"MembraneBeam: {name} must be finite and > 0, got {value!r}")

    @property
    def slack_load(self) -> float:
        """V_slack = P h / (2 L), eq. (4): the tip force that makes the root slack (force)."""
        return self.tension * self.depth / (2.0 * self.length)

    @property
    def onset_load(self) -> float:
        """V_slack / 3 = P h / (6 L): the tip force at which the root's compressed edge
        reaches zero stress (force)."""
        return self.slack_load / 3.0

    @property
    def bending_stiffness(self) -> float:
        """E I = E t h^3 / 12 (force length^2)."""
        return self.axial_stiffness * self.depth**3 / 12.0

    def moment(self, x, tip_load) -> np.ndarray:
        """M(x) = V (L - x), eq. (1) (force length)."""
        return tip_load * (self.length - np.asarray(x, dtype=float))

    def _checked_moment(self, moment) -> np.ndarray:
        M = np.asarray(moment, dtype=float)
        limit = 0.5 * self.tension * self.depth
        if np.any(M < 0) or np.any(M >= limit):
            raise ValueError(
                f"moment must lie in [0, P h/2) = [0, {limit:.6g}) (P h/2 is the "
                f"slack limit), got {M.min():.6g} .. {M.max():.6g}"
            )
        return M

    def taut_depth(self, moment) -> np.ndarray:
        """Depth c over which the section carries tension (length): h while M <= P h/6,
        else 3 (h/2 - M/P), eq. (6). Raises ValueError at or beyond the slack limit."""
        M = self._checked_moment(moment)
        return np.minimum(self.depth, 3.0 * (0.5 * self.depth - M / self.tension))

    def axial_stress(self, s, moment) -> np.ndarray:
        """Axial stress resultant N (force per length) at the distance s from the tension edge,
        eqs. (3) and (5)."""
        s = np.asarray(s, dtype=float)
        M = self._checked_moment(moment)
        P, h = self.tension, self.depth
        c = self.taut_depth(M)
        taut = P / h + 12.0 * M * (0.5 * h - s) / h**3
        wrinkled = np.where(s <= c, 2.0 * P * (c - s) / c**2, 0.0)
        return np.where(M <= P * h / 6.0, taut, wrinkled)

    def axial_strain(self, s, moment) -> np.ndarray:
        """Axial strain of the mean surface at s (plane sections over the whole depth):
        N/(E t) where taut, negative (the wrinkles' shortening) beyond the taut depth."""
        s = np.asarray(s, dtype=float)
        M = self._checked_moment(moment)
        P, h = self.tension, self.depth
        c = self.taut_depth(M)
        taut = P / h + 12.0 * M * (0.5 * h - s) / h**3
        return np.where(M <= P * h / 6.0, taut, 2.0 * P * (c - s) / c**2) / self.axial_stiffness

    def curvature(self, moment) -> np.ndarray:
        """kappa (1/length): M/(E I) while taut, 2 P/(E t c^2) when wrinkled, eqs. (3), (6)."""
        M = self._checked_moment(moment)
        c = self.taut_depth(M)
        return np.where(
            M <= self.tension * self.depth / 6.0,
            M / self.bending_stiffness,
            2.0 * self.tension / (self.axial_stiffness * c**2),
        )

    def shear_strain(self, moment, tip_load) -> np.ndarray:
        """Mean (energy-consistent) shear strain 6 V / (5 G t c) of the section."""
        return 1.2 * tip_load / (self.shear_stiffness * self.taut_depth(moment))

    def complementary_energy(self, moment) -> np.ndarray:
        """u*(M) = integral N^2 / (2 E t) ds per unit length of beam (force):
        P^2/(2 E t h) + 6 M^2/(E t h^3) while taut, 2 P^2/(3 E t c) when wrinkled."""
        M = self._checked_moment(moment)
        P, h, Et = self.tension, self.depth, self.axial_stiffness
        c = self.taut_depth(M)
        return np.where(
            M <= P * h / 6.0, P**2 / (2 * Et * h) + 6 * M**2 / (Et * h**3), 2 * P**2 / (3 * Et * c)
        )

    def _tip_load(self, tip_load) -> np.ndarray:
        V = np.asarray(tip_load, dtype=float)
        if np.any(V < 0) or np.any(V >= self.slack_load):
            raise ValueError(
                f"tip load must lie in [0, V_slack) = [0, {self.slack_load:.6g}), "
                f"got {V.min():.6g} .. {V.max():.6g}"
            )
        return V

    def wrinkled_length(self, tip_load) -> np.ndarray:
        """x_w = max(0, L - P h / (6 V)), eq. (7) (length from the root)."""
        V = self._tip_load(tip_load)
        with np.errstate(divide="ignore"):
            return np.maximum(0.0, self.length - self.tension * self.depth / (6.0 * V))

    def compressed_edge_strain(self, x, tip_load) -> np.ndarray:
        """Axial strain of the compressed edge s = h at x (dimensionless); changes sign at
        x_w."""
        V = self._tip_load(tip_load)
        return self.axial_strain(self.depth, self.moment(x, V))

    def tip_deflection(self, tip_load, shear: bool = True) -> np.ndarray:
        """Transverse tip deflection w_L (length, along V), eq. (9); ``shear=False`` leaves out
        the shear strain's part."""
        V = self._tip_load(tip_load)
        P, h, L = self.tension, self.depth, self.length
        Et, Gt, EI = self.axial_stiffness, self.shear_stiffness, self.bending_stiffness
        f = V / self.slack_load
        with np.errstate(divide="ignore", invalid="ignore"):
            taut_length = np.where(f <= 1.0 / 3.0, L, P * h / (6.0 * V))
            bending = V * taut_length**3 / (3.0 * EI)
            shear_part = 1.2 * V * taut_length / (Gt * h)
            wrinkled = f > 1.0 / 3.0
            g = np.where(wrinkled, f, 0.5)  # any value in (1/3, 1) where not wrinkled
            bending = bending + np.where(
                wrinkled,
                2
                * P**3
                / (9 * Et * np.where(wrinkled, V, 1.0) ** 2)
                * (1.0 / (1.0 - g) - 1.5 + np.log(1.5 * (1.0 - g))),
                0.0,
            )
            shear_part = shear_part + np.where(
                wrinkled, 0.4 * P / Gt * np.log(2.0 / (3.0 * (1.0 - g))), 0.0
            )
        return bending + shear_part if shear else bending

    def transverse_tension_needed(self, tip_load) -> np.ndarray:
        """Smallest transverse pretension q (force per length) that keeps the taut depth taut
        under the parabolic shear at the root, eq. (10): 8 V^2 / (3 P c_root)."""
        V = self._tip_load(tip_load)
        return 8.0 * V**2 / (3.0 * self.tension * self.taut_depth(self.moment(0.0, V)))
