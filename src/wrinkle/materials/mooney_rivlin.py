"""Incompressible Mooney-Rivlin membrane material in plane stress.

The 3-D right Cauchy-Green tensor of the membrane is C3 = diag(C, C33), C the (2, 2) in-plane
part (material frame), and incompressibility det C3 = 1 gives C33 = 1/J with J = det C (plane
stress S33 = 0 then fixes the hydrostatic pressure; S13 = S23 = 0 hold identically). The
invariants of C3 are

    I1 = tr C3 = tr C + 1/J,
    I2 = (I1^2 - tr C3^2)/2 = det C3 tr C3^-1 = tr C^-1 + C33^-1 = tr C / J + J,

(the last step by Cayley-Hamilton in 2-D, tr C^-1 = tr C / det C). With the strain energy per
unit reference volume Psi = C10 (I1 - 3) + C01 (I2 - 3):

    w = D0 Psi = D0 [C10 (tr C + 1/J - 3) + C01 (tr C / J + J - 3)],
    N = 2 dw/dC = 2 D0 [C10 (I - C^-1/J) + C01 (I/J - tr C C^-1/J + J C^-1)],

using dJ/dC = J C^-1, d(1/J)/dC = -C^-1/J, dC^-1/dC = -II(C^-1) with
II_abcd(A) = (A_ac A_bd + A_ad A_bc)/2. The tangent dN/dE = 2 dN/dC is

    dN/dE = 4 D0 [C10 (C^-1 (x) C^-1 + II(C^-1))/J
                  + C01 ((tr C/J + J) C^-1 (x) C^-1 + (tr C/J - J) II(C^-1)
                         - (I (x) C^-1 + C^-1 (x) I)/J)],

major-symmetric, in Voigt form (11, 22, 12) with engineering shear. The current thickness is
D = D0/sqrt(J). At C = I the tangent is that of a neo-Hookean membrane with the shear modulus
mu = 2 (C10 + C01); C01 = 0 is the incompressible neo-Hookean law with mu = 2 C10.

Parameters: C10 > 0 and C01 >= 0 (force/area), which keep Psi >= 0, growing in every
stretch, so that mu = 2 (C10 + C01) > 0; D0 > 0 a length: consistent units.

C must be positive definite (det C > 0 and C11 > 0): ``energy`` returns +inf where it is not,
``response`` raises ValueError naming the first bad point.
"""

from __future__ import annotations

import numpy as np

from wrinkle.materials.base import MembraneResponse, as_cauchy_green_batch
from wrinkle.materials.neo_hookean import _inverse_2x2, _voigt_tensor_products

__all__ = ["MooneyRivlin"]


def _check_modulus(value: float, name: str, allow_zero: bool) -> float:
    value = float(value)
    ok = np.isfinite(value) and (value >= 0.0 if allow_zero else value > 0.0)
    if not ok:
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"MooneyRivlin: {name} must be finite and {bound}, got {value}")
    return value


class MooneyRivlin:
    """Incompressible Mooney-Rivlin membrane (see the module docstring for the formulas).

    Parameters
    ----------
    C10:
        Coefficient of (I1 - 3), C10 > 0 (force/area).
    C01:
        Coefficient of (I2 - 3), C01 >= 0 (force/area).
    thickness:
        Reference thickness D0 > 0 (length).
    """

    def __init__(self, C10: float, C01: float, thickness: float) -> None:
        self.C10 = _check_modulus(C10, "C10", allow_zero=False)
        self.C01 = _check_modulus(C01, "C01", allow_zero=True)
        self.thickness = _check_modulus(thickness, "thickness", allow_zero=False)

    @property
    def is_isotropic(self) -> bool:
        """Always True: the Mooney-Rivlin law is isotropic."""
        return True

    @property
    def shear_modulus(self) -> float:
        """Small-strain shear modulus mu = 2 (C10 + C01) (force/area)."""
        return 2.0 * (self.C10 + self.C01)

    def energy(self, C: np.ndarray) -> np.ndarray:
        """Strain energy per unit reference area w = D0 Psi, (n,) for C (n, 2, 2); +inf where
        C is not positive definite."""
        C = as_cauchy_green_batch(C, "MooneyRivlin")
        a, b, c = C[:, 0, 0], C[:, 1, 1], C[:, 0, 1]
        det = a * b - c * c
        ok = (det > 0.0) & (a > 0.0)
        J = np.where(ok, det, 1.0)
        trace = a + b
        psi = self.C10 * (trace + 1.0 / J - 3.0) + self.C01 * (trace / J + J - 3.0)
        return np.where(ok, self.thickness * psi, np.inf)

    def response(self, C: np.ndarray, tangent: bool = True) -> MembraneResponse:
        """Membrane response for C shaped (n, 2, 2).

        stress (n, 2, 2): N = D0 S; tangent (n, 3, 3): dN/dE, Voigt (11, 22, 12), engineering
        shear (None if ``tangent`` is False); thickness (n,): D = D0/sqrt(det C).

        Raises ValueError if C is not positive definite at some point.
        """
        C = as_cauchy_green_batch(C, "MooneyRivlin")
        a, b, c = C[:, 0, 0], C[:, 1, 1], C[:, 0, 1]
        J = a * b - c * c
        bad = ~((J > 0.0) & (a > 0.0))
        if np.any(bad):
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(
                f"MooneyRivlin: C must be positive definite, got det C = {J[i]:.6g}, "
                f"C11 = {a[i]:.6g} at point {i} (det C <= 0: collapsed or inverted element)"
            )
        C10, C01, D0 = self.C10, self.C01, self.thickness
        C_inv = _inverse_2x2(a, b, c, J)
        trace = a + b
        identity = np.eye(2)
        inv_J = (1.0 / J)[:, None, None]
        stress = (2.0 * D0) * (
            C10 * (identity - C_inv * inv_J)
            + C01
            * (identity * inv_J - (trace / J)[:, None, None] * C_inv + J[:, None, None] * C_inv)
        )

        tangent_matrix = None
        if tangent:
            p, q, r = C_inv[:, 0, 0], C_inv[:, 1, 1], C_inv[:, 0, 1]
            outer, II = _voigt_tensor_products(p, q, r)
            inverse_voigt = np.stack([p, q, r], axis=-1)
            identity_voigt = np.array([1.0, 1.0, 0.0])
            mixed = (
                identity_voigt[None, :, None] * inverse_voigt[:, None, :]
                + inverse_voigt[:, :, None] * identity_voigt[None, None, :]
            )
            ratio = (trace / J)[:, None, None]
            tangent_matrix = (4.0 * D0) * (
                (C10 / J)[:, None, None] * (outer + II)
                + C01
                * (
                    (ratio + J[:, None, None]) * outer
                    + (ratio - J[:, None, None]) * II
                    - mixed * inv_J
                )
            )
        return MembraneResponse(stress=stress, tangent=tangent_matrix, thickness=D0 / np.sqrt(J))

    def __repr__(self) -> str:
        return f"MooneyRivlin(C10={self.C10}, C01={self.C01}, thickness={self.thickness})"
