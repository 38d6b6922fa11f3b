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
    each iteration of the step's converged solve, the first at its start.
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


class Results:
    """Converged load steps of a model, in order.

    probes ({name: node indices}) and units ({"length": "m", ...}) go into the files that
    ``save`` writes; source: the case file the model came from, if any (``Case.solve`` sets
    the three).
    """

    def __init__(self, model: Model):
        self.model = model
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
        system = self.model.discretise()
        reactions = ev.reactions
        if reactions is None:
            reactions = system.reactions(u, load_factor)
        value = self.model.pressure_value
        factor = load_factor if pressure_factor is None else pressure_factor
        if self._closed is None:
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
            None if value is None else factor * value,
            system.enclosed_volume(u) if self._closed else None,
            tuple(float(r) for r in solved.residual_norms),
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
        value = self.model.pressure_value
        pressure_factor = (
            None if value is None or chosen.pressure is None else chosen.pressure / value
        )
        return natural_modes(
            self.model,
            chosen.displacement,
            count,
            load_factor=chosen.load_factor,
            pressure_factor=pressure_factor,
            mass=mass,
            shift=shift,
            linear_solver=linear_solver,
        )

    def __len__(self) -> int:
        return len(self.steps)
