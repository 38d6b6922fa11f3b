"""How wrinkle scales: the inflated airbag and the paper's shear-stretch square on structured
meshes of about 10^3 .. 10^6 elements.

Each mesh is solved in its own Python process (so that the peak resident set is that
solve's): the quarter airbag of examples/airbag.toml inflated from the flat sheet at full
pressure, the same airbag with the sheet's own bending stiffness on the mean surface
(``airbag_bending``: ``[material] bending = true``, wrinkle.bending), that airbag solved first
on coarser meshes (``airbag_nested``: ``[mesh] refine`` from about 32 squares a side and
``[solver] nested``, wrinkle.sequencing; the iterations are the finest mesh's, the times all
levels'), and the unit square of
examples/shear_stretch.toml (f = 5) under its boundary displacements; the three airbags on
unstructured gmsh meshes of about as many triangles (``airbag_gmsh``, ``airbag_gmsh_bending``,
``airbag_gmsh_nested``: benchmarks/hard_cases/airbag_gmsh.toml, meshes made by
benchmarks/gmsh_airbag.py, which needs the mesh extra), and the bending gmsh airbag solved
first on independent gmsh meshes of about 1/16 and 1/4 as many triangles
(``airbag_gmsh_levels``: ``[mesh] levels``, wrinkle.transfer). For each: elements,
unknowns, load steps, Newton iterations, the factorisations of the whole run and of its
finest mesh alone (the coarse levels of a nested solve left out: issue 18's measure), wall
time split into element evaluation, assembly,
linear solves and the rest (``Results.timings``), the peak resident set, and the result
(airbag: centre deflection; square: top-edge force F1). The case's load steps are kept (no
cut-back); a mesh whose step does not converge within
``--max-iterations`` is reported as not converged, with the time and memory it took. A mesh
whose process is stopped by ``--time-limit`` is reported as not converged with what it did up
to its last Newton iteration: the iterations, the time split and peak resident set at that
iteration, and in the result column where it stopped (iteration, load step, residual and the
residual needed; the CSV has the row, not converged). The solve writes these after each
iteration to a progress file the parent reads (``Progress``). Prints a table and writes it as
CSV.

    python benchmarks/scale.py --max-elements 200000 --linear-solver auto
    python benchmarks/scale.py --problems airbag airbag_bending --sizes 23 71 224 708 \
        --max-elements 2e6 --max-iterations 600
    python benchmarks/scale.py --problems airbag --sizes 708 --max-iterations 2   # cost of
        # the first Newton iterations on the 10^6-element airbag
    python benchmarks/scale.py --problems airbag_gmsh_levels airbag_gmsh_nested \
        airbag_gmsh_bending --sizes 72 224 --in-turns   # each size, the three in turn
    python benchmarks/scale.py --problems shear_stretch --sizes 708 --whole-matrix  # the
        # solver before the free block (compare with the same command without the flag)
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from table import write_csv

ROOT = Path(__file__).resolve().parents[1]
SIZES = {  # squares per side: 2 n^2 triangles
    "airbag": [23, 71, 224, 708],
    "airbag_bending": [23, 71, 224, 708],
    "airbag_nested": [64, 128, 224, 704],  # finest mesh; divisible by 2^levels (below)
    "shear_stretch": [23, 71, 224, 708],
    # gmsh meshes of about 2 n^2 triangles (benchmarks/gmsh_airbag.py; needs the mesh extra)
    "airbag_gmsh": [23, 71, 224],
    "airbag_gmsh_bending": [23, 71, 224],
    "airbag_gmsh_nested": [64, 128, 224],  # the finest mesh: a gmsh mesh refined (below)
    "airbag_gmsh_levels": [64, 128, 224],  # the finest mesh; levels of n/4 and n/2 (below)
}
# problem: (case file in examples/, overrides beyond the mesh)
CASES = {
    "airbag": ("airbag", {}),
    "airbag_bending": ("airbag", {"material": {"bending": True}}),  # the sheet's own D
    # the same, solved first on coarser meshes ([solver] nested, wrinkle.sequencing)
    "airbag_nested": ("airbag", {"material": {"bending": True}, "solver": {"nested": True}}),
    "shear_stretch": ("shear_stretch", {}),
    "airbag_gmsh": ("airbag_gmsh", {}),
    "airbag_gmsh_bending": ("airbag_gmsh", {"material": {"bending": True}}),
    "airbag_gmsh_nested": (
        "airbag_gmsh",
        {"material": {"bending": True}, "solver": {"nested": True}},
    ),
    "airbag_gmsh_levels": (
        "airbag_gmsh",
        {"material": {"bending": True}, "solver": {"nested": True}},
    ),
}
CASE_FILES = {  # the case files, by name
    "airbag": ROOT / "examples" / "airbag.toml",
    "shear_stretch": ROOT / "examples" / "shear_stretch.toml",
    "airbag_gmsh": ROOT / "benchmarks" / "hard_cases" / "airbag_gmsh.toml",
}
RESULT_NAMES = {
    "airbag": "centre deflection (mm)",
    "airbag_bending": "centre deflection (mm)",
    "airbag_nested": "centre deflection (mm)",
    "shear_stretch": "top-edge force F1",
    "airbag_gmsh": "centre deflection (mm)",
    "airbag_gmsh_bending": "centre deflection (mm)",
    "airbag_gmsh_nested": "centre deflection (mm)",
    "airbag_gmsh_levels": "centre deflection (mm)",
}
LEVELS = (4, 2)  # airbag_gmsh_levels: gmsh meshes of n / 4 and n / 2 squares a side first


def mesh_overrides(problem: str, n: int, scratch: Path | None = None) -> dict:
    """The [mesh] overrides of an n x n mesh: for the nested problems, a mesh of about 32
    squares a side refined k times to n (n divisible by 2^k); for the gmsh problems a gmsh
    mesh of about 2 n^2 triangles (or 2 (n / 2^k)^2, refined k times), written to scratch;
    for airbag_gmsh_levels also gmsh meshes of about 2 (n / d)^2 triangles for each d of
    ``LEVELS``, its [mesh] levels."""
    if problem == "airbag_gmsh_levels":
        from gmsh_airbag import write_airbag_mesh

        if scratch is None:
            raise ValueError(f"{problem}: the gmsh meshes need a scratch folder")
        files = []
        for divisor in (*LEVELS, 1):
            path = scratch / f"airbag-{n}-{divisor}.msh"
            write_airbag_mesh(round(2 * (n / divisor) ** 2), path, seed=divisor)
            files.append(str(path))
        return {"file": files[-1], "levels": files[:-1]}
    levels = 0
    if problem.endswith("nested"):
        levels = max(1, int(math.log2(n / 32)))
        if n % 2**levels:
            raise SystemExit(f"{problem}: {n} squares a side is not divisible by 2^{levels}")
    base = n // 2**levels
    if problem.startswith("airbag_gmsh"):
        from gmsh_airbag import write_airbag_mesh

        if scratch is None:
            raise ValueError(f"{problem}: the gmsh mesh needs a scratch folder")
        path = scratch / f"airbag-{base}.msh"
        write_airbag_mesh(2 * base * base, path)
        mesh: dict = {"file": str(path)}
    else:
        mesh = {"rectangle": {"nx": base, "ny": base}}
    return {**mesh, "refine": levels} if levels else mesh


FIELDS = [
    "problem",
    "elements",
    "unknowns",
    "steps",
    "iterations",
    "max_per_step",
    "factorisations",
    "finest_factorisations",
    "converged",
    "element_s",
    "assembly_s",
    "linear_s",
    "rest_s",
    "total_s",
    "outside_linear",
    "peak_rss_mb",
    "result",
    "result_name",
    "linear_solver",
]


def make_row(
    known: dict,
    per_step: list[int],
    converged: bool,
    timings: dict | None,
    total: float,
    result: float,
    factorisations: tuple[int, int] | None = None,
) -> dict:
    """A row of the table from the columns known before the solve, the Newton iterations of
    each load step, the stopwatch's seconds per part (``Results.timings``; None: not known),
    the wall time since the process began the case, and the factorisations of the whole run
    and of its finest mesh alone (None: not known)."""
    nan = float("nan")
    every, finest = factorisations if factorisations is not None else (nan, nan)
    element, assembly, linear = (
        (timings[part] if timings else nan)
        for part in ("element evaluation", "assembly", "linear solves")
    )
    return {
        **known,
        "iterations": sum(per_step),
        "max_per_step": max(per_step),
        "factorisations": every,
        "finest_factorisations": finest,
        "converged": converged,
        "element_s": element,
        "assembly_s": assembly,
        "linear_s": linear,
        "rest_s": total - linear - element - assembly,
        "total_s": total,
        "outside_linear": 1.0 - linear / total,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "result": result,
    }


class Progress(logging.Handler):
    """Appends a partial row (one line of JSON) to a file after each Newton iteration
    and each converged load step, from the solver's log messages, so that a run stopped by
    ``--time-limit`` can be reported. The row has, beyond the table's columns, the load step
    (``step``), its last iteration (``step_iteration``), the residual and the residual needed
    (tolerance x force scale; the solver also accepts one at round-off, which is not logged),
    and ``time_split``: whether the seconds per part are known (from the solve's stopwatch,
    ``stopwatch``; without it they are NaN)."""

    ITERATION = re.compile(r"iteration\s+(\d+): residual (\S+) \(scale (\S+)\)")
    STEP = re.compile(r"load factor \S+ converged in (\d+) iterations")

    def __init__(self, path: str, known: dict, start: float, tolerance: float):
        super().__init__(logging.INFO)
        self.path, self.known, self.start, self.tolerance = path, known, start, tolerance
        self.per_step: list[int] = []  # iterations of the converged load steps
        self.iteration = 0  # last iteration of the step being solved
        self.residual = self.needed = float("nan")
        self.stopwatch = None  # the solve's (Results.stopwatch), for the time split

    def emit(self, record: logging.LogRecord) -> None:
        message = record.getMessage()
        if match := self.ITERATION.search(message):
            self.iteration, self.residual = int(match[1]), float(match[2])
            self.needed = self.tolerance * float(match[3])
        elif match := self.STEP.search(message):
            self.per_step.append(int(match[1]))
            self.iteration, self.residual, self.needed = 0, float("nan"), float("nan")
        else:
            return
        timings = self.stopwatch.summary() if self.stopwatch is not None else None
        row = make_row(
            self.known,
            [*self.per_step, self.iteration],
            False,
            timings,
            time.perf_counter() - self.start,
            float("nan"),
        )
        row.update(
            step=len(self.per_step) + 1,
            step_iteration=self.iteration,
            residual=self.residual,
            needed=self.needed,
            time_split=timings is not None,
        )
        with open(self.path, "a") as file:  # written out at once, for the parent to read
            file.write(json.dumps(row) + "\n")


def solve_one(
    problem: str,
    n: int,
    linear_solver: str,
    max_iterations: int | None,
    progress: str | None = None,
) -> dict:
    """Solve one mesh in this process; the row of the table (also when the solve fails).
    ``progress``: a file to write a partial row to after each Newton iteration (``Progress``)."""
    import numpy as np

    from wrinkle.case import read_case
    from wrinkle.results import Results
    from wrinkle.sequencing import NestedStart
    from wrinkle.solvers import ConvergenceError, follow_load_path
    from wrinkle.solvers.linear import make_linear_solver

    name, overrides = CASES[problem]
    with tempfile.TemporaryDirectory(prefix="scale-mesh-") as scratch:
        mesh = mesh_overrides(problem, n, Path(scratch))  # a gmsh mesh: before the clock
        start = time.perf_counter()
        case = read_case(CASE_FILES[name], overrides={**overrides, "mesh": mesh})
    model = case.model
    steps = case.settings.steps
    # the case's load steps, no cut-back: a failed step ends the run
    settings = case.settings.replace(
        linear_solver=linear_solver, max_iterations=max_iterations, min_step=1.0 / steps
    )
    known = {
        "problem": problem,
        "elements": model.mesh.n_elements,
        "unknowns": int(np.count_nonzero(~model.constrained)),
        "steps": steps,
        "result_name": RESULT_NAMES[problem],
        "linear_solver": make_linear_solver(linear_solver, model.n_dofs).name,
    }
    log = logging.getLogger("wrinkle")  # the solver's "wrinkle.solver" messages come here too
    level = log.level
    results = Results(model)  # what Model.solve does, with the stopwatch in reach
    if progress:
        handler = Progress(progress, known, start, settings.tolerance)
        handler.stopwatch = results.stopwatch
        log.addHandler(handler)
        log.setLevel(logging.INFO)
    failed = None
    stopwatch = results.stopwatch
    coarse_factorisations = 0  # those of the coarser meshes, charged to the same stopwatch
    try:
        first_guess = None
        if case.coarse:  # the coarse levels' time counts: the stopwatch is the solve's
            nested = NestedStart(case.coarse, model, settings, stopwatch)

            def first_guess(load_factor: float) -> np.ndarray | None:
                nonlocal coarse_factorisations
                before = stopwatch.factorisations
                start = nested(load_factor)
                coarse_factorisations += stopwatch.factorisations - before
                return start

        follow_load_path(
            model.discretise(),
            settings.solver(),
            settings.controller(),
            on_step=results.append,
            timer=results.stopwatch,
            first_guess=first_guess,
        )
    except ConvergenceError as error:
        failed = error
    finally:
        if progress:
            log.removeHandler(handler)
            log.setLevel(level)
    per_step = [step.iterations for step in results.steps]
    if failed is not None:
        per_step.append(len(failed.history) - 1)
    timings = results.timings
    result = float("nan")
    if failed is None:
        u = results.final.displacement
        if name.startswith("airbag"):
            centre = case.probes["centre"]
            result = 1e3 * float(u.reshape(-1, 3)[centre, 2].mean())
        else:
            top = model.mesh.node_sets["top"]
            result = float(results.final.reactions.reshape(-1, 3)[top, 0].sum())
    total = time.perf_counter() - start
    every = stopwatch.factorisations
    counts = (every, every - coarse_factorisations)
    return make_row(known, per_step, failed is None, timings, total, result, counts)


def stopped_row(progress: Path, time_limit: float) -> dict | None:
    """The last partial row a run stopped after time_limit seconds wrote to its progress file
    (``Progress``), with a note of where it stopped; None if it wrote none."""
    for line in reversed(progress.read_text().splitlines()):
        try:
            row = json.loads(line)
        except json.JSONDecodeError:  # the line being written when the process was stopped
            continue
        if row["residual"] != row["residual"]:  # NaN: stopped between two load steps
            where = f"in step {row['step']}, after step {row['step'] - 1} converged"
        else:
            where = (
                f"at iteration {row['step_iteration']} of step {row['step']} (residual "
                f"{row['residual']:.2e}, {row['needed']:.2e} needed)"
            )
        row["stopped"] = f"stopped after {time_limit:.0f} s {where}"
        if not row["time_split"]:
            row["stopped"] += ", time split not known"
        return row
    return None


def print_row(row: dict) -> None:
    if row.get("stopped"):
        result = row["stopped"]
    elif row["converged"]:
        result = f"{row['result_name']} = {row['result']:.6g}"
    else:
        result = "NOT CONVERGED"
    print(
        f"{row['problem']:>13} {row['elements']:9d} {row['unknowns']:9d} "
        f"{row['steps']:5d} {row['iterations']:5d} {row['max_per_step']:8d} "
        f"{row['factorisations']:6.0f} {row['finest_factorisations']:6.0f} "
        f"{row['element_s']:10.2f} {row['assembly_s']:10.2f} {row['linear_s']:9.2f} "
        f"{row['rest_s']:7.2f} {row['total_s']:8.1f} {row['outside_linear']:10.0%} "
        f"{row['peak_rss_mb']:8.0f}  {result}",
        flush=True,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--max-elements", type=float, default=2.5e5, help="skip meshes with more elements than this"
    )
    parser.add_argument("--problems", nargs="+", default=list(SIZES), choices=list(SIZES))
    parser.add_argument(
        "--sizes", type=int, nargs="+", help="squares per side instead of the default meshes"
    )
    parser.add_argument("--linear-solver", default="auto")
    parser.add_argument(
        "--max-iterations",
        type=int,
        help="Newton iterations per load step (default: the solver's, 100)",
    )
    parser.add_argument(
        "--time-limit",
        type=float,
        default=1800.0,
        help="seconds per mesh before its process is stopped",
    )
    parser.add_argument(
        "--in-turns",
        action="store_true",
        help="each size for all the problems in turn (instead of each problem for all sizes), "
        "so that a shared machine's load falls on all alike",
    )
    parser.add_argument(
        "--whole-matrix",
        action="store_true",
        help="factorise the whole matrix, the held components' stored zeros too (the solver "
        "before 4 December 2026; RegularisedSolver.free_block = False)",
    )
    parser.add_argument(
        "--before-parallel",
        action="store_true",
        help="OpenBLAS on as many threads as it starts and the St Venant-Kirchhoff response in "
        "NumPy (the solver before the parallel kernels of 4 December 2026; "
        "RegularisedSolver.blas_threads = None, Wrinkling.compiled_linear_law = False; the "
        "element stiffness and the symmetry check stay parallel)",
    )
    parser.add_argument("--csv", default="scale.csv")
    parser.add_argument("--one", nargs=2, metavar=("PROBLEM", "N"), help=argparse.SUPPRESS)
    parser.add_argument("--progress", help=argparse.SUPPRESS)  # --one's partial rows go here
    args = parser.parse_args()
    if args.one:
        from wrinkle.solvers.base import RegularisedSolver
        from wrinkle.wrinkling import Wrinkling

        if args.whole_matrix:
            RegularisedSolver.free_block = False
        if args.before_parallel:
            RegularisedSolver.blas_threads = None
            Wrinkling.compiled_linear_law = False
        row = solve_one(
            args.one[0], int(args.one[1]), args.linear_solver, args.max_iterations, args.progress
        )
        print(json.dumps(row))
        return
    print(
        f"{'problem':>13} {'elements':>9} {'unknowns':>9} {'steps':>5} {'iter':>5} "
        f"{'max/step':>8} {'fact':>6} {'finest':>6} {'elements s':>10} {'assembly s':>10} "
        f"{'linear s':>9} {'rest s':>7} {'total s':>8} {'not linear':>10} {'peak MB':>8}  result"
    )
    rows = []
    runs = [(problem, n) for problem in args.problems for n in args.sizes or SIZES[problem]]
    if args.in_turns:
        runs.sort(key=lambda run: run[1])  # stable: the problems in the order given
    with tempfile.TemporaryDirectory(prefix="scale-") as scratch:
        for problem, n in runs:
            if 2 * n * n > args.max_elements:
                print(f"{problem:>13} n = {n}: skipped, {2 * n * n} elements > --max-elements")
                continue
            progress = Path(scratch) / f"{problem}-{n}.jsonl"
            progress.write_text("")
            command = [
                sys.executable,
                __file__,
                "--one",
                problem,
                str(n),
                "--linear-solver",
                args.linear_solver,
                "--progress",
                str(progress),
            ]
            if args.max_iterations:
                command += ["--max-iterations", str(args.max_iterations)]
            if args.whole_matrix:
                command.append("--whole-matrix")
            if args.before_parallel:
                command.append("--before-parallel")
            try:
                done = subprocess.run(
                    command,
                    capture_output=True,
                    text=True,
                    check=False,
                    timeout=args.time_limit,
                )
            except subprocess.TimeoutExpired:
                row = stopped_row(progress, args.time_limit)
                if row is None:
                    print(f"{problem:>13} n = {n}: stopped after {args.time_limit:.0f} s")
                else:
                    rows.append(row)
                    print_row(row)
                continue
            if done.returncode != 0:
                print(f"{problem:>13} n = {n}: failed\n{done.stderr.strip()[-2000:]}")
                continue
            row = json.loads(done.stdout.strip().splitlines()[-1])
            rows.append(row)
            print_row(row)
    write_csv(args.csv, rows, FIELDS)


if __name__ == "__main__":
    main()
