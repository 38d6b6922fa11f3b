"""The cost of load control's stability check (``wrinkle.solvers.stability``: one more
factorisation of each converged step's tangent, for a membrane that encloses a volume).

The neo-Hookean octant of ``verification/cases/sphere.toml`` on n x n divisions (n^2
elements) is inflated under load control in ``--steps`` steps to 0.9 of its limit pressure,
with the check (as ``Model.solve`` does for balloons) and without it, in turns, ``--turns``
times. It prints the median wall time and factorisations of each and their ratio.

    python benchmarks/stability_cost.py              # n = 100: 10,000 elements
    python benchmarks/stability_cost.py --n 40 --turns 2
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from verification.references.sphere import InflatedSphere  # noqa: E402
from wrinkle.case import read_case  # noqa: E402
from wrinkle.solvers.stepping import follow_load_path  # noqa: E402
from wrinkle.timing import Stopwatch  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100, help="the octant's divisions")
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--turns", type=int, default=3)
    args = parser.parse_args()
    pressure = 0.9 * InflatedSphere(4e5, 1e-3, 0.1).limit_pressure
    case = read_case(
        ROOT / "verification" / "cases" / "sphere.toml",
        {
            "mesh": {"sphere": {"radius": 0.1, "n": args.n}},
            "load": [{"kind": "pressure", "value": pressure}],
            "solver": {"steps": args.steps},
        },
    )
    system = case.model.discretise()
    print(f"octant, {case.model.mesh.n_elements} elements, {args.steps} steps to {pressure:.0f} Pa")
    rows: dict[bool, list[tuple[float, int]]] = {True: [], False: []}
    for _ in range(args.turns):
        for stability in (True, False):
            solver = case.settings.solver()
            timer = Stopwatch()
            start = time.perf_counter()
            follow_load_path(
                system, solver, case.settings.controller(), timer=timer, stability=stability
            )
            rows[stability].append((time.perf_counter() - start, timer.factorisations))
            solver.release()
    print(f"{'stability check':<16} {'time s':>8} {'factorisations':>14}")
    medians = {}
    for stability, runs in rows.items():
        seconds = statistics.median(r[0] for r in runs)
        count = statistics.median(r[1] for r in runs)
        medians[stability] = seconds
        print(f"{'on' if stability else 'off':<16} {seconds:8.2f} {count:14.0f}")
    print(f"ratio on / off: {medians[True] / medians[False]:.2f}")


if __name__ == "__main__":
    main()
