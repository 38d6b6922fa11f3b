"""Paths controlled by a scalar equation: the enclosed volume, a gas law, a probe's motion.

Under volume control (``[solver] control = "volume"``) the path parameter t runs from 0 to 1
over the steps, the enclosed volume V(u) is prescribed at each step (from its initial value
to ``volume_ratio`` times it, or to an absolute ``volume``), and the factor mu on the
pressures is the unknown: each step is a bordered solve (``wrinkle.solvers.bordered``) of the
balance and

    c = V(u) - V_target(t, mu) = 0,

with V_target independent of mu, judged by the augmented Lagrangian of the energy
(``VolumeLagrangian``). A gas load (``wrinkle.gas.Gas``) is the same equation with the gas
law's volume at the gauge pressure mu, V_target = V_gas(t, mu) (the load factor t pumps the
gas in), judged by the total energy with the gas's potential (``GasEnergy``). Either way,
the other loads and the prescribed motions grow with t, and a step that fails is cut back
as under load control (``StepController``). As the end of a load-controlled path, the step
to t = 1 from the reference state may take the creep budget (``end_iterations``, rule 7 of
the step controller, docs/solvers.md), and a step that fails is first tried again at the
same increment with that budget, once a level (rule 9): until the gas fills the sheet at
ambient pressure the levels are slack, and the step into the pressurised part creeps as a
solve from the flat sheet does, while a cut-back lands in the regime of a small pressure.

A stop at a probe's displacement (``[solver] stop``) ends any path at the step that reaches
it: that step is solved again from the interpolation of the two states around the crossing,
with c = |d_probe(u)| - d_stop for the step's unknown (``ProbeDisplacement``), and ends the
path there (``PathEnd``).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from wrinkle.gas import Gas
from wrinkle.solvers.base import ConvergenceError, Evaluation, SolverResult
from wrinkle.solvers.bordered import (
    BorderedResult,
    Constraint,
    Family,
    Linearised,
    Merit,
    ProbeDisplacement,
    solve_bordered,
)
from wrinkle.solvers.newton import RegularisedNewton
from wrinkle.solvers.stepping import (
    OnStep,
    StepController,
    SteppedProblem,
    end_iterations,
    extrapolate,
    follow_load_path,
    retry_iterations,
)
from wrinkle.timing import Stopwatch

__all__ = [
    "EnclosedVolume",
    "GasEnergy",
    "LoadFamily",
    "PathEnd",
    "PressureFamily",
    "VolumeLagrangian",
    "VolumeLevels",
    "follow_load_path_to",
    "follow_volume_path",
    "land",
]

logger = logging.getLogger("wrinkle")

_END = 1e-12  # a path parameter within this of 1 is the end of the path


class VolumeLevels(Protocol):
    """What these paths need of a discrete system (``wrinkle.system.DiscreteSystem``)."""

    n_dofs: int

    def at(
        self,
        load_factor: float = 1.0,
        prescribed: np.ndarray | None = None,
        pressure_factor: float | None = None,
    ) -> SteppedProblem: ...

    def load_derivative(self, u: np.ndarray, pressure_only: bool = False) -> np.ndarray: ...

    def enclosed_volume(self, u: np.ndarray) -> float: ...

    def volume_gradient(self, u: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class PathEnd:
    """How a path ended: ``message`` for the summary ("converged to load factor 1", "reached
    the stop ..."), ``complete`` whether it did all it was asked."""

    message: str
    complete: bool = True


@dataclass(frozen=True)
class LoadFamily:
    """R(u, mu) with mu the load factor on every load (arc length, and the landing of a
    load-controlled path at a probe's displacement)."""

    system: VolumeLevels

    def at(self, mu: float) -> SteppedProblem:
        return self.system.at(mu)

    def derivative(self, u: np.ndarray) -> np.ndarray:
        return self.system.load_derivative(u)


@dataclass(frozen=True)
class PressureFamily:
    """R(u, mu) with the other loads at load factor t and mu the factor on the pressures
    (volume control, gas loads)."""

    system: VolumeLevels
    t: float

    def at(self, mu: float) -> SteppedProblem:
        return self.system.at(self.t, pressure_factor=mu)

    def derivative(self, u: np.ndarray) -> np.ndarray:
        return self.system.load_derivative(u, pressure_only=True)


VolumeTarget = Callable[[float], tuple[float, float]]  # mu -> (V_target, dV_target/dmu)


@dataclass(frozen=True)
class EnclosedVolume:
    """c = V(u) - V_target(mu) for the enclosed volume V (``enclosed_volume``). target(mu):
    the volume to enclose and its derivative in mu; scale: the size of the volumes (c within
    tolerance times it is satisfied); least_mu: the smallest mu the target is defined
    above (-inf: all)."""

    system: VolumeLevels
    target: VolumeTarget
    scale: float
    least_mu: float = -np.inf

    def admits(self, mu: float) -> bool:
        return mu > self.least_mu

    def __call__(self, u: np.ndarray, mu: float) -> Linearised:
        volume, slope = self.target(mu)
        return Linearised(
            self.system.enclosed_volume(u) - volume, self.system.volume_gradient(u), -slope
        )


@dataclass
class VolumeLagrangian:
    """The merit of volume control: the augmented Lagrangian of the energy Pi(u) under the
    constraint c = V(u) - V* with the pressure lambda = mu p (p the pressure loads' one
    value) as its multiplier,

        phi = Pi(u) - lambda c + rho/2 c^2 = E(u, mu) + mu p V* + rho/2 c^2,

    E being the evaluation's energy (which holds -mu p V). Along the bordered step,
    dphi = -du.K du - 2 c p dmu - rho c^2; rho grows, where it must, to twice the value
    that makes this negative (Nocedal & Wright, Numerical Optimization, 2006, section 18.3):
    the step then descends phi, and the energy sees, as it does under load control, the
    benefit of lifting a flat sheet out of its plane, which the residual does not."""

    pressure: float
    volume: float
    rho: float = 0.0

    def project(self, u: np.ndarray, mu: float) -> float:
        return mu

    def value(self, ev: Evaluation, u: np.ndarray, mu: float, c: float) -> float:
        if not np.isfinite(ev.energy):
            return np.inf
        return ev.energy + mu * self.pressure * self.volume + 0.5 * self.rho * c * c

    def slope(
        self, ev: Evaluation, c: float, du: np.ndarray, dmu: float, K_du: np.ndarray
    ) -> float | None:
        if not np.isfinite(ev.energy):
            return None
        unpenalised = -float(du @ K_du) - 2.0 * c * self.pressure * dmu
        if c != 0.0 and unpenalised > 0.0:
            self.rho = max(self.rho, 2.0 * unpenalised / (c * c))
        return unpenalised - self.rho * c * c

    def derivative(
        self, ev: Evaluation, lin: Linearised, du: np.ndarray, dmu: float
    ) -> float | None:
        """dphi = (-R + rho c g).du - p c dmu at the point of ev (R its residual, -dE/du)
        and lin (c, g = dV/du)."""
        if not np.isfinite(ev.energy):
            return None
        c = lin.value
        along = 0.0 if lin.gradient is None else float(lin.gradient @ du)
        return -float(ev.residual @ du) + self.rho * c * along - self.pressure * c * dmu


@dataclass(frozen=True)
class GasEnergy:
    """The merit of a gas load: the total potential energy Pi(u) + G(V(u)) with the gas's
    potential G (``wrinkle.gas.Gas.energy``) and the gauge pressure mu eliminated, mu =
    p_gas(V(u)) - p_ambient at every trial point (``project``); the bordered step is then
    Newton's step on this energy, whose tangent holds the gas's stiffness -dp/dV g g^T,
    and its slope is -R.du. Infinite where the volume is not positive (a flat start)."""

    system: VolumeLevels
    gas: Gas
    t: float
    reference_volume: float

    def project(self, u: np.ndarray, mu: float) -> float:
        volume = self.system.enclosed_volume(u)
        return self.gas.pressure(self.t, self.reference_volume, volume) if volume > 0 else np.nan

    def value(self, ev: Evaluation, u: np.ndarray, mu: float, c: float) -> float:
        volume = self.system.enclosed_volume(u)
        if not (volume > 0 and np.isfinite(ev.energy)):
            return np.inf
        return ev.energy + mu * volume + self.gas.energy(self.t, self.reference_volume, volume)

    def slope(
        self, ev: Evaluation, c: float, du: np.ndarray, dmu: float, K_du: np.ndarray
    ) -> float | None:
        return self.derivative(ev, None, du, dmu)

    def derivative(
        self, ev: Evaluation, lin: Linearised | None, du: np.ndarray, dmu: float
    ) -> float | None:
        """-R.du at the point of ev, its pressure the gas's there (``project``)."""
        return -float(ev.residual @ du) if np.isfinite(ev.energy) else None


def _shared(timer: Stopwatch | None) -> Callable[[SteppedProblem], None] | None:
    if timer is None:
        return None

    def share(problem: SteppedProblem) -> None:
        problem.timer = timer

    return share


def land(
    family: Family,
    stop: ProbeDisplacement,
    before: tuple[np.ndarray, float],
    after: tuple[np.ndarray, float],
    solver: RegularisedNewton,
    timer: Stopwatch | None = None,
) -> BorderedResult:
    """The state between two converged ones, before = (u, mu) and after, where the probe's
    displacement is the stop's: a bordered solve from their linear interpolation at the
    crossing of the probe's displacement."""
    d0, d1 = stop.displacement(before[0]), stop.displacement(after[0])
    share = 1.0 if d1 == d0 else min(1.0, max(0.0, (stop.target - d0) / (d1 - d0)))
    u = before[0] + share * (after[0] - before[0])
    mu = before[1] + share * (after[1] - before[1])
    logger.info("landing on the stop: probe displacement %.6g", stop.target)
    return solve_bordered(family, stop, u, mu, solver, _shared(timer))


class _Reached(Exception):
    """Raised from a load-controlled path's step callback at the step that passes the stop."""

    def __init__(self, factor: float, u: np.ndarray):
        super().__init__()
        self.factor, self.u = factor, u


def follow_load_path_to(
    system: VolumeLevels,
    solver: RegularisedNewton,
    controller: StepController,
    stop: ProbeDisplacement,
    on_step: OnStep,
    u0: np.ndarray | None = None,
    timer: Stopwatch | None = None,
    **options,
) -> PathEnd:
    """Load control (``follow_load_path``, ``options`` its keywords) that ends where the
    probe's displacement reaches the stop: the step that passes it is solved again for the
    load factor there (``land``). Returns how the path ended."""
    last: list[tuple[np.ndarray, float]] = [
        (np.zeros(system.n_dofs) if u0 is None else np.array(u0, dtype=float), 0.0)
    ]

    def record(factor: float, u: np.ndarray, solved: SolverResult) -> None:
        if stop.displacement(u) >= stop.target:
            raise _Reached(factor, u)
        last.append((u, factor))
        on_step(factor, u, solved)

    try:
        follow_load_path(system, solver, controller, u0=u0, on_step=record, timer=timer, **options)
    except _Reached as reached:
        landed = land(
            LoadFamily(system), stop, last[-1], (reached.u, reached.factor), solver, timer
        )
        on_step(landed.mu, landed.u, landed)
        return PathEnd(
            f"reached the stop: probe displacement {stop.target:.6g} at load factor {landed.mu:.6g}"
        )
    return PathEnd(
        f"converged to load factor 1 before the probe's displacement reached the stop "
        f"{stop.target:.6g}"
    )


def follow_volume_path(
    system: VolumeLevels,
    solver: RegularisedNewton,
    controller: StepController,
    constraint_at: Callable[[float], tuple[Constraint, Merit | None]],
    on_step: OnStep,
    u0: np.ndarray | None = None,
    mu0: float = 0.0,
    timer: Stopwatch | None = None,
    stop: ProbeDisplacement | None = None,
) -> PathEnd:
    """Volume control or a gas load (module docstring): t from 0 to 1 with the increments of
    ``controller``, each step a bordered solve for (u, mu) with the equation and merit
    ``constraint_at(t)`` (``VolumeLagrangian``, ``GasEnergy``; None: the residual's), from the
    extrapolation of the last two converged states.
    on_step(t, u, solved) after each (solved: a ``BorderedResult`` whose ``mu`` is the
    pressure factor). stop: end where a probe's displacement reaches it. The iteration
    limits of rules 7 and 9 (module docstring). Returns how the path ended; raises
    ConvergenceError (``reached`` set) when a step fails at the smallest increment."""
    u = np.zeros(system.n_dofs) if u0 is None else np.array(u0, dtype=float)
    mu, t = float(mu0), 0.0
    previous: tuple[float, np.ndarray, float] | None = None
    increment = controller.first()
    share = _shared(timer)
    retry = False  # the next try is the step that failed, with the creep budget (rule 9)
    budgeted = False  # whether a try from this level had the creep budget
    while t < 1.0 - _END:
        trial_t = t + increment
        trial_t = 1.0 if trial_t >= 1.0 - _END else trial_t
        start_u, start_mu = u, mu
        if previous is not None:
            before_t, before_u, before_mu = previous
            start_u = extrapolate((before_t, before_u), t, u, trial_t)  # type: ignore[assignment]
            start_mu = mu + (trial_t - t) / (t - before_t) * (mu - before_mu)
        constraint, merit = constraint_at(trial_t)
        if not constraint.admits(start_mu):
            start_mu = mu
        family = PressureFamily(system, trial_t)
        iterations = None
        if trial_t == 1.0 and not np.any(start_u):  # rule 7: the whole path from rest
            iterations = end_iterations(solver, start_u, family.at(start_mu).free)
        elif retry:  # rule 9: the step that failed, again with the creep budget
            iterations = retry_iterations(solver, family.at(start_mu).free, trial_t)
        budgeted, retry = budgeted or iterations is not None, False
        try:
            solved = solve_bordered(
                family, constraint, start_u, start_mu, solver, share, merit, iterations
            )
        except ConvergenceError as error:
            if not budgeted and getattr(solver, "limit_is_default", False):
                retry = True
                continue
            smaller = controller.after_failure(increment)
            if smaller is None:
                failure = ConvergenceError(
                    f"step to path parameter {trial_t:.6g} failed with increment "
                    f"{increment:.3g} (minimum {controller.min_step:.3g}): {error}",
                    error.history,
                )
                failure.reached = t
                raise failure from error
            increment = smaller
            logger.info("step to %.6g failed; increment cut to %.4g", trial_t, increment)
            continue
        if stop is not None and stop.displacement(solved.u) >= stop.target:
            landed = land(family, stop, (u, mu), (solved.u, solved.mu), solver, timer)
            on_step(trial_t, landed.u, landed)
            return PathEnd(
                f"reached the stop: probe displacement {stop.target:.6g} at path parameter "
                f"{trial_t:.6g}"
            )
        previous = (t, u, mu)
        t, u, mu = trial_t, solved.u, solved.mu
        budgeted = False
        logger.info(
            "path parameter %.6g converged in %d iterations (pressure factor %.6g)",
            t,
            solved.iterations,
            mu,
        )
        on_step(t, u, solved)
        increment = controller.after_success(increment, solved.iterations)
    return PathEnd("converged to path parameter 1")
