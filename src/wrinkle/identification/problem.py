"""A material identification read from TOML: the case, the parameters to find, the measured curves.

A fit file (docs/fit.md) names a case file (``case``, relative to the fit file), the
parameters to identify (``[[parameter]]``: a dotted ``path`` into the case as in a study,
``material.E_L``, ``load.1.value``, ``material.angle``; a ``start``, by default the case's
value; ``bounds = [low, high]``, by default none; ``gradient``: "auto", "adjoint" or
"finite-difference") and the experiments (``[[experiment]]``: a ``name``; its own ``case``,
by default the fit's; a measured CSV ``data`` with a load column ``x`` and one or several
measured columns ``y``; the model ``quantity`` each column is, by default the column's own
name: a support's reaction ``<support>_Fx`` or a probe's displacement ``<probe>_ux``, as in
history.csv; ``full_load``, the x at load factor 1 of the case, by default 1; ``weight``,
by default 1). ``tolerance`` (default 1e-10) is the solver tolerance of every solve of the
fit, ``fit_tolerance`` (default 1e-10) the optimiser's, ``max_evaluations`` (default 100)
the most residual evaluations it may take.

An experiment's measured point at x is the case solved to load factor x / full_load; a row
at x = 0 is the reference state and left out. Bad input raises FitError, one line naming the
file and the key.
"""

from __future__ import annotations

import copy
import csv
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from wrinkle.case import Case, CaseError, read_case, read_case_data
from wrinkle.identification.sensitivity import functional, quantity_names
from wrinkle.studies.design import get_path, variant_overrides

__all__ = [
    "GRADIENTS",
    "Experiment",
    "FitError",
    "FitParameter",
    "FitProblem",
    "case_of",
    "read_fit",
]

GRADIENTS = ("auto", "adjoint", "finite-difference")
FIT_KEYS = {"case", "tolerance", "fit_tolerance", "max_evaluations", "parameter", "experiment"}
PARAMETER_KEYS = {"path", "start", "bounds", "gradient"}
EXPERIMENT_KEYS = {"name", "case", "data", "x", "y", "quantity", "full_load", "weight"}
# the relative change of a parameter with which "auto" tests whether the adjoint applies
PROBE_CHANGE = 1e-3


class FitError(ValueError):
    """Bad input in a fit file; the message names the file and the key."""


@dataclass(frozen=True)
class FitParameter:
    """A case key to identify: its dotted path, start value, bounds (low, high; infinite
    where open) and how its gradient is found ("adjoint" or "finite-difference")."""

    path: str
    start: float
    bounds: tuple[float, float]
    gradient: str

    @property
    def scale(self) -> float:
        """The size the optimiser measures the parameter in: |start|, else the bounds'
        width, else 1."""
        if self.start != 0.0:
            return abs(self.start)
        width = self.bounds[1] - self.bounds[0]
        return width if math.isfinite(width) else 1.0


@dataclass(frozen=True)
class Experiment:
    """One measured experiment: its case file and TOML data (``base``), the measured load
    values x (n_points,) and the load factors x / full_load they are reached at, the
    measured columns (n_points, n_quantities) with their names and the model quantities
    they are, and the weight of its residuals."""

    name: str
    case: Path
    base: dict[str, Any] = field(repr=False)
    data: Path
    x_name: str
    x: np.ndarray
    load_factors: np.ndarray
    columns: tuple[str, ...]
    quantities: tuple[str, ...]
    measured: np.ndarray
    weight: float = 1.0


@dataclass(frozen=True)
class FitProblem:
    """A fit file read: its parameters and experiments, the solver tolerance of every solve,
    the optimiser's tolerance and its most residual evaluations."""

    source: Path
    parameters: tuple[FitParameter, ...]
    experiments: tuple[Experiment, ...]
    tolerance: float = 1e-10
    fit_tolerance: float = 1e-10
    max_evaluations: int = 100

    @property
    def start(self) -> dict[str, float]:
        return {p.path: p.start for p in self.parameters}


def case_of(experiment: Experiment, assignment: dict[str, float], tolerance: float) -> Case:
    """The experiment's case with the parameters' values ``assignment`` set and the solver
    tolerance ``tolerance`` (CaseError if the values make no valid case)."""
    values = {**assignment, "solver.tolerance": tolerance}
    return read_case(experiment.case, variant_overrides(experiment.base, values))


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _load(source: Path) -> dict[str, Any]:
    try:
        with open(source, "rb") as handle:
            return tomllib.load(handle)
    except OSError as error:
        raise FitError(f"{source}: cannot be read ({error.strerror or error})") from None
    except ValueError as error:  # tomllib.TOMLDecodeError
        raise FitError(f"{source}: not valid TOML ({error})") from None


def _case_data(path: Path, where: str, fail) -> dict[str, Any]:
    try:
        data = read_case_data(path)
    except CaseError as error:
        fail(where, str(error))
    data = copy.deepcopy(data)
    if not isinstance(data.setdefault("solver", {}), dict):
        fail(where, f"{path}: [solver] must be a table")
    return data


def _check_keys(table: Any, where: str, keys: set[str], fail) -> None:
    """Fail unless ``table`` is a table of some of ``keys``."""
    if not isinstance(table, dict):
        fail(where, "must be a table")
    unknown = sorted(set(table) - keys)
    if unknown:
        fail(where, f"unknown key '{unknown[0]}' (keys: {', '.join(sorted(keys))})")


def _read_columns(path: Path, names: list[str], where: str, fail) -> dict[str, np.ndarray]:
    """The named columns of a measured CSV file (a header row, then numbers)."""
    try:
        with open(path, newline="") as handle:
            rows = list(csv.reader(handle))
    except OSError as error:
        fail(where, f"data '{path}' cannot be read ({error.strerror or error})")
    if not rows:
        fail(where, f"data '{path}' is empty")
    header = [name.strip() for name in rows[0]]
    columns: dict[str, np.ndarray] = {}
    for name in names:
        if name not in header:
            fail(where, f"data '{path}' has no column {name!r} (columns: {', '.join(header)})")
        index = header.index(name)
        values = []
        for line, row in enumerate(rows[1:], start=2):
            if not any(cell.strip() for cell in row):
                continue
            try:
                value = float(row[index])
            except (IndexError, ValueError):
                fail(where, f"data '{path}' line {line}: column {name!r} is not a number")
            if not math.isfinite(value):
                fail(where, f"data '{path}' line {line}: column {name!r} is not finite")
            values.append(value)
        columns[name] = np.array(values)
    return columns


def _read_experiment(
    table: Any, where: str, folder: Path, default_case: Path | None, fail
) -> Experiment:
    _check_keys(table, where, EXPERIMENT_KEYS, fail)
    name = table.get("name", where)
    if not isinstance(name, str) or not name:
        fail(where, f"'name' must be a text, got {name!r}")
    if "case" in table:
        if not isinstance(table["case"], str):
            fail(where, "'case' must name a case file")
        case = (folder / table["case"]).resolve()
    elif default_case is not None:
        case = default_case
    else:
        fail(where, "no 'case': give one here or at the top level")
    for key in ("data", "x"):
        if not isinstance(table.get(key), str):
            fail(where, f"'{key}' must be given, as a text")
    y = table.get("y")
    y = [y] if isinstance(y, str) else y
    if not isinstance(y, list) or not y or not all(isinstance(v, str) for v in y):
        fail(where, f"'y' must name a measured column or a list of them, got {y!r}")
    quantity = table.get("quantity", y)
    quantity = [quantity] if isinstance(quantity, str) else quantity
    if (
        not isinstance(quantity, list)
        or len(quantity) != len(y)
        or not all(isinstance(v, str) for v in quantity)
    ):
        fail(where, f"'quantity' must name one model quantity per column of 'y', got {quantity!r}")
    full_load = table.get("full_load", 1.0)
    if not _number(full_load) or full_load == 0:
        fail(where, f"'full_load' must be a non-zero number, got {full_load!r}")
    weight = table.get("weight", 1.0)
    if not _number(weight) or weight <= 0:
        fail(where, f"'weight' must be a number > 0, got {weight!r}")
    data = (folder / table["data"]).resolve()
    columns = _read_columns(data, [table["x"], *y], where, fail)
    x = columns[table["x"]]
    keep = x != 0.0  # the reference state: nothing to fit
    load_factors = x[keep] / float(full_load)
    if load_factors.size == 0:
        fail(where, f"data '{data}' has no point away from x = 0")
    if np.any(load_factors <= 0) or np.any(np.diff(load_factors) <= 0):
        fail(
            where,
            f"data '{data}': x / full_load must be > 0 and increase from row to row "
            "(one loading, in order)",
        )
    measured = np.stack([columns[name][keep] for name in y], axis=1)
    base = _case_data(case, where, fail)
    return Experiment(
        name,
        case,
        base,
        data,
        table["x"],
        x[keep],
        load_factors,
        tuple(y),
        tuple(quantity),
        measured,
        float(weight),
    )


def _refuse(case: Case, where: str, fail) -> None:
    """Fail for a case the fit cannot follow: its path must be one load-controlled one."""
    settings = case.settings
    if case.steps:
        fail(where, f"{case.source}: [[step]] tables: a fit follows one proportional path")
    if settings.control != "load":
        fail(where, f"{case.source}: solver control = {settings.control!r}: a fit needs 'load'")
    if case.model.gas is not None:
        fail(where, f"{case.source}: a gas load: a fit needs a load-controlled path")
    if settings.stop is not None:
        fail(where, f"{case.source}: solver stop: a fit sets the load factors itself")
    if case.form_finding is not None:
        fail(where, f"{case.source}: [formfinding]: a fit solves the case's model as it is")


def _same_discretisation(one: Case, other: Case) -> bool:
    """Whether two cases have the same mesh, supports and supported values: then a
    parameter changes only the forces at fixed displacements, and the adjoint applies."""
    a, b = one.model, other.model
    return (
        a.mesh.n_nodes == b.mesh.n_nodes
        and np.array_equal(a.mesh.triangles, b.mesh.triangles)
        and np.array_equal(a.mesh.nodes, b.mesh.nodes)
        and np.array_equal(a.constrained, b.constrained)
        and np.array_equal(a.prescribed, b.prescribed)
    )


def _read_parameter(
    table: Any, where: str, experiments: list[Experiment], tolerance: float, fail
) -> FitParameter:
    _check_keys(table, where, PARAMETER_KEYS, fail)
    path = table.get("path")
    if not isinstance(path, str):
        fail(where, f"'path' must be a dotted path such as \"material.E_L\", got {path!r}")
    gradient = table.get("gradient", "auto")
    if gradient not in GRADIENTS:
        fail(where, f"'gradient' must be one of {', '.join(GRADIENTS)}, got {gradient!r}")
    bounds = table.get("bounds", [-math.inf, math.inf])
    if (
        not isinstance(bounds, list)
        or len(bounds) != 2
        or not all(isinstance(b, int | float) and not isinstance(b, bool) for b in bounds)
        or not bounds[0] < bounds[1]
    ):
        fail(where, f"'bounds' must be [low, high] with low < high, got {bounds!r}")
    low, high = float(bounds[0]), float(bounds[1])
    first = experiments[0]
    start = table.get("start")
    if start is None:
        try:
            start = get_path(first.base, path)
        except ValueError as error:
            fail(where, f"path '{path}': {error}")
        if not _number(start):
            fail(where, f"path '{path}': the case has no number there; give 'start'")
    if not _number(start):
        fail(where, f"'start' must be a number, got {start!r}")
    start = float(start)
    if not low <= start <= high:
        fail(where, f"'bounds' [{low:g}, {high:g}] exclude the start {start:g}")
    parameter = FitParameter(path, start, (low, high), "adjoint")
    changed = start + PROBE_CHANGE * parameter.scale
    if changed > high:
        changed = start - PROBE_CHANGE * parameter.scale
    adjoint = True
    for experiment in experiments:
        try:
            at_start = case_of(experiment, {path: start}, tolerance)
            moved = case_of(experiment, {path: changed}, tolerance)
        except ValueError as error:  # a path the case has not, a value it cannot take
            fail(where, f"path '{path}' in experiment '{experiment.name}': {error}")
        adjoint = adjoint and _same_discretisation(at_start, moved)
    if gradient == "adjoint" and not adjoint:
        fail(
            where,
            f"path '{path}' changes the mesh or the supported values: its gradient needs "
            "gradient = 'finite-difference' (or 'auto')",
        )
    method = "finite-difference" if gradient == "finite-difference" or not adjoint else "adjoint"
    return FitParameter(path, start, (low, high), method)


def read_fit(path: str | Path) -> FitProblem:
    """Read a fit file (the module docstring). Raises FitError, one line naming the file and
    the key, for bad input: an unknown key, a case that cannot be read or that the fit
    cannot follow, a parameter path the case does not have, bounds that exclude the start,
    a measured file without a named column, a quantity the case has not."""
    source = Path(path)

    def fail(where: str, message: str) -> NoReturn:
        raise FitError(f"{source}: {where}: {message}")

    data = _load(source)
    unknown = sorted(set(data) - FIT_KEYS)
    if unknown:
        fail("top level", f"unknown key '{unknown[0]}' (keys: {', '.join(sorted(FIT_KEYS))})")
    default_case = None
    if "case" in data:
        if not isinstance(data["case"], str):
            fail("top level", "'case' must name a case file")
        default_case = (source.parent / data["case"]).resolve()
    tolerance = data.get("tolerance", 1e-10)
    fit_tolerance = data.get("fit_tolerance", 1e-10)
    for key, value in (("tolerance", tolerance), ("fit_tolerance", fit_tolerance)):
        if not _number(value) or not 0 < value < 1:
            fail("top level", f"'{key}' must be a number between 0 and 1, got {value!r}")
    max_evaluations = data.get("max_evaluations", 100)
    if not isinstance(max_evaluations, int) or isinstance(max_evaluations, bool):
        fail("top level", f"'max_evaluations' must be a whole number, got {max_evaluations!r}")
    if max_evaluations < 1:
        fail("top level", f"'max_evaluations' must be at least 1, got {max_evaluations}")
    tables = data.get("experiment")
    if not isinstance(tables, list) or not tables:
        fail("[[experiment]]", "at least one experiment is needed")
    experiments = [
        _read_experiment(t, f"[[experiment]] {i + 1}", source.parent, default_case, fail)
        for i, t in enumerate(tables)
    ]
    if len({e.name for e in experiments}) != len(experiments):
        fail("[[experiment]]", "two experiments have the same name")
    tables = data.get("parameter")
    if not isinstance(tables, list) or not tables:
        fail("[[parameter]]", "at least one parameter is needed")
    parameters = [
        _read_parameter(t, f"[[parameter]] {i + 1}", experiments, float(tolerance), fail)
        for i, t in enumerate(tables)
    ]
    if len({p.path for p in parameters}) != len(parameters):
        fail("[[parameter]]", "a path is given twice")
    start = {p.path: p.start for p in parameters}
    for index, experiment in enumerate(experiments):
        where = f"[[experiment]] {index + 1}"
        try:
            case = case_of(experiment, start, float(tolerance))
        except ValueError as error:
            fail(where, f"the parameters' start values make no valid case: {error}")
        _refuse(case, where, fail)
        for name in experiment.quantities:
            if name not in quantity_names(case):
                fail(
                    where,
                    f"'quantity' {name!r} is not a quantity of the case (quantities: "
                    f"{', '.join(quantity_names(case))})",
                )
            functional(case, name)
    return FitProblem(
        source,
        tuple(parameters),
        tuple(experiments),
        float(tolerance),
        float(fit_tolerance),
        int(max_evaluations),
    )
