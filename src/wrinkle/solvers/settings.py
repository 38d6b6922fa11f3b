"""Solver settings: the one place where the nonlinear solver's and the load stepping's
defaults are stated (a case file's ``[solver]`` table, ``Model.solve``'s keywords)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from wrinkle.solvers.base import RegularisedSolver
from wrinkle.solvers.elimination import Elimination
from wrinkle.solvers.linear import LINEAR_SOLVERS
from wrinkle.solvers.newton import RegularisedNewton
from wrinkle.solvers.restricted_step import RestrictedStep
from wrinkle.solvers.stepping import StepController

__all__ = ["CONTROLS", "CONVERGENCE_TESTS", "SOLVERS", "SolverSettings", "make_solver"]

# what steers the path: the load factor, the arc length (the load factor an unknown,
# ``wrinkle.solvers.arc_length``) or the enclosed volume (the pressure an unknown,
# ``wrinkle.solvers.control``)
CONTROLS = ("load", "arc-length", "volume")

# the tests that may end a solve: the residual test alone, or the accuracy stop too
# (``wrinkle.solvers.stopping``) on the finer levels of a mesh sequence
CONVERGENCE_TESTS = ("residual", "accuracy")

SOLVERS: dict[str, type[RegularisedSolver]] = {
    "newton": RegularisedNewton,
    "restricted-step": RestrictedStep,
}


def make_solver(
    method: str = "newton",
    tolerance: float = 1e-6,
    max_iterations: int | None = None,
    linear_solver: str = "auto",
) -> RegularisedSolver:
    """Solver by name: "newton" (default) or "restricted-step"; max_iterations None takes the
    method's default (100 for Newton, 300 for the slower restricted step); linear_solver one of
    ``wrinkle.solvers.linear.LINEAR_SOLVERS`` or "auto"."""
    try:
        cls = SOLVERS[method]
    except KeyError:
        raise ValueError(
            f"unknown solver method {method!r}; choose one of {sorted(SOLVERS)}"
        ) from None
    if linear_solver != "auto" and linear_solver not in LINEAR_SOLVERS:
        raise ValueError(
            f"unknown linear solver {linear_solver!r}; choose auto or one of "
            f"{sorted(LINEAR_SOLVERS)}"
        )
    return cls(tolerance=tolerance, max_iterations=max_iterations, linear_solver=linear_solver)


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _is_integer(value: Any, minimum: int) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= minimum


# the loosest tolerance: a residual of 1 % of the forces (Abaqus' default is 0.5 %). At a
# tolerance of 1 or more every start would pass, the residual at the start being at most the
# applied forces.
MAX_TOLERANCE = 1e-2
# the most load steps a path may aim at: each converged step is a results file, and 10^4 is
# the number of increments of the default min_step already
MAX_STEPS = 10_000
# an arc-length path without a stop ends at load factor 1 within this many times ``steps``
# steps, or fails (its loads have a maximum below their full value)
ARC_LENGTH_STEPS = 10


@dataclass(frozen=True)
class SolverSettings:
    """How a model is solved: the nonlinear method and the load stepping.

    method: "newton" (regularised Newton on the energy) or "restricted-step" (the paper's);
    tolerance: on the residual force relative to the applied and reaction forces and the
    prescribed motion's force scale;
    max_iterations: per load step (None: the method's, 100 or 300); linear_solver: "auto",
    "superlu", "pardiso", "cholmod" or "amg". Load stepping (``StepController``): steps
    (the first increment of the load factor is 1/steps), min_step, max_step (None: 1/steps),
    cutback (factor on the increment after a failed step), growth (factor after an easy
    step), target_iterations (a step converged in at most this many iterations is easy),
    regrow_after (after a cut-back, this many steps in a row converged at the cut increment
    let it grow whatever their iterations; 0: only easy steps do), look_ahead (if the first
    step fails, solve the end of the path first and the levels below it downwards, before
    cutting back); nested: start the first load step from the solution of
    coarser meshes (``Model.solve``'s ``coarse``; a case file makes them from ``[mesh]
    refine`` and ``[mesh] levels``): True, False, or "auto" (the default: on where coarser
    models are given; a case file gives them for ``[mesh] levels``, and for ``[mesh] refine``
    where the sheet has bending stiffness, ``nests``). convergence: "residual", or
    "accuracy" to let the accuracy stop (``wrinkle.solvers.stopping``) end the solves of the
    finer levels of a nested first step, with accuracy_energy (eta, the fraction of the
    discretisation error of the energy that may remain) and accuracy_change (the largest
    remaining change of a probe or reaction, relative to the largest displacement or the
    force scale).
    control: "load" (the load factor grows over the steps), "arc-length" (the load factor
    is an unknown and the path may pass limit points; ``steps`` sets the first increment,
    and is the largest number of steps with ``stop``, ARC_LENGTH_STEPS times it without) or
    "volume" (the enclosed volume goes from its initial value to volume_ratio times it, or
    to the absolute ``volume``, and the pressure is the unknown); stop: (probe name,
    displacement) to end the path where the magnitude of that probe's mean displacement
    reaches the value (any control). Arc length, volume control, gas loads and a stop use
    the Newton method. elimination: nonlinear elimination after each global step of Newton's
    load-controlled solves (``wrinkle.solvers.elimination``; method "newton", control
    "load", a pure membrane: no bending, cables, follower edge loads or gas load).
    Raises ValueError naming the first bad field.
    """

    method: str = "newton"
    tolerance: float = 1e-6
    max_iterations: int | None = None
    linear_solver: str = "auto"
    steps: int = 1
    min_step: float = 1e-4
    max_step: float | None = None
    cutback: float = 0.5
    growth: float = 2.0
    target_iterations: int = 6
    regrow_after: int = 2
    look_ahead: bool = True
    nested: bool | str = "auto"
    convergence: str = "residual"
    accuracy_energy: float = 0.1
    accuracy_change: float = 1e-4
    control: str = "load"
    volume_ratio: float | None = None
    volume: float | None = None
    stop: tuple[str, float] | None = None
    elimination: bool = False

    def __post_init__(self) -> None:
        linear_solvers = ["auto", *LINEAR_SOLVERS]
        rules: list[tuple[str, Callable[[], bool], str]] = [
            ("method", lambda: self.method in SOLVERS, f"one of {sorted(SOLVERS)}"),
            (
                "linear_solver",
                lambda: self.linear_solver in linear_solvers,
                f"one of {linear_solvers}",
            ),
            (
                "tolerance",
                lambda: _is_number(self.tolerance) and 0 < self.tolerance <= MAX_TOLERANCE,
                f"a number in (0, {MAX_TOLERANCE}]",
            ),
            (
                "max_iterations",
                lambda: self.max_iterations is None or _is_integer(self.max_iterations, 1),
                "an integer >= 1",
            ),
            (
                "steps",
                lambda: _is_integer(self.steps, 1) and self.steps <= MAX_STEPS,
                f"an integer in [1, {MAX_STEPS}] (each converged step is written to a file)",
            ),
            (
                "min_step",
                lambda: _is_number(self.min_step) and 0 < self.min_step <= 1,
                "a number in (0, 1]",
            ),
            (
                "max_step",
                lambda: (
                    self.max_step is None
                    or (_is_number(self.max_step) and self.min_step <= self.max_step <= 1)
                ),
                f"a number in [min_step, 1] = [{self.min_step}, 1]",
            ),
            (
                "cutback",
                lambda: _is_number(self.cutback) and 0 < self.cutback < 1,
                "a number in (0, 1)",
            ),
            ("growth", lambda: _is_number(self.growth) and self.growth >= 1, "a number >= 1"),
            (
                "target_iterations",
                lambda: _is_integer(self.target_iterations, 0),
                "an integer >= 0",
            ),
            (
                "regrow_after",
                lambda: _is_integer(self.regrow_after, 0),
                "an integer >= 0",
            ),
            ("look_ahead", lambda: isinstance(self.look_ahead, bool), "true or false"),
            ("elimination", lambda: isinstance(self.elimination, bool), "true or false"),
            (
                "nested",
                lambda: isinstance(self.nested, bool) or self.nested == "auto",
                'true, false or "auto"',
            ),
            (
                "convergence",
                lambda: self.convergence in CONVERGENCE_TESTS,
                f"one of {list(CONVERGENCE_TESTS)}",
            ),
            (
                "accuracy_energy",
                lambda: _is_number(self.accuracy_energy) and 0 < self.accuracy_energy <= 1,
                "a number in (0, 1]",
            ),
            (
                "accuracy_change",
                lambda: (
                    _is_number(self.accuracy_change) and 0 < self.accuracy_change <= MAX_TOLERANCE
                ),
                f"a number in (0, {MAX_TOLERANCE}]",
            ),
            ("control", lambda: self.control in CONTROLS, f"one of {list(CONTROLS)}"),
            (
                "volume_ratio",
                lambda: (
                    self.volume_ratio is None
                    or (_is_number(self.volume_ratio) and self.volume_ratio > 0)
                ),
                "a number > 0",
            ),
            (
                "volume",
                lambda: self.volume is None or (_is_number(self.volume) and self.volume > 0),
                "a number > 0",
            ),
            (
                "stop",
                lambda: (
                    self.stop is None
                    or (
                        isinstance(self.stop, tuple)
                        and len(self.stop) == 2
                        and isinstance(self.stop[0], str)
                        and _is_number(self.stop[1])
                        and self.stop[1] > 0
                    )
                ),
                "(probe name, displacement > 0)",
            ),
        ]
        for name, holds, requirement in rules:
            if not holds():
                raise ValueError(
                    f"solver {name} must be {requirement}, got {getattr(self, name)!r}"
                )
        if self.convergence == "accuracy" and self.nested is False:
            raise ValueError(
                "solver convergence = 'accuracy' needs nested = true: the mesh's discretisation "
                "error is estimated from the solution of the coarser mesh"
            )

        given = [name for name in ("volume_ratio", "volume") if getattr(self, name) is not None]
        if self.control == "volume" and len(given) != 1:
            raise ValueError(
                "solver control = 'volume' needs one of volume_ratio (a multiple of the "
                "initial enclosed volume) and volume (an absolute one)"
            )
        if self.control != "volume" and given:
            raise ValueError(f"solver {given[0]} needs control = 'volume'")
        if (self.control != "load" or self.stop is not None) and self.method != "newton":
            raise ValueError(
                f"solver method = {self.method!r} cannot follow control = {self.control!r} or "
                "a stop: arc length, volume control and stops use method = 'newton'"
            )

        if self.elimination and (self.method != "newton" or self.control != "load"):
            raise ValueError(
                "solver elimination = true needs method = 'newton' and control = 'load', got "
                f"{self.method!r} and {self.control!r}: it works on load-controlled Newton solves"
            )
        if self.elimination and self.convergence == "accuracy":
            raise ValueError(
                "solver elimination = true cannot go with convergence = 'accuracy': a relaxed "
                "step's gain ratio does not show that the quadratic model held, which the "
                "accuracy stop relies on"
            )

    def nests(self, levels: bool, refined: bool, bending: bool) -> bool:
        """Whether a case nests its first step: nested True, or "auto" with ``levels`` given
        or the mesh ``refined`` and the sheet with ``bending``. Nesting pays with bending at
        every size measured (docs/solvers.md, mesh sequencing) and costs more for a pure
        membrane, whose interpolated start has none of the finer mesh's folds."""
        if self.nested == "auto":
            return levels or (refined and bending)
        return bool(self.nested)

    def replace(self, **changes: Any) -> SolverSettings:
        """A copy with some fields changed (values None are ignored); TypeError for a name
        that is not a field."""
        names = {f.name for f in dataclasses.fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise TypeError(f"unknown solver setting {unknown[0]!r} (one of {sorted(names)})")
        given = {key: value for key, value in changes.items() if value is not None}
        return dataclasses.replace(self, **given) if given else self

    def solver(self) -> RegularisedSolver:
        """The nonlinear solver these settings name (with ``elimination``, its
        ``Elimination``)."""
        solver = make_solver(self.method, self.tolerance, self.max_iterations, self.linear_solver)
        if self.elimination:
            solver.elimination = Elimination()
        return solver

    def controller(self) -> StepController:
        """The load-step controller of these settings."""
        return StepController(
            first_step=1.0 / self.steps,
            min_step=self.min_step,
            max_step=1.0 / self.steps if self.max_step is None else self.max_step,
            cutback=self.cutback,
            growth=self.growth,
            target_iterations=self.target_iterations,
            regrow_after=self.regrow_after,
            look_ahead=self.look_ahead,
        )
