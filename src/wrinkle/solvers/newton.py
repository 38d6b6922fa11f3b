"""Levenberg-regularised Newton method on the potential energy (the default solver).

Each iteration solves (K + theta M) du = f - f* (docs/method.md section 7) with a sparse direct
solver (``wrinkle.solvers.linear``) and accepts the step by the gain ratio of the potential
energy Pi(u) = sum_e A0 w_relaxed - f.u (- p V for pressure) against its quadratic model,
rho = [Pi(u) - Pi(u + du)] / [r.du - du.K.du / 2]. Where the predicted decrease is at the
level of round-off in Pi (close to convergence), the actual decrease is measured from the
residuals r = f - f* at both ends by the trapezoidal rule,
Pi(u) - Pi(u + du) = int_0^1 r(u + s du).du ds ~ [r(u) + r(u + du)].du / 2, exact for a
quadratic Pi and as precise as the forces, not the total energy. Only where the loads have
no potential is the merit |f - f*|^2, with its Gauss-Newton model. (Before 6 December 2026
that merit took over wherever the energy model predicted less than round-off, a rise
included; it accepts steps towards any equilibrium, a hilltop or saddle of Pi too, and on
an indefinite tangent it predicts no decrease for a strongly regularised step, so that
near convergence a solve could be refused every step.) Near the solution theta falls to a
floor of 1e-14 and the iteration is Newton's, converging quadratically with the consistent
tangent.

The metric M measures the step. With the problem's ``Evaluation.metric`` L (the model gives
the stiffness of a unit tension, a Laplacian on each displacement component, i.e. the H1
seminorm of the step), M = (s_K / s_L) L + 1e-3 s_K I, s being mean diagonals; else M = s_K I.
The identity penalises every nodal motion alike, so that on a fine mesh a theta that tames the
rough motions of a wrinkled region (which has no stiffness across its wrinkles) freezes the
smooth, mesh-wide ones; the Laplacian penalises motions by their strain, like the membrane, and
keeps the number of iterations from growing as fast with the mesh (a trust region in a norm
that reflects the problem's geometry: Conn, Gould & Toint, Trust-Region Methods, SIAM 2000).

A rejected step is not thrown away: 0.3 and then 0.1 of it are tried (an evaluation without
stiffness each, far cheaper than a factorisation on a large mesh) and the first that decreases
the energy by at least 0.1 of its quadratic model's prediction is taken (a sufficient-decrease
test like Armijo's, Nocedal & Wright, Numerical Optimization, 2006, section 3.1); theta has
grown all the same. On the inflated airbag most rejected steps overshoot in the wrinkled band,
and a shortened one is accepted.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from wrinkle.solvers.base import (
    Evaluation,
    Problem,
    RegularisedSolver,
    deferring,
    shifted,
    stiffness_scale,
    try_evaluate,
)
from wrinkle.solvers.linear import Matrix, MatrixSum, diagonal_positions

__all__ = ["RegularisedNewton"]

_THETA_FLOOR = 1e-14
_ROUND_OFF = 1e-12
_IDENTITY_SHARE = 1e-3  # share of the identity in the metric M when the problem gives one
_BACKTRACK = (0.3, 0.1)  # fractions of a rejected step tried before a new factorisation
_SUFFICIENT = 0.1  # least ratio of actual to predicted energy decrease on a shortened step


class RegularisedNewton(RegularisedSolver):
    """Trust-region / Levenberg-regularised Newton on the potential energy."""

    method = "newton"
    default_max_iterations = 100
    #: evaluate the shortened steps of ``backtrack`` with the stiffness (False: without it,
    #: and again with it where one is accepted)
    backtrack_stiffness = True

    def initial_theta(self, K: sp.csr_matrix, free: np.ndarray) -> float:
        self._scale = stiffness_scale(K, free)
        self._metric_scale: float | None = None
        self._shifted: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        return 1e-8

    def regularised(self, ev: Evaluation, theta: float, free: np.ndarray) -> Matrix:
        """K + theta M (module docstring) on K's own pattern; with the problem's metric L a
        ``MatrixSum`` K + theta (s_K / s_L) L + 1e-3 theta s_K I_free, whose entries the
        linear back-end forms where it reads them."""
        K = ev.tangent
        if ev.metric is None:
            return shifted(K, theta * self._scale, free, ev.diagonal)
        positions = ev.diagonal if ev.diagonal is not None else diagonal_positions(K)
        if self._metric_scale is None:
            diagonal = ev.metric[positions[free]]
            mean = float(np.mean(diagonal)) if diagonal.size else 0.0
            self._metric_scale = self._scale / mean if mean > 0.0 else 0.0
        factor, shift = theta * self._metric_scale, _IDENTITY_SHARE * theta * self._scale
        return MatrixSum(K, ev.metric, factor, self._free_diagonal(positions, free, K.nnz), shift)

    def _free_diagonal(self, positions: np.ndarray, free: np.ndarray, nnz: int) -> np.ndarray:
        """The free dofs' diagonal entries flagged among K's nnz values, (nnz,) bool, from the
        diagonal's positions (n_dofs,); made again only for other positions or free dofs."""
        if self._shifted is not None:
            known_positions, known_free, flags = self._shifted
            if (
                known_positions is positions
                and flags.size == nnz
                and np.array_equal(known_free, free)
            ):
                return flags
        flags = np.zeros(nnz, dtype=bool)
        flags[positions[free]] = True
        self._shifted = (positions, free.copy(), flags)
        return flags

    def trial_step(
        self, ev: Evaluation, theta: float, free: np.ndarray
    ) -> tuple[np.ndarray | None, float]:
        """Step and the decrease predicted for the merit in use: the potential energy by its
        quadratic model r.du - du.K.du / 2 (not positive: the step is refused and theta
        grows), or (no potential) |r|^2 by its Gauss-Newton model. From a flat membrane
        under pressure only the energy model sees the benefit of moving out of plane (the
        tangent has no out-of-plane stiffness there)."""
        solve = self.factorise(self.regularised(ev, theta, free), ev.symmetric, free)
        if solve is None:
            return None, 0.0
        step = solve(ev.residual)
        if not np.all(np.isfinite(step)):
            return None, 0.0
        r = ev.residual
        K_step = ev.tangent @ step
        # the energy model along the step, r.du and du.K.du, kept for ``backtrack``
        self._slope, self._curvature = float(r @ step), float(step @ K_step)
        self._step = self._moved = step
        energy_model = self._slope - 0.5 * self._curvature
        self._use_energy = bool(np.isfinite(ev.energy))
        if self._use_energy:
            return step, energy_model
        return step, float(r @ r - np.sum((r - K_step) ** 2))

    def _decrease(
        self,
        ev: Evaluation,
        trial: Evaluation,
        predicted: float,
        direction: np.ndarray,
        fraction: float = 1.0,
    ) -> float:
        """Pi(u) - Pi(u + d) (J), d = fraction x direction the displacement to the trial
        point: from the energies; where the decrease predicted is at round-off in Pi,
        int_0^1 r(u + s d).d ds by the trapezoidal rule from the residuals at both ends
        (exact for a quadratic Pi, and as precise as the forces)."""
        if predicted > _ROUND_OFF * abs(ev.energy):
            return ev.energy - trial.energy
        return 0.5 * fraction * float((ev.residual + trial.residual) @ direction)

    def gain_ratio(self, ev: Evaluation, trial: Evaluation, predicted: float) -> float:
        if self._use_energy:
            actual = self._decrease(ev, trial, predicted, self._moved)
            return actual / predicted if np.isfinite(actual) else -np.inf
        return (ev.residual_norm**2 - trial.residual_norm**2) / predicted

    def backtrack(
        self, problem: Problem, u: np.ndarray, ev: Evaluation, step: np.ndarray
    ) -> tuple[np.ndarray, Evaluation] | None:
        """Fractions of a rejected step (module docstring): (u, evaluation) or None."""
        if not self._use_energy:
            return None
        for fraction in _BACKTRACK:
            predicted = fraction * self._slope - 0.5 * fraction**2 * self._curvature
            if predicted <= 0.0:
                continue
            shorter = u + fraction * step
            # with the stiffness at once: the shortened step is accepted more often than not,
            # and the stiffness adds less to an evaluation than a second evaluation costs
            # (102,400 elements: 0.21 s with it, 0.14 s without); deferred where the problem
            # can, formed only if accepted
            if self.backtrack_stiffness:
                trial = try_evaluate(problem, shorter, **deferring(problem))
            else:
                trial = try_evaluate(problem, shorter, stiffness=False)
            if (
                trial is not None
                and self._decrease(ev, trial, predicted, self._step, fraction)
                >= _SUFFICIENT * predicted
            ):
                if trial.stiffness is not None or trial.later is not None:
                    return shorter, trial.with_stiffness()
                evaluation = try_evaluate(problem, shorter)
                return None if evaluation is None else (shorter, evaluation)
        return None

    def increase(self, theta: float) -> float:
        return max(4.0 * theta, 1e-10)

    def decrease(self, theta: float) -> float:
        return max(0.1 * theta, _THETA_FLOOR)
