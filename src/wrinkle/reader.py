"""Reading a results folder back: ``open_results(DIR)`` (issue 22, item 5).

A folder written by ``wrinkle run`` (``wrinkle.output.ResultWriter``) holds summary.json,
history.csv and one step_NNNN.vtu per converged step (step_NNNN.h5 with mesh.h5 and
results.xdmf for ``[output] format = "xdmf"``). ``open_results`` gives them back as
arrays: the summary (a dict), the history (column name -> (n_steps,) array), each step's
load factor and, read from its .vtu when asked, its point and cell data; the mesh in the
reference configuration. It is also what ``wrinkle run --restart`` reads its last step from.

A missing folder or summary, a summary that is not JSON or has no list of steps, a step
without its file or load factor, a .vtu that cannot be read: ValueError, one line naming the
file.
"""

from __future__ import annotations

import csv
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from wrinkle.mesh import Mesh, meshio_read
from wrinkle.xdmf import read_step

__all__ = ["ResultsFolder", "open_results", "read_summary"]

SUMMARY = "summary.json"  # the names of wrinkle.output (which imports this module)
HISTORY = "history.csv"


def read_summary(path: str | os.PathLike) -> dict:
    """summary.json at ``path`` with its list of steps (possibly empty), each with its
    "file" and "load_factor"; ValueError naming the file if it is missing, not valid JSON,
    or damaged."""
    path = Path(path)
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ValueError(f"{path}: not found (is this a folder written by wrinkle run?)") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ValueError(f"{path}: damaged, not readable as JSON ({error})") from None
    steps = summary.get("steps") if isinstance(summary, dict) else None
    if not isinstance(steps, list) or not all(isinstance(step, dict) for step in steps):
        raise ValueError(f"{path}: damaged, it has no list of steps")
    if not all({"file", "load_factor"} <= set(step) for step in steps):
        raise ValueError(f"{path}: damaged, a step lacks its file or load factor")
    for key in ("converged", "message"):
        summary.setdefault(key, False if key == "converged" else "")
    return summary


def _read_history(path: Path) -> dict[str, np.ndarray]:
    """history.csv as column name -> (n_rows,) float array ({} if there is no file)."""
    if not path.is_file():
        return {}
    try:
        with open(path, newline="", encoding="utf-8") as handle:
            rows = list(csv.reader(handle))
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise ValueError(f"{path}: not readable ({error})") from None
    if not rows:
        return {}
    header, body = rows[0], rows[1:]
    if any(len(row) != len(header) for row in body):
        raise ValueError(f"{path}: damaged, a row has not the header's {len(header)} columns")
    try:
        values = np.array(body, dtype=float).reshape(len(body), len(header))
    except ValueError:
        raise ValueError(f"{path}: damaged, a value is not a number") from None
    return {name: values[:, column] for column, name in enumerate(header)}


@dataclass
class ResultsFolder:
    """A results folder read back (``open_results``).

    directory: the folder; summary: summary.json as a dict; history: history.csv, column
    name -> (n_steps,) array; steps: the summary's step entries, in order. ``fields(step)``
    reads a step's .vtu (index into ``steps``, default the last).
    """

    directory: Path
    summary: dict
    history: dict[str, np.ndarray]
    steps: list[dict] = field(default_factory=list)
    _cache: dict[int, Any] = field(default_factory=dict, repr=False)

    def __len__(self) -> int:
        return len(self.steps)

    @property
    def load_factors(self) -> np.ndarray:
        """(n_steps,) the load factor of each converged step."""
        return np.array([float(step["load_factor"]) for step in self.steps])

    def step_data(self, step: int = -1) -> tuple[np.ndarray, np.ndarray, dict, dict]:
        """(nodes (n_nodes, 3), triangles (n_elements, 3), point data, the triangles' cell
        data) of a step's file, .vtu or the xdmf format's .h5; ValueError naming the file if
        it cannot be read. The last step read is kept (one at a time: a 10^6-element step is
        large)."""
        if not self.steps:
            raise ValueError(f"{self.directory / SUMMARY}: no converged step")
        index = range(len(self.steps))[step]  # IndexError for a step out of range
        if index not in self._cache:
            name = str(self.steps[index]["file"])
            self._cache.clear()
            if name.endswith(".h5"):
                self._cache[index] = read_step(self.directory, name)
            else:
                path = self.directory / name
                data = meshio_read(path, f"{path}")
                point = {key: np.asarray(value) for key, value in data.point_data.items()}
                cell = {}
                kinds = [block.type for block in data.cells]
                for key, blocks in data.cell_data.items():
                    for kind, values in zip(kinds, blocks, strict=True):
                        if kind == "triangle":
                            cell[key] = np.asarray(values)
                triangles = data.get_cells_type("triangle")
                nodes = np.asarray(data.points, dtype=float)
                self._cache[index] = (nodes, triangles, point, cell)
        return self._cache[index]

    def mesh(self, step: int = -1) -> Mesh:
        """The mesh (reference configuration) of a step's file: nodes (n_nodes, 3) and the
        triangles (n_elements, 3)."""
        nodes, triangles, _, _ = self.step_data(step)
        return Mesh(nodes, triangles)

    def fields(self, step: int = -1) -> dict[str, np.ndarray]:
        """A step's point data (n_nodes, ...) and cell data of its triangles (n_elements,
        ...) by name ("displacement", "reaction", "stress_nodal", "state", "stress", ...:
        the fields of docs/case-file.md), from its .vtu or .h5 file."""
        _, _, point, cell = self.step_data(step)
        return {**point, **cell}

    def displacement(self, step: int = -1) -> np.ndarray:
        """A step's displacements, (n_nodes * 3,) in the solver's order (x, y, z per node)."""
        return np.asarray(self.fields(step)["displacement"], dtype=float).reshape(-1)


def open_results(directory: str | os.PathLike) -> ResultsFolder:
    """The results folder ``directory`` (written by ``wrinkle run`` or ``Results.save``)
    read back as arrays (``ResultsFolder``); ValueError naming the file for a missing or
    damaged folder. The steps' .vtu files are read when their fields are asked for."""
    folder = Path(directory)
    if not folder.is_dir():
        raise ValueError(f"{folder}: no such results folder")
    summary = read_summary(folder / SUMMARY)
    return ResultsFolder(folder, summary, _read_history(folder / HISTORY), summary["steps"])
