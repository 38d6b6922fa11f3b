"""Levenberg-regularised Newton method on the potential energy (the default solver).

Each iteration solves (K + theta I) du = f - f* (METHOD.md section 7) with a sparse direct
solver (``wrinkle.solvers.linear``) and
accepts the step by the gain ratio of the potential energy Pi(u) = sum_e A0 w_relaxed - f.u
(- p V for pressure) against its quadratic model, rho = [Pi(u) - Pi(u + du)] / [r.du -
du.K.du / 2]. Where the decrease is at the level of round-off in Pi (close to convergence), or
the loads have no potential, the merit is |f - f*|^2 with its Gauss-Newton model instead. Near the solution
theta falls to a floor of 1e-14 times the mean diagonal stiffness and the iteration is Newton's,
converging quadratically with the consistent tangent.
"""

from __future__ import annotations

import numpy as np

from wrinkle.solvers.base import Evaluation, RegularisedSolver, shifted, stiffness_scale

_THETA_FLOOR = 1e-14
_ROUND_OFF = 1e-12


class RegularisedNewton(RegularisedSolver):
    """Trust-region / Levenberg-regularised Newton on the potential energy."""

    method = "newton"
    default_max_iterations = 100

    def initial_theta(self, K, free) -> float:
        self._scale = stiffness_scale(K, free)
        return 1e-8

    def trial_step(self, ev: Evaluation, theta: float, free: np.ndarray):
        """Step and the decrease predicted for the merit in use: the potential energy by its
        quadratic model, or (no potential, or a decrease at round-off) |r|^2 by its
        Gauss-Newton model. From a flat membrane under pressure only the energy model sees the
        benefit of moving out of plane (the tangent has no out-of-plane stiffness there)."""
        solve = self.factorise(shifted(ev.stiffness, theta * self._scale, free, ev.diagonal),
                               ev.symmetric)
        if solve is None:
            return None, 0.0
        step = solve(ev.residual)
        if not np.all(np.isfinite(step)):
            return None, 0.0
        r = ev.residual
        K_step = ev.stiffness @ step
        energy_model = float(r @ step - 0.5 * step @ K_step)
        self._use_energy = np.isfinite(ev.energy) and energy_model > _ROUND_OFF * abs(ev.energy)
        if self._use_energy:
            return step, energy_model
        return step, float(r @ r - np.sum((r - K_step) ** 2))

    def gain_ratio(self, ev: Evaluation, trial: Evaluation, predicted: float) -> float:
        if self._use_energy:
            actual = ev.energy - trial.energy
            return actual / predicted if np.isfinite(actual) else -np.inf
        return (ev.residual_norm**2 - trial.residual_norm**2) / predicted

    def increase(self, theta: float) -> float:
        return max(10.0 * theta, 1e-10)

    def decrease(self, theta: float) -> float:
        return max(0.001 * theta, _THETA_FLOOR)
