"""The paper's restricted-step method (Roddeman et al. 1987, Part II, eq. 45).

Each iteration minimises the linearised residual |f - f* - K du|^2 with a penalty on |du|:
(2 K^T K + theta I) du = 2 K^T (f - f*). For symmetric K this is
du = Re[(K - i mu I)^-1 (f - f*)] with mu^2 = theta / 2 (docs/method.md section 7), so one complex
LU of a matrix with K's own sparsity replaces the much denser K^T K (with follower loads K is
not symmetric and K^T K is formed). theta follows Fletcher's
rules (Practical Methods of Optimization, vol. 1, 1980, section 5.2): the gain ratio
rho = (|r|^2 - |r_new|^2) / (|r|^2 - |r - K du|^2); theta * 4 if rho < 0.25, theta / 2 if
rho > 0.75, and theta set to its floor once it falls below a critical value so that the
iteration ends as Newton's; the step is taken if rho > 0.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from wrinkle.solvers.base import Evaluation, RegularisedSolver, shifted, stiffness_scale

__all__ = ["RestrictedStep"]

_CRITICAL = 1e-8  # relative mu below which theta drops to the floor (Fletcher's nu_c)
_FLOOR = 1e-12  # relative mu at the floor


class RestrictedStep(RegularisedSolver):
    """Restricted-step (Levenberg-Marquardt) iteration on the residual norm."""

    method = "restricted-step"
    default_max_iterations = 300
    # its merit |r|^2 is not smooth where elements change state; from the linear-elastic
    # prediction of a flat sheet pulled at one node it stalls at a residual of 1e-4 of the
    # force scale (tests/test_solvers.py), while from the moved supports alone it converges
    tangent_predictor = False

    def initial_theta(self, K: sp.csr_matrix, free: np.ndarray) -> float:
        self._scale = stiffness_scale(K, free)
        return 2.0 * (1e-3 * self._scale) ** 2

    def trial_step(
        self, ev: Evaluation, theta: float, free: np.ndarray
    ) -> tuple[np.ndarray | None, float]:
        r = ev.residual
        K = ev.tangent
        solve: Callable[[np.ndarray], np.ndarray] | None
        if ev.symmetric:
            mu = np.sqrt(theta / 2.0)
            complex_solve = self.factorise(shifted(K, -1j * mu, free, ev.diagonal), True, free)
            if complex_solve is None:
                return None, 0.0
            factorised = complex_solve

            def solve(rhs: np.ndarray) -> np.ndarray:
                return factorised(rhs.astype(complex)).real

            rhs = r
        else:  # follower loads: form 2 K^T K (denser) as the paper does
            normal = (K.T @ K).tocsr()
            normal.sort_indices()
            solve = self.factorise(shifted(normal, theta / 2.0, free), True, free)
            rhs = K.T @ r
        if solve is None:
            return None, 0.0
        step = solve(rhs)
        if not np.all(np.isfinite(step)):
            return None, 0.0
        predicted = float(r @ r - np.sum((r - K @ step) ** 2))
        return step, predicted

    def gain_ratio(self, ev: Evaluation, trial: Evaluation, predicted: float) -> float:
        return (ev.residual_norm**2 - trial.residual_norm**2) / predicted

    def increase(self, theta: float) -> float:
        return max(4.0 * theta, 2.0 * (_CRITICAL * self._scale) ** 2)

    def decrease(self, theta: float) -> float:
        theta = 0.5 * theta
        if theta < 2.0 * (_CRITICAL * self._scale) ** 2:
            theta = 2.0 * (_FLOOR * self._scale) ** 2
        return theta
