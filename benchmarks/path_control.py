"""The cost of an iteration of arc length and volume control against load control's Newton
iteration (issue 20: at most 1.2 times, one factorisation and two solves).

The quarter airbag of ``examples/airbag.toml`` on an n x n mesh (2 n^2 elements), with the
sheet's bending stiffness (``[material] bending = true``), is inflated
to 5 kPa under load control; from its solution with the heights scaled by 0.999 (a start
out of balance) the same state is then solved three ways, in turns, ``--turns`` times:

- load control: Newton at load factor 1 (``RegularisedNewton.solve``);
- volume control: the bordered solve for the pressure at the solution's enclosed volume,
  with the Lagrangian merit (``wrinkle.solvers.control``);
- arc length: the bordered solve for the load factor on Riks' plane through the solution
  normal to the step (``wrinkle.solvers.arc_length.ArcLengthPlane``).

It prints, per method, the median over the turns of the wall time, the iterations, the
factorisations and the time per iteration, and the ratio of the time per iteration to load
control's.

    python benchmarks/path_control.py            # n = 72: 10,368 elements
    python benchmarks/path_control.py --n 32 --turns 2
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

from wrinkle.case import read_case
from wrinkle.solvers.arc_length import ArcLengthPlane
from wrinkle.solvers.bordered import solve_bordered
from wrinkle.solvers.control import (
    EnclosedVolume,
    LoadFamily,
    PressureFamily,
    VolumeLagrangian,
)

ROOT = Path(__file__).resolve().parents[1]
AIRBAG = ROOT / "examples" / "airbag.toml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=72, help="squares along each edge")
    parser.add_argument("--turns", type=int, default=3)
    args = parser.parse_args()
    # with the sheet's bending stiffness: the pure membrane on 10^4 elements needs hundreds of
    # iterations from the flat sheet (docs/performance.md), which is not what is measured here
    case = read_case(
        AIRBAG,
        {
            "mesh": {"rectangle": {"nx": args.n, "ny": args.n}},
            "material": {"bending": True},
            "solver": {"max_iterations": 400},
        },
    )
    model, settings = case.model, case.settings
    print(f"airbag, {model.mesh.n_elements} elements: load control from the flat sheet ...")
    solution = model.solve(settings).final
    system = model.discretise()
    u1 = solution.displacement
    start = (u1.reshape(-1, 3) * [1.0, 1.0, 0.999]).ravel()  # the bag 0.1 % less high
    volume = system.enclosed_volume(u1)
    step = u1 - start
    scale_u2 = float(step @ step)

    def load_control(solver):
        problem = system.at(1.0)
        return solver.solve(problem, start), problem.timer

    def volume_control(solver):
        timers = []

        def share(problem):
            timers.append(problem.timer)

        solved = solve_bordered(
            PressureFamily(system, 1.0),
            EnclosedVolume(system, lambda mu: (volume, 0.0), volume),
            start,
            1.0,
            solver,
            share,
            VolumeLagrangian(5000.0, volume),
        )
        return solved, timers

    def arc_length(solver):
        size = np.sqrt(float(step @ step) / scale_u2)
        plane = ArcLengthPlane(step / size, 0.0, start, 1.0, scale_u2, size)
        timers = []

        def share(problem):
            timers.append(problem.timer)

        return solve_bordered(LoadFamily(system), plane, start, 1.0, solver, share), timers

    methods = {"load control": load_control, "volume control": volume_control}
    methods["arc length"] = arc_length
    table: dict[str, list[tuple[float, int, int]]] = {name: [] for name in methods}
    for _ in range(args.turns):
        for name, method in methods.items():
            solver = settings.solver()
            before = time.perf_counter()
            solved, _ = method(solver)
            seconds = time.perf_counter() - before
            factorisations = solver._timer.factorisations
            solver.release()
            table[name].append((seconds, solved.iterations, factorisations))
    print(
        f"\n{'method':<16} {'time s':>8} {'iterations':>10} {'factorisations':>14} "
        f"{'s/iteration':>12} {'ratio':>6}"
    )
    base = None
    for name, rows in table.items():
        seconds = statistics.median(r[0] for r in rows)
        iterations = statistics.median(r[1] for r in rows)
        factorisations = statistics.median(r[2] for r in rows)
        per = seconds / max(iterations, 1)
        base = per if base is None else base
        print(
            f"{name:<16} {seconds:8.2f} {iterations:10.0f} {factorisations:14.0f} "
            f"{per:12.3f} {per / base:6.2f}"
        )


if __name__ == "__main__":
    main()
