"""St Venant-Kirchhoff membrane material: linear S(E), any anisotropy, in plane stress.

The 3-D law is ``S = H E`` with a constant 6x6 stiffness ``H`` in the material frame
(axis 1 = fibre, axis 2 in plane, axis 3 = membrane normal), Voigt order
(11, 22, 33, 23, 13, 12) and engineering shear strains (2 E23, 2 E13, 2 E12).

Plane stress (S33 = S23 = S13 = 0) is imposed by static condensation of the out-of-plane
strains: with the in-plane indices i = (11, 22, 12) and the out-of-plane ones o = (33, 23, 13),

    Q   = H_ii - H_io H_oo^-1 H_oi          (3x3, Voigt (11, 22, 12))
    e_o = -H_oo^-1 H_oi e_i                 (out-of-plane strains, e_o[0] = E33)

so that the membrane response is linear in the in-plane strain e_i = (E11, E22, 2 E12):
``N = D0 Q e_i``, ``dN/dE = D0 Q``, ``w = D0/2 e_i . Q e_i``, and the current thickness is
``D = D0 sqrt(1 + 2 E33)``. Sources: Zienkiewicz & Taylor, The Finite Element Method, vol. 1,
6th ed., 2005, ch. 6 (plane stress); Jones, Mechanics of Composite Materials, 2nd ed., 1999,
ch. 2 (anisotropic, orthotropic and transversely isotropic compliance).

Units are consistent: stiffness in force/area, thickness in length, stress resultants in
force/length, energies in force/length (energy per unit reference area).
"""

from __future__ import annotations

import numpy as np

from wrinkle.materials.base import (
    MembraneResponse,
    as_cauchy_green_batch,
    tangent_is_isotropic,
)

__all__ = ["IN_PLANE", "OUT_OF_PLANE", "StVenantKirchhoff"]

#: Voigt positions (in the 6-vector 11, 22, 33, 23, 13, 12) of the in-plane components.
IN_PLANE = np.array([0, 1, 5])
#: Voigt positions of the out-of-plane components 33, 23, 13.
OUT_OF_PLANE = np.array([2, 3, 4])

_SYMMETRY_RTOL = 1e-8
_LARGEST_MODULUS = 1e150  # the largest |H| whose products stay finite
_TINY = np.finfo(float).tiny


def _check_thickness(thickness: float, owner: str) -> float:
    thickness = float(thickness)
    if not (np.isfinite(thickness) and thickness > 0.0):
        raise ValueError(f"{owner}: thickness must be finite and > 0, got {thickness}")
    return thickness


def _check_modulus(value: float, name: str, owner: str) -> float:
    value = float(value)
    if not (np.isfinite(value) and value > 0.0):
        raise ValueError(f"{owner}: {name} must be finite and > 0, got {value}")
    return value


class StVenantKirchhoff:
    """St Venant-Kirchhoff membrane: S = H E in 3-D, condensed to plane stress.

    Parameters
    ----------
    stiffness:
        (6, 6) symmetric positive definite 3-D elastic stiffness H in the material frame,
        Voigt order (11, 22, 33, 23, 13, 12), engineering shear strains; force/area.
    thickness:
        Reference thickness D0 > 0 (length).

    Attributes
    ----------
    stiffness: (6, 6) the 3-D stiffness H (symmetrised copy).
    plane_stress_stiffness: (3, 3) condensed stiffness Q, Voigt (11, 22, 12), force/area.
    out_of_plane_strain: (3, 3) matrix R with (E33, 2 E23, 2 E13) = R (E11, E22, 2 E12).
    thickness: D0.
    is_isotropic: whether Q is invariant under in-plane rotation (``tangent_is_isotropic``).

    Raises ValueError, naming the parameter, for a stiffness that is not 6x6, not finite, not
    symmetric (relative tolerance 1e-8) or not positive definite, and for a thickness that is
    not finite and positive.
    """

    def __init__(self, stiffness: np.ndarray, thickness: float) -> None:
        owner = "StVenantKirchhoff"
        H = np.array(stiffness, dtype=float)
        if H.shape != (6, 6):
            raise ValueError(f"{owner}: stiffness must have shape (6, 6), got {H.shape}")
        scale = np.max(np.abs(H)) if np.all(np.isfinite(H)) else np.inf
        # its squares (eigenvalues, energies) must stay finite too
        if not scale < _LARGEST_MODULUS:
            raise ValueError(
                f"{owner}: stiffness must be finite and below {_LARGEST_MODULUS:.0e} "
                f"(max |H| = {scale:.3g}); check the units of the moduli"
            )
        asymmetry = np.max(np.abs(H - H.T))
        if asymmetry > _SYMMETRY_RTOL * scale:
            raise ValueError(
                f"{owner}: stiffness must be symmetric (max |H - H^T| = {asymmetry:.3g}, "
                f"max |H| = {scale:.3g})"
            )
        H = 0.5 * (H + H.T)
        smallest = float(np.linalg.eigvalsh(H)[0]) if scale > 0 else 0.0
        if not smallest > 0.0:
            raise ValueError(
                f"{owner}: stiffness must be positive definite (smallest eigenvalue {smallest:.3g})"
            )
        self.thickness = _check_thickness(thickness, owner)
        self.stiffness = H
        H_ii = H[np.ix_(IN_PLANE, IN_PLANE)]
        H_io = H[np.ix_(IN_PLANE, OUT_OF_PLANE)]
        H_oi = H[np.ix_(OUT_OF_PLANE, IN_PLANE)]
        H_oo = H[np.ix_(OUT_OF_PLANE, OUT_OF_PLANE)]
        self.out_of_plane_strain = -np.linalg.solve(H_oo, H_oi)
        Q = H_ii + H_io @ self.out_of_plane_strain
        self.plane_stress_stiffness = 0.5 * (Q + Q.T)
        self._isotropic = tangent_is_isotropic(self.plane_stress_stiffness)

    @property
    def is_isotropic(self) -> bool:
        """Whether the plane-stress stiffness Q (the tangent at C = I, the same at every C) is
        invariant under rotation about the normal, to 1e-12 of its largest entry: True for
        ``isotropic`` and for ``transversely_isotropic`` with E_L = E_T and
        G_LT = E_L / (2 (1 + nu_LT)); then the fibre direction changes no result."""
        return self._isotropic

    # ------------------------------------------------------------------ constructors
    @classmethod
    def isotropic(cls, E: float, nu: float, thickness: float) -> StVenantKirchhoff:
        """Isotropic St Venant-Kirchhoff material from Young's modulus E > 0 (force/area) and
        Poisson's ratio -1 < nu < 0.5; Lame constants lambda = E nu/((1+nu)(1-2nu)),
        mu = E/(2(1+nu)). The plane-stress stiffness is E/(1-nu^2) [[1,nu,0],[nu,1,0],
        [0,0,(1-nu)/2]]."""
        owner = "StVenantKirchhoff.isotropic"
        E = _check_modulus(E, "E", owner)
        nu = float(nu)
        if not (-1.0 < nu < 0.5):
            raise ValueError(f"{owner}: nu must satisfy -1 < nu < 0.5, got {nu}")
        _check_thickness(thickness, owner)
        lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
        mu = E / (2.0 * (1.0 + nu))
        H = np.zeros((6, 6))
        H[:3, :3] = lam
        H[[0, 1, 2], [0, 1, 2]] += 2.0 * mu
        H[[3, 4, 5], [3, 4, 5]] = mu
        return cls(H, thickness)

    @classmethod
    def transversely_isotropic(
        cls,
        E_L: float,
        E_T: float,
        nu_LT: float,
        nu_TT: float,
        G_LT: float,
        thickness: float,
    ) -> StVenantKirchhoff:
        """Transversely isotropic material: L = axis 1 (fibre), isotropic in the 2-3 plane.

        The compliance (Voigt 11, 22, 33, 23, 13, 12, engineering shear) is

            [ 1/E_L      -nu_LT/E_L  -nu_LT/E_L                                   ]
            [-nu_LT/E_L   1/E_T      -nu_TT/E_T                                   ]
            [-nu_LT/E_L  -nu_TT/E_T   1/E_T                                       ]
            [                                   2(1+nu_TT)/E_T                    ]
            [                                                  1/G_LT             ]
            [                                                          1/G_LT     ]

        and the stiffness is its inverse (Jones, Mechanics of Composite Materials, 1999, ch. 2,
        orthotropic compliance with 2-3 isotropy). Moduli in force/area; nu_LT is the
        contraction in T for a stress along L. Positive definiteness requires E_L, E_T,
        G_LT > 0, -1 < nu_TT < 1 and nu_LT^2 < E_L (1 - nu_TT) / (2 E_T).
        """
        owner = "StVenantKirchhoff.transversely_isotropic"
        E_L = _check_modulus(E_L, "E_L", owner)
        E_T = _check_modulus(E_T, "E_T", owner)
        G_LT = _check_modulus(G_LT, "G_LT", owner)
        nu_LT = float(nu_LT)
        nu_TT = float(nu_TT)
        if not (-1.0 < nu_TT < 1.0):
            raise ValueError(f"{owner}: nu_TT must satisfy -1 < nu_TT < 1, got {nu_TT}")
        bound = E_L * (1.0 - nu_TT) / (2.0 * E_T)
        if not (nu_LT**2 < bound):
            raise ValueError(
                f"{owner}: nu_LT must satisfy nu_LT^2 < E_L (1 - nu_TT) / (2 E_T) = {bound:.6g} "
                f"for a positive definite compliance, got nu_LT = {nu_LT}"
            )
        _check_thickness(thickness, owner)
        S = np.zeros((6, 6))
        S[0, 0] = 1.0 / E_L
        S[1, 1] = S[2, 2] = 1.0 / E_T
        S[0, 1] = S[1, 0] = S[0, 2] = S[2, 0] = -nu_LT / E_L
        S[1, 2] = S[2, 1] = -nu_TT / E_T
        S[3, 3] = 2.0 * (1.0 + nu_TT) / E_T
        S[4, 4] = S[5, 5] = 1.0 / G_LT
        H = np.linalg.inv(S)
        return cls(0.5 * (H + H.T), thickness)

    # ------------------------------------------------------------------ evaluation
    # Written with the (n,) component arrays E11, E22, 2 E12: for batches of tiny vectors this
    # is several times faster than einsum / matmul (the wrinkling wrapper calls ``response``
    # in every Newton iteration).
    @staticmethod
    def _strain_components(C: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Voigt Green-Lagrange strain (E11, E22, 2 E12) of (n, 2, 2) C, each (n,)."""
        return 0.5 * (C[:, 0, 0] - 1.0), 0.5 * (C[:, 1, 1] - 1.0), C[:, 0, 1]

    def energy(self, C: np.ndarray) -> np.ndarray:
        """Strain energy per unit reference area w = D0/2 e.Q.e, (n,), for C shaped (n, 2, 2)."""
        e0, e1, e2 = self._strain_components(as_cauchy_green_batch(C, "StVenantKirchhoff"))
        Q = self.plane_stress_stiffness
        quadratic = (
            e0 * (Q[0, 0] * e0 + 2.0 * (Q[0, 1] * e1 + Q[0, 2] * e2))
            + e1 * (Q[1, 1] * e1 + 2.0 * Q[1, 2] * e2)
            + Q[2, 2] * (e2 * e2)
        )
        return (0.5 * self.thickness) * quadratic

    def response(self, C: np.ndarray, tangent: bool = True) -> MembraneResponse:
        """Membrane response for C shaped (n, 2, 2).

        stress (n, 2, 2): N = D0 S = D0 Q e_i; tangent (n, 3, 3): D0 Q (or None);
        thickness (n,): D = D0 sqrt(1 + 2 E33) with E33 from the condensation; 1 + 2 E33 is
        clipped to the smallest positive float at absurd compressive strains where the linear
        law would make it non-positive (the thickness is then tiny but never NaN).
        """
        C = as_cauchy_green_batch(C, "StVenantKirchhoff")
        e0, e1, e2 = self._strain_components(C)
        n = C.shape[0]
        DQ = self.thickness * self.plane_stress_stiffness
        stress = np.empty((n, 2, 2))
        stress[:, 0, 0] = DQ[0, 0] * e0 + DQ[0, 1] * e1 + DQ[0, 2] * e2
        stress[:, 1, 1] = DQ[1, 0] * e0 + DQ[1, 1] * e1 + DQ[1, 2] * e2
        stress[:, 0, 1] = DQ[2, 0] * e0 + DQ[2, 1] * e1 + DQ[2, 2] * e2
        stress[:, 1, 0] = stress[:, 0, 1]
        R = self.out_of_plane_strain[0]
        E33 = R[0] * e0 + R[1] * e1 + R[2] * e2
        tangent_matrix = None
        if tangent:  # np.tile: a few times faster than broadcasting DQ into an empty array
            tangent_matrix = np.tile(DQ.reshape(1, 9), (n, 1)).reshape(n, 3, 3)
        return MembraneResponse(
            stress=stress,
            tangent=tangent_matrix,
            thickness=self.thickness * np.sqrt(np.maximum(1.0 + 2.0 * E33, _TINY)),
        )

    def __repr__(self) -> str:
        return f"StVenantKirchhoff(stiffness={self.stiffness.tolist()}, thickness={self.thickness})"
