"""The cost of a fit per optimiser iteration against one forward solve of all experiments
(issue 23: at most 1.3 times, the point of adjoint gradients).

The fit of examples/fit (four parameters of the fibre-reinforced sheet, one experiment of
eight measured states) on sheets of ``--nx`` x nx/2 squares, to the noise-free data of each,
is run ``--repeats`` times, each followed by forward solves of its experiment from the flat
sheet (as ``wrinkle run`` makes them) at the start values and at every point the fit
evaluated; the table gives the medians: the fit's seconds per Jacobian (an optimiser
iteration: its residual evaluations and one Jacobian), the seconds of one forward solve at
the start and averaged over the fit's points (a solve at the true values takes up to twice
as long as at the start here: the sheet wrinkles more), the ratios of an iteration to each,
and the part the adjoint gradients take of a Jacobian evaluation. In turns with each fit, the
same fit whose warm states are the last forward solve's as they are (``LastStatesEngine``,
without the first-order prediction from the Jacobian's du/dp): its seconds per iteration and
its Newton iterations against the fit's.

    python benchmarks/fit_cost.py [--repeats 3] [--nx 16 40]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from wrinkle import read_case
from wrinkle.identification import read_fit, run_fit
from wrinkle.identification.fit import LocalEngine, tasks_for

FIT = Path(__file__).resolve().parents[1] / "examples" / "fit" / "fit.toml"


def fit_on_mesh(folder: Path, nx: int) -> Path:
    """The example's fit on a sheet of nx x nx/2 squares, its data the noise-free history of
    that sheet at the true values (a ``wrinkle run``)."""
    for name in ("fit.toml", "sheet.toml"):
        shutil.copy(FIT.parent / name, folder / name)
    sheet = folder / "sheet.toml"
    sheet.write_text(sheet.read_text().replace("nx = 16, ny = 8", f"nx = {nx}, ny = {nx // 2}"))
    read_case(sheet).run(folder / "run")
    fit = folder / "fit.toml"
    text = fit.read_text().replace('data = "measured.csv"', 'data = "run/history.csv"')
    text = text.replace('x = "pull_mm"\nfull_load = 4.0', 'x = "load_factor"')
    text = text.replace('y = ["Fx_N", "Fy_N", "ux_mm", "uy_mm"]\n', "")
    fit.write_text(text.replace("quantity = [", "y = ["))
    return fit


class TimedEngine(LocalEngine):
    """The engine of the fit, timing its forward solves and adjoint gradients apart."""

    def __init__(self) -> None:
        super().__init__()
        self.forward_seconds = 0.0
        self.adjoint_seconds = 0.0
        self.iterations = 0  # Newton iterations of the forward solves

    def forward(self, tasks):
        started = time.perf_counter()
        try:
            answers = super().forward(tasks)
        finally:
            self.forward_seconds += time.perf_counter() - started
        self.iterations += sum(answer.iterations for answer in answers)
        return answers

    def adjoint(self, tasks):
        started = time.perf_counter()
        try:
            return super().adjoint(tasks)
        finally:
            self.adjoint_seconds += time.perf_counter() - started


class LastStatesEngine(TimedEngine):
    """The fit's engine starting each forward solve from the last one's states as they are
    (the engine before the first-order prediction, for comparison)."""

    def _start(self, task):
        return self._warm.get(id(task.experiment))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--nx", type=int, nargs="+", default=[16, 40])
    args = parser.parse_args()
    print(
        f"{'elements':>8} {'states':>6} {'evals':>5} {'jacs':>4} {'forward, start [s]':>18} "
        f"{'forward, points [s]':>19} {'fit/iteration [s]':>17} {'ratio, points':>13} "
        f"{'ratio, start':>12} {'adjoint/iteration [s]':>21} "
        f"{'last states: fit/iteration [s]':>30} {'Newton, last states / fit':>25}"
    )
    for nx in args.nx:
        with tempfile.TemporaryDirectory() as scratch:
            row(read_fit(fit_on_mesh(Path(scratch), nx)), args.repeats, nx)


def cold_forward(problem, assignment) -> float:
    """Seconds of one forward solve of all experiments from the flat sheet at ``assignment``."""
    started = time.perf_counter()
    LocalEngine().forward(tasks_for(problem, assignment, adjoint=False))
    return time.perf_counter() - started


def row(problem, repeats: int, nx: int) -> None:
    at_start, at_points, per_iteration, adjoint_part, counts = [], [], [], [], []
    last_states, newton = [], (0, 0)
    for _ in range(repeats):
        started = time.perf_counter()
        plain_engine = LastStatesEngine()
        plain = run_fit(problem, plain_engine)
        last_states.append((time.perf_counter() - started) / plain.jacobians)
        engine = TimedEngine()
        started = time.perf_counter()
        result = run_fit(problem, engine)
        seconds = time.perf_counter() - started
        per_iteration.append(seconds / result.jacobians)
        adjoint_part.append(engine.adjoint_seconds / result.jacobians)
        counts.append((result.evaluations, result.jacobians))
        newton = (plain_engine.iterations, engine.iterations)
        at_start.append(cold_forward(problem, problem.start))
        points = [cold_forward(problem, entry["parameters"]) for entry in result.history]
        at_points.append(statistics.mean(points))
    start, points = statistics.median(at_start), statistics.median(at_points)
    iteration = statistics.median(per_iteration)
    print(
        f"{2 * nx * (nx // 2):8d} {problem.experiments[0].x.size:6d} {counts[0][0]:5d} "
        f"{counts[0][1]:4d} {start:18.3f} {points:19.3f} {iteration:17.3f} "
        f"{iteration / points:13.2f} {iteration / start:12.2f} "
        f"{statistics.median(adjoint_part):21.3f} {statistics.median(last_states):30.3f} "
        f"{f'{newton[0]} / {newton[1]}':>25}",
        flush=True,
    )


if __name__ == "__main__":
    main()
