"""The results of a solve: the converged load steps, in order (``Results``, ``StepResult``)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from wrinkle.modes import Modes, natural_modes
from wrinkle.output import save_results
from wrinkle.solvers.base import SolverResult
from wrinkle.solvers.control import PathEnd
from wrinkle.system import DiscreteSystem, LoadState, StepStart
from wrinkle.timing import Stopwatch

if TYPE_CHECKING:
    from wrinkle.model import Model

__all__ = ["Results", "StepResult"]


@dataclass
class StepResult:
    """One converged load step: load factor, displacements (n_dofs,), solver information.

    reactions: (n_dofs,) internal minus external force, nonzero at the supports (force);
    states: (taut, wrinkled, slack) element counts; stopped_by: the test that ended the
    solve, "residual" or "accuracy" (``wrinkle.solvers.stopping``), with stop_report the
    numbers the accuracy stop decided on; pressure: the current value of the pressure loads
    (their value times the load factor, or times the pressure factor that volume control
    and gas loads solve for; None without pressure); enclosed_volume: the volume the
    pressurised membrane encloses (``DiscreteSystem.enclosed_volume``), where it is closed
    or closed by symmetry planes, else None; residual_history: the residual norm (force) of
    each iteration of the step's converged solve, the first at its start; analysis_step: the
    number of the analysis step (``[[step]]``, from 1) whose path the load factor is on;
    pressure_factor: the factor on its pressures (the load factor but under volume control
    and gas loads); controller: the step controller's state after it, where a load path
    solved it (``SolverResult.path_state``), which a restart continues from.
    """

    load_factor: float
    displacement: np.ndarray
    iterations: int
    residual: float
    reactions: np.ndarray
    states: tuple[int, int, int]
    stopped_by: str = "residual"
    stop_report: dict[str, Any] | None = None
    pressure: float | None = None
    enclosed_volume: float | None = None
    residual_history: tuple[float, ...] = ()
    analysis_step: int = 1
    pressure_factor: float | None = None
    controller: dict[str, Any] | None = None

    @property
    def time(self) -> float:
        """The total time of a staged analysis, each analysis step lasting 1: the analysis
        step's number minus 1 plus the load factor (Abaqus's total time)."""
        return self.analysis_step - 1 + self.load_factor


class Results:
    """Converged load steps of a model, in order.

    probes ({name: node indices}) and units ({"length": "m", ...}) go into the files that
    ``save`` writes; source: the case file the model came from, if any (``Case.solve`` sets
    the three). system: the discrete system of the path solved (default the model's);
    analysis_step: its number in a staged analysis; end_state: the loads and supported
    values at its end (``Model.load_state``), where a next analysis step starts
    (``step_start``). ``systems`` holds each analysis step's system by its number.
    """

    def __init__(
        self,
        model: Model,
        system: DiscreteSystem | None = None,
        analysis_step: int = 1,
        end_state: LoadState | None = None,
    ):
        self.model = model
        self.analysis_step = analysis_step
        self.end_state = end_state
        self.systems: dict[int, DiscreteSystem] = {}
        if system is not None:
            self.systems[analysis_step] = system
        self.steps: list[StepResult] = []
        self.stopwatch = Stopwatch()
        self.probes: dict[str, np.ndarray] = {}
        self.units: dict[str, str] = {}
        self.source: Path | None = None
        self.end: PathEnd | None = None
        self._closed: bool | None = None  # whether the pressurised surface encloses a volume

    @property
    def timings(self) -> dict[str, float]:
        """Wall seconds so far in element evaluation, assembly, linear solves, the rest, and
        in total (``wrinkle.timing``)."""
        return self.stopwatch.summary()

    @property
    def factorisations(self) -> int:
        """Tangent factorisations so far, those of failed load steps and of coarser meshes
        (``nested``) included."""
        return self.stopwatch.factorisations

    @property
    def elimination(self) -> dict[str, int]:
        """The work of nonlinear elimination so far (``[solver] elimination``): patches
        tried, their local Newton iterations and factorisations (the latter counted in
        ``factorisations`` too); zeros without it."""
        watch = self.stopwatch
        return {
            "patches": watch.patches,
            "local_iterations": watch.local_iterations,
            "local_factorisations": watch.local_factorisations,
        }

    def append(
        self,
        load_factor: float,
        u: np.ndarray,
        solved: SolverResult,
        pressure_factor: float | None = None,
    ) -> StepResult:
        """Add the converged step u (n_dofs,); its reactions come from the solver's last
        evaluation, at u, where it has them. pressure_factor: the factor on the pressure
        loads (default load_factor)."""
        ev = solved.evaluation
        system = self.system_of(self.analysis_step)
        reactions = ev.reactions
        if reactions is None:
            reactions = system.reactions(u, load_factor)
        factor = load_factor if pressure_factor is None else pressure_factor
        element = self.model.pressure_element
        value = None if element is None else float(system.pressure_at(factor)[element])
        if self._closed is None:  # (the elements any pressure load acts on, in any step)
            self._closed = value is not None and system.volume_closure() is None
        step = StepResult(
            load_factor,
            u.copy(),
            solved.iterations,
            ev.residual_norm,
            reactions,
            ev.states,
            solved.stopped_by,
            solved.stop_report,
            value,
            system.enclosed_volume(u) if self._closed else None,
            tuple(float(r) for r in solved.residual_norms),
            self.analysis_step,
            factor,
            getattr(solved, "path_state", None),
        )
        self.steps.append(step)
        return step

    def save(
        self,
        directory: str | os.PathLike,
        probes: Mapping[str, np.ndarray] | None = None,
        units: Mapping[str, str] | None = None,
        file_format: str = "vtu",
        fields: Sequence[str] | None = None,
        precision: str = "double",
    ) -> Path:
        """Write every step (ParaView files, summary.json, history.csv) into ``directory``;
        probes and units default to the results' own (from a case file); file_format "vtu"
        or "xdmf", the fields to write and their precision as ``[output]``
        (``wrinkle.output``). Returns the directory."""
        return save_results(
            self,
            directory,
            probes=self.probes if probes is None else probes,
            units=self.units if units is None else units,
            case=self.source,
            file_format=file_format,
            fields=fields,
            precision=precision,
        )

    @property
    def final(self) -> StepResult:
        """The last converged step."""
        return self.steps[-1]

    def system_of(self, analysis_step: int) -> DiscreteSystem:
        """The discrete system on whose path analysis step ``analysis_step`` was solved
        (the model's own if it was not recorded)."""
        return self.systems.get(analysis_step) or self.model.discretise()

    def step_start(self) -> StepStart:
        """Where the next analysis step starts (``Model.solve(start=...)``): the loads and
        supported values at the end of this path and its last displacement. ValueError if
        the path has no converged step or did not reach its end (load factor 1)."""
        if not self.steps or abs(self.final.load_factor - 1.0) > 1e-12:
            reached = self.final.load_factor if self.steps else 0.0
            raise ValueError(
                f"analysis steps: the step before ended at load factor {reached:.6g}, not 1: "
                "the next one cannot start from it"
            )
        if self.end_state is None:
            raise ValueError("analysis steps: these results do not record their loads")
        return StepStart(self.end_state, self.final.displacement, self.analysis_step)

    def extend(self, later: Results) -> None:
        """Add the steps of a later analysis step's results (``Model.solve(start=...)``)
        to these: its steps, its system, its end and its timings."""
        self.steps += later.steps
        self.systems.update(later.systems)
        self.analysis_step, self.end_state, self.end = (
            later.analysis_step,
            later.end_state,
            later.end,
        )
        self.stopwatch.absorb(later.stopwatch)

    def modes(
        self,
        count: int,
        step: int = -1,
        mass: str = "consistent",
        shift: float | None = None,
        linear_solver: str = "auto",
    ) -> Modes:
        """The ``count`` lowest natural modes about converged step ``step`` (an index into
        ``steps``, default the last), with its load and pressure factors and the tangent
        there (``wrinkle.modes.natural_modes``, which says what ``mass`` and ``shift``
        mean). The model's materials need a density."""
        chosen = self.steps[step]
        return natural_modes(
            self.model,
            chosen.displacement,
            count,
            load_factor=chosen.load_factor,
            pressure_factor=chosen.pressure_factor,
            mass=mass,
            shift=shift,
            linear_solver=linear_solver,
            system=self.system_of(chosen.analysis_step),
        )

    def __len__(self) -> int:
        return len(self.steps)
