"""Progress of a run: a bar on a terminal, plain log lines otherwise.

Each converged load step is reported (``Progress.step``); within a step, each nonlinear
iteration (``Progress.iteration``, a listener of ``wrinkle.solvers.listening``): on a
terminal the bar's line shows the step in progress, its iteration and residual; without a
terminal a line is printed when ``interval`` seconds (30) have passed since the last one, so
a long step is never silent.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable

__all__ = ["INTERVAL", "Progress"]

INTERVAL = 30.0  # seconds between the lines of a step in progress, without a terminal


class Progress:
    """Reports each converged load step: step, load factor, the pressure where the model
    has one, iterations, residual and the numbers of wrinkled and slack elements, and the
    iterations of the step in progress (module docstring). On a terminal the line is redrawn
    in place as a bar; otherwise one line per step, and one per ``interval`` seconds of a
    step in progress. ``quiet`` prints nothing. clock: seconds (``time.perf_counter``)."""

    def __init__(
        self,
        stream=None,
        quiet: bool = False,
        width: int = 24,
        interval: float = INTERVAL,
        clock: Callable[[], float] = time.perf_counter,
    ):
        self.stream = stream if stream is not None else sys.stderr
        self.quiet = quiet
        self.width = width
        self.interval = interval
        self.clock = clock
        self.terminal = bool(getattr(self.stream, "isatty", lambda: False)())
        self.count = 0
        self.staged = False  # a run of [[step]] tables: each line names its analysis step
        self.start = clock()
        self.last_line = self.start  # when a line was last printed
        self.load_factor = 0.0  # of the last converged step
        self.open = False  # a bar line is on the terminal without its newline

    def _bar(self) -> str:
        filled = round(self.width * min(max(self.load_factor, 0.0), 1.0))
        return "[" + "#" * filled + "-" * (self.width - filled) + "]"

    def step(self, step) -> None:
        """Report one converged StepResult."""
        self.count += 1
        self.load_factor = float(step.load_factor)
        if self.quiet:
            return
        _, wrinkled, slack = step.states
        pressure = getattr(step, "pressure", None)
        now = self.clock()
        text = (
            f"step {self.count:3d}  "
            + (f"analysis step {getattr(step, 'analysis_step', 1)}  " if self.staged else "")
            + f"load factor {step.load_factor:7.4f}  "
            + ("" if pressure is None else f"pressure {pressure:.4g}  ")
            + f"iterations {step.iterations:3d}  residual {step.residual:9.2e}  "
            f"wrinkled {wrinkled}  slack {slack}  ({now - self.start:.1f} s)"
        )
        if self.terminal:
            self.stream.write(f"\r{self._bar()} {text}\x1b[K")
            self.open = True
            if step.load_factor >= 1.0 - 1e-12:
                self.stream.write("\n")
                self.open = False
        else:
            self.stream.write(text + "\n")
        self.last_line = now
        self.stream.flush()

    def iteration(
        self, method: str, iteration: int, residual: float, states: tuple[int, int, int]
    ) -> None:
        """Report an iteration of the step in progress (a ``wrinkle.solvers.listening``
        listener): residual relative to the force scale, states (taut, wrinkled, slack)."""
        if self.quiet:
            return
        now = self.clock()
        text = (
            f"step {self.count + 1:3d} in progress: {method} iteration {iteration:3d}  "
            f"residual {residual:9.2e}  wrinkled {states[1]}  slack {states[2]}  "
            f"({now - self.start:.1f} s)"
        )
        if self.terminal:
            self.stream.write(f"\r{self._bar()} {text}\x1b[K")
            self.open = True
        elif now - self.last_line >= self.interval:
            self.stream.write(text + "\n")
            self.last_line = now
        else:
            return
        self.stream.flush()

    def close(self) -> None:
        """End a bar line left open by an interrupted run."""
        if self.terminal and not self.quiet and self.open:
            self.stream.write("\n")
            self.stream.flush()
            self.open = False
