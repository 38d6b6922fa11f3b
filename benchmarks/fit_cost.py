"""The cost of a fit per optimiser iteration against one forward solve of all experiments
(issue 23: at most 1.3 times, the point of adjoint gradients).

The fit of examples/fit (four parameters of the fibre-reinforced sheet, one experiment of
eight measured states, 256 elements) is run ``--repeats`` times, in turns with the same
number of forward solves of its experiment at the start values; the table gives the medians:
the fit's seconds per Jacobian (an optimiser iteration: its residual evaluations and one
Jacobian), the seconds of one forward solve, their ratio, and the part the adjoint
gradients take of a Jacobian evaluation.

    python benchmarks/fit_cost.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from wrinkle.identification import read_fit, run_fit
from wrinkle.identification.fit import LocalEngine, tasks_for

FIT = Path(__file__).resolve().parents[1] / "examples" / "fit" / "fit.toml"


class TimedEngine(LocalEngine):
    """The engine of the fit, timing its forward solves and adjoint gradients apart."""

    def __init__(self) -> None:
        super().__init__()
        self.forward_seconds = 0.0
        self.adjoint_seconds = 0.0

    def forward(self, tasks):
        started = time.perf_counter()
        try:
            return super().forward(tasks)
        finally:
            self.forward_seconds += time.perf_counter() - started

    def adjoint(self, tasks):
        started = time.perf_counter()
        try:
            return super().adjoint(tasks)
        finally:
            self.adjoint_seconds += time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    problem = read_fit(FIT)
    forward, per_iteration, adjoint_part, counts = [], [], [], []
    for _ in range(args.repeats):
        started = time.perf_counter()
        LocalEngine().forward(tasks_for(problem, problem.start, adjoint=False))
        forward.append(time.perf_counter() - started)
        engine = TimedEngine()
        started = time.perf_counter()
        result = run_fit(problem, engine)
        seconds = time.perf_counter() - started
        per_iteration.append(seconds / result.jacobians)
        adjoint_part.append(engine.adjoint_seconds / result.jacobians)
        counts.append((result.evaluations, result.jacobians))
    one = statistics.median(forward)
    iteration = statistics.median(per_iteration)
    print(
        f"fit of {FIT.name}: {problem.experiments[0].x.size} states, "
        f"{len(problem.parameters)} parameters; evaluations, jacobians: {counts[0]}"
    )
    print(
        f"{'forward solve [s]':>18} {'fit per iteration [s]':>22} {'ratio':>6} "
        f"{'adjoint per iteration [s]':>26}"
    )
    print(
        f"{one:18.3f} {iteration:22.3f} {iteration / one:6.2f} "
        f"{statistics.median(adjoint_part):26.3f}"
    )


if __name__ == "__main__":
    main()
