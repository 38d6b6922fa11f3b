"""Writing results as the analysis runs: ParaView files, a JSON summary and a CSV history.

``ResultWriter(out_dir, model)`` writes into ``out_dir``, each time a load step converges
(``write_step``):

- ``step_0001.vtu``, ``step_0002.vtu``, ...: the mesh in the reference configuration with
  point data ``displacement`` (n_nodes, 3) and ``reaction`` (n_nodes, 3; zero except at
  supports), and cell data ``state`` (0 taut, 1 wrinkled, 2 slack), ``tension_direction`` and
  ``wrinkle_direction`` (unit 3-vectors in the deformed configuration, zero where not defined),
  ``principal_stress`` (minor, major Cauchy stress resultant, force per unit current length),
  the same as the scalars ``principal_stress_major`` and ``principal_stress_minor``,
  ``stress`` (the Cauchy stress resultant tensor in global axes, 9 components, force per
  current length), ``strain`` (the Green-Lagrange strain in global reference axes, 9
  components), ``fibre_direction`` (the material axis 1 in the reference),
  ``wrinkling_strain`` (beta) and ``thickness`` (current); point data ``stress_nodal``, the
  current-area-weighted average of ``stress`` over the elements at each node. In ParaView,
  open ``results.pvd`` and apply the "Warp By Vector" filter with the vectors
  ``displacement`` (scale factor 1) to see the deformed membrane; colour by ``state`` and
  add "Glyph" on ``tension_direction`` for the tension field.
- ``results.pvd``: a ParaView collection of the converged steps, timestep = load factor (in
  a staged run, ``analysis_steps``: the total time, analysis step - 1 + load factor).
- with ``file_format="xdmf"`` (``[output] format``) instead of the .vtu files and
  results.pvd: ``mesh.h5`` once, ``step_0001.h5``, ... and ``results.xdmf``
  (``wrinkle.xdmf``), the same fields (the symmetric tensors as their six components);
  ``fields`` chooses the fields of either format (``FIELDS``; "displacement" always), and
  ``precision`` "single" writes the floating-point fields but the displacement and the
  reactions in single precision.
- ``summary.json``: {"converged", "message", "steps": [{"step", "file", "load_factor",
  "iterations", "residual", "states": {"taut", "wrinkled", "slack"}, "reactions":
  {support label: [Fx, Fy, Fz]}, "max_displacement", "residual_history" (the residual
  norm of each iteration of the step's solve), "stopped_by" ("residual" or
  "accuracy"), and for "accuracy" "accuracy_stop": {"residual" (relative to the force scale),
  "energy_gap", "discretisation_error", "contraction", "remaining_change": {quantity:
  value}} (``wrinkle.solvers.stopping``), "controller" where a load path solved the step:
  the step controller's state after it, {"increment" (the next), "in_a_row", "needed",
  "regrown"}, which ``--restart`` continues from, and "pressure" where the model has pressure loads
  and "enclosed_volume" where they enclose a volume (``StepResult``), "strain_energy",
  "external_work" (trapezoidal rule over the steps, ``ResultWriter._quantities``), "areas"
  {"taut", "wrinkled", "slack"} (current), "max_principal_stress" {"value", "element",
  "position"}, and "moments" {label: [Mx, My, Mz]} for supports with ``moment_about``}],
  "wall_time" (seconds since the writer was made), "reference_volume" where the membrane
  encloses a volume, the last step's "strain_energy", "external_work" and
  "enclosed_volume", and "units" and "case" if given}. A staged run (``analysis_steps``,
  the names of its ``[[step]]`` tables) adds "analysis_steps" and, to each step,
  "analysis_step" (from 1) and "time", which history.csv has after load_factor.
- with ``write_modes`` (a case's ``[modes]``): ``mode_01.vtu``, ``mode_02.vtu``, ...: the
  mesh in the reference configuration with point data ``displacement`` (the state the modes
  are about) and ``mode`` (the mode shape, scaled to a largest nodal amplitude of 1, length
  units); ``modes.pvd``, a collection of them with timestep = mode number, which ParaView
  steps through (apply "Warp By Vector" on ``displacement``, then another on ``mode`` with
  the amplitude to show as its scale factor); and in the
  summary ``"frequencies"`` (1/time, Hz in SI units, ascending) and ``"modes"``: {"mass",
  "shift" (1/time^2), "files", "residuals"} (``wrinkle.modes.Modes``).
- ``history.csv``: one row per step: step, load_factor, iterations, residual, then pressure
  and enclosed_volume where the summary has them, taut, wrinkled, slack, strain_energy,
  external_work, taut_area, wrinkled_area, slack_area, max_principal_stress,
  ``<support>_Fx/_Fy/_Fz`` per support, ``<support>_Mx/_My/_Mz`` per support with a moment
  point, ``<probe>_ux/_uy/_uz`` per probe (mean displacement of the probe's nodes).

Every file is written to a temporary file in ``out_dir`` and moved into place with
``os.replace``, so a crash or Ctrl-C leaves every finished step readable, and ``summary.json``
says where the analysis stopped ("converged": false, "message": "running") until ``finish``.

Units are consistent units; ``units`` (e.g. {"length": "m", "force": "N"}) is recorded in the
summary for the pictures (``wrinkle.plot.plot_results``) and the reader.
"""

from __future__ import annotations

import csv
import io
import json
import os
import re
import secrets
import time
from collections.abc import Callable, Mapping, Sequence
from functools import partial
from pathlib import Path
from types import ModuleType
from xml.sax.saxutils import quoteattr

import numpy as np

from wrinkle.cables import CableState
from wrinkle.element import ElementResult
from wrinkle.mesh import require_meshio
from wrinkle.post import (
    ElementReport,
    element_report,
    nodal_average,
    support_moments,
    support_reactions,
)
from wrinkle.reader import HISTORY, SUMMARY, open_results
from wrinkle.wrinkling import STATE_NAMES
from wrinkle.xdmf import COLLECTION as XDMF_COLLECTION
from wrinkle.xdmf import (
    MESH_FILE,
    layout,
    packed,
    read_layout,
    require_h5py,
    write_collection,
    write_mesh_file,
    write_step_file,
)

__all__ = [
    "COLLECTION",
    "MODE_COLLECTION",
    "HISTORY",
    "STEP_FILE",
    "SUMMARY",
    "ResultWriter",
    "atomic_write",
    "save_results",
    "step_file_name",
]

# the pictures `wrinkle plot` draws into a results folder (wrinkle.plot), removed with the old
# steps when a new run starts there
STATE_PICTURE, STRESS_PICTURE, CURVE_PICTURE, VOLUME_PICTURE = (
    "state.png",
    "principal_stress.png",
    "load_displacement.png",
    "pressure_volume.png",
)
SHAPE_PICTURE, STRESS_3D_PICTURE, HEIGHT_PICTURE, FIBRE_PICTURE, NEWTON_PICTURE = (
    "shape_3d.png",
    "stress_3d.png",
    "height.png",
    "fibres.png",
    "convergence.png",
)
PICTURES = (
    STATE_PICTURE,
    STRESS_PICTURE,
    CURVE_PICTURE,
    VOLUME_PICTURE,
    SHAPE_PICTURE,
    STRESS_3D_PICTURE,
    HEIGHT_PICTURE,
    FIBRE_PICTURE,
    NEWTON_PICTURE,
)
COLLECTION = "results.pvd"
MODE_COLLECTION = "modes.pvd"
STEP_FILE = re.compile(r"step_\d{4,}\.(vtu|h5)")
FORMATS = ("vtu", "xdmf")  # [output] format
# the fields a step file may hold ([output] fields); "displacement" is always written
POINT_FIELDS = ("displacement", "reaction", "stress_nodal")
CELL_FIELDS = (
    "state",
    "tension_direction",
    "wrinkle_direction",
    "principal_stress",
    "principal_stress_major",
    "principal_stress_minor",
    "stress",
    "strain",
    "fibre_direction",
    "wrinkling_strain",
    "thickness",
)
CABLE_FIELDS = ("cable_force", "cable_taut")  # on the cables' line cells, .vtu only
TENSORS = ("stress", "strain", "stress_nodal")  # symmetric: Tensor6 in the xdmf format
PRECISIONS = ("double", "single")  # [output] precision of the floating-point fields
EXACT_FIELDS = ("displacement", "reaction")  # always in double precision (restart, balance)
FIELDS = (*POINT_FIELDS, *CELL_FIELDS, *CABLE_FIELDS)
MODE_FILE = re.compile(r"mode_\d{2,}\.vtu")


def step_file_name(index: int, file_format: str = "vtu") -> str:
    """File name of the ``index``-th converged step (1-based): step_0001.vtu, ... (.h5 for
    the xdmf format)."""
    return f"step_{index:04d}.{'h5' if file_format == 'xdmf' else 'vtu'}"


class ResultsWriteError(OSError):
    """A results file could not be written (a full disk, a folder made read-only): the
    message names the file and the reason; the files written before it are intact."""


def atomic_write(path: Path, write: Callable[[Path], None]) -> None:
    """Call ``write(temporary_path)`` on a temporary file next to ``path``, flush it to disk
    and move it onto ``path`` with os.replace: readers see the old file or the whole new one.
    The temporary file is removed if ``write`` fails or is interrupted; an OSError becomes a
    ResultsWriteError naming ``path``."""
    path = Path(path)
    try:
        while True:  # mode "x": a new file with the usual permissions (not mkstemp's 0600)
            temporary = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
            try:
                open(temporary, "x").close()
                break
            except FileExistsError:  # pragma: no cover - 32 random bits collided
                continue
    except OSError as error:
        raise ResultsWriteError(f"cannot write {path}: {error.strerror or error}") from None
    try:
        write(temporary)
        with open(temporary, "rb+") as handle:
            os.fsync(handle.fileno())
        os.replace(temporary, path)
    except OSError as error:
        temporary.unlink(missing_ok=True)
        raise ResultsWriteError(f"cannot write {path}: {error.strerror or error}") from None
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def _write_mesh(meshio: ModuleType, mesh, temporary: Path) -> None:
    meshio.write(temporary, mesh, file_format="vtu")


def _write_text(path: Path, text: str) -> None:
    def write(temporary: Path) -> None:
        temporary.write_text(text, encoding="utf-8")

    atomic_write(path, write)


class ResultWriter:
    """Writes each converged load step of ``model`` into ``out_dir`` (see the module docstring).

    probes: {name: node indices (k,)} whose mean displacement goes into history.csv;
    units: e.g. {"length": "m", "force": "N"}, recorded in summary.json; case: the case file
    the model came from, recorded in summary.json. Supports are ``model.supports`` (objects
    with ``label`` and ``dofs``), read when the writer is made; each one's reaction sums only
    the components it holds, and supports with the same label are reported as one (summed
    over the union of their components). Creates ``out_dir``; removes the step_NNNN.vtu
    files and pictures of an earlier run there. Raises ValueError for a probe with no nodes or
    with nodes outside the mesh.
    """

    def __init__(
        self,
        out_dir: str | os.PathLike,
        model,
        probes: Mapping[str, np.ndarray] | None = None,
        units: Mapping[str, str] | None = None,
        case: str | os.PathLike | None = None,
        resume: bool = False,
        file_format: str = "vtu",
        fields: Sequence[str] | None = None,
        precision: str = "double",
        analysis_steps: Sequence[str] | None = None,
    ):
        self._start = time.perf_counter()
        self.analysis_steps = None if analysis_steps is None else [str(n) for n in analysis_steps]
        if precision not in PRECISIONS:
            raise ValueError(f"output precision {precision!r}: one of {', '.join(PRECISIONS)}")
        self.precision = precision
        if file_format not in FORMATS:
            raise ValueError(f"output format {file_format!r}: one of {', '.join(FORMATS)}")
        unknown = sorted(set(fields or ()) - set(FIELDS))
        if unknown:
            raise ValueError(f"output field {unknown[0]!r} unknown (fields: {', '.join(FIELDS)})")
        if file_format == "xdmf":
            require_h5py()
        self.file_format = file_format
        self.fields = None if fields is None else frozenset(fields)
        self._layouts: list[list] = []  # each xdmf step's fields (names, shapes, types)
        self.out_dir = Path(out_dir)
        self.model = model
        n_nodes = model.mesh.n_nodes
        self.probes: dict[str, np.ndarray] = {}
        for name, nodes in (probes or {}).items():
            nodes = np.atleast_1d(np.asarray(nodes))
            if nodes.dtype == bool:
                nodes = np.flatnonzero(nodes)
            if nodes.size == 0 or not np.issubdtype(nodes.dtype, np.integer):
                raise ValueError(f"probe {name!r}: give a non-empty array of node indices")
            if np.any((nodes < 0) | (nodes >= n_nodes)):
                raise ValueError(f"probe {name!r}: node indices must lie in 0..{n_nodes - 1}")
            self.probes[str(name)] = nodes.astype(np.int64)
        self.supports = list(getattr(model, "supports", []))
        self.support_labels = list(dict.fromkeys(str(s.label) for s in self.supports))
        self.units = dict(units) if units else None
        self.case = str(case) if case is not None else None
        self.steps: list[dict] = []
        self.rows: list[list] = []
        self.modes: dict | None = None  # the summary's "modes" (write_modes)
        self.form_finding: dict | None = None  # the summary's "formfinding" (Case.run)
        self._last_displacement = np.zeros(model.n_dofs if hasattr(model, "n_dofs") else 0)
        self._last_forces: np.ndarray | None = None  # f* at the last step (external work)
        self._work = 0.0  # the loads' and supports' work up to the last step
        self.moment_labels = list(
            dict.fromkeys(
                str(s.label) for s in self.supports if getattr(s, "moment_about", None) is not None
            )
        )
        self.frequencies: list[float] | None = None
        # the pressure column where the model has pressure loads, the enclosed volume where
        # they enclose one (``DiscreteSystem.volume_closure``)
        self.has_pressure = getattr(model, "pressure_value", None) is not None
        self.system = model.discretise() if hasattr(model, "discretise") else None
        self._cables: tuple[int, CableState] | None = None  # (step id, its state), reused
        system = self.system if self.has_pressure else None
        self.has_volume = system is not None and system.volume_closure() is None
        self.reference_volume = (
            system.reference_volume if system is not None and self.has_volume else None
        )
        self.out_dir.mkdir(parents=True, exist_ok=True)
        kept: set[str] = set()
        if resume:
            kept = self._resume()
        pictures = {*PICTURES, MODE_COLLECTION}
        # the other format's collection would show an old run
        pictures.add(COLLECTION if file_format == "xdmf" else XDMF_COLLECTION)
        if file_format == "xdmf":
            mesh = model.mesh
            if not (resume and (self.out_dir / MESH_FILE).is_file()):
                atomic_write(
                    self.out_dir / MESH_FILE,
                    partial(write_mesh_file, nodes=mesh.nodes, triangles=mesh.triangles),
                )
            kept.add(MESH_FILE)
        else:
            pictures.add(MESH_FILE)
        for old in self.out_dir.iterdir():
            if old.name in kept:
                continue
            if (
                STEP_FILE.fullmatch(old.name)
                or MODE_FILE.fullmatch(old.name)
                or old.name in pictures
            ):
                old.unlink()
        self._write_collection()
        self._write_history()
        self._write_summary(False, "running")

    def _resume(self) -> set[str]:
        """Take up the steps already in the folder (``wrinkle run --restart``): the summary's
        steps, the history's rows, the work and the state of the last step. Returns the
        names of the step files kept. ValueError naming the file if the folder's history
        has other columns than this model's or its last step another mesh."""
        folder = open_results(self.out_dir)
        self.steps = [dict(step) for step in folder.summary["steps"]]
        self.form_finding = folder.summary.get("formfinding")
        header = self.history_header()
        path = self.out_dir / HISTORY
        with open(path, newline="", encoding="utf-8") as handle:
            rows = list(csv.reader(handle))
        if not rows or rows[0] != header or len(rows) - 1 != len(self.steps):
            raise ValueError(
                f"{path}: its columns or rows are not those of this case's run "
                f"({len(self.steps)} steps, columns {', '.join(header)})"
            )
        self.rows = rows[1:]
        if self.steps:
            u = folder.displacement(-1)
            if u.shape != self._last_displacement.shape:
                raise ValueError(
                    f"{self.out_dir / self.steps[-1]['file']}: a mesh of {u.size // 3} nodes, "
                    f"not the case's {self._last_displacement.size // 3}"
                )
            self._last_displacement = u
            self._work = float(self.steps[-1].get("external_work", 0.0))
            if self.system is not None:
                self._last_forces = self.system.strain_energy_and_forces(u)[1]
        if self.file_format == "xdmf":
            self._layouts = [read_layout(self.out_dir / str(s["file"])) for s in self.steps]
        return {str(step["file"]) for step in self.steps}

    # -- per step -----------------------------------------------------------------------
    def write_step(self, step) -> Path:
        """Write one converged ``StepResult``: its .vtu, then the collection, the history and
        the summary ("running"). Returns the path of the .vtu."""
        index = len(self.steps) + 1
        name = step_file_name(index, self.file_format)
        path = self.out_dir / name
        displacement = np.asarray(step.displacement, dtype=float)
        # one evaluation of the elements for the fields and the energies
        elements = None
        if self.system is not None:
            elements = self.system.evaluate_elements(displacement, stiffness=False)
        report = element_report(self.model, displacement, elements)
        self._write_step_file(path, step, report)
        u = displacement.reshape(-1, 3)
        reactions = np.asarray(step.reactions, dtype=float)
        support_forces = support_reactions(self.supports, reactions)
        positions = self.model.mesh.nodes + u
        moments = support_moments(self.supports, reactions, positions)
        quantities = self._quantities(displacement, report, positions, elements)
        self._last_displacement = displacement
        probe_means = {name: u[nodes].mean(axis=0) for name, nodes in self.probes.items()}
        states = [int(s) for s in step.states]
        entry = {
            "step": index,
            "file": name,
            "load_factor": float(step.load_factor),
            **self._stage_keys(step),
            "iterations": int(step.iterations),
            "residual": float(step.residual),
            "states": dict(zip(STATE_NAMES, states)),
            "reactions": support_forces,
            "max_displacement": float(np.linalg.norm(u, axis=1).max(initial=0.0)),
            "stopped_by": getattr(step, "stopped_by", "residual"),
            "residual_history": [float(r) for r in getattr(step, "residual_history", ())],
        }
        stop = getattr(step, "stop_report", None)
        if stop is not None:
            entry["accuracy_stop"] = {key: value for key, value in stop.items() if key != "rule"}
        controller = getattr(step, "controller", None)
        if controller is not None:
            entry["controller"] = dict(controller)
        extra: list[float | None] = []
        for name, present in (
            ("pressure", self.has_pressure),
            ("enclosed_volume", self.has_volume),
        ):
            if present:
                value = getattr(step, name, None)
                number = None if value is None else float(value)
                entry[name] = number
                extra.append(number)
        entry.update(quantities)
        if moments:
            entry["moments"] = moments
        cables = self.cable_state(step)
        if cables is not None and self.system is not None and self.system.cables is not None:
            entry["cables"] = self.system.cables.summary(cables.axial, cables.taut)
        self.steps.append(entry)
        row: list = [index, float(step.load_factor), *self._stage_keys(step).values()]
        row += [int(step.iterations), float(step.residual)]
        row += extra
        row += states
        row += [quantities[key] for key in ("strain_energy", "external_work")]
        row += [quantities["areas"][state] for state in STATE_NAMES]
        row.append(quantities["max_principal_stress"]["value"])
        for force in support_forces.values():
            row += force
        for label in self.moment_labels:
            row += moments[label]
        for mean in probe_means.values():
            row += mean.tolist()
        self.rows.append(row)
        self._write_collection()
        self._write_history()
        self._write_summary(False, "running")
        return path

    def _stage_keys(self, step) -> dict[str, int | float]:
        """A staged run's "analysis_step" (its number, from 1) and "time" (the number minus
        1 plus the load factor) of a step; none for a run of one path."""
        if self.analysis_steps is None:
            return {}
        number = int(getattr(step, "analysis_step", 1))
        return {"analysis_step": number, "time": float(getattr(step, "time", step.load_factor))}

    def _quantities(
        self,
        u: np.ndarray,
        report: ElementReport,
        positions: np.ndarray,
        elements: ElementResult | None = None,
    ) -> dict:
        """The step's "strain_energy" (``DiscreteSystem.strain_energy_and_forces``),
        "external_work" (the loads' and the supports' work from the reference state, by the
        trapezoidal rule over the steps on the internal forces f*, which at a balanced state
        are the applied loads plus the reactions), "areas" (current area of each state) and
        "max_principal_stress" ({"value", "element", "position"}: the largest major principal
        Cauchy stress resultant, its element and the element's current centroid)."""
        if self.system is not None:
            energy, forces = self.system.strain_energy_and_forces(u, elements)
            previous = self._last_forces
            if previous is None:
                previous = self.system.strain_energy_and_forces(np.zeros_like(u))[1]
            self._work += 0.5 * float((previous + forces) @ (u - self._last_displacement))
            self._last_forces = forces
        else:
            energy = float("nan")
            self._work = float("nan")
        areas = np.bincount(report.state, weights=report.area, minlength=len(STATE_NAMES))
        major = report.principal_stress[:, 1]
        largest = int(np.argmax(major))
        centroid = positions[self.model.mesh.triangles[largest]].mean(axis=0)
        return {
            "strain_energy": energy,
            "external_work": self._work,
            "areas": dict(zip(STATE_NAMES, (float(a) for a in areas), strict=True)),
            "max_principal_stress": {
                "value": float(major[largest]),
                "element": largest,
                "position": centroid.tolist(),
            },
        }

    def cable_state(self, step) -> CableState | None:
        """The cables' ``CableState`` at a step (None without cables), computed once."""
        if self.system is None or self.system.cables is None:
            return None
        if self._cables is None or self._cables[0] != id(step):
            u = np.asarray(step.displacement, dtype=float)
            self._cables = (id(step), self.system.cable_state(u, tangent=False))
        return self._cables[1]

    def write_modes(self, modes) -> list[Path]:
        """Write the natural modes (``wrinkle.modes.Modes``) of the last step written:
        mode_NN.vtu, modes.pvd and, in the summary, their frequencies (module docstring).
        Returns the paths of the .vtu files."""
        meshio = require_meshio()
        mesh = self.model.mesh
        state = self._last_displacement.reshape(-1, 3)
        width = max(2, len(str(len(modes))))
        paths, names = [], []
        for index in range(len(modes)):
            shape = np.asarray(modes.shapes[index], dtype=float).reshape(-1, 3)
            largest = float(np.linalg.norm(shape, axis=1).max(initial=0.0))
            name = f"mode_{index + 1:0{width}d}.vtu"
            vtu = meshio.Mesh(
                mesh.nodes,
                [("triangle", mesh.triangles)],
                point_data={
                    "displacement": state,
                    "mode": shape / largest if largest > 0 else shape,
                },
            )
            path = self.out_dir / name
            atomic_write(path, partial(_write_mesh, meshio, vtu))
            paths.append(path)
            names.append(name)
        entries = [
            f'    <DataSet timestep="{index + 1}" group="" part="0" file={quoteattr(name)}/>'
            for index, name in enumerate(names)
        ]
        self._write_pvd(MODE_COLLECTION, entries)
        self.frequencies = [float(f) for f in modes.frequencies]
        self.modes = {
            "mass": modes.mass,
            "shift": float(modes.shift),
            "files": names,
            "residuals": [float(r) for r in modes.residuals],
        }
        self._write_summary(False, "running")
        return paths

    def finish(self, converged: bool, message: str) -> Path:
        """Write the final summary.json (wall time since the writer was made); returns it."""
        return self._write_summary(bool(converged), str(message))

    # -- files --------------------------------------------------------------------------
    def _fields(self, step, report: ElementReport) -> tuple[dict, dict]:
        """The step's point data (n_nodes, ...) and the triangles' cell data (n_elements,
        ...) by name: those of ``fields`` (all when it is None), "displacement" always."""
        mesh = self.model.mesh
        point_data = {
            "displacement": lambda: np.asarray(step.displacement, dtype=float).reshape(-1, 3),
            "reaction": lambda: np.asarray(step.reactions, dtype=float).reshape(-1, 3),
            "stress_nodal": lambda: nodal_average(
                mesh.triangles, report.cauchy_stress, report.area
            ).reshape(-1, 9),
        }
        cell_data = {
            "state": lambda: report.state.astype(np.int32),
            "tension_direction": lambda: report.tension_direction,
            "wrinkle_direction": lambda: report.wrinkle_direction,
            "principal_stress": lambda: report.principal_stress,
            "principal_stress_major": lambda: report.principal_stress[:, 1].copy(),
            "principal_stress_minor": lambda: report.principal_stress[:, 0].copy(),
            "stress": lambda: report.cauchy_stress.reshape(-1, 9),
            "strain": lambda: report.strain.reshape(-1, 9),
            "fibre_direction": lambda: report.fibre_direction,
            "wrinkling_strain": lambda: report.wrinkling_strain,
            "thickness": lambda: report.thickness,
        }
        chosen = self.fields

        def wanted(name: str) -> bool:
            return chosen is None or name in chosen or name == "displacement"

        single = self.precision == "single"

        def stored(name: str, values: np.ndarray) -> np.ndarray:
            values = np.ascontiguousarray(values)
            if single and values.dtype == np.float64 and name not in EXACT_FIELDS:
                return values.astype(np.float32)
            return values

        return (
            {name: stored(name, make()) for name, make in point_data.items() if wanted(name)},
            {name: stored(name, make()) for name, make in cell_data.items() if wanted(name)},
        )

    def _write_step_file(self, path: Path, step, report: ElementReport) -> None:
        """The step's fields as ``path`` (step_NNNN.vtu, or step_NNNN.h5 for xdmf)."""
        point_data, cell_data = self._fields(step, report)
        if self.file_format == "xdmf":
            write = partial(
                write_step_file, point_data=point_data, cell_data=cell_data, symmetric=TENSORS
            )
            atomic_write(path, write)
            self._layouts.append(layout(packed(point_data, TENSORS), packed(cell_data, TENSORS)))
            return
        meshio = require_meshio()
        mesh = self.model.mesh
        cells = [("triangle", mesh.triangles)]
        blocks = {key: [value] for key, value in cell_data.items()}
        cables = self.cable_state(step)
        chosen = self.fields
        if cables is not None and self.system is not None and self.system.cables is not None:
            segments = self.system.cables.edges  # as line cells, after the triangles
            cells.append(("line", segments))
            for key, value in cell_data.items():
                blocks[key].append(np.zeros((len(segments), *value.shape[1:]), value.dtype))
            if chosen is None or "cable_force" in chosen:
                blocks["cable_force"] = [np.zeros(mesh.n_elements), cables.axial]  # N, double
            if chosen is None or "cable_taut" in chosen:
                blocks["cable_taut"] = [
                    np.zeros(mesh.n_elements, np.int32),
                    cables.taut.astype(np.int32),
                ]
        vtu = meshio.Mesh(mesh.nodes, cells, point_data=point_data, cell_data=blocks)
        atomic_write(path, lambda temporary: meshio.write(temporary, vtu, file_format="vtu"))

    def _write_collection(self) -> None:
        if self.file_format == "xdmf":
            mesh = self.model.mesh
            steps = [
                (float(entry.get("time", entry["load_factor"])), str(entry["file"]), fields)
                for entry, fields in zip(self.steps, self._layouts, strict=True)
            ]
            write_collection(
                self.out_dir / XDMF_COLLECTION,
                mesh.n_nodes,
                mesh.n_elements,
                steps,
                _write_text,
            )
            return
        self._write_pvd(
            COLLECTION,
            [
                f'    <DataSet timestep="{s.get("time", s["load_factor"])!r}" group="" part="0" '
                f"file={quoteattr(s['file'])}/>"
                for s in self.steps
            ],
        )

    def _write_pvd(self, name: str, entries: list[str]) -> None:
        """A ParaView collection ``name`` of the <DataSet> lines ``entries``."""
        lines = [
            '<?xml version="1.0"?>',
            '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
            "  <Collection>",
            *entries,
            "  </Collection>",
            "</VTKFile>",
            "",
        ]
        _write_text(self.out_dir / name, "\n".join(lines))

    def history_header(self) -> list[str]:
        """Column names of history.csv."""
        header = ["step", "load_factor"]
        header += ["analysis_step", "time"] if self.analysis_steps is not None else []
        header += ["iterations", "residual"]
        header += ["pressure"] if self.has_pressure else []
        header += ["enclosed_volume"] if self.has_volume else []
        header += STATE_NAMES
        header += ["strain_energy", "external_work"]
        header += [f"{state}_area" for state in STATE_NAMES]
        header += ["max_principal_stress"]
        for label in self.support_labels:
            header += [f"{label}_Fx", f"{label}_Fy", f"{label}_Fz"]
        for label in self.moment_labels:
            header += [f"{label}_Mx", f"{label}_My", f"{label}_Mz"]
        for name in self.probes:
            header += [f"{name}_ux", f"{name}_uy", f"{name}_uz"]
        return header

    def _write_history(self) -> None:
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(self.history_header())
        writer.writerows(self.rows)
        _write_text(self.out_dir / HISTORY, buffer.getvalue())

    def _write_summary(self, converged: bool, message: str) -> Path:
        summary = {
            "converged": converged,
            "message": message,
            "steps": self.steps,
            "wall_time": time.perf_counter() - self._start,
        }
        if self.reference_volume is not None:
            summary["reference_volume"] = self.reference_volume
        if self.steps:  # the last step's energies and volume, as the checks read them
            last = self.steps[-1]
            for key in ("strain_energy", "external_work", "enclosed_volume"):
                if key in last:
                    summary[key] = last[key]
        if self.analysis_steps is not None:
            summary["analysis_steps"] = self.analysis_steps
        if self.form_finding is not None:
            summary["formfinding"] = self.form_finding
        if self.frequencies is not None:
            summary["frequencies"] = self.frequencies
            summary["modes"] = self.modes
        if self.units is not None:
            summary["units"] = self.units
        if self.case is not None:
            summary["case"] = self.case
        path = self.out_dir / SUMMARY
        _write_text(path, json.dumps(summary, indent=2) + "\n")
        return path


def save_results(
    results,
    out_dir: str | os.PathLike,
    probes: Mapping[str, np.ndarray] | None = None,
    units: Mapping[str, str] | None = None,
    case: str | os.PathLike | None = None,
    file_format: str = "vtu",
    fields: Sequence[str] | None = None,
    precision: str = "double",
) -> Path:
    """Write every step of a finished ``Results`` into ``out_dir`` (files as ``ResultWriter``,
    in ``file_format`` with ``fields`` at ``precision``).

    The summary says converged if the last step reached load factor 1, otherwise where it
    stopped (e.g. the partial ``results`` of a ConvergenceError); its wall time is the writing
    time. Returns ``out_dir`` as a Path.
    """
    numbers = sorted({int(getattr(step, "analysis_step", 1)) for step in results.steps})
    writer = ResultWriter(
        out_dir,
        results.model,
        probes=probes,
        units=units,
        case=case,
        file_format=file_format,
        fields=fields,
        precision=precision,
        analysis_steps=[f"step {k}" for k in range(1, numbers[-1] + 1)]
        if numbers and numbers[-1] > 1
        else None,
    )
    for step in results.steps:
        writer.write_step(step)
    end = getattr(results, "end", None)
    if end is not None:
        writer.finish(end.complete, end.message)
    elif results.steps and abs(results.steps[-1].load_factor - 1.0) <= 1e-12:
        writer.finish(True, "converged to load factor 1")
    else:
        reached = results.steps[-1].load_factor if results.steps else 0.0
        writer.finish(False, f"stopped at load factor {reached:.6g}")
    return writer.out_dir
