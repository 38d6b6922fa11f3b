"""Wall-clock time spent in the parts of a solve (element evaluation, assembly, linear solves)."""

from __future__ import annotations

import time
from collections import defaultdict
from contextlib import contextmanager

__all__ = ["ASSEMBLY", "ELEMENTS", "LINEAR", "Stopwatch"]

ELEMENTS = "element evaluation"
ASSEMBLY = "assembly"
LINEAR = "linear solves"


class Stopwatch:
    """Accumulates seconds per named part: ``with watch.part(ELEMENTS): ...``.

    Parts may nest (assembly of each block inside element evaluation): the time of an inner
    part counts for it alone, not for the part around it. ``factorisations`` counts the
    tangent factorisations made (the linear solvers add to it), failed load steps included;
    ``patches`` (tried), ``local_iterations`` and ``local_factorisations`` the work of
    nonlinear elimination (``wrinkle.solvers.elimination``), its factorisations counted in
    ``factorisations`` too.
    """

    def __init__(self):
        self.seconds: dict[str, float] = defaultdict(float)
        self.factorisations = 0
        self.patches = 0
        self.local_iterations = 0
        self.local_factorisations = 0
        self._start = time.perf_counter()
        self._inner: list[float] = []  # seconds of inner parts, one entry per open part

    @contextmanager
    def part(self, name: str):
        start = time.perf_counter()
        self._inner.append(0.0)
        try:
            yield
        finally:
            elapsed = time.perf_counter() - start
            self.seconds[name] += elapsed - self._inner.pop()
            if self._inner:
                self._inner[-1] += elapsed

    def absorb(self, other: Stopwatch) -> None:
        """Add the seconds and factorisations of another stopwatch (a later part of the same
        run) to this one's."""
        for name, seconds in other.seconds.items():
            self.seconds[name] += seconds
        self.factorisations += other.factorisations
        self.patches += other.patches
        self.local_iterations += other.local_iterations
        self.local_factorisations += other.local_factorisations

    def summary(self) -> dict[str, float]:
        """Seconds in each part, "rest" (everything else) and "total" since creation."""
        total = time.perf_counter() - self._start
        parts = {name: self.seconds.get(name, 0.0) for name in (ELEMENTS, ASSEMBLY, LINEAR)}
        return {**parts, "rest": max(total - sum(parts.values()), 0.0), "total": total}
