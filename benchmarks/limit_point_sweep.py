"""The neo-Hookean balloon under load control across its limit point (issue 20's sweep):
20 pressures from 0.95 to 1.5 times the closed form's largest pressure, in 1 and 20 steps,
on the octant of verification/cases/sphere.toml. For each: converged (with the mean stretch
and the closed form's on the faceted octant) or failed (with the load factor and pressure of
the limit point the message names, and the faceted octant's limit pressure). A wrong answer
would be a converged row above the limit pressure or with the wrong stretch.

With ``--control arc-length`` the same sweep by arc length: below the limit pressure the
path must end on the closed form's stretch; above it no point of the path carries the load,
and the run must fail with the largest load the path carried (at most the facets' limit
pressure).

    python benchmarks/limit_point_sweep.py --n 8
    python benchmarks/limit_point_sweep.py --n 8 --control arc-length
    python benchmarks/limit_point_sweep.py --n 8 --regrow-after 0   # the controller before
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from verification.references.sphere import InflatedSphere, effective_radius  # noqa: E402
from wrinkle.case import read_case  # noqa: E402
from wrinkle.solvers import ConvergenceError  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=8, help="the octant's subdivisions")
    parser.add_argument("--control", choices=("load", "arc-length"), default="load")
    parser.add_argument(
        "--regrow-after",
        type=int,
        help="[solver] regrow_after (default the solver's, 2; 0: cut increments grow back only "
        "after easy steps, as before 4 December 2026)",
    )
    args = parser.parse_args()
    solver: dict = {} if args.regrow_after is None else {"regrow_after": args.regrow_after}
    reference = InflatedSphere(radius=0.1, thickness=1e-3, mu=4e5)
    print("steps | p / p_max | outcome | stretch | closed form | limit pressure | s")
    for steps in (1, 20):
        for pressure in np.linspace(0.95, 1.5, 20) * reference.limit_pressure:
            case = read_case(
                ROOT / "verification" / "cases" / "sphere.toml",
                {
                    "mesh": {"sphere": {"radius": 0.1, "n": args.n}},
                    "load": [{"kind": "pressure", "value": float(pressure)}],
                    "solver": {"steps": steps, "control": args.control, **solver},
                },
            )
            facets = effective_radius(case.model.mesh) / 0.1
            limit = reference.limit_pressure / facets
            start = time.perf_counter()
            try:
                results = case.solve()
            except ConvergenceError as error:
                found = "-" if error.limit_point is None else f"{error.limit_point * pressure:.1f}"
                outcome = "limit point" if "limit point passed" in str(error) else "FAILED"
                if "load factor 1 not reached" in str(error):  # arc length: the largest load
                    highest = float(str(error).split("was ")[1].split(" ")[0])
                    outcome, found = "largest load", f"{highest * pressure:.1f}"
                row = [outcome, "", "", f"{found} (facets {limit:.1f})"]
            else:
                x = case.model.mesh.nodes + results.final.displacement.reshape(-1, 3)
                stretch = np.linalg.norm(x, axis=1).mean() / 0.1
                closed = reference.stretch(pressure * facets) if pressure <= limit else np.nan
                row = ["converged", f"{stretch:.5f}", f"{closed:.5f}", f"(facets {limit:.1f})"]
            elapsed = time.perf_counter() - start
            ratio = pressure / reference.limit_pressure
            print(" | ".join([str(steps), f"{ratio:.3f}", *row, f"{elapsed:.1f}"]), flush=True)


if __name__ == "__main__":
    main()
