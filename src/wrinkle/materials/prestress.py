"""A membrane prestress: a constant stress resultant added to any membrane material.

``Prestressed(material, prestress)`` is the law

    N(C) = N_el(C) + N0,        w(C) = w_el(C) + N0 : E,        dN/dE = dN_el/dE,

with E = (C - I)/2 and N0 the constant prestress, force per unit reference length, in the
material frame (axis 1 = fibre). The energy's gradient is the stress (2 dw/dC = N_el + N0), so
the problem stays conservative, and the tangent is the inner material's.

What the prestress is: N is the second Piola-Kirchhoff stress resultant referred to the
reference (mesh) configuration, so N0 is the stress that the membrane carries in that
configuration; there F = I and the PK2 and Cauchy resultants coincide: N0 is the Cauchy
(true) membrane stress, force per unit length, of the membrane as meshed and unloaded, e.g.
a sheet tensioned on a frame before the load. The elastic part N_el(C) is the inner law
measured from that same configuration (its thickness too: the thickness is the inner
material's, D0 at C = I), so the reference configuration is not stress-free: the stress-free
state is ``stress_free_state`` C0, with N_el(C0) = -N0.

Negative prestress is refused: an isotropic value n < 0, or a tensor that is not positive
semidefinite (an eigenvalue below -1e-12 times its largest |entry|). A compressive prestress
would wrinkle the unloaded membrane at once and has no meaning in tension-field theory.
"""

from __future__ import annotations

import numpy as np

from wrinkle.materials.base import (
    Material,
    MembraneResponse,
    as_cauchy_green_batch,
    tangent_of,
)

__all__ = ["Prestressed", "prestress_tensor"]

_PSD_RTOL = 1e-12
_NEWTON_ITERATIONS = 60


def prestress_tensor(prestress: float | tuple | list | np.ndarray) -> np.ndarray:
    """The (2, 2) prestress tensor N0 of an isotropic value n (N0 = n I) or of the Voigt
    components [n11, n22, n12] (material frame), force per unit length.

    Raises ValueError for a value that is not finite, a list that is not of length 3, or a
    negative prestress: n < 0, or a tensor that is not positive semidefinite (smallest
    eigenvalue below -1e-12 times its largest |entry|)."""
    values = np.asarray(prestress, dtype=float)
    if values.ndim == 0:
        n = float(values)
        if not np.isfinite(n):
            raise ValueError(f"prestress must be finite, got {n}")
        if n < 0.0:
            raise ValueError(f"prestress must be >= 0 (a tension), got {n}")
        return n * np.eye(2)
    if values.shape != (3,):
        raise ValueError(
            f"prestress must be one number or a list [n11, n22, n12], got shape {values.shape}"
        )
    if not np.all(np.isfinite(values)):
        raise ValueError(f"prestress must be finite, got {values.tolist()}")
    N0 = np.array([[values[0], values[2]], [values[2], values[1]]])
    smallest = float(np.linalg.eigvalsh(N0)[0])
    if smallest < -_PSD_RTOL * float(np.abs(values).max()):
        raise ValueError(
            f"prestress [n11, n22, n12] = {values.tolist()} must be positive semidefinite "
            f"(a tension in every direction); its smallest principal value is {smallest:.6g}"
        )
    return N0


class Prestressed:
    """A membrane material with a constant prestress N0 (module docstring).

    material: the elastic law (any ``Material``); prestress: n >= 0 (isotropic, N0 = n I) or
    [n11, n22, n12] positive semidefinite in the material frame, force per unit length.

    Attributes: ``material``, ``prestress`` (2, 2) N0, ``thickness`` D0 of the inner material,
    ``stress_free_state`` (2, 2) C0 with N(C0) = 0 (the state the wrinkling wrapper measures
    slackness from, ``wrinkle.wrinkling``). ValueError for a negative prestress or one for
    which no stress-free state is found (a prestress beyond what the inner law can release,
    such as n >= E t / (2 (1 - nu)) for isotropic St Venant-Kirchhoff, where C0 would not be
    positive definite).
    """

    def __init__(self, material: Material, prestress: float | tuple | list | np.ndarray):
        self.material = material
        self.prestress = prestress_tensor(prestress)
        self.thickness = material.thickness
        self.stress_free_state = self._stress_free_state()
        N0 = self.prestress
        isotropic_prestress = N0[0, 1] == 0.0 and N0[0, 0] == N0[1, 1]
        self._isotropic = isotropic_prestress and bool(getattr(material, "is_isotropic", False))

    @property
    def is_isotropic(self) -> bool:
        """The inner material's ``is_isotropic``, and False for an anisotropic prestress
        (n11 != n22 or n12 != 0): then the fibre direction matters."""
        return self._isotropic

    def energy(self, C: np.ndarray) -> np.ndarray:
        """w = w_el(C) + N0 : E, E = (C - I)/2, per unit reference area, (n,); C (n, 2, 2)."""
        C = as_cauchy_green_batch(C, "Prestressed")
        N0 = self.prestress
        work = (
            0.5 * (N0[0, 0] * (C[:, 0, 0] - 1.0) + N0[1, 1] * (C[:, 1, 1] - 1.0))
            + N0[0, 1] * (C[:, 0, 1] + C[:, 1, 0]) * 0.5
        )
        return self.material.energy(C) + work

    def response(self, C: np.ndarray, tangent: bool = True) -> MembraneResponse:
        """N = N_el(C) + N0 (n, 2, 2), the inner tangent dN_el/dE (n, 3, 3) and thickness (n,)."""
        C = as_cauchy_green_batch(C, "Prestressed")
        inner = self.material.response(C, tangent=tangent)
        return MembraneResponse(
            stress=inner.stress + self.prestress, tangent=inner.tangent, thickness=inner.thickness
        )

    def _stress_free_state(self) -> np.ndarray:
        """C0 (2, 2) with N_el(C0) + N0 = 0: Newton on the Voigt strain from E = 0, each step
        halved until C0 stays positive definite and |N| decreases."""
        N0 = self.prestress
        if not np.any(N0):
            return np.eye(2)
        scale = float(np.abs(N0).max())
        strain = np.zeros(3)  # (E11, E22, 2 E12)

        def state(e: np.ndarray) -> np.ndarray:
            return np.array([[1.0 + 2.0 * e[0], e[2]], [e[2], 1.0 + 2.0 * e[1]]])

        def residual(e: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
            C = state(e)
            if not np.linalg.eigvalsh(C)[0] > 0.0:
                return np.full(3, np.inf), None
            with np.errstate(all="ignore"):
                r = self.response(C[None], tangent=True)
            N = r.stress[0]
            return np.array([N[0, 0], N[1, 1], N[0, 1]]), tangent_of(r)[0]

        g, D = residual(strain)
        for _ in range(_NEWTON_ITERATIONS):
            size = float(np.abs(g).max())
            if size <= 1e-14 * scale:
                return state(strain)
            assert D is not None
            step = np.linalg.solve(D, -g)
            if np.abs(step).max() <= 4.0 * np.finfo(float).eps * (1.0 + np.abs(strain).max()):
                return state(strain)  # at round-off
            for _ in range(40):
                trial_g, trial_D = residual(strain + step)
                if np.all(np.isfinite(trial_g)) and np.abs(trial_g).max() < size:
                    break
                step *= 0.5
            else:
                break
            strain, g, D = strain + step, trial_g, trial_D
        raise ValueError(
            f"prestress {self.prestress.tolist()}: the material has no stress-free state "
            "(N_el(C0) = -N0 not solved with C0 positive definite): the prestress is too "
            "large for it"
        )

    def __repr__(self) -> str:
        N0 = self.prestress
        return f"Prestressed({self.material!r}, [{N0[0, 0]}, {N0[1, 1]}, {N0[0, 1]}])"
