"""Progress over the load steps: a bar on a terminal, plain log lines otherwise."""

from __future__ import annotations

import sys
import time

__all__ = ["Progress"]


class Progress:
    """Reports each converged load step: step, load factor, the pressure where the model
    has one, iterations, residual and the numbers of wrinkled and slack elements. On a
    terminal the line is redrawn in place as a bar; otherwise one line per step is printed.
    ``quiet`` prints nothing."""

    def __init__(self, stream=None, quiet: bool = False, width: int = 24):
        self.stream = stream if stream is not None else sys.stderr
        self.quiet = quiet
        self.width = width
        self.terminal = bool(getattr(self.stream, "isatty", lambda: False)())
        self.count = 0
        self.start = time.perf_counter()

    def step(self, step) -> None:
        """Report one converged StepResult."""
        self.count += 1
        if self.quiet:
            return
        _, wrinkled, slack = step.states
        pressure = getattr(step, "pressure", None)
        text = (
            f"step {self.count:3d}  load factor {step.load_factor:7.4f}  "
            + ("" if pressure is None else f"pressure {pressure:.4g}  ")
            + f"iterations {step.iterations:3d}  residual {step.residual:9.2e}  "
            f"wrinkled {wrinkled}  slack {slack}  ({time.perf_counter() - self.start:.1f} s)"
        )
        if self.terminal:
            filled = round(self.width * min(step.load_factor, 1.0))
            bar = "#" * filled + "-" * (self.width - filled)
            self.stream.write(f"\r[{bar}] {text}")
            if step.load_factor >= 1.0 - 1e-12:
                self.stream.write("\n")
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def close(self) -> None:
        """End a bar line left open by an interrupted run."""
        if self.terminal and not self.quiet and self.count:
            self.stream.write("\n")
            self.stream.flush()
