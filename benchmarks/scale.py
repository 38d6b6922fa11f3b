"""How wrinkle scales: the inflated airbag and the paper's shear-stretch square on structured
meshes of about 10^3 .. 10^6 elements.

Each mesh is solved in its own Python process (so that the peak resident set is that
solve's): the quarter airbag of examples/airbag.toml inflated from the flat sheet at full
pressure, and the unit square of examples/shear_stretch.toml (f = 5) under its boundary
displacements. For each: elements, unknowns, load steps, Newton iterations, wall time split
into element evaluation, assembly, linear solves and the rest (``Results.timings``), the peak
resident set, and the result (airbag: centre deflection; square: top-edge force F1).
Prints a table and writes it as CSV.

    python benchmarks/scale.py --max-elements 200000 --linear-solver auto
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
FIELDS = ["problem", "elements", "unknowns", "steps", "iterations", "element_s", "assembly_s",
          "linear_s", "rest_s", "total_s", "outside_linear", "peak_rss_mb", "result",
          "result_name", "linear_solver"]


def solve_one(problem: str, n: int, linear_solver: str) -> dict:
    """Solve one mesh in this process; the row of the table."""
    import numpy as np

    from wrinkle.case import read_case
    from wrinkle.solvers.linear import make_linear_solver

    start = time.perf_counter()
    case = ROOT / "examples" / f"{problem}.toml"
    model = read_case(case, overrides={"mesh": {"rectangle": {"nx": n, "ny": n}}})
    results = model.solve(linear_solver=linear_solver)
    timings = results.timings
    u = results.final.displacement
    if problem == "airbag":
        centre = model.probes["centre"]
        result, name = 1e3 * float(u.reshape(-1, 3)[centre, 2].mean()), "centre deflection (mm)"
    else:
        top = model.mesh.node_sets["top"]
        reactions = results.final.reactions.reshape(-1, 3)
        result, name = float(reactions[top, 0].sum()), "top-edge force F1"
    total = time.perf_counter() - start
    linear = timings["linear solves"]
    row = {
        "problem": problem, "elements": model.mesh.n_elements,
        "unknowns": int(np.count_nonzero(~model.constrained)), "steps": len(results),
        "iterations": sum(step.iterations for step in results.steps),
        "element_s": timings["element evaluation"], "assembly_s": timings["assembly"],
        "linear_s": linear, "rest_s": total - linear - timings["element evaluation"]
        - timings["assembly"], "total_s": total,
        "outside_linear": 1.0 - linear / total,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "result": result, "result_name": name,
        "linear_solver": make_linear_solver(linear_solver, model.n_dofs).name,
    }
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-elements", type=float, default=2.5e5,
                        help="skip meshes with more elements than this")
    parser.add_argument("--problems", nargs="+", default=list(SIZES), choices=list(SIZES))
    parser.add_argument("--linear-solver", default="auto")
    parser.add_argument("--csv", default="scale.csv")
    parser.add_argument("--one", nargs=2, metavar=("PROBLEM", "N"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        row = solve_one(args.one[0], int(args.one[1]), args.linear_solver)
        print(json.dumps(row))
        return
    print(f"{'problem':>13} {'elements':>9} {'unknowns':>9} {'steps':>5} {'iter':>4} "
          f"{'elements s':>10} {'assembly s':>10} {'linear s':>9} {'rest s':>7} {'total s':>8} "
          f"{'not linear':>10} {'peak MB':>8}  result")
    rows = []
    for problem in args.problems:
        for n in SIZES[problem]:
            if 2 * n * n > args.max_elements:
                continue
            done = subprocess.run(
                [sys.executable, __file__, "--one", problem, str(n),
                 "--linear-solver", args.linear_solver],
                capture_output=True, text=True, check=False,
            )
            if done.returncode != 0:
                print(f"{problem:>13} n = {n}: failed\n{done.stderr.strip()[-2000:]}")
                continue
            row = json.loads(done.stdout.strip().splitlines()[-1])
            rows.append(row)
            print(f"{row['problem']:>13} {row['elements']:9d} {row['unknowns']:9d} "
                  f"{row['steps']:5d} {row['iterations']:4d} {row['element_s']:10.2f} "
                  f"{row['assembly_s']:10.2f} {row['linear_s']:9.2f} {row['rest_s']:7.2f} "
                  f"{row['total_s']:8.1f} {row['outside_linear']:10.0%} "
                  f"{row['peak_rss_mb']:8.0f}  {row['result_name']} = {row['result']:.6g}",
                  flush=True)
    write_csv(args.csv, rows, FIELDS)


if __name__ == "__main__":
    main()
