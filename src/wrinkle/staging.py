"""Analysis steps: a load history in stages, each a proportional path from the end of the last.

A staged analysis (a case's ``[[step]]`` tables, docs/case-file.md) is a sequence of
``AnalysisStep``: in each, the loads and supports it names by their labels grow from their
values at the end of the step before to their own values, along a load factor from 0 to 1,
while the others keep theirs (zero before the first step that names them). Step k's path is
L(lambda) = L_(k-1) + lambda (L_k - L_(k-1)) (``wrinkle.system.DiscreteSystem.along``), solved
by ``Model.solve(start=..., loads=..., supports=...)`` from the displacement where step k - 1
ended; its own solver settings choose the path follower and the increments. Where the
problem has a potential (a hyperelastic membrane under dead loads and a pressure on a closed
or held surface) and one equilibrium, the end state does not depend on the path: inflating a
tube, then bending it, ends where doing both at once ends.

``solve_steps`` runs the steps and gathers their converged states into one ``Results``, each
state knowing its analysis step (``StepResult.analysis_step``, ``time`` = step - 1 + load
factor); ``restart_point`` finds where a staged run written by ``wrinkle run`` continues.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from wrinkle.results import Results, StepResult
from wrinkle.solvers.base import ConvergenceError
from wrinkle.solvers.control import PathEnd
from wrinkle.solvers.settings import SolverSettings
from wrinkle.solvers.stepping import Resume, StepController
from wrinkle.system import LoadState, StepStart

if TYPE_CHECKING:
    from wrinkle.model import Model

__all__ = ["AnalysisStep", "restart_point", "solve_steps", "state_after"]

_END = 1e-12  # a load factor within this of 1 is the end of a step's path


@dataclass(frozen=True)
class AnalysisStep:
    """One analysis step: its name, the labels of the loads and of the supports that grow in
    it, and the solver settings of its path."""

    name: str
    loads: tuple[str, ...] = ()
    supports: tuple[str, ...] = ()
    settings: SolverSettings = SolverSettings()


def state_after(model: Model, steps: Sequence[AnalysisStep], count: int) -> LoadState:
    """The loads and supported values at the end of the first ``count`` steps (the reference
    state for 0), built step by step as the run builds them: where two supports hold a
    component, the one named later sets it."""
    state = model.load_state([], [])
    zero = np.zeros(model.n_dofs)  # (the components held do not change between the steps)
    for number, step in enumerate(steps[:count]):
        start = StepStart(state, zero, number) if number else None
        state = model.load_state(step.loads, step.supports, start)
    return state


def solve_steps(
    model: Model,
    steps: Sequence[AnalysisStep],
    on_step: Callable[[StepResult], None] | None = None,
    probes: Mapping[str, np.ndarray] | None = None,
    first: int = 0,
    start: StepStart | None = None,
    resume: Resume | None = None,
    **options: Any,
) -> Results:
    """Solve ``steps[first:]`` in turn (``Model.solve`` with each step's settings and
    ``options`` over them), the first from ``start`` (None: the reference state) and, with
    ``resume``, continuing its path from there; returns their converged states in one
    ``Results``. A ConvergenceError carries all the states converged before it in its
    ``results``; a step whose path stops short of its end (load factor 1) ends the analysis
    with a ConvergenceError too, as the next cannot start."""
    gathered: Results | None = None
    for index in range(first, len(steps)):
        step = steps[index]
        try:
            results = model.solve(
                step.settings,
                on_step=on_step,
                probes=probes,
                start=start,
                loads=step.loads,
                supports=step.supports,
                resume=resume if index == first else None,
                **options,
            )
        except ConvergenceError as error:
            partial = getattr(error, "results", None)
            if gathered is not None and partial is not None:
                gathered.extend(partial)
                error.results = gathered
            raise
        if gathered is None:
            gathered = results
        else:
            gathered.extend(results)
        if index + 1 < len(steps):
            try:
                start = results.step_start()
            except ValueError as error:
                failure = ConvergenceError(
                    f"analysis step {index + 1} ({step.name!r}): {error}; the steps after it "
                    "were not solved",
                    [],
                )
                failure.results = gathered
                raise failure from None
    if gathered is None:
        raise ValueError("analysis steps: there is no step to solve")
    end = gathered.end or PathEnd("converged to load factor 1")
    gathered.end = PathEnd(
        f"{end.message} of analysis step {len(steps)} ({steps[-1].name!r}), the last",
        end.complete,
    )
    return gathered


def restart_point(
    model: Model,
    steps: Sequence[AnalysisStep],
    saved: Sequence[Mapping[str, Any]],
    displacement: Callable[[int], np.ndarray],
    **options: Any,
) -> tuple[int, StepStart | None, Resume | None]:
    """Where a staged run continues from its converged states ``saved`` (the summary's
    steps, each with "analysis_step", "load_factor" and "iterations"; ``displacement(i)``
    the displacement of saved[i]): the index of the first analysis step to solve, the start
    of that step and, in the middle of its path, the ``Resume`` of the path (None at its
    start). ValueError if the run had ended, or a saved state names no analysis step of
    these."""
    last = saved[-1]
    number = int(last.get("analysis_step", 1))
    if not 1 <= number <= len(steps):
        raise ValueError(f"its last step is of analysis step {number}, which the case has not")
    factor = float(last["load_factor"])
    u = displacement(len(saved) - 1)
    if factor >= 1.0 - _END:
        if number == len(steps):
            raise ValueError(
                "that run reached load factor 1 of its last analysis step: nothing to continue"
            )
        return number, StepStart(state_after(model, steps, number), u, number), None
    same = [i for i, entry in enumerate(saved) if int(entry.get("analysis_step", 1)) == number]
    before = [i for i, entry in enumerate(saved) if int(entry.get("analysis_step", 1)) < number]
    start_u = displacement(before[-1]) if before else np.zeros(model.n_dofs)
    start = None
    if number > 1:
        start = StepStart(state_after(model, steps, number - 1), start_u, number - 1)
    if len(same) > 1:
        previous = (float(saved[same[-2]]["load_factor"]), displacement(same[-2]))
    else:
        previous = (0.0, start_u)
    settings = steps[number - 1].settings.replace(**options)
    controller = last.get("controller")
    if controller is None:  # a folder written before the state was saved
        controller = saved_controller(settings.controller(), [saved[i] for i in same])
    return number - 1, start, Resume(factor, u, previous, controller)


def saved_controller(
    controller: StepController, levels: Sequence[Mapping[str, Any]]
) -> dict[str, Any]:
    """The step controller's state after the last of a path's converged ``levels`` (each
    with "load_factor" and "iterations"), for a folder that does not hold it: the last
    increment grown by ``after_success``, counting the levels before it at the same
    increment as steps in a row (a failed step between them cannot be seen)."""
    increments = np.diff([0.0, *(float(level["load_factor"]) for level in levels)])
    in_a_row = 1
    while in_a_row < increments.size and np.isclose(
        increments[-1 - in_a_row], increments[-1], rtol=1e-9, atol=0.0
    ):
        in_a_row += 1
    last = float(increments[-1])
    increment = controller.after_success(last, int(levels[-1]["iterations"]), in_a_row)
    return {"increment": increment, "in_a_row": 0 if increment != last else in_a_row}
