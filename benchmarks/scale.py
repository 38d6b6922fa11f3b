"""How wrinkle scales: the inflated airbag and the paper's shear-stretch square on structured
meshes of about 10^3 .. 10^6 elements.

Each mesh is solved in its own Python process (so that the peak resident set is that
solve's): the quarter airbag of examples/airbag.toml inflated from the flat sheet at full
pressure, and the unit square of examples/shear_stretch.toml (f = 5) under its boundary
displacements. For each: elements, unknowns, load steps, Newton iterations, wall time split
into element evaluation, assembly, linear solves and the rest (``Results.timings``), the peak
resident set, and the result (airbag: centre deflection; square: top-edge force F1).
The case's load steps are kept (no cut-back); a mesh whose step does not converge within
``--max-iterations`` is reported as not converged, with the time and memory it took. Prints a
table and writes it as CSV.

    python benchmarks/scale.py --max-elements 200000 --linear-solver auto
    python benchmarks/scale.py --problems airbag --sizes 708 --max-iterations 2   # cost of
        # the first Newton iterations on the 10^6-element airbag
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

from table import write_csv

ROOT = Path(__file__).resolve().parents[1]
SIZES = {  # squares per side: 2 n^2 triangles
    "airbag": [23, 71, 224, 708],
    "shear_stretch": [23, 71, 224, 708],
}
RESULT_NAMES = {"airbag": "centre deflection (mm)", "shear_stretch": "top-edge force F1"}
FIELDS = ["problem", "elements", "unknowns", "steps", "iterations", "max_per_step", "converged",
          "element_s", "assembly_s",
          "linear_s", "rest_s", "total_s", "outside_linear", "peak_rss_mb", "result",
          "result_name", "linear_solver"]


def solve_one(problem: str, n: int, linear_solver: str, max_iterations: int | None) -> dict:
    """Solve one mesh in this process; the row of the table (also when the solve fails)."""
    import numpy as np

    from wrinkle.case import read_case
    from wrinkle.solvers import ConvergenceError
    from wrinkle.solvers.linear import make_linear_solver

    start = time.perf_counter()
    case = ROOT / "examples" / f"{problem}.toml"
    model = read_case(case, overrides={"mesh": {"rectangle": {"nx": n, "ny": n}}})
    steps = model.solver_settings.get("steps", 1)
    failed = None
    try:  # the case's load steps, no cut-back: a failed step ends the run
        results = model.solve(linear_solver=linear_solver, max_iterations=max_iterations,
                              min_step=1.0 / steps)
    except ConvergenceError as error:
        results, failed = error.results, error
    per_step = [step.iterations for step in results.steps]
    if failed is not None:
        per_step.append(len(failed.history) - 1)
    timings = results.timings
    if failed is None:
        u = results.final.displacement
        if problem == "airbag":
            centre = model.probes["centre"]
            result = 1e3 * float(u.reshape(-1, 3)[centre, 2].mean())
        else:
            top = model.mesh.node_sets["top"]
            result = float(results.final.reactions.reshape(-1, 3)[top, 0].sum())
    total = time.perf_counter() - start
    linear = timings["linear solves"]
    return {
        "problem": problem, "elements": model.mesh.n_elements,
        "unknowns": int(np.count_nonzero(~model.constrained)), "steps": steps,
        "iterations": sum(per_step), "max_per_step": max(per_step),
        "converged": failed is None,
        "element_s": timings["element evaluation"], "assembly_s": timings["assembly"],
        "linear_s": linear, "rest_s": total - linear - timings["element evaluation"]
        - timings["assembly"], "total_s": total,
        "outside_linear": 1.0 - linear / total,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "result": result if failed is None else float("nan"),
        "result_name": RESULT_NAMES[problem],
        "linear_solver": make_linear_solver(linear_solver, model.n_dofs).name,
    }


def print_row(row: dict) -> None:
    result = (f"{row['result_name']} = {row['result']:.6g}" if row["converged"]
              else "NOT CONVERGED")
    print(f"{row['problem']:>13} {row['elements']:9d} {row['unknowns']:9d} "
          f"{row['steps']:5d} {row['iterations']:5d} {row['max_per_step']:8d} "
          f"{row['element_s']:10.2f} {row['assembly_s']:10.2f} {row['linear_s']:9.2f} "
          f"{row['rest_s']:7.2f} {row['total_s']:8.1f} {row['outside_linear']:10.0%} "
          f"{row['peak_rss_mb']:8.0f}  {result}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-elements", type=float, default=2.5e5,
                        help="skip meshes with more elements than this")
    parser.add_argument("--problems", nargs="+", default=list(SIZES), choices=list(SIZES))
    parser.add_argument("--sizes", type=int, nargs="+",
                        help="squares per side instead of the default meshes")
    parser.add_argument("--linear-solver", default="auto")
    parser.add_argument("--max-iterations", type=int,
                        help="Newton iterations per load step (default: the solver's, 100)")
    parser.add_argument("--time-limit", type=float, default=1800.0,
                        help="seconds per mesh before its process is stopped")
    parser.add_argument("--csv", default="scale.csv")
    parser.add_argument("--one", nargs=2, metavar=("PROBLEM", "N"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        row = solve_one(args.one[0], int(args.one[1]), args.linear_solver, args.max_iterations)
        print(json.dumps(row))
        return
    print(f"{'problem':>13} {'elements':>9} {'unknowns':>9} {'steps':>5} {'iter':>5} "
          f"{'max/step':>8} {'elements s':>10} {'assembly s':>10} {'linear s':>9} "
          f"{'rest s':>7} {'total s':>8} {'not linear':>10} {'peak MB':>8}  result")
    rows = []
    for problem in args.problems:
        for n in args.sizes or SIZES[problem]:
            if 2 * n * n > args.max_elements:
                print(f"{problem:>13} n = {n}: skipped, {2 * n * n} elements > --max-elements")
                continue
            command = [sys.executable, __file__, "--one", problem, str(n),
                       "--linear-solver", args.linear_solver]
            if args.max_iterations:
                command += ["--max-iterations", str(args.max_iterations)]
            try:
                done = subprocess.run(command, capture_output=True, text=True, check=False,
                                      timeout=args.time_limit)
            except subprocess.TimeoutExpired:
                print(f"{problem:>13} n = {n}: stopped after {args.time_limit:.0f} s")
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
