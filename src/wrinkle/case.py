"""Case files: a membrane analysis described in TOML, read into a ``Case``.

A case has the tables ``[mesh]``, ``[material]`` (or ``[[material]]`` with ``region``),
``[[support]]``, ``[[load]]``, ``[[probe]]``, ``[solver]`` and ``[modes]``; docs/case-file.md
lists every key. Every error names the file, the table and the key at fault (``CaseError``).
The ``Case`` holds the ``Model``, the solver settings, the probes, the units and the modes
to compute; ``Case.solve()`` and ``Case.run(out)`` solve it.
"""

from __future__ import annotations

import contextlib
import math
import os
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from wrinkle.formfinding import (
    FORM_TOLERANCE,
    MAX_FORM_ITERATIONS,
    FormFinding,
    FormFindingError,
    find_form,
)
from wrinkle.gas import Gas
from wrinkle.materials import MooneyRivlin, NeoHookean, Ogden, Prestressed, StVenantKirchhoff
from wrinkle.materials.base import Material
from wrinkle.mesh import (
    Mesh,
    annulus,
    check_fits,
    cylinder,
    disk,
    read_mesh,
    rectangle,
    sphere,
    write_mesh,
)
from wrinkle.model import Model
from wrinkle.modes import DEFAULT_MASS, MASS_KINDS, Modes
from wrinkle.output import FIELDS, FORMATS, PRECISIONS, ResultsWriteError, ResultWriter
from wrinkle.reader import SUMMARY, open_results
from wrinkle.refinement import MAX_REFINED_ELEMENTS, refine
from wrinkle.results import Results, StepResult
from wrinkle.selectors import evaluate_expression, select_nodes
from wrinkle.solvers import LINEAR_SOLVERS, SOLVERS, ConvergenceError, SolverSettings
from wrinkle.solvers.settings import CONTROLS, CONVERGENCE_TESTS
from wrinkle.solvers.stepping import Resume
from wrinkle.staging import AnalysisStep, restart_point, solve_steps
from wrinkle.system import StepStart
from wrinkle.xdmf import require_h5py

FORM_MESH = "formfound.msh"  # the found mesh, in the output folder of a [formfinding] case

__all__ = [
    "GENERATORS",
    "LOAD_KINDS",
    "MATERIAL_MODELS",
    "SOLVER_KEYS",
    "Case",
    "CaseError",
    "FormFindingSettings",
    "ModeSettings",
    "NoModesError",
    "merged",
    "read_case",
    "read_case_data",
]


class CaseError(ValueError):
    """Bad input in a case file; the message names the file and the key."""


MATERIAL_MODELS = {
    "svk": ("E", "nu"),
    "svk-transverse": ("E_L", "E_T", "nu_LT", "nu_TT", "G_LT"),
    "neo-hookean": ("mu",),
    "mooney-rivlin": ("C10", "C01"),
    "ogden": ("mu", "alpha"),
}
# the models whose parameters are lists of numbers, one per term
_LIST_PARAMETERS = {"ogden": ("mu", "alpha")}
GENERATORS: dict[str, tuple[Callable[..., Mesh], tuple[str, ...]]] = {
    "rectangle": (rectangle, ("width", "height", "nx", "ny")),
    "disk": (disk, ("outer_radius", "n_radial", "n_circumferential")),
    "annulus": (annulus, ("inner_radius", "outer_radius", "n_radial", "n_circumferential")),
    "sphere": (sphere, ("radius", "n")),
    "cylinder": (cylinder, ("radius", "length", "n_circumferential", "n_axial", "n_cap")),
}
LOAD_KINDS = {
    "pressure": ({"value"}, {"region", "label"}),
    "edge": ({"nodes"}, {"traction", "normal", "follow", "label"}),
    "nodal": ({"nodes", "force"}, {"label"}),
    "gravity": ({"acceleration", "density"}, {"region", "label"}),
    "gas": ({"ambient"}, {"p0", "amount", "gamma", "region", "label"}),
}
SOLVER_KEYS = {
    "method",
    "steps",
    "tolerance",
    "max_iterations",
    "min_step",
    "max_step",
    "cutback",
    "growth",
    "target_iterations",
    "regrow_after",
    "linear_solver",
    "look_ahead",
    "elimination",
    "nested",
    "convergence",
    "accuracy_energy",
    "accuracy_change",
    "control",
    "volume_ratio",
    "volume",
    "stop",
}
# the [solver] keys a [[step]] may set for its own path (the others are for one path only)
STEP_SOLVER_KEYS = SOLVER_KEYS - {
    "nested",
    "convergence",
    "accuracy_energy",
    "accuracy_change",
    "volume_ratio",
    "volume",
    "stop",
}


class _Reader:
    """Typed access to the tables of one case file, with messages naming file and key."""

    def __init__(self, path: Path):
        self.path = path
        # the mesh whose coordinates selectors are evaluated on, if not the model's own (the
        # case's mesh, when the model is rebuilt on its form-found mesh)
        self.select_on: Mesh | None = None

    def fail(self, where: str, message: str) -> NoReturn:
        raise CaseError(f"{self.path}: {where}: {message}")

    def keys(self, table: dict, where: str, required: set, optional: set) -> None:
        unknown = sorted(set(table) - required - optional)
        if unknown:
            allowed = ", ".join(sorted(required | optional))
            self.fail(where, f"unknown key '{unknown[0]}' (allowed: {allowed})")
        missing = sorted(required - set(table))
        if missing:
            self.fail(where, f"missing key '{missing[0]}'")

    def number(
        self, table: dict, key: str, where: str, positive=False, integer=False, minimum=None
    ):
        value = table[key]
        kind = int if integer else (int, float)
        if isinstance(value, bool) or not isinstance(value, kind):
            expected = "an integer" if integer else "a number"
            self.fail(where, f"'{key}' must be {expected}, got {value!r}")
        if not math.isfinite(value):
            self.fail(where, f"'{key}' must be finite, got {value!r}")
        if positive and not value > 0:
            self.fail(where, f"'{key}' must be > 0, got {value!r}")
        if minimum is not None and value < minimum:
            self.fail(where, f"'{key}' must be >= {minimum}, got {value!r}")
        return value

    def tables(self, data: dict, key: str, single: bool = False) -> list[dict]:
        """The array of tables [[key]] (or, where ``single``, one [key] table) as a list;
        [] where absent; fails naming it if it is anything else or holds a non-table."""
        value = data.get(key, [])
        if single and isinstance(value, dict):
            return [value]
        shape = f"[{key}] or [[{key}]]" if single else f"[[{key}]]"
        if not isinstance(value, list):
            self.fail(f"[[{key}]]", f"must be {shape} tables, got {value!r}")
        for index, item in enumerate(value):
            if not isinstance(item, dict):
                self.fail(f"[[{key}]] {index + 1}", f"must be a table ({shape}), got {item!r}")
        return value

    def string(self, table: dict, key: str, where: str) -> str:
        value = table[key]
        if not isinstance(value, str):
            self.fail(where, f"'{key}' must be a string, got {value!r}")
        return value

    def choice(self, table: dict, key: str, where: str, choices) -> str:
        """A string that must be one of ``choices``."""
        value = self.string(table, key, where)
        if value not in choices:
            self.fail(where, f"unknown {key} '{value}' (one of {', '.join(choices)})")
        return value

    def vector(self, table: dict, key: str, where: str, allow_free=False, expressions=False):
        """A list of 3 numbers (or expression strings, or "free" where allowed)."""
        value = table[key]
        if not isinstance(value, list) or len(value) != 3:
            self.fail(where, f"'{key}' must be a list of 3 values [x, y, z], got {value!r}")
        for item in value:
            ok = isinstance(item, (int, float)) and not isinstance(item, bool)
            if ok and not math.isfinite(item):
                self.fail(where, f"'{key}' must be finite, got {value!r}")
            ok = ok or (allow_free and item == "free") or (expressions and isinstance(item, str))
            if not ok:
                self.fail(where, f"'{key}' has a bad component {item!r}")
        return value

    def numbers(self, table: dict, key: str, where: str) -> list[float]:
        """A non-empty list of finite numbers."""
        value = table[key]
        if not isinstance(value, list) or not value:
            self.fail(where, f"'{key}' must be a non-empty list of numbers, got {value!r}")
        for item in value:
            if isinstance(item, bool) or not isinstance(item, (int, float)):
                self.fail(where, f"'{key}' has a bad entry {item!r} (a number is needed)")
            if not math.isfinite(item):
                self.fail(where, f"'{key}' must be finite, got {value!r}")
        return [float(item) for item in value]

    def nodes(self, mesh: Mesh, table: dict, where: str) -> np.ndarray:
        try:
            return select_nodes(self.select_on or mesh, self.string(table, "nodes", where))
        except (ValueError, TypeError) as error:
            self.fail(where, f"nodes: {error}")

    def elements(self, mesh: Mesh, table: dict, where: str):
        if "region" not in table:
            return None
        region = self.string(table, "region", where)
        if region not in mesh.element_sets:
            known = ", ".join(sorted(mesh.element_sets)) or "none"
            self.fail(
                where,
                f"region '{region}' is not a physical group of elements (the mesh has: {known})",
            )
        return mesh.element_sets[region]


def read_case_data(path: str | Path) -> dict:
    """The tables of the TOML case file ``path`` as a dict; CaseError if unreadable."""
    path = Path(path)
    if path.is_dir():
        raise CaseError(f"{path}: is a folder, not a case file")
    if not path.is_file():
        raise CaseError(f"{path}: case file not found")
    try:
        # utf-8-sig: a byte-order mark (some Windows editors write one) is not TOML
        return tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except OSError as error:
        raise CaseError(f"{path}: cannot be read ({error.strerror})") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise CaseError(f"{path}: not valid TOML: {error}") from None


def merged(data: dict, overrides: dict) -> dict:
    """A copy of the nested tables ``data`` with the keys of ``overrides`` replaced (tables
    merged key by key, anything else replaced whole)."""
    out = dict(data)
    for key, value in overrides.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merged(out[key], value)
        else:
            out[key] = value
    return out


class NoModesError(RuntimeError):
    """The last converged state has no natural modes (it is unstable, or its tangent has a
    complex eigenvalue): the steps stand, the run cannot answer [modes] (exit status 1)."""


@dataclass(frozen=True)
class ModeSettings:
    """The [modes] table: how many natural modes of the last converged state to compute,
    with which mass ("consistent" or "lumped", ``wrinkle.modes``) and, where shift (Hz) is
    given, the modes nearest that frequency instead of the lowest."""

    count: int
    mass: str = DEFAULT_MASS
    shift: float | None = None

    def of(self, results: Results) -> Modes:
        """The modes of the last step of ``results`` (``Results.modes``)."""
        sigma = None if self.shift is None else (2.0 * math.pi * self.shift) ** 2
        return results.modes(self.count, mass=self.mass, shift=sigma)


@dataclass(frozen=True)
class OutputSettings:
    """The [output] table: the step files' format ("vtu", one file a step with its mesh;
    "xdmf", an XDMF time series with the mesh written once, ``wrinkle.xdmf``), the fields
    they hold (None: all; "displacement" is always written) and the precision of the
    floating-point fields ("double", or "single" but for the displacement and reactions)."""

    file_format: str = "vtu"
    fields: tuple[str, ...] | None = None
    precision: str = "double"


@dataclass(frozen=True)
class FormFindingSettings:
    """The [formfinding] table: ``find_form``'s tolerance (the largest change of the shape
    in an iteration, relative to its size) and its most outer iterations."""

    tolerance: float = FORM_TOLERANCE
    max_iterations: int = MAX_FORM_ITERATIONS


@dataclass
class Case:
    """A case file read: the model and how to solve it and report it.

    model: the ``Model``; settings: the ``SolverSettings`` of the [solver] table; probes:
    {name: node indices} whose mean displacement the history records; units: labels such as
    {"length": "m", "force": "N"} for the summary and the pictures; source: the case file;
    title: its ``title``; verification: its [verification] table (read by the verification
    gallery only); coarse: with ``[solver] nested``, the same case on the coarser meshes of
    ``[mesh] levels`` and ``[mesh] refine``, coarsest first (``wrinkle.sequencing``);
    level_names: what each of them is (a level's file, "[mesh] refine = i"), for messages;
    modes: the [modes] table, the natural modes ``run`` computes after the last step;
    form_finding: the [formfinding] table, with which ``run`` form-finds the model first;
    rebuild: the case's model made again on another mesh of the same elements (the found
    form), its loads with it or not, its selectors evaluated on the case's own mesh;
    selections: each selector text of the case and the nodes it picks on the case's mesh,
    written into formfound.msh as node sets of those names; output: the [output] table;
    steps: the analysis steps of its [[step]] tables (``wrinkle.staging``), solved in
    turn (none: one proportional path).
    """

    model: Model
    settings: SolverSettings = field(default_factory=SolverSettings)
    probes: dict[str, np.ndarray] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)
    source: Path | None = None
    title: str = ""
    verification: dict[str, Any] = field(default_factory=dict)
    coarse: list[Model] = field(default_factory=list)
    level_names: list[str] = field(default_factory=list)
    modes: ModeSettings | None = None
    form_finding: FormFindingSettings | None = None
    rebuild: Callable[[Mesh, bool], Model] | None = None
    selections: dict[str, np.ndarray] = field(default_factory=dict)
    output: OutputSettings = field(default_factory=OutputSettings)
    steps: list[AnalysisStep] = field(default_factory=list)

    def _label(self, results: Results | None) -> None:
        if results is not None:
            results.probes, results.units, results.source = self.probes, self.units, self.source

    def solve(self, on_step: Callable[[StepResult], None] | None = None, **options: Any) -> Results:
        """Solve the model with the case's settings (``options``: fields of
        ``SolverSettings`` overriding them); the results carry the case's probes and units.
        Raises ConvergenceError (its ``results`` labelled the same) if a step fails. With
        analysis steps, their paths in turn (``wrinkle.staging.solve_steps``; ``restart``:
        where to take up a staged run, ``restart_point``)."""
        restart = options.pop("restart", None)
        try:
            if self.steps:
                first, start, resume = restart if restart is not None else (0, None, None)
                results = solve_steps(
                    self.model,
                    self.steps,
                    on_step,
                    self.probes,
                    first,
                    start,
                    resume,
                    **options,
                )
            else:
                results = self.model.solve(
                    self.settings,
                    on_step=on_step,
                    coarse=self.coarse or None,
                    probes=self.probes,
                    **options,
                )
        except ConvergenceError as error:
            self._label(error.results)
            raise
        except ValueError as error:  # the model's checks (supports, scale): name the file
            if isinstance(error, CaseError) or self.source is None:
                raise
            message = str(error)
            if message.startswith("nested:") and self.level_names:  # say which level is which
                names = [*self.level_names, "the case's own mesh"]
                message += " (" + ", ".join(f"level {i}: {n}" for i, n in enumerate(names)) + ")"
            raise CaseError(f"{self.source}: {message}") from None
        self._label(results)
        return results

    def run(
        self,
        out: str | os.PathLike,
        on_step: Callable[[StepResult], None] | None = None,
        loads: bool = True,
        restart: bool = False,
        **options: Any,
    ) -> Results:
        """Solve and write each converged step into the folder ``out`` as it converges
        (``wrinkle.output.ResultWriter``), then the final summary; ``on_step`` is called after
        each step is written. A ConvergenceError or KeyboardInterrupt is raised again after
        the summary records it; every converged step is on disk. With [modes], the natural
        modes of the last step are written too (``ResultWriter.write_modes``); NoModesError
        if the state has none (unstable), after the summary says so.

        With [formfinding] the model is form-found first (``find_form``): the found mesh is
        written as ``out/formfound.msh`` (with the case's node selections as node sets named
        by their selector text, so that a case on it selects the same nodes), and the case's
        model made again on it (``rebuild``: the supports hold the found boundary, the
        prestress kept) is solved under the case's loads, or without them in one step if
        ``loads`` is False (``wrinkle formfind``); the summary has "formfinding".
        FormFindingError if no form is found.

        With ``restart`` (``wrinkle run --restart``) the path continues from the last
        converged step in ``out`` (``resume_from``), as the run would have gone on, and the
        new steps are added to those there; from the start where ``out`` has none."""
        if self.form_finding is None:
            return self._run(out, on_step, None, restart, **options)
        form = self.find_form()
        assert self.rebuild is not None
        try:
            model = self.rebuild(form.mesh, loads)
        except CaseError as error:
            raise CaseError(f"{error} (on the form-found mesh)") from None
        analysis = replace(
            self,
            model=model,
            form_finding=None,
            coarse=[],
            level_names=[],
            steps=self.steps if loads else [],
        )
        path = Path(out)
        path.mkdir(parents=True, exist_ok=True)
        found = replace(form.mesh, node_sets={**self.selections, **form.mesh.node_sets})
        write_mesh(found, path / FORM_MESH)
        summary = {
            "iterations": form.iterations,
            "converged": form.converged,
            "shape_residual": form.residual,
            "residual": form.sliding[-1],
            "largest_move": float(np.linalg.norm(form.nodes - self.model.mesh.nodes, axis=1).max()),
            "mesh": FORM_MESH,
            "loads": loads,
        }
        if not loads:  # the found form alone: one step, at which it balances
            options = {"steps": 1, "control": "load", **options}
        return analysis._run(out, on_step, summary, restart, **options)

    def resume_from(self, out: str | os.PathLike, **options: Any) -> Resume | None:
        """Where the path continues from the results in the folder ``out``: its last
        converged step, the one before it and the increment the step controller (with the
        case's settings and ``options``) takes next, so that the run goes on as it would
        have (``wrinkle.solvers.stepping.Resume``); None if ``out`` has no converged step.
        CaseError if that run reached load factor 1 already, or its mesh is not the case's.
        (A case with analysis steps continues by ``wrinkle.staging.restart_point``.)"""
        folder = Path(out)
        if not (folder / SUMMARY).is_file():
            return None
        settings = self.settings.replace(**options)
        if settings.control != "load" or settings.stop is not None or self.model.gas is not None:
            raise CaseError(
                f"--restart: {self.source}: only a load-controlled path without a stop or gas "
                "load can be continued (solver control = 'load')"
            )
        point = self._staged_restart(out, [AnalysisStep("the path", settings=settings)])
        return None if point is None else point[2]

    def _staged_restart(
        self, out: str | os.PathLike, steps: list[AnalysisStep], **options: Any
    ) -> tuple[int, StepStart | None, Resume | None] | None:
        """Where a run of the analysis ``steps`` (one step: a single path) continues from the
        results in ``out`` (``wrinkle.staging.restart_point``); None if there are none.
        CaseError if that run had ended, or is not readable or of another mesh."""
        folder = Path(out)
        if not (folder / SUMMARY).is_file():
            return None
        try:
            saved = open_results(folder)
            if not saved.steps:
                return None

            def displacement(index: int) -> np.ndarray:
                u = saved.displacement(index)
                if u.size != self.model.n_dofs:
                    raise CaseError(
                        f"--restart: {folder / saved.steps[index]['file']}: a mesh of "
                        f"{u.size // 3} nodes, not the case's {self.model.mesh.n_nodes}"
                    )
                return u

            return restart_point(self.model, steps, saved.steps, displacement, **options)
        except (OSError, KeyError, TypeError) as error:
            raise CaseError(f"--restart: {folder}: not readable ({error})") from None
        except ValueError as error:
            if isinstance(error, CaseError):
                raise
            raise CaseError(f"--restart: {folder / SUMMARY}: {error}") from None

    def find_form(self) -> FormFinding:
        """The form of the case's model by its [formfinding] settings (default ones
        without the table); FormFindingError (naming the case file) if none is found,
        CaseError for a model that has no form."""
        settings = self.form_finding or FormFindingSettings()
        try:
            return find_form(
                self.model,
                tolerance=settings.tolerance,
                max_iterations=settings.max_iterations,
                linear_solver=self.settings.linear_solver,
            )
        except FormFindingError as error:
            raise FormFindingError(f"{self.source}: {error}", error.form) from None
        except ValueError as error:
            raise CaseError(f"{self.source}: [formfinding]: {error}") from None

    def _run(
        self,
        out: str | os.PathLike,
        on_step: Callable[[StepResult], None] | None,
        form_finding: dict | None,
        restart: bool = False,
        **options: Any,
    ) -> Results:
        resume = point = None
        if restart and self.steps:
            point = self._staged_restart(out, self.steps, **options)
        elif restart:
            resume = self.resume_from(out, **options)
        try:
            writer = ResultWriter(
                out,
                self.model,
                probes=self.probes,
                units=self.units,
                case=self.source,
                resume=resume is not None or point is not None,
                file_format=self.output.file_format,
                fields=self.output.fields,
                precision=self.output.precision,
                analysis_steps=[step.name for step in self.steps] or None,
            )
        except ValueError as error:  # a folder of another case's run
            raise CaseError(f"--restart: {error}") from None
        if resume is not None:
            options["resume"] = resume
        if point is not None:
            options["restart"] = point
        writer.form_finding = form_finding

        def write(step: StepResult) -> None:
            writer.write_step(step)
            if on_step is not None:
                on_step(step)

        try:
            results = self.solve(on_step=write, **options)
        except ConvergenceError as error:
            writer.finish(False, f"not converged: {error}")
            raise
        except ValueError as error:  # a check made when the path starts: said, not "running"
            writer.finish(False, f"stopped: {error}")
            raise
        except KeyboardInterrupt:
            writer.finish(False, "interrupted")
            raise
        except ResultsWriteError as error:
            with contextlib.suppress(OSError):  # the summary may not be writable either
                writer.finish(False, f"stopped: {error}")
            raise
        end = results.end
        message = "converged to load factor 1" if end is None else end.message
        if self.modes is not None:
            try:
                writer.write_modes(self.modes.of(results))
            except ValueError as error:  # an unstable state: the steps stand, say why
                writer.finish(True, f"{message}; no modes: {error}")
                raise NoModesError(f"{self.source}: [modes]: {error}") from None
        writer.finish(True, message)
        return results


def read_case(path: str | os.PathLike, overrides: dict[str, Any] | None = None) -> Case:
    """Read a TOML case file into a ``Case``.

    overrides: nested tables merged over the file's (e.g. ``{"mesh": {"rectangle": {"nx":
    8}}}`` for a mesh-convergence study, ``{"solver": {"steps": 4}}``). Raises CaseError (a
    ValueError) naming the file and key for any bad input.
    """
    path = Path(path)
    reader = _Reader(path)
    data = read_case_data(path)
    if overrides:
        data = merged(data, overrides)
    reader.keys(
        data,
        "top level",
        {"mesh", "material"},
        {
            "support",
            "load",
            "cable",
            "probe",
            "solver",
            "title",
            "verification",
            "modes",
            "formfinding",
            "output",
            "step",
        },
    )

    base, times, units, level_files = _read_mesh(reader, data["mesh"], path.parent)
    if base.n_elements * 4**times > MAX_REFINED_ELEMENTS:
        count = float(base.n_elements) * 4.0 ** min(times, 400)  # formattable however large
        reader.fail(
            "[mesh]",
            f"'refine' = {times} would make {count:.3g} elements "
            f"(at most {MAX_REFINED_ELEMENTS:,})",
        )
    try:
        check_fits(base.n_elements * 4**times, f"'refine' = {times}")
    except ValueError as error:
        reader.fail("[mesh]", str(error))
    meshes = [base]
    for _ in range(times):
        meshes.append(refine(meshes[-1]).mesh)
    mesh = meshes[-1]
    model = _read_model(reader, data, mesh)
    probes = {}
    for index, table in enumerate(reader.tables(data, "probe")):
        where = f"[[probe]] {index + 1}"
        reader.keys(table, where, {"nodes"}, {"name"})
        name = reader.string(table, "name", where) if "name" in table else table["nodes"]
        if str(name) in probes:
            reader.fail(where, f"probe name {str(name)!r} is used twice (each probe needs its own)")
        probes[str(name)] = reader.nodes(mesh, table, where)
    settings = _read_solver(reader, data.get("solver", {}))
    obstacle = model.elimination_obstacle()
    if settings.elimination and obstacle is not None:
        reader.fail("[solver]", f"elimination = true: {obstacle}")
    if settings.stop is not None and settings.stop[0] not in probes:
        reader.fail(
            "[solver]",
            f"'stop' names probe {settings.stop[0]!r}, which no [[probe]] defines (probes: "
            + (", ".join(probes) or "none")
            + ")",
        )
    steps = _read_steps(reader, data, model, settings) if "step" in data else []
    coarse, level_names = [], []
    if level_files and settings.nested is False:
        reader.fail(
            "[mesh]", "'levels' are the meshes of [solver] nested: set nested = true to use them"
        )
    nests = settings.nests(bool(level_files), times > 0, bool(np.any(model.bending > 0)))
    nests = nests and not steps  # (a staged analysis starts from the reference state)
    if settings.convergence == "accuracy" and not nests:
        reader.fail(
            "[solver]",
            "convergence = 'accuracy' needs nested = true and coarser meshes ([mesh] refine "
            ">= 1 or [mesh] levels): the discretisation error is estimated from them",
        )
    if nests:
        if times == 0 and not level_files:
            reader.fail(
                "[solver]",
                "'nested' needs coarser meshes: set [mesh] refine >= 1 or [mesh] levels",
            )
        for level_file, level_mesh in _read_levels(reader, level_files, base):
            try:
                coarse.append(_read_model(reader, data, level_mesh))
            except CaseError as error:
                raise CaseError(f"{error} (on the mesh of [mesh] levels: {level_file})") from None
            level_names.append(str(level_file))
        for level, level_mesh in enumerate(meshes[:-1]):
            try:
                coarse.append(_read_model(reader, data, level_mesh))
            except CaseError as error:
                raise CaseError(f"{error} (on the mesh of [mesh] refine = {level})") from None
            level_names.append(f"[mesh] refine = {level}")
    modes = _read_modes(reader, data["modes"], model) if "modes" in data else None
    form_finding = None
    selections: dict[str, np.ndarray] = {}
    if "formfinding" in data:
        form_finding = _read_form_finding(reader, data["formfinding"])
        if coarse:
            reader.fail(
                "[formfinding]",
                "a form-finding case is not nested: set [solver] nested = false, or drop "
                "[mesh] levels",
            )

        # the case's node selections, carried into formfound.msh as node sets named by their
        # selector text: a second case on it finds the same nodes with the same selectors
        for kind in ("support", "cable", "probe", "load"):
            for index, table in enumerate(reader.tables(data, kind)):
                if isinstance(table, dict) and isinstance(table.get("nodes"), str):
                    text = table["nodes"]
                    if text not in mesh.node_sets:
                        selections[text] = reader.nodes(mesh, table, f"[[{kind}]] {index + 1}")

    def rebuild(found: Mesh, loads: bool) -> Model:
        """The case's model on ``found`` (selectors on the case's mesh), held in place."""
        again = _Reader(path)
        again.select_on = mesh
        rebuilt = _read_model(again, data, found, loads=loads)
        rebuilt.hold_in_place()
        return rebuilt

    title = data.get("title", "")
    if not isinstance(title, str):
        reader.fail("top level", f"'title' must be a string, got {title!r}")
    verification = data.get("verification", {})
    if not isinstance(verification, dict):
        reader.fail("[verification]", "must be a table")
    return Case(
        model,
        settings,
        probes,
        units,
        path,
        title,
        verification,
        coarse,
        level_names,
        modes,
        form_finding,
        rebuild,
        selections,
        _read_output(reader, data["output"]) if "output" in data else OutputSettings(),
        steps,
    )


def _read_model(reader: _Reader, data: dict, mesh: Mesh, loads: bool = True) -> Model:
    """The model of the case's materials, supports, cables and (with ``loads``) loads on
    ``mesh``."""
    model = Model(mesh)
    materials = reader.tables(data, "material", single=True)
    if not materials:
        reader.fail("[material]", "at least one material is needed")
    for index, table in enumerate(materials):
        _read_material(
            reader,
            model,
            table,
            f"[[material]] {index + 1}" if len(materials) > 1 else "[material]",
        )
    supports = reader.tables(data, "support")
    if not supports:
        reader.fail("[[support]]", "at least one support is needed")
    for index, table in enumerate(supports):
        _read_support(reader, model, table, f"[[support]] {index + 1}")
    for index, table in enumerate(reader.tables(data, "load") if loads else []):
        _read_load(reader, model, table, index + 1)
    for index, table in enumerate(reader.tables(data, "cable")):
        _read_cable(reader, model, table, f"[[cable]] {index + 1}")
    try:
        model.check_supports()
    except ValueError as error:
        reader.fail("[[support]]", str(error))
    return model


def _read_cable(reader: _Reader, model: Model, table: dict, where: str) -> None:
    """A [[cable]]: nodes (a selector or a node set, such as a gmsh line physical group),
    EA, optional prestress (force), mass_per_length (for [modes]) and label."""
    if not isinstance(table, dict):
        reader.fail(where, "must be a table")
    reader.keys(table, where, {"nodes", "EA"}, {"prestress", "label", "mass_per_length"})
    nodes = reader.nodes(model.mesh, table, where)
    EA = reader.number(table, "EA", where, positive=True)
    prestress = reader.number(table, "prestress", where, minimum=0) if "prestress" in table else 0
    mass = (
        reader.number(table, "mass_per_length", where, minimum=0)
        if "mass_per_length" in table
        else 0
    )
    label = reader.string(table, "label", where) if "label" in table else str(table["nodes"])
    try:
        model.add_cables(nodes, float(EA), float(prestress), label, float(mass))
    except ValueError as error:
        reader.fail(where, str(error))


def _read_levels(reader: _Reader, files: list[Path], base: Mesh) -> list[tuple[Path, Mesh]]:
    """The meshes of [mesh] levels, each with its file, coarsest first: each with fewer
    elements than the next, the last fewer than the base mesh (before [mesh] refine)."""
    levels = []
    for index, file in enumerate(files):
        try:
            levels.append((file, read_mesh(file)))
        except (ValueError, ImportError, OSError) as error:
            reader.fail("[mesh]", f"levels[{index}]: {error}")
    counts = [mesh.n_elements for _, mesh in levels] + [base.n_elements]
    for index, (file, _) in enumerate(levels):
        if counts[index] >= counts[index + 1]:
            finer = files[index + 1].name if index + 1 < len(files) else "the case's own mesh"
            reader.fail(
                "[mesh]",
                f"levels[{index}]: {file} has {counts[index]:,} elements, not fewer than "
                f"{finer} ({counts[index + 1]:,}): list the levels coarsest first, each "
                "coarser than the next",
            )
    return levels


def _read_mesh(reader: _Reader, table: dict, folder: Path) -> tuple[Mesh, int, dict, list[Path]]:
    """The mesh before refinement, how many times [mesh] refine splits it, the units and the
    files of [mesh] levels (not read yet)."""
    where = "[mesh]"
    if not isinstance(table, dict):
        reader.fail(where, "must be a table")
    sources = [key for key in ("file", *GENERATORS) if key in table]
    reader.keys(table, where, set(), {"file", "units", "refine", "levels", *GENERATORS})
    if len(sources) != 1:
        reader.fail(where, "give exactly one of 'file', " + ", ".join(f"'{g}'" for g in GENERATORS))
    units = {}
    if "units" in table:
        units_table = table["units"]
        if isinstance(units_table, str):
            units = {"note": units_table}
        elif isinstance(units_table, dict):
            units = {str(k): str(v) for k, v in units_table.items()}
        else:
            reader.fail(
                where, '\'units\' must be a string or a table such as {length = "m", force = "N"}'
            )
    source = sources[0]
    times = 0
    if "refine" in table:
        times = int(reader.number(table, "refine", where, integer=True, minimum=0))
    levels = table.get("levels", [])
    if not isinstance(levels, list) or not all(isinstance(item, str) for item in levels):
        reader.fail(
            where,
            f"'levels' must be a list of mesh files, coarsest first, such as "
            f'["coarse.msh", "medium.msh"], got {levels!r}',
        )
    level_files = [folder / item for item in levels]
    try:
        if source == "file":
            file = folder / reader.string(table, "file", where)
            return read_mesh(file), times, units, level_files
        generator, keys = GENERATORS[source]
        parameters = table[source]
        sub = f"[mesh] {source}"
        if not isinstance(parameters, dict):
            reader.fail(sub, "must be a table, e.g. {width = 1.0, height = 1.0, nx = 10, ny = 10}")
        if source == "disk" and "inner_radius" in parameters:
            reader.fail(
                sub,
                "a disk has no 'inner_radius': for a disk with a hole use [mesh] "
                "annulus = {inner_radius, outer_radius, n_radial, "
                "n_circumferential}",
            )
        reader.keys(parameters, sub, set(keys), set())
        values = [
            reader.number(
                parameters,
                key,
                sub,
                positive=key != "n_cap",
                integer=key.startswith("n"),
                minimum=0 if key == "n_cap" else None,
            )
            for key in keys
        ]
        return generator(*values), times, units, level_files
    except CaseError:
        raise
    except (ValueError, ImportError, OSError) as error:
        reader.fail(where, str(error))


def _read_material(reader: _Reader, model: Model, table: dict, where: str) -> None:
    if not isinstance(table, dict):
        reader.fail(where, "must be a table")
    if "model" not in table:
        reader.fail(where, "missing key 'model' (one of " + ", ".join(MATERIAL_MODELS) + ")")
    name = reader.choice(table, "model", where, MATERIAL_MODELS)
    parameters = MATERIAL_MODELS[name]
    optional = {"model", "direction", "angle", "region", "bending", "prestress", "density"} | (
        {"lmbda"} if name == "neo-hookean" else set()
    )
    reader.keys(table, where, {*parameters, "thickness"}, optional)
    lists = _LIST_PARAMETERS.get(name, ())
    values: dict[str, Any] = {
        key: reader.numbers(table, key, where) if key in lists else reader.number(table, key, where)
        for key in (*parameters, "thickness")
    }
    if len({len(values[key]) for key in lists}) > 1:
        lengths = ", ".join(f"'{key}' {len(values[key])}" for key in lists)
        reader.fail(
            where,
            f"{' and '.join(repr(k) for k in lists)} must have the same length, got {lengths}",
        )
    if "lmbda" in table:
        values["lmbda"] = reader.number(table, "lmbda", where)
    material: Material
    try:
        if name == "svk":
            material = StVenantKirchhoff.isotropic(**values)
        elif name == "svk-transverse":
            material = StVenantKirchhoff.transversely_isotropic(**values)
        elif name == "mooney-rivlin":
            material = MooneyRivlin(**values)
        elif name == "ogden":
            material = Ogden(**values)
        else:
            material = NeoHookean(**values)
    except ValueError as error:
        reader.fail(where, str(error))
    if "prestress" in table:
        material = _read_prestress(reader, material, table, where)
    elements = reader.elements(model.mesh, table, where)
    direction = None
    if isinstance(table.get("direction"), str):  # per element, from the mesh's cell data
        name = table["direction"]
        data = model.mesh.cell_data.get(name)
        if data is None or data.shape != (model.mesh.n_elements, 3):
            known = ", ".join(f"{k} {v.shape}" for k, v in model.mesh.cell_data.items())
            reader.fail(
                where,
                f"'direction' names cell data '{name}', but the mesh has no "
                f"such (n_elements, 3) array (it has: {known or 'none'})",
            )
        direction = data if elements is None else data[elements]
    elif "direction" in table:
        direction = reader.vector(table, "direction", where)
        if not any(direction):
            reader.fail(where, "'direction' must not be zero")
    angle = math.radians(reader.number(table, "angle", where)) if "angle" in table else None
    density = (
        float(reader.number(table, "density", where, positive=True)) if "density" in table else None
    )
    try:
        model.assign_material(
            material, elements, fibre_direction=direction, fibre_angle=angle, density=density
        )
    except ValueError as error:
        reader.fail(where, str(error))
    if "bending" in table:
        _read_bending(reader, model, table, where, elements)


def _read_prestress(reader: _Reader, material: Material, table: dict, where: str) -> Prestressed:
    """``prestress = n`` (isotropic, n >= 0) or ``[n11, n22, n12]`` (material frame,
    positive semidefinite), force per unit length, around ``material``."""
    value = table["prestress"]
    if isinstance(value, list):
        if len(value) != 3:
            reader.fail(
                where, f"'prestress' must be a number or a list [n11, n22, n12], got {value!r}"
            )
        prestress: float | list[float] = reader.numbers(table, "prestress", where)
    else:
        prestress = float(reader.number(table, "prestress", where))
    try:
        return Prestressed(material, prestress)
    except ValueError as error:
        reader.fail(where, str(error))


def _read_bending(
    reader: _Reader, model: Model, table: dict, where: str, elements: np.ndarray | None
) -> None:
    """``bending = true`` (the material's own plate stiffness), ``false``, or a number D."""
    value = table["bending"]
    if value is False:
        return
    stiffness = None
    if value is not True:
        if isinstance(value, bool) or not isinstance(value, int | float):
            reader.fail(where, f"'bending' must be true, false or a number >= 0, got {value!r}")
        stiffness = float(reader.number(table, "bending", where, minimum=0))
    try:
        model.add_bending(stiffness, elements)
    except ValueError as error:
        reader.fail(where, f"'bending': {error}")


def _read_support(reader: _Reader, model: Model, table: dict, where: str) -> None:
    reader.keys(table, where, {"nodes"}, {"fix", "displacement", "label", "moment_about"})
    if ("fix" in table) == ("displacement" in table):
        reader.fail(where, "give either 'fix' or 'displacement'")
    nodes = reader.nodes(model.mesh, table, where)
    label = reader.string(table, "label", where) if "label" in table else table["nodes"]
    point = reader.vector(table, "moment_about", where) if "moment_about" in table else None
    if "fix" in table:
        fix = table["fix"]
        if not isinstance(fix, list) or not fix or any(c not in ("x", "y", "z") for c in fix):
            reader.fail(where, f'\'fix\' must be a list drawn from "x", "y", "z", got {fix!r}')
        model.fix(nodes, fix, label=label, moment_about=point)
        return
    components = reader.vector(table, "displacement", where, allow_free=True, expressions=True)
    X = model.mesh.nodes[nodes]
    values = np.full((nodes.size, 3), np.nan)
    for c, value in enumerate(components):
        if value == "free":
            continue
        try:
            values[:, c] = evaluate_expression(value, X)
        except ValueError as error:
            reader.fail(where, f"displacement {'xyz'[c]}: {error}")
    model.prescribe(nodes, values, label=label, moment_about=point)


def _read_load(reader: _Reader, model: Model, table: dict, index: int) -> None:
    """The [[load]] table number ``index`` (from 1), labelled by its ``label`` or "load
    <index>"."""
    where = f"[[load]] {index}"
    if "kind" not in table:
        reader.fail(where, "missing key 'kind' (one of " + ", ".join(LOAD_KINDS) + ")")
    kind = reader.choice(table, "kind", where, LOAD_KINDS)
    required, optional = LOAD_KINDS[kind]
    reader.keys(table, where, required | {"kind"}, optional)
    mesh = model.mesh
    label = reader.string(table, "label", where) if "label" in table else f"load {index}"
    try:
        if kind == "pressure":
            model.add_pressure(
                reader.number(table, "value", where),
                reader.elements(mesh, table, where),
                label=label,
            )
        elif kind == "nodal":
            model.add_nodal_force(
                reader.nodes(mesh, table, where),
                reader.vector(table, "force", where),
                label=label,
            )
        elif kind == "gas":
            values = {
                key: float(reader.number(table, key, where, positive=True))
                for key in ("ambient", "p0", "amount", "gamma")
                if key in table
            }
            model.add_gas(Gas(**values), reader.elements(mesh, table, where), label=label)
        elif kind == "gravity":
            model.add_gravity(
                reader.vector(table, "acceleration", where),
                reader.number(table, "density", where, positive=True),
                reader.elements(mesh, table, where),
                label=label,
            )
        else:
            if ("traction" in table) == ("normal" in table):
                reader.fail(where, "an edge load needs either 'traction' or 'normal'")
            follow = table.get("follow", False)
            if not isinstance(follow, bool):
                reader.fail(where, f"'follow' must be true or false, got {follow!r}")
            if follow and "traction" in table:
                reader.fail(where, "'follow' applies to 'normal' edge loads only")
            model.add_edge_load(
                reader.nodes(mesh, table, where),
                traction=reader.vector(table, "traction", where) if "traction" in table else None,
                normal=reader.number(table, "normal", where) if "normal" in table else None,
                follow=follow,
                label=label,
            )
    except CaseError:
        raise
    except ValueError as error:
        reader.fail(where, str(error))


def _read_form_finding(reader: _Reader, table: dict) -> FormFindingSettings:
    """The [formfinding] table: tolerance (> 0, < 1), max_iterations (>= 1)."""
    where = "[formfinding]"
    if not isinstance(table, dict):
        reader.fail(where, "must be a table")
    reader.keys(table, where, set(), {"tolerance", "max_iterations"})
    settings = FormFindingSettings()
    if "tolerance" in table:
        tolerance = float(reader.number(table, "tolerance", where, positive=True))
        if not tolerance < 1:
            reader.fail(where, f"'tolerance' must be < 1, got {tolerance!r}")
        settings = replace(settings, tolerance=tolerance)
    if "max_iterations" in table:
        count = int(reader.number(table, "max_iterations", where, integer=True, minimum=1))
        settings = replace(settings, max_iterations=count)
    return settings


def _read_output(reader: _Reader, table: dict) -> OutputSettings:
    """The [output] table: format ("vtu" or "xdmf"), fields (a list of field names)."""
    where = "[output]"
    if not isinstance(table, dict):
        reader.fail(where, "must be a table")
    reader.keys(table, where, set(), {"format", "fields", "precision"})
    file_format = reader.choice(table, "format", where, FORMATS) if "format" in table else "vtu"
    precision = (
        reader.choice(table, "precision", where, PRECISIONS) if "precision" in table else "double"
    )
    fields = None
    if "fields" in table:
        names = table["fields"]
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            reader.fail(where, f"'fields' must be a list of field names, got {names!r}")
        unknown = [name for name in names if name not in FIELDS]
        if unknown:
            reader.fail(
                where, f"'fields': unknown field {unknown[0]!r} (fields: {', '.join(FIELDS)})"
            )
        fields = tuple(names)
    if file_format == "xdmf":
        try:
            require_h5py()
        except ImportError as error:
            reader.fail(where, str(error))
    return OutputSettings(file_format, fields, precision)


def _read_modes(reader: _Reader, table: dict, model: Model) -> ModeSettings:
    """The [modes] table: count (1 .. the free components), mass, shift (Hz, >= 0)."""
    where = "[modes]"
    if not isinstance(table, dict):
        reader.fail(where, "must be a table")
    reader.keys(table, where, {"count"}, {"mass", "shift"})
    count = int(reader.number(table, "count", where, integer=True, minimum=1))
    free = int(np.count_nonzero(~model.constrained))
    if count > free:
        reader.fail(
            where, f"'count' = {count} is more than the model's {free} free degrees of freedom"
        )
    mass = reader.choice(table, "mass", where, MASS_KINDS) if "mass" in table else DEFAULT_MASS
    shift = float(reader.number(table, "shift", where, minimum=0)) if "shift" in table else None
    if not np.all(model.density > 0):
        reader.fail(
            where,
            "the natural modes need the mass: give [material] density (mass per unit volume) "
            "for every material",
        )
    if model.gas is not None:
        reader.fail(
            where,
            "a model with a gas load has no modes here (the gas's stiffness is not in the tangent)",
        )
    return ModeSettings(count, mass, shift)


def _read_steps(
    reader: _Reader, data: dict, model: Model, settings: SolverSettings
) -> list[AnalysisStep]:
    """The [[step]] tables: each an optional ``name``, the ``loads`` and ``supports`` (lists
    of labels) that grow in it and its own solver keys (``STEP_SOLVER_KEYS``, over
    [solver]). Every load, and every support that prescribes a displacement, must grow in
    one step, and only in one."""
    tables = reader.tables(data, "step")
    if settings.stop is not None or settings.control == "volume" or model.gas is not None:
        what = (
            "a gas load"
            if model.gas is not None
            else "[solver] " + ("'stop'" if settings.stop is not None else "control = 'volume'")
        )
        reader.fail("[[step]]", f"{what} is solved in one proportional path, without [[step]]")
    if settings.nested is True or settings.convergence == "accuracy":
        reader.fail("[[step]]", "[solver] nested and convergence = 'accuracy' are for one path")
    solver = data.get("solver", {})
    supports = list(dict.fromkeys(s.label for s in model.supports))
    named: dict[tuple[str, str], str] = {}  # (kind, label) -> the step that names it
    steps = []
    for index, table in enumerate(tables):
        where = f"[[step]] {index + 1}"
        if not isinstance(table, dict):
            reader.fail(where, "must be a table")
        reader.keys(table, where, set(), {"name", "loads", "supports", *STEP_SOLVER_KEYS})
        name = reader.string(table, "name", where) if "name" in table else f"step {index + 1}"
        labels: dict[str, list[str]] = {}
        for key, known in (("loads", model.load_labels), ("supports", supports)):
            values = table.get(key, [])
            if not isinstance(values, list) or not all(isinstance(v, str) for v in values):
                reader.fail(where, f"'{key}' must be a list of labels, got {values!r}")
            for label in values:
                if label not in known:
                    choices = ", ".join(repr(k) for k in known) or "none"
                    reader.fail(where, f"'{key}': no {key[:-1]} is labelled {label!r} ({choices})")
                if (key, label) in named:
                    reader.fail(
                        where,
                        f"'{key}': {label!r} grew in {named[(key, label)]} already (a load or "
                        "support reaches its value in one step)",
                    )
                named[(key, label)] = where
            labels[key] = list(values)
        if not labels["loads"] and not labels["supports"]:
            reader.fail(where, "names no load and no support to grow ('loads', 'supports')")
        own = {key: table[key] for key in STEP_SOLVER_KEYS if key in table}
        if own.get("control") == "volume":
            reader.fail(where, "control = 'volume' is solved in one path, without [[step]]")
        settings_of_step = _read_solver(reader, {**solver, **own}, where)
        if settings_of_step.control == "arc-length":
            movers = [
                s.label
                for s in model.supports
                if s.label in labels["supports"] and np.any(s.prescribed())
            ]
            if movers:
                reader.fail(
                    where,
                    f"control = 'arc-length': the loads alone may follow the load factor; "
                    f"this step moves support {movers[0]!r} (use control = 'load')",
                )
        steps.append(
            AnalysisStep(name, tuple(labels["loads"]), tuple(labels["supports"]), settings_of_step)
        )
    for label in model.load_labels:
        if ("loads", label) not in named:
            reader.fail("[[step]]", f"load {label!r} grows in no step: name it in 'loads'")
    for support in model.supports:
        moving = np.any(support.prescribed())
        if moving and ("supports", support.label) not in named:
            reader.fail(
                "[[step]]",
                f"support {support.label!r} prescribes a displacement but moves in no step: "
                "name it in 'supports'",
            )
    return steps


def _read_solver(reader: _Reader, table: dict, where: str = "[solver]") -> SolverSettings:
    if not isinstance(table, dict):
        reader.fail(where, "must be a table")
    reader.keys(table, where, set(), SOLVER_KEYS)
    solver: dict[str, Any] = {}
    choices = {
        "method": list(SOLVERS),
        "linear_solver": ["auto", *LINEAR_SOLVERS],
        "control": list(CONTROLS),
        "convergence": list(CONVERGENCE_TESTS),
    }
    for key, allowed in choices.items():
        if key in table:
            solver[key] = reader.choice(table, key, where, allowed)
    for key in ("steps", "max_iterations"):
        if key in table:
            solver[key] = reader.number(table, key, where, integer=True, minimum=1)
    for key in ("target_iterations", "regrow_after"):
        if key in table:
            solver[key] = reader.number(table, key, where, integer=True, minimum=0)
    for key in (
        "tolerance",
        "min_step",
        "max_step",
        "cutback",
        "growth",
        "accuracy_energy",
        "accuracy_change",
        "volume_ratio",
        "volume",
    ):
        if key in table:
            solver[key] = float(reader.number(table, key, where, positive=True))
    if "stop" in table:
        stop = table["stop"]
        if not isinstance(stop, dict) or set(stop) != {"probe", "displacement"}:
            reader.fail(
                where, f"'stop' must be {{probe = \"NAME\", displacement = VALUE}}, got {stop!r}"
            )
        probe = reader.string(stop, "probe", where + " stop")
        displacement = reader.number(stop, "displacement", where + " stop", positive=True)
        solver["stop"] = (probe, float(displacement))
    for key in ("look_ahead", "elimination", "nested"):
        if key in table:
            if not (isinstance(table[key], bool) or (key == "nested" and table[key] == "auto")):
                values = 'true, false or "auto"' if key == "nested" else "true or false"
                reader.fail(where, f"'{key}' must be {values}, got {table[key]!r}")
            solver[key] = table[key]
    try:
        return SolverSettings(**solver)
    except ValueError as error:
        reader.fail(where, str(error))
