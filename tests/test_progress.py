"""Progress of a run (issue 22, item 6): the converged steps, and within a step its
iterations, on a terminal redrawn in place, without one a line at least every 30 s of a long
step; the solvers' listeners receive every iteration."""

from __future__ import annotations

import io
from types import SimpleNamespace

import numpy as np

import wrinkle
from wrinkle.materials import StVenantKirchhoff
from wrinkle.progress import INTERVAL, Progress
from wrinkle.solvers import listening


class Stream(io.StringIO):
    def __init__(self, terminal: bool):
        super().__init__()
        self.terminal = terminal

    def isatty(self) -> bool:
        return self.terminal


class Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def step(load_factor: float, iterations: int = 4):
    return SimpleNamespace(
        load_factor=load_factor, iterations=iterations, residual=1e-9, states=(10, 2, 0)
    )


def test_without_a_terminal_a_long_step_prints_a_line_every_interval():
    """Iterations every 5 s: lines at 30 s and 60 s after the start (none between), the
    step's own line when it converges, and again only 30 s after that."""
    stream, clock = Stream(False), Clock()
    progress = Progress(stream, clock=clock)
    for k in range(1, 15):  # 5 .. 70 s
        clock.now = 5.0 * k
        progress.iteration("newton", k, 10.0**-k, (8, 4, 0))
    lines = stream.getvalue().splitlines()
    assert len(lines) == 2, lines
    assert lines[0].startswith("step   1 in progress: newton iteration   6")
    assert "(30.0 s)" in lines[0] and "(60.0 s)" in lines[1]
    assert "residual  1.00e-06" in lines[0] and "wrinkled 4" in lines[0]
    clock.now = 71.0
    progress.step(step(0.5))
    clock.now = 100.0
    progress.iteration("newton", 1, 0.1, (8, 4, 0))  # 29 s after the step's line: quiet
    clock.now = 101.0
    progress.iteration("newton", 2, 0.01, (8, 4, 0))
    lines = stream.getvalue().splitlines()
    assert lines[2].startswith("step   1  load factor  0.5000")
    assert lines[3].startswith("step   2 in progress: newton iteration   2")
    assert len(lines) == 4
    assert INTERVAL == 30.0


def test_on_a_terminal_the_bar_shows_the_iteration_in_progress():
    """Each iteration redraws the line (carriage return, clear to its end) with the bar at
    the last converged load factor; the last step ends the line; quiet prints nothing."""
    stream, clock = Stream(True), Clock()
    progress = Progress(stream, width=10, clock=clock)
    progress.step(step(0.5))
    progress.iteration("newton", 3, 2.5e-4, (9, 3, 1))
    text = stream.getvalue()
    last = text.split("\r")[-1]
    assert last.startswith("[#####-----] step   2 in progress: newton iteration   3")
    assert "residual  2.50e-04" in last and last.endswith("\x1b[K")
    assert "\n" not in text
    progress.step(step(1.0))
    assert stream.getvalue().endswith("\n")
    progress.close()  # nothing left open: no second newline
    assert not stream.getvalue().endswith("\n\n")
    quiet = Stream(True)
    silent = Progress(quiet, quiet=True, clock=clock)
    silent.iteration("newton", 1, 0.1, (1, 0, 0))
    silent.step(step(1.0))
    assert quiet.getvalue() == ""


def test_listeners_hear_every_iteration_of_a_solve_and_only_within_the_block():
    """A sheared sheet solved in two steps: the listener hears each step's iterations 0..n
    (n the step's iteration count), the last residual of each below the tolerance; after the
    block, nothing."""
    mesh = wrinkle.rectangle(1.0, 1.0, 4, 4)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=0.1))
    model.fix(mesh.node_sets["bottom"])
    model.prescribe(mesh.node_sets["top"], (0.2, 0.02, 0.0))
    heard: list[tuple[str, int, float]] = []

    def listener(method, iteration, residual, states):
        heard.append((method, iteration, residual))
        assert sum(states) == mesh.n_elements

    with listening(listener):
        results = model.solve(steps=2, tolerance=1e-8)
    starts = [i for i, (_, iteration, _) in enumerate(heard) if iteration == 0]
    ends = starts[1:] + [len(heard)]
    # the converged steps are the last attempts of the path; each heard from 0 to its count
    tails = [heard[a:b] for a, b in zip(starts, ends, strict=True)][-len(results.steps) :]
    for attempt, converged in zip(tails, results.steps, strict=True):
        assert [it for _, it, _ in attempt] == list(range(converged.iterations + 1))
        assert attempt[-1][2] <= 1e-8
    assert {method for method, _, _ in heard} == {"newton"}
    count = len(heard)
    model.solve(steps=1)
    assert len(heard) == count
    assert np.isfinite([r for _, _, r in heard]).all()


def test_a_staged_run_names_the_analysis_step_of_each_line():
    """With [[step]] tables (``staged``) each step's line says its analysis step."""
    stream = Stream(False)
    progress = Progress(stream, clock=Clock())
    progress.staged = True
    progress.step(SimpleNamespace(**vars(step(1.0)), analysis_step=1))
    progress.step(SimpleNamespace(**vars(step(0.5)), analysis_step=2))
    lines = stream.getvalue().splitlines()
    assert lines[0].startswith("step   1  analysis step 1  load factor  1.0000")
    assert lines[1].startswith("step   2  analysis step 2  load factor  0.5000")
