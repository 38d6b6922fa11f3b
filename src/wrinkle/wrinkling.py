"""Tension-field wrapper around any membrane material: taut, wrinkled and slack elements.

Roddeman et al. (1987) replace, where the membrane would be compressed, the real deformation F
by the modified deformation F' = (I + beta n1 (x) n1) F (Part II, eq. 12) and fix the wrinkle
direction n1 and the wrinkling strain beta by the conditions that the stress carries nothing
across the wrinkles (Part II, eqs. 31-33). We use the equivalent reference-plane form of
METHOD.md section 4: with w = F^T n1 / |F^T n1| (unit, reference plane) and
b = ((1 + beta)^2 - 1) |F^T n1|^2,

    C' = F'^T F' = C + b w (x) w,        N(C') w = 0,        b >= 0,

two equations for the angle phi of w in the material frame and for b; plane stress (the third
condition, eq. 33) is solved inside the material. The stress that enters the nodal forces is
N(C') itself (the first Piola-Kirchhoff stress is F N(C'), see METHOD.md eq. 11), which is also
the gradient of Pipkin's relaxed energy w(C + b w (x) w).

The consistent tangent follows from the implicit function theorem on the two conditions
(the reference-plane counterpart of Part II, eqs. 34-35): with Voigt strain e' = e + b m(phi),
m = (w1^2/2, w2^2/2, w1 w2), g(e, phi, b) = W(phi) s(e') = N(C') w,

    J = dg/d(phi, b) = [W D' b m' + V s', W D' m],
    dN/dE = D' - D' [b m', m] J^-1 W D'.

States (Part II, section 3; METHOD.md section 5): taut if both principal stresses of the plain
law are >= 0, else wrinkled if the major principal Green-Lagrange strain is > 0, else slack.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrinkle.materials.base import (
    Material,
    green_lagrange_voigt,
    tensor_from_voigt_stress,
    voigt_stress,
)

TAUT, WRINKLED, SLACK = 0, 1, 2
STATE_NAMES = ("taut", "wrinkled", "slack")

_NEWTON_ITERATIONS = 40
_GRID_ANGLES = 72


class WrinklingError(RuntimeError):
    """The wrinkling conditions could not be solved for some elements."""

    def __init__(self, elements: np.ndarray):
        self.elements = elements
        super().__init__(
            f"wrinkling conditions not solved for {elements.size} element(s), "
            f"first: {elements[:5].tolist()}"
        )


@dataclass
class WrinklingResponse:
    """Membrane response with wrinkling, for a batch of n elements (material frame).

    state: (n,) int8, TAUT = 0, WRINKLED = 1, SLACK = 2.
    stress: (n, 2, 2) stress resultant N (force per unit reference length) that enters the
        nodal forces: plain law if taut, N(C + b w w) if wrinkled, zero if slack.
    tangent: (n, 3, 3) consistent dN/dE, Voigt (11, 22, 12); None unless asked for.
    thickness: (n,) current thickness D (reference thickness for slack elements).
    wrinkle_angle: (n,) angle phi of the reference wrinkle direction w = (cos phi, sin phi),
        radians, material frame; 0 where not wrinkled.
    wrinkle_parameter: (n,) b >= 0 of C' = C + b w (x) w; 0 where not wrinkled.
    energy: (n,) relaxed strain energy per unit reference area.
    """

    state: np.ndarray
    stress: np.ndarray
    tangent: np.ndarray | None
    thickness: np.ndarray
    wrinkle_angle: np.ndarray
    wrinkle_parameter: np.ndarray
    energy: np.ndarray


def _symmetric_eigenvalues(T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Minor and major eigenvalues of symmetric (n, 2, 2) tensors."""
    mean = 0.5 * (T[:, 0, 0] + T[:, 1, 1])
    radius = np.hypot(0.5 * (T[:, 0, 0] - T[:, 1, 1]), T[:, 0, 1])
    return mean - radius, mean + radius


def _minor_direction_angle(T: np.ndarray) -> np.ndarray:
    """Angle (radians) of the eigenvector of the smaller eigenvalue of symmetric (n, 2, 2) T."""
    return 0.5 * np.arctan2(2.0 * T[:, 0, 1], T[:, 0, 0] - T[:, 1, 1]) + 0.5 * np.pi


def _direction_vectors(phi: np.ndarray):
    """m(phi), m'(phi) (n, 3) and W(phi), V(phi) (n, 2, 3) of the module docstring."""
    c, s = np.cos(phi), np.sin(phi)
    zero = np.zeros_like(c)
    m = np.stack([0.5 * c * c, 0.5 * s * s, c * s], axis=-1)
    dm = np.stack([-c * s, c * s, c * c - s * s], axis=-1)
    W = np.stack([np.stack([c, zero, s], -1), np.stack([zero, s, c], -1)], axis=1)
    V = np.stack([np.stack([-s, zero, c], -1), np.stack([zero, c, -s], -1)], axis=1)
    return m, dm, W, V


def _solve2(J: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Solve batched 2x2 systems J y = r, (n, 2, 2), (n, 2) -> (n, 2); singular -> nan."""
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        y0 = (J[:, 1, 1] * r[:, 0] - J[:, 0, 1] * r[:, 1]) / det
        y1 = (J[:, 0, 0] * r[:, 1] - J[:, 1, 0] * r[:, 0]) / det
    return np.stack([y0, y1], axis=-1)


def _cauchy_green(e: np.ndarray) -> np.ndarray:
    """C = I + 2E from Voigt Green-Lagrange strain (E11, E22, 2 E12), (n, 3) -> (n, 2, 2)."""
    return tensor_from_voigt_stress(e * np.array([2.0, 2.0, 1.0])) + np.eye(2)


def _modified_tensor(C: np.ndarray, phi: np.ndarray, b: np.ndarray) -> np.ndarray:
    """C' = C + b w (x) w, (n, 2, 2)."""
    w = np.stack([np.cos(phi), np.sin(phi)], axis=-1)
    return C + b[:, None, None] * w[:, :, None] * w[:, None, :]


class Wrinkling:
    """Tension-field (wrinkling) wrapper around a membrane ``Material``.

    ``response(C)`` gives state, stress, consistent tangent and thickness of a batch of
    in-plane right Cauchy-Green tensors C, (n, 2, 2), material frame.
    """

    def __init__(self, material: Material, tolerance: float = 1e-13):
        self.material = material
        self.tolerance = tolerance

    @property
    def thickness(self) -> float:
        return self.material.thickness

    def energy(self, C: np.ndarray) -> np.ndarray:
        """Relaxed strain energy per unit reference area, (n,)."""
        return self.response(C, tangent=False).energy

    def classify(self, C: np.ndarray, plain_stress: np.ndarray) -> np.ndarray:
        """Element states by the paper's criterion (METHOD.md section 5), (n,) int8."""
        state = np.full(C.shape[0], TAUT, dtype=np.int8)
        minor_stress, _ = _symmetric_eigenvalues(plain_stress)
        _, major_stretch = _symmetric_eigenvalues(C)
        compressed = minor_stress < 0.0
        state[compressed] = WRINKLED
        state[compressed & (major_stretch <= 1.0)] = SLACK
        return state

    def response(self, C: np.ndarray, tangent: bool = True) -> WrinklingResponse:
        n = C.shape[0]
        plain = self.material.response(C, tangent=tangent)
        state = self.classify(C, plain.stress)
        stress = plain.stress.copy()
        stiffness = plain.tangent.copy() if tangent else None
        thickness = plain.thickness.copy()
        energy = self.material.energy(C)
        phi = np.zeros(n)
        b = np.zeros(n)

        slack = state == SLACK
        stress[slack] = 0.0
        if tangent:
            stiffness[slack] = 0.0
        thickness[slack] = self.material.thickness
        energy[slack] = 0.0

        wrinkled = np.flatnonzero(state == WRINKLED)
        if wrinkled.size:
            Cw = C[wrinkled]
            phi_w, b_w = self._solve_conditions(Cw, plain.stress[wrinkled])
            modified = self.material.response(_modified_tensor(Cw, phi_w, b_w), tangent=True)
            stress[wrinkled] = modified.stress
            thickness[wrinkled] = modified.thickness
            energy[wrinkled] = self.material.energy(_modified_tensor(Cw, phi_w, b_w))
            phi[wrinkled] = phi_w
            b[wrinkled] = b_w
            if tangent:
                stiffness[wrinkled] = self._wrinkled_tangent(
                    phi_w, b_w, modified.stress, modified.tangent
                )
        return WrinklingResponse(state, stress, stiffness, thickness, phi, b, energy)

    # -- wrinkled state --------------------------------------------------------------------
    def _residual_and_jacobian(self, e: np.ndarray, phi: np.ndarray, b: np.ndarray):
        """g = N(C') w (n, 2), J = dg/d(phi, b) (n, 2, 2), and the modified response."""
        m, dm, W, V = _direction_vectors(phi)
        e_mod = e + b[:, None] * m
        modified = self.material.response(_cauchy_green(e_mod), tangent=True)
        s = voigt_stress(modified.stress)
        D = modified.tangent
        g = np.einsum("nij,nj->ni", W, s)
        WD = np.matmul(W, D)
        J = np.stack(
            [
                np.einsum("nij,nj->ni", WD, b[:, None] * dm) + np.einsum("nij,nj->ni", V, s),
                np.einsum("nij,nj->ni", WD, m),
            ],
            axis=-1,
        )
        return g, J, s

    def _newton(self, e, phi, b, g_tolerance, active):
        """Newton iterations on the wrinkling conditions for rows ``active`` (in place);
        converged where |g| <= g_tolerance (m,) or the step is at round-off."""
        converged = np.zeros(phi.shape[0], dtype=bool)
        idx = np.flatnonzero(active)
        for _ in range(_NEWTON_ITERATIONS):
            if idx.size == 0:
                break
            g, J, _ = self._residual_and_jacobian(e[idx], phi[idx], b[idx])
            step = _solve2(J, -g)
            ok = np.all(np.isfinite(step), axis=1)
            phi[idx[ok]] += step[ok, 0]
            b[idx[ok]] += step[ok, 1]
            small = (np.abs(step[:, 0]) <= 1e-14) & (
                np.abs(step[:, 1]) <= 1e-14 * (1.0 + np.abs(b[idx]))
            )
            small |= np.linalg.norm(g, axis=1) <= g_tolerance[idx]
            done = ok & small
            converged[idx[done]] = True
            idx = idx[ok & ~done]
        return converged

    def _solve_conditions(self, C: np.ndarray, plain_stress: np.ndarray):
        """Angle phi and parameter b of the wrinkled elements, (m,), (m,)."""
        e = green_lagrange_voigt(C)
        # |g| can be no smaller than round-off in E = (C - I)/2 times the stiffness
        stiffness = np.linalg.norm(self.material.response(C, tangent=True).tangent.reshape(-1, 9), axis=1)
        g_tolerance = np.maximum(
            self.tolerance * np.linalg.norm(plain_stress.reshape(-1, 4), axis=1),
            64.0 * np.finfo(float).eps * stiffness,
        )
        # first guess: the direction of the most compressive plain stress (exact for isotropy),
        # and b from the normal condition w.N'.w = 0 linearised at b = 0
        phi = _minor_direction_angle(plain_stress)
        b = self._linearised_b(e, phi)
        converged = self._newton(e, phi, b, g_tolerance, np.ones(phi.shape, dtype=bool))
        valid = converged & self._admissible(e, phi, b, g_tolerance)
        if not np.all(valid):
            # safeguard: global search over the angle for the least relaxed energy, then Newton
            retry = ~valid
            phi[retry], b[retry] = self._angle_search(e[retry])
            converged = self._newton(e, phi, b, g_tolerance, retry)
            valid[retry] = (converged & self._admissible(e, phi, b, g_tolerance))[retry]
            if not np.all(valid):
                raise WrinklingError(np.flatnonzero(~valid))
        phi = np.mod(phi, np.pi)
        return phi, np.maximum(b, 0.0)

    def _linearised_b(self, e: np.ndarray, phi: np.ndarray) -> np.ndarray:
        """b solving w.N(e + b m).w = 0 to first order in b, clipped at 0, (m,)."""
        m, _, _, _ = _direction_vectors(phi)
        plain = self.material.response(_cauchy_green(e), tangent=True)
        s = voigt_stress(plain.stress)
        Dm = np.einsum("nij,nj->ni", plain.tangent, m)
        return np.maximum(-np.sum(m * s, axis=1) / np.sum(m * Dm, axis=1), 0.0)

    def _admissible(self, e, phi, b, g_tolerance) -> np.ndarray:
        """b >= 0 and non-negative uniaxial tension at a solution, (m,) bool."""
        g, _, s = self._residual_and_jacobian(e, phi, b)
        tension = s[:, 0] + s[:, 1]  # trace of the (rank-one) stress
        return (
            (b >= -1e-12)
            & (tension >= -g_tolerance)
            & (np.linalg.norm(g, axis=1) <= 10.0 * g_tolerance)
        )

    def _angle_search(self, e: np.ndarray):
        """Least relaxed energy over a grid of angles (b by 1-D Newton per angle), (m,), (m,)."""
        n = e.shape[0]
        angles = np.linspace(0.0, np.pi, _GRID_ANGLES, endpoint=False)
        phi = np.repeat(angles[None, :], n, axis=0).ravel()
        ee = np.repeat(e, _GRID_ANGLES, axis=0)
        b = self._linearised_b(ee, phi)
        m, _, _, _ = _direction_vectors(phi)
        for _ in range(30):
            r = self.material.response(_cauchy_green(ee + b[:, None] * m), tangent=True)
            s = voigt_stress(r.stress)
            slope = np.sum(m * s, axis=1)
            curvature = np.sum(m * np.einsum("nij,nj->ni", r.tangent, m), axis=1)
            b = np.maximum(b - slope / curvature, 0.0)
        energy = self.material.energy(_cauchy_green(ee + b[:, None] * m))
        energy = energy.reshape(n, _GRID_ANGLES)
        best = np.argmin(energy, axis=1)
        rows = np.arange(n)
        return angles[best], b.reshape(n, _GRID_ANGLES)[rows, best]

    def _wrinkled_tangent(self, phi, b, stress, D) -> np.ndarray:
        """Consistent dN/dE of wrinkled elements (module docstring), (m, 3, 3)."""
        m, dm, W, V = _direction_vectors(phi)
        s = voigt_stress(stress)
        WD = np.matmul(W, D)
        M = np.stack([b[:, None] * dm, m], axis=-1)  # (m, 3, 2)
        DM = np.matmul(D, M)
        J = np.matmul(W, DM)
        J[:, :, 0] += np.einsum("nij,nj->ni", V, s)
        det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
        J_inv = np.stack(
            [np.stack([J[:, 1, 1], -J[:, 0, 1]], -1), np.stack([-J[:, 1, 0], J[:, 0, 0]], -1)],
            axis=1,
        ) / det[:, None, None]
        tangent = D - DM @ J_inv @ WD
        return 0.5 * (tangent + tangent.transpose(0, 2, 1))
