"""Incompressible Ogden membrane material in plane stress, in principal stretches.

With c1 >= c2 > 0 the eigenvalues of the in-plane C (c_i = lambda_i^2, unit eigenvectors v_i,
material frame) and incompressibility lambda_3 = 1/(lambda_1 lambda_2), the strain energy per
unit reference volume

    Psi = sum_k mu_k/alpha_k (lambda_1^alpha_k + lambda_2^alpha_k + lambda_3^alpha_k - 3)

is, with beta_k = alpha_k/2 - 1 and t_k = lambda_3^alpha_k = (c1 c2)^(-alpha_k/2), a function
of c1, c2. Plane stress S33 = 0 fixes the hydrostatic pressure, which leaves the principal
second Piola-Kirchhoff stresses S_i = 2 dPsi/dc_i:

    S_i = sum_k mu_k (c_i^beta_k - t_k/c_i),           N = D0 (S_1 v1 v1 + S_2 v2 v2),

and their derivatives

    dS_i/dc_i = sum_k mu_k (beta_k c_i^(beta_k - 1) + (1 + alpha_k/2) t_k/c_i^2),
    dS_i/dc_j = sum_k mu_k (alpha_k/2) t_k/(c_i c_j)    (i != j).

The consistent tangent dN/dE = 2 dN/dC of the isotropic function N(C) is, in the principal
frame and Voigt (11, 22, 12) with engineering shear,

    D0 [[2 dS_1/dc_1, 2 dS_1/dc_2, 0], [2 dS_2/dc_1, 2 dS_2/dc_2, 0], [0, 0, G]],
    G = (S_1 - S_2)/(c1 - c2) = sum_k mu_k (d_k + t_k/(c1 c2)),

with the divided difference d_k = (c1^beta_k - c2^beta_k)/(c1 - c2) of the power function,
written as d_k = c2^beta_k expm1(beta_k log1p(x))/(c1 - c2), x = (c1 - c2)/c2, which keeps
full precision however small the gap; below x = 1e-6 (and at c1 = c2 exactly) the binomial
series d_k = beta_k c2^(beta_k - 1) (1 + (beta_k - 1) x/2 + (beta_k - 1)(beta_k - 2) x^2/6)
is used (truncation below 1e-18 relative), whose limit G = dS_1/dc_1 - dS_1/dc_2 makes the
tangent isotropic at equal stretches. The tangent is turned into the material frame with the
eigenvectors (in Voigt form m_i = (v_i1^2, v_i2^2, v_i1 v_i2) and g = sym(v1 v2), it is
sum_ij 2 D0 dS_i/dc_j m_i m_j^T + 4 D0 G g g^T). Current thickness D = D0 lambda_3.

One term with alpha = 2 is the incompressible neo-Hookean law (mu = mu_1); alpha = (2, -2) is
Mooney-Rivlin with C10 = mu_1/2, C01 = -mu_2/2. The small-strain shear modulus is
mu = sum_k mu_k alpha_k / 2, which must be > 0; mu_k (force/area), alpha_k (dimensionless,
nonzero), D0 (length): consistent units.

C must be positive definite (det C > 0 and C11 > 0): ``energy`` returns +inf where it is not,
``response`` raises ValueError naming the first bad point.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from wrinkle.materials.base import MembraneResponse, as_cauchy_green_batch

__all__ = ["Ogden"]

# below this relative gap (c1 - c2)/c2 the divided difference is taken from its series
_SERIES_GAP = 1e-6


class Ogden:
    """Incompressible Ogden membrane (see the module docstring for the formulas).

    Parameters
    ----------
    mu:
        Moduli mu_k of the N terms (force/area), finite.
    alpha:
        Exponents alpha_k of the N terms (dimensionless), finite and nonzero, as many as mu.
        The shear modulus sum_k mu_k alpha_k / 2 must be > 0.
    thickness:
        Reference thickness D0 > 0 (length).
    """

    def __init__(self, mu: Sequence[float], alpha: Sequence[float], thickness: float) -> None:
        moduli = np.atleast_1d(np.asarray(mu, dtype=float))
        exponents = np.atleast_1d(np.asarray(alpha, dtype=float))
        if moduli.ndim != 1 or moduli.size == 0:
            raise ValueError(f"Ogden: mu must be a non-empty list of numbers, got {mu!r}")
        if exponents.shape != moduli.shape:
            raise ValueError(
                f"Ogden: mu and alpha must have the same length, got {moduli.size} and "
                f"{exponents.size}"
            )
        if not np.all(np.isfinite(moduli)):
            raise ValueError(f"Ogden: mu must be finite, got {mu!r}")
        if not np.all(np.isfinite(exponents) & (exponents != 0.0)):
            raise ValueError(f"Ogden: alpha must be finite and nonzero, got {alpha!r}")
        shear = 0.5 * float(np.sum(moduli * exponents))
        if not shear > 0.0:
            raise ValueError(
                "Ogden: mu and alpha: the shear modulus sum(mu_k alpha_k)/2 must be > 0, "
                f"got {shear}"
            )
        thickness = float(thickness)
        if not (np.isfinite(thickness) and thickness > 0.0):
            raise ValueError(f"Ogden: thickness must be finite and > 0, got {thickness}")
        self.mu = tuple(float(m) for m in moduli)
        self.alpha = tuple(float(a) for a in exponents)
        self.thickness = thickness

    @property
    def is_isotropic(self) -> bool:
        """Always True: the Ogden law is isotropic."""
        return True

    @property
    def shear_modulus(self) -> float:
        """Small-strain shear modulus mu = sum_k mu_k alpha_k / 2 (force/area)."""
        return 0.5 * sum(m * a for m, a in zip(self.mu, self.alpha, strict=True))

    # ------------------------------------------------------------------ principal stretches
    @staticmethod
    def _principal(C: np.ndarray) -> tuple[np.ndarray, ...]:
        """Eigenvalues c1 >= c2, their gap c1 - c2 (computed directly, no cancellation), the
        angle theta of v1 = (cos theta, sin theta) and det C, each (n,), for C (n, 2, 2)."""
        a, b, c = C[:, 0, 0], C[:, 1, 1], C[:, 0, 1]
        det = a * b - c * c
        half_gap = np.hypot(0.5 * (a - b), c)
        c1 = 0.5 * (a + b) + half_gap
        c2 = det / np.where(c1 > 0.0, c1, 1.0)
        theta = 0.5 * np.arctan2(2.0 * c, a - b)
        return c1, c2, 2.0 * half_gap, theta, det

    @staticmethod
    def _bad(C: np.ndarray) -> np.ndarray:
        det = C[:, 0, 0] * C[:, 1, 1] - C[:, 0, 1] ** 2
        return ~((det > 0.0) & (C[:, 0, 0] > 0.0))

    def energy(self, C: np.ndarray) -> np.ndarray:
        """Strain energy per unit reference area w = D0 Psi, (n,) for C (n, 2, 2); +inf where
        C is not positive definite."""
        C = as_cauchy_green_batch(C, "Ogden")
        bad = self._bad(C)
        C = np.where(bad[:, None, None], np.eye(2), C)
        c1, c2, _, _, det = self._principal(C)
        ln_c1, ln_c2, ln_det = np.log(c1), np.log(c2), np.log(det)
        psi = np.zeros(len(C))
        for mu, alpha in zip(self.mu, self.alpha, strict=True):
            h = 0.5 * alpha
            psi += (mu / alpha) * (
                np.expm1(h * ln_c1) + np.expm1(h * ln_c2) + np.expm1(-h * ln_det)
            )
        return np.where(bad, np.inf, self.thickness * psi)

    def response(self, C: np.ndarray, tangent: bool = True) -> MembraneResponse:
        """Membrane response for C shaped (n, 2, 2).

        stress (n, 2, 2): N = D0 S; tangent (n, 3, 3): dN/dE, Voigt (11, 22, 12), engineering
        shear (None if ``tangent`` is False); thickness (n,): D = D0/sqrt(det C).

        Raises ValueError if C is not positive definite at some point.
        """
        C = as_cauchy_green_batch(C, "Ogden")
        bad = self._bad(C)
        if np.any(bad):
            i = int(np.flatnonzero(bad)[0])
            det_i = C[i, 0, 0] * C[i, 1, 1] - C[i, 0, 1] ** 2
            raise ValueError(
                f"Ogden: C must be positive definite, got det C = {det_i:.6g}, "
                f"C11 = {C[i, 0, 0]:.6g} at point {i} (det C <= 0: collapsed or inverted "
                "element)"
            )
        D0 = self.thickness
        c1, c2, gap, theta, det = self._principal(C)
        ln_c1, ln_c2, ln_det = np.log(c1), np.log(c2), np.log(det)
        x = gap / c2
        series = x < _SERIES_GAP
        n = len(C)
        S1, S2 = np.zeros(n), np.zeros(n)
        dS11, dS22, dS12, shear = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
        for mu, alpha in zip(self.mu, self.alpha, strict=True):
            h = 0.5 * alpha
            beta = h - 1.0
            t = np.exp(-h * ln_det)  # lambda_3^alpha
            p1, p2 = np.exp(beta * ln_c1), np.exp(beta * ln_c2)  # c_i^beta
            S1 += mu * (p1 - t / c1)
            S2 += mu * (p2 - t / c2)
            if not tangent:
                continue
            dS11 += mu * (beta * p1 / c1 + (1.0 + h) * t / c1**2)
            dS22 += mu * (beta * p2 / c2 + (1.0 + h) * t / c2**2)
            dS12 += mu * h * t / det
            exact = p2 * np.expm1(beta * np.log1p(x)) / np.where(series, 1.0, gap)
            taylor = (beta * p2 / c2) * (
                1.0 + (beta - 1.0) * x / 2 + (beta - 1.0) * (beta - 2.0) * x**2 / 6
            )
            shear += mu * (np.where(series, taylor, exact) + t / det)

        cos, sin = np.cos(theta), np.sin(theta)
        v1 = np.stack([cos, sin], axis=-1)
        v2 = np.stack([-sin, cos], axis=-1)
        M1 = v1[:, :, None] * v1[:, None, :]
        M2 = v2[:, :, None] * v2[:, None, :]
        stress = D0 * (S1[:, None, None] * M1 + S2[:, None, None] * M2)

        tangent_matrix = None
        if tangent:
            m1 = np.stack([cos * cos, sin * sin, cos * sin], axis=-1)
            m2 = np.stack([sin * sin, cos * cos, -cos * sin], axis=-1)
            g = np.stack([-cos * sin, cos * sin, 0.5 * (cos * cos - sin * sin)], axis=-1)

            def outer(u: np.ndarray, w: np.ndarray) -> np.ndarray:
                return u[:, :, None] * w[:, None, :]

            tangent_matrix = D0 * (
                (2.0 * dS11)[:, None, None] * outer(m1, m1)
                + (2.0 * dS22)[:, None, None] * outer(m2, m2)
                + (2.0 * dS12)[:, None, None] * (outer(m1, m2) + outer(m2, m1))
                + (4.0 * shear)[:, None, None] * outer(g, g)
            )
        return MembraneResponse(
            stress=stress, tangent=tangent_matrix, thickness=D0 * np.exp(-0.5 * ln_det)
        )

    def __repr__(self) -> str:
        return f"Ogden(mu={list(self.mu)}, alpha={list(self.alpha)}, thickness={self.thickness})"
