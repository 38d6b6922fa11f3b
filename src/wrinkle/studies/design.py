"""A parameter study read from TOML: the base case, the parameters and the variants they make.

A study file (docs/studies.md) names a base case file (``case``, relative to the study file),
the parameters to vary (``[[parameter]]``: a dotted ``path`` into the case, such as
``material.E``, ``load.1.value`` or ``material.angle``, with ``values``, a ``range`` or
``bounds``), how they combine (``design``: ``"grid"``, every combination; ``"list"``, the lists
side by side; ``"latin-hypercube"``, ``samples`` points in the parameters' bounds, ``seed``)
and the quantities to collect (``collect``: history columns and ``frequency_N``; default all).

A dotted path addresses the case's TOML data: a table key, or for an array of tables
(``[[load]]``, ``[[material]]``, ...) or of numbers (a ``displacement``) its 1-based index; the
index may be left out of an array of one table (``material.E`` for a single
``[[material]]``). Every variant is the base case
with its values set there (``variant_overrides``), read by ``wrinkle.case.read_case``, which
checks it like any case.
"""

from __future__ import annotations

import copy
import itertools
import math
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from wrinkle.case import Case, CaseError, read_case, read_case_data
from wrinkle.output import ResultWriter

__all__ = [
    "BOOKKEEPING",
    "DESIGNS",
    "Parameter",
    "Study",
    "StudyError",
    "get_path",
    "quantity_names",
    "read_study",
    "set_path",
    "variant_overrides",
]

DESIGNS = ("grid", "list", "latin-hypercube")
# history columns that say how a step was solved, not what the membrane does: not quantities
BOOKKEEPING = ("step", "load_factor", "analysis_step", "time", "iterations", "residual")
STUDY_KEYS = {"case", "design", "samples", "seed", "collect", "parameter"}


class StudyError(ValueError):
    """Bad input in a study file; the message names the file and the key."""


@dataclass(frozen=True)
class Parameter:
    """A varied case key: its dotted path and its values (a list, or a range's points), or
    for a Latin hypercube its bounds (low, high)."""

    path: str
    values: tuple[float, ...] = ()
    bounds: tuple[float, float] | None = None


@dataclass(frozen=True)
class Study:
    """A study read from ``source``: the base case file, the parameters, the design and its
    variants ({path: value} each, in order), and the quantities to collect (None: all)."""

    source: Path
    case: Path
    parameters: tuple[Parameter, ...]
    design: str
    variants: tuple[dict[str, float], ...]
    collect: tuple[str, ...] | None = None
    base: dict[str, Any] = field(default_factory=dict, repr=False)  # the case's TOML data


def _path_parts(path: str) -> list[str]:
    parts = path.split(".")
    if not path or any(not part for part in parts):
        raise ValueError("a dotted path such as 'material.E' or 'load.1.value'")
    return parts


def _container(data: dict[str, Any], parts: list[str]) -> tuple[Any, str | int]:
    """The table or array holding the path's last part, and that part as its key (a 0-based
    index into an array). ValueError naming what is missing."""
    current: Any = data
    walked: list[str] = []
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        if isinstance(current, list):
            if part.isdigit():
                index = int(part) - 1
                if not 0 <= index < len(current):
                    raise ValueError(
                        f"'{'.'.join(walked)}' has {len(current)} table(s); there is no {part}"
                    )
                if last:
                    return current, index
                current, walked = current[index], [*walked, part]
                continue
            if len(current) != 1:
                raise ValueError(
                    f"'{'.'.join(walked)}' has {len(current)} tables: give the number of one, "
                    f"as in '{'.'.join([*walked, '1', *parts[depth:]])}'"
                )
            current = current[0]
        if not isinstance(current, dict):
            raise ValueError(f"'{'.'.join(walked)}' is a value, not a table")
        if last:
            return current, part
        if part not in current:
            raise ValueError(f"the case has no '{'.'.join([*walked, part])}'")
        current, walked = current[part], [*walked, part]
    raise ValueError("an empty path")  # (not reached: the parts are not empty)


def set_path(data: dict[str, Any], path: str, value: float) -> None:
    """Set the case key at the dotted ``path`` of the TOML data ``data`` to ``value``, in
    place (a key the table does not have yet is added: read_case then judges it); a whole
    value where the case has an integer, or nothing, is set as an integer.
    ValueError naming the part of the path that is missing."""
    container, key = _container(data, _path_parts(path))
    present = container[int(key)] if isinstance(container, list) else container.get(key)
    if isinstance(present, (dict, list)):
        raise ValueError(f"'{path}' is a table or a list, not a number")
    whole = isinstance(present, int) or present is None  # (a bool is an int, and not whole)
    if whole and not isinstance(present, bool) and float(value).is_integer():
        container[key] = int(value)  # an integer key (steps, nx, max_iterations) stays one
    else:
        container[key] = value


def get_path(data: dict[str, Any], path: str) -> Any:
    """The value at the dotted ``path`` of the TOML data ``data`` (None where the table has
    no such key). ValueError naming the part of the path that is missing."""
    container, key = _container(data, _path_parts(path))
    return container[int(key)] if isinstance(container, list) else container.get(key)


def variant_overrides(base: dict[str, Any], assignment: dict[str, float]) -> dict[str, Any]:
    """The ``read_case`` overrides of one variant: each top-level table of the base case data
    that the variant changes, whole, with the variant's values set (``set_path``)."""
    data = copy.deepcopy(base)
    for path, value in assignment.items():
        set_path(data, path, value)
    return {key: data[key] for key in {path.split(".")[0] for path in assignment}}


def quantity_names(case: Case) -> list[str]:
    """The quantities a run of ``case`` gives (what a study collects): its history's columns
    but the bookkeeping ones (``BOOKKEEPING``), and frequency_1 .. frequency_N where it asks
    for N modes."""
    with tempfile.TemporaryDirectory() as scratch:
        writer = ResultWriter(
            scratch,
            case.model,
            probes=case.probes,
            analysis_steps=[step.name for step in case.steps] or None,
        )
        names = [name for name in writer.history_header() if name not in BOOKKEEPING]
    if case.modes is not None:
        names += [f"frequency_{k + 1}" for k in range(case.modes.count)]
    return names


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


Fail = Callable[[str, str], NoReturn]


def _read_parameter(table: Any, where: str, fail: Fail) -> Parameter:
    if not isinstance(table, dict):
        fail(where, "must be a table")
    unknown = sorted(set(table) - {"path", "values", "range", "bounds"})
    if unknown:
        fail(where, f"unknown key '{unknown[0]}' (keys: path, values, range, bounds)")
    path = table.get("path")
    if not isinstance(path, str):
        fail(where, f"'path' must be a dotted path such as \"material.E\", got {path!r}")
    given = [key for key in ("values", "range", "bounds") if key in table]
    if len(given) != 1:
        fail(where, "give one of 'values', 'range' and 'bounds'")
    kind = given[0]
    value = table[kind]
    if kind == "values":
        if not isinstance(value, list) or not value or not all(_number(v) for v in value):
            fail(where, f"'values' must be a list of numbers, got {value!r}")
        return Parameter(path, tuple(float(v) for v in value))
    if kind == "range":
        ok = isinstance(value, list) and len(value) == 3 and all(_number(v) for v in value)
        if not ok or value[2] != int(value[2]) or value[2] < 1:
            fail(where, f"'range' must be [start, stop, count] with count >= 1, got {value!r}")
        start, stop, count = float(value[0]), float(value[1]), int(value[2])
        return Parameter(path, tuple(float(v) for v in np.linspace(start, stop, count)))
    ok = isinstance(value, list) and len(value) == 2 and all(_number(v) for v in value)
    if not ok or not value[0] < value[1]:
        fail(where, f"'bounds' must be [low, high] with low < high, got {value!r}")
    return Parameter(path, (), (float(value[0]), float(value[1])))


def _variants(
    parameters: list[Parameter], design: str, samples: int | None, seed: int, fail: Fail
) -> list[dict[str, float]]:
    paths = [p.path for p in parameters]
    if design == "latin-hypercube":
        if any(p.bounds is None for p in parameters):
            fail("[[parameter]]", "a latin-hypercube design needs 'bounds' for every parameter")
        if samples is None:
            fail("top level", "a latin-hypercube design needs 'samples'")
        from scipy.stats import qmc

        unit = qmc.LatinHypercube(d=len(parameters), seed=seed).random(int(samples))
        low = np.array([p.bounds[0] for p in parameters if p.bounds is not None])
        high = np.array([p.bounds[1] for p in parameters if p.bounds is not None])
        points = qmc.scale(unit, low, high)
        return [dict(zip(paths, map(float, row), strict=True)) for row in points]
    if any(p.bounds is not None for p in parameters):
        fail("[[parameter]]", f'\'bounds\' are for design = "latin-hypercube", not "{design}"')
    if design == "list":
        lengths = {len(p.values) for p in parameters}
        if len(lengths) != 1:
            fail(
                "[[parameter]]",
                'design = "list" takes the parameters\' values side by side: give every '
                f"parameter as many values (they have {sorted(lengths)})",
            )
        return [dict(zip(paths, row, strict=True)) for row in zip(*(p.values for p in parameters))]
    return [
        dict(zip(paths, row, strict=True))
        for row in itertools.product(*(p.values for p in parameters))
    ]


def read_study(path: str | Path) -> Study:
    """Read a study file (the module docstring). Raises StudyError, one line naming the file
    and the key, for bad input: an unknown key, a base case that cannot be read, a parameter
    path the case does not have, values that are not numbers, a design its parameters do not
    fit."""
    source = Path(path)

    def fail(where: str, message: str) -> NoReturn:
        raise StudyError(f"{source}: {where}: {message}")

    try:
        with open(source, "rb") as handle:
            import tomllib

            data = tomllib.load(handle)
    except OSError as error:
        raise StudyError(f"{source}: cannot be read ({error.strerror or error})") from None
    except ValueError as error:  # tomllib.TOMLDecodeError
        raise StudyError(f"{source}: not valid TOML ({error})") from None
    unknown = sorted(set(data) - STUDY_KEYS)
    if unknown:
        fail("top level", f"unknown key '{unknown[0]}' (keys: {', '.join(sorted(STUDY_KEYS))})")
    if not isinstance(data.get("case"), str):
        fail("top level", "'case' must name the base case file")
    case = (source.parent / data["case"]).resolve()
    try:
        base = read_case_data(case)
    except CaseError as error:
        fail("'case'", str(error))
    design = data.get("design", "grid")
    if design not in DESIGNS:
        fail("top level", f"'design' must be one of {', '.join(DESIGNS)}, got {design!r}")
    samples = data.get("samples")
    if samples is not None and (not isinstance(samples, int) or samples < 1):
        fail("top level", f"'samples' must be a whole number >= 1, got {samples!r}")
    seed = data.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool):
        fail("top level", f"'seed' must be a whole number, got {seed!r}")
    tables = data.get("parameter")
    if not isinstance(tables, list) or not tables:
        fail("[[parameter]]", "at least one parameter is needed")
    parameters = [_read_parameter(t, f"[[parameter]] {i + 1}", fail) for i, t in enumerate(tables)]
    if len({p.path for p in parameters}) != len(parameters):
        fail("[[parameter]]", "a path is given twice")
    collect = data.get("collect")
    if collect is not None and (
        not isinstance(collect, list) or not all(isinstance(c, str) for c in collect)
    ):
        fail("top level", f"'collect' must be a list of quantity names, got {collect!r}")
    variants = _variants(parameters, design, samples, seed, fail)
    made = None
    for index, parameter in enumerate(parameters):  # each path must address a case key
        first = variants[0][parameter.path]
        try:
            overrides = variant_overrides(base, {parameter.path: first})
        except ValueError as error:
            fail(f"[[parameter]] {index + 1}", f"path '{parameter.path}': {error}")
        try:
            made = read_case(case, overrides)
        except CaseError as error:
            fail(
                f"[[parameter]] {index + 1}",
                f"path '{parameter.path}' = {first:g} does not make a valid case: {error}",
            )
    if collect is not None and made is not None:
        known = quantity_names(made)
        for name in collect:
            if name not in known:
                fail(
                    "top level",
                    f"'collect': {name!r} is not a quantity of this case (quantities: "
                    + ", ".join(known)
                    + ")",
                )
    return Study(
        source,
        case,
        tuple(parameters),
        design,
        tuple(variants),
        None if collect is None else tuple(collect),
        base,
    )
