"""Neo-Hookean membrane material, incompressible or compressible, in plane stress.

The 3-D right Cauchy-Green tensor of the membrane is block diagonal, C3 = diag(C, C33), with
C the (2, 2) in-plane part (material frame) and C33 = (D/D0)^2; plane stress S33 = 0 fixes C33
(S13 = S23 = 0 hold identically for an isotropic law and a block-diagonal C3).

Incompressible (``lmbda=None``), C33 = 1/det C:

    w = mu D0/2 (tr C + 1/det C - 3)
    N = mu D0 (I - C^-1/det C)
    dN/dE = 2 dN/dC = (2 mu D0/det C) (C^-1 (x) C^-1 + II(C^-1))
    D = D0/sqrt(det C)

Compressible (``lmbda > 0``), Bonet & Wood, Nonlinear Continuum Mechanics for Finite Element
Analysis, 2nd ed., 2008, sec. 6.4.3 (energy, stress and elasticity tensor):

    Psi = mu/2 (I1 - 3) - mu ln J + lmbda/2 (ln J)^2,   I1 = tr C + C33,
    ln J = (ln det C + ln C33)/2,
    S = mu (I - C3^-1) + lmbda ln J C3^-1,
    CC = lmbda C3^-1 (x) C3^-1 + 2 (mu - lmbda ln J) II(C3^-1),

with II_abcd(A) = (A_ac A_bd + A_ad A_bc)/2. Plane stress S33 = 0 is
g(x) = mu (exp(x) - 1) + lmbda (ln det C + x)/2 = 0 for x = ln C33, increasing and convex in x;
it is solved by Newton's method from the small-strain solution (which lies above the root, so
the iterates decrease monotonically), safeguarded by bisection in a bracket. The in-plane
tangent is the condensed CC_abcd - CC_ab33 CC_33cd / CC_3333.

Then w = D0 Psi, N = D0 S (in-plane part), dN/dE = D0 CC (condensed, Voigt (11, 22, 12)),
D = D0 sqrt(C33). mu and lmbda are the small-strain Lame constants (force/area), D0 a length:
consistent units.

C must be positive definite (det C > 0 and C11 > 0, a non-collapsed, non-inverted element):
``energy`` returns +inf where it is not, ``response`` raises ValueError naming the first bad
point.
"""

from __future__ import annotations

import numpy as np

from wrinkle.materials.base import MembraneResponse, as_cauchy_green_batch

__all__ = ["NeoHookean"]

_MAX_NEWTON = 60


def _check_positive(value: float, name: str) -> float:
    value = float(value)
    if not (np.isfinite(value) and value > 0.0):
        raise ValueError(f"NeoHookean: {name} must be finite and > 0, got {value}")
    return value


def _inverse_2x2(a: np.ndarray, b: np.ndarray, c: np.ndarray, det: np.ndarray) -> np.ndarray:
    """Inverse of [[a, c], [c, b]] with determinant det, (n, 2, 2)."""
    inv = np.empty(a.shape + (2, 2))
    inv[:, 0, 0] = b / det
    inv[:, 1, 1] = a / det
    inv[:, 0, 1] = inv[:, 1, 0] = -c / det
    return inv


def _voigt_tensor_products(
    p: np.ndarray, q: np.ndarray, r: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Voigt (11, 22, 12) forms of A (x) A and II(A) for symmetric A = [[p, r], [r, q]].

    II_abcd(A) = (A_ac A_bd + A_ad A_bc)/2; T_ij = T[a_i, b_i, a_j, b_j] with the pairs
    (0, 0), (1, 1), (0, 1) (engineering shear, as ``tangent_to_voigt``). Each (n, 3, 3).
    """
    n = p.shape[0]
    outer = np.empty((n, 3, 3))
    II = np.empty((n, 3, 3))
    pp, qq, rr, pq, pr, qr = p * p, q * q, r * r, p * q, p * r, q * r
    for (i, j), o, s in (
        ((0, 0), pp, pp),
        ((1, 1), qq, qq),
        ((2, 2), rr, 0.5 * (pq + rr)),
        ((0, 1), pq, rr),
        ((0, 2), pr, pr),
        ((1, 2), qr, qr),
    ):
        outer[:, i, j] = outer[:, j, i] = o
        II[:, i, j] = II[:, j, i] = s
    return outer, II


class NeoHookean:
    """Neo-Hookean membrane (see the module docstring for the formulas).

    Parameters
    ----------
    mu:
        Shear modulus mu > 0 (force/area).
    thickness:
        Reference thickness D0 > 0 (length).
    lmbda:
        Lame's first constant lmbda > 0 (force/area) for the compressible law; None for the
        incompressible law.
    """

    def __init__(self, mu: float, thickness: float, lmbda: float | None = None) -> None:
        self.mu = _check_positive(mu, "mu")
        self.thickness = _check_positive(thickness, "thickness")
        self.lmbda = None if lmbda is None else _check_positive(lmbda, "lmbda")

    @property
    def is_isotropic(self) -> bool:
        """Always True: the neo-Hookean law is isotropic, the fibre direction changes nothing."""
        return True

    # ------------------------------------------------------------------ plane stress
    def _components(self, C: np.ndarray) -> tuple[np.ndarray, ...]:
        a, b, c = C[:, 0, 0], C[:, 1, 1], C[:, 0, 1]
        return a, b, c, a * b - c * c

    def _solve_ln_c33(self, ln_det: np.ndarray) -> np.ndarray:
        """x = ln C33 solving g(x) = mu (e^x - 1) + lmbda (ln_det + x)/2 = 0, (n,).

        g is increasing and convex. Bracket: e^x - 1 >= x gives x <= x_hi = -lmbda ln_det /
        (2 mu + lmbda) (the small-strain solution); e^x - 1 <= 0 for x <= 0 gives
        x >= x_lo = min(0, -ln_det). Newton from x_hi decreases monotonically to the root; a
        step leaving the bracket (possible only by round-off) is replaced by bisection.
        """
        mu, lmbda = self.mu, self.lmbda
        if lmbda is None:
            raise ValueError("the incompressible law has no C33 equation to solve")
        lo = np.minimum(0.0, -ln_det)
        hi = -lmbda * ln_det / (2.0 * mu + lmbda)
        x = hi.copy()
        for _ in range(_MAX_NEWTON):
            ex = np.exp(x)
            g = mu * (ex - 1.0) + 0.5 * lmbda * (ln_det + x)
            dg = mu * ex + 0.5 * lmbda
            hi = np.where(g > 0.0, x, hi)
            lo = np.where(g < 0.0, x, lo)
            step = np.where(g == 0.0, 0.0, g / dg)
            x_new = x - step
            outside = (x_new < lo) | (x_new > hi)
            x_new = np.where(outside & (g != 0.0), 0.5 * (lo + hi), x_new)
            change = np.abs(x_new - x)
            x = x_new
            if np.all(change <= 4.0 * np.finfo(float).eps * np.maximum(1.0, np.abs(x))):
                break
        return x

    # ------------------------------------------------------------------ evaluation
    def energy(self, C: np.ndarray) -> np.ndarray:
        """Strain energy per unit reference area w = D0 Psi at plane stress, (n,).

        +inf where C (n, 2, 2) is not positive definite.
        """
        C = as_cauchy_green_batch(C, "NeoHookean")
        a, b, _, det = self._components(C)
        ok = (det > 0.0) & (a > 0.0)
        ln_det = np.log(np.where(ok, det, 1.0))
        trace = a + b
        if self.lmbda is None:
            psi = 0.5 * self.mu * (trace + np.exp(-ln_det) - 3.0)
        else:
            x = self._solve_ln_c33(ln_det)
            ln_J = 0.5 * (ln_det + x)
            psi = (
                0.5 * self.mu * (trace + np.exp(x) - 3.0)
                - self.mu * ln_J
                + 0.5 * self.lmbda * ln_J**2
            )
        return np.where(ok, self.thickness * psi, np.inf)

    def response(self, C: np.ndarray, tangent: bool = True) -> MembraneResponse:
        """Membrane response for C shaped (n, 2, 2).

        stress (n, 2, 2): N = D0 S (in-plane); tangent (n, 3, 3): dN/dE, Voigt (11, 22, 12),
        engineering shear (None if ``tangent`` is False); thickness (n,): D = D0 sqrt(C33).

        Raises ValueError if C is not positive definite at some point (det C <= 0: collapsed
        or inverted element).
        """
        C = as_cauchy_green_batch(C, "NeoHookean")
        a, b, c, det = self._components(C)
        bad = ~((det > 0.0) & (a > 0.0))
        if np.any(bad):
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(
                f"NeoHookean: C must be positive definite, got det C = {det[i]:.6g}, "
                f"C11 = {a[i]:.6g} at point {i} (det C <= 0: collapsed or inverted element)"
            )
        mu, D0 = self.mu, self.thickness
        C_inv = _inverse_2x2(a, b, c, det)
        identity = np.eye(2)
        ln_det = np.log(det)

        if self.lmbda is None:
            C33 = 1.0 / det
            stress = mu * D0 * (identity - C_inv * C33[:, None, None])
        else:
            lmbda = self.lmbda
            x = self._solve_ln_c33(ln_det)
            C33 = np.exp(x)
            ln_J = 0.5 * (ln_det + x)
            stress = D0 * (mu * (identity - C_inv) + (lmbda * ln_J)[:, None, None] * C_inv)

        tangent_matrix = None
        if tangent:
            # Voigt (11, 22, 12) entries of C^-1 (x) C^-1 (``outer``) and II(C^-1), with the
            # components p = C^-1_11, q = C^-1_22, r = C^-1_12 (see ``_voigt_tensor_products``)
            p, q, r = C_inv[:, 0, 0], C_inv[:, 1, 1], C_inv[:, 0, 1]
            outer, II = _voigt_tensor_products(p, q, r)
            if self.lmbda is None:
                scale = D0 * (2.0 * mu * C33)
                tangent_matrix = scale[:, None, None] * (outer + II)
            else:
                # 3-D tangent, in-plane block and its 33 couplings (C3^-1_a3 = 0, C3^-1_33 = 1/C33)
                shear = 2.0 * (mu - lmbda * ln_J)
                CC_ab33 = lmbda / C33  # times C^-1
                CC_3333 = (lmbda + shear) / C33**2
                condensed = (CC_ab33 * CC_ab33 / CC_3333)[:, None, None] * outer
                tangent_matrix = D0 * (lmbda * outer + shear[:, None, None] * II - condensed)

        return MembraneResponse(stress=stress, tangent=tangent_matrix, thickness=D0 * np.sqrt(C33))

    def __repr__(self) -> str:
        return f"NeoHookean(mu={self.mu}, thickness={self.thickness}, lmbda={self.lmbda})"
