"""Arc-length path following (``[solver] control = "arc-length"``): the load factor as an
unknown, through limit points.

Riks' method with a fixed normal plane (Riks, Int. J. Solids Struct. 15, 1979; Crisfield,
Non-linear Finite Element Analysis of Solids and Structures, vol. 1, 1991, section 9.3).
Distances are measured in the scaled norm

    s^2 = |du|^2 / U^2 + dlambda^2,

with U the displacement per unit load factor of the first step, so both parts weigh alike
there. The first step is a load-controlled one (``solve_step``: from a flat sheet its
globalisation is what finds the inflated shape; as the whole path from the reference state it
may take the creep budget of load control's rule 7), cut back while it fails or, for a
membrane that encloses a volume, balances in an unstable state. Each later step predicts
along the secant of the last converged increment, t = (du, dlambda) / s (its direction is
kept through limit points, where dlambda changes sign), to the point at arc length ds, and
corrects on the plane normal to t through that point,

    c(u, lambda) = t_u.(u - u_n) / U^2 + t_lambda (lambda - lambda_n) - ds = 0,

by a bordered solve (``wrinkle.solvers.bordered``). The arc length follows the iterations:
ds_new = ds * sqrt(target / iterations), within [1/2, 2] times ds; a failed step halves it.
The path ends at load factor 1 (the step that passes it is solved again at exactly 1), at a
probe's displacement (``[solver] stop``, the step solved again there), or after the largest
number of steps.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from wrinkle.solvers.base import ConvergenceError, SolverResult, try_evaluate
from wrinkle.solvers.bordered import Linearised, ProbeDisplacement, solve_bordered
from wrinkle.solvers.control import LoadFamily, PathEnd, VolumeLevels, land
from wrinkle.solvers.newton import RegularisedNewton
from wrinkle.solvers.stability import unstable_modes
from wrinkle.solvers.stepping import OnStep, StepController, end_iterations, solve_step
from wrinkle.timing import Stopwatch

__all__ = ["ArcLengthPlane", "LoadFactor", "follow_arc_length"]

logger = logging.getLogger("wrinkle")

_END = 1e-12


@dataclass(frozen=True)
class ArcLengthPlane:
    """Riks' fixed normal plane through the predicted point (module docstring): direction
    (t_u (n_dofs,), t_lambda) of unit scaled norm, the last converged state (u_n, lambda_n),
    U^2 and the arc length ds."""

    direction_u: np.ndarray
    direction_factor: float
    u_n: np.ndarray
    factor_n: float
    scale_u2: float
    length: float

    @property
    def scale(self) -> float:
        return self.length

    def admits(self, mu: float) -> bool:
        return True

    def __call__(self, u: np.ndarray, mu: float) -> Linearised:
        gradient = self.direction_u / self.scale_u2
        value = float(gradient @ (u - self.u_n)) + self.direction_factor * (mu - self.factor_n)
        return Linearised(value - self.length, gradient, self.direction_factor)


@dataclass(frozen=True)
class LoadFactor:
    """c = lambda - target: the landing of an arc-length path at a load factor."""

    target: float

    @property
    def scale(self) -> float:
        return max(abs(self.target), 1.0)

    def admits(self, mu: float) -> bool:
        return True

    def __call__(self, u: np.ndarray, mu: float) -> Linearised:
        return Linearised(mu - self.target, None, 1.0)


def follow_arc_length(
    system: VolumeLevels,
    solver: RegularisedNewton,
    controller: StepController,
    on_step: OnStep,
    max_steps: int,
    u0: np.ndarray | None = None,
    timer: Stopwatch | None = None,
    stop: ProbeDisplacement | None = None,
    describe_load: Callable[[float], str] | None = None,
) -> PathEnd:
    """Arc length (module docstring) from the state u0 (zero) at load factor 0: the first
    step to load factor ``controller.first()`` under load control, then at most
    ``max_steps`` steps in all; the end at load factor 1, or, with ``stop``, only where the
    probe's displacement reaches it. on_step(load_factor, u, solved) after each converged
    step; describe_load(load_factor): the loads in words, for messages. Raises
    ConvergenceError (``reached`` set) where a step fails with the smallest arc length
    (``controller.min_step`` times the first) or, without a stop, where the path has not
    reached load factor 1 in max_steps steps or has come back to load factor 0 (the loads
    have a maximum below their full value: the message gives it)."""
    u = np.zeros(system.n_dofs) if u0 is None else np.array(u0, dtype=float)
    family = LoadFamily(system)
    share = None
    if timer is not None:

        def share(problem) -> None:
            problem.timer = timer

    first, solved = _first_step(system, solver, controller, u, timer)
    if stop is not None and stop.displacement(solved.u) >= stop.target:
        landed = land(family, stop, (u, 0.0), (solved.u, first), solver, timer)
        on_step(landed.mu, landed.u, landed)
        return PathEnd(f"reached the stop: probe displacement {stop.target:.6g}")
    on_step(first, solved.u, solved)
    if stop is None and first >= 1.0 - _END:
        return PathEnd("converged to load factor 1")
    moved = solved.u - u
    scale_u2 = float(moved @ moved) / first**2
    if not scale_u2 > 0.0:
        raise ConvergenceError("arc length: the first step moved nothing", solved.residual_norms)
    length = math.sqrt(2.0) * first
    smallest = controller.min_step * length
    before_u, before_factor = u, 0.0
    u, factor = solved.u, first
    steps = 1
    highest = first
    while steps < max_steps:
        du, dfactor = u - before_u, factor - before_factor
        size = math.sqrt(float(du @ du) / scale_u2 + dfactor**2)
        direction_u, direction_factor = du / size, dfactor / size
        plane = ArcLengthPlane(direction_u, direction_factor, u, factor, scale_u2, length)
        start_u = u + length * direction_u
        start_factor = factor + length * direction_factor
        try:
            solved_step = solve_bordered(family, plane, start_u, start_factor, solver, share)
        except ConvergenceError as error:
            length *= 0.5
            if length < smallest:
                failure = ConvergenceError(
                    f"arc length: the step from load factor {factor:.6g} failed with the "
                    f"smallest arc length {2 * length:.3g}: {error}",
                    error.history,
                )
                failure.reached = factor
                raise failure from error
            logger.info("arc-length step failed; arc length cut to %.4g", length)
            continue
        new_u, new_factor = solved_step.u, solved_step.mu
        if stop is not None and stop.displacement(new_u) >= stop.target:
            landed = land(family, stop, (u, factor), (new_u, new_factor), solver, timer)
            on_step(landed.mu, landed.u, landed)
            return PathEnd(
                f"reached the stop: probe displacement {stop.target:.6g} at load factor "
                f"{landed.mu:.6g}"
            )
        crossing = None  # a state before load factor 1 is passed, and the state past it
        if stop is None and new_factor >= 1.0 - _END > factor:
            crossing = ((u, factor), (new_u, new_factor))
        elif stop is None and before_factor <= factor > new_factor and factor < 1.0 - _END:
            # the load factor peaked between the neighbours of (u, factor): find its maximum,
            # which may carry the full load although no converged point did
            try:
                peak = _peak(family, (before_u, before_factor), (new_u, new_factor), solver, share)
            except ConvergenceError:
                peak = (u, factor)  # not resolved: the largest converged point stands
            highest = max(highest, peak[1])
            if peak[1] >= 1.0 - _END:
                crossing = ((before_u, before_factor), peak)
        if crossing is not None:
            (u_a, f_a), (u_b, f_b) = crossing
            landed = solve_bordered(
                family, LoadFactor(1.0), u_a + (u_b - u_a) * _share_to(f_a, f_b), 1.0, solver, share
            )
            on_step(1.0, landed.u, landed)
            return PathEnd("converged to load factor 1")
        before_u, before_factor = u, factor
        u, factor = new_u, new_factor
        steps += 1
        highest = max(highest, factor)
        if stop is None and factor <= 0.0:
            on_step(factor, u, solved_step)
            raise _short_of_the_end(
                "before the path came back to load factor 0", factor, highest, describe_load
            )
        logger.info(
            "arc-length step %d: load factor %.6g in %d iterations",
            steps,
            factor,
            solved_step.iterations,
        )
        on_step(factor, u, solved_step)
        ratio = math.sqrt(controller.target_iterations / max(solved_step.iterations, 1))
        length *= min(2.0, max(0.5, ratio))
    if stop is not None:
        return PathEnd(
            f"ended after {max_steps} steps (the largest number allowed) at load factor "
            f"{factor:.6g}, before the probe's displacement reached the stop {stop.target:.6g}"
        )
    raise _short_of_the_end(f"in {max_steps} steps", factor, highest, describe_load)


@dataclass(frozen=True)
class ChordPosition:
    """c = d.(u - u_a) / d.d - s: the point at the fraction s of the chord d = u_b - u_a
    between two states, measured along it (displacement control along the chord, the load
    factor free)."""

    u_a: np.ndarray
    chord: np.ndarray
    share: float

    @property
    def scale(self) -> float:
        return 1.0

    def admits(self, mu: float) -> bool:
        return True

    def __call__(self, u: np.ndarray, mu: float) -> Linearised:
        gradient = self.chord / float(self.chord @ self.chord)
        return Linearised(float(gradient @ (u - self.u_a)) - self.share, gradient, 0.0)


def _peak(
    family: LoadFamily,
    before: tuple[np.ndarray, float],
    after: tuple[np.ndarray, float],
    solver: RegularisedNewton,
    share: Callable | None,
) -> tuple[np.ndarray, float]:
    """The state of largest load factor between two converged states on either side of a
    peak: the load factor maximised over the position along their chord (bounded
    golden-section search, ``scipy.optimize.minimize_scalar``; each value a bordered solve
    with ``ChordPosition``, from the last one solved)."""
    (u_a, f_a), (u_b, f_b) = before, after
    chord = u_b - u_a
    last = [u_a + 0.5 * chord, max(f_a, f_b)]
    found: dict[float, tuple[np.ndarray, float]] = {}

    def minus_factor(position: float) -> float:
        solved = solve_bordered(
            family, ChordPosition(u_a, chord, position), last[0], last[1], solver, share
        )
        last[:] = [solved.u, solved.mu]
        found[position] = (solved.u, solved.mu)
        return -solved.mu

    best = minimize_scalar(
        minus_factor, bounds=(0.0, 1.0), method="bounded", options={"xatol": 1e-4}
    )
    return found.get(best.x, max(found.values(), key=lambda state: state[1]))


def _first_step(
    system: VolumeLevels,
    solver: RegularisedNewton,
    controller: StepController,
    u: np.ndarray,
    timer: Stopwatch | None,
) -> tuple[float, SolverResult]:
    """The load-controlled first step from u: its load factor and solve, cut back (by
    ``controller``) while it fails or, for a membrane that encloses a volume, balances in an
    unstable state (``wrinkle.solvers.stability``), which is on another branch than the one
    from the reference state. Where it is the whole path from the reference state, it may
    take the creep budget (``end_iterations``, rule 7 of the step controller)."""
    first = controller.first()
    enclosing = bool(getattr(system, "encloses_volume", False))
    while True:
        problem = system.at(first)
        if timer is not None:
            problem.timer = timer
        # the whole path from the reference state: the creep budget (rule 7)
        whole = first >= 1.0 - _END
        iterations = end_iterations(solver, u, problem.free) if whole else None
        try:
            solved = solve_step(problem, u, solver, iterations=iterations)
            ev = solved.evaluation
            if ev.stiffness is None:
                ev = try_evaluate(problem, solved.u) or ev
            if enclosing and ev.stiffness is not None and unstable_modes(solver, ev, problem.free):
                raise ConvergenceError("the first step balanced in an unstable state", [])
            return first, solved
        except ConvergenceError as error:
            smaller = controller.after_failure(first)
            if smaller is None:
                raise ConvergenceError(
                    f"arc length: the first, load-controlled step failed down to load factor "
                    f"{first:.3g}: {error}",
                    error.history,
                ) from error
            logger.info("arc length: first step to %.6g failed; cut to %.4g", first, smaller)
            first = smaller


def _short_of_the_end(
    when: str,
    factor: float,
    highest: float,
    describe_load: Callable[[float], str] | None,
) -> ConvergenceError:
    """The error of an arc-length path that did not reach load factor 1 ``when``; its
    ``limit_point`` is the largest load factor on the path."""
    load = "" if describe_load is None else f" ({describe_load(highest)})"
    failure = ConvergenceError(
        f"arc length: load factor 1 not reached {when}: the largest load factor on the path "
        f"was {highest:.6g}{load}, and it is now {factor:.6g}; the structure carries no more "
        "than that on this path (a stop at a probe's displacement ends it earlier)",
        [],
    )
    failure.reached = factor
    failure.limit_point = highest
    return failure


def _share_to(factor: float, new_factor: float) -> float:
    """The fraction of a step from ``factor`` to ``new_factor`` at which it passes 1."""
    return (1.0 - factor) / (new_factor - factor)
