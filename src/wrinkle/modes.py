"""Natural frequencies and mode shapes of a converged state (issue 21, item 4).

Small vibrations about a balanced state u solve the generalised eigenproblem on the free
components

    K_ff phi = omega^2 M_ff phi,        f = omega / 2 pi   (Hz when the units are SI)

with K the tangent of the state (``StepProblem.evaluate``: material, geometric, bending and
the follower loads' stiffness) and M the mass matrix of the reference configuration, which
mass conservation makes independent of the deformation: mu = rho t0 is the mass per unit
reference area (density times reference thickness), and for the linear triangle

- consistent: M_e[3a+i, 3b+j] = mu A0 / 12 (1 + delta_ab) delta_ij   (int psi_a psi_b dA0),
- lumped: the row sums of it, mu A0 / 3 on each of the element's nine diagonal entries.

The eigenproblem is solved by shift-invert Lanczos (``scipy.sparse.linalg.eigsh``; Arnoldi,
``eigs``, where the follower loads leave K unsymmetric), the operator (K - sigma M)^-1 applied
by wrinkle's own factorisation (``wrinkle.solvers.linear``: PARDISO for large problems, where
installed, else SuperLU), made once. A slack region has modes of (near) zero stiffness and a
wrinkled one nearly so, so K may be singular: the default shift sigma = -SHIFT lambda_scale
(lambda_scale = mean diag K_ff / mean diag M_ff, the scale of the largest eigenvalues) is
slightly negative, which makes K - sigma M positive definite for a positive semidefinite K,
and close enough to zero that the lowest eigenvalues stay well separated after inversion.

Negative eigenvalues: an eigenvalue below -UNSTABLE lambda_scale (the threshold of
``wrinkle.solvers.stability``) marks an unstable state, which has no vibration about it:
``natural_modes`` raises ValueError. Smaller negative ones (round-off, the near-zero modes of
a wrinkled sheet) are reported as negative frequencies, f = -sqrt(-lambda) / 2 pi.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from wrinkle.assembly import SparsityPattern
from wrinkle.element import KERNEL_BLOCK
from wrinkle.solvers.linear import SymmetryCheck, make_linear_solver
from wrinkle.solvers.stability import UNSTABLE
from wrinkle.threads import blas_threads

if TYPE_CHECKING:
    from wrinkle.model import Model
    from wrinkle.system import DiscreteSystem

__all__ = [
    "DEFAULT_MASS",
    "MASS_KINDS",
    "SHIFT",
    "Modes",
    "consistent_mass",
    "lumped_mass",
    "mass_matrix",
    "natural_modes",
    "solve_eigenproblem",
]

MASS_KINDS = ("consistent", "lumped")
DEFAULT_MASS = "consistent"  # an upper bound on each frequency, converging at second order
# the default shift, relative to lambda_scale (the module docstring)
SHIFT = 1e-10
# at most this many free components: a dense eigensolver (and wherever count >= n_free - 1,
# which ARPACK cannot give)
DENSE_LIMIT = 600
# an eigenvalue whose imaginary part is above this fraction of its modulus is complex
COMPLEX = 1e-6
# ARPACK's tolerance (``eigsh(tol=...)``, its Ritz estimates relative to each eigenvalue of
# the inverted operator; 0 is machine precision): on the tensioned membrane of
# benchmarks/modes.py 42 solves instead of 56 for ten modes, the eigenvalues the same to
# 3e-15 and the eigen-residuals |K phi - lambda M phi| / |K phi| 3.4e-12 (1e-6: 34 solves,
# residuals 1.3e-7)
TOLERANCE = 1e-10
# the most iterative-refinement steps of each PARDISO solve (``Pardiso.refinement``): none,
# unless the factorisation perturbed pivots; None keeps MKL's default of two
PARDISO_REFINEMENT: int | None = 0
# OpenBLAS threads in the Lanczos iterations (threadpoolctl, where installed; None leaves
# them): ARPACK's work is products of a tall (n, ncv) matrix and a vector, and with two
# threads on two cores that another process shares it took 2.4 s instead of 0.3 s, the
# SuperLU solves 0.08 s instead of 0.04 s (benchmarks/modes.py); MKL's threads (PARDISO)
# are left alone
LANCZOS_BLAS_THREADS: int | None = 1

# int psi_a psi_b dA0 / A0 of the linear triangle, spread over the three components
_CONSISTENT = np.kron((np.ones((3, 3)) + np.eye(3)) / 12.0, np.eye(3)).reshape(81)


def consistent_mass(
    pattern: SparsityPattern, area: np.ndarray, mass_per_area: np.ndarray
) -> sp.csr_matrix:
    """Consistent mass matrix (n_dofs, n_dofs) on the stiffness pattern, mass units:
    M_e[3a+i, 3b+j] = mu_e A0_e / 12 (1 + delta_ab) delta_ij; area (n_elements,) reference
    areas A0, mass_per_area (n_elements,) mu = rho t0 (mass per reference area)."""
    data = np.zeros(pattern.nnz)
    element_mass = np.asarray(mass_per_area, dtype=float) * np.asarray(area, dtype=float)
    for start in range(0, pattern.n_elements, KERNEL_BLOCK):
        block = slice(start, min(start + KERNEL_BLOCK, pattern.n_elements))
        pattern.add_to_data(data, block, element_mass[block, None] * _CONSISTENT)
    return pattern.matrix(data)


def lumped_mass(
    pattern: SparsityPattern, area: np.ndarray, mass_per_area: np.ndarray
) -> np.ndarray:
    """Diagonal of the lumped mass matrix (n_dofs,), mass units: a third of mu_e A0_e to each
    of the element's nodes in each component (the row sums of ``consistent_mass``)."""
    third = np.asarray(mass_per_area, dtype=float) * np.asarray(area, dtype=float) / 3.0
    return pattern.assemble_vector(np.repeat(third, 9).reshape(-1, 9))


def mass_matrix(
    pattern: SparsityPattern, area: np.ndarray, mass_per_area: np.ndarray, kind: str
) -> sp.csr_matrix:
    """The mass matrix of ``kind`` ("consistent" or "lumped"), CSR (n_dofs, n_dofs)."""
    if kind == "consistent":
        return consistent_mass(pattern, area, mass_per_area)
    if kind == "lumped":
        return sp.diags(lumped_mass(pattern, area, mass_per_area)).tocsr()
    raise ValueError(f"unknown mass '{kind}' (one of {', '.join(MASS_KINDS)})")


@dataclass(frozen=True)
class Modes:
    """Natural modes of a state, lowest first (nearest the shift where one is given).

    frequencies: (k,) f = omega / 2 pi, 1/time (Hz in SI units), ascending; negative for a
    round-off-level negative eigenvalue (module docstring). eigenvalues: (k,) omega^2,
    1/time^2. shapes: (k, n_dofs) mass-normalised (phi^T M phi = 1), zero at the constrained
    components. residuals: (k,) |K phi - omega^2 M phi| / (|K phi| + |omega^2 M phi|) on the
    free components. mass: "consistent" or "lumped"; shift: sigma, 1/time^2.
    """

    frequencies: np.ndarray
    eigenvalues: np.ndarray
    shapes: np.ndarray
    residuals: np.ndarray
    mass: str
    shift: float

    def __len__(self) -> int:
        return int(self.frequencies.size)


def solve_eigenproblem(
    K: sp.csr_matrix,
    M: sp.csr_matrix,
    count: int,
    symmetric: bool,
    shift: float | None = None,
    linear_solver: str = "auto",
) -> tuple[np.ndarray, np.ndarray, float]:
    """Eigenpairs of K phi = lambda M phi, (n, n) CSR each, M symmetric positive definite:
    the ``count`` lowest (shift None) or the ``count`` nearest the shift sigma; returns the
    eigenvalues (count,) ascending, the vectors (n, count) M-normalised and the shift used
    (default -SHIFT mean diag K / mean diag M).

    Shift-invert with (K - sigma M)^-1 from one factorisation by ``linear_solver`` (ARPACK
    at the tolerance TOLERANCE; PARDISO with PARDISO_REFINEMENT refinement steps); dense
    for at most DENSE_LIMIT unknowns or count >= n - 1. Shift-invert finds the eigenvalues
    nearest sigma, which are the lowest only if none lies below it: for a symmetric K the
    inertia of the same factorisation counts those below (Sylvester), and that many more
    are asked for, so that the lowest ``count`` are among them. ValueError if some of them
    are not found (large negative eigenvalues: an unstable state), for a complex eigenvalue
    (an unsymmetric K with flutter) or a singular K - sigma M.
    """
    n = K.shape[0]
    if not 1 <= count <= n:
        raise ValueError(f"mode count {count} must be between 1 and the {n} free components")
    scale = float(np.mean(np.abs(K.diagonal()))) / float(np.mean(M.diagonal()))
    sigma = -SHIFT * scale if shift is None else float(shift)
    below: int | None = None
    if n <= DENSE_LIMIT or count >= n - 1:
        Kd, Md = K.toarray(), M.toarray()
        if symmetric:
            values, vectors = la.eigh(Kd, Md)
        else:
            values, vectors = la.eig(Kd, Md)
        if shift is not None:
            nearest = np.argsort(np.abs(values - sigma), kind="stable")[:count]
        else:
            nearest = np.argsort(values.real, kind="stable")[:count]
        values, vectors = values[nearest], vectors[:, nearest]
    else:
        linear = make_linear_solver(linear_solver, n, one_off=True)
        if hasattr(linear, "refinement"):
            linear.refinement = PARDISO_REFINEMENT
        try:
            shifted = (K - sigma * M).tocsr()
            shifted.sort_indices()
            with_inertia = getattr(linear, "factorise_with_inertia", None)
            if symmetric and with_inertia is not None:
                solve, below = with_inertia(shifted)
            else:
                solve = linear.factorise(shifted, symmetric)
            if solve is None:
                raise ValueError(
                    f"K - sigma M is singular at the shift sigma = {sigma:.6g}: give another shift"
                )
            wanted = count + (below or 0) if shift is None else count
            if wanted >= n - 1:
                raise ValueError(
                    f"the tangent has {below} eigenvalues below the shift {sigma:.6g}: too "
                    f"many to find the {count} lowest of {n} by shift-invert"
                )
            inverse = spla.LinearOperator((n, n), matvec=solve, dtype=float)
            arpack = spla.eigsh if symmetric else spla.eigs
            with blas_threads(LANCZOS_BLAS_THREADS):
                values, vectors = arpack(
                    K, wanted, M, sigma=sigma, which="LM", OPinv=inverse, tol=TOLERANCE
                )
        finally:
            linear.release()
    if np.iscomplexobj(values):
        imaginary = np.abs(values.imag) > COMPLEX * np.maximum(np.abs(values), 1e-300)
        if np.any(imaginary):
            first = values[np.flatnonzero(imaginary)[0]]
            raise ValueError(
                f"the tangent has a complex eigenvalue {first:.6g} (the follower load's "
                "unsymmetric stiffness: a flutter instability): the state has no real modes"
            )
        values, vectors = values.real, vectors.real
    if below is not None and shift is None:
        found = int(np.count_nonzero(values < sigma))
        if found < below:
            raise ValueError(
                f"the tangent has {below} eigenvalue(s) below the shift {sigma:.6g}, and "
                f"only {found} of them near it: the state is unstable"
            )
    order = np.argsort(values, kind="stable")[:count]
    values, vectors = values[order], vectors[:, order]
    norms = np.sqrt(np.abs(np.einsum("ik,ik->k", vectors, M @ vectors)))
    return values, vectors / norms, sigma


def natural_modes(
    model: Model,
    u: np.ndarray,
    count: int,
    *,
    load_factor: float = 1.0,
    pressure_factor: float | None = None,
    mass: str = DEFAULT_MASS,
    shift: float | None = None,
    linear_solver: str = "auto",
    system: DiscreteSystem | None = None,
) -> Modes:
    """The ``count`` lowest natural modes of ``model`` about the balanced state u (n_dofs,)
    at ``load_factor`` (and ``pressure_factor``, default the load factor), with the mass
    of ``mass`` ("consistent", the default, or "lumped") from the materials' densities
    (``Model.assign_material(density=...)``). shift: sigma (1/time^2) to find the modes
    nearest omega^2 = sigma instead of the lowest. ValueError for an element without a
    density, a count outside 1 .. free components, a gas load (its stiffness is not in the
    tangent), an unstable state (an eigenvalue below -UNSTABLE lambda_scale) or a complex
    eigenvalue. system: the discrete system on whose path u lies (default the model's;
    ``Results.system_of``)."""
    if mass not in MASS_KINDS:
        raise ValueError(f"unknown mass '{mass}' (one of {', '.join(MASS_KINDS)})")
    if model.gas is not None:
        raise ValueError(
            "modes: a model with a gas load is not supported (the gas's stiffness, from the "
            "pressure's change with the enclosed volume, is not in the tangent)"
        )
    if isinstance(count, bool) or int(count) != count:
        raise ValueError(f"mode count must be an integer, got {count!r}")
    system = model.discretise() if system is None else system
    free = ~system.constrained
    n_free = int(np.count_nonzero(free))
    if not 1 <= count <= n_free:
        raise ValueError(
            f"mode count {count} must be between 1 and the model's {n_free} free components"
        )
    mu = model.mass_per_area()
    problem = system.at(load_factor, pressure_factor=pressure_factor)
    evaluation = problem.evaluate(np.asarray(u, dtype=float))
    K = evaluation.tangent
    symmetric = evaluation.symmetric or SymmetryCheck()(K)
    M = mass_matrix(system.pattern, system.geometry.area, mu, mass)
    if system.cables is not None:
        M = M + system.cables.mass_matrix(mass, system.n_dofs)
    K_ff = K[free][:, free].tocsr()
    M_ff = M[free][:, free].tocsr()
    values, vectors, sigma = solve_eigenproblem(
        K_ff, M_ff, int(count), symmetric, shift, linear_solver
    )
    scale = float(np.mean(np.abs(K_ff.diagonal()))) / float(np.mean(M_ff.diagonal()))
    if values[0] < -UNSTABLE * scale:
        raise ValueError(
            f"modes: the state is unstable: the tangent has the eigenvalue omega^2 = "
            f"{values[0]:.6g} (below -{UNSTABLE:g} of its scale {scale:.3g}); it has no "
            "vibration about it"
        )
    stiffness_part = K_ff @ vectors
    mass_part = (M_ff @ vectors) * values
    residuals = np.linalg.norm(stiffness_part - mass_part, axis=0) / np.maximum(
        np.linalg.norm(stiffness_part, axis=0) + np.linalg.norm(mass_part, axis=0), 1e-300
    )
    shapes = np.zeros((values.size, system.n_dofs))
    shapes[:, free] = vectors.T
    frequencies = np.sign(values) * np.sqrt(np.abs(values)) / (2.0 * math.pi)
    return Modes(frequencies, values, shapes, residuals, mass, sigma)
