"""Independent reference for the wrinkled membrane stress: the relaxed energy.

The relaxed (tension-field) energy of a hyperelastic membrane with energy density ``w(C)`` is

    w_rel(C) = min over symmetric positive semidefinite A of w(C + A)

(A. C. Pipkin, "The relaxed energy density for isotropic elastic membranes", IMA J. Appl.
Math. 36:85-99, 1986; docs/method.md section 4). The minimiser ``A*`` is the "wrinkling strain"
that the fine wrinkles absorb: ``A* = 0`` taut, ``rank A* = 1`` wrinkled, ``rank A* = 2`` slack
(then ``C + A* = C0``, the stress-free state: I, or that of a prestressed material). The
relaxed stress resultant is ``N(C + A*)`` where ``N = 2 dw/dC``; by the envelope theorem it
equals ``2 dw_rel/dC``.

This module finds ``A*`` by brute-force minimisation, without any knowledge of the modified
deformation tensor of Roddeman et al. (1987), and then polishes it to near machine precision
from the optimality conditions of the classified state. It shares no code with
``wrinkle.wrinkling`` and only uses ``material.energy`` and ``material.response``, so it is an
independent check of the element's wrinkling routine.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize, root

from wrinkle.materials.base import Material

__all__ = ["RelaxedState", "relax", "shifted_energy", "stress_free_state"]

_IDENTITY = np.eye(2)


@dataclass
class RelaxedState:
    """Relaxed (tension-field) state of one material point.

    state: "taut", "wrinkled" or "slack".
    energy: relaxed energy w_rel(C) = w(C + A), energy per unit reference area.
    A: (2, 2) optimal wrinkling strain (symmetric positive semidefinite), material frame.
    stress: (2, 2) relaxed stress resultant N(C + A) = 2 dw_rel/dC, force per unit reference
        length, material frame.
    wrinkle_angle: angle phi (radians, in (-pi/2, pi/2]) from material axis 1 of the
        reference-plane unit vector w = (cos phi, sin phi) across which no stress is
        transmitted (stress @ w = 0); None unless wrinkled.
    b: wrinkling amount, A = b w w^T when wrinkled; 0 when taut; trace(I - C) when slack.
    residual: norm of the optimality residual after polishing, force per unit length
        (|N(C + A) w| when wrinkled, |N(I)| when slack, 0 when taut).
    """

    state: str
    energy: float
    A: np.ndarray
    stress: np.ndarray
    wrinkle_angle: float | None
    b: float
    residual: float = 0.0


def _energy(material: Material, C: np.ndarray) -> float:
    """Energy per unit reference area of one (2, 2) C."""
    return float(material.energy(C[None])[0])


def _stress(material: Material, C: np.ndarray) -> np.ndarray:
    """Stress resultant N = 2 dw/dC, (2, 2), of one (2, 2) C."""
    return np.asarray(material.response(C[None], tangent=False).stress[0], dtype=float)


def _lower(params: np.ndarray) -> np.ndarray:
    """Lower-triangular (2, 2) L from params (L11, L21, L22)."""
    return np.array([[params[0], 0.0], [params[1], params[2]]])


def shifted_energy(
    material: Material, C: np.ndarray, params: np.ndarray
) -> tuple[float, np.ndarray]:
    """w(C + L L^T) and its gradient with respect to params = (L11, L21, L22).

    With G = dw/dC (symmetric, G = N/2) and d(L L^T)_kl / dL_ij = d_ki L_lj + L_kj d_li,
    dw/dL_ij = (G L + G^T L)_ij = (N L)_ij, of which the lower triangle is returned.

    C: (2, 2); params: (3,). Returns (energy per unit reference area, (3,) gradient).
    """
    L = _lower(params)
    Cs = C + L @ L.T
    NL = _stress(material, Cs) @ L
    return _energy(material, Cs), np.array([NL[0, 0], NL[1, 0], NL[1, 1]])


def _stiffness_scale(material: Material) -> float:
    """A stiffness (force per unit length) to make tolerances relative: |dN/dE| at C = I."""
    response = material.response(_IDENTITY[None], tangent=True)
    if response.tangent is not None:
        scale = float(np.linalg.norm(response.tangent[0]))
    else:  # secant over a 1 % equibiaxial stretch
        scale = float(np.linalg.norm(_stress(material, 1.02 * _IDENTITY))) / 0.01
    if not np.isfinite(scale) or scale <= 0.0:
        raise ValueError(f"material stiffness scale is {scale}; is the material degenerate?")
    return scale


def stress_free_state(material: Material) -> np.ndarray:
    """The stress-free state C0 (2, 2) of ``material``: the minimiser of w(C) over positive
    definite C = L L^T, by BFGS on (L11, L21, L22) from L = I with the gradient of
    ``shifted_energy`` (C = 0 + L L^T), then polished by ``scipy.optimize.root`` on N(C0) = 0.
    I for an ordinary material; for a prestressed one (w = w_el + N0 : E) the state that the
    prestress relaxes to."""
    scale = _stiffness_scale(material)
    zero = np.zeros((2, 2))

    def objective(params: np.ndarray) -> tuple[float, np.ndarray]:
        value, gradient = shifted_energy(material, zero, params)
        return value / scale, gradient / scale

    result = minimize(
        objective, np.array([1.0, 0.0, 1.0]), jac=True, method="BFGS", options={"gtol": 1e-12}
    )
    L = _lower(result.x)
    start = L @ L.T

    def stress(x: np.ndarray) -> np.ndarray:
        N = _stress(material, np.array([[x[0], x[2]], [x[2], x[1]]]))
        return np.array([N[0, 0], N[1, 1], N[0, 1]]) / scale

    x = root(stress, np.array([start[0, 0], start[1, 1], start[0, 1]]), method="hybr").x
    return np.array([[x[0], x[2]], [x[2], x[1]]])


def _starting_points(C: np.ndarray, C0: np.ndarray) -> list[np.ndarray]:
    """Nonzero starting points (L11, L21, L22); L = 0 is stationary and never used."""
    s = 0.3
    starts = [
        np.array([s, 0.0, s]),  # A ~ I
        np.array([s, 0.0, 0.1 * s]),  # A ~ e1 e1
        np.array([0.1 * s, 0.0, s]),  # A ~ e2 e2
        np.array([s, s, 0.1 * s]),  # A ~ (1, 1)(1, 1)
        np.array([s, -s, 0.1 * s]),  # A ~ (1, -1)(1, -1)
    ]
    eigenvalues, vectors = np.linalg.eigh(C)
    minor = vectors[:, 0]
    root_b = np.sqrt(max(1.0 - eigenvalues[0], 0.01))
    starts.append(np.array([root_b * minor[0], root_b * minor[1], 0.1 * s]))  # isotropic guess
    if np.linalg.eigvalsh(C0 - C)[0] > 0.0:  # slack guess: L L^T = C0 - C
        L = np.linalg.cholesky(C0 - C)
        starts.append(np.array([L[0, 0], L[1, 0], L[1, 1]]))
    return starts


def _minimise(
    material: Material, C: np.ndarray, scale: float, C0: np.ndarray
) -> tuple[np.ndarray, float]:
    """Generic minimisation of w(C + L L^T) from several starts; returns (A, energy)."""

    def objective(params: np.ndarray) -> tuple[float, np.ndarray]:
        value, gradient = shifted_energy(material, C, params)
        return value / scale, gradient / scale

    best_A, best_energy = np.zeros((2, 2)), _energy(material, C)
    for start in _starting_points(C, C0):
        result = minimize(
            objective, start, jac=True, method="BFGS", options={"gtol": 1e-13, "maxiter": 2000}
        )
        L = _lower(result.x)
        energy = _energy(material, C + L @ L.T)
        if np.isfinite(energy) and energy < best_energy:
            best_A, best_energy = L @ L.T, energy
    return best_A, best_energy


def _normalise_angle(phi: float) -> float:
    """Angle of an undirected line, mapped to (-pi/2, pi/2]."""
    phi = float(np.mod(phi + 0.5 * np.pi, np.pi) - 0.5 * np.pi)
    return phi + np.pi if phi <= -0.5 * np.pi else phi


# A polished candidate and whether it meets its conditions exactly (True) or only within the
# tolerance (False: C is within the tolerance of a boundary between states).
_Candidate = tuple[RelaxedState, bool]


def _taut(material: Material, C: np.ndarray, stress_tol: float) -> _Candidate | None:
    """A = 0; admissible when the plain stress has no negative principal value."""
    stress = _stress(material, C)
    smallest = np.linalg.eigvalsh(stress)[0]
    if smallest < -stress_tol:
        return None
    state = RelaxedState("taut", _energy(material, C), np.zeros((2, 2)), stress, None, 0.0)
    return state, bool(smallest >= 0.0)


def _slack(
    material: Material, C: np.ndarray, energy_bound: float, C0: np.ndarray
) -> _Candidate | None:
    """A = C0 - C; admissible when C0 - C is positive semidefinite and w(C0) is the minimum."""
    if np.linalg.eigvalsh(C0 - C)[0] < 0.0:
        return None
    energy = _energy(material, C0)
    if energy > energy_bound:
        return None
    A = C0 - C
    stress = _stress(material, C0)
    residual = float(np.linalg.norm(stress))
    return RelaxedState("slack", energy, A, stress, None, float(np.trace(A)), residual), True


def _wrinkled(
    material: Material, C: np.ndarray, phi0: float, b0: float, scale: float, stress_tol: float
) -> _Candidate | None:
    """A = b w w^T from N(C + b w w^T) w = 0, solved for (phi, b) from (phi0, b0).

    Admissible when the residual is below the tolerance, b > 0 and the uniaxial tension across
    w is non-negative.
    """

    def unit(phi: float) -> np.ndarray:
        return np.array([np.cos(phi), np.sin(phi)])

    def residual(x: np.ndarray) -> np.ndarray:
        w = unit(x[0])
        with np.errstate(all="ignore"):
            return _stress(material, C + x[1] * np.outer(w, w)) @ w / scale

    try:
        solution = root(residual, np.array([phi0, b0]), method="hybr", options={"xtol": 1e-15})
    except ValueError:  # an iterate left the domain of the material (C + A not positive definite)
        return None
    phi, b = float(solution.x[0]), float(solution.x[1])
    if not (np.isfinite(phi) and np.isfinite(b)) or b <= 0.0:
        return None
    w = unit(phi)
    A = b * np.outer(w, w)
    stress = _stress(material, C + A)
    error = float(np.linalg.norm(stress @ w))
    across = np.array([-w[1], w[0]])
    tension = float(across @ stress @ across)
    if not np.isfinite(error) or error > stress_tol or tension < -stress_tol:
        return None
    energy = _energy(material, C + A)
    state = RelaxedState("wrinkled", energy, A, stress, _normalise_angle(phi), b, error)
    return state, tension >= 0.0


def relax(
    material: Material,
    C: np.ndarray,
    rank_tol: float = 1e-6,
    stress_tol: float = 1e-9,
    stress_free: np.ndarray | None = None,
) -> RelaxedState:
    """Relaxed energy, stress and state of one in-plane right Cauchy-Green tensor.

    Implements w_rel(C) = min over positive semidefinite A of w(C + A) (Pipkin 1986,
    "The relaxed energy density for isotropic elastic membranes", IMA J. Appl. Math.
    36:85-99; docs/method.md section 4) for any hyperelastic membrane material:

    1. minimise w(C + L L^T) over lower-triangular L (3 parameters, A = L L^T is then
       positive semidefinite by construction) with BFGS and the analytic gradient
       N(C + L L^T) L (see ``shifted_energy``), from several nonzero starts, keeping the best;
    2. classify the minimiser by the rank of A (eigenvalues above ``rank_tol``);
    3. polish: taut A = 0 (admissible if N(C) >= 0), slack A = C0 - C (C0 = I unless
       ``stress_free`` is given; admissible if C0 - C is positive semidefinite, w(C0) being
       the minimum), wrinkled A = b w w^T with
       w = (cos phi, sin phi) and N(C + b w w^T) w = 0 solved for (phi, b) with
       ``scipy.optimize.root`` from the minimiser's values (admissible if b > 0 and the
       uniaxial tension is >= 0).

    The taut and slack candidates are always checked (they are cheap), the wrinkled one whenever
    the minimiser says rank 1 or neither of the others holds exactly. Of the admissible
    candidates (energy within 1e-10 stiffness of the minimiser's), those meeting their sign
    conditions exactly are preferred, then the lowest energy, then the classified state. This
    keeps the state right also for C within the minimiser's tolerance of a boundary between
    states, where the rank of the minimiser alone is ambiguous and the energies differ by
    less than their rounding.

    material: any ``wrinkle.materials.base.Material``.
    C: (2, 2) in-plane right Cauchy-Green tensor in the material frame (dimensionless).
    rank_tol: eigenvalue of A (dimensionless) above which it counts towards the rank.
    stress_tol: tolerance on stresses, relative to the stiffness |dN/dE| at C = I.
    stress_free: (2, 2) the material's stress-free state C0 where it is not I (a prestressed
        material: ``stress_free_state``); the slack candidate is then A = C0 - C.
    Returns a ``RelaxedState``; raises RuntimeError if no state passes its checks.
    """
    C = np.asarray(C, dtype=float)
    if C.shape != (2, 2) or abs(C[0, 1] - C[1, 0]) > 1e-12 * np.abs(C).max():
        raise ValueError(f"C must be a symmetric (2, 2) array, got {C!r}")
    C = 0.5 * (C + C.T)
    if np.linalg.eigvalsh(C)[0] <= 0.0:
        raise ValueError(f"C must be positive definite, got eigenvalues {np.linalg.eigvalsh(C)}")

    C0 = _IDENTITY if stress_free is None else np.asarray(stress_free, dtype=float)
    scale = _stiffness_scale(material)
    abs_stress_tol = stress_tol * scale
    A_min, energy_min = _minimise(material, C, scale, C0)
    energy_bound = energy_min + 1e-10 * scale

    eigenvalues, vectors = np.linalg.eigh(A_min)
    rank = int(np.sum(eigenvalues > rank_tol))
    if eigenvalues[1] > rank_tol:
        phi0, b0 = float(np.arctan2(vectors[1, 1], vectors[0, 1])), float(eigenvalues[1])
    else:  # isotropic guess: minor principal direction of C
        c_values, c_vectors = np.linalg.eigh(C)
        phi0 = float(np.arctan2(c_vectors[1, 0], c_vectors[0, 0]))
        b0 = max(1.0 - float(c_values[0]), 1e-6)

    taut = _taut(material, C, abs_stress_tol)
    slack = _slack(material, C, energy_bound, C0)
    wrinkled = None
    if rank == 1 or not ((taut is not None and taut[1]) or slack is not None):
        wrinkled = _wrinkled(material, C, phi0, b0, scale, abs_stress_tol)
    by_rank = [taut, wrinkled, slack]
    classified = by_rank[min(rank, 2)]
    admissible = [
        c for c in [classified, *by_rank] if c is not None and c[0].energy <= energy_bound
    ]
    if not admissible:
        raise RuntimeError(
            f"no admissible relaxed state for C = {C.tolist()} (minimiser: A = "
            f"{A_min.tolist()}, energy {energy_min})"
        )
    # exact conditions first, then the lowest energy, then the classified state (listed first)
    return min(admissible, key=lambda c: (not c[1], c[0].energy))[0]
