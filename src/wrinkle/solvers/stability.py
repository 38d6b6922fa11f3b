"""Whether a balanced state is stable: the tangent's eigenvalues below a small negative
threshold, counted by the inertia of a factorisation (docs/solvers.md, "Limit points").

Under load control a path can only follow stable states. A state whose tangent has an
eigenvalue well below zero is a saddle of the potential energy: Newton reached it by
jumping past a limit point of the load (an inflated balloon above its largest pressure, whose
octant found a polyhedral state at 12 times its radius), and it is not an answer. Round-off
and the near-zero modes of a wrinkled sheet give eigenvalues close to zero of either sign
(-9 x 10^-6 of the mean diagonal stiffness on the 2,048-element airbag, where the unstable
balloon has -0.06), so only eigenvalues below -UNSTABLE times the mean diagonal count: the
negative eigenvalues of K + UNSTABLE s_K I on the free components, by Sylvester's law of
inertia from its LDL^T factorisation.
"""

from __future__ import annotations

import numpy as np

from wrinkle.solvers.base import Evaluation, RegularisedSolver, shifted, stiffness_scale

__all__ = ["UNSTABLE", "unstable_modes"]

# an eigenvalue of the tangent below -UNSTABLE times its mean diagonal marks an unstable state
UNSTABLE = 1e-3


def unstable_modes(solver: RegularisedSolver, ev: Evaluation, free: np.ndarray) -> int | None:
    """The number of eigenvalues of the tangent of ev (on the free components ``free``,
    (n_dofs,) bool) below -UNSTABLE times its mean diagonal, from one factorisation by the
    solver's linear back-end; None where the tangent is not symmetric (no potential whose
    stability it would measure) or its inertia cannot be had."""
    K = ev.tangent
    if not (ev.symmetric or solver.is_symmetric(K)):
        return None
    A = shifted(K, UNSTABLE * stiffness_scale(K, free), free, ev.diagonal)
    return solver.negative_eigenvalues(A, free)
